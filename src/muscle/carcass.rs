//! The arm skeleton a muscle is attached to: two rods joined at the elbow.
//!
//! Rod 1 runs from its free end (the shoulder) to the elbow; the muscle is attached `a1` from
//! its free end, `b1` before the elbow. Rod 2 runs from the elbow to its free end (the hand);
//! the muscle is attached `a2` after the elbow, `b2` before the free end. The muscle spans the
//! two attachments, so its length `L` fixes the elbow: by the law of cosines the interior
//! angle is `alpha = acos((b1^2 + a2^2 - L^2) / (2 b1 a2))` and the flexion is `180 deg - alpha`.

/// The carcass configuration: rod lengths either side of the attachments, and thickness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Carcass {
    /// Free end of rod 1 to the muscle's attachment on rod 1.
    pub a1: f64,
    /// Attachment on rod 1 to the elbow.
    pub b1: f64,
    /// Elbow to the attachment on rod 2.
    pub a2: f64,
    /// Attachment on rod 2 to the free end of rod 2.
    pub b2: f64,
    /// Rod thickness (diameter).
    pub thickness: f64,
}

/// A length clamped into the range the carcass can take, and why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clamped<T> {
    /// The usable value.
    pub value: T,
    /// Set when the input was outside the possible range.
    pub note: Option<&'static str>,
}

impl Carcass {
    /// Shortest and longest muscle lengths the elbow allows: `|b1 - a2|` and `b1 + a2`.
    pub fn length_range(&self) -> (f64, f64) {
        ((self.b1 - self.a2).abs(), self.b1 + self.a2)
    }

    /// The elbow flexion in radians (0 = straight arm) for muscle length `length`, clamped to
    /// the triangle inequality.
    pub fn flexion_from_length(&self, length: f64) -> Clamped<f64> {
        let (min, max) = self.length_range();
        let note = if length < min {
            Some("the muscle is shorter than the arm allows: flexion clamped to fully bent")
        } else if length > max {
            Some("the muscle is longer than the arm allows: flexion clamped to straight")
        } else {
            None
        };
        let length = length.clamp(min, max);
        let cos_alpha =
            ((self.b1 * self.b1 + self.a2 * self.a2 - length * length) / (2.0 * self.b1 * self.a2)).clamp(-1.0, 1.0);
        Clamped { value: std::f64::consts::PI - cos_alpha.acos(), note }
    }

    /// The muscle length for an elbow flexion in radians, clamped to `[0, pi]`.
    pub fn length_from_flexion(&self, flexion: f64) -> Clamped<f64> {
        let note = if !(0.0..=std::f64::consts::PI).contains(&flexion) {
            Some("flexion is outside 0 to 180 degrees: clamped")
        } else {
            None
        };
        let flexion = flexion.clamp(0.0, std::f64::consts::PI);
        let squared = self.b1 * self.b1 + self.a2 * self.a2 + 2.0 * self.b1 * self.a2 * flexion.cos();
        Clamped { value: squared.max(0.0).sqrt(), note }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ARM: Carcass = Carcass { a1: 30.0, b1: 230.0, a2: 30.0, b2: 120.0, thickness: 5.0 };

    #[test]
    fn flexion_and_length_are_inverse() {
        for degrees in [0.0f64, 15.0, 30.0, 60.0, 90.0, 135.0, 180.0] {
            let length = ARM.length_from_flexion(degrees.to_radians()).value;
            let back = ARM.flexion_from_length(length).value.to_degrees();
            assert!((back - degrees).abs() < 1e-6, "{degrees} -> {length} -> {back}");
        }
    }

    #[test]
    fn a_straight_arm_stretches_the_muscle_to_the_sum_of_the_segments() {
        assert!((ARM.length_from_flexion(0.0).value - 260.0).abs() < 1e-9);
        assert!(
            (ARM.length_from_flexion(std::f64::consts::FRAC_PI_2).value - (230.0f64.powi(2) + 900.0).sqrt()).abs()
                < 1e-9
        );
    }

    #[test]
    fn impossible_lengths_are_clamped_with_a_note() {
        let long = ARM.flexion_from_length(300.0);
        assert_eq!(long.value, 0.0);
        assert!(long.note.is_some());
        let short = ARM.flexion_from_length(100.0);
        assert!((short.value - std::f64::consts::PI).abs() < 1e-12);
        assert!(short.note.is_some());
        assert!(ARM.flexion_from_length(250.0).note.is_none());
    }
}
