//! The 3-decimal rounding `r3` (`docs/spec/README.md` §5), the system's only noise filter.

use nalgebra::Vector2;

/// `r3(v) = rint(v · 1000) / 1000`, ties to even (`docs/spec/README.md` §5).
///
/// The multiplication comes first and the tie is decided on the product, as
/// the original's `numpy.round(v, 3)` did; so e.g. `r3(0.0005) == 0.0`,
/// `r3(0.0015) == 0.002`, and `r3(-0.0005)` is `-0.0`.
#[must_use]
pub fn r3(v: f64) -> f64 {
    (v * 1000.0).round_ties_even() / 1000.0
}

/// `r3` component-wise.
#[must_use]
pub fn r3_vec(v: Vector2<f64>) -> Vector2<f64> {
    Vector2::new(r3(v.x), r3(v.y))
}

/// Where the gate model's features and predictions round: to 3 decimals as
/// the thesis did ([`r3`]), or not at all (the improved model's `unrounded`
/// change, `docs/models.md` "Beyond the thesis").
///
/// The rounding was the original's only noise filter; it also quantises a
/// predicted step of a few millimetres to whole millimetres, an error a
/// 150-step prediction chain accumulates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    /// `r3` everywhere the specification rounds.
    Thesis,
    /// Full `f64` precision.
    Full,
}

impl Precision {
    /// `v` at this precision.
    #[must_use]
    pub fn round(self, v: f64) -> f64 {
        match self {
            Precision::Thesis => r3(v),
            Precision::Full => v,
        }
    }

    /// [`Precision::round`] component-wise.
    #[must_use]
    pub fn round_vec(self, v: Vector2<f64>) -> Vector2<f64> {
        Vector2::new(self.round(v.x), self.round(v.y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ties_go_to_even() {
        assert_eq!(r3(0.0005), 0.0);
        assert_eq!(r3(0.0015), 0.002);
        assert_eq!(r3(0.0025), 0.002);
        assert_eq!(r3(0.0035), 0.004);
        assert_eq!(r3(-0.0015), -0.002);
        assert_eq!(r3(2.5e-3 + 1e-12), 0.003);
    }

    #[test]
    fn negative_half_unit_rounds_to_negative_zero() {
        let z = r3(-0.0005);
        assert_eq!(z, 0.0);
        assert!(z.is_sign_negative());
        assert!(r3(0.0005).is_sign_positive());
    }

    #[test]
    fn ordinary_values() {
        assert_eq!(r3(0.4249999), 0.425);
        assert_eq!(r3(-0.4994), -0.499);
        assert_eq!(r3(1.0), 1.0);
        assert_eq!(r3(-2.934_500_1), -2.935);
        assert_eq!(
            r3_vec(Vector2::new(0.12345, -0.00049)),
            Vector2::new(0.123, -0.0)
        );
    }

    #[test]
    fn full_precision_keeps_every_bit_and_thesis_precision_is_r3() {
        for v in [0.0005, 0.0015, -0.0005, 0.123_456_789, 1e-9] {
            assert_eq!(Precision::Full.round(v).to_bits(), v.to_bits());
            assert_eq!(Precision::Thesis.round(v).to_bits(), r3(v).to_bits());
        }
        let v = Vector2::new(0.12345, -0.00049);
        assert_eq!(Precision::Thesis.round_vec(v), r3_vec(v));
        assert_eq!(Precision::Full.round_vec(v), v);
    }

    #[test]
    fn non_finite_values_pass_through() {
        assert!(r3(f64::NAN).is_nan());
        assert_eq!(r3(f64::INFINITY), f64::INFINITY);
    }
}
