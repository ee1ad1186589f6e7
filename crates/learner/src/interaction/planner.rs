//! Move to Target for the interaction model (`docs/spec/planning.md` §3, §4).

use nalgebra::Vector2;

use super::algorithm::InteractionModel;
use crate::features::{
    apply_homogeneous, dist, episode_difference, global_vec, InteractionState, PairKey,
    INTERACTION_DIM, TARGET_FEATURES,
};
use crate::planning::{
    circle, exploration, norm2, scaled, APPROACH_SPEED, EPS_CLOSE, EPS_CLOSE_ENOUGH, REACHED,
};
use crate::types::{Action, ACTUATOR_ID};

/// `circle_interaction(ι_c, q)` (`docs/spec/planning.md` §4): the clamped distance
/// between the block and actuator extracted from `ι_c`, the block→actuator
/// vector `R(θ_ref)·ι_c[5:7]` and the actuator's angle `atan2(ι6, ι5)`.
#[must_use]
pub fn circle_interaction(current: &InteractionState, q: Vector2<f64>) -> Action {
    let c = &current.components;
    let e = current.extract();
    let d = dist(e.reference_id, &e.reference, e.secondary_id, &e.secondary);
    let r = global_vec(current.theta_ref, Vector2::new(c[5], c[6]));
    circle(d, r, c[6].atan2(c[5]), q)
}

impl InteractionModel {
    /// `get_action()` of `docs/spec/planning.md` §3 for the pair (target block,
    /// actuator). Without a current state for that pair (the model has seen
    /// no world with the block yet) there is nothing to plan from: (0, 0),
    /// the target kept *(decision)*.
    pub(super) fn get_action(&mut self, rng: &mut dyn rand::Rng) -> Action {
        let Some(goal) = self.goal else {
            return Action::ZERO;
        };
        let key = PairKey::new(goal.target.id, ACTUATOR_ID);
        let Some(current) = self.current.get(&key).copied() else {
            return Action::ZERO;
        };
        let d = episode_difference(&current, &goal.state);
        let [i, j, k] = TARGET_FEATURES;
        // `|(d_2, d_3, d_4)|`, summed left to right like every norm here.
        if ((d[i] * d[i] + d[j] * d[j]) + d[k] * d[k]).sqrt() < REACHED {
            self.goal = None;
            return Action::ZERO;
        }
        let mut target_difference = [0.0; INTERACTION_DIM];
        for f in TARGET_FEATURES {
            target_difference[f] = d[f];
        }
        let c = &current.components;
        let here = Vector2::new(c[5], c[6]);
        // The global AIM's preconditions are `[ι (8), a_local (2)]`
        // (checked when deserialising; anything else explores).
        let Some(&[_, _, _, _, _, qx, qy, _, ax, ay]) = self
            .inverse
            .preconditions_for(&target_difference)
            .as_deref()
        else {
            return exploration(global_vec(current.theta_ref, -here), rng);
        };
        let q = Vector2::new(qx, qy);
        let wanted = apply_homogeneous(&current.t, q);
        let now = apply_homogeneous(&current.t, here);
        let delta = wanted - now;
        let push = global_vec(current.theta_ref, Vector2::new(ax, ay));
        let distance = norm2(delta);
        if distance > EPS_CLOSE {
            return circle_interaction(&current, q);
        }
        if distance > EPS_CLOSE_ENOUGH {
            // No safety check in this model (`docs/spec/planning.md` §6).
            return Action::from_vector(scaled(delta, APPROACH_SPEED));
        }
        Action::from_vector(scaled(push, APPROACH_SPEED))
    }
}
