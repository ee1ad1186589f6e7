//! Gate model features (`docs/spec/features.md` §3).

use nalgebra::Vector2;

use super::distance::{dist_closing_at, Body};
use super::round::Precision;
use super::transform::{global_vec, local_point, local_vec};
use crate::types::{ObjectState, TrackedObject};

/// Number of relative interaction features φ.
pub const RELATIVE_FEATURES_DIM: usize = 8;
/// Number of components of a local change Δ (and of the actuator change).
pub const LOCAL_CHANGE_DIM: usize = 3;
/// The prediction boost of the evaluated configuration (`docs/spec/README.md` §6; the
/// unused flag 64 of the original set 1.5).
pub const DEFAULT_PREDICTION_BOOST: f64 = 1.0;

/// Relative interaction features `φ(ref, other)` (`docs/spec/features.md` §3.2):
/// `[id_ref, id_other, distance, closing, rel_x, rel_y, v_other_x, v_other_y]`.
///
/// `reference` is the block, `other` the actuator. The distance is the signed
/// one (not clamped); components 6–7 are the other object's own displacement
/// rotated into the reference frame, not the difference of displacements
/// (`docs/spec/features.md` §8: follow the code).
#[must_use]
pub fn relative_features(
    reference: &TrackedObject,
    other: &TrackedObject,
) -> [f64; RELATIVE_FEATURES_DIM] {
    relative_features_at(reference, other, Precision::Thesis)
}

/// [`relative_features`] rounded at `precision`.
#[must_use]
pub fn relative_features_at(
    reference: &TrackedObject,
    other: &TrackedObject,
    precision: Precision,
) -> [f64; RELATIVE_FEATURES_DIM] {
    let dc = dist_closing_at(&Body::from(reference), &Body::from(other), precision);
    let (theta, p) = (reference.s.theta, reference.s.position());
    let rel = precision.round_vec(local_point(theta, p, other.s.position()));
    let vel = precision.round_vec(local_vec(theta, other.velocity()));
    [
        f64::from(reference.id),
        f64::from(other.id),
        dc.distance,
        dc.closing,
        rel.x,
        rel.y,
        vel.x,
        vel.y,
    ]
}

/// Local change `Δ(pre, post)` in the frame of `pre` (`docs/spec/features.md` §3.3):
/// rounded rotated position change, raw (unrounded, unwrapped) yaw change.
/// Also the planning target difference `Δ(current block, target)`.
#[must_use]
pub fn local_change(pre: &ObjectState, post: &ObjectState) -> [f64; LOCAL_CHANGE_DIM] {
    local_change_at(pre, post, Precision::Thesis)
}

/// [`local_change`] rounded at `precision`.
#[must_use]
pub fn local_change_at(
    pre: &ObjectState,
    post: &ObjectState,
    precision: Precision,
) -> [f64; LOCAL_CHANGE_DIM] {
    let dp = Vector2::new(post.x - pre.x, post.y - pre.y);
    let l = precision.round_vec(local_vec(pre.theta, dp));
    [l.x, l.y, post.theta - pre.theta]
}

/// A global state from the current state `s` and a predicted local change
/// (`docs/spec/features.md` §3.4): `(p + r3(R(θ)·b·Δ̂[0:2]), θ + b·Δ̂[2])` with boost `b`.
///
/// The boost scales the predicted change before it is rotated and rounded
/// *(decision: the spec only says the change is multiplied by it; with the
/// evaluated boost 1.0 the placement makes no difference)*. The sum is not
/// rounded again.
#[must_use]
pub fn apply_local_change(
    s: &ObjectState,
    delta: [f64; LOCAL_CHANGE_DIM],
    boost: f64,
) -> ObjectState {
    apply_local_change_at(s, delta, boost, Precision::Thesis)
}

