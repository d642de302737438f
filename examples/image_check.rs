//! Checks that a screenshot is not blank: it must hold many distinct colours, including the
//! panel's greys and the scene's colours. Used by the CI's window smoke test.

use std::collections::HashSet;
use std::process::ExitCode;

fn main() -> ExitCode {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: image_check SCREENSHOT.png");
        return ExitCode::from(2);
    };
    let image = match image::open(&path) {
        Ok(image) => image.to_rgb8(),
        Err(error) => {
            eprintln!("{path}: {error}");
            return ExitCode::from(1);
        }
    };
    let colours: HashSet<[u8; 3]> = image.pixels().map(|p| p.0).collect();
    println!("{path}: {}x{}, {} distinct colours", image.width(), image.height(), colours.len());
    if colours.len() < 50 {
        eprintln!("{path}: the window looks blank");
        return ExitCode::from(1);
    }
    ExitCode::SUCCESS
}
