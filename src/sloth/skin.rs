//! The sloth's skin: one smooth surface over the torso, neck, head, snout and limbs, made once
//! for an animal's proportions in a bind pose and deformed by the rig in every pose (linear
//! blend skinning).
//!
//! The surface is the zero set of a smooth union of tapered capsules, one per body part and
//! limb bone, blended where they meet so that the limbs grow out of the torso and the neck out
//! of the shoulders. It is meshed by surface nets on a grid of [`CELL_M`] (scaled with the
//! animal), each vertex pulled onto the surface by one Newton step. Each vertex is then bound
//! to the bones whose capsules lie nearest to it: the body (torso, neck and head move as one)
//! and the four bones of each limb, blended over [`SPREAD_M`] so that joints bend smoothly.
//! Its coat is streaky value noise stretched along the body, pale on the face, dark around the
//! eyes, as in the two-toed sloth.

use super::rig::{BodyFrame, JOINTS, LimbRig, Proportions};
use crate::foundation::random::Random;
use bevy::math::{Mat3, Vec3};

/// Limb thickness at the girdle, shoulder or hip, elbow or knee, wrist or ankle, and palm,
/// metres, for an animal of default proportions (scaled with the torso).
pub const LIMB_RADII: [f32; JOINTS] = [0.045, 0.04, 0.032, 0.022, 0.016];

/// The torso radius the lengths here are given for, metres (the default animal's).
const DEFAULT_TORSO_RADIUS: f32 = 0.085;

/// The meshing grid's cell, metres at the default proportions: fine enough for the wrists,
/// coarse enough to keep the surface at a few thousand triangles.
const CELL_M: f32 = 0.015;

/// How far apart two parts start to blend into each other, metres at the default proportions.
const BLEND_M: f32 = 0.02;

/// How much farther than the nearest bone's capsule another bone's may be and still move a
/// vertex, metres at the default proportions.
const SPREAD_M: f32 = 0.03;

/// Bones a vertex follows at most.
const INFLUENCES: usize = 4;

/// Bones: the body, then each limb's four (girdle, upper, lower, hand or foot) in the order
/// of [`Limb::ALL`](super::rig::Limb::ALL).
const BONES: usize = 1 + 4 * 4;

/// The body's bone.
const BODY: usize = 0;

/// The bind pose: limbs swung out from the body and half bent, apart from each other and from
/// the torso, so that the surface keeps them separate.
const BIND_ABDUCTION_DEG: f32 = 40.0;

/// How bent the bind pose's joints are, as a fraction of their rest flexion.
const BIND_BEND: f32 = 0.5;

/// A bone's placement: its rotation (columns: along the bone, across, the third axis) and
/// origin.
#[derive(Debug, Clone, Copy, PartialEq)]
struct BoneFrame {
    rotation: Mat3,
    origin: Vec3,
}

/// A tapered capsule: axis from `a` to `b`, radius `ra` at `a` to `rb` at `b`, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Capsule {
    a: Vec3,
    b: Vec3,
    ra: f32,
    rb: f32,
    /// The bone it belongs to.
    bone: usize,
}

