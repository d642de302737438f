//! A seeded tree and forest generator: the same settings and seed always give the same
//! supports, on every machine (a SplitMix64 stream, no platform randomness).
//!
//! Each tree is a leaning trunk of a few points; every support spawns `branches` forks spread
//! along its upper part with random headings and pitches, down to `depth` levels, each level
//! shorter and thinner than its parent. The output is ordinary supports, so a generated tree
//! can be written to a scene file and edited like a hand-written one.

use super::model::{Shape, SupportSpec};
use crate::foundation::random::Random;
use bevy::math::Vec3;
use std::fmt::Write;

/// What to generate.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct GeneratorSettings {
    /// The seed: equal seeds give equal trees.
    pub seed: u64,
    /// Trees, placed on a jittered grid.
    pub trunks: u32,
    /// Trunk height, metres.
    pub height: f32,
    /// Forks per support.
    pub branches: u32,
    /// Levels of forks below the trunk.
    pub depth: u32,
    /// Distance between neighbouring trees, metres.
    pub spacing: f32,
}

impl Default for GeneratorSettings {
    fn default() -> Self {
        Self { seed: 1, trunks: 1, height: 6.0, branches: 5, depth: 2, spacing: 6.0 }
    }
}

impl GeneratorSettings {
    /// Why these settings cannot be generated from, if they cannot: sizes must be sensible
    /// and the result at most about a million supports.
    pub fn check(&self) -> Result<(), String> {
        if !(self.height.is_finite() && self.height > 0.0 && self.height <= 200.0) {
            return Err(format!("height: expected metres greater than 0 and at most 200, found {}", self.height));
        }
        if !(self.spacing.is_finite() && self.spacing > 0.0 && self.spacing <= 1000.0) {
            return Err(format!("spacing: expected metres greater than 0 and at most 1000, found {}", self.spacing));
        }
        if self.depth > 4 {
            return Err(format!("depth: expected at most 4 levels, found {}", self.depth));
        }
        if self.trunks == 0 || self.trunks > 100_000 {
            return Err(format!("trunks: expected 1 to 100000, found {}", self.trunks));
        }
        if self.branches > 12 {
            return Err(format!("branches: expected at most 12 per support, found {}", self.branches));
        }
        let per_tree: u64 = (0..=self.depth).map(|level| u64::from(self.branches).pow(level)).sum();
        if per_tree * u64::from(self.trunks) > 1_000_000 {
            return Err(format!("{} trunks of {per_tree} supports each is over a million supports", self.trunks));
        }
        Ok(())
    }
}

/// The trees of `settings`, each as its supports (trunk first).
pub fn generate(settings: &GeneratorSettings) -> Vec<Vec<SupportSpec>> {
    let mut random = Random::new(settings.seed);
    let columns = (settings.trunks as f32).sqrt().ceil() as u32;
    (0..settings.trunks)
        .map(|index| {
            let (row, column) = (index / columns, index % columns);
            let centre = (columns as f32 - 1.0) * 0.5;
            let jitter = settings.spacing * 0.3;
            let base = Vec3::new(
                (column as f32 - centre) * settings.spacing + random.between(-jitter, jitter),
                0.0,
                (row as f32 - centre) * settings.spacing + random.between(-jitter, jitter),
            );
            tree(settings, base, &mut random)
        })
        .collect()
}

/// Trees scattered over a streamed world: each chunk of the finest level of detail gets its
/// own, placed and grown from the seed and the chunk alone, so that a chunk that streams out
/// and back in has the same trees.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScatterSettings {
    /// The seed: equal seeds give equal forests.
    pub seed: u64,
    /// Trees on each chunk.
    pub per_chunk: u32,
    /// Trunk height, metres.
    pub height: f32,
    /// Forks per support.
    pub branches: u32,
    /// Levels of forks below the trunk.
    pub depth: u32,
}

impl Default for ScatterSettings {
    fn default() -> Self {
        Self { seed: 1, per_chunk: 1, height: 8.0, branches: 4, depth: 2 }
    }
}

/// Most trees a chunk may have.
pub const MAX_PER_CHUNK: u32 = 8;

impl ScatterSettings {
    /// The settings one tree of a chunk is grown with.
    fn tree(&self) -> GeneratorSettings {
        GeneratorSettings {
            seed: self.seed,
            trunks: 1,
            height: self.height,
            branches: self.branches,
            depth: self.depth,
            spacing: 1.0,
        }
    }

