use super::*;

/// A test file in a temporary folder beside a scene of its own.
fn read(text: &str) -> Result<Vec<SceneTest>, FileError> {
    let folder = tempfile::tempdir().unwrap();
    std::fs::write(folder.path().join("scene.yaml"), "entities: []\n").unwrap();
    std::fs::write(folder.path().join("walk.yaml"), "- { at: 0, press: [KeyW] }\n").unwrap();
    let path = folder.path().join("a.test.yaml");
    std::fs::write(&path, text).unwrap();
    load(&path)
}

fn error(text: &str) -> FileError {
    read(text).unwrap_err()
}

const EXAMPLE: &str = "\
scene: scene.yaml
seconds: 20
input: walk.yaml
expect:
  - at: 10
    that: sloth.distance_travelled > 0.8
  - always: sloth.min_body_clearance >= 0
  - eventually: sloth.support == \"tree/bough\"
    before: 15
  - at: 20
    screenshot: golden/sloth_20s.png
    size: [320, 240]
    tolerance: { channel: 8, pixels: 0.002 }
";

#[test]
fn reads_the_documented_example() {
    let tests = read(EXAMPLE).unwrap();
    assert_eq!(tests.len(), 1);
    let test = &tests[0];
    assert_eq!((test.name.as_str(), test.steps, test.repeat), ("a", 1200, 1));
    assert!(matches!(&test.input, Input::File(path) if path.ends_with("walk.yaml")));
    let whens: Vec<When> = test.expectations.iter().map(|e| e.when).collect();
    assert_eq!(whens, [When::At(600), When::Always, When::Eventually(900), When::At(1200)]);
    assert_eq!((test.expectations[0].origin.line, test.expectations[0].origin.column), (6, 11));
    let What::Screenshot(shot) = &test.expectations[3].what else { panic!("a screenshot") };
    assert_eq!(shot.size, UVec2::new(320, 240));
    assert_eq!(shot.tolerance, Tolerance { channel: 8, pixels: 0.002 });
    assert!(shot.golden.ends_with("golden/sloth_20s.png"));
}

#[test]
fn several_tests_share_a_scene_and_its_defaults() {
    let text = "scene: scene.yaml\nseconds: 2\ntests:\n  - name: one\n    expect: [{ always: time >= 0 }]\n  - name: two\n    frames: 30\n    timeline: [{ at: 0.5, press: [KeyW] }]\n    repeat: 2\n    expect: [{ eventually: time > 0.1 }]\n";
    let tests = read(text).unwrap();
    assert_eq!(tests.iter().map(|t| t.name.as_str()).collect::<Vec<_>>(), ["a/one", "a/two"]);
    assert_eq!((tests[0].steps, tests[1].steps, tests[1].repeat), (120, 30, 2));
    assert!(matches!(&tests[1].input, Input::Inline(events) if events.len() == 1));
}

#[test]
fn expression_errors_point_at_their_column_in_the_file() {
    let e = error("scene: scene.yaml\nseconds: 1\nexpect:\n  - always: sloth.x >\n");
    assert_eq!(e.location.map(|l| l.0), Some(4), "{e}");
    assert!(e.location.unwrap().1 > 13, "{e}");
    assert!(e.message.contains("does not parse"), "{e}");
    let e = error("scene: scene.yaml\nseconds: 1\nexpect:\n  - always: \"a ==\"\n");
    assert_eq!(e.location.map(|l| l.0), Some(4), "{e}");
}

#[test]
fn problems_are_located_at_their_field() {
    let cases: &[(&str, usize, &str)] = &[
        ("scene: nothing.yaml\nseconds: 1\nexpect: [{ always: true }]\n", 1, "no file at"),
        ("scene: scene.yaml\nseconds: 1\nframes: 60\nexpect: [{ always: true }]\n", 3, "not both"),
        ("scene: scene.yaml\nexpect: [{ always: true }]\n", 1, "`seconds:` or `frames:`"),
        ("scene: scene.yaml\nseconds: 5000\nexpect: [{ always: true }]\n", 2, "at most 3600"),
        ("scene: scene.yaml\nseconds: 1\nexpect:\n  - at: 2\n    that: true\n", 4, "after the run ends at 1 s"),
        ("scene: scene.yaml\nseconds: 1\nexpect:\n  - at: 1\n", 4, "`that:` or `screenshot:`"),
        ("scene: scene.yaml\nseconds: 1\nexpect:\n  - { at: 0, screenshot: a.png }\n", 4, "drawn after the first step"),
        ("scene: scene.yaml\nseconds: 1\nexpect:\n  - always: true\n    before: 1\n", 5, "only an `eventually`"),
        ("scene: scene.yaml\nseconds: 1\nexpect:\n  - { at: 1, always: true }\n", 4, "one of `at:`"),
        ("scene: scene.yaml\nseconds: 1\nexpect:\n  - { at: 1, screenshot: a.jpg }\n", 4, "ending in .png"),
        ("scene: scene.yaml\nseconds: 1\nexpect:\n  - { at: 1, screenshot: a.png, size: [0, 10] }\n", 4, "each 1 to"),
        ("scene: scene.yaml\nseconds: 1\nrepeat: 0\nexpect: [{ always: true }]\n", 3, "1 to 10 runs"),
        ("scene: scene.yaml\nseconds: 1\nexpect: []\n", 3, "checks nothing"),
        ("scene: scene.yaml\nseconds: 1\ninput: none.yaml\nexpect: [{ always: true }]\n", 3, "no file at"),
        ("scene: scene.yaml\nseconds: 1\nexpect:\n  - { always: true, within: 2 }\n", 4, "unknown field `within`"),
        (
            "scene: scene.yaml\ntests:\n  - { name: x, seconds: 1, expect: [{ always: true }] }\n  - { name: x, seconds: 1, expect: [{ always: true }] }\n",
            4,
            "another test",
        ),
        ("scene: scene.yaml\nseconds: 1\nexpect: [{ always: true }]\ntests: []\n", 4, "not both"),
    ];
    for (text, line, words) in cases {
        let e = error(text);
        assert_eq!(e.location.map(|l| l.0).unwrap_or(1), *line, "{text}: {e}");
        assert!(e.message.contains(words), "{text}: {e}");
    }
}
