//! The frame pipeline: vertex lighting, culling and clipping, triangle setup, binning into
//! horizontal bands, and parallel rasterization of the bands with a z-buffer.
//!
//! Coverage uses exact integer edge functions on screen coordinates snapped to
//! 1/[`SUBPIXEL_STEPS`] of a pixel, sampled at pixel centres, with the top-left fill rule: a
//! pixel whose centre lies on an edge shared by two triangles is drawn by exactly one of them.
//! Colours and depths are interpolated with barycentric weights from the same edge functions;
//! colours perspective-correctly (`c/w` and `1/w` interpolated, divided per pixel), depth
//! linearly in screen space as the projection demands.

use super::camera::{Camera, Light};
use super::clip::{ClipVertex, clip_triangle, needs_clipping, outside_view};
use super::framebuffer::{Band, FAR_DEPTH, Framebuffer};
use super::mesh::MeshData;
use bevy::math::{Mat3, Mat4, Vec3};
use bevy::tasks::TaskPool;
use std::sync::Arc;

/// Rows in one band, the unit of parallel work.
pub const BAND_ROWS: u32 = 16;

/// Sub-pixel positions per pixel along each axis (8 bits of sub-pixel precision).
pub const SUBPIXEL_STEPS: i64 = 256;

/// One mesh placed in the world.
#[derive(Debug, Clone)]
pub struct Instance {
    /// The geometry, shared between instances.
    pub mesh: Arc<MeshData>,
    /// Model-to-world matrix.
    pub model: Mat4,
    /// Surface colour, RGB in `[0, 1]`, multiplied by the light intensity.
    pub color: Vec3,
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
}

/// Counts from one frame, for the UI and for tests.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RenderStats {
    /// Triangles handed to the pipeline.
    pub triangles_submitted: usize,
    /// Triangles (after clipping) that survived culling and were rasterized.
    pub triangles_rasterized: usize,
    /// Pixels covered by some rasterized triangle, counted once per triangle covering them
    /// (before the depth test).
    pub fragments: u64,
}

/// A triangle ready for rasterization: fixed-point screen vertices with a positive signed
/// area and its interpolants.
#[derive(Debug, Clone, Copy)]
struct SetupTriangle {
    /// Screen x of the vertices in sub-pixel units.
    x: [i64; 3],
    /// Screen y (downwards) of the vertices in sub-pixel units.
    y: [i64; 3],
    /// Normalized device depth of the vertices.
    z: [f32; 3],
    /// `1/w` of the vertices.
    inv_w: [f32; 3],
    /// Colour divided by `w` at the vertices.
    color_over_w: [Vec3; 3],
    /// `1 / (2 * area)` in sub-pixel units squared.
    inv_area: f32,
    /// Inclusive pixel bounds, clipped to the framebuffer.
    min_x: u32,
    max_x: u32,
    min_y: u32,
    max_y: u32,
}

/// The CPU rasterizer. Keeps its working buffers between frames so that drawing a scene of
/// steady size does not allocate.
#[derive(Debug, Default)]
pub struct Renderer {
    vertices: Vec<ClipVertex>,
    triangles: Vec<SetupTriangle>,
    bins: Vec<Vec<u32>>,
}

impl Renderer {
    /// Draws `frame` into `target` (cleared first), spreading the bands over `pool`.
    pub fn render(&mut self, target: &mut Framebuffer, pool: &TaskPool, frame: &Frame) -> RenderStats {
        let (width, height) = (target.width(), target.height());
        let mut stats = RenderStats::default();
        self.triangles.clear();
        if width > 0 && height > 0 {
            let view_projection = frame.camera.view_projection(width as f32 / height as f32);
            for instance in frame.instances {
                stats.triangles_submitted += instance.mesh.triangle_count();
                self.add_instance(instance, view_projection, &frame.light, width, height);
            }
        }
        stats.triangles_rasterized = self.triangles.len();
        self.bin(height);

        let (triangles, bins, background) = (&self.triangles, &self.bins, frame.background);
        let fragments = pool.scope(|scope| {
            for (band, bin) in target.bands_mut(BAND_ROWS).zip(bins) {
                scope.spawn(async move { rasterize_band(band, bin, triangles, background) });
            }
        });
        stats.fragments = fragments.iter().sum();
        stats
    }

