//! The `canopy` command: play a scene in a window, run it headless, check scene files,
//! generate tree scenes and heightmaps, and measure (see [`canopy::cli`]).

fn main() -> std::process::ExitCode {
    canopy::cli::main()
}
