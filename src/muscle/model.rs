//! The volume-preserving node model of a muscle (f64 throughout).
//!
//! `n >= 2` nodes lie on the muscle's axis at spacing `dx = len / (n - 1)`; node `i` has a
//! radius `r[i]` and a growth multiplier `m[i]`. The surface is the chain of frusta between
//! neighbouring nodes, of volume `V = pi * dx * F(r)` with
//! `F(r) = sum (r[i]^2 + r[i] r[i+1] + r[i+1]^2) / 3`.
//!
//! A new length gives `dx'`; every radius moves by `m[i] * d`, with `d` the root of
//! `A d^2 + B d + C = 0` that keeps `dx' F(r + m d) = dx F(r)`:
//! `A = sum (m[i]^2 + m[i] m[i+1] + m[i+1]^2) / 3`,
//! `B = sum (2 r[i] m[i] + r[i] m[i+1] + r[i+1] m[i] + 2 r[i+1] m[i+1]) / 3`,
//! `C = F(r) (1 - dx / dx')`. The state is always computed from the rest state, so it depends
//! only on the current length, never on the path taken to it.

use std::f64::consts::PI;

/// Why a length was refused; the model keeps its last valid state.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum Refusal {
    /// The node spacing would leave the configured bounds.
    #[error("length {length:.3} is outside the allowed range {min:.3} to {max:.3}")]
    OutOfBounds {
        /// The length asked for.
        length: f64,
        /// Shortest allowed length.
        min: f64,
        /// Longest allowed length.
        max: f64,
    },
    /// No radius change keeps the volume at this length.
    #[error("no radius change keeps the volume at length {length:.3}")]
    NoRoot {
        /// The length asked for.
        length: f64,
    },
    /// Keeping the volume would make a radius zero or negative.
    #[error("node {node} would reach a radius of {radius:.3} (must stay above 0) at length {length:.3}")]
    RadiusVanishes {
        /// The first node concerned.
        node: usize,
        /// The radius it would get.
        radius: f64,
        /// The length asked for.
        length: f64,
    },
}

/// Why a rest configuration is not a muscle.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// Fewer than two nodes.
    #[error("a muscle needs at least 2 nodes, found {0}")]
    TooFewNodes(usize),
    /// `radii` and `grow_mults` differ in length.
    #[error("radiuses has {radii} values but grow_mults has {mults}: they must match")]
    LengthMismatch {
        /// Number of radii.
        radii: usize,
        /// Number of multipliers.
        mults: usize,
    },
    /// A radius is not a positive finite number.
    #[error("radiuses[{0}] must be a finite number greater than 0, found {1}")]
    BadRadius(usize, f64),
    /// A multiplier is not finite.
    #[error("grow_mults[{0}] must be a finite number, found {1}")]
    BadMultiplier(usize, f64),
    /// The rest length is not a positive finite number.
    #[error("len must be a finite number greater than 0, found {0}")]
    BadLength(f64),
    /// The muscle has no configuration, inline or from a file.
    #[error("a muscle needs muscle_config and carcass_config, inline or from a `file`")]
    Missing,
    /// Growth is to be fitted to the measurements, and the model is not laid out as they are.
    #[error(
        "fit_growth fits the real biceps' nine measured nodes between two end nodes: the model needs 11 nodes, found {0}"
    )]
    NotMeasuredLayout(usize),
    /// Growth is to be fitted, and the configured multipliers cannot reach every flexion
    /// measured to start from.
    #[error(
        "fit_growth starts from grow_mults, and with them the arm cannot reach all of 0, 30, 60 and 90 degrees of flexion"
    )]
    NoFitFrom,
    /// The bounds on the node spacing are not `0 < min_part <= 1 <= max_part`.
    #[error("min_part and max_part must satisfy 0 < min_part <= 1 <= max_part, found {0} and {1}")]
    BadBounds(f64, f64),
}

/// `F(r)`: the sum over segments of `(r[i]^2 + r[i] r[i+1] + r[i+1]^2) / 3`.
pub fn frusta_sum(radii: &[f64]) -> f64 {
    radii.windows(2).map(|w| (w[0] * w[0] + w[0] * w[1] + w[1] * w[1]) / 3.0).sum()
}

