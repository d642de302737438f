//! `canopy terrain`: heightmaps generated, described, and the band textures written.

use super::refuse_to_replace;
use crate::terrain::bands::{Band, band_texture};
use crate::terrain::def::draw_seed;
use crate::terrain::heightmap::Heightmap;
use crate::terrain::image_io::{self, Encoding};
use crate::terrain::recipe::{DiamondSquareLayer, HillCentres, HillsLayer, Layer, PerlinLayer, Recipe};
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `canopy terrain ...`.
#[derive(Subcommand, Debug)]
pub enum TerrainCommand {
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

/// A generator of `canopy terrain generate`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum GeneratorName {
    /// Fractal Perlin noise.
    Perlin,
    /// Diamond-square midpoint displacement.
    DiamondSquare,
    /// Random paraboloids.
    Hills,
}

/// `canopy terrain generate`.
#[derive(Args, Debug)]
pub struct TerrainGenerateArgs {
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
    /// Hills: where their centres fall: inside, beyond_edges or island.
    #[arg(long, default_value = "inside", value_parser = parse_hill_centres)]
    hill_centres: HillCentres,
    /// Hills: dug down as lakes from a plateau instead of raised.
    #[arg(long)]
    lakes: bool,
    /// Replace `--out` if it exists (otherwise an existing file is never overwritten).
    #[arg(long)]
    force: bool,
}

impl TerrainCommand {
    /// Runs the terrain command.
    pub fn run(self) -> ExitCode {
        match self {
            TerrainCommand::Generate(args) => args.generate(),
            TerrainCommand::Stats { maps } => heightmap_stats(&maps),
            TerrainCommand::Textures { out } => write_band_textures(&out),
        }
    }
}

/// A hill placement by the name a recipe gives it.
fn parse_hill_centres(text: &str) -> Result<HillCentres, String> {
    serde_yaml::from_str(text).map_err(|_| format!("expected inside, beyond_edges or island, found \"{text}\""))
}

impl TerrainGenerateArgs {
    /// The recipe of one layer these arguments describe.
    fn recipe(&self) -> Recipe {
        let layer = match self.generator {
            GeneratorName::Perlin => Layer {
                perlin: Some(PerlinLayer {
                    scale: self.scale,
                    octaves: self.octaves,
                    lacunarity: self.lacunarity,
                    persistence: self.persistence,
                }),
                ..Layer::default()
            },
            GeneratorName::DiamondSquare => {
                Layer { diamond_square: Some(DiamondSquareLayer { roughness: self.roughness }), ..Layer::default() }
            }
            GeneratorName::Hills => {
                let radius = [self.radius[0], self.radius[1]];
                let hills = HillsLayer { count: self.hills, radius, centres: self.hill_centres, lakes: self.lakes };
                Layer { hills: Some(hills), ..Layer::default() }
            }
        };
        Recipe { size: [self.width, self.height], seed: self.seed, layers: vec![layer], apply: Vec::new() }
    }

    /// Writes the heightmap: exit 0 with it written, 1 if it could not be, 2 for bad settings.
    fn generate(&self) -> ExitCode {
        let encoding = match Encoding::for_path(&self.out, self.bits) {
            Ok(encoding) => encoding,
            Err(error) => {
                eprintln!("canopy terrain generate: {error}");
                return ExitCode::from(2);
            }
        };
        let recipe = self.recipe();
        if let Err(error) = recipe.check() {
            eprintln!("canopy terrain generate: {error}");
            return ExitCode::from(2);
        }
        if let Some(refused) = refuse_to_replace(&self.out, self.force) {
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
        match image_io::save(&map, &self.out, encoding) {
            Ok(()) => {
                println!("{}: seed {seed}, {}", self.out.display(), describe(&map));
                ExitCode::SUCCESS
            }
            Err(error) => {
                eprintln!("{}: cannot write the heightmap: {error}", self.out.display());
                ExitCode::from(1)
            }
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

/// `canopy terrain stats`: exit 0 if every map was read, 1 otherwise.
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

/// `canopy terrain textures`: exit 0 with every texture written, 1 otherwise.
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
