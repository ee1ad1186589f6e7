//! Orientations on the wire: a yaw about the world z axis as the quaternion
//! `[x, y, z, w]` the protocol carries, and back; and the normalisation the
//! world applies to the quaternions it is sent.
//!
//! The learner crate has its own spec-exact copy of these formulas
//! (`learner::features::{quaternion_to_yaw, yaw_to_quaternion}`,
//! `docs/spec/features.md` §1): the learner depends on nothing of ours, and the
//! protocol must not depend on the learner, so neither can call the other.
//! The two are kept equal bit for bit by the property tests below, which run
//! both on the same inputs.

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
/// components.
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
        fn yaw_is_the_learners_bit_for_bit(q in proptest::array::uniform4(component())) {
            let ours = yaw(q);
            let learners = learner::features::quaternion_to_yaw(q);
            prop_assert!(
                ours.to_bits() == learners.to_bits() || (ours.is_nan() && learners.is_nan()),
                "{q:?}: wire {ours} vs learner {learners}"
            );
        }

        #[test]
        fn from_yaw_is_the_learners_bit_for_bit(theta in prop_oneof![-10.0..10.0_f64, any::<f64>()]) {
            let ours = from_yaw(theta).map(f64::to_bits);
            let learners = learner::features::yaw_to_quaternion(theta).map(f64::to_bits);
            prop_assert_eq!(ours, learners);
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
    }
}
