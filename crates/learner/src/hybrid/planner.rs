//! Move to Target with the hybrid model: the thesis's greedy reduction of
//! one part of the error at a time (`docs/spec/inverse-model.md` §4), with
//! the pushes found by rolling the model forward instead of recalled from
//! a memory of pushes seen.
//!
//! Minimising the whole error at every push stalls: near the target
//! position a turn needs an off-centre push, which moves the block away
//! before it turns it, so no push looks good and large turns never happen.
//! The thesis's inverse model avoids this by working on the largest part of
//! the error in the block's frame (along, across, turn) until its sign
//! flips or it is small, whatever the others do meanwhile; so does this
//! planner. A frictionless pusher can only push along the normal of the
//! face it touches, so a push is chosen by where it starts: every
//! candidate contact around the block's outline is rolled forward with the
//! model for a short push, and the one that takes the chosen part nearest
//! zero, helping the rest most, wins. The pusher goes round the block
//! along its outline, approaches straight with the thesis's safety check
//! (`docs/spec/planning.md` §2) and pushes at the speed the model predicts
//! best for the next message.

use std::f64::consts::{PI, TAU};

use nalgebra::{Rotation2, Vector2};
use rand::Rng;

use super::mechanics::{Outline, Twist};
use super::model::{pusher_radius, surface_gap, HybridModel};
use crate::eval::goal_distance;
use crate::planning::{exploration, norm2, scaled, EPS_CLOSE, EPS_CLOSE_ENOUGH, REACHED};
use crate::types::{Action, ObjectState};

/// Candidate contacts per outline.
const CANDIDATES: usize = 48;
/// Messages a candidate push is rolled forward.
const HORIZON: usize = 12;
/// The pusher waits this far off the outline before a push.
const STANDOFF: f64 = 0.005;
/// The speed the pusher travels and pushes at: the world's limit
/// (`docs/spec/world.md` §5), faster than the thesis's planners (0.3 and
/// 0.4 m/s), and the speed of every training push, so the one the model
/// knows best.
const SPEED: f64 = 0.5;
/// Push speeds weighed at each message, fastest first (ties go to speed).
const SPEEDS: [f64; 6] = [SPEED, 0.3, 0.2, 0.1, 0.05, 0.02];
/// Messages a kept push is rolled forward to see that it still helps:
/// enough to close the stand-off.
const KEEP_CHECK: usize = 4;
/// How far off the outline the pusher goes round it: the middle of the
/// thesis's circling band (`docs/spec/planning.md` §1).
const CLEARANCE: f64 = 0.05;
/// How far along the outline ahead of itself the pusher heads while it
/// goes round.
const LOOK_AHEAD: f64 = 0.03;
/// The cosine above which the face the pusher touches is the plan's.
const SAME_FACE: f64 = 0.9;
/// A part of the error is worked on until it is this small
/// (`docs/spec/inverse-model.md` §4, the thesis's `ε_keep`).
const KEEP: f64 = 0.01;
/// What the rest of the error counts beside the part worked on, when
/// pushes are compared: less than it, so that the chosen part leads.
const REST_WEIGHT: f64 = 0.5;

/// The push being carried out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct PushPlan {
    /// Contact point and outward normal, slider frame.
    contact: Vector2<f64>,
    normal: Vector2<f64>,
    /// The part of the error it works on (0 along, 1 across the block,
    /// 2 the turn) and that part's sign when it was chosen.
    part: usize,
    sign: f64,
}

/// The way a pusher at `pusher` (slider frame) goes round the outline
/// towards `contact`, the shorter way, [`CLEARANCE`] off it: towards the
/// point [`LOOK_AHEAD`] further along. The thesis's circling (matching the
/// angle seen from the centre, `docs/spec/planning.md` §4) suits compact
/// blocks; beside a long one, the angle of a contact near an end is met
/// far from it and the pusher swings about there.
fn round_the_outline(
    outline: &Outline,
    pusher: Vector2<f64>,
    contact: Vector2<f64>,
) -> Vector2<f64> {
    let around = perimeter(outline);
    let here = along(outline, outline.closest(pusher).point);
    let ahead = (along(outline, contact) - here).rem_euclid(around);
    let step = if ahead <= around / 2.0 {
        ahead.min(LOOK_AHEAD)
    } else {
        -(around - ahead).min(LOOK_AHEAD)
    };
    let (point, normal) = at_along(outline, here + step);
    point + normal * (pusher_radius() + CLEARANCE) - pusher
}

