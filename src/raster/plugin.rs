//! The rasterizer as a Bevy plugin: every entity with a [`RasterMesh`] and a
//! `GlobalTransform` is drawn into the [`RasterTarget`] framebuffer after transform
//! propagation.
//!
//! | set (`PostUpdate`) | system | what it does |
//! |---|---|---|
//! | [`RenderSystems::Collect`] | `collect_meshes` | gathers meshes and transforms into [`RenderQueue`]; other plugins write [`RenderView`] here |
//! | [`RenderSystems::Raster`] | `rasterize` | draws the frame on the compute task pool |
//! | [`RenderSystems::Present`] | `save_screenshots` | writes requested screenshots; a window plugin shows the framebuffer |
//!
//! Drawing runs every frame, or only when asked ([`RenderPolicy`]) in headless runs that need
//! just their last frame.

use super::levels::MeshLevels;
use super::primitives::PrimitiveMeshes;
use super::{
    Camera, Framebuffer, Instance, Lens, Light, MAX_TARGET_SIZE, Material, MeshData, RenderSettings, RenderStats,
    Renderer,
};
use crate::foundation::messages::SaveScreenshot;
use crate::foundation::schedule::{ControlSystems, RenderSystems};
use crate::foundation::values::first_free_path;
use bevy::prelude::*;
use bevy::tasks::{ComputeTaskPool, TaskPool};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The geometry and material an entity is drawn with; its `GlobalTransform` places it.
///
/// Domain plugins feed the rasterizer only through this component: write a new mesh when the
/// shape changes, move the transform when it only moves.
#[derive(Component, Debug, Clone)]
#[require(Transform)]
pub struct RasterMesh {
    /// The triangles, shareable between entities.
    pub mesh: Arc<MeshData>,
    /// Colour, texture and sampling.
    pub material: Material,
}

impl RasterMesh {
    /// A mesh drawn in a plain colour (sRGB channels from 0 to 1, see
    /// [`srgb_channels`](crate::foundation::values::srgb_channels)).
    pub fn colored(mesh: Arc<MeshData>, color: Vec3) -> Self {
        Self { mesh, material: Material::colored(color) }
    }
}

/// The camera, light, background and settings of the next frame.
#[derive(Resource, Debug, Clone, Copy)]
pub struct RenderView {
    /// The viewpoint.
    pub camera: Camera,
    /// The directional light.
    pub light: Light,
    /// Colour where no surface is, RGBA8.
    pub background: [u8; 4],
    /// Shading mode and shadows.
    pub settings: RenderSettings,
}

impl Default for RenderView {
    fn default() -> Self {
        Self {
            camera: Camera {
                eye: Vec3::new(0.0, 0.0, 5.0),
                target: Vec3::ZERO,
                lens: Lens::FieldOfView(1.0),
                near: 0.1,
                far: 100.0,
            },
            light: Light { direction: Vec3::NEG_Y, diffuse: 1.0, fill: 0.0, ambient: 0.2 },
            background: [0, 0, 0, 255],
            settings: RenderSettings::default(),
        }
    }
}

/// The instances of the next frame, in a stable order.
#[derive(Resource, Debug, Default)]
pub struct RenderQueue(pub Vec<Instance>);

/// The framebuffer, its wanted size and the figures of the last frame drawn.
#[derive(Resource, Debug)]
pub struct RasterTarget {
    /// The last frame drawn.
    pub framebuffer: Framebuffer,
    /// The size the next frame is drawn at, in pixels (at most
    /// [`MAX_TARGET_SIZE`] a side).
    pub size: UVec2,
    /// Counts from the last frame.
    pub stats: RenderStats,
    /// Wall-clock time the last frame took to draw (for display only).
    pub raster_time: Duration,
}

impl RasterTarget {
    /// An empty target that draws at `size` pixels.
    pub fn new(size: UVec2) -> Self {
        Self { framebuffer: Framebuffer::default(), size, stats: RenderStats::default(), raster_time: Duration::ZERO }
    }
}

/// When frames are drawn.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq)]
pub struct RenderPolicy {
    /// Draw every frame (windows); otherwise only frames asked for with `requested`.
    pub every_frame: bool,
    /// Draw this frame; cleared once drawn.
    pub requested: bool,
}

impl RenderPolicy {
    fn wants_frame(policy: Res<RenderPolicy>) -> bool {
        policy.every_frame || policy.requested
    }
}