/// [`apply_local_change`] rounded at `precision`.
#[must_use]
pub fn apply_local_change_at(
    s: &ObjectState,
    delta: [f64; LOCAL_CHANGE_DIM],
    boost: f64,
    precision: Precision,
) -> ObjectState {
    let g = precision.round_vec(global_vec(
        s.theta,
        Vector2::new(delta[0] * boost, delta[1] * boost),
    ));
    ObjectState {
        x: s.x + g.x,
        y: s.y + g.y,
        theta: s.theta + delta[2] * boost,
    }
}

/// The actuator model's training output: the plain global difference
/// `new − old` (`docs/spec/features.md` §3.5).
#[must_use]
pub fn actuator_change(old: &ObjectState, new: &ObjectState) -> [f64; LOCAL_CHANGE_DIM] {
    [new.x - old.x, new.y - old.y, new.theta - old.theta]
}

/// The predicted actuator state `r3(s + Δ̂)` (`docs/spec/features.md` §3.5).
#[must_use]
pub fn apply_actuator_change(s: &ObjectState, delta: [f64; LOCAL_CHANGE_DIM]) -> ObjectState {
    apply_actuator_change_at(s, delta, Precision::Thesis)
}

/// [`apply_actuator_change`] rounded at `precision`.
#[must_use]
pub fn apply_actuator_change_at(
    s: &ObjectState,
    delta: [f64; LOCAL_CHANGE_DIM],
    precision: Precision,
) -> ObjectState {
    ObjectState {
        x: precision.round(s.x + delta[0]),
        y: precision.round(s.y + delta[1]),
        theta: precision.round(s.theta + delta[2]),
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::{FRAC_PI_2, PI};

    use super::*;
    use crate::types::{ACTUATOR_ID, BLUE_ID};

    fn assert_close<const N: usize>(got: [f64; N], want: [f64; N]) {
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() < 1e-4, "got {got:?}, want {want:?}");
        }
    }

    /// docs/spec/features.md §7 example 1.
    #[test]
    fn example_1_relative_features() {
        let block = TrackedObject::fresh(BLUE_ID, ObjectState::new(0.0, 0.5, 0.0));
        let act = TrackedObject::fresh(ACTUATOR_ID, ObjectState::new(0.0, 0.0, 0.0));
        let phi = relative_features(&block, &act);
        assert_eq!(phi, [15.0, 8.0, 0.425, 0.0, 0.0, -0.5, 0.0, 0.0]);

        let moving = TrackedObject {
            s_prev: ObjectState::new(0.0, -0.005, 0.0),
            ..act
        };
        let phi = relative_features(&block, &moving);
        assert_eq!(phi, [15.0, 8.0, 0.425, -0.005, 0.0, -0.5, 0.0, 0.005]);
    }

    #[test]
    fn velocity_features_are_the_others_own_displacement() {
        // Both move up by 0.005: closing is 0 (relative motion), but φ[6:8]
        // is the actuator's own displacement, not the difference (docs/spec/features.md §8).
        let block = TrackedObject {
            id: BLUE_ID,
            s: ObjectState::new(0.0, 0.5, 0.0),
            s_prev: ObjectState::new(0.0, 0.495, 0.0),
        };
        let act = TrackedObject {
            id: ACTUATOR_ID,
            s: ObjectState::new(0.0, 0.0, 0.0),
            s_prev: ObjectState::new(0.0, -0.005, 0.0),
        };
        let phi = relative_features(&block, &act);
        assert_eq!(phi[3], 0.0);
        assert_eq!([phi[6], phi[7]], [0.0, 0.005]);
        // In a block turned by π/2 the same global +y displacement is local +x (R(θ)ᵀ v).
        let turned = TrackedObject {
            s: ObjectState::new(0.0, 0.5, FRAC_PI_2),
            s_prev: ObjectState::new(0.0, 0.5, FRAC_PI_2),
            ..block
        };
        let phi = relative_features(&turned, &act);
        assert_close([phi[4], phi[5], phi[6], phi[7]], [-0.5, 0.0, 0.005, 0.0]);
    }

    #[test]
    fn distance_feature_is_not_clamped() {
        let block = TrackedObject::fresh(BLUE_ID, ObjectState::new(0.0, 0.5, 0.0));
        let act = TrackedObject::fresh(ACTUATOR_ID, ObjectState::new(0.0, 0.44, 0.0));
        assert_eq!(relative_features(&block, &act)[2], -0.015);
    }

    /// docs/spec/features.md §7 example 4.
    #[test]
    fn example_4_local_change() {
        let d = local_change(
            &ObjectState::new(0.0, 0.5, 0.0),
            &ObjectState::new(-0.001, 0.501, 0.5),
        );
        assert_close(d, [-0.001, 0.001, 0.5]);
        let d = local_change(
            &ObjectState::new(0.0, 0.5, FRAC_PI_2),
            &ObjectState::new(0.0, 0.55, FRAC_PI_2),
        );
        assert_close(d, [0.05, 0.0, 0.0]);
        // Exact equality where the components are rounded.
        assert_eq!([d[0], d[1]], [0.05, 0.0]);
    }

    #[test]
    fn local_change_rounds_position_but_not_angle() {
        let d = local_change(
            &ObjectState::new(0.0, 0.0, 0.0),
            &ObjectState::new(0.000_4, 0.001_6, 0.000_4),
        );
        assert_eq!(d, [0.0, 0.002, 0.000_4]);
    }

    #[test]
    fn angles_are_never_wrapped() {
        // Turning past ±π: 3.1 → −3.1 is a change of −6.2, not +0.083.
        let d = local_change(
            &ObjectState::new(0.0, 0.0, 3.1),
            &ObjectState::new(0.0, 0.0, -3.1),
        );
        assert!((d[2] - -6.2).abs() < 1e-12);
        let s = apply_local_change(&ObjectState::new(0.0, 0.0, 3.1), [0.0, 0.0, 0.1], 1.0);
        assert!((s.theta - 3.2).abs() < 1e-12 && s.theta > PI);
        let a = actuator_change(
            &ObjectState::new(0.0, 0.0, -PI),
            &ObjectState::new(0.0, 0.0, PI),
        );
        assert!((a[2] - 2.0 * PI).abs() < 1e-12);
    }

    #[test]
    fn apply_local_change_rotates_and_rounds_the_position_only() {
        let s = ObjectState::new(0.0, 0.5, FRAC_PI_2);
        let got = apply_local_change(&s, [0.05, 0.000_4, 0.012_34], 1.0);
        // R(π/2)·(0.05, 0.0004) = (−0.0004, 0.05) → rounded (−0.0, 0.05).
        assert_eq!(got.x, 0.0);
        assert!((got.y - 0.55).abs() < 1e-12);
        assert_eq!(got.theta, FRAC_PI_2 + 0.012_34);
        // Inverse of local_change on rounded changes.
        let pre = ObjectState::new(0.1, 0.2, 0.3);
        let post = ObjectState::new(0.113, 0.191, 0.35);
        let back = apply_local_change(&pre, local_change(&pre, &post), DEFAULT_PREDICTION_BOOST);
        assert!(back.distance_to(&post) < 1.5e-3);
    }

    #[test]
    fn boost_scales_the_change() {
        let s = ObjectState::new(0.0, 0.0, 0.0);
        let got = apply_local_change(&s, [0.002, 0.004, 0.1], 1.5);
        assert_eq!((got.x, got.y), (0.003, 0.006));
        assert!((got.theta - 0.15).abs() < 1e-15);
    }

    #[test]
    fn actuator_change_and_prediction() {
        let old = ObjectState::new(0.1, 0.2, 0.0);
        let new = ObjectState::new(0.1, 0.205, 0.0);
        let d = actuator_change(&old, &new);
        assert_eq!(d, [0.0, 0.205 - 0.2, 0.0]);
        let p = apply_actuator_change(&new, [0.000_4, 0.005_000_1, 0.0]);
        assert_eq!(p, ObjectState::new(0.1, 0.21, 0.0));
    }
}
