//! Runs one scene test: the scene headless at the fixed step, its input played, every
//! expectation checked at its steps, a frame drawn only where one is needed, and what a
//! failure leaves (the dump, the frame, the golden and their diff) written for a person to
//! look at.

use crate::app::{FIXED_HZ, entity_kinds};
use crate::controls::timeline::Timeline;
use crate::foundation::dump::{dump_state, write_dump};
use crate::foundation::yaml::FileError;
use crate::raster::plugin::{RasterTarget, RenderPolicy};
use crate::run::{RunError, live_app};
use crate::scene_test::expr::{Verdict, context};
use crate::scene_test::file::{DEFAULT_SIZE, Expectation, Input, SceneTest, Screenshot, What, When, located};
use crate::scene_test::golden::{compare, diff_image};
use crate::scene_test::state::{Reads, Scope};
use bevy::app::App;
use cel::Context;
use image::RgbaImage;
use serde_json::Value as Json;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// How tests run.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Write golden images that are missing or differ, instead of failing.
    pub bless: bool,
    /// Where a failed test's files go, one folder per test.
    pub artifacts: PathBuf,
}

/// How a test ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Every expectation held.
    Passed,
    /// An expectation did not hold, or the runs differed.
    Failed,
    /// The test cannot run as written: its scene or input is invalid, or an expression names
    /// what the scene does not have.
    Invalid,
}

/// What running a test found.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The test's name.
    pub name: String,
    /// Its file.
    pub file: PathBuf,
    /// Passed, failed or invalid.
    pub status: Status,
    /// Wall-clock time, every run together.
    pub wall: Duration,
    /// What went wrong, where it is written, in the order found.
    pub failures: Vec<FileError>,
    /// Golden images written by `bless`.
    pub blessed: Vec<PathBuf>,
    /// The folder of the failure's files, when written.
    pub artifacts: Option<PathBuf>,
    /// Expressions evaluated.
    pub evaluations: u64,
    /// Wall-clock time spent reading the state and evaluating expressions.
    pub checking: Duration,
}

/// Runs `test`.
pub fn run_test(test: &SceneTest, settings: &Settings) -> Outcome {
    let started = Instant::now();
    let mut outcome = Outcome {
        name: test.name.clone(),
        file: test.file.clone(),
        status: Status::Passed,
        wall: Duration::ZERO,
        failures: Vec::new(),
        blessed: Vec::new(),
        artifacts: None,
        evaluations: 0,
        checking: Duration::ZERO,
    };
    let folder = settings.artifacts.join(&test.name);
    // A folder left by an earlier failure would mislead.
    let _ = std::fs::remove_dir_all(&folder);
    let result = catch_unwind(AssertUnwindSafe(|| run_passes(test, settings, &folder, &mut outcome)));
    match result {
        Ok(Ok(())) => {}
        Ok(Err(invalid)) => {
            outcome.status = Status::Invalid;
            outcome.failures.extend(invalid);
        }
        Err(panic) => {
            let message = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "no message".into());
            outcome.status = Status::Failed;
            outcome.failures.push(FileError::whole_file(&test.scene, format!("the scene panicked: {message}")));
        }
    }
    if outcome.status == Status::Passed && !outcome.failures.is_empty() {
        outcome.status = Status::Failed;
    }
    if folder.is_dir() {
        outcome.artifacts = Some(folder);
    }
    outcome.wall = started.elapsed();
    outcome
}

/// Runs every pass of `test`; `Err` when it cannot run as written.
fn run_passes(
    test: &SceneTest,
    settings: &Settings,
    folder: &Path,
    outcome: &mut Outcome,
) -> Result<(), Vec<FileError>> {
    entity_kinds().load(&test.scene).map_err(|error| vec![error])?;
    let timeline = match &test.input {
        Input::None => None,
        Input::File(path) => Some(Timeline::load(path).map_err(|error| vec![error])?),
        Input::Inline(events) => Some(Timeline::new(events.clone())),
    };
    let mut first_dump: Option<Json> = None;
    for pass in 0..test.repeat {
        let mut run = Pass::start(test, timeline.clone())?;
        let checking = pass == 0;
        let dump = run.go(checking, settings, folder, outcome);
        match &first_dump {
            None => first_dump = Some(dump),
            Some(first) => {
                if let Some(difference) = first_difference(first, &dump, "") {
                    let message = format!("repeat: run {} gave another dump than run 1: {difference}", pass + 1);
                    outcome.failures.push(FileError::whole_file(&test.file, message));
                    break;
                }
            }
        }
    }
    Ok(())
}

