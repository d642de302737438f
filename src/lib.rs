//! Canopy: a small simulation engine on Bevy's ECS that draws its 3D view with its own CPU
//! rasterizer, plays scenes described in YAML files in a window with keyboard controls, and
//! runs the same scenes headless for tests.
//!
//! | plugin | module | what it does |
//! |---|---|---|
//! | [`SchedulePlugin`](schedule::SchedulePlugin) | [`schedule`] | system sets, fixed-step clock, pause |
//! | [`ScenePlugin`](scene::ScenePlugin) | [`scene`] | YAML scene assets, hot reload, spawning |
//! | [`ViewPlugin`](view::ViewPlugin) | [`view`] | camera and light entities and their keys |
//! | [`ShapePlugin`](shape::ShapePlugin) | [`shape`] | the `shape` entity kind |
//! | [`MusclePlugin`](muscle::MusclePlugin) | [`muscle`] | the `muscle` entity kind |
//! | [`TreePlugin`](tree::TreePlugin) | [`tree`] | the `tree` entity kind: supports, queries, editing |
//! | [`SlothPlugin`](sloth::SlothPlugin) | [`sloth`] | the `sloth` entity kind: rig, IK, gait, footholds |
//! | [`RasterPlugin`](raster::RasterPlugin) | [`raster`] | the CPU rasterizer |
//! | [`ControlsPlugin`](controls::ControlsPlugin) | [`controls`] | global keys, scripted timelines |
//! | [`UiPlugin`](ui::UiPlugin) | [`ui`] | the window: framebuffer, egui panel, key help |
//!
//! [`CanopyPlugins`] adds them all; [`app`] assembles windowed and headless apps.
#![forbid(unsafe_code)]

pub mod app;
pub mod controls;
pub mod dump;
pub mod muscle;
pub mod params;
pub mod raster;
pub mod run;
pub mod scene;
pub mod schedule;
pub mod shape;
pub mod sloth;
pub mod tree;
pub mod ui;
pub mod view;
pub mod yaml;

pub use app::CanopyPlugins;

/// The types most users of the library need.
pub mod prelude {
    pub use crate::app::{CanopyPlugins, Display};
    pub use crate::dump::{DumpState, RegisterDump};
    pub use crate::params::{ParamValue, RegisterParams};
    pub use crate::raster::{RasterMesh, RenderSystems};
    pub use crate::scene::SceneEntity;
    pub use crate::schedule::{ControlSystems, SimSystems};
}
