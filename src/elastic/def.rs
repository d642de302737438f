//! The `elastic_body:` entry of a scene file, and the kind that reads, builds and saves it.
//!
//! ```yaml
//! - name: plum
//!   elastic_body:
//!     sample: { shape: sphere, size: 24 }   # or mesh: meshes/fruit.obj (closed)
//!     size: 0.12                             # its extent along x, y and z, metres
//!     stem: { support: oak/limb, at: 0.6, length_m: 0.04 }   # or position: [x, y, z]
//!     cell_m: 0.015                          # the tetrahedral lattice's cell
//!     young_modulus_pa: 30000
//!     poisson_ratio: 0.4
//! ```

use super::material::Material;
use super::tet_mesh::Embedding;
use super::xpbd::{Attachment, Body};
use crate::foundation::kind::BuildContext;
use crate::foundation::values::{Color, FolderFile, Point, PositiveMetres, Size, UnitInterval, checked_number};
use crate::foundation::yaml::FileError;
use crate::soft_body::def::{DecodedMesh, SampleDef};
use crate::spatial::mesh_io::{MeshFile, MeshReport};
use crate::tree::TreeKind;
use bevy::color::Srgba;
use bevy::math::Vec3;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Most tetrahedra a body may have: beyond this a body could not keep up with the frames.
pub const MAX_TETS: usize = 200_000;

checked_number!(
    /// A density in kilograms per cubic metre: from 1 to 100000.
    Density(f32),
    "a density from 1 to 100000 kg/m^3",
    |v| (1.0..=1e5).contains(&v)
);
checked_number!(
    /// A Young's modulus in pascals: from 1 to 1e9.
    Modulus(f32),
    "a Young's modulus from 1 to 1e9 Pa",
    |v| (1.0..=1e9).contains(&v)
);
checked_number!(
    /// A Poisson's ratio: from 0 to 0.5.
    Poisson(f32),
    "a Poisson's ratio from 0 to 0.5",
    |v| (0.0..=0.5).contains(&v)
);
checked_number!(
    /// A damping rate, the share of velocity lost per second: from 0 to 100.
    Damping(f32),
    "a damping rate from 0 to 100 per second",
    |v| (0.0..=100.0).contains(&v)
);
checked_number!(
    /// A bending rigidity in newton metres: from 0 to 1000.
    Bending(f32),
    "a bending rigidity from 0 to 1000 N m",
    |v| (0.0..=1e3).contains(&v)
);
checked_number!(
    /// A friction coefficient: from 0 to 10.
    Friction(f32),
    "a friction coefficient from 0 to 10",
    |v| (0.0..=10.0).contains(&v)
);
checked_number!(
    /// Substeps a fixed step: a whole number from 1 to 100.
    Substeps(u32),
    "a whole number of substeps from 1 to 100",
    |v| v.fract() == 0.0 && (1.0..=100.0).contains(&v)
);

/// A stem a body hangs from: from a point of a tree's support (its underside) or from a
/// point in space, down to the body's top.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct StemDef {
    /// The support, `tree/support` (the tree's entity name and the support's name).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support: Option<String>,
    /// Where along the support, 0 at its start to 1 at its end; 0.5 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<UnitInterval>,
    /// A point in space instead of a support, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<Point>,
    /// The stem's length from the support's underside to the body's top, metres; 0.03 by default.
    #[serde(default = "default_stem")]
    pub length_m: PositiveMetres,
    /// A hand taking hold of a support (an animal's passing) within this many metres of the
    /// stem's anchor shakes the body loose; never by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shaken_loose_m: Option<PositiveMetres>,
}

fn default_stem() -> PositiveMetres {
    PositiveMetres(0.03)
}