/// One run of a test's scene.
struct Pass<'t> {
    test: &'t SceneTest,
    app: App,
    /// The variables any expression reads.
    roots: Vec<String>,
    /// What of them the expressions read.
    reads: Reads,
    /// CEL's environment and Canopy's functions; each step binds its variables in a scope
    /// inside it.
    root: Context<'static, 'static>,
    /// Per expectation: done with (an `eventually` met, an `always` failed once).
    settled: Vec<bool>,
    /// Per expectation: what an `eventually` read last, for its message at the deadline.
    last_values: Vec<String>,
}

impl<'t> Pass<'t> {
    /// Loads the scene and checks the input and every expression's names against it.
    fn start(test: &'t SceneTest, timeline: Option<Timeline>) -> Result<Self, Vec<FileError>> {
        let size = test
            .expectations
            .iter()
            .find_map(|e| if let What::Screenshot(shot) = &e.what { Some(shot.size) } else { None })
            .unwrap_or(DEFAULT_SIZE);
        let from = if let Input::File(path) = &test.input { path } else { &test.file };
        let mut app = live_app(&test.scene, size, timeline.map(|t| (t, from.as_path())), false).map_err(|error| {
            vec![match error {
                // A timeline that does not fit the scene, where the test names or writes it.
                RunError::Parameter { error, .. } => {
                    let message = match &test.input {
                        Input::File(path) => format!("{}: {error}", path.display()),
                        _ => error.to_string(),
                    };
                    match test.input_origin {
                        Some((line, column)) => FileError::at(&test.file, line, column, message),
                        None => FileError::whole_file(&test.file, message),
                    }
                }
                RunError::Invalid(error) => error,
                RunError::Load(message) => FileError::whole_file(&test.scene, message),
            }]
        })?;
        let scope = Scope::of(app.world_mut(), None);
        let mut errors = Vec::new();
        let mut reads = Reads::default();
        for expectation in &test.expectations {
            if let What::That(check) = &expectation.what {
                if let Err(error) = check.check_names(&scope.variables) {
                    errors.push(located(&test.file, expectation.origin, error));
                }
                check.paths().for_each(|path| reads.add(path));
            }
        }
        if !errors.is_empty() {
            return Err(errors);
        }
        let roots = reads.roots();
        let count = test.expectations.len();
        Ok(Self {
            test,
            app,
            roots,
            reads,
            root: context(),
            settled: vec![false; count],
            last_values: vec![String::new(); count],
        })
    }

    /// Takes every step, checking as it goes (when `checking`), and returns the last dump.
    fn go(&mut self, checking: bool, settings: &Settings, folder: &Path, outcome: &mut Outcome) -> Json {
        let steps = self.test.steps;
        let mut failed_once = false;
        let mut frame_kept = false;
        for step in 0..=steps {
            let rendered = step > 0 && self.wants_frame(step);
            if step > 0 {
                if rendered {
                    let size = self.screenshot_size(step).unwrap_or(DEFAULT_SIZE);
                    let world = self.app.world_mut();
                    world.resource_mut::<RasterTarget>().size = size;
                    world.resource_mut::<RenderPolicy>().requested = true;
                }
                self.app.update();
            }
            if !checking {
                continue;
            }
            let before = outcome.failures.len();
            let started = Instant::now();
            self.check_step(step, settings, folder, outcome);
            outcome.checking += started.elapsed();
            if outcome.failures.len() > before && !failed_once {
                failed_once = true;
                frame_kept = rendered && self.keep_frame(step, folder);
            }
        }
        if failed_once && !frame_kept {
            self.keep_frame(steps, folder);
        }
        dump_state(self.app.world_mut())
    }

