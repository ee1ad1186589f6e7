//! Move to Target with the hybrid model: push where the model says the
//! block goes towards its target.
//!
//! A frictionless pusher can only push along the normal of the face it
//! touches, so a push is chosen by where it starts: every candidate
//! contact around the block's outline is rolled forward with the model
//! for a short push, and the one that ends nearest the target wins. The
//! actuator then gets there the way the thesis's planners do
//! (`docs/spec/planning.md` §2, §4: circling at a distance, a straight
//! approach) and pushes, at the speed the model predicts best for the
//! next message. The choice is made again at every message, so a push
//! turns into another as the block turns.

use nalgebra::{Rotation2, Vector2};
use rand::Rng;

use super::mechanics::{Outline, Twist};
use super::model::{pusher_radius, surface_gap, HybridModel};
use crate::planning::{
    circle, exploration, norm2, scaled, APPROACH_SPEED, EPS_CLOSE, EPS_CLOSE_ENOUGH, REACHED,
};
use crate::types::{Action, ObjectState};

/// Candidate contacts per outline.
const CANDIDATES: usize = 48;
/// Messages a candidate push is rolled forward.
const HORIZON: usize = 12;
/// The pusher waits this far off the outline before a push.
const STANDOFF: f64 = 0.005;
/// Push speeds weighed at each message, fastest first (ties go to speed).
const SPEEDS: [f64; 5] = [APPROACH_SPEED, 0.2, 0.1, 0.05, 0.02];

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
        let now = block.distance_to(&goal);
        if now < REACHED {
            self.target = None;
            return Action::ZERO;
        }
        let outline = world.outline(target.id);
        // Keep the chosen push while it still brings the block nearer:
        // choosing afresh at every message makes the actuator chase a
        // contact that moves as it moves. Once at the block, a push is
        // kept only while the model says it still helps (the pusher slides
        // along the face as the block turns, so where it is says nothing
        // then).
        let distance = surface_gap(&outline, &block, pusher);
        let at_block = distance <= STANDOFF;
        let kept = self.push_plan.filter(|&(contact, normal)| {
            let to_world = Rotation2::new(block.theta);
            let wait =
                block.position() + to_world * (contact + normal * (pusher_radius() + STANDOFF));
            let approaching = !at_block && norm2(wait - pusher) > EPS_CLOSE_ENOUGH;
            let u = Action::from_vector(-(to_world * normal) * APPROACH_SPEED);
            approaching
                || self
                    .one_step(target.id, &outline, block, u)
                    .distance_to(&goal)
                    < now
        });
        let (contact, normal) = match kept {
            Some(plan) => plan,
            None => {
                let Some((contact, normal, reached)) =
                    self.best_push(target.id, block, &goal, &outline)
                else {
                    self.push_plan = None;
                    return exploration(block.position() - pusher, rng);
                };
                if reached >= now {
                    self.push_plan = None;
                    return exploration(block.position() - pusher, rng);
                }
                self.push_plan = Some((contact, normal));
                (contact, normal)
            }
        };
        let to_world = Rotation2::new(block.theta);
        let wait = contact + normal * (pusher_radius() + STANDOFF);
        let wait_world = block.position() + to_world * wait;
        let delta = wait_world - pusher;
        let gap = norm2(delta);
        let local_pusher = to_world.inverse() * (pusher - block.position());
        let r = pusher - block.position();
        if gap > EPS_CLOSE {
            return circle(distance, r, local_pusher.y.atan2(local_pusher.x), wait);
        }
        if gap > EPS_CLOSE_ENOUGH && distance > STANDOFF / 2.0 {
            let u = Action::from_vector(scaled(delta, APPROACH_SPEED));
            if self
                .one_step(target.id, &outline, block, u)
                .distance_to(&goal)
                > now
            {
                return circle(distance, r, local_pusher.y.atan2(local_pusher.x), wait);
            }
            return u;
        }
        let direction = -(to_world * normal);
        let mut best = (f64::INFINITY, Action::ZERO);
        for speed in SPEEDS {
            let u = Action::from_vector(direction * speed);
            let d = self
                .one_step(target.id, &outline, block, u)
                .distance_to(&goal);
            if d < best.0 {
                best = (d, u);
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

    /// Of the candidate contacts (slider frame), the one whose push brings
    /// the block nearest the goal within the horizon: its contact point,
    /// outward normal and the distance it reached.
    fn best_push(
        &self,
        id: u32,
        block: ObjectState,
        goal: &ObjectState,
        outline: &Outline,
    ) -> Option<(Vector2<f64>, Vector2<f64>, f64)> {
        let to_world = Rotation2::new(block.theta);
        let mut best: Option<(Vector2<f64>, Vector2<f64>, f64)> = None;
        for (contact, normal) in candidates(outline) {
            let mut pusher = block.position() + to_world * (contact + normal * pusher_radius());
            let direction = -(to_world * normal);
            let path = self.actuator_path(Action::from_vector(direction * APPROACH_SPEED));
            let mut pose = block;
            let mut motion = Twist::default();
            let mut nearest = f64::INFINITY;
            for _ in 0..HORIZON {
                let (next, moved) = self.block_after(id, outline, pose, motion, pusher, path);
                pusher += path;
                pose = next;
                motion = moved;
                nearest = nearest.min(pose.distance_to(goal));
            }
            if best.is_none_or(|b| nearest < b.2) {
                best = Some((contact, normal, nearest));
            }
        }
        best
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
