//! The primitive solids, meshed once and shared by every entity drawing one.

use super::MeshData;
use bevy::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Which solid a shape is. Each fits the box of its `size`: a sphere of size `[2, 1, 1]` is an
/// ellipsoid, a cylinder stands along y, a plane lies in xz facing +y.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Reflect)]
#[serde(rename_all = "snake_case")]
pub enum Primitive {
    /// A cuboid.
    Box,
    /// A sphere (ellipsoid for unequal sizes).
    Sphere,
    /// A cylinder along y with flat caps.
    Cylinder,
    /// A flat rectangle in xz facing +y; its y size is ignored.
    Plane,
}

impl Primitive {
    /// The name used in files and dumps.
    pub fn key(self) -> &'static str {
        match self {
            Primitive::Box => "box",
            Primitive::Sphere => "sphere",
            Primitive::Cylinder => "cylinder",
            Primitive::Plane => "plane",
        }
    }
}

/// The primitive meshes, built once and shared by every entity.
#[derive(Resource)]
pub struct PrimitiveMeshes {
    cube: Arc<MeshData>,
    sphere: Arc<MeshData>,
    cylinder: Arc<MeshData>,
    plane: Arc<MeshData>,
}

impl Default for PrimitiveMeshes {
    fn default() -> Self {
        Self {
            cube: Arc::new(MeshData::cube()),
            sphere: Arc::new(MeshData::sphere(24, 48)),
            cylinder: Arc::new(MeshData::cylinder(48)),
            plane: Arc::new(MeshData::plane(16)),
        }
    }
}

impl PrimitiveMeshes {
    /// The shared mesh of a primitive, sized 1 along every axis.
    pub fn get(&self, primitive: Primitive) -> &Arc<MeshData> {
        match primitive {
            Primitive::Box => &self.cube,
            Primitive::Sphere => &self.sphere,
            Primitive::Cylinder => &self.cylinder,
            Primitive::Plane => &self.plane,
        }
    }
}
