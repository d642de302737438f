//! Saving a live scene: every kind's parameters, changed while it runs, are in the saved file
//! and come back when it is read again; what nobody changed stays as written.

use super::common::small_app;
use canopy::foundation::params::{ParamValue, set_param};
use canopy::scene::save_live_scene;
use serde_yaml::Value;

/// A scene with an entity of every kind that has parameters.
const SCENE: &str = "\
entities:
  - name: box
    shape: { primitive: box, position: [0, 0.5, 0], color: [0.8, 0.2, 0.2] }
  - name: arm
    muscle:
      muscle_config:
        radiuses: [5.0, 5.0, 10.0, 15.0, 18.0, 18.0, 15.0, 10.0, 5.0, 5.0]
        grow_mults: [0.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 1.0, 1.0, 0.0]
        len: 250.0
      carcass_config:
        data: [[30.0, 230.0], [30.0, 120.0]]
        thickness: 5.0
  - name: land
    terrain:
      height: { size: [32, 32], seed: 3, layers: [{ perlin: { scale: 16 } }] }
      section: { origin: [0, 0], size: [16, 16] }
  - name: tree
    tree:
      supports:
        - { name: bough, points: [[-2, 2, 0], [2, 2.1, 0]], radii: [0.06, 0.04] }
  - name: sloth
    sloth: { support: bough, at: 0.3 }
  - name: patch
    soft_body: { sample: { shape: belly, size: 9 } }
  - name: plum
    elastic_body:
      sample: { shape: sphere, size: 12 }
      size: 0.1
      position: [0, 1, 1]
      cell_m: 0.03
";

/// The kind's mapping of the entity named `name` in the scene file `text`.
fn entry(text: &str, name: &str) -> Value {
    let scene: Value = serde_yaml::from_str(text).unwrap();
    let entity = scene["entities"].as_sequence().unwrap().iter().find(|e| e["name"].as_str() == Some(name));
    let entity = entity.unwrap_or_else(|| panic!("no {name} in\n{text}")).as_mapping().unwrap();
    entity.iter().find(|(key, _)| key.as_str() != Some("name")).map(|(_, value)| value.clone()).unwrap()
}

#[test]
fn every_kinds_live_parameters_are_saved_and_read_back() {
    let folder = tempfile::tempdir().unwrap();
    let path = folder.path().join("everything.yaml");
    std::fs::write(&path, SCENE).unwrap();

    let mut app = small_app(&path);
    let world = app.world_mut();
    for (name, value) in [
        ("box.position.x", ParamValue::Number(1.5)),
        ("box.size.y", ParamValue::Number(2.0)),
        ("arm.position.y", ParamValue::Number(0.25)),
        ("arm.scale", ParamValue::Number(0.005)),
        ("land.height_m", ParamValue::Number(3.5)),
        ("sloth.speed", ParamValue::Number(0.2)),
        ("sloth.autorun", ParamValue::Bool(true)),
        ("sloth.direction", ParamValue::Choice("back".into())),
        ("sloth.stride_mode", ParamValue::Choice("fixed".into())),
        ("sloth.stride_m", ParamValue::Number(0.5)),
        ("sloth.ik_sweeps", ParamValue::Number(20.0)),
        ("sloth.one_at_a_time", ParamValue::Bool(true)),
        ("sloth.step_delay_s", ParamValue::Number(0.3)),
        ("patch.k", ParamValue::Number(0.8)),
        ("plum.friction", ParamValue::Number(0.9)),
    ] {
        set_param(world, name, value).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    // Parameters reach their components at the next step.
    app.update();
    save_live_scene(app.world_mut()).unwrap();

    let saved = canopy::app::entity_kinds().load(&path).expect("the saved scene reads and checks");
    let (before, after) = (SCENE, &std::fs::read_to_string(&path).unwrap());
    let number = |value: &Value| value.as_f64().unwrap_or_else(|| panic!("not a number: {value:?}"));
    let shape = entry(after, "box");
    assert_eq!(number(&shape["position"][0]), 1.5);
    assert_eq!(number(&shape["size"][1]), 2.0);
    assert_eq!(shape["color"], entry(before, "box")["color"], "the colour nobody changed");
    let arm = entry(after, "arm");
    assert_eq!(number(&arm["position"][1]), 0.25);
    assert!((number(&arm["scale"]) - 0.005).abs() < 1e-9, "{arm:?}");
    assert_eq!(number(&entry(after, "land")["height_m"]), 3.5);
    let sloth = entry(after, "sloth");
    assert!((number(&sloth["speed"]) - 0.2).abs() < 1e-6, "{sloth:?}");
    assert_eq!(sloth["autorun"], Value::Bool(true));
    assert_eq!(sloth["direction"].as_str(), Some("back"));
    assert_eq!((sloth["stride_mode"].as_str(), sloth["ik_sweeps"].as_u64()), (Some("fixed"), Some(20)));
    assert!((number(&sloth["stride_m"]) - 0.5).abs() < 1e-6, "{sloth:?}");
    assert!((number(&sloth["step_delay_s"]) - 0.3).abs() < 1e-6, "{sloth:?}");
    for untouched in ["max_step_m", "ik_tolerance_mm", "hang", "stride_seed"] {
        assert!(sloth.get(untouched).is_none(), "{untouched} was not changed, so it is not written: {sloth:?}");
    }
    assert_eq!(sloth["support"], entry(before, "sloth")["support"], "where it hangs, as written");
    assert!((number(&entry(after, "patch")["k"]) - 0.8).abs() < 1e-6);
    assert!((number(&entry(after, "plum")["friction"]) - 0.9).abs() < 1e-6);
    // The tree, which nobody edited, is as it was.
    std::fs::write(&path, SCENE).unwrap();
    let written = canopy::app::entity_kinds().load(&path).unwrap();
    let tree =
        |scene: &canopy::scene::kinds::LoadedScene| scene.def.entities[3].def::<canopy::tree::TreeDef>().cloned();
    assert_eq!(tree(&saved), tree(&written));
    assert!(tree(&saved).is_some());
}