    /// Runs the vertex stage for one instance and sets up its visible triangles.
    fn add_instance(&mut self, instance: &Instance, view_projection: Mat4, light: &Light, width: u32, height: u32) {
        let clip_from_model = view_projection * instance.model;
        let normal_matrix = Mat3::from_mat4(instance.model).inverse().transpose();
        let mesh = &instance.mesh;
        self.vertices.clear();
        self.vertices.extend(mesh.positions.iter().zip(&mesh.normals).map(|(&p, &n)| {
            let normal = (normal_matrix * n).normalize_or_zero();
            ClipVertex { position: clip_from_model * p.extend(1.0), color: instance.color * light.intensity(normal) }
        }));
        for &[a, b, c] in &mesh.triangles {
            let triangle = [a, b, c].map(|i| self.vertices[i as usize]);
            if outside_view(&triangle) {
                continue;
            }
            if needs_clipping(&triangle) {
                let polygon = clip_triangle(&triangle);
                let vertices = polygon.vertices();
                for i in 1..vertices.len().saturating_sub(1) {
                    let fan = [vertices[0], vertices[i], vertices[i + 1]];
                    self.triangles.extend(setup(&fan, width, height));
                }
            } else {
                self.triangles.extend(setup(&triangle, width, height));
            }
        }
    }

    /// Sorts the set-up triangles into the bands their bounds touch, keeping their order.
    fn bin(&mut self, height: u32) {
        let bands = height.div_ceil(BAND_ROWS) as usize;
        self.bins.resize_with(bands, Vec::new);
        self.bins.iter_mut().for_each(Vec::clear);
        for (index, triangle) in self.triangles.iter().enumerate() {
            for band in triangle.min_y / BAND_ROWS..=triangle.max_y / BAND_ROWS {
                self.bins[band as usize].push(index as u32);
            }
        }
    }
}

/// Twice the signed area of the triangle `a b p`; positive when `p` lies to the right of
/// `a -> b` on a y-down screen.
fn edge(ax: i64, ay: i64, bx: i64, by: i64, px: i64, py: i64) -> i64 {
    (bx - ax) * (py - ay) - (by - ay) * (px - ax)
}

/// Whether the edge `a -> b` of a positive-area triangle is a top or a left edge, whose
/// pixels are drawn (the top-left fill rule).
fn is_top_left(ax: i64, ay: i64, bx: i64, by: i64) -> bool {
    (ay == by && bx > ax) || by < ay
}

