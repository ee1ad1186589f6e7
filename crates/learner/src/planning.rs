//! The model-independent parts of Move to Target (`docs/spec/planning.md`): the
//! constants of §1, circling (§4) and the exploration fallback (§5). Both
//! learners' `get_action()` (§2, §3) call these with their own inputs.

use nalgebra::Vector2;
use rand::{Rng, RngExt};

use crate::types::Action;

/// A target counts as reached when the difference norm is below this
/// (`docs/spec/planning.md` §1; no angle wrapping).
pub const REACHED: f64 = 0.01;
/// ε_close: farther than this from the precondition position, circle.
pub const EPS_CLOSE: f64 = 0.1;
/// ε_closeEnough: farther than this (within ε_close), move straight towards it.
pub const EPS_CLOSE_ENOUGH: f64 = 0.01;
/// Circling band: closer than this to the block, move away.
pub const CIRCLE_NEAR: f64 = 0.04;
/// Circling band: farther than this from the block, move towards it.
pub const CIRCLE_FAR: f64 = 0.06;
/// Circling speed, m/s.
pub const CIRCLE_SPEED: f64 = 0.4;
/// Approach, push and exploration speed, m/s.
pub const APPROACH_SPEED: f64 = 0.3;

/// `|v|` as `sqrt(x² + y²)` (left-to-right sum, like every norm of the
/// original), not `hypot`.
#[must_use]
pub fn norm2(v: Vector2<f64>) -> f64 {
    (v.x * v.x + v.y * v.y).sqrt()
}

/// `speed · v / |v|`; `v` itself when `|v| = 0`. `docs/spec/planning.md` §3 and §5
/// state this zero rule for the push and the exploration; for circling it is
/// a *decision* (the original divided by zero and sent NaN, which only
/// happens with the actuator exactly at the block's centre).
#[must_use]
pub fn scaled(v: Vector2<f64>, speed: f64) -> Vector2<f64> {
    let n = norm2(v);
    if n == 0.0 {
        v
    } else {
        speed * v / n
    }
}

/// `circle(dist, r, α_act, q)` of `docs/spec/planning.md` §4: keep the actuator in the
/// band 0.04 … 0.06 m around the block and move it tangentially, in the
/// rotational direction that reaches the wanted position `q` (block frame)
/// the shorter way.
///
/// * `dist`: actuator–block distance (gate model: signed `φ[2]`; interaction
///   model: the clamped `dist`);
/// * `r`: global vector from the block centre to the actuator;
/// * `alpha_act`: the actuator's angle around the block, in the block frame.
#[must_use]
pub fn circle(dist: f64, r: Vector2<f64>, alpha_act: f64, q: Vector2<f64>) -> Action {
    use std::f64::consts::PI;
    if dist < CIRCLE_NEAR {
        return Action::from_vector(scaled(r, CIRCLE_SPEED));
    }
    if dist > CIRCLE_FAR {
        return Action::from_vector(-scaled(r, CIRCLE_SPEED));
    }
    // Counter-clockwise tangent built from block→actuator (`docs/spec/planning.md` §6:
    // the code's sign, not the thesis's).
    let t = scaled(Vector2::new(-r.y, r.x), CIRCLE_SPEED);
    let alpha_tgt = q.y.atan2(q.x);
    // Written as the original computed it: both angles shifted by π first.
    let delta = (alpha_tgt + PI) - (alpha_act + PI);
    let ccw = if delta > 0.0 {
        delta.abs() < PI
    } else {
        // Δ = 0 lands here: clockwise (`docs/spec/planning.md` §4).
        delta.abs() >= PI
    };
    Action::from_vector(if ccw { t } else { -t })
}

/// The exploration fallback of `docs/spec/planning.md` §5: `u = g + (ξ1, ξ2)` with
/// ξ uniform in [−0.5, 0.5), drawn from the caller's generator, x first;
/// `0.3 · u / |u|` (or `u` if `|u| = 0`). `g` is the global vector from the
/// actuator to the block centre.
pub fn exploration(g: Vector2<f64>, rng: &mut dyn Rng) -> Action {
    let xi1 = rng.random::<f64>() - 0.5;
    let xi2 = rng.random::<f64>() - 0.5;
    Action::from_vector(scaled(g + Vector2::new(xi1, xi2), APPROACH_SPEED))
}

#[cfg(test)]
mod tests {
    use std::f64::consts::{FRAC_PI_2, PI};

    use super::*;

    fn assert_action(got: Action, want: (f64, f64)) {
        assert!(
            (got.vx - want.0).abs() < 1e-12 && (got.vy - want.1).abs() < 1e-12,
            "got {got:?}, want {want:?}"
        );
    }

