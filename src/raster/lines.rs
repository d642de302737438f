//! Lines drawn into the frame in 3D, for debug views (the sloth's foothold probes, its limb
//! chains): projected with the frame's camera, clipped at the near plane, and hidden behind
//! surfaces or drawn on top of them.
//!
//! Whoever shows lines adds them to [`Lines`] in [`RenderSystems::Collect`], which runs only
//! for frames that are drawn; they are drawn after the frame and then cleared.

use super::Framebuffer;
use super::plugin::{RasterTarget, RenderView, rasterize};
use crate::foundation::schedule::RenderSystems;
use bevy::prelude::*;

/// Draws the [`Lines`] into each frame after it is drawn.
pub struct LinesPlugin;

impl Plugin for LinesPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<Lines>().add_systems(PostUpdate, draw_lines.in_set(RenderSystems::Raster).after(rasterize));
    }
}

/// One line, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// One end.
    pub from: Vec3,
    /// The other.
    pub to: Vec3,
    /// Its colour, RGBA8.
    pub rgba: [u8; 4],
    /// Drawn over every surface instead of hidden behind the nearer ones.
    pub on_top: bool,
}

/// The lines of the frame being drawn.
#[derive(Resource, Debug, Default)]
pub struct Lines(pub Vec<Segment>);

impl Lines {
    /// Adds a polyline through `points`.
    pub fn polyline(&mut self, points: &[Vec3], rgba: [u8; 4], on_top: bool) {
        self.0.extend(points.windows(2).map(|pair| Segment { from: pair[0], to: pair[1], rgba, on_top }));
    }

    /// Adds a cross of three segments `size` metres long centred on `at`.
    pub fn cross(&mut self, at: Vec3, size: f32, rgba: [u8; 4], on_top: bool) {
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            let half = axis * (size * 0.5);
            self.0.push(Segment { from: at - half, to: at + half, rgba, on_top });
        }
    }
}

/// Draws the frame's lines into it and clears them.
fn draw_lines(view: Res<RenderView>, mut lines: ResMut<Lines>, mut target: ResMut<RasterTarget>) {
    if lines.0.is_empty() {
        return;
    }
    let framebuffer = &mut target.framebuffer;
    let aspect = framebuffer.width() as f32 / framebuffer.height().max(1) as f32;
    let clip_from_world = view.camera.view_projection(aspect);
    for segment in lines.0.drain(..) {
        draw(framebuffer, clip_from_world, &segment);
    }
}

/// Projects a segment, clips it at the near plane (clip-space depth 0) and draws it.
fn draw(framebuffer: &mut Framebuffer, clip_from_world: Mat4, segment: &Segment) {
    let (mut a, mut b) = (clip_from_world * segment.from.extend(1.0), clip_from_world * segment.to.extend(1.0));
    if a.z < 0.0 && b.z < 0.0 {
        return;
    }
    if a.z < 0.0 || b.z < 0.0 {
        let t = a.z / (a.z - b.z);
        let cut = a.lerp(b, t);
        if a.z < 0.0 { a = cut } else { b = cut }
    }
    let size = Vec2::new(framebuffer.width() as f32, framebuffer.height() as f32);
    framebuffer.draw_line_depth(screen(a, size), screen(b, size), segment.rgba, !segment.on_top);
}

/// A clip-space point in a frame of `size` pixels: pixel coordinates and normalized depth.
fn screen(clip: Vec4, size: Vec2) -> Vec3 {
    let ndc = clip.truncate() / clip.w.max(1e-6);
    Vec3::new((ndc.x + 1.0) * 0.5 * size.x, (1.0 - ndc.y) * 0.5 * size.y, ndc.z)
}

/// Where `point` lands in a frame of `size` pixels seen by `view`'s camera: pixel coordinates,
/// or `None` behind the camera.
pub fn pixel_of(view: &RenderView, size: UVec2, point: Vec3) -> Option<Vec2> {
    let clip = view.camera.view_projection(size.x as f32 / size.y.max(1) as f32) * point.extend(1.0);
    (clip.z >= 0.0 && clip.w > 0.0).then(|| screen(clip, size.as_vec2()).truncate())
}
