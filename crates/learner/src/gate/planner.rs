//! Move to Target with the gate model: `get_action()` (`docs/spec/planning.md` §2),
//! circling (§4) and the exploration fallback (§5).

use nalgebra::Vector2;
use rand::Rng;

use super::algorithm::GateModel;
use crate::features::{global_point, global_vec, relative_features};
use crate::planning::{
    circle, exploration, norm2, scaled, APPROACH_SPEED, EPS_CLOSE, EPS_CLOSE_ENOUGH, REACHED,
};
use crate::types::{Action, ObjectState, TrackedObject};

/// The precondition's motion passes through unscaled strictly inside
/// (`PASS_MIN`, `PASS_MAX`) or when it is zero.
pub const PASS_MIN: f64 = 0.01;
/// See [`PASS_MIN`].
pub const PASS_MAX: f64 = 0.2;

impl GateModel {
    /// `get_action()` of `docs/spec/planning.md` §2, from the model's actuator and its
    /// record of the target block.
    pub(super) fn get_action(&mut self, rng: &mut dyn Rng) -> Action {
        let Some(target) = self.target else {
            return Action::ZERO;
        };
        // set_target and deserialisation guarantee both; (0, 0) otherwise.
        let (Some(act), Some(b)) = (self.actuator, self.block(target.id)) else {
            return Action::ZERO;
        };
        let goal = target.pose;
        if b.s.distance_to(&goal) < REACHED {
            self.target = None;
            return Action::ZERO;
        }
        let d = self.local_change(&b.s, &goal);
        let pre = self
            .predictor_mut(b.id)
            .and_then(|p| p.inverse.preconditions_for(&d));
        let Some(pre) = pre else {
            return exploration(b.s.position() - act.s.position(), rng);
        };
        let q = Vector2::new(pre[4], pre[5]);
        let p_star = global_point(b.s.theta, b.s.position(), q);
        let v_star = global_vec(b.s.theta, Vector2::new(pre[6], pre[7]));
        let delta = p_star - act.s.position();
        let dn = norm2(delta);
        if dn > EPS_CLOSE {
            return circle_gate(&b, &act, q);
        }
        if dn > EPS_CLOSE_ENOUGH {
            let u = Action::from_vector(scaled(delta, APPROACH_SPEED));
            // docs/spec/planning.md §2: the gate as a safety check on the straight move.
            if self.predicted_block(&b, &act, u).distance_to(&goal) > b.s.distance_to(&goal) {
                return circle_gate(&b, &act, q);
            }
            return u;
        }
        let n = norm2(v_star);
        // docs/spec/planning.md §2: at 10 Hz the raw displacement passes through.
        let push = if n == 0.0 || (PASS_MIN < n && n < PASS_MAX) {
            Action::from_vector(v_star)
        } else {
            Action::from_vector(scaled(v_star, APPROACH_SPEED))
        };
        if self.config.params().improvements.forward_check {
            return self.checked_push(&b, &act, push);
        }
        push
    }

    /// The `forward-check` improvement: of the inverse model's `push` and
    /// slower or turned variants of it, the one after which the forward
    /// model predicts the block closest to the target; `push` itself on a
    /// tie. The inverse model averages pushes that had similar effects, so
    /// near the target its push often overshoots, and it knows nothing of
    /// the block's exact pose relative to the actuator, which the forward
    /// model sees.
    pub(super) fn checked_push(
        &self,
        b: &TrackedObject,
        act: &TrackedObject,
        push: Action,
    ) -> Action {
        let Some(goal) = self.target.map(|t| t.pose) else {
            return push;
        };
        let v = push.to_vector();
        let mut best = (self.predicted_block(b, act, push).distance_to(&goal), push);
        for &(speed, turn) in &FORWARD_CHECK_VARIANTS {
            let u = Action::from_vector(global_vec(turn, v) * speed);
            let d = self.predicted_block(b, act, u).distance_to(&goal);
            // Strict: a variant must be predicted better, not merely as good.
            if d < best.0 {
                best = (d, u);
            }
        }
        best.1
    }

    /// Block `b` one message after `u`, as the forward models predict it:
    /// where it is unless the gate says the actuator moves it.
    pub(super) fn predicted_block(
        &self,
        b: &TrackedObject,
        act: &TrackedObject,
        u: Action,
    ) -> ObjectState {
        let a_hat = self.predict_actuator(act, u);
        let phi = self.phi(b, &a_hat);
        if self.influences(&phi) {
            self.predictor_state(b, &phi).unwrap_or(b.s)
        } else {
            b.s
        }
    }
}

/// The variants of the inverse model's push that `forward-check` weighs:
/// (speed factor, turn in radians), in the order that breaks ties.
const FORWARD_CHECK_VARIANTS: [(f64, f64); 8] = [
    (0.5, 0.0),
    (0.25, 0.0),
    (1.0, 0.2),
    (1.0, -0.2),
    (1.0, 0.4),
    (1.0, -0.4),
    (0.5, 0.2),
    (0.5, -0.2),
];

/// `circle_gate(B, Act, q)` (`docs/spec/planning.md` §4): the distance and the
/// actuator's angle come from `φ(B, Act)`, `r` is the global vector from the
/// block to the actuator.
fn circle_gate(b: &TrackedObject, act: &TrackedObject, q: Vector2<f64>) -> Action {
    let phi = relative_features(b, act);
    let r = act.s.position() - b.s.position();
    circle(phi[2], r, phi[5].atan2(phi[4]), q)
}
