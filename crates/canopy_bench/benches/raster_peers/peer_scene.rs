//! The scene description every peer renderer receives.
//!
//! Plain slices and arrays rather than glam types, so that the peers do not depend on the
//! engine's maths library and all of them read exactly the same data.

/// One indexed triangle mesh with a single surface colour and one directional light.
///
/// Conventions shared by all peers:
/// - `positions` are world-space points, `normals` unit normals, one per position;
/// - `indices` hold 3 indices per triangle, front faces counter-clockwise
///   (right-handed, OpenGL convention);
/// - lighting is per vertex (Gouraud):
///   `color * (0.15 + 0.85 * max(dot(normal, light), 0))`, interpolated across the triangle.
#[derive(Clone, Copy, Debug)]
pub struct PeerScene<'a> {
    /// World-space vertex positions.
    pub positions: &'a [[f32; 3]],
    /// Unit vertex normals, parallel to `positions`.
    pub normals: &'a [[f32; 3]],
    /// Triangle list, 3 indices per triangle, counter-clockwise front faces.
    pub indices: &'a [u32],
    /// Linear RGB surface colour in `[0, 1]`.
    pub color: [f32; 3],
    /// Unit vector pointing towards the light.
    pub light: [f32; 3],
}