/// Where a point of the outline lies along it, counter-clockwise from the
/// corner at (−x, −y) for a box, from the +x axis for a disc.
fn along(outline: &Outline, point: Vector2<f64>) -> f64 {
    match *outline {
        Outline::Disc { radius } => radius * point.y.atan2(point.x).rem_euclid(TAU),
        Outline::Box { half: [hx, hy] } => {
            // The face the point is on, in proportion to the box's size
            // (at a corner the two faces' formulas agree).
            let (u, v) = (point.x / hx, point.y / hy);
            if v.abs() >= u.abs() {
                if v < 0.0 {
                    point.x + hx
                } else {
                    2.0 * hx + 2.0 * hy + (hx - point.x)
                }
            } else if u > 0.0 {
                2.0 * hx + (point.y + hy)
            } else {
                4.0 * hx + 2.0 * hy + (hy - point.y)
            }
        }
    }
}

/// The point of the outline at `s` along it ([`along`]) and the outward
/// normal there.
fn at_along(outline: &Outline, s: f64) -> (Vector2<f64>, Vector2<f64>) {
    let s = s.rem_euclid(perimeter(outline));
    match *outline {
        Outline::Disc { radius } => {
            let n = Vector2::new((s / radius).cos(), (s / radius).sin());
            (n * radius, n)
        }
        Outline::Box { half: [hx, hy] } => {
            let (bottom, right, top) = (2.0 * hx, 2.0 * hx + 2.0 * hy, 4.0 * hx + 2.0 * hy);
            if s < bottom {
                (Vector2::new(s - hx, -hy), Vector2::new(0.0, -1.0))
            } else if s < right {
                (Vector2::new(hx, s - bottom - hy), Vector2::new(1.0, 0.0))
            } else if s < top {
                (Vector2::new(hx - (s - right), hy), Vector2::new(0.0, 1.0))
            } else {
                (Vector2::new(-hx, hy - (s - top)), Vector2::new(-1.0, 0.0))
            }
        }
    }
}

/// The outline's length.
fn perimeter(outline: &Outline) -> f64 {
    match *outline {
        Outline::Disc { radius } => TAU * radius,
        Outline::Box { half: [hx, hy] } => 4.0 * (hx + hy),
    }
}

/// A candidate push and the block's errors over its horizon.
struct Rolled {
    contact: Vector2<f64>,
    normal: Vector2<f64>,
    errors: Vec<[f64; 3]>,
}

/// The block's error to `goal` in the frame of `frame`: the position
/// difference rotated into it and the wrapped turn (signed).
fn error_in(frame: &ObjectState, pose: &ObjectState, goal: &ObjectState) -> [f64; 3] {
    let d = Rotation2::new(-frame.theta) * (goal.position() - pose.position());
    let turn = wrapped(goal.theta - pose.theta);
    [d.x, d.y, turn]
}

fn wrapped(angle: f64) -> f64 {
    let a = angle.rem_euclid(TAU);
    if a > PI {
        a - TAU
    } else {
        a
    }
}

/// How much better `after` is than `before` for working on `part`: what
/// that part came nearer zero, plus [`REST_WEIGHT`] times what the rest
/// came nearer.
fn progress(part: usize, before: &[f64; 3], after: &[f64; 3]) -> f64 {
    let rest = |e: &[f64; 3]| {
        (0..3)
            .filter(|&j| j != part)
            .map(|j| e[j] * e[j])
            .sum::<f64>()
            .sqrt()
    };
    (before[part].abs() - after[part].abs()) + REST_WEIGHT * (rest(before) - rest(after))
}

/// The parts of `error` from the largest down (ties: the higher index
/// first, as the thesis's inverse model orders them).
fn parts_by_size(error: &[f64; 3]) -> [usize; 3] {
    let mut order = [2, 1, 0];
    order.sort_by(|&a, &b| error[b].abs().total_cmp(&error[a].abs()));
    order
}

