//! The frame pipeline: a parallel vertex stage, then (when shadows are on) the shadow map's
//! depth pass (module `depth`), then the image: its triangles sorted into bands of tile rows
//! (module `sort`), then the bands drawn in parallel (module `tile`) and, with shadows,
//! darkened where the light does not reach. The bands and the map's strips are handed to the
//! threads those that took longest in the last frame first (module `schedule`).
//!
//! A band takes the triangles reaching it in draw order, clips those crossing the near plane
//! or the guard band, sets each up (module `setup`: culling, pixel bounds, edge functions and
//! the planes of its values) and draws it at once into the band's tiles it touches, so that
//! earlier triangles win depth ties exactly as in a sequential renderer. A triangle reaching
//! two bands is set up in each. Every buffer lives in the [`Renderer`] and is reused, so a
//! frame of steady size allocates nothing of its own.

use crate::camera::{Camera, Light};
use crate::clip::{ClipLanes, ClipVertex, clip_triangle, outside};
use crate::depth::{DepthPass, DepthScene, STRIP_ROWS};
use crate::framebuffer::Framebuffer;
use crate::mesh::MeshData;
use crate::schedule::Schedule;
use crate::setup::Viewport;
use crate::shade::{Material, Shading, VARYINGS, Varyings, floor_lanes, slot};
use crate::shadow::{PixelsInMap, ShadowMap, fit_light};
use crate::sort::Sorted;
use crate::tile::{self, BandCounts, BandScratch, BandShadow, TileContext};
use bevy_math::{Mat3, Mat4, Vec2, Vec3, Vec4};
use bevy_tasks::TaskPool;
use std::ops::Range;
use std::sync::Arc;

/// Tile width in pixels.
pub const TILE_WIDTH: u32 = 64;

/// Tile height in pixels; a row of tiles is one unit of parallel work.
pub const TILE_HEIGHT: u32 = 64;

/// Sub-pixel positions per pixel along each axis (8 bits of sub-pixel precision).
pub const SUBPIXEL_STEPS: i64 = 256;

/// The largest framebuffer or shadow-map side, in pixels, for which the fixed-point edge
/// functions are exact.
pub const MAX_TARGET_SIZE: u32 = 4096;

/// Contiguous runs of vertices transformed in parallel, per worker thread.
const CHUNKS_PER_THREAD: usize = 4;

/// One mesh placed in the world.
#[derive(Debug, Clone)]
pub struct Instance {
    /// The geometry, shared between instances.
    pub mesh: Arc<MeshData>,
    /// Model-to-world matrix.
    pub model: Mat4,
    /// The surface it is drawn with.
    pub material: Material,
}

/// Switches that change how a frame is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RenderSettings {
    /// The lighting computation.
    pub shading: Shading,
    /// Whether the directional light casts shadows.
    pub shadows: bool,
    /// Whether shadow edges are filtered (bilinear percentage-closer filtering).
    pub pcf: bool,
    /// Shadow map side in texels: a multiple of [`TILE_HEIGHT`], at most [`MAX_TARGET_SIZE`].
    pub shadow_map_size: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self { shading: Shading::Gouraud, shadows: false, pcf: true, shadow_map_size: 1024 }
    }
}

/// Everything one frame is drawn from.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    /// The viewpoint.
    pub camera: Camera,
    /// The directional light.
    pub light: Light,
    /// Colour of pixels no triangle covers, as RGBA8.
    pub background: [u8; 4],
    /// What to draw, in order (earlier instances win depth ties).
    pub instances: &'a [Instance],
    /// Shading mode and shadows.
    pub settings: RenderSettings,
}

/// Counts from one frame, for the UI and for tests.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RenderStats {
    /// Triangles handed to the pipeline.
    pub triangles_submitted: usize,
    /// Triangles (after clipping) that survived culling and were drawn.
    pub triangles_rasterized: usize,
    /// Pixels covered by some rasterized triangle, counted once per triangle covering them
    /// (before the depth test).
    pub fragments: u64,
    /// Triangle-tile pairs skipped because the tile was already nearer everywhere.
    pub occluded: u64,
    /// Triangles (after clipping) drawn into the shadow map.
    pub shadow_triangles: usize,
}

/// A vertex projected to the screen: which planes it is outside of and (when it needs no
/// clipping) its fixed-point screen position, depth and `1/w`. The rare triangle that needs
/// clipping computes its clip positions again from the world positions.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct ScreenVertex {
    /// [`outside`] bits.
    pub code: u8,
    /// Screen x in sub-pixel units.
    pub x: i32,
    /// Screen y (downwards) in sub-pixel units.
    pub y: i32,
    /// Normalized device depth.
    pub z: f32,
    /// `1/w`.
    pub inv_w: f32,
}

