//! Scene test files (`*.test.yaml`): the scene under test, how long it runs and with what
//! input, and what must hold. Read and checked whole before anything runs; every problem is
//! a [`FileError`] at its line and column.
//!
//! ```yaml
//! scene: ../../scenes/sloth.yaml
//! seconds: 20                       # or frames: N (fixed 60 Hz steps)
//! input: ../../timelines/sloth_walk.yaml   # or timeline: [events, as in a timeline file]
//! repeat: 2                         # run twice, the dumps must be identical
//! expect:
//!   - { at: 10, that: sloth.distance_travelled > 0.8 }
//!   - always: sloth.min_body_clearance >= 0
//!   - { eventually: 'sloth.support == "tree/bough"', before: 15 }
//!   - { at: 20, screenshot: golden/sloth_20s.png, size: [320, 240], tolerance: { channel: 8, pixels: 0.002 } }
//! ```
//!
//! A file may instead hold several tests of one scene under `tests:`, each with a `name` and
//! its own `expect`; what the file sets beside `scene` is the default of each.

use crate::app::FIXED_HZ;
use crate::controls::timeline::{Seconds, TimelineEvent};
use crate::foundation::yaml::{FileError, parse_yaml};
use crate::raster::MAX_TARGET_SIZE;
use crate::scene_test::expr::{Check, ExprError};
use crate::scene_test::golden::Tolerance;
use crate::scene_test::locate::{Step, locate};
use bevy::math::UVec2;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Longest run a test may ask for, in simulated seconds.
pub const MAX_SECONDS: f64 = 3600.0;
/// Most runs of one test that `repeat` may ask for.
pub const MAX_REPEAT: u32 = 10;
/// Most tests in one file, and most expectations in one test.
pub const MAX_ENTRIES: usize = 1000;
/// Largest test file read, in bytes.
pub const MAX_FILE_BYTES: u64 = 1 << 20;
/// The frame size of a screenshot that names none, in pixels.
pub const DEFAULT_SIZE: UVec2 = UVec2::new(320, 240);

/// One scene test, ready to run.
#[derive(Debug)]
pub struct SceneTest {
    /// The name it is listed and filtered by: the file's name without `.test.yaml`, then
    /// `/name` for one of several tests in a file.
    pub name: String,
    /// The test file.
    pub file: PathBuf,
    /// The scene under test.
    pub scene: PathBuf,
    /// Fixed steps to take.
    pub steps: u64,
    /// Scripted input.
    pub input: Input,
    /// Where the input is named or written, for its errors.
    pub input_origin: Option<(usize, usize)>,
    /// Runs whose dumps must all be identical (at least 1).
    pub repeat: u32,
    /// What must hold, in file order.
    pub expectations: Vec<Expectation>,
}

impl SceneTest {
    /// The files the test reads: the test file, the scene and the timeline file.
    pub fn inputs(&self) -> Vec<PathBuf> {
        let mut files = vec![self.file.clone(), self.scene.clone()];
        if let Input::File(timeline) = &self.input {
            files.push(timeline.clone());
        }
        files
    }
}

/// Scripted input of a test.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// None.
    None,
    /// A timeline file.
    File(PathBuf),
    /// Timeline events written in the test file.
    Inline(Vec<TimelineEvent>),
}

/// When an expectation is checked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum When {
    /// After this step (0: the scene as loaded, before the first step).
    At(u64),
    /// After every step.
    Always,
    /// After some step no later than this one.
    Eventually(u64),
}

/// What an expectation checks.
#[derive(Debug)]
pub enum What {
    /// An expression that must be true.
    That(Check),
    /// The frame, against a golden image.
    Screenshot(Screenshot),
}

/// A golden frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Screenshot {
    /// The golden image, resolved against the test file's folder.
    pub golden: PathBuf,
    /// The frame's size in pixels.
    pub size: UVec2,
    /// How far the frame may stray.
    pub tolerance: Tolerance,
}

/// One expectation, with where it is written.
#[derive(Debug)]
pub struct Expectation {
    /// When it is checked.
    pub when: When,
    /// What it checks.
    pub what: What,
    /// Where its expression or image name is written.
    pub origin: Origin,
}

/// Where a value is written in a test file, to place positions inside it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Origin {
    /// 1-based line and column of the value.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
    /// The value is quoted: its text starts a column later.
    quoted: bool,
    /// The value is a block scalar (`|` or `>`): its text starts on the next line.
    block: bool,
}

impl Origin {
    fn at(text: &str, (line, column): (usize, usize)) -> Self {
        let first = text.lines().nth(line - 1).and_then(|l| l.chars().nth(column - 1));
        Self { line, column, quoted: matches!(first, Some('"' | '\'')), block: matches!(first, Some('|' | '>')) }
    }

