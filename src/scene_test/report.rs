//! What a suite's run says: a line per test, the failures in full, the tally; JUnit XML for CI
//! dashboards; JSON for scripts.

use crate::scene_test::runner::{Outcome, Status};
use quick_junit::{NonSuccessKind, Report, TestCase, TestCaseStatus, TestSuite};
use serde_json::{Value, json};

/// `passed  sloth  (3.21 s)`.
pub fn line(outcome: &Outcome) -> String {
    let status = match outcome.status {
        Status::Passed => "passed ",
        Status::Failed => "FAILED ",
        Status::Invalid => "INVALID",
    };
    let blessed = match outcome.blessed.len() {
        0 => String::new(),
        n => format!(", wrote {n} golden image{}", if n == 1 { "" } else { "s" }),
    };
    format!("{status} {}  ({:.2} s{blessed})", outcome.name, outcome.wall.as_secs_f64())
}

/// Each failure of a test on a line of its own, then where its files went.
pub fn failures(outcome: &Outcome) -> String {
    let mut out = format!("---- {} ----\n", outcome.name);
    for failure in &outcome.failures {
        out.push_str(&format!("{failure}\n"));
    }
    if let Some(folder) = &outcome.artifacts {
        out.push_str(&format!("the dump and frames of the failure: {}\n", folder.display()));
    }
    out.truncate(out.trim_end().len());
    out
}

/// `N passed, M failed` (and the invalid, when there are some).
pub fn tally(outcomes: &[Outcome]) -> String {
    let count = |status| outcomes.iter().filter(|o| o.status == status).count();
    let invalid = count(Status::Invalid);
    let invalid = if invalid > 0 { format!(", {invalid} invalid") } else { String::new() };
    format!("{} passed, {} failed{invalid}", count(Status::Passed), count(Status::Failed))
}

/// The process's exit code: 0 all passed, 1 a test failed, 2 a test cannot run as written.
pub fn exit_code(outcomes: &[Outcome]) -> u8 {
    if outcomes.iter().any(|o| o.status == Status::Invalid) {
        2
    } else if outcomes.iter().any(|o| o.status == Status::Failed) {
        1
    } else {
        0
    }
}

/// The run as JUnit XML: a suite per test file, a case per test.
pub fn junit(outcomes: &[Outcome]) -> String {
    let mut report = Report::new("canopy test");
    let mut files: Vec<&std::path::Path> = outcomes.iter().map(|o| o.file.as_path()).collect();
    files.dedup();
    for file in files {
        let mut suite = TestSuite::new(file.display().to_string());
        for outcome in outcomes.iter().filter(|o| o.file == file) {
            let status = match outcome.status {
                Status::Passed => TestCaseStatus::success(),
                Status::Failed | Status::Invalid => {
                    let kind =
                        if outcome.status == Status::Failed { NonSuccessKind::Failure } else { NonSuccessKind::Error };
                    let mut status = TestCaseStatus::non_success(kind);
                    let text: Vec<String> = outcome.failures.iter().map(ToString::to_string).collect();
                    status.set_message(outcome.failures.first().map(ToString::to_string).unwrap_or_default());
                    status.set_description(text.join("\n"));
                    status
                }
            };
            let mut case = TestCase::new(outcome.name.clone(), status);
            case.set_classname(file.display().to_string());
            case.set_time(outcome.wall);
            suite.add_test_case(case);
        }
        report.add_test_suite(suite);
    }
    report.to_string().expect("a report of plain strings serializes")
}

/// The run as JSON: every test's name, file, status, time and failures, and the tally.
pub fn json(outcomes: &[Outcome]) -> Value {
    let tests: Vec<Value> = outcomes
        .iter()
        .map(|o| {
            json!({
                "name": o.name,
                "file": o.file,
                "status": match o.status { Status::Passed => "passed", Status::Failed => "failed", Status::Invalid => "invalid" },
                "seconds": o.wall.as_secs_f64(),
                "failures": o.failures.iter().map(|f| json!({
                    "file": f.path,
                    "line": f.location.map(|l| l.0),
                    "column": f.location.map(|l| l.1),
                    "message": f.message,
                })).collect::<Vec<_>>(),
                "blessed": o.blessed,
                "artifacts": o.artifacts,
                "evaluations": o.evaluations,
                "checking_seconds": o.checking.as_secs_f64(),
            })
        })
        .collect();
    let count = |status| outcomes.iter().filter(|o| o.status == status).count();
    json!({
        "tests": tests,
        "passed": count(Status::Passed),
        "failed": count(Status::Failed),
        "invalid": count(Status::Invalid),
    })
}