impl ScreenVertex {
    /// Projects four clip-space positions onto a `width` x `height` target.
    #[inline(always)]
    fn lanes(clip: &ClipLanes, width: u32, height: u32) -> [Self; 4] {
        let codes = clip.outcodes();
        let projected = Self::project(clip, width, height);
        std::array::from_fn(|k| {
            let code = codes[k];
            let kept = if code & outside::CLIPPED == 0 { projected[k] } else { Self::default() };
            Self { code, ..kept }
        })
    }

    /// Projects a clip-space position known to be inside the near plane and the guard band
    /// (up to rounding).
    fn projected(clip: Vec4, width: u32, height: u32) -> Self {
        Self::project(&ClipLanes::splat(clip), width, height)[0]
    }

    /// Projects four clip-space positions, each inside the near plane and the guard band up
    /// to rounding.
    #[inline(always)]
    fn project(clip: &ClipLanes, width: u32, height: u32) -> [Self; 4] {
        let inv_w = Vec4::ONE / clip.w;
        let steps = SUBPIXEL_STEPS as f32;
        // The limits only guard against rounding past the guard band after clipping; `max`
        // comes first so that a position without a direction (on the eye point) lands on one.
        let limit = Vec4::splat(3.0 * MAX_TARGET_SIZE as f32 * steps);
        let fixed = |v: Vec4| floor_lanes(v.max(-limit).min(limit) + 0.5).to_array();
        let x = fixed((clip.x * inv_w + 1.0) * 0.5 * width as f32 * steps);
        let y = fixed((1.0 - clip.y * inv_w) * 0.5 * height as f32 * steps);
        let (z, inv_w) = ((clip.z * inv_w).max(Vec4::ZERO).to_array(), inv_w.to_array());
        std::array::from_fn(|k| Self { code: 0, x: x[k], y: y[k], z: z[k], inv_w: inv_w[k] })
    }
}

/// Where an instance's vertices and triangles start in the frame's global numbering, and its
/// transforms.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Span {
    pub first_vertex: usize,
    pub first_triangle: usize,
    model: Mat4,
    normal_matrix: Mat3,
}

/// A view triangles are drawn in: its projection, its projected vertices and its viewport.
#[derive(Clone, Copy)]
pub(crate) struct View<'a> {
    pub clip_from_world: Mat4,
    pub vertices: &'a [ScreenVertex],
    pub viewport: Viewport,
}

impl View<'_> {
    /// Clips the triangle of global vertices `indices` against the near plane and the guard
    /// band, and hands each triangle of the clipped polygon's fan, projected, to `draw` with
    /// its varyings.
    pub(crate) fn clip<'v>(
        &self,
        world: &[Vec3],
        indices: [usize; 3],
        varyings: impl Fn(usize) -> &'v Varyings,
        mut draw: impl FnMut([&ScreenVertex; 3], [&Varyings; 3]),
    ) {
        let clip = clip_triangle(&std::array::from_fn(|k| ClipVertex {
            position: self.clip_from_world * world[indices[k]].extend(1.0),
            varyings: *varyings(indices[k]),
        }));
        let polygon = clip.vertices();
        let (width, height) = (self.viewport.width, self.viewport.height);
        for i in 1..polygon.len().saturating_sub(1) {
            let fan = [polygon[0], polygon[i], polygon[i + 1]];
            let vertices = fan.map(|v| ScreenVertex::projected(v.position, width, height));
            draw(vertices.each_ref(), fan.each_ref().map(|v| &v.varyings));
        }
    }
}

/// The CPU rasterizer. Keeps its working buffers between frames so that drawing a scene of
/// steady size does not allocate.
#[derive(Debug, Default)]
pub struct Renderer {
    spans: Vec<Span>,
    world: Vec<Vec3>,
    vertices: Vec<ScreenVertex>,
    light_vertices: Vec<ScreenVertex>,
    varyings: Vec<Varyings>,
    /// The triangles reaching each band of the image.
    sorted: Sorted,
    bands: Vec<BandScratch>,
    band_schedule: Schedule,
    depth_pass: DepthPass,
    shadow: ShadowMap,
}

