//! Quasi-static pushing of a planar slider by a round, frictionless pusher
//! (`docs/models.md` "The hybrid model").
//!
//! The world's actuator is a sphere with a friction coefficient of 0.01
//! against the blocks, so the force it exerts is (almost) along the contact
//! normal. The blocks slide on the ground with a friction of 0.9, which makes
//! their motion under a steady push nearly quasi-static: inertia matters
//! only in the first and last moments of a contact. A quasi-static slider
//! moves so as to dissipate the least power in friction among the motions
//! the pusher allows (the maximum-dissipation principle behind the limit
//! surface, Goyal, Ruina & Papadopoulos 1991; Mason 1986). Here the
//! friction acts at the slider's support points and is bounded along each
//! world axis separately (the world's friction pyramid), so the
//! dissipation is a weighted sum of absolute values and the motion is the
//! solution of a small linear programme ([`least_dissipation`]). Its one
//! free parameter, how far the push tips the weight onto the far supports,
//! is identified online by the model.
//!
//! The pusher's path over one message is cut into [`SUBSTEPS`] pieces, and
//! each piece pushes the slider out of the pusher's way; that keeps contact
//! changes within a message (the pusher reaching the block, sliding off a
//! corner) where they happen. Out of contact, a slider keeps sliding and
//! slows down at a constant rate ([`Slide`]), a Coulomb-friction stop.

use nalgebra::{Rotation2, Vector2};
use serde::{Deserialize, Serialize};

use crate::features::Shape;
use crate::types::{Footprint, ObjectState};

/// Pieces of the pusher's path per message. Five resolve contact changes
/// to a fifth of a message (1 mm at the push task's speed); ten gave the
/// same errors on the push task (4 folds, 1–30 training runs) at twice
/// the cost.
pub const SUBSTEPS: usize = 5;

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

    /// The outline of a footprint the world gave.
    #[must_use]
    pub fn of_footprint(footprint: Footprint) -> Self {
        match footprint {
            Footprint::Box { half_extents } => Outline::Box { half: half_extents },
            Footprint::Disc { radius } => Outline::Disc { radius },
        }
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

    /// Where the slider rests on the ground (slider frame), written to the
    /// start of `out`; returns how many: a box on its four corners, as a
    /// rigid box on a plane does; a disc on points around its rim.
    pub fn supports_into(&self, out: &mut [Vector2<f64>; MAX_SUPPORTS]) -> usize {
        match *self {
            Outline::Box { half } => {
                out[0] = Vector2::new(-half[0], -half[1]);
                out[1] = Vector2::new(half[0], -half[1]);
                out[2] = Vector2::new(half[0], half[1]);
                out[3] = Vector2::new(-half[0], half[1]);
                4
            }
            Outline::Disc { radius } => {
                for (i, p) in out.iter_mut().enumerate().take(RIM_SUPPORTS) {
                    let a = std::f64::consts::TAU * (i as f64 + 0.5) / RIM_SUPPORTS as f64;
                    *p = Vector2::new(radius * a.cos(), radius * a.sin());
                }
                RIM_SUPPORTS
            }
        }
    }
}

impl Outline {
    /// A length that makes a turn comparable with a displacement: the
    /// largest distance of the outline from its centre.
    #[must_use]
    pub fn size(&self) -> f64 {
        match *self {
            Outline::Box { half } => half[0].hypot(half[1]),
            Outline::Disc { radius } => radius,
        }
    }
}

/// Support points of a disc.
const RIM_SUPPORTS: usize = 8;