    /// Whether step `step` draws a frame: for a screenshot, for an `at` expression (the frame
    /// of its failure), and the last step.
    fn wants_frame(&self, step: u64) -> bool {
        step == self.test.steps || self.test.expectations.iter().any(|e| e.when == When::At(step))
    }

    fn screenshot_size(&self, step: u64) -> Option<bevy::math::UVec2> {
        self.test.expectations.iter().find_map(|e| match &e.what {
            What::Screenshot(shot) if e.when == When::At(step) => Some(shot.size),
            _ => None,
        })
    }

    fn check_step(&mut self, step: u64, settings: &Settings, folder: &Path, outcome: &mut Outcome) {
        let due = |e: &Expectation, settled: bool| match e.when {
            When::At(at) => at == step,
            When::Always => step > 0 && !settled,
            When::Eventually(deadline) => step <= deadline && !settled,
        };
        if !self.test.expectations.iter().zip(&self.settled).any(|(e, settled)| due(e, *settled)) {
            return;
        }
        let scope = Scope::of(self.app.world_mut(), Some(&self.roots));
        let context = scope.bind(&self.root, &self.reads);
        let time = step as f64 / FIXED_HZ;
        for (index, expectation) in self.test.expectations.iter().enumerate() {
            if !due(expectation, self.settled[index]) {
                continue;
            }
            let fail = |message: String| {
                FileError::at(&self.test.file, expectation.origin.line, expectation.origin.column, message)
            };
            match &expectation.what {
                What::That(check) => {
                    outcome.evaluations += 1;
                    let verdict = check.evaluate(&context);
                    let expression = check.source();
                    let problem = match &verdict {
                        Verdict::True => None,
                        Verdict::False => Some(format!("{expression} is false")),
                        Verdict::Error(error) => Some(format!("{expression} cannot be evaluated: {error}")),
                    };
                    match (expectation.when, problem) {
                        (When::Eventually(_), None) => self.settled[index] = true,
                        (When::Eventually(deadline), Some(_)) => {
                            self.last_values[index] = check.values_read(&context);
                            if step == deadline {
                                let message = format!(
                                    "by {:.3} s: {expression} never held (at {:.3} s: {})",
                                    deadline as f64 / FIXED_HZ,
                                    time,
                                    self.last_values[index]
                                );
                                outcome.failures.push(fail(message));
                            }
                        }
                        (_, None) => {}
                        (when, Some(problem)) => {
                            let first = if when == When::Always { " (the first step it fails)" } else { "" };
                            let values = check.values_read(&context);
                            outcome.failures.push(fail(format!("at {time:.3} s{first}: {problem} ({values})")));
                            self.settled[index] = true;
                        }
                    }
                }
                What::Screenshot(shot) => {
                    let frame = self.frame();
                    if let Some(message) = judge_frame(&frame, shot, settings, folder, outcome) {
                        outcome.failures.push(fail(format!("at {time:.3} s: {message}")));
                    }
                }
            }
        }
        if outcome.failures.is_empty() {
            return;
        }
        // The dump of the first failure stays; `go` keeps the frame.
        let dump_path = folder.join("dump.json");
        if !dump_path.exists() && std::fs::create_dir_all(folder).is_ok() {
            let _ = write_dump(&dump_path, &dump_state(self.app.world_mut()));
        }
    }

    /// Writes the frame drawn at `step` into `folder`; whether it could.
    fn keep_frame(&self, step: u64, folder: &Path) -> bool {
        let path = folder.join(format!("frame-{:.3}s.png", step as f64 / FIXED_HZ));
        write_image(&path, &self.frame()).is_ok()
    }

    fn frame(&self) -> RgbaImage {
        let framebuffer = &self.app.world().resource::<RasterTarget>().framebuffer;
        RgbaImage::from_raw(framebuffer.width(), framebuffer.height(), framebuffer.color().to_vec())
            .expect("a framebuffer holds width x height RGBA pixels")
    }
}