impl Renderer {
    /// Draws `frame` into `target` (cleared first), spreading the work over `pool`.
    ///
    /// # Panics
    /// If the target or the shadow map is larger than [`MAX_TARGET_SIZE`] on a side, or the
    /// shadow map size is not a positive multiple of [`TILE_HEIGHT`].
    pub fn render(&mut self, target: &mut Framebuffer, pool: &TaskPool, frame: &Frame) -> RenderStats {
        let (width, height) = (target.width(), target.height());
        let settings = frame.settings;
        assert!(
            width <= MAX_TARGET_SIZE && height <= MAX_TARGET_SIZE && settings.shadow_map_size <= MAX_TARGET_SIZE,
            "render targets are limited to {MAX_TARGET_SIZE} pixels a side"
        );
        assert!(
            settings.shadow_map_size > 0 && settings.shadow_map_size.is_multiple_of(TILE_HEIGHT),
            "the shadow map size must be a positive multiple of {TILE_HEIGHT}"
        );
        let mut stats = RenderStats {
            triangles_submitted: frame.instances.iter().map(|i| i.mesh.triangle_count()).sum(),
            ..RenderStats::default()
        };
        let aspect = width.max(1) as f32 / height.max(1) as f32;
        let light_clip = if settings.shadows && width > 0 && height > 0 {
            scene_bounds(frame.instances).and_then(|bounds| fit_light(&frame.camera, aspect, &frame.light, bounds))
        } else {
            None
        };
        self.shadow.reset(settings.shadow_map_size, light_clip, settings.pcf);

        let view_projection = frame.camera.view_projection(aspect);
        self.vertex_stage(pool, frame, view_projection, width, height, light_clip);
        let view = View {
            clip_from_world: view_projection,
            vertices: &self.vertices,
            viewport: Viewport { width, height, cull_back_faces: true },
        };
        let light_view = light_clip.map(|clip_from_world| View {
            clip_from_world,
            vertices: &self.light_vertices,
            viewport: Viewport {
                width: settings.shadow_map_size,
                height: settings.shadow_map_size,
                cull_back_faces: false,
            },
        });
        // The image's and the shadow map's triangles are sorted in one pass over them.
        let light_sorting = light_view.map(|view| (&mut self.depth_pass.sorted, view));
        Sorted::sort_for::<TILE_HEIGHT, STRIP_ROWS>(
            pool,
            &self.spans,
            frame.instances,
            (&mut self.sorted, view),
            light_sorting,
        );
        if let Some(view) = light_view {
            let scene = DepthScene { world: &self.world, view };
            stats.shadow_triangles = self.depth_pass.draw(pool, scene, &mut self.shadow);
        }
        let shadow = self.shadow.is_active().then(|| BandShadow {
            map: &self.shadow,
            pixels: PixelsInMap::new(&self.shadow, view_projection, width, height),
            light: frame.light,
            filtered: settings.pcf,
        });
        let context = TileContext {
            frame,
            spans: &self.spans,
            world: &self.world,
            varyings: &self.varyings,
            view,
            sorted: &self.sorted,
            shadow,
        };
        self.bands.resize_with(height.div_ceil(TILE_HEIGHT) as usize, BandScratch::default);
        let bands = target.bands_mut(TILE_HEIGHT).zip(&mut self.bands);
        let draw = |row: usize, (band, scratch)| tile::draw_band(&context, row as u32, band, scratch);
        let counts = self.band_schedule.run(pool, bands, draw, BandCounts::add);
        RenderStats {
            fragments: counts.fragments,
            occluded: counts.occluded,
            triangles_rasterized: counts.triangles,
            ..stats
        }
    }

    /// The shadow map of the last frame.
    pub fn shadow_map(&self) -> &ShadowMap {
        &self.shadow
    }

    /// Transforms, lights and projects every vertex, in parallel runs.
    fn vertex_stage(
        &mut self,
        pool: &TaskPool,
        frame: &Frame,
        view_projection: Mat4,
        width: u32,
        height: u32,
        light_clip: Option<Mat4>,
    ) {
        self.spans.clear();
        let (mut vertices, mut triangles) = (0, 0);
        for instance in frame.instances {
            self.spans.push(Span {
                first_vertex: vertices,
                first_triangle: triangles,
                model: instance.model,
                normal_matrix: Mat3::from_mat4(instance.model).inverse().transpose(),
            });
            vertices += instance.mesh.positions.len();
            triangles += instance.mesh.triangle_count();
        }
        self.world.resize(vertices, Vec3::ZERO);
        self.vertices.resize(vertices, ScreenVertex::default());
        self.varyings.resize(vertices, [0.0; VARYINGS]);
        self.light_vertices.resize(if light_clip.is_some() { vertices } else { 0 }, ScreenVertex::default());

        let threads = pool.thread_num().max(1);
        let run = vertices.div_ceil(threads * CHUNKS_PER_THREAD).max(1024);
        let lit = frame.settings.shading == Shading::Gouraud;
        let stage = VertexStage {
            frame,
            spans: &self.spans,
            view_projection,
            width,
            height,
            light: light_clip.map(|clip| (clip, frame.settings.shadow_map_size)),
            lit,
        };
        let mut light_runs = self.light_vertices.chunks_mut(run);
        pool.scope(|scope| {
            let runs = self.world.chunks_mut(run).zip(self.vertices.chunks_mut(run)).zip(self.varyings.chunks_mut(run));
            for (index, ((world, screen), varyings)) in runs.enumerate() {
                let outputs = VertexOutputs { world, screen, varyings, light: light_runs.next().unwrap_or_default() };
                let stage = &stage;
                scope.spawn(async move { stage.run(index * run, outputs) });
            }
        });
    }
}