impl Capsule {
    /// Signed distance from `p` to the capsule's surface (exact for an even radius, close for
    /// a gentle taper), metres.
    fn distance(&self, p: Vec3) -> f32 {
        let ab = self.b - self.a;
        let t = ((p - self.a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
        p.distance(self.a + ab * t) - (self.ra + (self.rb - self.ra) * t)
    }
}

/// The skin of one animal: its surface in the bind pose, each vertex's bones, and its coat.
#[derive(Debug, Clone, PartialEq)]
pub struct Skin {
    /// Vertex positions in the bind pose, metres.
    bind: Vec<Vec3>,
    /// Triangles, counter-clockwise seen from outside.
    triangles: Vec<[u32; 3]>,
    /// Each vertex's bones and weights (summing to one; unused slots weigh zero).
    influences: Vec<[(u8, f32); INFLUENCES]>,
    /// Each bone's frame in the bind pose.
    bind_frames: [BoneFrame; BONES],
    /// Each vertex's coat colour as a multiple of the fur colour, before the face's.
    shade: Vec<f32>,
    /// Each vertex's colour mix: 0 fur, 1 the pale face, -1 the dark eye patches.
    face: Vec<f32>,
}

/// The colour of the face.
pub const FACE: Vec3 = Vec3::new(0.88, 0.82, 0.66);
/// The colour of the patches round the eyes.
pub const EYE_PATCH: Vec3 = Vec3::new(0.08, 0.06, 0.05);

impl Skin {
    /// The skin of an animal of `proportions` with limbs `rigs`.
    pub fn new(proportions: &Proportions, rigs: &[LimbRig; 4]) -> Self {
        let scale = thickness_scale(proportions);
        let frame = BodyFrame { centre: Vec3::ZERO, forward: Vec3::X, up: Vec3::Y };
        let angles = rigs.map(|rig| {
            let mut angles = rig.rest.map(|angle| angle * BIND_BEND);
            angles[0] = BIND_ABDUCTION_DEG.to_radians();
            angles
        });
        let capsules = capsules(proportions, rigs, &frame, &angles);
        let field = |p: Vec3| {
            capsules
                .iter()
                .map(|capsule| capsule.distance(p))
                .fold(f32::INFINITY, |a, b| smooth_min(a, b, BLEND_M * scale))
        };
        let (bind, triangles) = surface_nets(&field, &capsules, CELL_M * scale);
        let influences: Vec<_> = bind.iter().map(|&p| influences(&capsules, p, SPREAD_M * scale)).collect();
        let head = frame.head(proportions);
        let eyes = eye_centres(&frame, head, proportions.head_radius);
        let face = bind.iter().map(|&p| face_mix(p, head, proportions.head_radius, &eyes)).collect();
        let shade = bind
            .iter()
            .zip(&influences)
            .map(|(&p, influences)| coat_shade(p / scale) * limb_tone(influences))
            .collect();
        Self { bind, triangles, influences, bind_frames: bone_frames(&frame, rigs, &angles), shade, face }
    }

    /// The surface's triangles.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The vertices where the rig puts them with the body at `frame` and each limb of `rigs` at
    /// its joint `angles` (indexed like [`Limb::ALL`]).
    pub fn posed(&self, frame: &BodyFrame, rigs: &[LimbRig; 4], angles: &[[f32; JOINTS]; 4]) -> Vec<Vec3> {
        let now = bone_frames(frame, rigs, angles);
        // Each bone's motion from the bind pose: p -> rotation * p + shift.
        let motions: [(Mat3, Vec3); BONES] = std::array::from_fn(|bone| {
            let rotation = now[bone].rotation * self.bind_frames[bone].rotation.transpose();
            (rotation, now[bone].origin - rotation * self.bind_frames[bone].origin)
        });
        self.bind
            .iter()
            .zip(&self.influences)
            .map(|(&p, influences)| {
                influences
                    .iter()
                    .map(|&(bone, weight)| {
                        let (rotation, shift) = motions[bone as usize];
                        (rotation * p + shift) * weight
                    })
                    .sum()
            })
            .collect()
    }

    /// Each vertex's colour for a coat of colour `fur`.
    pub fn colors(&self, fur: Vec3) -> Vec<Vec3> {
        self.shade
            .iter()
            .zip(&self.face)
            .map(|(&shade, &face)| {
                let coat = fur * shade;
                if face >= 0.0 { coat.lerp(FACE, face) } else { coat.lerp(EYE_PATCH, -face) }
            })
            .collect()
    }
}

/// How much thicker than the default animal's the parts of an animal of `proportions` are.
pub(super) fn thickness_scale(proportions: &Proportions) -> f32 {
    proportions.torso_radius / DEFAULT_TORSO_RADIUS
}

/// The polynomial smooth minimum of `a` and `b`, blending over `k`.
fn smooth_min(a: f32, b: f32, k: f32) -> f32 {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

/// The grip end of a limb's last bone without its claws: the palm or sole.
pub(super) fn palm(points: &[Vec3; JOINTS], claw: f32) -> Vec3 {
    let hand = (points[JOINTS - 1] - points[JOINTS - 2]).normalize_or_zero();
    points[JOINTS - 1] - hand * claw
}

/// The parts of the body and the limbs' bones as capsules, in the pose of `frame` and `angles`.
fn capsules(
    proportions: &Proportions,
    rigs: &[LimbRig; 4],
    frame: &BodyFrame,
    angles: &[[f32; JOINTS]; 4],
) -> Vec<Capsule> {
    let (r, hr, forward) = (proportions.torso_radius, proportions.head_radius, frame.forward);
    let (hips, shoulders, head) = (frame.hips(proportions), frame.shoulders(proportions), frame.head(proportions));
    let snout = head + forward * (hr * 0.75) - frame.up * (hr * 0.15);
    let body = |a, b, ra, rb| Capsule { a, b, ra, rb, bone: BODY };
    let mut capsules = vec![
        body(hips, frame.centre, r * 0.92, r),
        body(frame.centre, shoulders, r, r * 0.85),
        body(shoulders, head, hr * 0.7, hr * 0.6),
        body(head - forward * (hr * 0.3), head + forward * (hr * 0.3), hr, hr * 0.9),
        body(snout - forward * (hr * 0.3), snout + forward * (hr * 0.15), hr * 0.62, hr * 0.45),
    ];
    let radii = LIMB_RADII.map(|radius| radius * thickness_scale(proportions));
    for (l, rig) in rigs.iter().enumerate() {
        let mut points = rig.points(frame, &angles[l]);
        points[JOINTS - 1] = palm(&points, proportions.claw);
        for bone in 0..4 {
            capsules.push(Capsule {
                a: points[bone],
                b: points[bone + 1],
                ra: radii[bone],
                rb: radii[bone + 1],
                bone: 1 + 4 * l + bone,
            });
        }
    }
    capsules
}

/// Every bone's frame with the body at `frame` and the limbs at `angles`.
fn bone_frames(frame: &BodyFrame, rigs: &[LimbRig; 4], angles: &[[f32; JOINTS]; 4]) -> [BoneFrame; BONES] {
    let mut frames =
        [BoneFrame { rotation: Mat3::from_cols(frame.forward, frame.up, frame.right()), origin: frame.centre }; BONES];
    for (l, rig) in rigs.iter().enumerate() {
        let points = rig.points(frame, &angles[l]);
        // Flexion turns each bone inside the limb's plane, whose normal is the flexion axis:
        // bone direction, axis and their cross product make a right-handed frame.
        let (_, across) = rig.axes(frame, angles[l][0]);
        for bone in 0..4 {
            let along = (points[bone + 1] - points[bone]).normalize_or(frame.up);
            frames[1 + 4 * l + bone] =
                BoneFrame { rotation: Mat3::from_cols(along, across, along.cross(across)), origin: points[bone] };
        }
    }
    frames
}

/// The bones of the capsules nearest `p`, weighted by how much nearer than `spread` beyond the
/// nearest they are.
fn influences(capsules: &[Capsule], p: Vec3, spread: f32) -> [(u8, f32); INFLUENCES] {
    let mut distance = [f32::INFINITY; BONES];
    for capsule in capsules {
        distance[capsule.bone] = distance[capsule.bone].min(capsule.distance(p));
    }
    let nearest = distance.iter().copied().fold(f32::INFINITY, f32::min);
    let mut weights: Vec<(u8, f32)> = distance
        .iter()
        .enumerate()
        .map(|(bone, &d)| (bone as u8, (1.0 - (d - nearest) / spread).max(0.0).powi(2)))
        .filter(|&(_, weight)| weight > 0.0)
        .collect();
    weights.sort_by(|a, b| b.1.total_cmp(&a.1));
    weights.truncate(INFLUENCES);
    let total: f32 = weights.iter().map(|(_, weight)| weight).sum();
    let mut out = [(BODY as u8, 0.0); INFLUENCES];
    for (slot, (bone, weight)) in out.iter_mut().zip(weights) {
        *slot = (bone, weight / total);
    }
    out
}

/// Where the eyes are on a head of `radius` centred at `head`.
fn eye_centres(frame: &BodyFrame, head: Vec3, radius: f32) -> [Vec3; 2] {
    [-1.0, 1.0].map(|side| {
        head + frame.forward * (radius * 0.62) - frame.up * (radius * 0.45) + frame.right() * (side * radius * 0.38)
    })
}

/// The face's colour mix at `p` (see [`Skin::face`]): dark round the eyes, pale over the
/// front of the head and the snout, fur elsewhere. In the bind pose, whose forward is `+x`.
fn face_mix(p: Vec3, head: Vec3, radius: f32, eyes: &[Vec3; 2]) -> f32 {
    let eye = eyes.iter().map(|eye| eye.distance(p)).fold(f32::INFINITY, f32::min);
    if eye < radius * 0.55 {
        return -smoothstep(radius * 0.55, radius * 0.3, eye);
    }
    if p.distance(head) > radius * 2.2 {
        return 0.0;
    }
    smoothstep(0.1, 0.6, (p.x - head.x) / radius)
}

/// 0 at `from`, 1 at `to`, smooth in between (either way round).
fn smoothstep(from: f32, to: f32, x: f32) -> f32 {
    let t = ((x - from) / (to - from)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The coat's shade at `p` (bind pose, metres at the default proportions): long streaks along
/// the body over a fine grain, between 0.6 and 1.3 times the fur colour.
fn coat_shade(p: Vec3) -> f32 {
    let streaks = value_noise(Vec3::new(p.x * 14.0, p.y * 60.0, p.z * 60.0));
    let grain = value_noise(p * 120.0 + Vec3::splat(17.0));
    0.6 + 0.7 * (0.6 * streaks + 0.4 * grain)
}

/// How much darker the coat grows down the limbs, as in the animal: a multiple of the shade
/// by each bone (body, then girdle, upper, lower, hand or foot), blended by the weights.
fn limb_tone(influences: &[(u8, f32); INFLUENCES]) -> f32 {
    const TONES: [f32; 5] = [1.0, 0.95, 0.88, 0.78, 0.66];
    influences
        .iter()
        .map(|&(bone, weight)| {
            weight * if bone as usize == BODY { TONES[0] } else { TONES[1 + (bone as usize - 1) % 4] }
        })
        .sum()
}

/// Smooth value noise in `[0, 1]`: hashed lattice values, blended with smoothstep weights.
fn value_noise(p: Vec3) -> f32 {
    let cell = p.floor();
    let f = p - cell;
    let w = f * f * (Vec3::splat(3.0) - 2.0 * f);
    let lattice = |dx: i64, dy: i64, dz: i64| {
        let key = (cell.x as i64 + dx).wrapping_mul(73_856_093)
            ^ (cell.y as i64 + dy).wrapping_mul(19_349_663)
            ^ (cell.z as i64 + dz).wrapping_mul(83_492_791);
        Random::new(key as u64).unit()
    };
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let plane = |dz| {
        let near = lerp(lattice(0, 0, dz), lattice(1, 0, dz), w.x);
        let far = lerp(lattice(0, 1, dz), lattice(1, 1, dz), w.x);
        lerp(near, far, w.y)
    };
    lerp(plane(0), plane(1), w.z)
}

/// The zero set of `field` around `capsules`, meshed by surface nets on a grid of `cell`
/// metres: vertices on the surface, triangles counter-clockwise seen from outside.
fn surface_nets(field: &impl Fn(Vec3) -> f32, capsules: &[Capsule], cell: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let margin = capsules.iter().map(|c| c.ra.max(c.rb)).fold(0.0, f32::max) + 2.0 * cell;
    let low = capsules.iter().flat_map(|c| [c.a, c.b]).fold(Vec3::INFINITY, Vec3::min) - Vec3::splat(margin);
    let high = capsules.iter().flat_map(|c| [c.a, c.b]).fold(Vec3::NEG_INFINITY, Vec3::max) + Vec3::splat(margin);
    let n = ((high - low) / cell).ceil().as_uvec3() + 1;
    let (nx, ny, nz) = (n.x as usize, n.y as usize, n.z as usize);
    let node = |i: usize, j: usize, k: usize| low + Vec3::new(i as f32, j as f32, k as f32) * cell;
    let index = |i: usize, j: usize, k: usize| (k * ny + j) * nx + i;
    let mut values = vec![0.0; nx * ny * nz];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                values[index(i, j, k)] = field(node(i, j, k));
            }
        }
    }
    // One vertex in each cell the surface crosses: the mean of its edges' crossings, then
    // pulled onto the surface along the field's gradient.
    let mut cell_vertex = vec![u32::MAX; nx * ny * nz];
    let mut vertices = Vec::new();
    for k in 0..nz - 1 {
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let corner = |c: usize| (i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
                let value = |c: usize| {
                    let (a, b, d) = corner(c);
                    values[index(a, b, d)]
                };
                let inside = (0..8).filter(|&c| value(c) < 0.0).count();
                if inside == 0 || inside == 8 {
                    continue;
                }
                let (mut sum, mut crossings) = (Vec3::ZERO, 0.0);
                for c in 0..8 {
                    for bit in [1, 2, 4] {
                        let d = c | bit;
                        if c & bit != 0 || (value(c) < 0.0) == (value(d) < 0.0) {
                            continue;
                        }
                        let t = value(c) / (value(c) - value(d));
                        let (p, q) = (corner(c), corner(d));
                        sum += node(p.0, p.1, p.2).lerp(node(q.0, q.1, q.2), t);
                        crossings += 1.0;
                    }
                }
                cell_vertex[index(i, j, k)] = vertices.len() as u32;
                vertices.push(onto_surface(field, sum / crossings, cell));
            }
        }
    }
    // A quad across each grid edge the surface crosses, joining the four cells round it.
    let mut triangles = Vec::new();
    let size = [nx, ny, nz];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let at = [i, j, k];
                let here = values[index(i, j, k)] < 0.0;
                for axis in 0..3 {
                    let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
                    if at[axis] + 1 >= size[axis] || at[b] == 0 || at[c] == 0 {
                        continue;
                    }
                    let mut next = at;
                    next[axis] += 1;
                    if (values[index(next[0], next[1], next[2])] < 0.0) == here {
                        continue;
                    }
                    let around = [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(ob, oc)| {
                        let mut cell = at;
                        cell[b] -= ob;
                        cell[c] -= oc;
                        cell_vertex[index(cell[0], cell[1], cell[2])]
                    });
                    // Going round the cells in this order faces along +axis: outwards when
                    // this node is inside.
                    let [v0, v1, v2, v3] = if here { around } else { [around[3], around[2], around[1], around[0]] };
                    triangles.push([v0, v1, v2]);
                    triangles.push([v0, v2, v3]);
                }
            }
        }
    }
    (vertices, triangles)
}

