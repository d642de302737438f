//! `canopy test`: runs scene tests (see [`crate::scene_test`]) with a progress bar, a line per
//! test, each failure in full and the tally; exits 0 when all pass, 1 when one fails, 2 on a
//! bad command line or a test that cannot run as written.

use crate::scene_test::report;
use crate::scene_test::runner::{Outcome, Settings};
use crate::scene_test::suite::{Shard, find_files, load_all, run_all, select};
use indicatif::{ProgressBar, ProgressStyle};
use notify_debouncer_full::new_debouncer;
use notify_debouncer_full::notify::RecursiveMode;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::mpsc;
use std::time::Duration;

/// Runs scene tests (`*.test.yaml`) and reports what held and what did not.
#[derive(clap::Args, Debug)]
pub struct TestArgs {
    /// Test files, or folders searched for `*.test.yaml` [default: tests/scenes, else the
    /// current folder].
    paths: Vec<PathBuf>,
    /// Tests run at once [default: the cores].
    #[arg(long, short, value_parser = clap::value_parser!(u16).range(1..=256))]
    jobs: Option<u16>,
    /// Run only the tests whose name contains this text.
    #[arg(long)]
    filter: Option<String>,
    /// List the tests that would run, and run none.
    #[arg(long)]
    list: bool,
    /// Write the results as JUnit XML to this file.
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Print the results as JSON on stdout (the lines go to stderr).
    #[arg(long)]
    json: bool,
    /// Run the K-th of N parts of the suite (1 <= K <= N), for a CI matrix.
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    /// Write golden images that are missing or differ from the frame, and say which.
    #[arg(long)]
    bless: bool,
    /// After the run, run a test again whenever its test file, scene or timeline changes.
    #[arg(long)]
    watch: bool,
    /// Where a failed test leaves its dump, frame, golden and diff, a folder per test.
    #[arg(long, value_name = "DIR", default_value = "target/canopy-test")]
    artifacts: PathBuf,
}

impl TestArgs {
    /// Finds, reads, runs and reports; watches when asked.
    pub fn test(self) -> ExitCode {
        let settings = Settings { bless: self.bless, artifacts: self.artifacts.clone() };
        let code = self.run_once(&settings, None).unwrap_or(2);
        if !self.watch {
            return ExitCode::from(code);
        }
        match self.watch(&settings) {
            Ok(()) => ExitCode::SUCCESS,
            Err(error) => {
                eprintln!("--watch: {error}");
                ExitCode::from(2)
            }
        }
    }

    /// One run of the suite, or of the tests that read one of `changed`; the exit code, or
    /// `None` when the test files could not be read.
    fn run_once(&self, settings: &Settings, changed: Option<&BTreeSet<PathBuf>>) -> Option<u8> {
        let files = match find_files(&self.paths) {
            Ok(files) => files,
            Err(error) => {
                eprintln!("{error}");
                return None;
            }
        };
        let (tests, errors) = load_all(&files);
        for error in &errors {
            eprintln!("{error}");
        }
        if !errors.is_empty() {
            eprintln!(
                "{} test file{} cannot be read; nothing ran",
                errors.len(),
                if errors.len() == 1 { "" } else { "s" }
            );
            return None;
        }
        let mut tests = select(tests, self.filter.as_deref(), self.shard);
        if let Some(changed) = changed {
            tests.retain(|test| test.inputs().iter().any(|input| changed.contains(&canonical(input))));
        }
        if self.list {
            tests.iter().for_each(|test| println!("{}", test.name));
            return Some(0);
        }
        let jobs = self.jobs.map_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()), usize::from);
        let bar = ProgressBar::new(tests.len() as u64);
        bar.set_style(
            ProgressStyle::with_template("{bar:32} {pos}/{len} tests, {elapsed}")
                .expect("the template is valid")
                .progress_chars("=> "),
        );
        let say = |text: String| {
            bar.suspend(|| if self.json { eprintln!("{text}") } else { println!("{text}") });
        };
        let outcomes = run_all(&tests, jobs, settings, |outcome: &Outcome| {
            say(report::line(outcome));
            for golden in &outcome.blessed {
                say(format!("        wrote {}", golden.display()));
            }
            bar.inc(1);
        });
        bar.finish_and_clear();
        for outcome in outcomes.iter().filter(|o| !o.failures.is_empty()) {
            say(report::failures(outcome));
        }
        say(report::tally(&outcomes));
        if self.json {
            println!("{}", serde_json::to_string_pretty(&report::json(&outcomes)).expect("JSON of plain values"));
        }
        if let Some(path) = &self.junit
            && let Err(error) = std::fs::write(path, report::junit(&outcomes))
        {
            eprintln!("{}: cannot write the JUnit report: {error}", path.display());
            return Some(2);
        }
        Some(report::exit_code(&outcomes))
    }

    /// Waits for changes to the files the tests read, and reruns the tests that read them.
    fn watch(&self, settings: &Settings) -> Result<(), String> {
        let (sender, events) = mpsc::channel();
        let mut debouncer = new_debouncer(Duration::from_millis(200), None, sender).map_err(|e| e.to_string())?;
        let mut watched: BTreeSet<PathBuf> = BTreeSet::new();
        loop {
            // Folders, not files: editors replace a file when saving it.
            for folder in self.folders_read() {
                if watched.insert(folder.clone()) {
                    debouncer
                        .watch(&folder, RecursiveMode::NonRecursive)
                        .map_err(|e| format!("{}: {e}", folder.display()))?;
                }
            }
            eprintln!("watching for changes (Ctrl-C stops)");
            let batch = events.recv().map_err(|e| e.to_string())?;
            let mut changed: BTreeSet<PathBuf> = BTreeSet::new();
            for event in batch.into_iter().flatten() {
                changed.extend(event.event.paths.iter().map(|path| canonical(path)));
            }
            // More events may have queued while the first arrived.
            while let Ok(batch) = events.try_recv() {
                for event in batch.into_iter().flatten() {
                    changed.extend(event.event.paths.iter().map(|path| canonical(path)));
                }
            }
            if !changed.is_empty() {
                self.run_once(settings, Some(&changed));
            }
        }
    }

    /// The folders holding the test files, their scenes and timelines.
    fn folders_read(&self) -> BTreeSet<PathBuf> {
        let files = find_files(&self.paths).unwrap_or_default();
        let (tests, _) = load_all(&files);
        let mut inputs: Vec<PathBuf> = files;
        inputs.extend(tests.iter().flat_map(|test| test.inputs()));
        inputs.iter().filter_map(|path| canonical(path).parent().map(Path::to_path_buf)).collect()
    }
}

/// A path made absolute and free of `..`, as file events name it; as given when it does not
/// exist.
fn canonical(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}
