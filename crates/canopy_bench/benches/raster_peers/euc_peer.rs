//! Peer renderer built on [`euc`] 0.5.3, a small software rasterizer whose shaders are Rust code.
//!
//! # How euc 0.5.3 maps onto the benchmark's conventions
//!
//! euc 0.5.3 has no configurable coordinate system (no coordinate mode, handedness, y direction
//! or depth range setting); its conventions are fixed in `rasterizer/triangles.rs`:
//! - the vertex shader returns homogeneous clip coordinates `[x, y, z, w]`; euc divides by `w`
//!   and maps NDC `x, y` in `[-1, 1]` to the framebuffer with **y up** (row 0 is the top row),
//!   sampling at pixel centres: the same as the benchmark's clip space;
//! - the depth buffer stores the perspective-correct interpolated NDC depth `z / w`, unchanged.
//!   With `perspective_rh`-style matrices (near 0, far 1) and a depth buffer cleared to 1.0,
//!   [`DepthStrategy::IfLessWrite`] is the usual "less" test (euc compares with `<=`);
//! - with [`BackfaceCullingEnabled`] a triangle is culled when its NDC winding is clockwise
//!   (`(b - a) x (c - a)` has a negative z), i.e. counter-clockwise triangles are front faces,
//!   as in OpenGL.
//!
//! Differences from a GPU pipeline that remain (none matters for a scene that lies entirely
//! in front of the near plane): euc does not clip, so fragments nearer than the near plane
//! (`z < 0`) are drawn and triangles crossing the `w = 0` plane come out wrong; it has no
//! top-left fill rule (pixels centred exactly on a shared edge are drawn twice); its depth test
//! passes on equality.
//!
//! # Threads
//!
//! euc 0.5.3 is single-threaded: it is a `no_std` crate without threads, rayon or a `par`
//! feature (its features are `std` and `libm` only), and `Triangles::draw` walks the triangles
//! one after the other on the calling thread. This peer therefore uses one core.

use euc::buffer::Buffer2d;
use euc::rasterizer::{BackfaceCullingEnabled, Triangles};
use euc::{DepthStrategy, Interpolate, Pipeline, Target};

use super::peer_scene::PeerScene;

/// Opaque black in the packing of [`pack_rgba8`]: the clear colour.
const CLEAR_COLOR: u32 = 0xFF00_0000;

/// Depth of the far plane in the `[0, 1]` clip-space depth range: the clear depth.
const CLEAR_DEPTH: f32 = 1.0;

/// Renders the standard scene with euc into colour and depth buffers it keeps between frames.
pub struct EucPeer {
    /// RGBA8 pixels packed as `r | g << 8 | b << 16 | a << 24` (bytes R, G, B, A in memory on
    /// little-endian machines), top row first.
    color: Buffer2d<u32>,
    /// NDC depth `z / w` per pixel, 0 at the near plane and 1 at the far plane.
    depth: Buffer2d<f32>,
}

impl EucPeer {
    /// Allocates the colour and depth buffers of a `width` x `height` image.
    pub fn new(width: usize, height: usize) -> Self {
        Self { color: Buffer2d::new([width, height], CLEAR_COLOR), depth: Buffer2d::new([width, height], CLEAR_DEPTH) }
    }

    /// Clears both buffers and draws one frame of `scene` seen through `clip_from_world`
    /// (column-major, clip depth in `[0, 1]`, y up).
    ///
    /// Nothing is allocated: the pipeline is a small stack value borrowing the scene, and euc
    /// reads the index list directly as its vertex stream (the vertex shader fetches position
    /// and normal by index). euc has no vertex cache, so each index is shaded once per
    /// triangle corner that uses it.
    pub fn render(&mut self, scene: &PeerScene, clip_from_world: [f32; 16]) {
        self.color.clear(CLEAR_COLOR);
        self.depth.clear(CLEAR_DEPTH);

        let pipeline = Gouraud {
            positions: scene.positions,
            normals: scene.normals,
            color: scene.color,
            light: scene.light,
            clip_from_world,
        };
        pipeline.draw::<Triangles<Buffer2d<f32>, BackfaceCullingEnabled>, _>(
            scene.indices,
            &mut self.color,
            Some(&mut self.depth),
        );
    }

