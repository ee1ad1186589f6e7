//! What moves: an action (the actuator's planar velocity) and an object's
//! planar state. The learner plans and predicts in these, the driver scores
//! them and the Python extension hands them across; vectors are nalgebra's,
//! as in the learner's arithmetic.

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

/// A primitive action: the actuator's planar velocity in m/s, global frame.
/// It stays in force until replaced (`docs/spec/README.md` §4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Action {
    pub vx: f64,
    pub vy: f64,
}

impl Action {
    /// Standing still; also what a model without a target returns.
    pub const ZERO: Action = Action { vx: 0.0, vy: 0.0 };

    #[must_use]
    pub const fn new(vx: f64, vy: f64) -> Self {
        Self { vx, vy }
    }

    #[must_use]
    pub fn to_vector(self) -> Vector2<f64> {
        Vector2::new(self.vx, self.vy)
    }

    #[must_use]
    pub fn from_vector(v: Vector2<f64>) -> Self {
        Self { vx: v.x, vy: v.y }
    }

    /// Euclidean norm of (vx, vy).
    #[must_use]
    pub fn norm(self) -> f64 {
        (self.vx * self.vx + self.vy * self.vy).sqrt()
    }

    #[must_use]
    pub fn is_finite(self) -> bool {
        self.vx.is_finite() && self.vy.is_finite()
    }
}

/// The state `s = (x, y, θ)` of one object in the global frame.
///
/// Parsed states are 3-decimal rounded (`docs/spec/features.md` §1); predicted ones need
/// not be. θ is never wrapped (`docs/spec/README.md` §5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ObjectState {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

impl ObjectState {
    #[must_use]
    pub const fn new(x: f64, y: f64, theta: f64) -> Self {
        Self { x, y, theta }
    }

    /// `p = (x, y)`.
    #[must_use]
    pub fn position(&self) -> Vector2<f64> {
        Vector2::new(self.x, self.y)
    }

    #[must_use]
    pub fn to_array(&self) -> [f64; 3] {
        [self.x, self.y, self.theta]
    }

    #[must_use]
    pub const fn from_array(a: [f64; 3]) -> Self {
        Self {
            x: a[0],
            y: a[1],
            theta: a[2],
        }
    }

    /// `|s − other|` over all three components with the raw angle difference:
    /// the start-position check (`docs/spec/experiments.md` §2) and the gate model's
    /// reached test (`docs/spec/planning.md` §2) deliberately do not wrap angles.
    #[must_use]
    pub fn distance_to(&self, other: &ObjectState) -> f64 {
        let dx = self.x - other.x;
        let dy = self.y - other.y;
        let dt = self.theta - other.theta;
        (dx * dx + dy * dy + dt * dt).sqrt()
    }

    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.theta.is_finite()
    }
}
