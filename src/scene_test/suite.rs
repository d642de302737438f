//! A suite of scene tests: found in files and folders, read whole before any runs, chosen by
//! name and shard, and run in parallel, each test in an app of its own.

use crate::foundation::yaml::FileError;
use crate::scene_test::file::{SceneTest, TEST_FILE_SUFFIX, load};
use crate::scene_test::runner::{Outcome, Settings, run_test};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The folder searched when none is named, if it exists.
pub const DEFAULT_FOLDER: &str = "tests/scenes";
/// Most test files one search takes.
const MAX_FILES: usize = 10_000;

/// Test files named on the command line, or found in the folders it names (recursively,
/// in name order). No paths: [`DEFAULT_FOLDER`] if there is one, else the current folder.
pub fn find_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    let defaults;
    let paths = if paths.is_empty() {
        let folder = Path::new(DEFAULT_FOLDER);
        defaults = [if folder.is_dir() { folder.to_path_buf() } else { PathBuf::from(".") }];
        &defaults[..]
    } else {
        paths
    };
    let mut files = Vec::new();
    for path in paths {
        if path.is_dir() {
            let before = files.len();
            search(path, &mut files)?;
            files[before..].sort();
        } else if path.is_file() {
            files.push(path.clone());
        } else {
            return Err(format!("{}: no such file or folder", path.display()));
        }
    }
    Ok(files)
}

fn search(folder: &Path, out: &mut Vec<PathBuf>) -> Result<(), String> {
    let entries = std::fs::read_dir(folder).map_err(|error| format!("{}: {error}", folder.display()))?;
    for entry in entries.flatten() {
        let path = entry.path();
        let Ok(kind) = entry.file_type() else { continue };
        if kind.is_dir() {
            search(&path, out)?;
        } else if path.file_name().is_some_and(|name| name.to_string_lossy().ends_with(TEST_FILE_SUFFIX)) {
            if out.len() == MAX_FILES {
                return Err(format!("{}: more than {MAX_FILES} test files", folder.display()));
            }
            out.push(path);
        }
    }
    Ok(())
}

/// Reads every file; the tests of the valid ones, and the errors of the others.
pub fn load_all(files: &[PathBuf]) -> (Vec<SceneTest>, Vec<FileError>) {
    let mut tests = Vec::new();
    let mut errors = Vec::new();
    for file in files {
        match load(file) {
            Ok(found) => tests.extend(found),
            Err(error) => errors.push(error),
        }
    }
    (tests, errors)
}

/// One of `count` parts of a suite, numbered from 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which part, 1 to `count`.
    pub index: usize,
    /// How many parts.
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let error = || format!("expected K/N with 1 <= K <= N, e.g. 2/3; found `{text}`");
        let (k, n) = text.split_once('/').ok_or_else(error)?;
        let (index, count) = (k.parse::<usize>().map_err(|_| error())?, n.parse::<usize>().map_err(|_| error())?);
        if index >= 1 && index <= count { Ok(Self { index, count }) } else { Err(error()) }
    }
}

/// The tests whose name contains `filter`, then those of `shard`: the tests in name order,
/// dealt round the shards like cards, so every test is in exactly one shard and the split
/// is the same on every machine.
pub fn select(mut tests: Vec<SceneTest>, filter: Option<&str>, shard: Option<Shard>) -> Vec<SceneTest> {
    tests.retain(|test| filter.is_none_or(|text| test.name.contains(text)));
    tests.sort_by(|a, b| a.name.cmp(&b.name).then_with(|| a.file.cmp(&b.file)));
    match shard {
        None => tests,
        Some(shard) => {
            tests.into_iter().enumerate().filter(|(i, _)| i % shard.count == shard.index - 1).map(|(_, t)| t).collect()
        }
    }
}

/// Runs `tests` on `jobs` threads, calling `done` as each finishes; the outcomes in the
/// tests' order.
pub fn run_all(tests: &[SceneTest], jobs: usize, settings: &Settings, done: impl Fn(&Outcome) + Sync) -> Vec<Outcome> {
    let next = AtomicUsize::new(0);
    let outcomes: Mutex<Vec<Option<Outcome>>> = Mutex::new(vec![None; tests.len()]);
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, tests.len().max(1)) {
            scope.spawn(|| {
                loop {
                    let index = next.fetch_add(1, Ordering::Relaxed);
                    let Some(test) = tests.get(index) else { break };
                    let outcome = run_test(test, settings);
                    done(&outcome);
                    outcomes.lock().unwrap_or_else(|poisoned| poisoned.into_inner())[index] = Some(outcome);
                }
            });
        }
    });
    outcomes.into_inner().unwrap_or_else(|poisoned| poisoned.into_inner()).into_iter().flatten().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_test::file::Input;

    fn test(name: &str) -> SceneTest {
        SceneTest {
            name: name.into(),
            file: PathBuf::from(format!("{name}.test.yaml")),
            scene: PathBuf::from("scene.yaml"),
            steps: 1,
            input: Input::None,
            input_origin: None,
            repeat: 1,
            expectations: Vec::new(),
        }
    }

    #[test]
    fn shards_cover_the_suite_exactly_once_the_same_way_every_time() {
        let names: Vec<String> = (0..23).map(|i| format!("t{i:02}")).collect();
        let suite = || names.iter().rev().map(|n| test(n)).collect::<Vec<_>>();
        for count in 1..=5 {
            let mut seen: Vec<String> = Vec::new();
            for index in 1..=count {
                let shard = Some(Shard { index, count });
                let part: Vec<String> = select(suite(), None, shard).into_iter().map(|t| t.name).collect();
                let again: Vec<String> = select(suite(), None, shard).into_iter().map(|t| t.name).collect();
                assert_eq!(part, again);
                assert!(part.len() >= 23 / count && part.len() <= 23 / count + 1, "balanced: {}", part.len());
                seen.extend(part);
            }
            seen.sort();
            assert_eq!(seen, names, "{count} shards");
        }
    }

    #[test]
    fn filters_by_name_and_reads_shards() {
        let picked = select(vec![test("sloth"), test("biceps"), test("sloth_fruit")], Some("sloth"), None);
        assert_eq!(picked.iter().map(|t| t.name.as_str()).collect::<Vec<_>>(), ["sloth", "sloth_fruit"]);
        assert_eq!("2/3".parse::<Shard>(), Ok(Shard { index: 2, count: 3 }));
        for bad in ["0/3", "4/3", "3", "a/b", "1/0"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }
}
