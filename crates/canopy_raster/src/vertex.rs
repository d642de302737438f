//! The vertex stage: every instance's vertices transformed, projected and lit in parallel
//! runs of four, with their texture coordinates and shadow-map positions.

use crate::camera::Light;
use crate::clip::ClipLanes;
use crate::frame::{Frame, Instance, Span};
use crate::mesh::Morph;
use crate::screen::ScreenVertex;
use crate::shade::{VARYINGS, Varyings, slot};
use bevy_math::{Mat4, Vec2, Vec3, Vec4};

/// Contiguous runs of vertices transformed in parallel, per worker thread.
pub(crate) const CHUNKS_PER_THREAD: usize = 4;

/// What the vertex stage reads: the frame, where each instance's vertices start and the
/// projections they go through.
pub(crate) struct VertexStage<'a> {
    pub frame: &'a Frame<'a>,
    pub spans: &'a [Span],
    pub view_projection: Mat4,
    pub width: u32,
    pub height: u32,
    /// The shadow map's projection and side in texels, when shadows are drawn.
    pub light: Option<(Mat4, u32)>,
    /// Whether the vertex colours are lit (Gouraud shading).
    pub lit: bool,
}

/// One run of the vertex stage's outputs, from the same first vertex on.
pub(crate) struct VertexOutputs<'a> {
    pub world: &'a mut [Vec3],
    pub screen: &'a mut [ScreenVertex],
    pub varyings: &'a mut [Varyings],
    /// Empty when shadows are off.
    pub light: &'a mut [ScreenVertex],
}

impl VertexStage<'_> {
    /// Transforms, lights and projects the run of vertices from global index `first` on,
    /// instance by instance.
    pub(crate) fn run(&self, first: usize, out: VertexOutputs) {
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
            let mut world = [world.x, world.y, world.z];
            let mut normal = gather(&normals[lanes.clone()]);
            if let Some(morph) = &mesh.morph {
                let targets = local + lanes.start..local + lanes.end;
                (world, normal) = self.morphed(span.model, morph, targets, world, normal);
            }
            // Projected from the world positions, exactly as clipping projects them again.
            let screen =
                ScreenVertex::lanes(&ClipLanes::transform(self.view_projection, world), self.width, self.height);
            let normal = normalize_or_zero(ClipLanes::transform(normal_matrix, normal));
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

impl VertexStage<'_> {
    /// Lanes of world positions and model normals moved towards their `morph` targets (those
    /// of the mesh's vertices `targets`) by their horizontal distance from the eye: four lanes
    /// of [`Morph::weight`].
    #[inline(always)]
    fn morphed(
        &self,
        model: Mat4,
        morph: &Morph,
        targets: std::ops::Range<usize>,
        world: [Vec4; 3],
        normal: [Vec4; 3],
    ) -> ([Vec4; 3], [Vec4; 3]) {
        let eye = self.frame.camera.eye;
        let (dx, dz) = (world[0] - Vec4::splat(eye.x), world[2] - Vec4::splat(eye.z));
        let distance = (dx * dx + dz * dz).sqrt();
        let span = Vec4::splat((morph.end_m - morph.start_m).max(f32::MIN_POSITIVE));
        let t = ((distance - Vec4::splat(morph.start_m)) / span).clamp(Vec4::ZERO, Vec4::ONE);
        let target = ClipLanes::transform(model, gather(&morph.positions[targets.clone()]));
        let target_normal = gather(&morph.normals[targets]);
        // Weighted this way, both ends are exact: the vertex at 0, its target at 1.
        let lerp = |from: [Vec4; 3], to: [Vec4; 3]| std::array::from_fn(|k| from[k] * (Vec4::ONE - t) + to[k] * t);
        (lerp(world, [target.x, target.y, target.z]), lerp(normal, target_normal))
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
    varyings[slot::BLEND] = mesh.blend.get(local).copied().unwrap_or(0.0);
    varyings
}
