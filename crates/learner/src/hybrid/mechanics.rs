//! Quasi-static pushing of a planar slider by a round, frictionless pusher
//! (`docs/models.md` "The hybrid model").
//!
//! The world's actuator is a sphere with a friction coefficient of 0.01
//! against the blocks, so the force it exerts is (almost) along the contact
//! normal. The blocks slide on the ground with a friction of 0.9, which makes
//! their motion under a steady push nearly quasi-static: inertia matters
//! only in the first and last moments of a contact. The slider's motion
//! then follows from its limit surface (Goyal, Ruina & Papadopoulos 1991),
//! approximated by an ellipsoid (Lynch, Maekawa & Tanie 1992): the twist
//! `(v, ω)` about the centre of mass is parallel to
//! `(F, λ·m)` for a force `F` and its moment `m`, with one parameter
//! `λ = 1/c²` per slider. A frictionless pusher pushes along the contact
//! normal `n`, so the twist is `k·(n, λ·(q × n))` for the contact point `q`,
//! and `k` follows from the pusher not passing through the slider.
//!
//! The pusher's path over one message is cut into [`SUBSTEPS`] pieces, and
//! each piece pushes the slider out of the pusher's way; that keeps contact
//! changes within a message (the pusher reaching the block, sliding off a
//! corner) where they happen. Out of contact, a slider keeps sliding and
//! slows down at a constant rate ([`Slide`]), a Coulomb-friction stop.

use nalgebra::{Rotation2, Vector2};
use serde::{Deserialize, Serialize};

use crate::features::Shape;
use crate::types::ObjectState;

/// Pieces of the pusher's path per message. Ten resolves contact changes
/// to a tenth of a message (half a millimetre at the push task's speed),
/// finer than the positions are known to.
pub const SUBSTEPS: usize = 10;

/// A slider's outline as the pusher meets it, in its own frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Outline {
    /// A rectangle with these half-sizes along the slider's x and y axes.
    Box { half: [f64; 2] },
    /// A disc (an upright cylinder) of this radius.
    Disc { radius: f64 },
}

impl Outline {
    /// The outline of a shape of the learner's shape table: its corners'
    /// bounding box, or a disc of its radius if it has no segments.
    #[must_use]
    pub fn of_shape(shape: &Shape) -> Self {
        if shape.segments.is_empty() {
            return Outline::Disc {
                radius: shape.radius,
            };
        }
        let half = shape.corners.iter().fold([0.0_f64; 2], |h, c| {
            [h[0].max(c[0].abs()), h[1].max(c[1].abs())]
        });
        Outline::Box { half }
    }

    /// The closest point of the outline to `p` (slider frame), the
    /// outward normal there and the signed distance from `p` (negative
    /// inside).
    #[must_use]
    pub fn closest(&self, p: Vector2<f64>) -> Contact {
        match *self {
            Outline::Disc { radius } => {
                let d = p.norm();
                let normal = if d > 0.0 {
                    p / d
                } else {
                    Vector2::new(0.0, -1.0)
                };
                Contact {
                    point: normal * radius,
                    normal,
                    distance: d - radius,
                }
            }
            Outline::Box { half } => {
                let clamped =
                    Vector2::new(p.x.clamp(-half[0], half[0]), p.y.clamp(-half[1], half[1]));
                let outside = p - clamped;
                let d = outside.norm();
                if d > 0.0 {
                    return Contact {
                        point: clamped,
                        normal: outside / d,
                        distance: d,
                    };
                }
                // Inside: the nearest face.
                let to_x = half[0] - p.x.abs();
                let to_y = half[1] - p.y.abs();
                if to_x < to_y {
                    let s = p.x.signum_or_one();
                    Contact {
                        point: Vector2::new(s * half[0], p.y),
                        normal: Vector2::new(s, 0.0),
                        distance: -to_x,
                    }
                } else {
                    let s = p.y.signum_or_one();
                    Contact {
                        point: Vector2::new(p.x, s * half[1]),
                        normal: Vector2::new(0.0, s),
                        distance: -to_y,
                    }
                }
            }
        }
    }