/// What the vertex stage reads: the frame, where each instance's vertices start and the
/// projections they go through.
struct VertexStage<'a> {
    frame: &'a Frame<'a>,
    spans: &'a [Span],
    view_projection: Mat4,
    width: u32,
    height: u32,
    /// The shadow map's projection and side in texels, when shadows are drawn.
    light: Option<(Mat4, u32)>,
    /// Whether the vertex colours are lit (Gouraud shading).
    lit: bool,
}

/// One run of the vertex stage's outputs, from the same first vertex on.
struct VertexOutputs<'a> {
    world: &'a mut [Vec3],
    screen: &'a mut [ScreenVertex],
    varyings: &'a mut [Varyings],
    /// Empty when shadows are off.
    light: &'a mut [ScreenVertex],
}

impl VertexStage<'_> {
    /// Transforms, lights and projects the run of vertices from global index `first` on,
    /// instance by instance.
    fn run(&self, first: usize, out: VertexOutputs) {
        let mut span_index = self.spans.partition_point(|s| s.first_vertex <= first).saturating_sub(1);
        let mut done = 0;
        while done < out.world.len() {
            let span = &self.spans[span_index];
            let instance = &self.frame.instances[span_index];
            let local = first + done - span.first_vertex;
            let count = (instance.mesh.positions.len() - local).min(out.world.len() - done);
            let outputs = VertexOutputs {
                world: &mut out.world[done..done + count],
                screen: &mut out.screen[done..done + count],
                varyings: &mut out.varyings[done..done + count],
                light: if out.light.is_empty() { &mut [] } else { &mut out.light[done..done + count] },
            };
            self.instance_run(span, instance, local, outputs);
            done += count;
            span_index += 1;
        }
    }

    /// The vertices of one instance from its vertex `local` on, as many as `out` holds, four
    /// at a time.
    fn instance_run(&self, span: &Span, instance: &Instance, local: usize, out: VertexOutputs) {
        let mesh = &instance.mesh;
        let count = out.world.len();
        let normal_matrix = Mat4::from_mat3(span.normal_matrix);
        let (positions, normals) = (&mesh.positions[local..local + count], &mesh.normals[local..local + count]);
        for group in (0..count).step_by(VERTEX_LANES) {
            let lanes = group..(group + VERTEX_LANES).min(count);
            let position = gather(&positions[lanes.clone()]);
            let world = ClipLanes::transform(span.model, position);
            // Projected from the world positions, exactly as clipping projects them again.
            let world = [world.x, world.y, world.z];
            let screen =
                ScreenVertex::lanes(&ClipLanes::transform(self.view_projection, world), self.width, self.height);
            let normal = normalize_or_zero(ClipLanes::transform(normal_matrix, gather(&normals[lanes.clone()])));
            let diffuse = self.frame.light.diffuse_lanes(normal);
            let light = self
                .light
                .map(|(light_clip, size)| ScreenVertex::lanes(&ClipLanes::transform(light_clip, world), size, size));
            let (world, normal, diffuse) = (columns(world), columns(normal), diffuse.to_array());
            for (k, i) in lanes.enumerate() {
                out.world[i] = Vec3::from_array(world[k]);
                out.screen[i] = screen[k];
                let normal = Vec3::from_array(normal[k]);
                out.varyings[i] = vertex_varyings(instance, local + i, normal, diffuse[k], &self.frame.light, self.lit);
                if let Some(vertices) = &light {
                    out.light[i] = vertices[k];
                }
            }
        }
    }
}

/// Vertices the vertex stage works on at once.
const VERTEX_LANES: usize = 4;

/// Up to [`VERTEX_LANES`] points as lanes of their coordinates; lanes past the points repeat
/// the last one.
#[inline(always)]
fn gather(points: &[Vec3]) -> [Vec4; 3] {
    let at = |k: usize| points[k.min(points.len() - 1)];
    let [a, b, c, d] = [at(0), at(1), at(2), at(3)];
    [Vec4::new(a.x, b.x, c.x, d.x), Vec4::new(a.y, b.y, c.y, d.y), Vec4::new(a.z, b.z, c.z, d.z)]
}

/// Lanes back to the [`VERTEX_LANES`] vectors they hold: entry `k` has lane `k` of each
/// component.
#[inline(always)]
fn columns<const N: usize>(components: [Vec4; N]) -> [[f32; N]; VERTEX_LANES] {
    let components = components.map(|c| c.to_array());
    std::array::from_fn(|k| components.map(|c| c[k]))
}

/// Each lane's vector scaled to unit length, or zero where that is not possible.
#[inline(always)]
fn normalize_or_zero(v: ClipLanes) -> [Vec4; 3] {
    let scale = Vec4::ONE / (v.x * v.x + v.y * v.y + v.z * v.z).sqrt();
    let valid = scale.is_finite_mask() & scale.cmpgt(Vec4::ZERO);
    [v.x, v.y, v.z].map(|c| Vec4::select(valid, c * scale, Vec4::ZERO))
}