/// Volume of the chain of frusta with node spacing `dx`.
pub fn chain_volume(dx: f64, radii: &[f64]) -> f64 {
    PI * dx * frusta_sum(radii)
}

/// A muscle: its rest configuration, bounds and current state.
#[derive(Debug, Clone, PartialEq)]
pub struct Muscle {
    rest_radii: Vec<f64>,
    mults: Vec<f64>,
    rest_length: f64,
    min_part: f64,
    max_part: f64,
    length: f64,
    radii: Vec<f64>,
}

impl Muscle {
    /// A muscle at rest. `min_part` and `max_part` bound the node spacing relative to the
    /// rest spacing.
    pub fn new(
        radii: Vec<f64>,
        mults: Vec<f64>,
        length: f64,
        min_part: f64,
        max_part: f64,
    ) -> Result<Self, ConfigError> {
        if radii.len() != mults.len() {
            return Err(ConfigError::LengthMismatch { radii: radii.len(), mults: mults.len() });
        }
        if radii.len() < 2 {
            return Err(ConfigError::TooFewNodes(radii.len()));
        }
        if let Some((i, &r)) = radii.iter().enumerate().find(|(_, r)| !(r.is_finite() && **r > 0.0)) {
            return Err(ConfigError::BadRadius(i, r));
        }
        if let Some((i, &m)) = mults.iter().enumerate().find(|(_, m)| !m.is_finite()) {
            return Err(ConfigError::BadMultiplier(i, m));
        }
        if !(length.is_finite() && length > 0.0) {
            return Err(ConfigError::BadLength(length));
        }
        if !(min_part > 0.0 && min_part <= 1.0 && max_part >= 1.0 && max_part.is_finite()) {
            return Err(ConfigError::BadBounds(min_part, max_part));
        }
        Ok(Self { radii: radii.clone(), rest_radii: radii, mults, rest_length: length, min_part, max_part, length })
    }

    /// The same muscle at rest with other growth multipliers, one per node.
    pub fn with_mults(&self, mults: Vec<f64>) -> Result<Self, ConfigError> {
        Self::new(self.rest_radii.clone(), mults, self.rest_length, self.min_part, self.max_part)
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.radii.len()
    }

    /// Current radii, one per node.
    pub fn radii(&self) -> &[f64] {
        &self.radii
    }

    /// Radii at rest.
    pub fn rest_radii(&self) -> &[f64] {
        &self.rest_radii
    }

    /// Growth multipliers.
    pub fn mults(&self) -> &[f64] {
        &self.mults
    }

    /// Current length.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// Rest length.
    pub fn rest_length(&self) -> f64 {
        self.rest_length
    }

    /// Current node spacing.
    pub fn node_spacing(&self) -> f64 {
        self.length / (self.nodes() - 1) as f64
    }

    /// The shortest and longest allowed lengths.
    pub fn length_bounds(&self) -> (f64, f64) {
        (self.rest_length * self.min_part, self.rest_length * self.max_part)
    }

    /// Current volume of the chain of frusta.
    pub fn volume(&self) -> f64 {
        chain_volume(self.node_spacing(), &self.radii)
    }

    /// Volume at rest, which every state keeps.
    pub fn rest_volume(&self) -> f64 {
        chain_volume(self.rest_length / (self.nodes() - 1) as f64, &self.rest_radii)
    }

    /// The radii the muscle has at `length`, or why it cannot have that length.
    pub fn radii_at(&self, length: f64) -> Result<Vec<f64>, Refusal> {
        let (min, max) = self.length_bounds();
        if !(length.is_finite() && length >= min && length <= max) {
            return Err(Refusal::OutOfBounds { length, min, max });
        }
        let (r, m) = (&self.rest_radii, &self.mults);
        let pairs = || r.windows(2).zip(m.windows(2));
        let a: f64 = m.windows(2).map(|w| (w[0] * w[0] + w[0] * w[1] + w[1] * w[1]) / 3.0).sum();
        let b: f64 =
            pairs().map(|(r, m)| (2.0 * r[0] * m[0] + r[0] * m[1] + r[1] * m[0] + 2.0 * r[1] * m[1]) / 3.0).sum();
        // dx / dx' = rest length / length.
        let c = frusta_sum(r) * (1.0 - self.rest_length / length);
        let d = if c == 0.0 {
            0.0
        } else if a == 0.0 {
            // Every multiplier is zero: no radius can change.
            return Err(Refusal::NoRoot { length });
        } else {
            let discriminant = b * b - 4.0 * a * c;
            if discriminant < 0.0 {
                return Err(Refusal::NoRoot { length });
            }
            // The root through d = 0 at c = 0, in the cancellation-free form 2c / (-b -+ sqrt);
            // q is non-zero because c is.
            let q = -0.5 * (b + b.signum() * discriminant.sqrt());
            c / q
        };
        let radii: Vec<f64> = r.iter().zip(m).map(|(r, m)| r + m * d).collect();
        if let Some((node, &radius)) = radii.iter().enumerate().find(|(_, r)| **r <= 0.0) {
            return Err(Refusal::RadiusVanishes { node, radius, length });
        }
        Ok(radii)
    }

