//! Move to Target with the gate model: `get_action()` (`planning.md` §2),
//! circling (§4) and the exploration fallback (§5).

use std::f64::consts::PI;

use nalgebra::Vector2;
use rand::{Rng, RngExt};

use super::model::GateModel;
use crate::features::{global_point, global_vec, local_change, relative_features};
use crate::types::{Action, TrackedObject};

/// The target is reached below this norm of the raw 3-component difference
/// (no angle wrapping).
pub const REACHED: f64 = 0.01;
/// ε_close: farther than this from the precondition position, circle.
pub const EPS_CLOSE: f64 = 0.1;
/// ε_closeEnough: farther than this (within ε_close), move straight to it.
pub const EPS_CLOSE_ENOUGH: f64 = 0.01;
/// Circling band: closer than this, move away from the block.
pub const CIRCLE_NEAR: f64 = 0.04;
/// Circling band: farther than this, move towards the block.
pub const CIRCLE_FAR: f64 = 0.06;
/// Circling speed (m/s).
pub const CIRCLE_SPEED: f64 = 0.4;
/// Approach, push and exploration speed (m/s).
pub const APPROACH_SPEED: f64 = 0.3;
/// The precondition's motion passes through unscaled strictly inside
/// (`PASS_MIN`, `PASS_MAX`) or when it is zero.
pub const PASS_MIN: f64 = 0.01;
/// See [`PASS_MIN`].
pub const PASS_MAX: f64 = 0.2;

impl GateModel {
    /// `get_action()` of `planning.md` §2, from the model's actuator and its
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
        let d = local_change(&b.s, &goal);
        let pre = self
            .predictors
            .get_mut(&b.id)
            .and_then(|p| p.inverse.preconditions_for(&d));
        let Some(pre) = pre else {
            return exploration(b.s.position() - act.s.position(), rng);
        };
        let q = Vector2::new(pre[4], pre[5]);
        let p_star = global_point(b.s.theta, b.s.position(), q);
        let v_star = global_vec(b.s.theta, Vector2::new(pre[6], pre[7]));
        let delta = p_star - act.s.position();
        let dn = norm(delta);
        if dn > EPS_CLOSE {
            return circle_gate(&b, &act, q);
        }
        if dn > EPS_CLOSE_ENOUGH {
            let u = towards(APPROACH_SPEED, delta);
            // planning.md §2: the gate as a safety check on the straight move.
            let a_hat = self.predict_actuator(&act, u);
            let phi = relative_features(&b, &a_hat);
            if !self.influences(&phi) {
                return u;
            }
            let b_hat = self.predictor_state(&b, &phi).unwrap_or(b.s);
            if b_hat.distance_to(&goal) > b.s.distance_to(&goal) {
                return circle_gate(&b, &act, q);
            }
            return u;
        }
        let n = norm(v_star);
        // planning.md §2: at 10 Hz the raw displacement passes through.
        if n == 0.0 || (PASS_MIN < n && n < PASS_MAX) {
            return Action::from_vector(v_star);
        }
        towards(APPROACH_SPEED, v_star)
    }
}

/// `circle_gate(B, Act, q)` (`planning.md` §4): the distance and the
/// actuator's angle come from `φ(B, Act)`, `r` is the global vector from the
/// block to the actuator.
fn circle_gate(b: &TrackedObject, act: &TrackedObject, q: Vector2<f64>) -> Action {
    let phi = relative_features(b, act);
    let r = act.s.position() - b.s.position();
    circle(phi[2], r, phi[5].atan2(phi[4]), q)
}

/// `circle(dist, r, α_act, q)` (`planning.md` §4): keep 0.04–0.06 m from the
/// block and turn towards the wanted angular position `q` the shorter way.
pub(super) fn circle(dist: f64, r: Vector2<f64>, alpha_act: f64, q: Vector2<f64>) -> Action {
    if dist < CIRCLE_NEAR {
        return towards(CIRCLE_SPEED, r);
    }
    if dist > CIRCLE_FAR {
        return towards(-CIRCLE_SPEED, r);
    }
    let t = Vector2::new(-r.y, r.x);
    let alpha_tgt = q.y.atan2(q.x);
    // The original's expression, +π on both sides included (it can move the
    // difference by a rounding unit).
    let delta = (alpha_tgt + PI) - (alpha_act + PI);
    // planning.md §4: Δ = 0 exactly gives the clockwise tangent.
    let counter_clockwise = if delta > 0.0 {
        delta.abs() < PI
    } else {
        delta.abs() >= PI
    };
    let speed = if counter_clockwise {
        CIRCLE_SPEED
    } else {
        -CIRCLE_SPEED
    };
    towards(speed, t)
}

/// The exploration fallback (`planning.md` §5): towards the block with
/// uniform noise in [−0.5, 0.5) per axis, exactly two draws, x first.
pub(super) fn exploration(to_block: Vector2<f64>, rng: &mut dyn Rng) -> Action {
    let xi1 = rng.random::<f64>() - 0.5;
    let xi2 = rng.random::<f64>() - 0.5;
    towards(APPROACH_SPEED, to_block + Vector2::new(xi1, xi2))
}

/// `k · v / |v|` as the original evaluated it (`(k·v) / |v|` per
/// component); `v` itself if it is zero (`planning.md` §5; the circling's
/// `r` and `t` are zero only with the actuator on the block's centre, where
/// the original divided by zero — *decision*: no motion instead of NaN).
fn towards(k: f64, v: Vector2<f64>) -> Action {
    let n = norm(v);
    if n == 0.0 {
        return Action::from_vector(v);
    }
    Action::new((k * v.x) / n, (k * v.y) / n)
}

/// `|v|` as `sqrt(x² + y²)`.
fn norm(v: Vector2<f64>) -> f64 {
    (v.x * v.x + v.y * v.y).sqrt()
}