    /// Why these settings cannot be scattered with, if they cannot.
    pub fn check(&self) -> Result<(), String> {
        if !(1..=MAX_PER_CHUNK).contains(&self.per_chunk) {
            return Err(format!("per_chunk: expected 1 to {MAX_PER_CHUNK} trees, found {}", self.per_chunk));
        }
        self.tree().check()
    }
}

/// The trees of the chunk `(x, z)` whose square starts at `min` (x, z, metres) and is `size`
/// metres a side, standing at height 0 (each trunk is raised onto the ground by its caller).
/// Trunks keep a tenth of the side from the chunk's edges, so neighbouring chunks' trunks do
/// not meet.
pub fn scatter(settings: &ScatterSettings, (x, z): (i32, i32), min: (f32, f32), size: f32) -> Vec<Vec<SupportSpec>> {
    let key = (u64::from(x as u32) << 32) | u64::from(z as u32);
    let mut random = Random::new(settings.seed ^ key.wrapping_mul(0x9e37_79b9_7f4a_7c15));
    let (low, high) = (size * 0.1, size * 0.9);
    let tree_settings = settings.tree();
    (0..settings.per_chunk)
        .map(|_| {
            let base = Vec3::new(min.0 + random.between(low, high), 0.0, min.1 + random.between(low, high));
            tree(&tree_settings, base, &mut random)
        })
        .collect()
}

/// One tree standing at `base`.
fn tree(settings: &GeneratorSettings, base: Vec3, random: &mut Random) -> Vec<SupportSpec> {
    let height = settings.height * random.between(0.8, 1.2);
    let radius = height * 0.035;
    let lean = Vec3::new(random.between(-0.08, 0.08), 0.0, random.between(-0.08, 0.08));
    let points: Vec<Vec3> = (0..4).map(|i| base + (Vec3::Y + lean * i as f32) * (height * i as f32 / 3.0)).collect();
    let radii = vec![radius, radius * 0.8, radius * 0.55, radius * 0.3];
    let trunk = SupportSpec { name: "trunk".into(), shape: Shape::Polyline { points, radii }, kind: None };
    let mut supports = vec![trunk];
    // Breadth first: (support index, its length, its start radius, its level).
    let mut pending = vec![(0usize, height, radius, 0u32)];
    while let Some((parent, length, parent_radius, level)) = pending.pop() {
        if level >= settings.depth {
            continue;
        }
        let count = settings.branches;
        for k in 0..count {
            let at = 0.35 + 0.6 * (k as f32 + random.between(0.2, 0.8)) / count as f32;
            let branch_length = length * random.between(0.35, 0.55);
            let start = (parent_radius * (1.0 - 0.7 * at) * 0.8).max(0.005);
            let name = format!("{}-{}", supports[parent].name, k + 1);
            let shape = Shape::Fork {
                parent: supports[parent].name.clone(),
                at,
                yaw_deg: random.between(-180.0, 180.0),
                pitch_deg: random.between(-5.0, 40.0),
                length: branch_length,
                radius: [start, (start * 0.3).max(0.003)],
                bend_deg: [random.between(-25.0, 25.0), random.between(-20.0, 5.0)],
                sections: 4,
            };
            supports.push(SupportSpec { name, shape, kind: None });
            pending.push((supports.len() - 1, branch_length, start, level + 1));
        }
    }
    supports
}

/// A scene file holding the generated trees, one `tree` entity each, with a ground and a
/// camera that frames them.
pub fn scene_text(settings: &GeneratorSettings, trees: &[Vec<SupportSpec>]) -> String {
    let columns = (settings.trunks as f32).sqrt().ceil();
    let extent = columns * settings.spacing;
    let mut text = String::new();
    let s = settings;
    let _ = writeln!(
        text,
        "# Generated by `canopy tree generate --seed {} --trunks {} --height {} --branches {} --depth {} --spacing {}`.\n\
         # An ordinary scene: edit it freely (the format is described in docs/scenes.md).\n",
        s.seed, s.trunks, s.height, s.branches, s.depth, s.spacing
    );
    let _ = writeln!(
        text,
        "camera:\n  position: [0.0, {:.2}, {:.2}]\n  look_at: [0.0, {:.2}, 0.0]\n  fov_deg: 55\n  far: {:.0}\n",
        s.height * 0.9 + extent * 0.25,
        extent * 0.55 + s.height * 1.5,
        s.height * 0.45,
        (extent * 4.0).max(100.0)
    );
    let _ = writeln!(text, "entities:");
    let _ = writeln!(
        text,
        "  - name: ground\n    shape: {{ primitive: plane, size: [{0:.1}, 1, {0:.1}], color: [0.42, 0.52, 0.33] }}\n",
        extent + s.spacing
    );
    for (index, supports) in trees.iter().enumerate() {
        let _ = writeln!(text, "  - name: tree-{}\n    tree:\n      supports:", index + 1);
        for support in supports {
            let _ = writeln!(text, "        - {}", support_yaml(support, 3));
        }
        let _ = writeln!(text);
    }
    text
}

