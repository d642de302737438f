//! Canopy: a small simulation engine on Bevy's ECS that draws its 3D view with its own CPU
//! rasterizer, plays scenes described in YAML files in a window with keyboard controls, and
//! runs the same scenes headless for tests.
//!
//! # Layers
//!
//! Modules import only from the layers below them (`tests/architecture.rs` reads the
//! `crate::` paths of every file and refuses an upward use, a cycle, and a kind reaching into
//! another kind's plugin):
//!
//! | layer | modules | what it holds |
//! |---|---|---|
//! | app | [`app`], [`run`], [`scene_test`], [`ui`], [`cli`], `main` | the plugin group and the list of kinds, headless runs, scene tests, the window, the command line |
//! | kinds | [`shape`], [`muscle`], [`tree`], [`sloth`], [`terrain`], [`world`], [`soft_body`], [`elastic`], [`ar`] | each a folder: an entry (`kind.rs`), its file format (`def.rs`), its plugin and panel, its pure cores; a kind may use another's pure cores |
//! | services | [`spatial`], [`view`], [`raster`], [`controls`] | what things are made of and the picking system; camera and light; the rasterizer's plugin; keys and timelines |
//! | scene | [`scene`] | loading, checking, spawning and saving through the kind registry, naming no kind |
//! | foundation | [`foundation`] | the entity marker, the kind trait, checked values, located errors, parameters, dumps, keys, panel sections, the schedule |
//! | crates | `canopy_raster`, `canopy_vision` | pixels, markers and cameras from plain data |
//!
//! An entity kind is a folder and one line in [`app::entity_kinds`].
//!
//! | plugin | module | what it does |
//! |---|---|---|
//! | [`FoundationPlugin`](foundation::FoundationPlugin) | [`foundation`] | the phases of a frame, the simulated clock, app-wide messages |
//! | [`ControlsPlugin`](controls::ControlsPlugin) | [`controls`] | global keys, scripted timelines |
//! | [`ScenePlugin`](scene::ScenePlugin) | [`scene`] | YAML scene assets, hot reload, spawning |
//! | [`ViewPlugin`](view::ViewPlugin) | [`view`] | camera and light entities and their keys |
//! | [`SpatialPlugin`](spatial::SpatialPlugin) | [`spatial`] | the order of the spatial sets; one ray cast under the pointer into every pickable, the nearest hit handed to its kind |
//! | [`RenderSettingsPlugin`](raster::RenderSettingsPlugin) | [`raster`] | the `render` entity: shading and shadows |
//! | [`ShapePlugin`](shape::ShapePlugin) | [`shape`] | the `shape` entity kind |
//! | [`MusclePlugin`](muscle::MusclePlugin) | [`muscle`] | the `muscle` entity kind |
//! | [`TerrainPlugin`](terrain::TerrainPlugin) | [`terrain`] | the `terrain` entity kind: heightmaps, the visible section, bands |
//! | [`WorldPlugin`](world::WorldPlugin) | [`world`] | the `world` entity kind: an unbounded terrain streamed in chunks |
//! | [`TreePlugin`](tree::TreePlugin) | [`tree`] | the `tree` entity kind: supports, queries, editing |
//! | [`SlothPlugin`](sloth::SlothPlugin) | [`sloth`] | the `sloth` entity kind: rig, IK, gait, footholds |
//! | [`SoftBodyPlugin`](soft_body::SoftBodyPlugin) | [`soft_body`] | the `soft_body` entity kind: regions of surfaces shrunk by deformers |
//! | [`ElasticPlugin`](elastic::ElasticPlugin) | [`elastic`] | the `elastic_body` entity kind: soft solids by XPBD |
//! | [`ArPlugin`](ar::ArPlugin) | [`ar`] | the `ar` entity kind: the scene on a marker over a camera's frames |
//! | [`RasterPlugin`](raster::RasterPlugin) | [`raster`] | the CPU rasterizer |
//! | [`LinesPlugin`](raster::lines::LinesPlugin) | [`raster`] | lines drawn into the frame in 3D, for debug views |
//! | [`UiPlugin`](ui::UiPlugin) | [`ui`] | the window: the frame and the egui panel composed on the CPU, key help |
//!
//! [`CanopyPlugins`] adds them all; [`app`] assembles windowed and headless apps.
//!
//! # Where each rule lives
//!
//! | rule | where |
//! |---|---|
//! | the muscle's frustum volume and the quadratic (its `A` coefficient) that keeps it when the length changes | [`muscle::model`] |
//! | elbow flexion from muscle length and back, by the law of cosines | [`muscle::carcass`] |
//! | a support tilted more than 70 degrees from horizontal is a trunk | [`tree::model`] |
//! | the diagonal-sequence gait: footfall order and timing from speed | [`sloth::gait`] |
//! | the leg order, "hind feet never ahead of fore feet", with the step lengths it works with | [`sloth::foothold`] |
//! | what a body's particles meet, and how deep a point lies inside it | [`spatial::solid`] |
//! | the nearest hit under the pointer across every kind | [`spatial::pick`] |
//! | joint limits from the animal's range of motion | [`sloth::rig`] |
//! | trunks climbed head up; transfers between a branch and its trunk | [`sloth::transfer`] |
//! | the top-left fill rule and the edge functions | `canopy_raster::setup` |
//! | the shadow map fitted to the light's view, its biases and filtering | [`raster::shadow`] |
//! | errors at file, line, column and field | [`foundation::yaml`] |
//! | the phases of a frame | [`foundation::schedule`] |
// One `unsafe` call, to hand the window handles to `softbuffer` (`ui::surface`).
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod app;
pub mod ar;
pub mod cli;
pub mod controls;
pub mod elastic;
pub mod foundation;
pub mod muscle;
pub mod raster;
pub mod run;
pub mod scene;
pub mod scene_test;
pub mod shape;
pub mod sloth;
pub mod soft_body;
pub mod spatial;
pub mod terrain;
pub mod tree;
pub mod ui;
pub mod view;
pub mod world;

pub use app::CanopyPlugins;

/// The types most users of the library need.
pub mod prelude {
    pub use crate::app::{CanopyPlugins, Display, entity_kinds};
    pub use crate::foundation::actions::RegisterActions;
    pub use crate::foundation::dump::{DumpState, RegisterDump};
    pub use crate::foundation::entity::SceneEntity;
    pub use crate::foundation::kind::EntityKind;
    pub use crate::foundation::params::{ParamValue, RegisterParams};
    pub use crate::foundation::schedule::{ControlSystems, RenderSystems, SimSystems, WriteBackSystems};
    pub use crate::raster::RasterMesh;
}
