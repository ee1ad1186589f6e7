//! Feature computation (`docs/spec/features.md`): the "domain knowledge given to the
//! models from outside".
//!
//! | `docs/spec/features.md` | Here |
//! |---|---|
//! | §1 parsing, yaw ↔ quaternion | [`parse_frame`], [`quaternion_to_yaw`], [`yaw_to_quaternion`] |
//! | `docs/spec/README.md` §5 rounding | [`r3`] |
//! | §2 frames and transforms | [`transform`], [`inverse_transform`], [`local_point`], [`local_vec`], [`global_point`], [`global_vec`] |
//! | §3 gate model features | [`relative_features`], [`local_change`], [`apply_local_change`], [`actuator_change`], [`apply_actuator_change`] |
//! | §4 shape table | [`Shape`] |
//! | §5 distance and closing | [`closest_point_on_segment`], [`dist_closing`], [`dist`] |
//! | §6 interaction model features | [`InteractionState`], [`local_action`], [`episode_difference`], [`changed_features`], [`interaction_states`], [`poses_from_states`], [`target_interaction_state`] |
//!
//! Component order, rounding and the evaluation order of every sum are the
//! spec's: the learners' thresholds are one rounding unit wide, so a
//! reordered sum can change a learned map.

mod distance;
mod gate;
mod interaction;
mod parse;
mod round;
mod shape;
mod transform;

pub use distance::{
    closest_point_on_segment, dist, dist_closing, dist_closing_at, Body, DistClosing,
};
pub use gate::{
    actuator_change, apply_actuator_change, apply_actuator_change_at, apply_local_change,
    apply_local_change_at, local_change, local_change_at, relative_features, relative_features_at,
    DEFAULT_PREDICTION_BOOST, LOCAL_CHANGE_DIM, RELATIVE_FEATURES_DIM,
};
pub use interaction::{
    changed_features, episode_difference, interaction_states, local_action, poses_from_states,
    target_interaction_state, ExtractedPair, InteractionState, PairKey, PairKeyError,
    EPS_NOISE_100HZ, EPS_NOISE_10HZ, INTERACTION_DIM, INTERACTION_INPUT_DIM, TARGET_FEATURES,
};
pub use parse::{
    is_skipped, parse_frame, parse_frame_at, parse_observation, parse_observation_at,
    quaternion_to_yaw, yaw_to_quaternion, ActuatorYaw, ParseError,
};
pub use round::{r3, r3_vec, Precision};
pub use shape::{Shape, ACTUATOR_SHAPE, BLUE_SHAPE, POINT_SHAPE, RED_SHAPE};
pub use transform::{
    apply_homogeneous, global_point, global_vec, inverse_transform, local_point, local_vec,
    mat_mul, transform,
};

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::r3;

    proptest! {
        #[test]
        fn r3_is_idempotent(v in -1.0e6f64..1.0e6) {
            let once = r3(v);
            prop_assert_eq!(r3(once).to_bits(), once.to_bits());
        }

        #[test]
        fn r3_is_within_half_a_unit(v in -1.0e3f64..1.0e3) {
            prop_assert!((r3(v) - v).abs() <= 0.000_5 + 1e-12);
        }
    }
}