    /// The characteristic length `c` of the limit-surface ellipsoid for a
    /// uniform pressure over the outline: the mean distance of its area
    /// from the centre (Lynch, Maekawa & Tanie 1992 take `c = m_max /
    /// f_max`, which is this for uniform pressure). The model's prior
    /// before it has identified anything.
    #[must_use]
    pub fn uniform_pressure_length(&self) -> f64 {
        match *self {
            Outline::Disc { radius } => 2.0 * radius / 3.0,
            Outline::Box { half } => {
                // A midpoint rule on a 64 × 64 grid: exact to well under 1 %.
                const N: usize = 64;
                let mut sum = 0.0;
                for i in 0..N {
                    for j in 0..N {
                        let x = half[0] * (2.0 * (i as f64 + 0.5) / N as f64 - 1.0);
                        let y = half[1] * (2.0 * (j as f64 + 0.5) / N as f64 - 1.0);
                        sum += x.hypot(y);
                    }
                }
                sum / (N * N) as f64
            }
        }
    }
}

trait SignumOrOne {
    fn signum_or_one(self) -> Self;
}

impl SignumOrOne for f64 {
    /// The side a point exactly on an axis is pushed to: the positive one.
    fn signum_or_one(self) -> f64 {
        if self < 0.0 {
            -1.0
        } else {
            1.0
        }
    }
}

/// Where a point is relative to an outline (slider frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    pub point: Vector2<f64>,
    /// Outward unit normal at `point`.
    pub normal: Vector2<f64>,
    /// Signed distance of the point from the outline.
    pub distance: f64,
}

/// A slider's motion over one message: displacement of its centre (world
/// frame) and rotation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    pub dx: f64,
    pub dy: f64,
    pub dtheta: f64,
}

impl Twist {
    #[must_use]
    pub fn between(from: &ObjectState, to: &ObjectState) -> Self {
        Self {
            dx: to.x - from.x,
            dy: to.y - from.y,
            dtheta: to.theta - from.theta,
        }
    }

    #[must_use]
    pub fn speed(&self) -> f64 {
        self.dx.hypot(self.dy)
    }

    /// In the frame of a slider with yaw `theta`: `(along x, along y, dθ)`.
    #[must_use]
    pub fn in_frame(&self, theta: f64) -> [f64; 3] {
        let v = Rotation2::new(-theta) * Vector2::new(self.dx, self.dy);
        [v.x, v.y, self.dtheta]
    }

    /// From a slider frame with yaw `theta` to the world frame.
    #[must_use]
    pub fn from_frame(local: [f64; 3], theta: f64) -> Self {
        let v = Rotation2::new(theta) * Vector2::new(local[0], local[1]);
        Self {
            dx: v.x,
            dy: v.y,
            dtheta: local[2],
        }
    }

    #[must_use]
    pub fn applied_to(&self, s: &ObjectState) -> ObjectState {
        ObjectState::new(s.x + self.dx, s.y + self.dy, s.theta + self.dtheta)
    }
}

/// How a slider stops when nothing pushes it: its speed and its rate of
/// turn fall by these amounts per message, down to zero.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Slide {
    /// Metres per message, per message.
    pub linear: f64,
    /// Radians per message, per message.
    pub angular: f64,
}

/// The parameters of the mechanics that the model identifies.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Parameters {
    /// `λ = 1/c²` of the limit-surface ellipsoid, 1/m².
    pub lambda: f64,
    pub slide: Slide,
}

/// One slider and the pusher over one message.
#[derive(Clone, Copy, Debug)]
pub struct Push<'a> {
    pub outline: &'a Outline,
    pub parameters: &'a Parameters,
    /// The pusher's radius.
    pub pusher_radius: f64,
}

/// What [`Push::step`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stepped {
    pub slider: ObjectState,
    /// The slider's motion over the message, which it keeps sliding with.
    pub motion: Twist,
    /// Whether the pusher touched the slider during the message.
    pub touched: bool,
}

