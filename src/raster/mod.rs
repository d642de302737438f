//! The CPU rasterizer's side of the app: the pure core is the `canopy_raster` crate
//! (re-exported here), built optimized even in development builds.
//!
//! | module | what it holds |
//! |---|---|
//! | [`lines`] | lines drawn into the frame in 3D, behind surfaces or on top: the debug views' |
//! | [`plugin`] | [`RasterPlugin`]: every [`RasterMesh`] drawn into the framebuffer after transform propagation |
//! | [`settings`] | the scene's `render` entity: shading and shadows as parameters and keys |
//! | [`primitives`] | the primitive solids, meshed once and shared |
//! | [`texture`] | the `texture:` section shapes and trees share, and the material it makes |

pub use canopy_raster::*;

pub mod levels;
pub mod lines;
pub mod plugin;
pub mod primitives;
pub mod settings;
pub mod texture;

pub use plugin::{RasterMesh, RasterPlugin, RenderView};
pub use settings::{RenderParams, RenderSettingsPlugin};
