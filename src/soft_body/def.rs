//! The `soft_body:` entry of a scene file, and the kind that reads, spawns and saves it.
//!
//! ```yaml
//! - soft_body:
//!     name: torso
//!     mesh: meshes/torso.obj        # an .obj, .ply, .stl, .gltf or .glb file; or
//!     # sample: { shape: torso, size: 80 }
//!     position: [0, 0.7, 0]
//!     method: area                  # edge_lengths, edge_sum or area
//!     variant: projection           # or source, constant, decreasing, steepest, coordinate
//!     k: 0.9
//! ```

use super::deform::{Deformer, Method, Settings, Variant};
use super::sample::{SIZES, Shape};
use crate::foundation::kind::{BuildContext, EntityContext, ReferencedFile};
use crate::foundation::values::{Color, FolderFile, Point, checked_number};
use crate::foundation::yaml::FileError;
use crate::spatial::mesh_io::{self, MeshFile, MeshReport, Source, TriangleMesh};
use crate::spatial::surface::Surface;
use bevy::color::Srgba;
use bevy::math::Vec3;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

checked_number!(
    /// A deformer's coefficient: greater than 0 and at most 1.
    Coefficient(f32),
    "a coefficient greater than 0 and at most 1",
    |v| v > 0.0 && v <= 1.0
);
checked_number!(
    /// A convergence threshold: greater than 0 and at most 1.
    Threshold(f64),
    "a threshold greater than 0 and at most 1",
    |v| v > 0.0 && v <= 1.0
);
checked_number!(
    /// An iteration cap: a whole number from 1 to a million.
    IterationCap(u32),
    "a whole number of iterations from 1 to 1000000",
    |v| v.fract() == 0.0 && (1.0..=1e6).contains(&v)
);
checked_number!(
    /// How many times its file's size a surface is shown: from 0.001 to 1000.
    Scale(f32),
    "a scale from 0.001 to 1000",
    |v| (1e-3..=1e3).contains(&v)
);
checked_number!(
    /// Vertices along a sample's main direction: a whole number from 3 to 1000.
    SampleSize(u32),
    "a whole number from 3 to 1000",
    |v| v.fract() == 0.0 && (*SIZES.start() as f64..=*SIZES.end() as f64).contains(&v)
);

/// A sample surface the project makes.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SampleDef {
    /// Which surface.
    pub shape: Shape,
    /// Vertices along its main direction (see [`Shape`]); 64 by default.
    #[serde(default = "default_sample_size")]
    pub size: SampleSize,
}

fn default_sample_size() -> SampleSize {
    SampleSize(64)
}

/// A `soft_body` entity in a scene file: a surface from a mesh file or a sample, where it
/// stands, and the deformer its regions are shrunk with at first.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SoftBodyDef {
    /// The mesh file, relative to the scene's folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<FolderFile<MeshFile>>,
    /// A sample surface instead of a file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample: Option<SampleDef>,
    /// Where the surface's origin stands, metres; the origin by default.
    #[serde(default = "origin")]
    pub position: Point,
    /// How many times its own size it is shown (marks and the dump stay in its own metres);
    /// 1 by default.
    #[serde(default = "unit_scale")]
    pub scale: Scale,
    /// Its colour; a skin tone by default.
    #[serde(default = "skin")]
    pub color: Color,
    /// The deformer; `area` by default.
    #[serde(default = "default_deformer")]
    pub method: Deformer,
    /// How the edge-sum and area deformers step; `projection` by default.
    #[serde(default = "default_variant")]
    pub variant: Variant,
    /// The coefficient; 0.9 by default (below 1 for the area).
    #[serde(default = "default_k")]
    pub k: Coefficient,
    /// The convergence threshold; 1e-5 by default.
    #[serde(default = "default_eps")]
    pub eps: Threshold,
    /// The iteration cap; 2000 by default.
    #[serde(default = "default_cap")]
    pub max_iterations: IterationCap,
    /// The mesh as read from `mesh`, filled in when the scene is resolved.
    #[serde(skip)]
    pub decoded: Option<Arc<(TriangleMesh, MeshReport, Source)>>,
}

fn origin() -> Point {
    Point(Vec3::ZERO)
}

fn unit_scale() -> Scale {
    Scale(1.0)
}

fn skin() -> Color {
    Color(Srgba::rgb(0.85, 0.64, 0.53))
}

fn default_deformer() -> Deformer {
    Deformer::Area
}

fn default_variant() -> Variant {
    Variant::Projection
}

fn default_k() -> Coefficient {
    Coefficient(0.9)
}

fn default_eps() -> Threshold {
    Threshold(1e-5)
}

