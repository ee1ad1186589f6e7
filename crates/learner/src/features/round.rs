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
    fn non_finite_values_pass_through() {
        assert!(r3(f64::NAN).is_nan());
        assert_eq!(r3(f64::INFINITY), f64::INFINITY);
    }
}