/// Projects a clipped triangle to the screen, culls back faces and empty triangles, and
/// computes its interpolants.
fn setup(triangle: &[ClipVertex; 3], width: u32, height: u32) -> Option<SetupTriangle> {
    let mut x = [0i64; 3];
    let mut y = [0i64; 3];
    let mut z = [0f32; 3];
    let mut inv_w = [0f32; 3];
    let mut color_over_w = [Vec3::ZERO; 3];
    let steps = SUBPIXEL_STEPS as f32;
    for (i, vertex) in triangle.iter().enumerate() {
        let w = 1.0 / vertex.position.w;
        let ndc = vertex.position.truncate() * w;
        x[i] = ((ndc.x + 1.0) * 0.5 * width as f32 * steps).round() as i64;
        y[i] = ((1.0 - ndc.y) * 0.5 * height as f32 * steps).round() as i64;
        z[i] = ndc.z;
        inv_w[i] = w;
        color_over_w[i] = vertex.color * w;
    }
    // Front faces wind counter-clockwise in NDC (y up), hence clockwise and negative on the
    // y-down screen; swapping two vertices makes the area positive for the rasterizer.
    let area = edge(x[0], y[0], x[1], y[1], x[2], y[2]);
    if area >= 0 {
        return None;
    }
    x.swap(1, 2);
    y.swap(1, 2);
    z.swap(1, 2);
    inv_w.swap(1, 2);
    color_over_w.swap(1, 2);

    // Pixel (px, py) is sampled at its centre, (px + 1/2, py + 1/2).
    let half = SUBPIXEL_STEPS / 2;
    let first = |v: i64| (v - half + SUBPIXEL_STEPS - 1).div_euclid(SUBPIXEL_STEPS);
    let last = |v: i64| (v - half).div_euclid(SUBPIXEL_STEPS);
    let min_x = first(*x.iter().min()?).max(0);
    let max_x = last(*x.iter().max()?).min(width as i64 - 1);
    let min_y = first(*y.iter().min()?).max(0);
    let max_y = last(*y.iter().max()?).min(height as i64 - 1);
    if min_x > max_x || min_y > max_y {
        return None;
    }
    Some(SetupTriangle {
        x,
        y,
        z,
        inv_w,
        color_over_w,
        inv_area: 1.0 / (-area) as f32,
        min_x: min_x as u32,
        max_x: max_x as u32,
        min_y: min_y as u32,
        max_y: max_y as u32,
    })
}