/// The twist (slider frame) that moves the contact point `depth` along the
/// inward normal while dissipating the least power in friction at the
/// supports: the maximum-dissipation principle for a quasi-static slider,
/// here a linear programme (friction bounded per world axis makes the
/// dissipation a weighted sum of absolute values). Its optimum lies where
/// two of the absolute values vanish, so every such pair is solved and the
/// cheapest kept; equally cheap solutions are averaged, which is
/// optimal too (the optimal set is convex) and keeps the answer
/// continuous where the optimum is not unique.
fn least_dissipation(
    outline: &Outline,
    contact: &Contact,
    depth: f64,
    theta: f64,
    tipping: f64,
    hint: &mut Option<(usize, usize)>,
) -> [f64; 3] {
    // Work in the world's axes, about the slider's centre.
    let to_world = Rotation2::new(theta);
    let n = to_world * -contact.normal;
    let q = to_world * contact.point;
    let constraint = [n.x, n.y, q.x * n.y - q.y * n.x];
    let mut supports = [Vector2::zeros(); MAX_SUPPORTS];
    let count = outline.supports_into(&mut supports);
    let supports = &mut supports[..count];
    for p in supports.iter_mut() {
        *p = to_world * *p;
    }
    // The push's moment about the ground tips the weight to the far side,
    // linearly in the distance along the push (clamped at zero).
    let spread: f64 = supports.iter().map(|p| p.dot(&n).powi(2)).sum();
    let gradient = if spread > 0.0 {
        tipping * count as f64 / spread
    } else {
        0.0
    };
    let mut terms = [([0.0; 3], 0.0); 2 * MAX_SUPPORTS];
    for (i, p) in supports.iter().enumerate() {
        let weight = (1.0 + gradient * p.dot(&n)).max(0.0);
        // Velocity of the support: (v_x − ω p_y, v_y + ω p_x).
        terms[2 * i] = ([1.0, 0.0, -p.y], weight);
        terms[2 * i + 1] = ([0.0, 1.0, p.x], weight);
    }
    let terms = &terms[..2 * count];
    let to_slider = |world: [f64; 3]| {
        let v = to_world.inverse() * Vector2::new(world[0], world[1]);
        [v.x, v.y, world[2]]
    };
    if let Some((j, k)) = *hint {
        if let Some(v) = vertex(terms, constraint, depth, j, k) {
            if is_optimal(terms, constraint, &v, j, k) {
                return to_slider(v);
            }
        }
    }
    let cost = |v: &[f64; 3]| -> f64 { terms.iter().map(|(a, w)| w * dot3(a, v).abs()).sum() };
    let mut best = f64::INFINITY;
    let mut sum = [0.0; 3];
    let mut ties = 0.0;
    for j in 0..terms.len() {
        for k in j + 1..terms.len() {
            let Some(v) = vertex(terms, constraint, depth, j, k) else {
                continue;
            };
            let c = cost(&v);
            let tolerance = if best.is_finite() { 1e-9 * best } else { 0.0 };
            if c < best - tolerance {
                best = c;
                sum = v;
                ties = 1.0;
                *hint = Some((j, k));
            } else if c <= best + tolerance {
                for (s, x) in sum.iter_mut().zip(v) {
                    *s += x;
                }
                ties += 1.0;
            }
        }
    }
    if ties == 0.0 {
        *hint = None;
        return [0.0; 3];
    }
    to_slider(sum.map(|s| s / ties))
}

/// Most support points an outline has.
const MAX_SUPPORTS: usize = RIM_SUPPORTS;

fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The motion that meets the push's constraint with terms `j` and `k`
/// at zero.
fn vertex(
    terms: &[([f64; 3], f64)],
    constraint: [f64; 3],
    depth: f64,
    j: usize,
    k: usize,
) -> Option<[f64; 3]> {
    solve3([constraint, terms[j].0, terms[k].0], [depth, 0.0, 0.0])
}

/// Whether the vertex `v` of terms `j`, `k` is optimal: the
/// Karush–Kuhn–Tucker condition with the two vanishing terms' subgradients
/// within [−1, 1] (any other vanishing term taken at 0, which makes this a
/// sufficient test, not a necessary one: a failure only costs the full
/// search).
fn is_optimal(
    terms: &[([f64; 3], f64)],
    constraint: [f64; 3],
    v: &[f64; 3],
    j: usize,
    k: usize,
) -> bool {
    let mut gradient = [0.0; 3];
    for (i, (a, w)) in terms.iter().enumerate() {
        if i == j || i == k {
            continue;
        }
        let speed = dot3(a, v);
        let sign = if speed > 1e-15 {
            1.0
        } else if speed < -1e-15 {
            -1.0
        } else {
            0.0
        };
        for (g, x) in gradient.iter_mut().zip(a) {
            *g += w * sign * x;
        }
    }
    let (aj, wj) = terms[j];
    let (ak, wk) = terms[k];
    // Columns: w_j a_j, w_k a_k, −c; unknowns: s_j, s_k, μ.
    let rows = [
        [wj * aj[0], wk * ak[0], -constraint[0]],
        [wj * aj[1], wk * ak[1], -constraint[1]],
        [wj * aj[2], wk * ak[2], -constraint[2]],
    ];
    match solve3(rows, gradient.map(|g| -g)) {
        Some([sj, sk, _]) => sj.abs() <= 1.0 + 1e-9 && sk.abs() <= 1.0 + 1e-9,
        None => false,
    }
}

