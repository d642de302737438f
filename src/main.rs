//! The `canopy` command: play a scene in a window, run it headless, check scene files,
//! generate tree scenes and heightmaps, and measure.

use bevy::math::UVec2;
use canopy::app::{FIXED_HZ, entity_kinds, window_app};
use canopy::foundation::dump::write_dump;
use canopy::raster::MAX_TARGET_SIZE;
use canopy::run::{Recording, RunOptions, run_headless, run_recorded};
use canopy::terrain::bands::{Band, band_texture};
use canopy::terrain::def::draw_seed;
use canopy::terrain::experiment;
use canopy::terrain::generate::{DiamondSquareLayer, HillsLayer, Layer, PerlinLayer, Recipe};
use canopy::terrain::heightmap::Heightmap;
use canopy::terrain::image_io::{self, Encoding};
use canopy::tree::GeneratorSettings;
use canopy::tree::generate::{generate, scene_text};
use canopy::ui::WindowCapture;
use canopy::ui::pacing::FramePacing;
use canopy::ui::plot::save_timing_plot;
use clap::{Args, Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The scene played when none is named.
const DEFAULT_SCENE: &str = "scenes/canopy.yaml";

/// Canopy plays interactive 3D scenes described in YAML files, drawn by a CPU rasterizer.
#[derive(Parser, Debug)]
#[command(name = "canopy", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Play a scene in a window with keyboard controls (the default). Without a display,
    /// render it headless to a PNG and print where.
    Play {
        /// The scene file [default: scenes/canopy.yaml]
        scene: Option<PathBuf>,
        /// Save a screenshot of the whole window to this file after `--frames` frames, then
        /// exit.
        #[arg(long, value_name = "OUT.png")]
        screenshot: Option<PathBuf>,
        /// Frames to show before the `--screenshot`.
        #[arg(long, default_value_t = 30, requires = "screenshot")]
        frames: u32,
        /// Also write the state as JSON to this file with the `--screenshot`.
        #[arg(long, value_name = "STATE.json", requires = "screenshot")]
        dump: Option<PathBuf>,
        /// Frames a second at most; 0 draws frames back to back (for measuring).
        #[arg(long, default_value_t = 60, value_name = "FPS")]
        max_fps: u32,
    },
    /// Run a scene headless at a fixed 60 Hz step and write its state and last frame.
    Run(RunArgs),
    /// Check scene files without running them; exit 0 only if all are valid.
    Check {
        /// The scene files.
        #[arg(required = true)]
        scenes: Vec<PathBuf>,
    },
    /// Tree tools.
    Tree {
        #[command(subcommand)]
        action: TreeCommand,
    },
    /// Heightmap tools.
    Terrain {
        #[command(subcommand)]
        action: TerrainCommand,
    },
    /// Shrink a region of a mesh file with a surface deformer and print the report as JSON.
    Deform(DeformArgs),
    /// Mesh tools.
    Mesh {
        #[command(subcommand)]
        action: MeshCommand,
    },
    /// Augmented-reality tools: printable markers, sample camera sequences, and the marker
    /// detector on images.
    Ar {
        #[command(subcommand)]
        action: ArCommand,
    },
    /// Measurements.
    Bench {
        #[command(subcommand)]
        action: BenchCommand,
    },
}

#[derive(Subcommand, Debug)]
enum ArCommand {
    /// Write a marker as a PNG for printing: its black border, its cells and a white margin.
    Marker {
        /// The dictionary, by OpenCV's name: 4x4_50, 5x5_100, 6x6_250, aruco_original, ...
        #[arg(long, default_value = "6x6_250")]
        dictionary: String,
        /// The marker's id in the dictionary.
        #[arg(long)]
        id: u32,
        /// Pixels a cell, 1 to 1000.
        #[arg(long, default_value_t = 40, value_parser = clap::value_parser!(u32).range(1..=1000))]
        cell_px: u32,
        /// White margin around the border, in cells (0 to 10).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=10))]
        margin: u32,
        /// The PNG to write.
        #[arg(long)]
        out: PathBuf,
        /// Replace `--out` if it exists.
        #[arg(long)]
        force: bool,
    },
    /// Write a synthetic camera sequence of a marker on a table under known poses, with noise,
    /// blur, changing light and occlusions: frames, `calibration.yaml` and `truth.json`.
    Sequence(SequenceArgs),
    /// Find markers in images and print them as JSON: per image its markers, each with its id,
    /// corners (OpenCV's order and pixel convention) and, given a calibration and a side, its
    /// pose as OpenCV's rvec and tvec with the reprojection error.
    Detect {
        /// PNG or JPEG images.
        #[arg(required = true)]
        images: Vec<PathBuf>,
        /// The camera's calibration in OpenCV's YAML or JSON layout.
        #[arg(long)]
        calibration: Option<PathBuf>,
        /// The dictionary, by OpenCV's name.
        #[arg(long, default_value = "6x6_250")]
        dictionary: String,
        /// The markers' side (the black square) in metres, for their poses.
        #[arg(long, value_parser = parse_side)]
        side: Option<f64>,
    },
}