    /// The file's line and column of a position inside the value's text.
    pub fn place(&self, line: usize, column: usize) -> (usize, usize) {
        if self.block {
            (self.line + line, column)
        } else if line == 1 {
            (self.line, self.column + usize::from(self.quoted) + column - 1)
        } else {
            (self.line + line - 1, column)
        }
    }
}

// Serde's `flatten` would share the settings' fields between these two, but loses
// `deny_unknown_fields` and the positions of errors inside them.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    scene: String,
    seconds: Option<Seconds>,
    frames: Option<u64>,
    input: Option<String>,
    timeline: Option<Vec<TimelineEvent>>,
    repeat: Option<u32>,
    expect: Option<Vec<RawExpectation>>,
    tests: Option<Vec<RawTest>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTest {
    name: String,
    seconds: Option<Seconds>,
    frames: Option<u64>,
    input: Option<String>,
    timeline: Option<Vec<TimelineEvent>>,
    repeat: Option<u32>,
    expect: Vec<RawExpectation>,
}

/// What a test file sets for every test, and each test may set for itself.
#[derive(Clone)]
struct RawSettings {
    seconds: Option<Seconds>,
    frames: Option<u64>,
    input: Option<String>,
    timeline: Option<Vec<TimelineEvent>>,
    repeat: Option<u32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawExpectation {
    at: Option<Seconds>,
    that: Option<String>,
    screenshot: Option<String>,
    size: Option<[u32; 2]>,
    tolerance: Option<Tolerance>,
    always: Option<String>,
    eventually: Option<String>,
    before: Option<Seconds>,
}

/// Reads a test file into its tests.
pub fn load(path: &Path) -> Result<Vec<SceneTest>, FileError> {
    let size = std::fs::metadata(path).map_err(|error| FileError::unreadable(path, error))?.len();
    if size > MAX_FILE_BYTES {
        return Err(FileError::whole_file(path, format!("the file is {size} bytes, more than {MAX_FILE_BYTES}")));
    }
    let bytes = std::fs::read(path).map_err(|error| FileError::unreadable(path, error))?;
    let raw: RawFile = parse_yaml(path, &bytes, "a scene test: `scene:`, `seconds:` and `expect:`")?;
    let text = String::from_utf8_lossy(&bytes);
    Reader { path, text: &text }.tests(raw)
}

/// The ending that marks a scene test file.
pub const TEST_FILE_SUFFIX: &str = ".test.yaml";

/// The name a test file gives its tests: its file name without `.test.yaml`.
pub fn file_stem(path: &Path) -> String {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    name.strip_suffix(TEST_FILE_SUFFIX).or_else(|| name.strip_suffix(".yaml")).unwrap_or(&name).to_string()
}

/// Reads one file's raw content into tests, locating every problem in `text`.
struct Reader<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Reader<'_> {
    fn error(&self, at: &[Step], message: impl Into<String>) -> FileError {
        match locate(self.text, at) {
            Some((line, column)) => FileError::at(self.path, line, column, message),
            None => FileError::whole_file(self.path, message),
        }
    }

    fn resolve(&self, relative: &str) -> PathBuf {
        self.path.parent().unwrap_or(Path::new("")).join(relative)
    }

    fn tests(&self, raw: RawFile) -> Result<Vec<SceneTest>, FileError> {
        let scene = self.resolve(&raw.scene);
        if !scene.is_file() {
            return Err(self.error(&[Step::Key("scene")], format!("scene: no file at {}", scene.display())));
        }
        let stem = file_stem(self.path);
        let defaults = RawSettings {
            seconds: raw.seconds,
            frames: raw.frames,
            input: raw.input,
            timeline: raw.timeline,
            repeat: raw.repeat,
        };
        match (raw.expect, raw.tests) {
            (Some(_), Some(_)) => Err(self.error(
                &[Step::Key("tests")],
                "tests: a file holds either `expect:` (one test) or `tests:` (several), not both",
            )),
            (None, None) => Err(self.error(&[], "expected `expect:`, a list of what must hold, or `tests:`")),
            (Some(expect), None) => Ok(vec![self.test(stem, &scene, &defaults, expect, &[])?]),
            (None, Some(tests)) => {
                if tests.is_empty() || tests.len() > MAX_ENTRIES {
                    return Err(self.error(&[Step::Key("tests")], format!("tests: expected 1 to {MAX_ENTRIES} tests")));
                }
                let mut out: Vec<SceneTest> = Vec::new();
                for (index, test) in tests.into_iter().enumerate() {
                    let at = [Step::Key("tests"), Step::Index(index)];
                    let valid = test.name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
                    if test.name.is_empty() || test.name.len() > 64 || !valid {
                        return Err(self.error(
                            &[at[0], at[1], Step::Key("name")],
                            format!("name: expected 1 to 64 letters, digits, `_` or `-`, found \"{}\"", test.name),
                        ));
                    }
                    let name = format!("{stem}/{}", test.name);
                    if out.iter().any(|earlier| earlier.name == name) {
                        return Err(self.error(
                            &[at[0], at[1], Step::Key("name")],
                            format!("name: another test of this file is named \"{}\"", test.name),
                        ));
                    }
                    let own = RawSettings {
                        seconds: test.seconds,
                        frames: test.frames,
                        input: test.input,
                        timeline: test.timeline,
                        repeat: test.repeat,
                    };
                    let settings = merged(&own, &defaults);
                    out.push(self.test(name, &scene, &settings, test.expect, &at)?);
                }
                Ok(out)
            }
        }
    }

