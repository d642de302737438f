//! The frame pipeline: a parallel vertex stage, then (when shadows are on) the shadow map's
//! depth pass (module `shadow_pass`), then the image: its triangles sorted into bands of tile rows
//! (module `sort`), then the bands drawn in parallel (module `color_pass`) and, with shadows,
//! darkened where the light does not reach. The bands and the map's strips are handed to the
//! threads those that took longest in the last frame first (module `work_queue`).
//!
//! A band takes the triangles reaching it in draw order, clips those crossing the near plane
//! or the guard band, sets each up (module `setup`: culling, pixel bounds, edge functions and
//! the planes of its values) and draws it at once into the band's tiles it touches, so that
//! earlier triangles win depth ties exactly as in a sequential renderer. A triangle reaching
//! two bands is set up in each. Every buffer lives in the [`Renderer`] and is reused, so a
//! frame of steady size allocates nothing of its own.

use crate::clip::outside;
use crate::color_pass::{self, BandCounts, BandScratch, BandShadow, TileContext};
use crate::frame::{Frame, Instance, RenderStats, Span, View, box_reaches, scene_bounds, world_box};
use crate::framebuffer::Framebuffer;
use crate::screen::{MAX_TARGET_SIZE, ScreenVertex, TILE_HEIGHT};
use crate::setup::Viewport;
use crate::shade::{Shading, VARYINGS, Varyings};
use crate::shadow::{PixelsInMap, ShadowMap, fit_light};
use crate::shadow_pass::{DepthPass, DepthScene, STRIP_ROWS};
use crate::sort::Sorted;
use crate::vertex::{CHUNKS_PER_THREAD, VertexOutputs, VertexStage};
use crate::work_queue::Schedule;
use bevy_math::{Mat3, Mat4, Vec3};
use bevy_tasks::TaskPool;

/// The CPU rasterizer. Keeps its working buffers between frames so that drawing a scene of
/// steady size does not allocate.
#[derive(Debug, Default)]
pub struct Renderer {
    /// Each instance's world box, and the instances reaching the view or the shadow map.
    boxes: Vec<Option<(Vec3, Vec3)>>,
    visible: Vec<Instance>,
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
        let stats = RenderStats {
            triangles_submitted: frame.instances.iter().map(|i| i.mesh.triangle_count()).sum(),
            ..RenderStats::default()
        };
        let aspect = width.max(1) as f32 / height.max(1) as f32;
        self.boxes.clear();
        self.boxes.extend(frame.instances.iter().map(world_box));
        let light_clip = if settings.shadows && width > 0 && height > 0 {
            scene_bounds(&self.boxes)
                .and_then(|bounds| fit_light(&frame.camera, aspect, &frame.light, bounds, settings.shadow_distance_m))
        } else {
            None
        };
        self.shadow.reset(settings.shadow_map_size, light_clip, settings.pcf);