#[derive(Args, Debug)]
struct SequenceArgs {
    /// The folder to write (created if needed).
    #[arg(long)]
    out: PathBuf,
    /// Frames, 1 to 10000.
    #[arg(long, default_value_t = 90, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    frames: u32,
    /// Frame size in pixels, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", default_value = "640x480", value_parser = parse_size)]
    size: UVec2,
    /// The camera's vertical field of view, degrees (10 to 120).
    #[arg(long, default_value_t = 50.0)]
    fov: f64,
    /// The dictionary, by OpenCV's name.
    #[arg(long, default_value = "6x6_250")]
    dictionary: String,
    /// The marker's id.
    #[arg(long, default_value_t = 23)]
    id: u32,
    /// The marker's side (the black square) in metres.
    #[arg(long, default_value_t = 0.1, value_parser = parse_side)]
    side: f64,
    /// The seed of the noise, occlusions and clutter.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Noise, standard deviation in grey levels (0 to 50).
    #[arg(long, default_value_t = 3.0)]
    noise: f32,
    /// The largest blur, standard deviation in pixels (0 to 5).
    #[arg(long, default_value_t = 1.0)]
    blur: f32,
    /// The lens's radial distortion k1 (-0.5 to 0.5; negative for barrel distortion), written
    /// to the calibration with the rest.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    k1: f64,
    /// Keep the light steady.
    #[arg(long)]
    steady_light: bool,
    /// Nothing passes in front of the marker.
    #[arg(long)]
    no_occlusion: bool,
    /// The camera never looks away from the marker.
    #[arg(long)]
    no_look_away: bool,
    /// Write JPEG frames at this quality (1 to 100) instead of PNG.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=100))]
    jpeg: Option<u8>,
    /// Write into `--out` even if it holds files.
    #[arg(long)]
    force: bool,
}

fn parse_side(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(side) if side.is_finite() && side > 0.0 && side <= 100.0 => Ok(side),
        _ => Err(format!("expected a side in metres greater than 0 and at most 100, found `{text}`")),
    }
}