fn default_cap() -> IterationCap {
    IterationCap(2000)
}

impl SoftBodyDef {
    /// The deformer and settings the definition asks for.
    pub fn deformer(&self) -> (Method, Settings) {
        let settings = Settings { k: self.k.0, eps: self.eps.0, max_iterations: self.max_iterations.0 };
        (self.method.method(self.variant), settings)
    }
}

/// What a soft body's build made: its surface and what reading its file found.
#[derive(Debug, Clone)]
pub struct SoftBodyBuilt {
    /// The surface, every vertex movable.
    pub surface: Surface,
    /// What welding its file found (nothing for a sample).
    pub read: MeshReport,
    /// The mesh file it was read from, to write models back over (none for a sample).
    pub file: Option<Arc<DecodedMesh>>,
}

/// Checks that an entry of kind `key` names a surface by exactly one of `mesh` and `sample`.
pub fn check_source<F>(
    key: &str,
    mesh: &Option<F>,
    sample: &Option<SampleDef>,
    cx: &EntityContext,
) -> Result<(), FileError> {
    match (mesh, sample) {
        (Some(_), Some(_)) => Err(cx.field_error("sample", 0, "sample", "a surface from a mesh or a sample, not both")),
        (None, None) => Err(cx.locate(
            key,
            cx.kind_index,
            format!(
                "{}: expected `mesh: FILE` (an .obj, .ply, .stl, .gltf or .glb file) or `sample: {{ shape: torso }}`",
                cx.field("mesh")
            ),
        )),
        _ => Ok(()),
    }
}

/// Reads and welds the mesh file of an entry's `mesh` field, once for every entry naming it.
pub fn read_mesh(file: &mut ReferencedFile, cx: &EntityContext) -> Result<Arc<DecodedMesh>, FileError> {
    let located = |message: String| cx.field_error("mesh", 0, "mesh", format!("{}: {message}", file.path.display()));
    let format = mesh_io::Format::of(file.path).map_err(|error| located(error.to_string()))?;
    file.decoded(|path, bytes| {
        mesh_io::parse_source(bytes.to_vec(), format, mesh_io::folder_of(path)).map_err(|error| error.to_string())
    })
    .map_err(located)
}

/// A mesh file read: the welded mesh, what welding found, and the file for writing back.
pub type DecodedMesh = (TriangleMesh, MeshReport, Source);

/// The surface an entry names, from its mesh as read or its sample, with what welding the
/// file found (nothing for a sample); an error is located at `mesh`.
pub fn source_surface(
    decoded: &Option<Arc<DecodedMesh>>,
    sample: Option<SampleDef>,
    cx: &BuildContext,
) -> Result<(Surface, MeshReport), FileError> {
    let (surface, read) = match (decoded, sample) {
        (Some(decoded), _) => {
            let (mesh, read, _) = &**decoded;
            let movable = vec![true; mesh.positions.len()];
            let surface = Surface::new(mesh.positions.clone(), mesh.triangles.clone(), movable)
                .map_err(|error| cx.entity.field_error("mesh", 0, "mesh", error))?;
            (surface, *read)
        }
        (None, Some(sample)) => (sample.shape.make(sample.size.0), MeshReport::default()),
        (None, None) => return Err(cx.entity.field_error("mesh", 0, "mesh", "the mesh was not read")),
    };
    if surface.triangles.is_empty() {
        return Err(cx.entity.field_error("mesh", 0, "mesh", "the mesh has no triangles"));
    }
    Ok((surface, read))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_and_checked_values() {
        let def: SoftBodyDef = serde_yaml::from_str("sample: { shape: torso }").unwrap();
        assert_eq!(
            (def.method, def.variant, def.k.0, def.max_iterations.0),
            (Deformer::Area, Variant::Projection, 0.9, 2000)
        );
        assert_eq!(def.sample.unwrap().size.0, 64);
        for (text, expected) in [
            ("{sample: {shape: torso}, k: 1.5}", "a coefficient greater than 0 and at most 1"),
            ("{sample: {shape: torso}, max_iterations: 2.5}", "a whole number of iterations"),
            ("{sample: {shape: torso, size: 2}}", "a whole number from 3 to 1000"),
            ("{sample: {shape: cube}}", "unknown variant `cube`"),
            ("{mesh: ../body.obj}", "inside the scene's folder"),
            ("{mesh: body.fbx}", "an .obj, .ply, .stl, .gltf or .glb file"),
            ("{sample: {shape: torso}, method: bend}", "unknown variant `bend`"),
        ] {
            let error = serde_yaml::from_str::<SoftBodyDef>(text).unwrap_err().to_string();
            assert!(error.contains(expected), "{text}: {error}");
        }
    }
}
