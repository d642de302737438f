//! The CPU rasterizer: the pure core is the `canopy_raster` crate (re-exported here), built
//! optimized even in development builds; [`plugin`] is its ECS side and [`settings`] the scene's
//! `render` entity.

pub use canopy_raster::*;

pub mod plugin;
pub mod settings;

pub use plugin::{RasterMesh, RasterPlugin, RenderSystems, RenderView};
pub use settings::{RenderParams, RenderSettingsPlugin};