/// Screenshots asked for and the folder they go to.
#[derive(Resource, Debug, Clone)]
pub struct Screenshots {
    /// Folder screenshots are written to (created when needed).
    pub folder: PathBuf,
    /// A screenshot is due after the next frame.
    pending: bool,
}

/// Draws [`RasterMesh`] entities into a [`RasterTarget`].
pub struct RasterPlugin {
    /// Size of the framebuffer until something resizes it, in pixels.
    pub size: UVec2,
    /// Whether to draw every frame, or only on request.
    pub every_frame: bool,
}

impl Plugin for RasterPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<RenderView>()
            .init_resource::<RenderQueue>()
            .insert_resource(RasterTarget::new(self.size))
            .insert_resource(RenderPolicy { every_frame: self.every_frame, requested: false })
            .insert_resource(Screenshots { folder: PathBuf::from("screenshots"), pending: false })
            .init_resource::<PrimitiveMeshes>()
            .configure_sets(
                PostUpdate,
                (
                    RenderSystems::Collect,
                    RenderSystems::Camera,
                    RenderSystems::Raster,
                    RenderSystems::Composite,
                    RenderSystems::Present,
                )
                    .run_if(RenderPolicy::wants_frame),
            )
            .add_systems(Update, request_screenshots.in_set(ControlSystems::Apply))
            .add_systems(PostUpdate, collect_meshes.in_set(RenderSystems::Collect))
            .add_systems(PostUpdate, rasterize.in_set(RenderSystems::Raster))
            .add_systems(PostUpdate, save_screenshots.in_set(RenderSystems::Present));
    }
}

fn request_screenshots(
    mut requests: MessageReader<SaveScreenshot>,
    mut screenshots: ResMut<Screenshots>,
    mut policy: ResMut<RenderPolicy>,
) {
    if requests.read().count() > 0 {
        screenshots.pending = true;
        policy.requested = true;
    }
}

/// The frame's instances: every mesh where it stands, at the level of detail its size on
/// screen asks for.
fn collect_meshes(
    meshes: Query<(&RasterMesh, &GlobalTransform, Option<&MeshLevels>)>,
    view: Res<RenderView>,
    target: Res<RasterTarget>,
    mut queue: ResMut<RenderQueue>,
) {
    let height = target.size.y.min(MAX_TARGET_SIZE);
    queue.0.clear();
    queue.0.extend(meshes.iter().map(|(raster, transform, levels)| {
        let model = transform.to_matrix();
        let mesh = levels.map_or(&raster.mesh, |levels| levels.choose(&raster.mesh, model, &view.camera, height));
        Instance { mesh: mesh.clone(), model, material: raster.material.clone() }
    }));
}

/// Draws the frame.
pub(super) fn rasterize(
    view: Res<RenderView>,
    queue: Res<RenderQueue>,
    mut target: ResMut<RasterTarget>,
    mut policy: ResMut<RenderPolicy>,
    mut renderer: Local<Renderer>,
) {
    let started = Instant::now();
    let target = &mut *target;
    let size = target.size.min(UVec2::splat(MAX_TARGET_SIZE));
    if target.framebuffer.width() != size.x || target.framebuffer.height() != size.y {
        target.framebuffer.resize(size.x, size.y);
    }
    let frame = super::Frame {
        camera: view.camera,
        light: view.light,
        background: view.background,
        instances: &queue.0,
        settings: view.settings,
    };
    let pool = ComputeTaskPool::get_or_init(TaskPool::default);
    target.stats = renderer.render(&mut target.framebuffer, pool, &frame);
    target.raster_time = started.elapsed();
    policy.requested = false;
}

fn save_screenshots(mut screenshots: ResMut<Screenshots>, target: Res<RasterTarget>) {
    if !screenshots.pending {
        return;
    }
    screenshots.pending = false;
    let saved = std::fs::create_dir_all(&screenshots.folder).map_err(|e| e.to_string()).and_then(|()| {
        // The first free name: an earlier screenshot is never overwritten.
        let path = first_free_path(|n| screenshots.folder.join(format!("canopy-{n:04}.png")));
        target.framebuffer.save_png(&path).map(|()| path).map_err(|e| e.to_string())
    });
    match saved {
        Ok(path) => info!("screenshot saved to {}", path.display()),
        Err(error) => error!("could not save the screenshot in {}: {error}", screenshots.folder.display()),
    }
}
