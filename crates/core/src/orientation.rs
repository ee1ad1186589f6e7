//! Orientations: a yaw about the world z axis as the quaternion `[x, y, z, w]`
//! the protocol carries, and back (`docs/spec/features.md` §1); the
//! normalisation the world applies to the quaternions it is sent; and the
//! world's own yaw of the unit quaternions it simulates.
//!
//! Two yaw formulas live here on purpose, each bit-fixed by published
//! numbers: [`yaw`] is the learners' (it normalises first; every parsed state
//! and so every result of `docs/results/` goes through it), [`unit_yaw`] is
//! the calibration sweep's (`docs/results.md` §2). They agree up to rounding
//! on unit quaternions, not bit for bit, so neither may replace the other.

/// The quaternion `[x, y, z, w] = [0, 0, sin(θ/2), cos(θ/2)]` of a rotation by
/// `yaw` radians about the world z axis.
#[must_use]
pub fn from_yaw(yaw: f64) -> [f64; 4] {
    let half = yaw / 2.0;
    [0.0, 0.0, half.sin(), half.cos()]
}

/// The unit quaternion of `q` (`[x, y, z, w]`, finite), or `None` for the
/// zero quaternion: how the world normalises a SetPose orientation.
///
/// Dividing by the largest component first keeps every finite quaternion
/// from under- or overflowing. [`yaw`] normalises differently (pre-scaling
/// only on overflow, as the learner's spec does), and the two may differ in
/// the last bit: this one feeds the physics, so its arithmetic is fixed by
/// the reference results (`docs/results/`), and [`yaw`]'s by the learner's.
#[must_use]
pub fn normalise(q: [f64; 4]) -> Option<[f64; 4]> {
    let largest = q.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if largest == 0.0 {
        return None;
    }
    let scaled = q.map(|x| x / largest);
    let norm = scaled.iter().map(|x| x * x).sum::<f64>().sqrt();
    Some(scaled.map(|x| x / norm))
}

/// The yaw of an orientation quaternion `[x, y, z, w]`, in `[-π, π]`:
/// normalised first, 0 for the zero quaternion, NaN for non-finite
/// components (`docs/spec/features.md` §1 step 2, unrounded).
#[must_use]
pub fn yaw(q: [f64; 4]) -> f64 {
    let [mut x, mut y, mut z, mut w] = q;
    let largest = x.abs().max(y.abs()).max(z.abs()).max(w.abs());
    if largest == 0.0 {
        return 0.0;
    }
    let mut norm = (x * x + y * y + z * z + w * w).sqrt();
    if !norm.is_normal() {
        // The squares overflowed or underflowed although the quaternion is not
        // zero: pre-scaling by the largest component keeps the result finite,
        // and changes nothing for the unit quaternions the world sends.
        (x, y, z, w) = (x / largest, y / largest, z / largest, w / largest);
        norm = (x * x + y * y + z * z + w * w).sqrt();
    }
    (x, y, z, w) = (x / norm, y / norm, z / norm, w / norm);
    (2.0 * (x * y + w * z)).atan2(w * w + x * x - y * y - z * z)
}

/// The yaw, in (−π, π], of a quaternion `[x, y, z, w]` already of unit norm,
/// as the world reports its bodies' (the calibration sweep,
/// `docs/results.md` §2): not normalised, and with the denominator written
/// `1 − 2(y² + z²)`, so it differs from [`yaw`] in the last bits.
#[must_use]
pub fn unit_yaw(q: [f64; 4]) -> f64 {
    let [x, y, z, w] = q;
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    fn component() -> impl Strategy<Value = f64> {
        prop_oneof![
            -2.0..2.0_f64,
            Just(0.0),
            Just(-0.0),
            -1e300..1e300_f64,
            -1e-300..1e-300_f64,
            any::<f64>(),
        ]
    }

    proptest! {
        #[test]
        fn a_unit_yaw_is_the_yaw_up_to_rounding(theta in -10.0..10.0_f64) {
            let q = from_yaw(theta);
            prop_assert!((unit_yaw(q) - yaw(q)).abs() < 1e-12, "{theta}");
        }

        #[test]
        fn any_quaternion_has_a_yaw_in_range_or_nan(q in proptest::array::uniform4(component())) {
            // Non-finite components give NaN, except a NaN among zeros, which
            // `f64::max` passes over to find the zero quaternion: parsing refuses
            // non-finite components before it asks for a yaw.
            let theta = yaw(q);
            let in_range = (-std::f64::consts::PI..=std::f64::consts::PI).contains(&theta);
            if q.iter().all(|c| c.is_finite()) {
                prop_assert!(in_range, "{q:?}: {theta}");
            } else {
                prop_assert!(in_range || theta.is_nan(), "{q:?}: {theta}");
            }
        }
    }

    #[test]
    fn normalise_gives_unit_quaternions_at_any_scale() {
        assert_eq!(normalise([0.0; 4]), None);
        assert_eq!(normalise([0.0, 0.0, 0.0, -0.0]), None);
        // Powers of two: the scaled components are exact, so the result is too.
        for scale in [f64::MIN_POSITIVE, 0.5, 1.0, 2.0, 2f64.powi(1000)] {
            let q = normalise([0.0, 0.0, 3.0 * scale, 4.0 * scale]).unwrap();
            assert_eq!(q, [0.0, 0.0, 0.6, 0.8], "scale {scale}");
        }
        let q = normalise([1e308, -1e308, 1e308, 1e308]).unwrap();
        assert_eq!(q, [0.5, -0.5, 0.5, 0.5]);
    }

    #[test]
    fn a_yaw_survives_the_round_trip() {
        for theta in [-3.0, -1.0, 0.0, 0.5, 3.1] {
            assert!((yaw(from_yaw(theta)) - theta).abs() < 1e-15, "{theta}");
        }
        assert_eq!(yaw([0.0; 4]), 0.0);
        // Scale does not matter, even where the squares overflow or underflow.
        for scale in [1e-200, 1e200, 1e300] {
            let q = from_yaw(0.5).map(|c| c * scale);
            assert!((yaw(q) - 0.5).abs() < 1e-15, "{scale}");
        }
        assert!(yaw([f64::NAN, 0.0, 0.0, 1.0]).is_nan());
    }
}