#[derive(Subcommand, Debug)]
enum MeshCommand {
    /// Write one of the project's sample surfaces as an .obj or .ply file.
    Sample {
        /// Which surface.
        #[arg(value_enum)]
        name: SampleName,
        /// The file to write.
        #[arg(long)]
        out: PathBuf,
        /// Vertices along a side (the belly), around (the cap, the sphere and the torus) or
        /// rings from hips to chest (the torso), 3 to 1000.
        #[arg(long, default_value_t = 65, value_parser = clap::value_parser!(u32).range(3..=1000))]
        size: u32,
        /// Replace `--out` if it exists.
        #[arg(long)]
        force: bool,
    },
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum SampleName {
    /// A patch of body surface 0.4 m a side with a belly 0.12 m high.
    Belly,
    /// A cap of a unit sphere, 60 degrees around its pole.
    Cap,
    /// A closed unit sphere.
    Sphere,
    /// A closed cube 2 m a side with rounded edges.
    Cushion,
    /// A closed torus 1 m across its centre line.
    Torus,
    /// An open torso 0.6 m high with a belly.
    Torso,
}

/// `canopy deform`.
#[derive(Args, Debug)]
struct DeformArgs {
    /// The mesh: an .obj, .ply or .stl file.
    input: PathBuf,
    /// The outline: three or more points on the surface as x:y:z in metres
    /// (`0.1:0.05:0,-0.1:0.05:0,0:0.05:0.1`), or vertex indices of the mesh as read (welded;
    /// an OBJ's numbered by first use in its faces), joined along the surface.
    #[arg(long, allow_hyphen_values = true)]
    region: String,
    /// The deformer: edge (a length constraint per edge), edge-sum or area.
    #[arg(long, default_value = "edge")]
    method: String,
    /// For edge-sum and area: projection (the constraint's projection) or source (the
    /// source's step).
    #[arg(long, default_value = "projection")]
    variant: String,
    /// The coefficient, in (0, 1] (below 1 for area).
    #[arg(long)]
    k: f32,
    /// The convergence threshold: metres of shift for edge, a share of the target for
    /// edge-sum and area.
    #[arg(long, default_value_t = 1e-5)]
    eps: f64,
    /// Iterations at most.
    #[arg(long, default_value_t = 10_000)]
    max_iterations: u32,
    /// Where to write the whole deformed mesh: an .obj or .ply file.
    #[arg(long)]
    out: PathBuf,
    /// Replace `--out` if it exists.
    #[arg(long)]
    force: bool,
}

#[derive(Subcommand, Debug)]
enum TerrainCommand {
    /// Generate a heightmap and write it as a grayscale PNG or BMP; the same settings and
    /// seed always give the same bytes.
    Generate(TerrainGenerateArgs),
    /// Print heightmap images' size, lowest, highest and mean height, and checksum.
    Stats {
        /// PNG or BMP heightmaps.
        #[arg(required = true)]
        maps: Vec<PathBuf>,
    },
    /// Write the project's five band textures (water, sand, grass, rock, snow) as PNG files.
    Textures {
        /// The folder to write them to.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
    },
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum GeneratorName {
    /// Fractal Perlin noise.
    Perlin,
    /// Diamond-square midpoint displacement.
    DiamondSquare,
    /// Random paraboloids.
    Hills,
}

#[derive(Args, Debug)]
struct TerrainGenerateArgs {
    /// The file to write: `.png` (8 or 16 bit) or `.bmp` (8 bit).
    #[arg(long, value_name = "MAP.png")]
    out: PathBuf,
    /// Bits a sample: 8 or 16 (PNG only).
    #[arg(long, default_value_t = 8)]
    bits: u8,
    /// Samples along x.
    #[arg(long, default_value_t = 256)]
    width: u32,
    /// Samples along z.
    #[arg(long, default_value_t = 256)]
    height: u32,
    /// The generator.
    #[arg(long, value_enum, default_value_t = GeneratorName::Perlin)]
    generator: GeneratorName,
    /// The seed; -1 draws one and prints it.
    #[arg(long, default_value_t = -1, allow_negative_numbers = true)]
    seed: i64,
    /// Perlin: samples per lattice unit of the first octave.
    #[arg(long, default_value_t = 64.0)]
    scale: f32,
    /// Perlin: octaves.
    #[arg(long, default_value_t = 1)]
    octaves: u32,
    /// Perlin: frequency multiplier per octave.
    #[arg(long, default_value_t = 2.0)]
    lacunarity: f32,
    /// Perlin: amplitude multiplier per octave.
    #[arg(long, default_value_t = 0.5)]
    persistence: f32,
    /// Diamond-square: displacement kept per finer level, in (0, 1].
    #[arg(long, default_value_t = 0.5)]
    roughness: f32,
    /// Hills: how many.
    #[arg(long, default_value_t = 200)]
    hills: u32,
    /// Hills: smallest and largest radius in samples.
    #[arg(long, num_args = 2, value_names = ["MIN", "MAX"], default_values_t = [4.0, 32.0])]
    radius: Vec<f32>,
    /// Replace `--out` if it exists (otherwise an existing file is never overwritten).
    #[arg(long)]
    force: bool,
}

#[derive(Subcommand, Debug)]
enum BenchCommand {
    /// The source's experiment: time to produce the image of the visible section against its
    /// size, with and without shadows; prints the table and draws the plot.
    Terrain {
        /// The plot to write (PNG).
        #[arg(long, value_name = "PLOT.png")]
        out: PathBuf,
        /// Runs of each configuration.
        #[arg(long, default_value_t = 10)]
        runs: usize,
        /// Section sizes (vertices a side, 2 to 512).
        #[arg(long, num_args = 1.., default_values_t = canopy::terrain::experiment::SIZES)]
        sizes: Vec<u32>,
    },
}

#[derive(Subcommand, Debug)]
enum TreeCommand {
    /// Write a scene of seeded, generated trees: an ordinary scene file to play and edit.
    Generate(GenerateArgs),
}

#[derive(Args, Debug)]
struct GenerateArgs {
    /// The seed: the same seed and settings always give the same trees.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Trees, on a jittered grid.
    #[arg(long, default_value_t = 1)]
    trunks: u32,
    /// Trunk height in metres.
    #[arg(long, default_value_t = 6.0)]
    height: f32,
    /// Forks per support.
    #[arg(long, default_value_t = 5)]
    branches: u32,
    /// Levels of forks below the trunk (at most 4).
    #[arg(long, default_value_t = 2)]
    depth: u32,
    /// Distance between neighbouring trees in metres.
    #[arg(long, default_value_t = 6.0)]
    spacing: f32,
    /// The scene file to write.
    #[arg(long, value_name = "SCENE.yaml")]
    out: PathBuf,
    /// Replace `--out` if it exists (otherwise an existing file is never overwritten).
    #[arg(long)]
    force: bool,
}

#[derive(Args, Debug)]
struct RunArgs {
    /// The scene file.
    scene: PathBuf,
    /// Fixed steps to run [default: 60, one second].
    #[arg(long, conflicts_with = "seconds")]
    frames: Option<u64>,
    /// Simulated seconds to run (rounded to whole steps).
    #[arg(long, value_parser = parse_seconds)]
    seconds: Option<f64>,
    /// A timeline of scripted key presses and parameter settings (YAML).
    #[arg(long, value_name = "TIMELINE.yaml")]
    input: Option<PathBuf>,
    /// Write the final state as JSON to this file.
    #[arg(long, value_name = "STATE.json")]
    dump: Option<PathBuf>,
    /// Write the last frame as PNG to this file.
    #[arg(long, value_name = "OUT.png")]
    screenshot: Option<PathBuf>,
    /// Frame size in pixels, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", default_value = "1280x720", value_parser = parse_size)]
    size: UVec2,
    /// Write frames as PNG files into this folder while running (`frame-00001.png`, ...).
    #[arg(long, value_name = "DIR")]
    record: Option<PathBuf>,
    /// Steps between recorded frames: 2 records 30 frames a second.
    #[arg(long, default_value_t = 1, requires = "record", value_parser = clap::value_parser!(u64).range(1..))]
    record_every: u64,
}

fn parse_seconds(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(seconds) if seconds.is_finite() && (0.0..=1.0e6).contains(&seconds) => Ok(seconds),
        _ => Err(format!("expected seconds from 0 to 1000000, found `{text}`")),
    }
}

fn parse_size(text: &str) -> Result<UVec2, String> {
    let error =
        || format!("expected WIDTHxHEIGHT with each from 1 to {MAX_TARGET_SIZE}, e.g. 1280x720; found `{text}`");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(error)?;
    let (w, h) = (w.parse::<u32>().map_err(|_| error())?, h.parse::<u32>().map_err(|_| error())?);
    let valid = 1..=MAX_TARGET_SIZE;
    if valid.contains(&w) && valid.contains(&h) { Ok(UVec2::new(w, h)) } else { Err(error()) }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command.unwrap_or(Command::Play { scene: None, screenshot: None, frames: 0, dump: None, max_fps: 60 }) {
        Command::Play { scene, screenshot, frames, dump, max_fps } => {
            let capture = screenshot.map(|path| WindowCapture::new(path, frames, dump));
            play(scene.unwrap_or_else(default_scene), capture, FramePacing::max_fps(max_fps))
        }
        Command::Run(args) => run(args),
        Command::Check { scenes } => check(&scenes),
        Command::Tree { action: TreeCommand::Generate(args) } => generate_trees(&args),
        Command::Terrain { action: TerrainCommand::Generate(args) } => generate_heightmap(&args),
        Command::Terrain { action: TerrainCommand::Stats { maps } } => heightmap_stats(&maps),
        Command::Terrain { action: TerrainCommand::Textures { out } } => write_band_textures(&out),
        Command::Deform(args) => deform_mesh(&args),
        Command::Mesh { action: MeshCommand::Sample { name, out, size, force } } => {
            write_sample(name, &out, size, force)
        }
        Command::Ar { action: ArCommand::Marker { dictionary, id, cell_px, margin, out, force } } => {
            write_marker(&dictionary, id, cell_px, margin, &out, force)
        }
        Command::Ar { action: ArCommand::Sequence(args) } => write_sequence(&args),
        Command::Ar { action: ArCommand::Detect { images, calibration, dictionary, side } } => {
            detect_markers(&images, calibration.as_deref(), &dictionary, side)
        }
        Command::Bench { action: BenchCommand::Terrain { out, runs, sizes } } => bench_terrain(&out, runs, &sizes),
    }
}

/// Exit 1, saying why, if `out` exists and `force` does not say to replace it: nothing the
/// user made is replaced unasked.
fn refuse_to_replace(out: &Path, force: bool) -> Option<ExitCode> {
    (out.exists() && !force).then(|| {
        eprintln!("{}: already exists; choose another --out, or add --force to replace it", out.display());
        ExitCode::from(1)
    })
}

/// `canopy ar marker`: exit 0 with the file written, 1 if it could not be, 2 for bad settings.
fn write_marker(dictionary: &str, id: u32, cell_px: u32, margin: u32, out: &Path, force: bool) -> ExitCode {
    use canopy_vision::{Dictionary, synth::marker_image};
    let dictionary = match Dictionary::named(dictionary) {
        Ok(dictionary) => dictionary,
        Err(error) => {
            eprintln!("canopy ar marker: {error}");
            return ExitCode::from(2);
        }
    };
    if let Some(refused) = refuse_to_replace(out, force) {
        return refused;
    }
    let Some(marker) = marker_image(&dictionary, id, cell_px, margin) else {
        eprintln!("canopy ar marker: {dictionary} has markers 0 to {}, not {id}", dictionary.len() - 1);
        return ExitCode::from(2);
    };
    match image::GrayImage::from_raw(marker.width, marker.height, marker.pixels).map(|image| image.save(out)) {
        Some(Ok(())) => {
            println!("{}: {dictionary} marker {id}, {} x {} pixels", out.display(), marker.width, marker.height);
            ExitCode::SUCCESS
        }
        Some(Err(error)) => {
            eprintln!("{}: {error}", out.display());
            ExitCode::from(1)
        }
        None => ExitCode::from(1),
    }
}

/// `canopy ar sequence`: exit 0 with the files written, 1 if they could not be, 2 for bad
/// settings.
fn write_sequence(args: &SequenceArgs) -> ExitCode {
    use canopy::ar::sample::{FrameFormat, write_sequence};
    use canopy_vision::{Dictionary, Intrinsics, synth::SequenceSettings};
    let settings = Dictionary::named(&args.dictionary).map_err(|e| e.to_string()).and_then(|dictionary| {
        if args.id >= dictionary.len() {
            return Err(format!("{dictionary} has markers 0 to {}, not {}", dictionary.len() - 1, args.id));
        }
        if !(10.0..=120.0).contains(&args.fov)
            || !(0.0..=50.0).contains(&args.noise)
            || !(0.0..=5.0).contains(&args.blur)
        {
            return Err("--fov is 10 to 120 degrees, --noise 0 to 50, --blur 0 to 5".into());
        }
        Ok(SequenceSettings {
            camera: Intrinsics::pinhole([args.size.x, args.size.y], args.fov),
            dictionary,
            id: args.id,
            side_m: args.side,
            frames: args.frames,
            distance_m: [3.0 * args.side, 7.0 * args.side],
            seed: args.seed,
            noise: args.noise,
            max_blur_px: args.blur,
            lighting: !args.steady_light,
            occlusion: !args.no_occlusion,
            look_away: !args.no_look_away,
        })
    });
    let settings = match settings {
        Ok(settings) => settings,
        Err(error) => {
            eprintln!("canopy ar sequence: {error}");
            return ExitCode::from(2);
        }
    };
    let occupied = std::fs::read_dir(&args.out).is_ok_and(|mut entries| entries.next().is_some());
    if occupied && !args.force {
        eprintln!(
            "{}: the folder holds files; choose another --out, or add --force to write into it",
            args.out.display()
        );
        return ExitCode::from(1);
    }
    let format = args.jpeg.map_or(FrameFormat::Png, FrameFormat::Jpeg);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    match write_sequence(&settings, &args.out, format, threads) {
        Ok(files) => {
            println!("{}: {} frames, calibration.yaml, truth.json", args.out.display(), files.len().saturating_sub(2));
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("canopy ar sequence: {error}");
            ExitCode::from(1)
        }
    }
}

/// `canopy ar detect`: prints the JSON; exit 0 if every image was read, 1 if some could not
/// be, 2 for bad settings.
fn detect_markers(images: &[PathBuf], calibration: Option<&Path>, dictionary: &str, side: Option<f64>) -> ExitCode {
    use canopy::ar::plugin::marker_json;
    use canopy::ar::{calibration as calib, frames::load_image};
    use canopy_vision::{Dictionary, Gray, Scratch, Settings, detect, pose::estimate};
    let dictionary = match Dictionary::named(dictionary) {
        Ok(dictionary) => dictionary,
        Err(error) => {
            eprintln!("canopy ar detect: {error}");
            return ExitCode::from(2);
        }
    };
    let calibration = match calibration.map(calib::read).transpose() {
        Ok(calibration) => calibration,
        Err(error) => {
            eprintln!("{error}");
            return ExitCode::from(2);
        }
    };
    let mut scratch = Scratch::default();
    let mut all_read = true;
    let mut results = Vec::new();
    for path in images {
        let image = match load_image(path, None) {
            Ok(image) => image,
            Err(error) => {
                eprintln!("{error}");
                all_read = false;
                results.push(serde_json::json!({"image": path, "error": error}));
                continue;
            }
        };
        let size = [image.width(), image.height()];
        let camera = match calibration.as_ref().map(|c| c.for_frames(size)).transpose() {
            Ok(camera) => camera,
            Err(error) => {
                eprintln!("{}: {error}", path.display());
                all_read = false;
                results.push(serde_json::json!({"image": path, "error": error}));
                continue;
            }
        };
        let gray = Gray::from_rgba(size[0], size[1], image.as_raw());
        let markers: Vec<serde_json::Value> =
            detect(&gray, &dictionary, &Settings::default(), camera.as_ref(), &mut scratch)
                .into_iter()
                .map(|marker| {
                    let corners = marker.corners_f64();
                    let pose = camera.as_ref().zip(side).and_then(|(camera, side)| estimate(&corners, side, camera));
                    let mut entry = marker_json(&corners, pose.as_ref());
                    entry["id"] = serde_json::json!(marker.id);
                    entry
                })
                .collect();
        results.push(serde_json::json!({"image": path, "markers": markers}));
    }
    println!("{}", serde_json::to_string_pretty(&results).unwrap_or_default());
    if all_read { ExitCode::SUCCESS } else { ExitCode::from(1) }
}

/// `canopy mesh sample`: exit 0 with the file written, 1 if it could not be.
fn write_sample(name: SampleName, out: &Path, size: u32, force: bool) -> ExitCode {
    use canopy::soft_body::{mesh_io, sample};
    if let Some(refused) = refuse_to_replace(out, force) {
        return refused;
    }
    let surface = match name {
        SampleName::Belly => sample::Shape::Belly,
        SampleName::Cap => sample::Shape::Cap,
        SampleName::Sphere => sample::Shape::Sphere,
        SampleName::Cushion => sample::Shape::Cushion,
        SampleName::Torus => sample::Shape::Torus,
        SampleName::Torso => sample::Shape::Torso,
    }
    .make(size);
    let mesh = mesh_io::TriangleMesh { positions: surface.positions, triangles: surface.triangles };
    match mesh_io::write(&mesh, out) {
        Ok(()) => {
            println!("{}: {} vertices, {} triangles", out.display(), mesh.positions.len(), mesh.triangles.len());
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("canopy mesh sample: {}: {error}", out.display());
            ExitCode::from(1)
        }
    }
}

/// `canopy deform`: exit 0 with the report printed, 1 for bad input, 2 for bad settings.
fn deform_mesh(args: &DeformArgs) -> ExitCode {
    use canopy::soft_body::batch::{self, BatchError};
    use canopy::soft_body::deform::Settings;
    if let Some(refused) = refuse_to_replace(&args.out, args.force) {
        return refused;
    }
    let settings = Settings { k: args.k, eps: args.eps, max_iterations: args.max_iterations };
    let result = batch::method(&args.method, &args.variant)
        .and_then(|method| Ok((method, batch::parse_marks(&args.region)?)))
        .and_then(|(method, marks)| batch::run(&args.input, &marks, method, settings, &args.out));
    match result {
        Ok(report) => {
            println!("{}", serde_json::to_string_pretty(&report).unwrap_or_default());
            ExitCode::SUCCESS
        }
        Err(error @ BatchError::Settings(_)) => {
            eprintln!("canopy deform: {error}");
            ExitCode::from(2)
        }
        Err(error) => {
            eprintln!("canopy deform: {error}");
            ExitCode::from(1)
        }
    }
}

/// `scenes/canopy.yaml` from the working directory, else from the source tree.
fn default_scene() -> PathBuf {
    let local = PathBuf::from(DEFAULT_SCENE);
    if local.exists() { local } else { Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_SCENE) }
}