/// Clears one band and draws the triangles binned into it; returns the fragments covered.
fn rasterize_band(band: Band, bin: &[u32], triangles: &[SetupTriangle], background: [u8; 4]) -> u64 {
    for pixel in band.color.chunks_exact_mut(4) {
        pixel.copy_from_slice(&background);
    }
    band.depth.fill(FAR_DEPTH);
    let rows = band.rows();
    let mut fragments = 0;
    for &index in bin {
        let t = &triangles[index as usize];
        let y_start = t.min_y.max(band.y0);
        let y_end = t.max_y.min(band.y0 + rows - 1);
        // Edge i is the one opposite vertex i; its function weighs vertex i.
        let edges = [(1, 2), (2, 0), (0, 1)].map(|(a, b)| {
            let bias = if is_top_left(t.x[a], t.y[a], t.x[b], t.y[b]) { 0 } else { -1 };
            (a, b, bias)
        });
        let step_x = edges.map(|(a, b, _)| (t.y[a] - t.y[b]) * SUBPIXEL_STEPS);
        for py in y_start..=y_end {
            let sample_y = py as i64 * SUBPIXEL_STEPS + SUBPIXEL_STEPS / 2;
            let sample_x = t.min_x as i64 * SUBPIXEL_STEPS + SUBPIXEL_STEPS / 2;
            let mut w = edges.map(|(a, b, _)| edge(t.x[a], t.y[a], t.x[b], t.y[b], sample_x, sample_y));
            let row = ((py - band.y0) * band.width) as usize;
            for px in t.min_x..=t.max_x {
                let inside = (w[0] + edges[0].2) | (w[1] + edges[1].2) | (w[2] + edges[2].2);
                if inside >= 0 {
                    fragments += 1;
                    let l = w.map(|wi| wi as f32 * t.inv_area);
                    let depth = l[0] * t.z[0] + l[1] * t.z[1] + l[2] * t.z[2];
                    let slot = row + px as usize;
                    if depth < band.depth[slot] {
                        band.depth[slot] = depth;
                        let inv_w = l[0] * t.inv_w[0] + l[1] * t.inv_w[1] + l[2] * t.inv_w[2];
                        let color =
                            (t.color_over_w[0] * l[0] + t.color_over_w[1] * l[1] + t.color_over_w[2] * l[2]) / inv_w;
                        let rgb = (color.clamp(Vec3::ZERO, Vec3::ONE) * 255.0).round();
                        band.color[slot * 4..slot * 4 + 4].copy_from_slice(&[
                            rgb.x as u8,
                            rgb.y as u8,
                            rgb.z as u8,
                            255,
                        ]);
                    }
                }
                for (wi, step) in w.iter_mut().zip(step_x) {
                    *wi += step;
                }
            }
        }
    }
    fragments
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
        Light { direction: Vec3::NEG_Z, diffuse: 1.0, ambient: 1.0 }
    }

    fn draw(camera: Camera, instances: &[Instance], size: (u32, u32)) -> (Framebuffer, RenderStats) {
        let mut target = Framebuffer::new(size.0, size.1);
        let frame = Frame { camera, light: full_light(), background: SKY, instances };
        let stats = Renderer::default().render(&mut target, &TaskPool::new(), &frame);
        (target, stats)
    }

    fn instance(mesh: MeshData, model: Mat4, color: Vec3) -> Instance {
        Instance { mesh: Arc::new(mesh), model, color }
    }

    /// A triangle fan over the square [-2, 2]^2 at z = 0 around an off-grid centre, facing +z.
    fn fan(centre: Vec3, rim_points: usize) -> MeshData {
        let mut mesh = MeshData { positions: vec![centre], normals: vec![Vec3::Z], triangles: vec![] };
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
    fn shared_edges_cover_every_pixel_exactly_once() {
        // The camera sees exactly [-1, 1]^2 at z = 0; the fan covers more, so every pixel
        // must be produced once: a gap would lower the count, a double pixel would raise it.
        for (centre, size) in
            [(Vec3::ZERO, (64, 64)), (Vec3::new(0.123, -0.377, 0.0), (97, 61)), (Vec3::new(-0.5, 0.25, 0.0), (40, 40))]
        {
            let camera = camera_at(Vec3::Z, Vec3::ZERO);
            let mesh = fan(centre, 37);
            let (_, stats) = draw(camera, &[instance(mesh, Mat4::IDENTITY, Vec3::ONE)], size);
            assert_eq!(stats.fragments, size.0 as u64 * size.1 as u64, "centre {centre}");
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
    fn interpenetrating_triangles_split_where_they_cross() {
        // Two quads crossing along the y axis: each is nearer on one side.
        let tilted = |angle: f32, color| {
            let model =
                Mat4::from_rotation_y(angle) * Mat4::from_rotation_x(FRAC_PI_2) * Mat4::from_scale(Vec3::splat(3.0));
            instance(MeshData::plane(1), model, color)
        };
        let camera = camera_at(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO);
        let (fb, _) = draw(camera, &[tilted(0.4, Vec3::X), tilted(-0.4, Vec3::Y)], (64, 64));
        let left = fb.pixel(20, 32);
        let right = fb.pixel(44, 32);
        assert_ne!(left, right);
        assert!(left == [255, 0, 0, 255] || left == [0, 255, 0, 255], "{left:?}");
        assert!(right == [255, 0, 0, 255] || right == [0, 255, 0, 255], "{right:?}");
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
        let light = Light { direction: Vec3::NEG_X, diffuse: 1.0, ambient: 0.1 };
        let sphere = instance(MeshData::sphere(24, 48), Mat4::IDENTITY, Vec3::ONE);
        let mut fb = Framebuffer::new(64, 64);
        let frame = Frame {
            camera: camera_at(Vec3::new(0.0, 0.0, 0.9), Vec3::ZERO),
            light,
            background: SKY,
            instances: &[sphere],
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
    fn rendering_is_deterministic_and_reuses_buffers() {
        let sphere = instance(MeshData::sphere(16, 32), Mat4::IDENTITY, Vec3::new(0.3, 0.6, 0.9));
        let frame = Frame {
            camera: camera_at(Vec3::new(0.4, 0.3, 1.2), Vec3::ZERO),
            light: Light { direction: Vec3::new(0.3, -1.0, -0.2).normalize(), diffuse: 0.8, ambient: 0.2 },
            background: SKY,
            instances: &[sphere],
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
}