impl HybridModel {
    pub(super) fn plan(&mut self, rng: &mut dyn Rng) -> Action {
        let Some(target) = self.target else {
            return Action::ZERO;
        };
        let Some(world) = self.current() else {
            return Action::ZERO;
        };
        let Some(&block) = world.poses.blocks.get(&target.id) else {
            return Action::ZERO;
        };
        let pusher = world.poses.actuator.position();
        let goal = target.pose;
        let now = goal_distance(&block, &goal);
        if now < REACHED {
            self.target = None;
            self.push_plan = None;
            return Action::ZERO;
        }
        let outline = world.outline(target.id);
        let error = error_in(&block, &block, &goal);
        let to_world = Rotation2::new(block.theta);
        // Keep the chosen push while its part of the error is still to be
        // worked on: choosing afresh at every message makes the actuator
        // chase a contact that moves as it moves. Once at the block, a
        // push is kept only while the model says it still helps (the
        // pusher slides along the face as the block turns, so where it is
        // says nothing then).
        let distance = surface_gap(&outline, &block, pusher);
        let local_pusher = to_world.inverse() * (pusher - block.position());
        let touching = outline.closest(local_pusher);
        // At the plan's face, not merely at the block: a pusher that came
        // to rest against another face would slide along it.
        let pushing = |plan: &PushPlan| {
            distance <= STANDOFF / 2.0 && touching.normal.dot(&plan.normal) > SAME_FACE
        };
        let kept = self.push_plan.filter(|plan| {
            let part = error[plan.part];
            if part.signum() != plan.sign || part.abs() <= KEEP {
                return false;
            }
            let wait = block.position()
                + to_world * (plan.contact + plan.normal * (pusher_radius() + STANDOFF));
            let approaching = !pushing(plan) && norm2(wait - pusher) > EPS_CLOSE_ENOUGH;
            approaching || {
                let direction = -(to_world * plan.normal);
                self.roll(target.id, &outline, block, pusher, direction, KEEP_CHECK)
                    .iter()
                    .any(|pose| progress(plan.part, &error, &error_in(&block, pose, &goal)) > 0.0)
            }
        });
        // A kept push goes on wherever along its face the pusher has slid
        // (the roll above says it still helps from there); a new one
        // starts at its contact.
        let under_way = kept.is_some_and(|plan| pushing(&plan));
        let plan = match kept {
            Some(plan) => plan,
            None => {
                let Some(plan) = self.best_push(target.id, block, &goal, &outline, &error) else {
                    self.push_plan = None;
                    return exploration(block.position() - pusher, rng);
                };
                self.push_plan = Some(plan);
                plan
            }
        };
        let wait = plan.contact + plan.normal * (pusher_radius() + STANDOFF);
        let wait_world = block.position() + to_world * wait;
        let delta = wait_world - pusher;
        let gap = norm2(delta);
        let go_round = || {
            let way = round_the_outline(&outline, local_pusher, plan.contact);
            Action::from_vector(scaled(to_world * way, SPEED))
        };
        if gap > EPS_CLOSE {
            return go_round();
        }
        if gap > EPS_CLOSE_ENOUGH && !under_way {
            let u = Action::from_vector(scaled(delta, SPEED));
            // The thesis's safety check (`docs/spec/planning.md` §2): a
            // straight move that would touch the block and knock it away
            // from its target goes round instead. Contact is asked of the
            // geometry, as the thesis asks its gate: the residual memory
            // may move a block a little with no contact at all.
            let touches = surface_gap(&outline, &block, pusher + self.actuator_path(u)) <= 0.0;
            if touches && goal_distance(&self.one_step(target.id, &outline, block, u), &goal) > now
            {
                return go_round();
            }
            return u;
        }
        let direction = -(to_world * plan.normal);
        let mut best = (f64::NEG_INFINITY, Action::ZERO);
        for speed in SPEEDS {
            let u = Action::from_vector(direction * speed);
            let next = self.one_step(target.id, &outline, block, u);
            let gain = progress(plan.part, &error, &error_in(&block, &next, &goal));
            if gain > best.0 {
                best = (gain, u);
            }
        }
        best.1
    }