/// `x` with `rows · x = rhs`, by Cramer's rule; `None` if singular.
fn solve3(rows: [[f64; 3]; 3], rhs: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(rows);
    if d.abs() < 1e-12 {
        return None;
    }
    let mut x = [0.0; 3];
    for (c, out) in x.iter_mut().enumerate() {
        let mut m = rows;
        for r in 0..3 {
            m[r][c] = rhs[r];
        }
        *out = det(m) / d;
    }
    Some(x)
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
    /// How far the push tips the slider's weight towards its far side,
    /// in metres: μ times the height at which the pusher meets it (see
    /// [`least_dissipation`]).
    pub tipping: f64,
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
        // The optimum of one piece is almost always the next one's.
        self.step_in(slider, motion, from, path, SUBSTEPS, &mut None)
    }

    /// [`Push::step`] in `pieces` pieces, starting the search for the
    /// least dissipation at `hint` (and leaving the last optimum there).
    #[must_use]
    pub fn step_in(
        &self,
        slider: ObjectState,
        motion: Twist,
        from: Vector2<f64>,
        path: Vector2<f64>,
        pieces: usize,
        hint: &mut Option<(usize, usize)>,
    ) -> Stepped {
        let mut s = slider;
        let mut velocity = motion;
        let mut touched = false;
        let pieces = pieces.max(1);
        let piece = path / pieces as f64;
        let mut pusher = from;
        let fraction = 1.0 / pieces as f64;
        for _ in 0..pieces {
            pusher += piece;
            let local = Rotation2::new(-s.theta) * (pusher - s.position());
            let contact = self.outline.closest(local);
            let depth = self.pusher_radius - contact.distance;
            if depth > 0.0 {
                touched = true;
                let twist = least_dissipation(
                    self.outline,
                    &contact,
                    depth,
                    s.theta,
                    self.parameters.tipping,
                    hint,
                );
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

    fn push(parameters: &Parameters) -> Push<'_> {
        static BLUE: Outline = Outline::Box { half: [0.25, 0.05] };
        Push {
            outline: &BLUE,
            parameters,
            pusher_radius: 0.025,
        }
    }

    const STOPS: Parameters = Parameters {
        tipping: 0.0,
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
            tipping: 0.0,
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
    fn the_dead_zone_of_an_offset_push_narrows_as_the_push_tips_the_block() {
        let outline = blue();
        // A push along +y at 3.5 cm off centre, on the long face.
        let contact = outline.closest(Vector2::new(0.035, -0.074));
        let flat = least_dissipation(&outline, &contact, 0.001, 0.0, 0.0, &mut None);
        // Level weight: turning costs the x-friction of all four corners,
        // more than it saves below 5 cm off centre: a pure translation.
        assert!(
            flat[2].abs() < 1e-12 && (flat[1] - 0.001).abs() < 1e-12,
            "{flat:?}"
        );
        // Weight tipped to the far corners: the near ones swing cheaply.
        let tipped = least_dissipation(&outline, &contact, 0.001, 0.0, 0.027, &mut None);
        assert!(tipped[2] > 0.0, "{tipped:?}");
        // The contact point advances by exactly the depth.
        assert!((tipped[1] + tipped[2] * 0.035 - 0.001).abs() < 1e-12);
        // Mirror image, mirror motion.
        let mirrored = outline.closest(Vector2::new(-0.035, -0.074));
        let m = least_dissipation(&outline, &mirrored, 0.001, 0.0, 0.027, &mut None);
        assert!((m[2] + tipped[2]).abs() < 1e-12 && (m[1] - tipped[1]).abs() < 1e-12);
    }

    #[test]
    fn solve3_refuses_singular_systems() {
        assert_eq!(solve3([[1.0, 0.0, 0.0]; 3], [1.0, 0.0, 0.0]), None);
        let x = solve3(
            [[2.0, 0.0, 0.0], [0.0, 4.0, 0.0], [1.0, 0.0, 1.0]],
            [2.0, 4.0, 3.0],
        )
        .unwrap();
        assert_eq!(x, [1.0, 1.0, 2.0]);
    }
}