        // Instances that reach neither the view nor the shadow map are left out of every stage:
        // the map's casters are kept whatever their depth along the light.
        let view_projection = frame.camera.view_projection(aspect);
        let reaches = |bounds: (Vec3, Vec3)| {
            box_reaches(view_projection, bounds, outside::VIEW)
                || light_clip
                    .is_some_and(|clip| box_reaches(clip, bounds, outside::VIEW & !(outside::NEAR | outside::FAR)))
        };
        let mut visible = std::mem::take(&mut self.visible);
        visible.clear();
        let boxes = frame.instances.iter().zip(&self.boxes);
        visible.extend(boxes.filter(|(_, bounds)| bounds.is_some_and(reaches)).map(|(instance, _)| instance.clone()));
        let stats =
            self.draw(target, pool, &Frame { instances: &visible, ..*frame }, view_projection, light_clip, stats);
        self.visible = visible;
        stats
    }

    /// Draws the instances of `frame`, all of which may reach the view or the shadow map, into
    /// `target` (see [`Renderer::render`]), adding to `stats`.
    fn draw(
        &mut self,
        target: &mut Framebuffer,
        pool: &TaskPool,
        frame: &Frame,
        view_projection: Mat4,
        light_clip: Option<Mat4>,
        mut stats: RenderStats,
    ) -> RenderStats {
        let (width, height, settings) = (target.width(), target.height(), frame.settings);
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
        let draw = |row: usize, (band, scratch)| color_pass::draw_band(&context, row as u32, band, scratch);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Camera, Lens, Light, Material, MeshData, Morph, RenderSettings};
    use std::f32::consts::FRAC_PI_2;
    use std::sync::Arc;

    const SKY: [u8; 4] = [10, 20, 30, 255];

    fn camera_at(eye: Vec3, target: Vec3) -> Camera {
        Camera { eye, target, lens: Lens::FieldOfView(FRAC_PI_2), near: 0.1, far: 100.0 }
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
    fn only_instances_reaching_neither_the_view_nor_the_shadow_map_are_left_out() {
        // A narrow view of the floor around the origin, the light falling steeply towards +x:
        // a cube beside the view on the light's side still shadows the floor in view, a cube
        // far off to the other side reaches neither.
        let floor = instance(MeshData::plane(4), Mat4::from_scale(Vec3::splat(8.0)), Vec3::ONE);
        let caster = instance(MeshData::cube(), Mat4::from_translation(Vec3::new(-3.0, 2.5, 0.0)), Vec3::ONE);
        let far_off = instance(MeshData::cube(), Mat4::from_translation(Vec3::new(30.0, 0.5, -30.0)), Vec3::ONE);
        let camera = Camera { lens: Lens::FieldOfView(0.5), ..camera_at(Vec3::new(0.0, 4.0, 4.0), Vec3::ZERO) };
        let light = Light { direction: Vec3::new(1.0, -1.0, 0.0).normalize(), diffuse: 0.8, fill: 0.0, ambient: 0.2 };
        let render = |instances: &[Instance]| {
            let mut target = Framebuffer::new(64, 64);
            let settings = RenderSettings { shadows: true, ..RenderSettings::default() };
            let frame = Frame { camera, light, background: SKY, instances, settings };
            let mut renderer = Renderer::default();
            let stats = renderer.render(&mut target, &TaskPool::new(), &frame);
            (target, stats, renderer.world.len())
        };
        let (alone, _, _) = render(std::slice::from_ref(&floor));
        let (image, stats, vertices) = render(&[floor.clone(), caster.clone(), far_off]);
        assert_eq!(stats.triangles_submitted, 2 * 16 + 2 * 12, "every instance counts as submitted");
        assert_eq!(vertices, floor.mesh.positions.len() + caster.mesh.positions.len(), "the far cube is left out");
        let darker = image.color().chunks_exact(4).zip(alone.color().chunks_exact(4)).filter(|(a, b)| a < b).count();
        assert!(darker > 20, "the cube beside the view casts into it: {darker} pixels in its shadow");
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
        use crate::benchmark_scene as standard;
        use crate::sort::Corners;
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

    #[test]
    fn a_morph_draws_the_mesh_near_its_targets_far_and_moves_in_between() {
        // A plane of 20 m with a ridge, whose morph flattens it; seen from above its middle,
        // lit from the side with shadows, so that both the image and the shadow map see the
        // vertices wherever the morph puts them.
        let mut ridged = MeshData::plane(16);
        let flat = ridged.clone();
        for (p, n) in ridged.positions.iter_mut().zip(&mut ridged.normals) {
            p.y = (p.x * 9.0).cos() * 0.08;
            *n = Vec3::new((p.x * 9.0).sin() * 0.7, 1.0, 0.0).normalize();
        }
        let morph = |start_m, end_m| {
            let mut mesh = ridged.clone();
            mesh.morph =
                Some(Morph { positions: flat.positions.clone(), normals: flat.normals.clone(), start_m, end_m });
            mesh
        };
        let draw = |mesh: MeshData| {
            let model = Mat4::from_scale(Vec3::splat(20.0));
            let mut target = Framebuffer::new(96, 64);
            let frame = Frame {
                camera: camera_at(Vec3::new(0.0, 9.0, 4.0), Vec3::ZERO),
                light: high_light(),
                background: SKY,
                instances: &[instance(mesh, model, Vec3::ONE)],
                settings: RenderSettings { shadows: true, ..RenderSettings::default() },
            };
            Renderer::default().render(&mut target, &TaskPool::new(), &frame);
            target
        };
        let (near, far) = (draw(ridged.clone()), draw(flat.clone()));
        assert_ne!(near.color(), far.color());
        assert_eq!(draw(morph(100.0, 200.0)).color(), near.color(), "nearer than the start: unmoved");
        assert_eq!(draw(morph(0.0, 1e-3)).color(), far.color(), "beyond the end: at the targets");
        // Vertices 0 to 14 m from the eye (horizontally): the morph band across the middle.
        let between = draw(morph(2.0, 8.0));
        assert!(between.color() != near.color() && between.color() != far.color());
        assert_eq!(morph(2.0, 8.0).morph.unwrap().weight(5.0), 0.5);
    }
}
