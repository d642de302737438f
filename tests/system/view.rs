//! The camera, the light and the render settings: keys, parameters, shading and shadows.

use super::common::*;
use canopy::raster::Framebuffer;
use canopy::run::RunOutput;
use serde_json::Value;

#[test]
fn held_keys_orbit_the_camera_at_their_documented_rate() {
    let start = run("scenes/demo.yaml", 30, None, SMALL);
    let turned = run(
        "scenes/demo.yaml",
        30,
        Some("- { at: 0, press: [ArrowLeft] }\n- { at: 0.5, release: [ArrowLeft] }"),
        SMALL,
    );
    let yaw = |dump: &Value| {
        let camera = entity(dump, "camera");
        let offset = vec3(&camera["position"]) - vec3(&camera["target"]);
        offset.x.atan2(offset.z).to_degrees()
    };
    // 60 degrees per second for half a second, to the left.
    let turn = yaw(&turned.dump) - yaw(&start.dump);
    assert!((turn + 30.0).abs() < 1e-2, "turned {turn} degrees");
    assert_ne!(start.framebuffer.color(), turned.framebuffer.color());
}

/// Mean brightness of a frame, 0 to 765.
fn brightness(framebuffer: &Framebuffer) -> f64 {
    let sum: u64 = framebuffer.color().chunks_exact(4).map(|p| p[..3].iter().map(|&c| u64::from(c)).sum::<u64>()).sum();
    sum as f64 / (framebuffer.width() * framebuffer.height()) as f64
}

#[test]
fn shadows_and_shading_switch_at_run_time_by_parameter_and_key() {
    let render = |output: &RunOutput| entity(&output.dump, "render").clone();
    let shadowed = run("scenes/demo.yaml", 2, None, SMALL);
    assert_eq!(render(&shadowed)["shadows"], true);

    // The parameter and the key reach the same frame; without shadows it is brighter.
    let by_param = run("scenes/demo.yaml", 2, Some("- { at: 0, set: { render.shadows: false } }"), SMALL);
    let by_key = run("scenes/demo.yaml", 2, Some("- { at: 0, press: [KeyH] }"), SMALL);
    assert_eq!(render(&by_key)["shadows"], false);
    assert_eq!(by_param.framebuffer.color(), by_key.framebuffer.color());
    assert!(brightness(&by_param.framebuffer) > brightness(&shadowed.framebuffer) + 1.0);

    // V cycles Gouraud -> Phong -> flat; each mode draws a different frame.
    let mut frames = vec![shadowed.framebuffer.color().to_vec()];
    for (presses, mode) in [(1, "phong"), (2, "flat")] {
        // Press and release on alternate frames (timeline times are seconds at 60 steps per second).
        let frame = |n: u32| f64::from(n) / 60.0;
        let timeline: String = (0..presses)
            .map(|i| {
                format!(
                    "- {{ at: {}, press: [KeyV] }}\n- {{ at: {}, release: [KeyV] }}\n",
                    frame(2 * i),
                    frame(2 * i + 1)
                )
            })
            .collect();
        let output = run("scenes/demo.yaml", 6, Some(&timeline), SMALL);
        assert_eq!(render(&output)["shading"], mode);
        let by_param =
            run("scenes/demo.yaml", 6, Some(&format!("- {{ at: 0, set: {{ render.shading: {mode} }} }}")), SMALL);
        assert_eq!(output.framebuffer.color(), by_param.framebuffer.color(), "{mode}");
        assert!(!frames.contains(&output.framebuffer.color().to_vec()), "{mode} looks like another mode");
        frames.push(output.framebuffer.color().to_vec());
    }
}

#[test]
fn a_following_camera_moves_with_the_sloth_and_a_free_one_stays() {
    let start = run("scenes/sloth_fruit.yaml", 1, None, SMALL);
    let (target0, body0) =
        (vec3(&entity(&start.dump, "camera")["target"]), vec3(&entity(&start.dump, "sloth")["body_position"]));
    let follow = "- { at: 0.0, set: { camera.follow: true } }\n";
    for (timeline, following) in [(Some(follow), true), (None, false)] {
        let output = run("scenes/sloth_fruit.yaml", 300, timeline, SMALL);
        let camera = entity(&output.dump, "camera");
        assert_eq!(camera["follow"], following);
        let moved = vec3(&camera["target"]) - target0;
        let walked = vec3(&entity(&output.dump, "sloth")["body_position"]) - body0;
        assert!(walked.length() > 0.3, "the sloth walks: {walked}");
        if following {
            assert!((moved - walked).length() < 0.02, "the target moved {moved} as the sloth {walked}");
        } else {
            assert_eq!(moved, bevy::math::Vec3::ZERO);
        }
    }
}