    /// The block one message after `u`, by the model.
    fn one_step(&self, id: u32, outline: &Outline, block: ObjectState, u: Action) -> ObjectState {
        let Some(world) = self.current() else {
            return block;
        };
        let motion = world.motion.get(&id).copied().unwrap_or_default();
        let from = world.poses.actuator.position();
        self.block_after(id, outline, block, motion, from, self.actuator_path(u))
            .0
    }

    /// The block's poses over `messages` of a push from `pusher` along
    /// `direction` at the approach speed, from rest, by the model.
    fn roll(
        &self,
        id: u32,
        outline: &Outline,
        block: ObjectState,
        mut pusher: Vector2<f64>,
        direction: Vector2<f64>,
        messages: usize,
    ) -> Vec<ObjectState> {
        let path = self.actuator_path(Action::from_vector(direction * SPEED));
        let mut pose = block;
        let mut motion = Twist::default();
        (0..messages)
            .map(|_| {
                let (next, moved) = self.block_after(id, outline, pose, motion, pusher, path);
                pusher += path;
                pose = next;
                motion = moved;
                pose
            })
            .collect()
    }

    /// The push that works best on the largest part of `error` that some
    /// push can work on: of the candidate contacts, the one whose push,
    /// rolled forward over the horizon, makes the most [`progress`] on
    /// that part at its best message. `None` if no push helps any part.
    fn best_push(
        &self,
        id: u32,
        block: ObjectState,
        goal: &ObjectState,
        outline: &Outline,
        error: &[f64; 3],
    ) -> Option<PushPlan> {
        let to_world = Rotation2::new(block.theta);
        // Each candidate's poses over the horizon, rolled once for all parts.
        let rolled: Vec<Rolled> = candidates(outline)
            .into_iter()
            .map(|(contact, normal)| {
                let start = block.position() + to_world * (contact + normal * pusher_radius());
                let errors = self
                    .roll(id, outline, block, start, -(to_world * normal), HORIZON)
                    .iter()
                    .map(|pose| error_in(&block, pose, goal))
                    .collect();
                Rolled {
                    contact,
                    normal,
                    errors,
                }
            })
            .collect();
        for part in parts_by_size(error) {
            let mut best: Option<(f64, Vector2<f64>, Vector2<f64>)> = None;
            for Rolled {
                contact,
                normal,
                errors,
            } in &rolled
            {
                let gain = errors
                    .iter()
                    .map(|after| progress(part, error, after))
                    .fold(f64::NEG_INFINITY, f64::max);
                if gain > 0.0 && best.is_none_or(|b| gain > b.0) {
                    best = Some((gain, *contact, *normal));
                }
            }
            if let Some((_, contact, normal)) = best {
                return Some(PushPlan {
                    contact,
                    normal,
                    part,
                    sign: error[part].signum(),
                });
            }
        }
        None
    }
}

