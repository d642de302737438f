//! Timelines, pause and step, determinism, and the key help against the key reference.

use super::common::*;
use bevy::math::Vec3;
use canopy::run::RunOutput;

#[test]
fn timelines_set_parameters_by_name() {
    let output = run(
        "scenes/demo.yaml",
        2,
        Some("- { at: 0, set: { light.azimuth_deg: 90, light.elevation_deg: 0, ball.color.red: 0.25 } }"),
        SMALL,
    );
    let light = entity(&output.dump, "light");
    assert!((vec3(&light["direction"]) - Vec3::NEG_X).length() < 1e-6, "{light}");
    assert_eq!(entity(&output.dump, "ball")["color"][0], 0.25);
}

#[test]
fn pause_stops_the_clock_and_step_advances_it_by_one() {
    let pause = "- { at: 0.25, press: [Space] }\n- { at: 0.3, release: [Space] }\n";
    let paused_early = run("scenes/demo.yaml", 40, Some(pause), SMALL);
    let paused_late = run("scenes/demo.yaml", 60, Some(pause), SMALL);
    let frame = |output: &RunOutput| output.dump["frame"].as_u64().unwrap();
    assert_eq!(frame(&paused_early), frame(&paused_late));
    assert!(frame(&paused_early) < 40 && frame(&paused_early) > 10);
    let stepped = run(
        "scenes/demo.yaml",
        60,
        Some(&format!("{pause}- {{ at: 0.5, press: [Period] }}\n- {{ at: 0.55, release: [Period] }}\n")),
        SMALL,
    );
    assert_eq!(frame(&stepped), frame(&paused_late) + 1);
}

#[test]
fn runs_are_deterministic() {
    let timeline = Some("- { at: 0.1, press: [KeyJ, ArrowUp] }\n- { at: 0.3, release: [KeyJ] }\n");
    let a = run("scenes/demo.yaml", 25, timeline, SMALL);
    let b = run("scenes/demo.yaml", 25, timeline, SMALL);
    assert_eq!(a.dump, b.dump);
    assert_eq!(a.framebuffer.color(), b.framebuffer.color());
}

#[test]
fn the_key_reference_lists_every_registered_key() {
    let app = canopy::app::headless_app(&path("scenes/demo.yaml"), SMALL, false).unwrap();
    let reference = std::fs::read_to_string(path("docs/reference.md")).unwrap();
    let keys_section = reference.split("## Keys").nth(1).unwrap().split("\n## ").next().unwrap();
    let key_map = app.world().resource::<canopy::foundation::keys::KeyMap>();
    assert!(key_map.0.len() >= 15);
    for help in &key_map.0 {
        let name = help.key_name();
        let listed = keys_section.lines().any(|line| {
            line.starts_with('|')
                && line.split('|').nth(1).is_some_and(|cell| cell.split(" / ").any(|k| k.trim() == name))
        });
        assert!(listed, "the key table of docs/reference.md does not list {name} ({})", help.action);
    }
}

#[test]
fn the_key_help_starts_hidden_and_f1_shows_and_hides_it() {
    use bevy::input::ButtonState;
    use bevy::input::keyboard::{Key, KeyboardInput, NativeKey};
    use bevy::prelude::{Entity, KeyCode};
    use canopy::controls::HelpVisible;
    let mut app = small_app(&path("scenes/demo.yaml"));
    let key = |app: &mut bevy::app::App, state| {
        app.world_mut().write_message(KeyboardInput {
            key_code: KeyCode::F1,
            logical_key: Key::Unidentified(NativeKey::Unidentified),
            state,
            text: None,
            repeat: false,
            window: Entity::PLACEHOLDER,
        });
        app.update();
        app.world().resource::<HelpVisible>().0
    };
    assert!(!app.world().resource::<HelpVisible>().0, "the key help covers the view at start");
    assert!(key(&mut app, ButtonState::Pressed));
    assert!(key(&mut app, ButtonState::Released), "releasing F1 keeps the help shown");
    assert!(!key(&mut app, ButtonState::Pressed));
}

#[test]
fn the_fixed_steps_of_a_frame_are_timed_for_the_panel() {
    use canopy::foundation::schedule::FixedStepTime;
    let mut app = small_app(&path("scenes/sloth.yaml"));
    app.update();
    assert!(app.world().resource::<FixedStepTime>().last > std::time::Duration::ZERO);
}
