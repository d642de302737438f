//! Scene tests: what a scene author states must hold, as data (`*.test.yaml`), checked by
//! running the scene headless: `canopy test`.
//!
//! | module | what |
//! |---|---|
//! | [`file`] | the test file: scene, duration, input, expectations; located errors |
//! | [`expr`] | expressions in the Common Expression Language, the paths they read |
//! | [`state`] | the variables an expression sees at a step |
//! | [`golden`] | golden frames: comparison within a tolerance, diff images |
//! | [`runner`] | one test: its runs, checks and the files a failure leaves |
//! | [`suite`] | finding, choosing, sharding and running tests in parallel |
//! | [`report`] | lines, tallies, JUnit XML and JSON |
//! | [`locate`] | the line and column of a value in a YAML text |
//!
//! `docs/scene-tests.md` is the reference for people writing tests.

pub mod expr;
pub mod file;
pub mod golden;
pub mod locate;
pub mod report;
pub mod runner;
pub mod state;
pub mod suite;