impl Push<'_> {
    /// The slider after the pusher moved from `from` by `path` (world
    /// frame), the slider having moved by `motion` over the previous
    /// message.
    #[must_use]
    pub fn step(
        &self,
        slider: ObjectState,
        motion: Twist,
        from: Vector2<f64>,
        path: Vector2<f64>,
    ) -> Stepped {
        let mut s = slider;
        let mut velocity = motion;
        let mut touched = false;
        let piece = path / SUBSTEPS as f64;
        let mut pusher = from;
        let fraction = 1.0 / SUBSTEPS as f64;
        for _ in 0..SUBSTEPS {
            pusher += piece;
            let local = Rotation2::new(-s.theta) * (pusher - s.position());
            let contact = self.outline.closest(local);
            let depth = self.pusher_radius - contact.distance;
            if depth > 0.0 {
                touched = true;
                let twist = self.resolve(&contact, depth);
                let moved = Twist::from_frame(twist, s.theta);
                s = moved.applied_to(&s);
                velocity = Twist {
                    dx: moved.dx / fraction,
                    dy: moved.dy / fraction,
                    dtheta: moved.dtheta / fraction,
                };
            } else {
                velocity = self.slide(velocity, fraction);
                s = Twist {
                    dx: velocity.dx * fraction,
                    dy: velocity.dy * fraction,
                    dtheta: velocity.dtheta * fraction,
                }
                .applied_to(&s);
            }
        }
        Stepped {
            slider: s,
            motion: Twist::between(&slider, &s),
            touched,
        }
    }

    /// The twist (slider frame) that moves the contact point `depth` along
    /// the inward normal, on the limit-surface ellipsoid.
    fn resolve(&self, contact: &Contact, depth: f64) -> [f64; 3] {
        let n = -contact.normal;
        let q = contact.point;
        let moment = q.x * n.y - q.y * n.x;
        let lambda = self.parameters.lambda;
        let k = depth / (1.0 + lambda * moment * moment);
        [k * n.x, k * n.y, k * lambda * moment]
    }

    /// A velocity (per message) after a `fraction` of a message of sliding
    /// freely.
    fn slide(&self, v: Twist, fraction: f64) -> Twist {
        let slide = self.parameters.slide;
        let speed = v.speed();
        let linear = if speed > 0.0 {
            (1.0 - slide.linear * fraction / speed).max(0.0)
        } else {
            0.0
        };
        let turn = v.dtheta.abs();
        let angular = if turn > 0.0 {
            (1.0 - slide.angular * fraction / turn).max(0.0)
        } else {
            0.0
        };
        Twist {
            dx: v.dx * linear,
            dy: v.dy * linear,
            dtheta: v.dtheta * angular,
        }
    }
}