/// The varyings of one vertex.
///
/// When `lit` the colour is lit as if the light reached the vertex (Gouraud: nothing is left
/// to light per pixel but shadows).
#[inline(always)]
fn vertex_varyings(
    instance: &Instance,
    local: usize,
    normal: Vec3,
    diffuse: f32,
    light: &Light,
    lit: bool,
) -> Varyings {
    let material = &instance.material;
    let mesh = &instance.mesh;
    let mut color = material.color * mesh.colors.get(local).copied().unwrap_or(Vec3::ONE);
    if lit {
        color *= light.combine(diffuse, 1.0);
    }
    let uv = mesh.uvs.get(local).copied().unwrap_or(Vec2::ZERO) * material.uv_scale;
    let mut varyings = [0.0; VARYINGS];
    varyings[slot::COLOR..slot::COLOR + 3].copy_from_slice(&color.to_array());
    varyings[slot::DIFFUSE] = diffuse;
    varyings[slot::NORMAL..slot::NORMAL + 3].copy_from_slice(&normal.to_array());
    varyings[slot::UV..slot::UV + 2].copy_from_slice(&uv.to_array());
    varyings
}

/// The diffuse term of a triangle's geometric normal, for flat shading.
pub(crate) fn flat_diffuse(corners: [Vec3; 3], light: &Light) -> f32 {
    let [a, b, c] = corners;
    light.diffuse_term((b - a).cross(c - a).normalize_or_zero())
}

/// World bounds of everything drawn, from each instance's transformed model bounds.
fn scene_bounds(instances: &[Instance]) -> Option<(Vec3, Vec3)> {
    instances
        .iter()
        .filter_map(|instance| {
            let (min, max) = instance.mesh.bounds()?;
            let centre = instance.model.transform_point3((min + max) * 0.5);
            let half = (max - min) * 0.5;
            let m = Mat3::from_mat4(instance.model);
            // The transformed box's half extent along each world axis.
            let extent = Vec3::new(m.row(0).abs().dot(half), m.row(1).abs().dot(half), m.row(2).abs().dot(half));
            Some((centre - extent, centre + extent))
        })
        .reduce(|(a_min, a_max), (b_min, b_max)| (a_min.min(b_min), a_max.max(b_max)))
}

/// The triangles of all `instances`, whose spans are `spans`.
pub(crate) fn triangle_count(spans: &[Span], instances: &[Instance]) -> usize {
    spans.last().zip(instances.last()).map_or(0, |(s, i)| s.first_triangle + i.mesh.triangle_count())
}

/// Splits `0..total` into at most `parts` contiguous, nearly equal runs.
pub(crate) fn runs(total: usize, parts: usize) -> impl Iterator<Item = Range<usize>> {
    let size = total.div_ceil(parts.max(1)).max(1);
    (0..total).step_by(size).map(move |start| start..(start + size).min(total))
}

/// The instances the global triangles `range` belong to, each with the part of `range` among
/// its triangles, in order.
pub(crate) fn instance_runs<'a>(
    spans: &'a [Span],
    instances: &'a [Instance],
    range: Range<usize>,
) -> impl Iterator<Item = InstanceRun<'a>> {
    let first = spans.partition_point(|s| s.first_triangle <= range.start).saturating_sub(1);
    spans.iter().zip(instances).skip(first).map_while(move |(span, instance)| {
        let start = range.start.max(span.first_triangle);
        let end = range.end.min(span.first_triangle + instance.mesh.triangle_count());
        (start < range.end).then(|| InstanceRun {
            span,
            instance,
            triangles: start - span.first_triangle..end - span.first_triangle,
        })
    })
}

/// Some of the triangles of one instance.
pub(crate) struct InstanceRun<'a> {
    pub span: &'a Span,
    pub instance: &'a Instance,
    /// Which of its triangles.
    pub triangles: Range<usize>,
}

/// Inclusive pixel bounds of a triangle, within its target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PixelBounds {
    pub min_x: u32,
    pub max_x: u32,
    pub min_y: u32,
    pub max_y: u32,
}

