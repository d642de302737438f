use super::*;
use serde_json::json;

fn scope() -> Map<String, Json> {
    let sloth = json!({
        "distance_travelled": 0.62,
        "support": "tree/bough",
        "body_position": [1.0, 2.0, 3.0],
        "feet": {
            "front_left": { "planted": true, "surface_distance": 0.004 },
            "hind_right": { "planted": false, "surface_distance": 0.2 },
        },
        "footfalls": [{ "limb": "front_left", "time": 0.5 }],
        "changing_to": null,
    });
    let mut variables = Map::new();
    variables.insert("sloth".into(), sloth.clone());
    variables.insert("entities".into(), json!({ "sloth": sloth }));
    variables.insert("time".into(), json!(10.0));
    variables.insert("frame".into(), json!(600));
    variables
}

fn verdict(source: &str) -> Verdict {
    let check = Check::compile(source).unwrap();
    let scope = scope();
    check.check_names(&scope).unwrap();
    let root = context();
    let mut context = root.new_inner_scope();
    for path in check.paths() {
        context.add_variable_from_value(path[0].clone(), to_cel(&scope[&path[0]]));
    }
    check.evaluate(&context)
}

#[test]
fn compares_combines_and_does_arithmetic() {
    assert_eq!(verdict("sloth.distance_travelled > 0.5"), Verdict::True);
    assert_eq!(verdict("sloth.distance_travelled > 0.8"), Verdict::False);
    assert_eq!(verdict("sloth.distance_travelled / time >= 0.06 && frame == 600"), Verdict::True);
    assert_eq!(verdict("sloth.support == \"tree/bough\" || false"), Verdict::True);
    assert_eq!(verdict("frame > 599.5"), Verdict::True, "an int compared with a double");
    assert_eq!(verdict("entities[\"sloth\"].support.startsWith(\"tree/\")"), Verdict::True);
}

#[test]
fn tests_every_and_any_element_of_maps_and_lists() {
    let within = "sloth.feet.all(limb, !sloth.feet[limb].planted || sloth.feet[limb].surface_distance < 0.01)";
    assert_eq!(verdict(within), Verdict::True);
    assert_eq!(verdict("sloth.feet.all(limb, sloth.feet[limb].planted)"), Verdict::False);
    assert_eq!(verdict("sloth.footfalls.exists(f, f.limb == \"front_left\" && f.time < 1.0)"), Verdict::True);
    assert_eq!(verdict("size(sloth.footfalls) == 1"), Verdict::True);
}

#[test]
fn compares_approximately_and_measures_distances() {
    assert_eq!(verdict("approx(sloth.distance_travelled, 0.6, 0.05)"), Verdict::True);
    assert_eq!(verdict("approx(sloth.distance_travelled, 0.6, 0.01)"), Verdict::False);
    assert_eq!(verdict("approx(sloth.body_position, [1, 2, 3.001], 0.01)"), Verdict::True);
    assert_eq!(verdict("distance(sloth.body_position, [1, 2, 5]) == 2.0"), Verdict::True);
    assert_eq!(verdict("math.abs(-sloth.distance_travelled) < 1.0"), Verdict::True);
    assert!(matches!(verdict("approx(sloth.support, 1, 0.1)"), Verdict::Error(_)));
}

#[test]
fn a_result_that_is_not_a_truth_value_is_an_error() {
    let Verdict::Error(message) = verdict("sloth.distance_travelled + 1.0") else { panic!("not an error") };
    assert!(message.contains("1.62"), "{message}");
}

#[test]
fn parse_errors_point_into_the_expression() {
    let error = Check::compile("sloth.distance_travelled >").unwrap_err();
    assert_eq!(error.line, 1);
    assert!(error.column >= 26, "{error:?}");
    assert!(error.message.contains("does not parse"), "{}", error.message);
    let error = Check::compile("a &&\n  (b").unwrap_err();
    assert_eq!(error.line, 2, "{error:?}");
}

#[test]
fn unknown_names_are_found_before_anything_runs_with_what_exists() {
    let scope = scope();
    let error = Check::compile("slot.distance_travelled > 0").unwrap().check_names(&scope).unwrap_err();
    assert_eq!((error.line, error.column), (1, 1));
    assert!(error.message.contains("no entity or variable `slot`; did you mean `sloth`?"), "{}", error.message);
    let error = Check::compile("time > 1 && sloth.distance_travled > 0.8").unwrap().check_names(&scope).unwrap_err();
    assert_eq!((error.line, error.column), (1, 19));
    assert!(
        error.message.contains("`sloth` has no field `distance_travled`; did you mean `distance_travelled`?"),
        "{}",
        error.message
    );
    let error = Check::compile("sloth.feet.front_left.plantd").unwrap().check_names(&scope).unwrap_err();
    assert!(error.message.contains("`sloth.feet.front_left` has no field `plantd`"), "{}", error.message);
    // Inside lists and nulls the names cannot be known in advance; macro variables are bound.
    let fine = [
        "sloth.footfalls[0].anything",
        "sloth.changing_to.anything",
        "sloth.feet.all(k, k.size() > 0)",
        "has(sloth.maybe)",
    ];
    for source in fine {
        Check::compile(source).unwrap().check_names(&scope).unwrap_or_else(|e| panic!("{source}: {e:?}"));
    }
}

#[test]
fn a_failure_shows_every_path_it_read() {
    let check = Check::compile("sloth.distance_travelled > 0.8 && sloth.support != \"\"").unwrap();
    let scope = scope();
    let root = context();
    let mut context = root.new_inner_scope();
    context.add_variable_from_value("sloth", to_cel(&scope["sloth"]));
    assert_eq!(check.values_read(&context), "sloth.distance_travelled = 0.62, sloth.support = \"tree/bough\"");
}

#[test]
fn numbers_read_as_people_write_them() {
    assert_eq!(number_text(0.6200000047683716), "0.62");
    assert_eq!(number_text(1234.5678), "1234.57");
    assert_eq!(number_text(-0.000123456789), "-0.000123457");
    assert_eq!(number_text(1e-9), "1.00000e-9");
    assert_eq!(number_text(3.0), "3");
}
