//! Shapes: drawn where they are, hidden behind each other, dumped in scene order, spinning.

use super::common::*;
use bevy::math::Vec3;

const RED: [u8; 4] = [255, 0, 0, 255];
const GREEN: [u8; 4] = [0, 255, 0, 255];
const SKY: [u8; 4] = [0, 0, 255, 255];

#[test]
fn a_red_sphere_in_front_of_the_camera_is_red_at_the_centre_with_sky_at_the_corners() {
    let output = run("tests/scenes/red_sphere.yaml", 1, None, SMALL);
    let fb = &output.framebuffer;
    assert_eq!((fb.width(), fb.height()), (160, 120));
    assert_eq!(fb.pixel(80, 60), RED);
    for (x, y) in [(0, 0), (159, 0), (0, 119), (159, 119)] {
        assert_eq!(fb.pixel(x, y), SKY, "corner {x},{y}");
    }
    // A sphere of radius 1 at distance 5 under a 40 degree fov covers a disc of radius
    // ~ tan(asin(1/5)) / tan(20 deg) * 60 pixels.
    let radius = (1.0f64 / 5.0).asin().tan() / 20f64.to_radians().tan() * 60.0;
    let expected = std::f64::consts::PI * radius * radius;
    let red = count_pixels(fb, RED) as f64;
    assert!((red - expected).abs() < expected * 0.03, "{red} red pixels, expected about {expected}");
}

#[test]
fn a_box_behind_another_is_hidden_until_the_front_one_moves() {
    let hidden = run("tests/scenes/occlusion.yaml", 1, None, SMALL);
    assert_eq!(count_pixels(&hidden.framebuffer, RED), 0);
    assert!(count_pixels(&hidden.framebuffer, GREEN) > 1000);
    let moved = run("tests/scenes/occlusion.yaml", 1, Some("- { at: 0, set: { front.position.x: 10 } }"), SMALL);
    assert!(count_pixels(&moved.framebuffer, RED) > 100);
    assert_eq!(count_pixels(&moved.framebuffer, GREEN), 0);
}

#[test]
fn the_demo_scene_dumps_every_entity_in_order_and_spins_at_its_rate() {
    let output = run("scenes/demo.yaml", 60, None, SMALL);
    let dump = &output.dump;
    assert_eq!(dump["frame"], 60);
    assert!((dump["time"].as_f64().unwrap() - 1.0).abs() < 1e-6);
    let names: Vec<&str> = dump["entities"].as_array().unwrap().iter().map(|e| e["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["camera", "light", "render", "ground", "ball", "crate", "column", "spinner"]);
    let spinner = entity(dump, "spinner");
    assert_eq!(spinner["kind"], "shape");
    assert_eq!(spinner["primitive"], "box");
    // 90 degrees per second for one second.
    assert!((vec3(&spinner["rotation_deg"]).y - 90.0).abs() < 1e-3, "{spinner}");
    assert_eq!(vec3(&entity(dump, "ball")["position"]), Vec3::new(0.0, 0.6, 0.0));
}
