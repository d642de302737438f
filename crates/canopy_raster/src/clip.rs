//! Polygon clipping in homogeneous clip space.
//!
//! Triangles are clipped against the near plane (`z >= 0` for the `[0, 1]` depth range) so that
//! a triangle crossing it is cut, never dropped or stretched, and against a guard band at
//! [`GUARD_BAND`] times the viewport in x and y so that projected coordinates stay small enough
//! for exact fixed-point edge functions. Far-plane and viewport clipping are left to the depth
//! test and the screen bounds.

use crate::shade::Varyings;
use bevy_math::{BVec4A, Mat4, Vec4};

/// How far outside the viewport, in viewport half-sizes, vertices may lie before x/y clipping
/// cuts the triangle.
pub const GUARD_BAND: f32 = 4.0;

/// The most vertices a clipped triangle can have: three plus one per clipping plane.
pub const MAX_CLIPPED: usize = 3 + PLANES.len();

/// Clipping planes as `p` such that a vertex is inside when `p . position >= 0`.
const PLANES: [Vec4; 5] = [
    Vec4::new(0.0, 0.0, 1.0, 0.0),
    Vec4::new(1.0, 0.0, 0.0, GUARD_BAND),
    Vec4::new(-1.0, 0.0, 0.0, GUARD_BAND),
    Vec4::new(0.0, 1.0, 0.0, GUARD_BAND),
    Vec4::new(0.0, -1.0, 0.0, GUARD_BAND),
];

/// A vertex after the vertex stage: its clip-space position and the values interpolated
/// across its triangles.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ClipVertex {
    /// Homogeneous clip-space position.
    pub position: Vec4,
    /// Interpolated values (see [`shade`](crate::shade)).
    pub varyings: Varyings,
}

impl ClipVertex {
    fn lerp(self, other: Self, t: f32) -> Self {
        let mut varyings = self.varyings;
        for (v, o) in varyings.iter_mut().zip(other.varyings) {
            *v += (o - *v) * t;
        }
        Self { position: self.position.lerp(other.position, t), varyings }
    }
}

/// Bits of [`outcode`]: which planes a clip-space position lies outside of.
pub mod outside {
    /// In front of the near plane.
    pub const NEAR: u8 = 1;
    /// Beyond the far plane.
    pub const FAR: u8 = 2;
    /// Left of the viewport.
    pub const LEFT: u8 = 4;
    /// Right of the viewport.
    pub const RIGHT: u8 = 8;
    /// Below the viewport.
    pub const BOTTOM: u8 = 16;
    /// Above the viewport.
    pub const TOP: u8 = 32;
    /// Outside the guard band on some side.
    pub const GUARD: u8 = 64;
    /// The view volume's planes: a triangle with all vertices outside one of them is invisible.
    pub const VIEW: u8 = NEAR | FAR | LEFT | RIGHT | BOTTOM | TOP;
    /// The planes [`clip_triangle`](super::clip_triangle) cuts against.
    pub const CLIPPED: u8 = NEAR | GUARD;
}

/// Which planes `position` lies outside of, as [`outside`] bits.
pub fn outcode(p: Vec4) -> u8 {
    ClipLanes::splat(p).outcodes()[0]
}

/// Four homogeneous positions, one per lane of each coordinate, for the vertex stage to work
/// on four vertices at once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ClipLanes {
    pub x: Vec4,
    pub y: Vec4,
    pub z: Vec4,
    pub w: Vec4,
}

impl ClipLanes {
    /// The same position in every lane.
    pub fn splat(p: Vec4) -> Self {
        Self { x: Vec4::splat(p.x), y: Vec4::splat(p.y), z: Vec4::splat(p.z), w: Vec4::splat(p.w) }
    }

    /// `matrix` applied to the four points `(x, y, z, 1)` given lane by lane.
    #[inline(always)]
    pub fn transform(matrix: Mat4, [x, y, z]: [Vec4; 3]) -> Self {
        let row = |k: usize| {
            Vec4::splat(matrix.x_axis[k]) * x
                + Vec4::splat(matrix.y_axis[k]) * y
                + Vec4::splat(matrix.z_axis[k]) * z
                + Vec4::splat(matrix.w_axis[k])
        };
        Self { x: row(0), y: row(1), z: row(2), w: row(3) }
    }

    /// Which planes each lane's position lies outside of, as [`outside`] bits.
    #[inline(always)]
    pub fn outcodes(&self) -> [u8; 4] {
        // Each plane adds its bit where the lane is outside; the bits are distinct powers of
        // two, so the float sum is exact.
        let bit = |outside: BVec4A, bit: u8| Vec4::select(outside, Vec4::splat(f32::from(bit)), Vec4::ZERO);
        let guard = self.w * GUARD_BAND;
        let code = bit(self.z.cmplt(Vec4::ZERO), outside::NEAR)
            + bit(self.z.cmpgt(self.w), outside::FAR)
            + bit(self.x.cmplt(-self.w), outside::LEFT)
            + bit(self.x.cmpgt(self.w), outside::RIGHT)
            + bit(self.y.cmplt(-self.w), outside::BOTTOM)
            + bit(self.y.cmpgt(self.w), outside::TOP)
            + bit(self.x.abs().cmpgt(guard) | self.y.abs().cmpgt(guard), outside::GUARD);
        code.to_array().map(|c| c as u8)
    }
}