fn play(scene: PathBuf, capture: Option<WindowCapture>, pacing: FramePacing) -> ExitCode {
    if !scene.is_file() {
        eprintln!("{}: no such scene file", scene.display());
        return ExitCode::from(1);
    }
    let set = |name: &str| std::env::var_os(name).is_some_and(|value| !value.is_empty());
    if !set("DISPLAY") && !set("WAYLAND_DISPLAY") {
        let stem = scene.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let dump = capture.as_ref().and_then(|c| c.dump.clone());
        let out = capture.map_or_else(|| std::env::temp_dir().join(format!("canopy-{stem}.png")), |c| c.path);
        eprintln!(
            "no display available (neither DISPLAY nor WAYLAND_DISPLAY is set): rendering {} headless instead",
            scene.display()
        );
        let options =
            RunOptions { scene, frames: FIXED_HZ as u64, timeline: None, size: UVec2::new(1280, 720), log: true };
        return match run_headless(&options).map_err(|e| e.to_string()).and_then(|output| {
            output.framebuffer.save_png(&out).map_err(|e| format!("{}: {e}", out.display()))?;
            dump.map_or(Ok(()), |path| write_dump(&path, &output.dump).map_err(|e| format!("{}: {e}", path.display())))
        }) {
            Ok(()) => {
                println!("{}", out.display());
                ExitCode::SUCCESS
            }
            Err(error) => {
                eprintln!("{error}");
                ExitCode::from(1)
            }
        };
    }
    if let Err(error) = entity_kinds().load(&scene) {
        // The window opens anyway and shows the error until the file is fixed.
        eprintln!("{error}");
    }
    match window_app(&scene, capture, pacing) {
        Ok(mut app) => match app.run() {
            bevy::app::AppExit::Success => ExitCode::SUCCESS,
            bevy::app::AppExit::Error(code) => ExitCode::from(code.get()),
        },
        Err(error) => {
            eprintln!("{}: {error}", scene.display());
            ExitCode::from(1)
        }
    }
}