    /// Fraction of the pixels that are not the clear colour, in `[0, 1]`.
    pub fn coverage(&self) -> f64 {
        let pixels: &[u32] = self.color.as_ref();
        if pixels.is_empty() {
            return 0.0;
        }
        let covered = pixels.iter().filter(|&&pixel| pixel != CLEAR_COLOR).count();
        covered as f64 / pixels.len() as f64
    }
}

/// The euc pipeline: per-vertex (Gouraud) diffuse lighting, colour interpolated per pixel.
struct Gouraud<'a> {
    positions: &'a [[f32; 3]],
    normals: &'a [[f32; 3]],
    color: [f32; 3],
    light: [f32; 3],
    /// Column-major: element `(row, col)` is at `col * 4 + row`.
    clip_from_world: [f32; 16],
}

impl Pipeline for Gouraud<'_> {
    /// The vertex stream is the index list; the shader fetches attributes itself.
    type Vertex = u32;
    /// Lit vertex colour, interpolated (perspective-correct) across the triangle.
    type VsOut = Rgb;
    /// Packed RGBA8, see [`pack_rgba8`].
    type Pixel = u32;

    #[inline(always)]
    fn vert(&self, index: &u32) -> ([f32; 4], Rgb) {
        let index = *index as usize;
        let [x, y, z] = self.positions[index];
        let m = &self.clip_from_world;
        let clip = [
            m[0] * x + m[4] * y + m[8] * z + m[12],
            m[1] * x + m[5] * y + m[9] * z + m[13],
            m[2] * x + m[6] * y + m[10] * z + m[14],
            m[3] * x + m[7] * y + m[11] * z + m[15],
        ];

        let [nx, ny, nz] = self.normals[index];
        let [lx, ly, lz] = self.light;
        let intensity = 0.15 + 0.85 * (nx * lx + ny * ly + nz * lz).max(0.0);
        let [r, g, b] = self.color;
        (clip, Rgb([r * intensity, g * intensity, b * intensity]))
    }

    #[inline(always)]
    fn frag(&self, color: &Rgb) -> u32 {
        pack_rgba8(color.0)
    }

    /// Depth "less" with depth writes; stated explicitly although it is euc's default.
    fn get_depth_strategy(&self) -> DepthStrategy {
        DepthStrategy::IfLessWrite
    }
}

/// Linear RGB colour passed from the vertex shader to the fragment shader.
///
/// A local type rather than euc's `(f32, f32, f32)` implementation, whose `f32::mul_add`
/// becomes a slow `fmaf` library call on CPUs targeted without FMA: plain products and sums
/// are what the other peers compute too.
#[derive(Clone, Copy)]
struct Rgb([f32; 3]);

impl Interpolate for Rgb {
    #[inline(always)]
    fn lerp2(a: Self, b: Self, x: f32, y: f32) -> Self {
        Rgb([a.0[0] * x + b.0[0] * y, a.0[1] * x + b.0[1] * y, a.0[2] * x + b.0[2] * y])
    }

    #[inline(always)]
    fn lerp3(a: Self, b: Self, c: Self, x: f32, y: f32, z: f32) -> Self {
        Rgb([
            a.0[0] * x + b.0[0] * y + c.0[0] * z,
            a.0[1] * x + b.0[1] * y + c.0[1] * z,
            a.0[2] * x + b.0[2] * y + c.0[2] * z,
        ])
    }
}

/// Converts a colour to opaque RGBA8 (rounding to nearest, as GL does for 8-bit targets) and
/// packs it as `r | g << 8 | b << 16 | 0xFF << 24`.
#[inline(always)]
fn pack_rgba8([r, g, b]: [f32; 3]) -> u32 {
    let to_u8 = |channel: f32| (channel.clamp(0.0, 1.0) * 255.0 + 0.5) as u32;
    to_u8(r) | (to_u8(g) << 8) | (to_u8(b) << 16) | (0xFF << 24)
}
