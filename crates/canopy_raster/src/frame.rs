//! What a frame is made of: the instances, the settings and the figures of a frame, the
//! global numbering of vertices and triangles across instances, and the view they are drawn in.

use crate::camera::{Camera, Light};
use crate::clip::{ClipVertex, clip_triangle, outcode};
use crate::mesh::MeshData;
use crate::screen::ScreenVertex;
use crate::setup::Viewport;
use crate::shade::{Material, Shading, Varyings};
use bevy_math::{Mat3, Mat4, Vec3};
use std::ops::Range;
use std::sync::Arc;

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
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderSettings {
    /// The lighting computation.
    pub shading: Shading,
    /// Whether the directional light casts shadows.
    pub shadows: bool,
    /// Whether shadow edges are filtered (bilinear percentage-closer filtering).
    pub pcf: bool,
    /// Shadow map side in texels: a multiple of [`TILE_HEIGHT`], at most [`MAX_TARGET_SIZE`].
    pub shadow_map_size: u32,
    /// Distance fog: drawn pixels fade into a colour with their distance; `None` for none.
    pub fog: Option<Fog>,
    /// Shadows are cast within this many metres of the camera, the shadow map fitted to that
    /// part of the view; `None` fits it to all of the scene the camera sees.
    pub shadow_distance_m: Option<f32>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            shading: Shading::Gouraud,
            shadows: false,
            pcf: true,
            shadow_map_size: 1024,
            fog: None,
            shadow_distance_m: None,
        }
    }
}

/// Distance fog: a drawn pixel's colour fades linearly into `color` from `start_m` to `end_m`
/// along the view direction (its depth in front of the camera), all of it beyond.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fog {
    /// RGB8: the colour far pixels take; `None` for the frame's background, so that the end
    /// of the world fades into the sky instead of ending in a line.
    pub color: Option<[u8; 3]>,
    /// Where the fog begins, metres in front of the camera.
    pub start_m: f32,
    /// Where it hides everything, metres (beyond `start_m`).
    pub end_m: f32,
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

/// Where an instance's vertices and triangles start in the frame's global numbering, and its
/// transforms.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Span {
    pub first_vertex: usize,
    pub first_triangle: usize,
    pub model: Mat4,
    pub normal_matrix: Mat3,
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

/// The diffuse term of a triangle's geometric normal, for flat shading.
pub(crate) fn flat_diffuse(corners: [Vec3; 3], light: &Light) -> f32 {
    let [a, b, c] = corners;
    light.diffuse_term((b - a).cross(c - a).normalize_or_zero())
}

/// World bounds of everything drawn, from each instance's transformed model bounds.
pub(crate) fn scene_bounds(boxes: &[Option<(Vec3, Vec3)>]) -> Option<(Vec3, Vec3)> {
    boxes.iter().flatten().copied().reduce(|(a_min, a_max), (b_min, b_max)| (a_min.min(b_min), a_max.max(b_max)))
}

/// The smallest world-axis-aligned box holding `instance`'s mesh as its model matrix places
/// it, `(min, max)`; `None` for a mesh without positions.
pub(crate) fn world_box(instance: &Instance) -> Option<(Vec3, Vec3)> {
    let (min, max) = instance.mesh.bounds()?;
    let centre = instance.model.transform_point3((min + max) * 0.5);
    let half = (max - min) * 0.5;
    let m = Mat3::from_mat4(instance.model);
    // The transformed box's half extent along each world axis.
    let extent = Vec3::new(m.row(0).abs().dot(half), m.row(1).abs().dot(half), m.row(2).abs().dot(half));
    Some((centre - extent, centre + extent))
}

/// Whether some of the world box `(min, max)` may lie inside the view volume of
/// `clip_from_world`, as far as the planes of `planes` (bits of
/// [`outside`](crate::clip::outside)) bound it: false
/// only when all eight corners lie beyond one of them, so that nothing inside the box can
/// reach the view.
pub(crate) fn box_reaches(clip_from_world: Mat4, (min, max): (Vec3, Vec3), planes: u8) -> bool {
    let beyond = (0..8).fold(planes, |beyond, corner: u8| {
        let pick = |bit: u8, low: f32, high: f32| if corner & bit == 0 { low } else { high };
        let point = Vec3::new(pick(1, min.x, max.x), pick(2, min.y, max.y), pick(4, min.z, max.z));
        beyond & outcode(clip_from_world * point.extend(1.0))
    });
    beyond == 0
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Lens;
    use crate::clip::outside;

    #[test]
    fn a_box_reaches_a_view_unless_it_lies_wholly_beyond_one_of_its_planes() {
        let camera =
            Camera { eye: Vec3::ZERO, target: Vec3::NEG_Z, lens: Lens::FieldOfView(1.0), near: 0.1, far: 50.0 };
        let view = camera.view_projection(1.0);
        let cube = |centre: Vec3| (centre - 0.5, centre + 0.5);
        assert!(box_reaches(view, cube(Vec3::new(0.0, 0.0, -5.0)), outside::VIEW), "in front");
        assert!(box_reaches(view, cube(Vec3::new(3.0, 0.0, -5.0)), outside::VIEW), "across the right plane");
        assert!(box_reaches(view, cube(Vec3::ZERO), outside::VIEW), "round the eye");
        for (centre, beyond) in [
            (Vec3::new(0.0, 0.0, 5.0), "behind"),
            (Vec3::new(0.0, 0.0, -60.0), "past the far plane"),
            (Vec3::new(10.0, 0.0, -5.0), "to the right"),
            (Vec3::new(0.0, -10.0, -5.0), "below"),
        ] {
            assert!(!box_reaches(view, cube(centre), outside::VIEW), "{beyond}");
        }
        // Without the near and far planes, depth along the view no longer matters.
        let sides = outside::VIEW & !(outside::NEAR | outside::FAR);
        assert!(box_reaches(view, cube(Vec3::new(0.0, 0.0, -60.0)), sides));
        assert!(!box_reaches(view, cube(Vec3::new(10.0, 0.0, -5.0)), sides));
    }
}