/// `p` moved onto the zero set of `field` by one Newton step along its gradient (central
/// differences over a tenth of a `cell`), at most a cell.
fn onto_surface(field: &impl Fn(Vec3) -> f32, p: Vec3, cell: f32) -> Vec3 {
    let h = cell * 0.1;
    let gradient = Vec3::new(
        field(p + Vec3::X * h) - field(p - Vec3::X * h),
        field(p + Vec3::Y * h) - field(p - Vec3::Y * h),
        field(p + Vec3::Z * h) - field(p - Vec3::Z * h),
    ) / (2.0 * h);
    let step = gradient * (field(p) / gradient.length_squared().max(1e-12));
    p - step.clamp_length_max(cell)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sloth::rig::{Limb, limb_rigs};

    fn skin() -> (Skin, Proportions, [LimbRig; 4]) {
        let proportions = Proportions::default();
        let rigs = limb_rigs(&proportions);
        (Skin::new(&proportions, &rigs), proportions, rigs)
    }

    /// The pose of the rest angles with the body at `frame`.
    fn rest(rigs: &[LimbRig; 4]) -> [[f32; JOINTS]; 4] {
        rigs.map(|rig| rig.rest)
    }

    #[test]
    fn the_surface_is_closed_faces_out_and_stays_small() {
        let (skin, ..) = skin();
        assert!((1000..12_000).contains(&skin.triangles.len()), "{} triangles", skin.triangles.len());
        // Closed and consistently wound: each edge is walked as often one way as the other
        // (twice each way where surface nets pinch two sheets together at one edge).
        let mut edges = std::collections::HashMap::new();
        for &[a, b, c] in &skin.triangles {
            for edge in [(a, b), (b, c), (c, a)] {
                *edges.entry(edge).or_insert(0) += 1;
            }
        }
        assert!(edges.iter().all(|(&(a, b), count)| edges.get(&(b, a)) == Some(count)));
        // Facing out: the enclosed volume is positive, and about the capsules' own.
        let volume: f32 = skin
            .triangles
            .iter()
            .map(|&[a, b, c]| skin.bind[a as usize].dot(skin.bind[b as usize].cross(skin.bind[c as usize])) / 6.0)
            .sum();
        assert!((0.008..0.03).contains(&volume), "{volume} m³");
    }

    #[test]
    fn weights_sum_to_one_and_the_posed_skin_follows_the_rig() {
        let (skin, proportions, rigs) = skin();
        for influences in &skin.influences {
            assert!((influences.iter().map(|(_, w)| w).sum::<f32>() - 1.0).abs() < 1e-5);
        }
        // Moved and turned as a whole, the body's own vertices move rigidly with it.
        let frame = BodyFrame { centre: Vec3::new(1.0, 2.0, 3.0), forward: Vec3::Z, up: Vec3::NEG_Y };
        let posed = skin.posed(&frame, &rigs, &rest(&rigs));
        let bind_head = BodyFrame { centre: Vec3::ZERO, forward: Vec3::X, up: Vec3::Y }.head(&proportions);
        let head = frame.head(&proportions);
        for (v, p) in skin.bind.iter().zip(&posed) {
            if v.distance(bind_head) < proportions.head_radius {
                assert!((p.distance(head) - v.distance(bind_head)).abs() < 1e-4, "the head keeps its shape");
            }
        }
        // Each grip's palm is covered by the skin in any pose the limbs take.
        let mut angles = rest(&rigs);
        angles[Limb::LeftFore.index()][3] -= 0.6;
        let posed = skin.posed(&frame, &rigs, &angles);
        for (l, rig) in rigs.iter().enumerate() {
            let points = rig.points(&frame, &angles[l]);
            let palm = palm(&points, proportions.claw);
            let nearest = posed.iter().map(|p| p.distance(palm)).fold(f32::INFINITY, f32::min);
            assert!(nearest < 0.03, "{:?}'s palm is {nearest} m from the skin", rig.limb);
            let wrist = points[3];
            let nearest = posed.iter().map(|p| p.distance(wrist)).fold(f32::INFINITY, f32::min);
            assert!(nearest < 0.04, "{:?}'s wrist is {nearest} m from the skin", rig.limb);
        }
    }

    #[test]
    fn the_face_is_pale_with_dark_eye_patches_and_the_coat_varies() {
        let (skin, ..) = skin();
        let fur = Vec3::new(0.45, 0.35, 0.25);
        let colors = skin.colors(fur);
        assert!(colors.iter().any(|c| c.distance(EYE_PATCH) < 0.05), "eye patches");
        assert!(colors.iter().any(|c| c.distance(FACE) < 0.05), "a pale face");
        let coat: Vec<f32> =
            skin.shade.iter().copied().zip(&skin.face).filter(|(_, f)| **f == 0.0).map(|(s, _)| s).collect();
        let mean = coat.iter().sum::<f32>() / coat.len() as f32;
        let spread = (coat.iter().map(|s| (s - mean).powi(2)).sum::<f32>() / coat.len() as f32).sqrt();
        assert!(spread > 0.05, "a shaggy coat, not one flat colour: {spread}");
        assert!(coat.iter().all(|s| (0.6 * 0.66..=1.3).contains(s)));
    }
}