fn run(args: RunArgs) -> ExitCode {
    let frames = match (args.frames, args.seconds) {
        (Some(frames), _) => frames,
        (None, Some(seconds)) => (seconds * FIXED_HZ).round() as u64,
        (None, None) => FIXED_HZ as u64,
    };
    let options = RunOptions { scene: args.scene, frames, timeline: args.input, size: args.size, log: true };
    let recording = args.record.map(|folder| Recording { folder, every: args.record_every });
    let output = match run_recorded(&options, recording.as_ref()) {
        Ok(output) => output,
        Err(error) => {
            eprintln!("{error}");
            return ExitCode::from(1);
        }
    };
    if let Some(path) = &args.dump
        && let Err(error) = write_dump(path, &output.dump)
    {
        eprintln!("{}: cannot write the dump: {error}", path.display());
        return ExitCode::from(1);
    }
    if let Some(path) = &args.screenshot
        && let Err(error) = output.framebuffer.save_png(path)
    {
        eprintln!("{}: cannot write the screenshot: {error}", path.display());
        return ExitCode::from(1);
    }
    ExitCode::SUCCESS
}

fn generate_trees(args: &GenerateArgs) -> ExitCode {
    let settings = GeneratorSettings {
        seed: args.seed,
        trunks: args.trunks,
        height: args.height,
        branches: args.branches,
        depth: args.depth,
        spacing: args.spacing,
    };
    if let Err(error) = settings.check() {
        eprintln!("canopy tree generate: {error}");
        return ExitCode::from(2);
    }
    if let Some(refused) = refuse_to_replace(&args.out, args.force) {
        return refused;
    }
    let trees = generate(&settings);
    let supports: usize = trees.iter().map(Vec::len).sum();
    match std::fs::write(&args.out, scene_text(&settings, &trees)) {
        Ok(()) => {
            println!("{}: {} trees, {supports} supports", args.out.display(), trees.len());
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("{}: cannot write the scene: {error}", args.out.display());
            ExitCode::from(1)
        }
    }
}