    fn test(
        &self,
        name: String,
        scene: &Path,
        settings: &RawSettings,
        expect: Vec<RawExpectation>,
        at: &[Step],
    ) -> Result<SceneTest, FileError> {
        let step = |key| [at, &[Step::Key(key)]].concat();
        let steps = match (settings.seconds, settings.frames) {
            (Some(_), Some(_)) => {
                return Err(self.error(&step("frames"), "frames: give `seconds:` or `frames:`, not both"));
            }
            (None, None) => {
                return Err(self.error(at, "expected `seconds:` or `frames:`, how long the scene runs"));
            }
            (Some(seconds), None) if seconds.0 > MAX_SECONDS => {
                return Err(self.error(&step("seconds"), format!("seconds: at most {MAX_SECONDS}")));
            }
            (Some(seconds), None) => to_steps(seconds.0),
            (None, Some(frames)) if frames as f64 > MAX_SECONDS * FIXED_HZ => {
                return Err(self.error(&step("frames"), format!("frames: at most {}", MAX_SECONDS * FIXED_HZ)));
            }
            (None, Some(frames)) => frames,
        };
        let input = match (&settings.input, &settings.timeline) {
            (Some(_), Some(_)) => {
                return Err(self.error(&step("timeline"), "timeline: give `input:` (a file) or `timeline:`, not both"));
            }
            (Some(file), None) => {
                let file = self.resolve(file);
                if !file.is_file() {
                    return Err(self.error(&step("input"), format!("input: no file at {}", file.display())));
                }
                Input::File(file)
            }
            (None, Some(events)) => Input::Inline(events.clone()),
            (None, None) => Input::None,
        };
        let input_key = if settings.timeline.is_some() { "timeline" } else { "input" };
        let input_origin = locate(self.text, &step(input_key)).or_else(|| locate(self.text, &[Step::Key(input_key)]));
        let repeat = settings.repeat.unwrap_or(1);
        if !(1..=MAX_REPEAT).contains(&repeat) {
            return Err(self.error(&step("repeat"), format!("repeat: expected 1 to {MAX_REPEAT} runs")));
        }
        if expect.is_empty() || expect.len() > MAX_ENTRIES {
            return Err(self.error(
                &step("expect"),
                format!("expect: expected 1 to {MAX_ENTRIES} expectations; a test without any checks nothing"),
            ));
        }
        let mut expectations = Vec::new();
        for (index, raw) in expect.into_iter().enumerate() {
            let at = [at, &[Step::Key("expect"), Step::Index(index)]].concat();
            self.expectation(raw, &at, steps, &mut expectations)?;
        }
        Ok(SceneTest {
            name,
            file: self.path.to_path_buf(),
            scene: scene.to_path_buf(),
            steps,
            input,
            input_origin,
            repeat,
            expectations,
        })
    }