/// An `elastic_body` entity in a scene file: a closed surface from a mesh file or a sample,
/// filled with tetrahedra, its material and where it starts: standing at a position or
/// hanging from a stem.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ElasticBodyDef {
    /// The mesh file of its closed surface, relative to the scene's folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<FolderFile<MeshFile>>,
    /// A sample surface instead of a file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample: Option<SampleDef>,
    /// Its extent along x, y and z, metres (the surface is scaled to fit); 0.2 by default.
    #[serde(default = "default_size")]
    pub size: Size,
    /// Where its centre starts, metres; the origin by default (not with a stem).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<Point>,
    /// The stem it hangs from, until it is dropped.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stem: Option<StemDef>,
    /// Its velocity at the start, metres per second; at rest by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<Point>,
    /// The side of the lattice's cubic cells, metres; a tenth of its smallest extent by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cell_m: Option<PositiveMetres>,
    /// Density, kilograms per cubic metre; 1000 by default.
    #[serde(default = "default_density")]
    pub density_kg_m3: Density,
    /// Young's modulus, pascals; 20000 (a firm jelly) by default.
    #[serde(default = "default_modulus")]
    pub young_modulus_pa: Modulus,
    /// Poisson's ratio; 0.4 by default.
    #[serde(default = "default_poisson")]
    pub poisson_ratio: Poisson,
    /// The share of velocity lost per second; 0.5 by default.
    #[serde(default = "default_damping")]
    pub damping_per_s: Damping,
    /// The bending rigidity of its skin, newton metres; 0 (no skin) by default.
    #[serde(default = "default_bending")]
    pub bending_rigidity_nm: Bending,
    /// Friction with the solids it touches; 0.6 by default.
    #[serde(default = "default_friction")]
    pub friction: Friction,
    /// Substeps a fixed step; 10 by default.
    #[serde(default = "default_substeps")]
    pub substeps: Substeps,
    /// Its colour; a jelly's red by default.
    #[serde(default = "default_color")]
    pub color: Color,
    /// The mesh as read from `mesh`, filled in when the scene is resolved.
    #[serde(skip)]
    pub decoded: Option<Arc<DecodedMesh>>,
}

fn default_size() -> Size {
    Size(Vec3::splat(0.2))
}

fn default_density() -> Density {
    Density(1000.0)
}

fn default_modulus() -> Modulus {
    Modulus(2e4)
}

fn default_poisson() -> Poisson {
    Poisson(0.4)
}

fn default_damping() -> Damping {
    Damping(0.5)
}

fn default_bending() -> Bending {
    Bending(0.0)
}

fn default_friction() -> Friction {
    Friction(0.6)
}

fn default_substeps() -> Substeps {
    Substeps(10)
}

fn default_color() -> Color {
    Color(Srgba::rgb(0.85, 0.2, 0.25))
}

impl ElasticBodyDef {
    /// The material the definition asks for.
    pub fn material(&self) -> Material {
        Material {
            density_kg_m3: self.density_kg_m3.0,
            young_modulus_pa: self.young_modulus_pa.0,
            poisson_ratio: self.poisson_ratio.0,
            damping_per_s: self.damping_per_s.0,
            bending_rigidity_nm: self.bending_rigidity_nm.0,
        }
    }

    /// The lattice's cell side, metres.
    pub fn cell(&self) -> f32 {
        self.cell_m.map_or(self.size.0.min_element() / 10.0, |c| c.0)
    }
}

/// What an elastic body's build made: the body at its start, and its surface as carried by
/// its tetrahedra.
#[derive(Debug, Clone)]
pub struct ElasticBuilt {
    /// The body as it starts, stems attached.
    pub body: Body,
    /// The surface's vertices in the tetrahedra.
    pub embedding: Embedding,
    /// The surface's triangles (shared with what picks the body).
    pub triangles: Arc<Vec<[u32; 3]>>,
    /// What welding its file found (nothing for a sample).
    pub read: MeshReport,
    /// The side of its lattice's cells, metres.
    pub cell_m: f32,
    /// Its stem's anchor and the distance from it within which a hand shakes it loose.
    pub shaken_loose: Option<(Vec3, f32)>,
}

