//! A body's material and the compliance of each constraint it gives: an edge's from the
//! Young's modulus over the edge's share of the volume, a tetrahedron's from the bulk modulus,
//! a hinge's from the bending rigidity.

/// The physical settings of a body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Density, kilograms per cubic metre.
    pub density_kg_m3: f32,
    /// Young's modulus, pascals: each edge is a spring over its share of the body's volume,
    /// with the strain energy `E V (strain)^2 / 2` (infinite: rigid edges).
    pub young_modulus_pa: f32,
    /// Poisson's ratio, 0 to 0.5: the bulk modulus `K = E / (3 (1 - 2 nu))` of each
    /// tetrahedron's volume, with the energy `K (V - V0)^2 / (2 V0)` (0.5: its volume is kept
    /// as hard as the substeps can).
    pub poisson_ratio: f32,
    /// The share of velocity lost per second, from 0.
    pub damping_per_s: f32,
    /// The bending rigidity of its skin, newton metres: the hinge between two neighbouring
    /// surface triangles stores `3 B |e|^2 / (A1 + A2) (angle - rest)^2 / 2` (0: no skin).
    pub bending_rigidity_nm: f32,
}

impl Material {
    /// The compliance of an edge of rest length `length_m` over `volume_m3` of the body, metres
    /// per newton.
    pub(super) fn edge_compliance(&self, length_m: f32, volume_m3: f32) -> f32 {
        length_m * length_m / (self.young_modulus_pa * volume_m3)
    }

    /// The compliance of the constraint `6 (V - V0)` of a tetrahedron of rest volume
    /// `volume_m3`, per joule and metres to the sixth.
    pub(super) fn volume_compliance(&self, volume_m3: f32) -> f32 {
        let bulk = self.young_modulus_pa / (3.0 * (1.0 - 2.0 * self.poisson_ratio).max(0.0));
        36.0 * volume_m3 / bulk
    }

    /// The compliance of a hinge's angle of `weight` (`3 |e|^2 / (A1 + A2)` at rest), per
    /// joule; infinite without a skin.
    pub(super) fn hinge_compliance(&self, weight: f32) -> f32 {
        1.0 / (self.bending_rigidity_nm * weight)
    }
}
