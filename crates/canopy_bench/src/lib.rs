//! Canopy's benchmarks live in `benches/`, each against its peers where it has them (rapier3d,
//! noise, fastnoise-lite, euc, Mesa's llvmpipe, aruco-rs). This crate keeps them and their peers
//! out of the engine's own build: `cargo test` and `cargo run` at the root never compile them.
//!
//! Run one with `cargo bench -p canopy_bench --bench NAME` (add `--profile dev` for the profile
//! the figures in `docs/performance.md` were measured with).

use std::path::Path;

/// The workspace's root folder, where the shipped scenes are.
pub const WORKSPACE_ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

/// Makes the workspace's root the working folder, so that scene paths such as
/// `scenes/canopy.yaml` mean what they mean to the app (cargo starts a benchmark in its
/// package's folder).
pub fn at_workspace_root() {
    std::env::set_current_dir(Path::new(WORKSPACE_ROOT)).expect("the workspace root is a folder");
}