/// One support as a YAML flow mapping, its numbers rounded to `decimals` places.
pub fn support_yaml(support: &SupportSpec, decimals: i32) -> String {
    let scale = 10f32.powi(decimals);
    let number = |v: f32| format!("{}", (v * scale).round() / scale);
    let polyline = |points: &[Vec3], radii: &[f32]| {
        let points: Vec<String> =
            points.iter().map(|p| format!("[{}, {}, {}]", number(p.x), number(p.y), number(p.z))).collect();
        let radii: Vec<String> = radii.iter().map(|&r| number(r)).collect();
        format!("points: [{}], radii: [{}]", points.join(", "), radii.join(", "))
    };
    match &support.shape {
        Shape::Polyline { points, radii } => format!("{{ name: {}, {} }}", support.name, polyline(points, radii)),
        Shape::Attached { parent, points, radii } => {
            format!("{{ name: {}, parent: {parent}, {} }}", support.name, polyline(points, radii))
        }
        Shape::Fork { parent, at, yaw_deg, pitch_deg, length, radius, bend_deg, sections } => format!(
            "{{ name: {}, parent: {parent}, at: {}, yaw_deg: {}, pitch_deg: {}, length: {}, radius: [{}, {}], bend_deg: [{}, {}], sections: {sections} }}",
            support.name,
            number(*at),
            number(*yaw_deg),
            number(*pitch_deg),
            number(*length),
            number(radius[0]),
            number(radius[1]),
            number(bend_deg[0]),
            number(bend_deg[1]),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chunk_always_gets_the_same_trees_inside_it_and_its_neighbour_others() {
        let settings = ScatterSettings { per_chunk: 3, ..ScatterSettings::default() };
        let trees = scatter(&settings, (-2, 5), (-32.0, 80.0), 16.0);
        assert_eq!(trees.len(), 3);
        assert_eq!(trees, scatter(&settings, (-2, 5), (-32.0, 80.0), 16.0));
        for tree in &trees {
            let Shape::Polyline { points, .. } = &tree[0].shape else { panic!("a trunk is a polyline") };
            assert!((-30.4..=-17.6).contains(&points[0].x) && (81.6..=94.4).contains(&points[0].z), "{}", points[0]);
            assert_eq!(points[0].y, 0.0);
        }
        assert_ne!(trees, scatter(&settings, (-2, 6), (-32.0, 96.0), 16.0));
        assert!(ScatterSettings { per_chunk: 0, ..settings }.check().is_err());
        assert!(settings.check().is_ok());
    }
    use crate::tree::model::Tree;

    #[test]
    fn the_same_seed_gives_the_same_forest_and_another_seed_another() {
        let settings = GeneratorSettings { trunks: 4, ..GeneratorSettings::default() };
        assert_eq!(generate(&settings), generate(&settings));
        assert_ne!(generate(&settings), generate(&GeneratorSettings { seed: 2, ..settings }));
    }

    #[test]
    fn generated_trees_build_with_the_expected_number_of_supports() {
        let settings = GeneratorSettings { trunks: 3, branches: 4, depth: 2, ..GeneratorSettings::default() };
        for supports in generate(&settings) {
            assert_eq!(supports.len(), 1 + 4 + 16);
            let tree = Tree::build(&supports).unwrap();
            assert_eq!(tree.supports[0].kind, crate::tree::SupportKind::Trunk);
            assert!(tree.supports.iter().all(|s| s.radii.iter().all(|&r| r > 0.0)));
        }
    }

    #[test]
    fn settings_out_of_range_are_refused_with_the_field() {
        let too_many = GeneratorSettings { trunks: 10_000, branches: 10, depth: 4, ..GeneratorSettings::default() };
        assert!(too_many.check().unwrap_err().contains("over a million supports"));
        let flat = GeneratorSettings { height: 0.0, ..GeneratorSettings::default() };
        assert!(flat.check().unwrap_err().starts_with("height:"));
        assert!(GeneratorSettings::default().check().is_ok());
    }
}