    /// Sets the length, keeping the volume; on refusal the state is unchanged.
    pub fn set_length(&mut self, length: f64) -> Result<(), Refusal> {
        self.radii = self.radii_at(length)?;
        self.length = length;
        Ok(())
    }

    /// Changes node `node`'s rest radius and multiplier, keeping the current length when it
    /// stays valid (else returning to the rest length).
    pub fn edit_node(&mut self, node: usize, radius: f64, mult: f64) -> Result<(), ConfigError> {
        if node >= self.nodes() {
            return Err(ConfigError::TooFewNodes(node + 1));
        }
        if !(radius.is_finite() && radius > 0.0) {
            return Err(ConfigError::BadRadius(node, radius));
        }
        if !mult.is_finite() {
            return Err(ConfigError::BadMultiplier(node, mult));
        }
        self.rest_radii[node] = radius;
        self.mults[node] = mult;
        if self.set_length(self.length).is_err() {
            self.length = self.rest_length;
            self.radii = self.rest_radii.clone();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The source's first configuration.
    fn biceps() -> Muscle {
        Muscle::new(
            vec![5.0, 5.0, 10.0, 15.0, 18.0, 18.0, 15.0, 10.0, 5.0, 5.0],
            vec![0.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 1.0, 1.0, 0.0],
            250.0,
            0.5,
            1.5,
        )
        .unwrap()
    }

    fn relative_error(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn the_volume_of_a_cylinder_chain_is_pi_r_squared_l() {
        let muscle = Muscle::new(vec![2.0; 5], vec![1.0; 5], 10.0, 0.5, 1.5).unwrap();
        assert!(relative_error(muscle.volume(), PI * 4.0 * 10.0) < 1e-15);
    }

    #[test]
    fn contraction_thickens_and_keeps_the_volume() {
        let mut muscle = biceps();
        let rest = muscle.rest_volume();
        muscle.set_length(230.0).unwrap();
        assert!(relative_error(muscle.volume(), rest) < 1e-13, "{}", relative_error(muscle.volume(), rest));
        assert!(muscle.radii()[4] > 18.0);
        // End nodes have zero multipliers and keep their radius.
        assert_eq!(muscle.radii()[0], 5.0);
        muscle.set_length(270.0).unwrap();
        assert!(muscle.radii()[4] < 18.0);
        assert!(relative_error(muscle.volume(), rest) < 1e-13);
    }

    #[test]
    fn refusals_keep_the_last_valid_state() {
        let mut muscle = biceps();
        muscle.set_length(240.0).unwrap();
        let before = muscle.clone();
        assert!(matches!(muscle.set_length(100.0), Err(Refusal::OutOfBounds { .. })));
        assert!(matches!(muscle.set_length(f64::NAN), Err(Refusal::OutOfBounds { .. })));
        assert_eq!(muscle, before);
        // A node with a large negative multiplier vanishes when the muscle stretches.
        let mut thinning = Muscle::new(vec![5.0, 1.0, 5.0], vec![1.0, -10.0, 1.0], 100.0, 0.5, 1.5).unwrap();
        let error = thinning.set_length(140.0).unwrap_err();
        assert!(matches!(error, Refusal::RadiusVanishes { node: 1, .. }), "{error}");
        assert_eq!(thinning.length(), 100.0);
        // No multipliers: nothing can change.
        let mut rigid = Muscle::new(vec![1.0, 1.0], vec![0.0, 0.0], 10.0, 0.5, 1.5).unwrap();
        assert!(matches!(rigid.set_length(9.0), Err(Refusal::NoRoot { .. })));
        assert!(rigid.set_length(10.0).is_ok());
    }

    #[test]
    fn bad_configurations_are_refused_with_the_field() {
        let error = Muscle::new(vec![1.0, 2.0], vec![1.0], 1.0, 0.5, 1.5).unwrap_err();
        assert_eq!(error.to_string(), "radiuses has 2 values but grow_mults has 1: they must match");
        assert!(matches!(Muscle::new(vec![1.0], vec![1.0], 1.0, 0.5, 1.5), Err(ConfigError::TooFewNodes(1))));
        assert!(matches!(
            Muscle::new(vec![1.0, 0.0], vec![1.0, 1.0], 1.0, 0.5, 1.5),
            Err(ConfigError::BadRadius(1, _))
        ));
        assert!(matches!(
            Muscle::new(vec![1.0, 1.0], vec![1.0, f64::NAN], 1.0, 0.5, 1.5),
            Err(ConfigError::BadMultiplier(1, _))
        ));
        assert!(matches!(Muscle::new(vec![1.0, 1.0], vec![1.0, 1.0], -1.0, 0.5, 1.5), Err(ConfigError::BadLength(_))));
        assert!(matches!(Muscle::new(vec![1.0, 1.0], vec![1.0, 1.0], 1.0, 1.5, 0.5), Err(ConfigError::BadBounds(..))));
    }

    #[test]
    fn editing_a_node_keeps_the_current_length() {
        let mut muscle = biceps();
        muscle.set_length(240.0).unwrap();
        muscle.edit_node(4, 20.0, 3.0).unwrap();
        assert_eq!(muscle.length(), 240.0);
        assert_eq!(muscle.rest_radii()[4], 20.0);
        assert!(relative_error(muscle.volume(), muscle.rest_volume()) < 1e-13);
    }

    /// A valid random configuration: radii in (1, 30), multipliers mostly positive.
    fn config() -> impl Strategy<Value = (Vec<f64>, Vec<f64>, f64)> {
        (2usize..40).prop_flat_map(|n| {
            (proptest::collection::vec(1.0f64..30.0, n), proptest::collection::vec(-0.5f64..5.0, n), 10.0f64..500.0)
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn volume_is_conserved_to_rounding((radii, mults, length) in config(), part in 0.6f64..1.4) {
            let mut muscle = Muscle::new(radii, mults, length, 0.5, 1.5).unwrap();
            let rest = muscle.rest_volume();
            if muscle.set_length(length * part).is_ok() {
                prop_assert!(relative_error(muscle.volume(), rest) < 1e-12, "{}", relative_error(muscle.volume(), rest));
                prop_assert!(muscle.radii().iter().all(|r| *r > 0.0 && r.is_finite()));
            }
        }

        #[test]
        fn a_round_trip_returns_the_rest_radii((radii, mults, length) in config(), part in 0.6f64..1.4) {
            let mut muscle = Muscle::new(radii, mults, length, 0.5, 1.5).unwrap();
            if muscle.set_length(length * part).is_ok() {
                muscle.set_length(length).unwrap();
                for (now, rest) in muscle.radii().iter().zip(muscle.rest_radii()) {
                    prop_assert!((now - rest).abs() <= 1e-12 * rest.abs().max(1.0), "{now} vs {rest}");
                }
            }
        }

        #[test]
        fn radii_move_monotonically_with_length(
            (radii, mults, length) in config(),
            a in 0.6f64..1.4,
            b in 0.6f64..1.4,
        ) {
            let mults: Vec<f64> = mults.iter().map(|m| m.abs() + 0.01).collect();
            let muscle = Muscle::new(radii, mults, length, 0.5, 1.5).unwrap();
            let (short, long) = (length * a.min(b), length * a.max(b));
            if let (Ok(at_short), Ok(at_long)) = (muscle.radii_at(short), muscle.radii_at(long)) {
                for (s, l) in at_short.iter().zip(&at_long) {
                    prop_assert!(s >= l, "shorter must be thicker: {s} < {l}");
                }
            }
        }
    }
}