/// Where a stem hangs from: its point, or the underside of its support at `at`; an unknown
/// tree or support is an error located at the stem's `support`.
pub(super) fn stem_anchor(stem: &StemDef, cx: &BuildContext) -> Result<Vec3, FileError> {
    if let Some(point) = stem.point {
        return Ok(point.0);
    }
    let label = stem.support.as_deref().unwrap_or_default();
    let trees: Vec<_> = cx.built::<TreeKind>().collect();
    let found = label.split_once('/').and_then(|(tree, support)| {
        let (_, tree) = trees.iter().find(|(name, _)| *name == tree)?;
        tree.supports.iter().find(|s| s.name == support)
    });
    let Some(support) = found else {
        let known: Vec<String> = trees
            .iter()
            .flat_map(|(name, tree)| tree.supports.iter().map(move |s| format!("{name}/{}", s.name)))
            .collect();
        let known = if known.is_empty() { "the scene has no trees".to_string() } else { known.join(", ") };
        return Err(cx.entity.field_error(
            "support",
            0,
            "stem.support",
            format!("no support `{label}` (supports: {known})"),
        ));
    };
    let (point, _, radius) = support.at(stem.at.map_or(0.5, |a| a.0));
    Ok(point - Vec3::Y * radius)
}

/// The stems from `anchor` to the particles of the body's top (within a cell of its highest)
/// that lie within a quarter of its width, or one and a half cells, of the anchor's
/// vertical: a stem holds a patch of the body, so that it does not pull one particle out.
pub(super) fn stems(body: &Body, anchor: Vec3, cell: f32) -> Vec<Attachment> {
    let top = body.positions.iter().map(|p| p.y).fold(f32::MIN, f32::max);
    let (low, high) = body.positions.iter().fold((Vec3::MAX, Vec3::MIN), |(l, h), &p| (l.min(p), h.max(p)));
    let reach = (0.25 * (high.x - low.x).min(high.z - low.z)).max(1.5 * cell);
    let across = |p: Vec3| Vec3::new(p.x - anchor.x, 0.0, p.z - anchor.z).length();
    let near_top = |p: usize| body.positions[p].y > top - cell - 1e-6;
    let mut held: Vec<usize> =
        (0..body.positions.len()).filter(|&p| near_top(p) && across(body.positions[p]) <= reach).collect();
    if held.is_empty() {
        // A top off the anchor's vertical: the top particle nearest it.
        held.extend(
            (0..body.positions.len())
                .filter(|&p| near_top(p))
                .min_by(|&a, &b| across(body.positions[a]).total_cmp(&across(body.positions[b]))),
        );
    }
    held.into_iter()
        .map(|p| Attachment {
            particle: p as u32,
            anchor,
            length_m: body.positions[p].distance(anchor),
            compliance: 0.0,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_and_checked_values() {
        let def: ElasticBodyDef = serde_yaml::from_str("sample: { shape: sphere }").unwrap();
        assert_eq!((def.size.0, def.cell(), def.substeps.0), (Vec3::splat(0.2), 0.02, 10));
        for (text, expected) in [
            ("{sample: {shape: sphere}, poisson_ratio: 0.6}", "a Poisson's ratio from 0 to 0.5"),
            ("{sample: {shape: sphere}, young_modulus_pa: 0}", "a Young's modulus from 1 to 1e9 Pa"),
            ("{sample: {shape: sphere}, substeps: 2.5}", "a whole number of substeps"),
            ("{sample: {shape: sphere}, density_kg_m3: -3}", "a density from 1 to 100000"),
            ("{sample: {shape: sphere}, friction: .nan}", "a friction coefficient"),
            ("{sample: {shape: sphere}, damping_per_s: 1000}", "a damping rate"),
            ("{sample: {shape: sphere}, bending_rigidity_nm: -1}", "a bending rigidity from 0 to 1000 N m"),
            ("{sample: {shape: sphere}, stem: {support: a/b, at: 2}}", "a number from 0 to 1"),
            ("{sample: {shape: sphere}, stem: {length_m: -1}}", "a length in metres greater than 0"),
            ("{sample: {shape: sphere}, bounce: 1}", "unknown field `bounce`"),
        ] {
            let error = serde_yaml::from_str::<ElasticBodyDef>(text).unwrap_err().to_string();
            assert!(error.contains(expected), "{text}: {error}");
        }
    }
}