fn generate_heightmap(args: &TerrainGenerateArgs) -> ExitCode {
    let encoding = match Encoding::for_path(&args.out, args.bits) {
        Ok(encoding) => encoding,
        Err(error) => {
            eprintln!("canopy terrain generate: {error}");
            return ExitCode::from(2);
        }
    };
    let layer = match args.generator {
        GeneratorName::Perlin => Layer {
            perlin: Some(PerlinLayer {
                scale: args.scale,
                octaves: args.octaves,
                lacunarity: args.lacunarity,
                persistence: args.persistence,
            }),
            ..Layer::default()
        },
        GeneratorName::DiamondSquare => {
            Layer { diamond_square: Some(DiamondSquareLayer { roughness: args.roughness }), ..Layer::default() }
        }
        GeneratorName::Hills => {
            let radius = [args.radius[0], args.radius[1]];
            Layer { hills: Some(HillsLayer { count: args.hills, radius }), ..Layer::default() }
        }
    };
    let recipe = Recipe { size: [args.width, args.height], seed: args.seed, layers: vec![layer], apply: Vec::new() };
    if let Err(error) = recipe.check() {
        eprintln!("canopy terrain generate: {error}");
        return ExitCode::from(2);
    }
    if let Some(refused) = refuse_to_replace(&args.out, args.force) {
        return refused;
    }
    let seed = recipe.seed_used(draw_seed);
    let map = match recipe.generate(seed) {
        Ok(map) => map,
        Err(error) => {
            eprintln!("canopy terrain generate: {error}");
            return ExitCode::from(2);
        }
    };
    match image_io::save(&map, &args.out, encoding) {
        Ok(()) => {
            println!("{}: seed {seed}, {}", args.out.display(), describe(&map));
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("{}: cannot write the heightmap: {error}", args.out.display());
            ExitCode::from(1)
        }
    }
}