/// Contact points evenly around an outline with their outward normals
/// (slider frame), corners left out: a push at a corner has no normal.
fn candidates(outline: &Outline) -> Vec<(Vector2<f64>, Vector2<f64>)> {
    match *outline {
        Outline::Disc { radius } => (0..CANDIDATES)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / CANDIDATES as f64;
                let n = Vector2::new(a.cos(), a.sin());
                (n * radius, n)
            })
            .collect(),
        Outline::Box { half } => {
            let perimeter = 4.0 * (half[0] + half[1]);
            let faces = [
                (Vector2::new(0.0, -1.0), 2.0 * half[0]),
                (Vector2::new(1.0, 0.0), 2.0 * half[1]),
                (Vector2::new(0.0, 1.0), 2.0 * half[0]),
                (Vector2::new(-1.0, 0.0), 2.0 * half[1]),
            ];
            let mut out = Vec::with_capacity(CANDIDATES);
            for (normal, length) in faces {
                let count = ((CANDIDATES as f64 * length / perimeter).round() as usize).max(1);
                let along = Vector2::new(-normal.y, normal.x);
                let centre = Vector2::new(normal.x * half[0], normal.y * half[1]);
                for j in 0..count {
                    // Points at the middles of `count` equal pieces of the face.
                    let t = (j as f64 + 0.5) / count as f64 - 0.5;
                    out.push((centre + along * (t * length), normal));
                }
            }
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_largest_part_comes_first_and_ties_go_to_the_higher_index() {
        assert_eq!(parts_by_size(&[0.1, -0.3, 0.2]), [1, 2, 0]);
        assert_eq!(parts_by_size(&[0.2, -0.2, 0.2]), [2, 1, 0]);
        assert_eq!(parts_by_size(&[-0.5, 0.0, 0.0]), [0, 2, 1]);
    }

    #[test]
    fn the_error_is_in_the_blocks_frame_and_the_turn_the_short_way() {
        let block = ObjectState::new(1.0, 0.0, std::f64::consts::FRAC_PI_2);
        let goal = ObjectState::new(1.0, 0.5, -3.0);
        let e = error_in(&block, &block, &goal);
        // Straight ahead along the block's own x axis, which points up.
        assert!((e[0] - 0.5).abs() < 1e-12 && e[1].abs() < 1e-12);
        // From π/2 to −3.0 is −4.57 rad one way, +1.71 the other.
        assert!(
            (e[2] - (-3.0 - std::f64::consts::FRAC_PI_2 + std::f64::consts::TAU)).abs() < 1e-12
        );
    }

    #[test]
    fn progress_leads_with_the_chosen_part_and_punishes_overshoot() {
        let before = [0.2, 0.1, 0.0];
        // Halving the chosen part while the rest grows a little still helps.
        assert!(progress(0, &before, &[0.1, 0.15, 0.0]) > 0.0);
        // Overshooting to the other side by more than it was is no help.
        assert!(progress(0, &before, &[-0.25, 0.1, 0.0]) < 0.0);
        // Nothing moved: nothing gained.
        assert_eq!(progress(1, &before, &before), 0.0);
    }

    #[test]
    fn along_the_outline_and_back_agree() {
        let bar = Outline::Box { half: [0.25, 0.05] };
        assert!((perimeter(&bar) - 1.2).abs() < 1e-12);
        for i in 0..120 {
            let s = 0.01 * f64::from(i) + 0.005;
            let (point, normal) = at_along(&bar, s);
            assert!((along(&bar, point) - s).abs() < 1e-12, "at {s}");
            assert_eq!(bar.closest(point + normal * 0.01).normal, normal);
        }
        let disc = Outline::Disc { radius: 0.1 };
        let (point, normal) = at_along(&disc, 0.1);
        assert!((along(&disc, point) - 0.1).abs() < 1e-12);
        assert!((normal.norm() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn going_round_takes_the_shorter_way_and_keeps_clear() {
        let bar = Outline::Box { half: [0.25, 0.05] };
        // Below the middle of the long face, for a contact near the right
        // end of the top face: round the right end (counter-clockwise).
        let pusher = Vector2::new(0.0, -0.125);
        let way = round_the_outline(&bar, pusher, Vector2::new(0.2, 0.05));
        assert!(way.x > 0.0 && way.y.abs() < 1e-12, "{way:?}");
        // The same contact seen from the left end: the top face is shorter.
        let pusher = Vector2::new(-0.325, 0.0);
        let way = round_the_outline(&bar, pusher, Vector2::new(0.2, 0.05));
        assert!(way.y > 0.0 && way.x.abs() < 1e-12, "{way:?}");
        // Too close: the aim is out at the clearance.
        let pusher = Vector2::new(0.0, -0.08);
        let way = round_the_outline(&bar, pusher, Vector2::new(-0.2, -0.05));
        assert!(way.y < 0.0 && way.x < 0.0, "{way:?}");
    }

    #[test]
    fn candidates_cover_every_face_in_proportion() {
        let c = candidates(&Outline::Box { half: [0.25, 0.05] });
        assert_eq!(c.len(), 48);
        let on_long = c.iter().filter(|(_, n)| n.x == 0.0).count();
        assert_eq!(on_long, 40);
        for (p, n) in &c {
            assert!(p.x.abs() <= 0.25 + 1e-12 && p.y.abs() <= 0.05 + 1e-12);
            assert!((n.norm() - 1.0).abs() < 1e-12);
        }
        assert_eq!(candidates(&Outline::Disc { radius: 0.1 }).len(), 48);
    }
}