/// What one observed message says about `λ`: with the pusher in contact
/// at its end, the rotation `dθ` against `k·(q × n)`, `k` being the
/// slider's advance along the inward normal. `None` when the message says
/// nothing (no contact, or a push without lever arm and without rotation).
#[must_use]
pub fn lambda_evidence(
    outline: &Outline,
    pusher_radius: f64,
    before: &ObjectState,
    after: &ObjectState,
    pusher_after: Vector2<f64>,
    contact_tolerance: f64,
) -> Option<(f64, f64)> {
    let local = Rotation2::new(-after.theta) * (pusher_after - after.position());
    let contact = outline.closest(local);
    if contact.distance - pusher_radius > contact_tolerance {
        return None;
    }
    let n = -contact.normal;
    let q = contact.point;
    let moment = q.x * n.y - q.y * n.x;
    let local_motion = Twist::between(before, after).in_frame(after.theta);
    let k = local_motion[0] * n.x + local_motion[1] * n.y;
    if k <= 0.0 {
        return None;
    }
    Some((k * moment, local_motion[2]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::{BLUE_SHAPE, RED_SHAPE};

    fn blue() -> Outline {
        Outline::of_shape(&BLUE_SHAPE)
    }

    #[test]
    fn outlines_come_from_the_shape_table() {
        assert_eq!(blue(), Outline::Box { half: [0.25, 0.05] });
        assert_eq!(
            Outline::of_shape(&RED_SHAPE),
            Outline::Box { half: [0.15, 0.15] }
        );
    }

    #[test]
    fn closest_points_outside_inside_and_on_a_disc() {
        let c = blue().closest(Vector2::new(0.1, -0.1));
        assert!((c.distance - 0.05).abs() < 1e-12);
        assert_eq!(c.normal, Vector2::new(0.0, -1.0));
        assert_eq!(c.point, Vector2::new(0.1, -0.05));
        let corner = blue().closest(Vector2::new(0.28, -0.09));
        assert!((corner.distance - 0.05).abs() < 1e-12);
        assert_eq!(corner.point, Vector2::new(0.25, -0.05));
        let inside = blue().closest(Vector2::new(0.0, -0.04));
        assert!((inside.distance + 0.01).abs() < 1e-12);
        assert_eq!(inside.normal, Vector2::new(0.0, -1.0));
        let disc = Outline::Disc { radius: 0.1 }.closest(Vector2::new(0.0, -0.3));
        assert!((disc.distance - 0.2).abs() < 1e-12);
        assert_eq!(disc.point, Vector2::new(0.0, -0.1));
    }

    #[test]
    fn the_uniform_pressure_length_matches_closed_forms() {
        // A square of side 2a: c = a·(√2 + ln(1 + √2))/3 ≈ 0.7652·a.
        let square = Outline::Box { half: [1.0, 1.0] }.uniform_pressure_length();
        let exact = (2.0_f64.sqrt() + (1.0 + 2.0_f64.sqrt()).ln()) / 3.0;
        assert!((square - exact).abs() < 1e-3, "{square} vs {exact}");
        let disc = Outline::Disc { radius: 0.3 }.uniform_pressure_length();
        assert!((disc - 0.2).abs() < 1e-12);
    }

    fn push(parameters: &Parameters) -> Push<'_> {
        static BLUE: Outline = Outline::Box { half: [0.25, 0.05] };
        Push {
            outline: &BLUE,
            parameters,
            pusher_radius: 0.025,
        }
    }

    const STOPS: Parameters = Parameters {
        lambda: 30.0,
        slide: Slide {
            linear: 1.0,
            angular: 1.0,
        },
    };

    #[test]
    fn a_central_push_translates_and_an_offset_one_turns() {
        let block = ObjectState::new(0.0, 0.25, 0.0);
        // The pusher's surface 1 mm from the block, moving 5 mm into it.
        let from = Vector2::new(0.0, 0.25 - 0.05 - 0.025 - 0.001);
        let path = Vector2::new(0.0, 0.005);
        let central = push(&STOPS).step(block, Twist::default(), from, path);
        assert!(central.touched);
        assert!((central.slider.y - 0.254).abs() < 1e-9, "{central:?}");
        assert!(central.slider.x.abs() < 1e-12 && central.slider.theta.abs() < 1e-12);

        let offset =
            push(&STOPS).step(block, Twist::default(), from + Vector2::new(0.2, 0.0), path);
        // Pushed up at its right end, the block turns counter-clockwise
        // and its centre advances less than the pusher.
        assert!(offset.slider.theta > 0.0);
        assert!(offset.slider.y - 0.25 < 0.004 && offset.slider.y > 0.25);
    }

    #[test]
    fn out_of_contact_a_slider_slows_down_and_stops() {
        let block = ObjectState::new(0.0, 0.25, 0.0);
        let far = Vector2::new(1.0, 1.0);
        let gentle = Parameters {
            lambda: 30.0,
            slide: Slide {
                linear: 0.001,
                angular: 0.01,
            },
        };
        let moving = Twist {
            dx: 0.0,
            dy: 0.005,
            dtheta: 0.0,
        };
        let s = push(&gentle).step(block, moving, far, Vector2::zeros());
        assert!(!s.touched);
        assert!(s.motion.dy > 0.0035 && s.motion.dy < 0.005, "{s:?}");
        let stopped = push(&STOPS).step(block, moving, far, Vector2::zeros());
        assert!(stopped.motion.dy < 0.001);
    }

    #[test]
    fn lambda_evidence_reads_the_rotation_against_the_lever_arm() {
        let before = ObjectState::new(0.0, 0.25, 0.0);
        let from = Vector2::new(0.2, 0.25 - 0.05 - 0.025 - 0.001);
        let path = Vector2::new(0.0, 0.005);
        let s = push(&STOPS).step(before, Twist::default(), from, path);
        let (x, y) =
            lambda_evidence(&blue(), 0.025, &before, &s.slider, from + path, 0.002).unwrap();
        // One message of the mechanics with λ = 30 reads back as about 30.
        assert!((y / x - 30.0).abs() < 1.5, "{}", y / x);
        assert!(lambda_evidence(
            &blue(),
            0.025,
            &before,
            &before,
            Vector2::new(1.0, 1.0),
            0.002
        )
        .is_none());
    }
}