/// A heightmap's figures on one line.
fn describe(map: &Heightmap) -> String {
    let stats = map.stats();
    format!(
        "{} x {} samples, heights {:.4} to {:.4}, mean {:.4}, checksum {:016x}",
        stats.width, stats.height, stats.min, stats.max, stats.mean, stats.checksum
    )
}

fn heightmap_stats(maps: &[PathBuf]) -> ExitCode {
    let mut valid = true;
    for path in maps {
        match std::fs::read(path)
            .map_err(|e| e.to_string())
            .and_then(|bytes| image_io::decode(&bytes).map_err(|e| e.to_string()))
        {
            Ok(map) => println!("{}: {}", path.display(), describe(&map)),
            Err(error) => {
                eprintln!("{}: {error}", path.display());
                valid = false;
            }
        }
    }
    if valid { ExitCode::SUCCESS } else { ExitCode::from(1) }
}

fn write_band_textures(folder: &Path) -> ExitCode {
    if let Err(error) = std::fs::create_dir_all(folder) {
        eprintln!("{}: {error}", folder.display());
        return ExitCode::from(1);
    }
    for band in Band::ALL {
        let path = folder.join(format!("{}.png", band.key()));
        if let Err(error) = band_texture(band).save_png(&path) {
            eprintln!("{}: {error}", path.display());
            return ExitCode::from(1);
        }
        println!("{}", path.display());
    }
    ExitCode::SUCCESS
}

fn bench_terrain(out: &Path, runs: usize, sizes: &[u32]) -> ExitCode {
    if let Some(bad) = sizes.iter().find(|s| !(2..=512).contains(*s)) {
        eprintln!("canopy bench terrain: a section size is 2 to 512 vertices a side, not {bad}");
        return ExitCode::from(2);
    }
    let pool = bevy::tasks::TaskPool::new();
    let timings = experiment::run(sizes, runs.max(1), UVec2::new(1280, 720), &pool);
    print!("{}", experiment::table(&timings));
    match save_timing_plot(&timings, out) {
        Ok(()) => {
            println!("plot: {}", out.display());
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("{}: cannot write the plot: {error}", out.display());
            ExitCode::from(1)
        }
    }
}

fn check(scenes: &[PathBuf]) -> ExitCode {
    let kinds = entity_kinds();
    let mut valid = true;
    for scene in scenes {
        match kinds.load(scene) {
            Ok(loaded) => println!("{}: ok ({} entities)", scene.display(), loaded.def.entities.len()),
            Err(error) => {
                eprintln!("{error}");
                valid = false;
            }
        }
    }
    if valid { ExitCode::SUCCESS } else { ExitCode::from(1) }
}