/// A convex polygon of at most [`MAX_CLIPPED`] vertices, stored inline.
#[derive(Debug, Clone, Copy)]
pub struct Polygon {
    vertices: [ClipVertex; MAX_CLIPPED],
    len: usize,
}

impl Polygon {
    /// The polygon's vertices, in order.
    pub fn vertices(&self) -> &[ClipVertex] {
        &self.vertices[..self.len]
    }
}

/// Clips a triangle against the near plane and the guard band (Sutherland-Hodgman), keeping
/// the vertex order. The result has fewer than three vertices when nothing is left.
pub fn clip_triangle(triangle: &[ClipVertex; 3]) -> Polygon {
    let mut current = Polygon { vertices: [ClipVertex::default(); MAX_CLIPPED], len: 3 };
    current.vertices[..3].copy_from_slice(triangle);
    for plane in PLANES {
        let mut next = Polygon { vertices: current.vertices, len: 0 };
        let input = current.vertices();
        for (i, &a) in input.iter().enumerate() {
            let b = input[(i + 1) % input.len()];
            let (da, db) = (plane.dot(a.position), plane.dot(b.position));
            if da >= 0.0 {
                next.vertices[next.len] = a;
                next.len += 1;
            }
            if (da >= 0.0) != (db >= 0.0) {
                next.vertices[next.len] = a.lerp(b, da / (da - db));
                next.len += 1;
            }
        }
        if next.len < 3 {
            next.len = 0;
            return next;
        }
        current = next;
    }
    current
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shade::VARYINGS;

    fn vertex(x: f32, y: f32, z: f32, w: f32) -> ClipVertex {
        ClipVertex { position: Vec4::new(x, y, z, w), varyings: [z; VARYINGS] }
    }

    fn codes(triangle: &[ClipVertex; 3]) -> [u8; 3] {
        triangle.map(|v| outcode(v.position))
    }

    #[test]
    fn outcodes_name_every_plane_a_lane_is_outside_of() {
        let lanes = [
            (Vec4::new(0.2, -0.3, 0.5, 1.0), 0),
            (Vec4::new(0.0, 0.0, -0.1, 1.0), outside::NEAR),
            (Vec4::new(-2.0, 2.0, 3.0, 2.5), outside::FAR),
            (Vec4::new(-5.0, 1.5, 0.5, 1.0), outside::LEFT | outside::TOP | outside::GUARD),
            (Vec4::new(1.5, -4.5, 0.5, 1.0), outside::RIGHT | outside::BOTTOM | outside::GUARD),
        ];
        for (p, expected) in lanes {
            assert_eq!(outcode(p), expected, "{p}");
        }
        // Four at once agree with one at a time.
        let four = ClipLanes {
            x: Vec4::new(0.2, 0.0, -2.0, -5.0),
            y: Vec4::new(-0.3, 0.0, 2.0, 1.5),
            z: Vec4::new(0.5, -0.1, 3.0, 0.5),
            w: Vec4::new(1.0, 1.0, 2.5, 1.0),
        };
        assert_eq!(four.outcodes(), [0, 1, 2, 3].map(|k| lanes[k].1));
    }

    #[test]
    fn a_triangle_inside_is_left_alone() {
        let tri = [vertex(0.0, 0.0, 0.5, 1.0), vertex(0.5, 0.0, 0.5, 1.0), vertex(0.0, 0.5, 0.5, 1.0)];
        assert_eq!(codes(&tri), [0; 3]);
        assert_eq!(clip_triangle(&tri).vertices(), &tri);
    }

    #[test]
    fn crossing_the_near_plane_cuts_into_a_quad_on_the_plane() {
        // One vertex behind the near plane (z < 0).
        let tri = [vertex(0.0, 0.0, -1.0, 1.0), vertex(1.0, 0.0, 1.0, 2.0), vertex(0.0, 1.0, 1.0, 2.0)];
        assert!(codes(&tri).iter().any(|c| c & outside::CLIPPED != 0));
        let polygon = clip_triangle(&tri);
        assert_eq!(polygon.vertices().len(), 4);
        for v in polygon.vertices() {
            assert!(v.position.z >= -1e-6, "{v:?} behind the near plane");
        }
        let on_plane = polygon.vertices().iter().filter(|v| v.position.z.abs() < 1e-6).count();
        assert_eq!(on_plane, 2);
        // Varyings are interpolated with the position: they were all set to z.
        for v in polygon.vertices() {
            assert!(v.varyings.iter().all(|&value| (value - v.position.z).abs() < 1e-6));
        }
    }

    #[test]
    fn a_triangle_behind_the_eye_vanishes() {
        let tri = [vertex(0.0, 0.0, -1.0, 1.0), vertex(1.0, 0.0, -0.5, 1.0), vertex(0.0, 1.0, -2.0, 1.0)];
        assert_ne!(codes(&tri).into_iter().fold(outside::VIEW, |all, c| all & c), 0);
        assert!(clip_triangle(&tri).vertices().is_empty());
    }

    #[test]
    fn far_outside_the_guard_band_is_cut_back_to_it() {
        let tri = [vertex(-100.0, 0.0, 0.5, 1.0), vertex(100.0, 0.0, 0.5, 1.0), vertex(0.0, 1.0, 0.5, 1.0)];
        let polygon = clip_triangle(&tri);
        assert!(polygon.vertices().len() >= 3);
        for v in polygon.vertices() {
            assert!(v.position.x.abs() <= GUARD_BAND * v.position.w + 1e-4);
        }
    }
}