/// Twice the signed area of the triangle `a b p` in sub-pixel units squared; positive when `p`
/// lies to the right of `a -> b` on a y-down screen.
#[inline(always)]
pub(crate) fn edge(a: (i64, i64), b: (i64, i64), p: (i64, i64)) -> i64 {
    (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
}

/// The least and the greatest of three coordinates.
#[inline(always)]
pub(crate) fn range_of([a, b, c]: [i64; 3]) -> (i64, i64) {
    (a.min(b).min(c), a.max(b).max(c))
}

/// The first and last of `size` pixel columns (or rows) whose centres lie between `least` and
/// `greatest` (sub-pixel units); `None` when there is none.
#[inline(always)]
pub(crate) fn pixel_span((least, greatest): (i64, i64), size: u32) -> Option<(u32, u32)> {
    // Pixel p is sampled at its centre, p + 1/2.
    let half = SUBPIXEL_STEPS / 2;
    let first = (least - half + SUBPIXEL_STEPS - 1).div_euclid(SUBPIXEL_STEPS).max(0);
    let last = (greatest - half).div_euclid(SUBPIXEL_STEPS).min(i64::from(size) - 1);
    (first <= last).then_some((first as u32, last as u32))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::FRAC_PI_2;

    const SKY: [u8; 4] = [10, 20, 30, 255];

    fn camera_at(eye: Vec3, target: Vec3) -> Camera {
        Camera { eye, target, fov_y: FRAC_PI_2, near: 0.1, far: 100.0 }
    }

    fn full_light() -> Light {
        Light { direction: Vec3::NEG_Z, diffuse: 1.0, fill: 0.0, ambient: 1.0 }
    }

    /// A light from high above, slightly to the side, with an ambient floor.
    fn high_light() -> Light {
        Light { direction: Vec3::new(0.2, -1.0, 0.1).normalize(), diffuse: 0.8, fill: 0.0, ambient: 0.2 }
    }

    fn draw(camera: Camera, instances: &[Instance], size: (u32, u32)) -> (Framebuffer, RenderStats) {
        let mut target = Framebuffer::new(size.0, size.1);
        let frame =
            Frame { camera, light: full_light(), background: SKY, instances, settings: RenderSettings::default() };
        let stats = Renderer::default().render(&mut target, &TaskPool::new(), &frame);
        (target, stats)
    }

    fn instance(mesh: MeshData, model: Mat4, color: Vec3) -> Instance {
        Instance { mesh: Arc::new(mesh), model, material: Material::colored(color) }
    }

    /// A triangle fan over the square [-2, 2]^2 at z = 0 around an off-grid centre, facing +z.
    fn fan(centre: Vec3, rim_points: usize) -> MeshData {
        let mut mesh = MeshData { positions: vec![centre], normals: vec![Vec3::Z], ..MeshData::default() };
        for i in 0..rim_points {
            let angle = std::f32::consts::TAU * i as f32 / rim_points as f32 + 0.1;
            let rim = Vec3::new(angle.cos(), angle.sin(), 0.0);
            mesh.positions.push(rim * 2.0 / rim.x.abs().max(rim.y.abs()));
            mesh.normals.push(Vec3::Z);
        }
        for i in 0..rim_points as u32 {
            mesh.triangles.push([0, 1 + i, 1 + (i + 1) % rim_points as u32]);
        }
        mesh
    }

    #[test]
    fn projected_vertices_are_those_clipping_computes_from_world_positions() {
        // A triangle that needs clipping projects its kept corners again from their world
        // positions; a neighbour that needs none reads the vertex stage's projection. Both
        // must give the same sub-pixel position, or the edge they share could crack.
        let model = Mat4::from_scale_rotation_translation(
            Vec3::new(1.3, 0.7, 1.1),
            bevy_math::Quat::from_euler(bevy_math::EulerRot::XYZ, 0.4, -0.9, 0.3),
            Vec3::new(0.17, -0.23, 0.31),
        );
        let sphere = instance(MeshData::sphere(24, 48), model, Vec3::ONE);
        let camera = camera_at(Vec3::new(0.3, 0.4, 2.7), Vec3::new(0.05, 0.0, 0.0));
        let frame = Frame {
            camera,
            light: full_light(),
            background: SKY,
            instances: &[sphere],
            settings: RenderSettings { shadows: true, ..RenderSettings::default() },
        };
        let (width, height) = (97, 61);
        let mut renderer = Renderer::default();
        renderer.render(&mut Framebuffer::new(width, height), &TaskPool::new(), &frame);
        let view_projection = camera.view_projection(width as f32 / height as f32);
        let light_clip = renderer.shadow_map().clip_from_world();
        let size = frame.settings.shadow_map_size;
        let views =
            [(&renderer.vertices, view_projection, width, height), (&renderer.light_vertices, light_clip, size, size)];
        for (vertices, clip_from_world, width, height) in views {
            for (vertex, world) in vertices.iter().zip(&renderer.world).filter(|(v, _)| v.code & outside::CLIPPED == 0)
            {
                let expected = ScreenVertex::projected(clip_from_world * world.extend(1.0), width, height);
                assert_eq!(
                    (vertex.x, vertex.y, vertex.z, vertex.inv_w),
                    (expected.x, expected.y, expected.z, expected.inv_w)
                );
            }
        }
    }

    #[test]
    fn shared_edges_cover_every_pixel_exactly_once() {
        // The camera sees exactly [-1, 1]^2 at z = 0; the fan covers more, so every pixel
        // must be produced once: a gap would lower the count, a double pixel would raise it.
        for (centre, size) in
            [(Vec3::ZERO, (64, 64)), (Vec3::new(0.123, -0.377, 0.0), (97, 61)), (Vec3::new(-0.5, 0.25, 0.0), (40, 40))]
        {
            let camera = camera_at(Vec3::Z, Vec3::ZERO);
            let mesh = fan(centre, 37);
            let (target, stats) = draw(camera, &[instance(mesh, Mat4::IDENTITY, Vec3::ONE)], size);
            assert_eq!(stats.fragments, size.0 as u64 * size.1 as u64, "centre {centre}");
            // Every pixel is stored too, up to the last of each band (where a run of pixels
            // reaches past the band's end when the width is not a multiple of the run).
            let background = target.color().chunks_exact(4).filter(|pixel| *pixel == SKY).count();
            assert_eq!(background, 0, "centre {centre}");
        }
    }

    #[test]
    fn a_red_cube_in_front_of_the_camera_is_red_at_the_centre() {
        let cube = instance(MeshData::cube(), Mat4::IDENTITY, Vec3::X);
        let (fb, stats) = draw(camera_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO), &[cube], (80, 60));
        assert_eq!(fb.pixel(40, 30), [255, 0, 0, 255]);
        for (x, y) in [(0, 0), (79, 0), (0, 59), (79, 59)] {
            assert_eq!(fb.pixel(x, y), SKY);
        }
        assert_eq!(stats.triangles_submitted, 12);
        // Only the front face survives back-face culling.
        assert_eq!(stats.triangles_rasterized, 2);
    }

    #[test]
    fn the_nearer_surface_wins_regardless_of_draw_order() {
        let near = instance(MeshData::cube(), Mat4::from_translation(Vec3::new(0.0, 0.0, 1.0)), Vec3::Y);
        let far = instance(MeshData::cube(), Mat4::from_scale(Vec3::splat(1.5)), Vec3::X);
        let camera = camera_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO);
        for order in [[near.clone(), far.clone()], [far, near]] {
            let (fb, _) = draw(camera, &order, (64, 64));
            assert_eq!(fb.pixel(32, 32), [0, 255, 0, 255]);
        }
    }

    #[test]
    fn a_floor_crossing_the_near_plane_is_clipped_not_dropped() {
        // A huge floor under the camera reaches behind the eye; its near part must still
        // cover the bottom of the image.
        let floor = instance(MeshData::plane(1), Mat4::from_scale(Vec3::splat(50.0)), Vec3::ONE);
        let camera = camera_at(Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.8, -1.0));
        let (fb, _) = draw(camera, &[floor], (64, 64));
        for x in [0, 32, 63] {
            assert_eq!(fb.pixel(x, 63), [255, 255, 255, 255]);
        }
        assert_eq!(fb.pixel(32, 0), SKY);
    }

    #[test]
    fn gouraud_shading_follows_the_light() {
        let light = Light { direction: Vec3::NEG_X, diffuse: 1.0, fill: 0.0, ambient: 0.1 };
        let sphere = instance(MeshData::sphere(24, 48), Mat4::IDENTITY, Vec3::ONE);
        let mut fb = Framebuffer::new(64, 64);
        let frame = Frame {
            camera: camera_at(Vec3::new(0.0, 0.0, 0.9), Vec3::ZERO),
            light,
            background: SKY,
            instances: &[sphere],
            settings: RenderSettings::default(),
        };
        Renderer::default().render(&mut fb, &TaskPool::new(), &frame);
        // Lit from +x: the right side is bright, the left half at the ambient floor.
        let right = fb.pixel(48, 32)[0];
        let centre = fb.pixel(32, 32)[0];
        let left = fb.pixel(16, 32)[0];
        assert!(right > centre + 50 && centre >= left, "{left} {centre} {right}");
        assert!(left.abs_diff(26) <= 1, "ambient floor 0.1 gives 26, got {left}");
    }

    #[test]
    fn shadows_darken_only_drawn_pixels_and_leave_them_opaque() {
        // A sphere over a floor, in an image whose rows do not split into whole runs.
        let sphere = instance(MeshData::sphere(16, 32), Mat4::from_translation(Vec3::Y * 0.6), Vec3::ONE);
        let floor = instance(MeshData::plane(4), Mat4::from_scale(Vec3::splat(3.0)), Vec3::ONE);
        let instances = [sphere, floor];
        let light = high_light();
        let camera = camera_at(Vec3::new(0.0, 2.0, 3.0), Vec3::ZERO);
        let render = |shadows: bool| {
            let mut target = Framebuffer::new(97, 61);
            let settings = RenderSettings { shadows, ..RenderSettings::default() };
            let frame = Frame { camera, light, background: [10, 20, 30, 40], instances: &instances, settings };
            Renderer::default().render(&mut target, &TaskPool::new(), &frame);
            target
        };
        let (lit, shadowed) = (render(false), render(true));
        assert_eq!(lit.depth(), shadowed.depth());
        let pixels = |image: &Framebuffer| image.color().chunks_exact(4).map(|p| [p[0], p[1], p[2], p[3]]).collect();
        let (lit, shadowed): (Vec<[u8; 4]>, Vec<[u8; 4]>) = (pixels(&lit), pixels(&shadowed));
        let mut darker = 0;
        for (a, b) in lit.iter().zip(&shadowed) {
            if *a == [10, 20, 30, 40] {
                assert_eq!(a, b, "the background is left as it is");
                continue;
            }
            assert_eq!(b[3], 255, "drawn pixels are opaque");
            assert!(b[..3].iter().zip(&a[..3]).all(|(s, l)| s <= l), "shadows only darken: {a:?} {b:?}");
            darker += usize::from(b != a);
        }
        // The sphere's shadow on the floor, under it.
        assert!(darker > 20, "{darker} pixels in shadow");
    }

    #[test]
    fn targets_smaller_than_a_run_are_drawn_with_and_without_shadows() {
        // Every run of these reaches past the end of its band.
        let floor = instance(MeshData::plane(2), Mat4::from_scale(Vec3::splat(20.0)), Vec3::ONE);
        let camera = camera_at(Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.0, -1.0));
        let light = high_light();
        for (size, shadows) in [((1, 1), false), ((1, 1), true), ((3, 2), true), ((5, 1), true)] {
            let mut target = Framebuffer::new(size.0, size.1);
            let settings = RenderSettings { shadows, ..RenderSettings::default() };
            let frame = Frame { camera, light, background: SKY, instances: std::slice::from_ref(&floor), settings };
            Renderer::default().render(&mut target, &TaskPool::new(), &frame);
            for pixel in target.color().chunks_exact(4) {
                assert!(pixel != SKY && pixel[3] == 255, "{size:?} {shadows}: {pixel:?}");
            }
        }
    }

    #[test]
    fn rendering_is_deterministic_and_reuses_buffers() {
        let sphere = instance(MeshData::sphere(16, 32), Mat4::IDENTITY, Vec3::new(0.3, 0.6, 0.9));
        let frame = Frame {
            camera: camera_at(Vec3::new(0.4, 0.3, 1.2), Vec3::ZERO),
            light: Light { direction: Vec3::new(0.3, -1.0, -0.2).normalize(), diffuse: 0.8, fill: 0.0, ambient: 0.2 },
            background: SKY,
            instances: &[sphere],
            settings: RenderSettings { shadows: true, ..RenderSettings::default() },
        };
        let pool = TaskPool::new();
        let mut renderer = Renderer::default();
        let (mut a, mut b) = (Framebuffer::new(100, 70), Framebuffer::new(100, 70));
        let first = renderer.render(&mut a, &pool, &frame);
        let second = renderer.render(&mut b, &pool, &frame);
        assert_eq!(first, second);
        assert_eq!(a.color(), b.color());
        assert_eq!(a.depth(), b.depth());
    }

    #[test]
    fn one_sorting_pass_for_the_image_and_the_shadow_map_sorts_each_as_alone() {
        use crate::sort::Corners;
        use crate::standard;
        let pool = TaskPool::new();
        let instances = [standard::instance()];
        let settings = RenderSettings { shadows: true, ..RenderSettings::default() };
        let frame = standard::frame(&standard::CAMERAS[1], &instances, settings);
        let (width, height, map) = (standard::WIDTH, standard::HEIGHT, settings.shadow_map_size);
        // A frame drawn leaves the vertices as the camera and the light see them.
        let mut renderer = Renderer::default();
        renderer.render(&mut Framebuffer::new(width, height), &pool, &frame);
        // Sorting reads only the projected vertices and the viewport.
        let view = |vertices, width, height, cull_back_faces| View {
            clip_from_world: Mat4::IDENTITY,
            vertices,
            viewport: Viewport { width, height, cull_back_faces },
        };
        let image_view = view(&renderer.vertices, width, height, true);
        let light_view = view(&renderer.light_vertices, map, map, false);
        let spans = &renderer.spans;
        let [mut image, mut light, mut image_alone, mut light_alone] = std::array::from_fn(|_| Sorted::default());
        Sorted::sort_for::<64, 32>(&pool, spans, &instances, (&mut image, image_view), Some((&mut light, light_view)));
        Sorted::sort_for::<64, 64>(&pool, spans, &instances, (&mut image_alone, image_view), None);
        Sorted::sort_for::<32, 32>(&pool, spans, &instances, (&mut light_alone, light_view), None);
        let strips = |sorted: &Sorted, count: u32| -> Vec<Vec<Corners>> {
            (0..count as usize).map(|strip| sorted.strip(strip).copied().collect()).collect()
        };
        let (image_strips, light_strips) = (height.div_ceil(64), map.div_ceil(32));
        assert_eq!(strips(&image, image_strips), strips(&image_alone, image_strips));
        assert_eq!(strips(&light, light_strips), strips(&light_alone, light_strips));
        assert!(strips(&light, light_strips).iter().all(|strip| !strip.is_empty()), "the light sees the whole grid");
    }
}