/// Compares a frame with its golden image, blessing it when asked; the reason it fails, with
/// the frame, the golden and their diff written into `folder`.
fn judge_frame(
    frame: &RgbaImage,
    shot: &Screenshot,
    settings: &Settings,
    folder: &Path,
    outcome: &mut Outcome,
) -> Option<String> {
    let stem = shot.golden.file_stem().map_or_else(|| "frame".into(), |s| s.to_string_lossy().into_owned());
    let golden_name = shot.golden.display();
    let bless = |outcome: &mut Outcome| match write_image(&shot.golden, frame) {
        Ok(()) => {
            outcome.blessed.push(shot.golden.clone());
            None
        }
        Err(error) => Some(format!("cannot write the golden image {golden_name}: {error}")),
    };
    let keep_frame = || write_image(&folder.join(format!("{stem}.png")), frame).err();
    let golden = match image::open(&shot.golden) {
        Err(_) if !shot.golden.exists() => {
            if settings.bless {
                return bless(outcome);
            }
            let kept = keep_frame().map(|e| format!(" (the frame could not be kept: {e})")).unwrap_or_default();
            return Some(format!(
                "no golden image at {golden_name}; run with --bless to write it from this frame{kept}"
            ));
        }
        Err(error) => return Some(format!("cannot read the golden image {golden_name}: {error}")),
        Ok(golden) => golden.to_rgba8(),
    };
    if golden.dimensions() != frame.dimensions() {
        if settings.bless {
            return bless(outcome);
        }
        keep_frame();
        let (gw, gh) = golden.dimensions();
        return Some(format!(
            "the golden image {golden_name} is {gw}x{gh}, the frame {}x{}; run with --bless to replace it",
            frame.width(),
            frame.height()
        ));
    }
    let difference = compare(frame, &golden, shot.tolerance);
    if difference.within(shot.tolerance) {
        return None;
    }
    if settings.bless {
        return bless(outcome);
    }
    keep_frame();
    let _ = write_image(&folder.join(format!("{stem}.golden.png")), &golden);
    let _ = write_image(&folder.join(format!("{stem}.diff.png")), &diff_image(frame, &golden, shot.tolerance));
    Some(format!(
        "the frame differs from {golden_name} in {:.2} % of its pixels by more than {} (at most {:.2} % may); \
         largest difference {}; frame, golden and diff in {}",
        difference.share() * 100.0,
        shot.tolerance.channel,
        shot.tolerance.pixels * 100.0,
        difference.largest,
        folder.display()
    ))
}

fn write_image(path: &Path, image: &RgbaImage) -> Result<(), String> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(|e| e.to_string())?;
    }
    image.save(path).map_err(|e| e.to_string())
}

/// The first place two dumps differ, as `path: a != b`.
fn first_difference(a: &Json, b: &Json, path: &str) -> Option<String> {
    match (a, b) {
        (Json::Object(a), Json::Object(b)) => {
            for (key, value) in a {
                let here = if path.is_empty() { key.clone() } else { format!("{path}.{key}") };
                match b.get(key) {
                    Some(other) => {
                        if let Some(found) = first_difference(value, other, &here) {
                            return Some(found);
                        }
                    }
                    None => return Some(format!("{here} is missing from the later run")),
                }
            }
            b.keys().find(|key| !a.contains_key(*key)).map(|key| format!("{path}.{key} appears in the later run"))
        }
        (Json::Array(a), Json::Array(b)) if a.len() == b.len() => {
            a.iter().zip(b).enumerate().find_map(|(i, (a, b))| first_difference(a, b, &format!("{path}[{i}]")))
        }
        _ if a == b => None,
        _ => Some(format!("{path}: {a} != {b}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn names_the_first_difference_of_two_dumps() {
        let a = json!({"time": 1.0, "entities": [{"name": "a", "x": 1.0}, {"name": "b", "x": 2.0}]});
        let mut b = a.clone();
        assert_eq!(first_difference(&a, &b, ""), None);
        b["entities"][1]["x"] = json!(2.5);
        assert_eq!(first_difference(&a, &b, "").unwrap(), "entities[1].x: 2.0 != 2.5");
    }
}