    fn expectation(
        &self,
        raw: RawExpectation,
        at: &[Step],
        steps: u64,
        out: &mut Vec<Expectation>,
    ) -> Result<(), FileError> {
        let field = |key: &'static str| [at, &[Step::Key(key)]].concat();
        let end = steps as f64 / FIXED_HZ;
        let within_run = |key, seconds: Seconds| {
            let step = to_steps(seconds.0);
            if step > steps {
                Err(self.error(&field(key), format!("{key}: {} s is after the run ends at {} s", seconds.0, end)))
            } else {
                Ok(step)
            }
        };
        let only_with = |present: bool, key: &'static str, with: &str| {
            if present {
                Err(self.error(&field(key), format!("{key}: only an `{with}` expectation takes this")))
            } else {
                Ok(())
            }
        };
        only_with(raw.before.is_some() && raw.eventually.is_none(), "before", "eventually")?;
        only_with(raw.that.is_some() && raw.at.is_none(), "that", "at")?;
        only_with(raw.screenshot.is_some() && raw.at.is_none(), "screenshot", "at")?;
        only_with(raw.size.is_some() && raw.screenshot.is_none(), "size", "screenshot")?;
        only_with(raw.tolerance.is_some() && raw.screenshot.is_none(), "tolerance", "screenshot")?;
        let kinds = [raw.at.is_some(), raw.always.is_some(), raw.eventually.is_some()];
        if kinds.iter().filter(|&&k| k).count() != 1 {
            return Err(
                self.error(at, "expected one of `at:` (with `that:` or `screenshot:`), `always:` or `eventually:`")
            );
        }
        if let Some(seconds) = raw.at {
            let when = When::At(within_run("at", seconds)?);
            if raw.that.is_none() && raw.screenshot.is_none() {
                return Err(self.error(&field("at"), "at: say what holds then, with `that:` or `screenshot:`"));
            }
            if let Some(source) = raw.that {
                out.push(self.check(&source, &field("that"), when)?);
            }
            if let Some(golden) = raw.screenshot {
                if when == When::At(0) {
                    let message =
                        format!("at: the first frame is drawn after the first step: from {} s on", 1.0 / FIXED_HZ);
                    return Err(self.error(&field("at"), message));
                }
                let shot = self.screenshot(&golden, raw.size, raw.tolerance, at)?;
                let origin = self.origin(&field("screenshot"));
                out.push(Expectation { when, what: What::Screenshot(shot), origin });
            }
        } else if let Some(source) = raw.always {
            out.push(self.check(&source, &field("always"), When::Always)?);
        } else if let Some(source) = raw.eventually {
            let deadline = raw.before.map(|before| within_run("before", before)).transpose()?.unwrap_or(steps);
            out.push(self.check(&source, &field("eventually"), When::Eventually(deadline))?);
        }
        Ok(())
    }

    fn origin(&self, at: &[Step]) -> Origin {
        Origin::at(self.text, locate(self.text, at).unwrap_or((1, 1)))
    }

    fn check(&self, source: &str, at: &[Step], when: When) -> Result<Expectation, FileError> {
        let origin = self.origin(at);
        let check = Check::compile(source).map_err(|error| located(self.path, origin, error))?;
        Ok(Expectation { when, what: What::That(check), origin })
    }

    fn screenshot(
        &self,
        golden: &str,
        size: Option<[u32; 2]>,
        tolerance: Option<Tolerance>,
        at: &[Step],
    ) -> Result<Screenshot, FileError> {
        let field = |key| [at, &[Step::Key(key)]].concat();
        if !golden.to_ascii_lowercase().ends_with(".png") {
            return Err(self.error(&field("screenshot"), "screenshot: expected a PNG file name, ending in .png"));
        }
        let size = size.map_or(DEFAULT_SIZE, UVec2::from);
        let valid = 1..=MAX_TARGET_SIZE;
        if !valid.contains(&size.x) || !valid.contains(&size.y) {
            return Err(
                self.error(&field("size"), format!("size: expected [width, height], each 1 to {MAX_TARGET_SIZE}"))
            );
        }
        let tolerance = tolerance.unwrap_or_default();
        if !(0.0..=1.0).contains(&tolerance.pixels) {
            return Err(self.error(&field("tolerance"), "tolerance: `pixels` is a share of the frame, from 0 to 1"));
        }
        Ok(Screenshot { golden: self.resolve(golden), size, tolerance })
    }
}

/// An expression's error at its place in the file.
pub fn located(path: &Path, origin: Origin, error: ExprError) -> FileError {
    let (line, column) = origin.place(error.line, error.column);
    FileError::at(path, line, column, error.message)
}

/// A test's own settings, with the file's where it has none.
fn merged(own: &RawSettings, defaults: &RawSettings) -> RawSettings {
    // A test's own duration or input replaces the file's, whichever way either is given.
    let (seconds, frames) = if own.seconds.is_some() || own.frames.is_some() {
        (own.seconds, own.frames)
    } else {
        (defaults.seconds, defaults.frames)
    };
    let (input, timeline) = if own.input.is_some() || own.timeline.is_some() {
        (own.input.clone(), own.timeline.clone())
    } else {
        (defaults.input.clone(), defaults.timeline.clone())
    };
    RawSettings { seconds, frames, input, timeline, repeat: own.repeat.or(defaults.repeat) }
}

/// Simulated seconds as whole fixed steps.
pub fn to_steps(seconds: f64) -> u64 {
    (seconds * FIXED_HZ).round() as u64
}

#[cfg(test)]
mod tests;