    #[test]
    fn circle_moves_away_when_too_close_and_towards_when_too_far() {
        let r = Vector2::new(0.0, -0.3);
        let q = Vector2::new(1.0, 0.0);
        assert_action(circle(0.039, r, 0.0, q), (0.0, -0.4));
        assert_action(circle(0.061, r, 0.0, q), (0.0, 0.4));
        // The band's edges themselves are inside it: tangential.
        for d in [0.04, 0.06] {
            let a = circle(d, r, -FRAC_PI_2, q);
            assert!(
                (a.vx.abs() - 0.4).abs() < 1e-12 && a.vy.abs() < 1e-12,
                "{a:?}"
            );
        }
        // Negative (unclamped gate) distances move away too.
        assert_action(circle(-0.01, r, 0.0, q), (0.0, -0.4));
    }

    #[test]
    fn circle_takes_the_shorter_way_round() {
        // Actuator below the block (r = (0, −0.3), α_act = −π/2).
        let r = Vector2::new(0.0, -0.3);
        let ccw = (0.4, 0.0); // t = (−r_y, r_x) = (0.3, 0) scaled
        let cw = (-0.4, 0.0);
        // Target to the right (α_tgt = 0): Δ = π/2 > 0, |Δ| < π → ccw.
        assert_action(circle(0.05, r, -FRAC_PI_2, Vector2::new(1.0, 0.0)), ccw);
        // Target to the left (α_tgt = π): Δ = 3π/2 ≥ π → cw.
        assert_action(circle(0.05, r, -FRAC_PI_2, Vector2::new(-1.0, 0.0)), cw);
        // Target slightly below-left (α_tgt just above −π): Δ < 0, |Δ| < π → cw.
        assert_action(circle(0.05, r, -FRAC_PI_2, Vector2::new(-1.0, -0.1)), cw);
        // α_act near +π, target near −π: Δ ≈ −2π, |Δ| ≥ π → ccw.
        let r_left = Vector2::new(-0.3, 0.0);
        let a = circle(0.05, r_left, PI - 0.1, Vector2::new(-1.0, -0.1));
        assert_action(a, (0.0, -0.4));
    }

    #[test]
    fn circle_with_zero_delta_turns_clockwise() {
        let r = Vector2::new(0.3, 0.0);
        let q = Vector2::new(2.0, 0.0);
        // Δ = 0 exactly: the else branch with |Δ| < π → clockwise, −t.
        assert_action(circle(0.05, r, 0.0, q), (0.0, -0.4));
    }

    #[test]
    fn circle_with_delta_exactly_pi() {
        let r = Vector2::new(0.0, 0.3);
        // α_act = 0 shifted by π is π; α_tgt = π shifted is 2π: Δ = π, not < π → cw.
        let a = circle(0.05, r, 0.0, Vector2::new(-1.0, 0.0));
        assert_action(a, (0.4, 0.0));
    }

    #[test]
    fn circle_never_divides_by_zero() {
        let a = circle(0.0, Vector2::zeros(), 0.0, Vector2::new(1.0, 0.0));
        assert_eq!(a, Action::ZERO);
    }

    /// Replays fixed 64-bit words, so the expected samples are known exactly.
    struct Words(Vec<u64>);

    impl rand::TryRng for Words {
        type Error = std::convert::Infallible;
        fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
            Ok(self.0.remove(0) as u32)
        }
        fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
            Ok(self.0.remove(0))
        }
        fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Self::Error> {
            dst.fill(0);
            Ok(())
        }
    }

    #[test]
    fn exploration_adds_noise_x_first_and_scales_to_0_3() {
        // The top 53 bits make the f64 in [0, 1): 0 → 0.0, 1 << 63 → 0.5.
        let mut rng = Words(vec![0, 1 << 63]);
        let a = exploration(Vector2::new(0.5, 0.25), &mut rng);
        // u = (0.5 − 0.5, 0.25 + 0.0) = (0, 0.25) → (0, 0.3).
        assert_action(a, (0.0, 0.3));
        assert!(rng.0.is_empty(), "exactly two draws");

        let mut rng = Words(vec![1 << 63, 0]);
        let a = exploration(Vector2::new(0.5, 0.25), &mut rng);
        // u = (0.5, −0.25).
        let n = (0.25f64 + 0.0625).sqrt();
        assert_action(a, (0.3 * 0.5 / n, -0.3 * 0.25 / n));
    }

    #[test]
    fn exploration_returns_a_zero_sum_unscaled() {
        let mut rng = Words(vec![0, 0]);
        let a = exploration(Vector2::new(0.5, 0.5), &mut rng);
        assert_eq!(a, Action::ZERO);
    }
}
