//! Interaction model features (`docs/spec/features.md` §6).

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use nalgebra::{Matrix3, Vector2};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::round::r3_vec;
use super::transform::{
    apply_homogeneous, inverse_transform, local_point, local_vec, mat_mul, transform,
};
use crate::types::{Action, ObjectState, Poses, Target, ACTUATOR_ID};

/// Number of interaction-state components.
pub const INTERACTION_DIM: usize = 8;
/// Interaction state plus local action: the input of the ACs, the ACS and the
/// global AIM (`docs/spec/interaction-model.md` §1).
pub const INTERACTION_INPUT_DIM: usize = INTERACTION_DIM + 2;
/// The components of a target difference that planning uses (`docs/spec/features.md` §6.5).
pub const TARGET_FEATURES: [usize; 3] = [2, 3, 4];
/// ε_noise at 100 Hz (`docs/spec/README.md` §6; the thesis's table says 0.01).
pub const EPS_NOISE_100HZ: f64 = 0.001;
/// ε_noise at 10 Hz.
pub const EPS_NOISE_10HZ: f64 = 0.01;

/// The key of an ordered object pair, written "n1,n2" (e.g. "15,8")
/// (`docs/spec/features.md` §6.1). Ordered by (reference, secondary); serialised as the
/// string so that it can key JSON maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(into = "String", try_from = "String")]
pub struct PairKey {
    pub reference: u32,
    pub secondary: u32,
}

impl PairKey {
    #[must_use]
    pub const fn new(reference: u32, secondary: u32) -> Self {
        Self {
            reference,
            secondary,
        }
    }
}

impl fmt::Display for PairKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{},{}", self.reference, self.secondary)
    }
}

/// A string that is not "n1,n2" with two unsigned integers.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[error("not a pair key \"n1,n2\": {0:?}")]
pub struct PairKeyError(pub String);

impl FromStr for PairKey {
    type Err = PairKeyError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let parse = || {
            let (a, b) = s.split_once(',')?;
            Some(PairKey::new(a.parse().ok()?, b.parse().ok()?))
        };
        parse().ok_or_else(|| PairKeyError(s.to_owned()))
    }
}

impl From<PairKey> for String {
    fn from(k: PairKey) -> Self {
        k.to_string()
    }
}

impl TryFrom<String> for PairKey {
    type Error = PairKeyError;

    fn try_from(s: String) -> Result<Self, Self::Error> {
        s.parse()
    }
}

/// An interaction state ι(o1, o2) (`docs/spec/features.md` §6.1): eight components plus
/// the attached frame of the reference object at the time it was computed.
///
/// A prediction changes `components` but keeps `t`, `t_inv` and `theta_ref`
/// (`docs/spec/interaction-model.md` §5), so the attachments are stored, never derived
/// from the components.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct InteractionState {
    /// `[id1, id2, x1', y1', θ1', x2', y2', θ2 − θ1]` (reference's own local
    /// pose, 0 when computed; secondary's pose relative to the reference).
    pub components: [f64; INTERACTION_DIM],
    /// `T(θ1, p1)`.
    pub t: Matrix3<f64>,
    /// `T⁻¹(θ1, p1)`, built as `(Rᵀ, −Rᵀp)`.
    pub t_inv: Matrix3<f64>,
    /// `θ1`.
    pub theta_ref: f64,
}

/// Objects extracted from an interaction state (`docs/spec/features.md` §6.4).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExtractedPair {
    pub reference_id: u32,
    pub reference: ObjectState,
    pub secondary_id: u32,
    /// Always with yaw 0: component 7 is not used.
    pub secondary: ObjectState,
}

/// An id stored as a feature component back as an id. Ids are small integers,
/// exactly representable; anything else (which no computation here produces)
/// saturates as Rust's `as` does.
fn id_from_component(v: f64) -> u32 {
    v as u32
}

impl InteractionState {
    /// ι(o1, o2) from object states (`docs/spec/features.md` §6.1).
    #[must_use]
    pub fn new(
        reference_id: u32,
        reference: &ObjectState,
        secondary_id: u32,
        secondary: &ObjectState,
    ) -> Self {
        let (theta, p) = (reference.theta, reference.position());
        let rel = r3_vec(local_point(theta, p, secondary.position()));
        Self {
            components: [
                f64::from(reference_id),
                f64::from(secondary_id),
                0.0,
                0.0,
                0.0,
                rel.x,
                rel.y,
                secondary.theta - reference.theta,
            ],
            t: transform(theta, p),
            t_inv: inverse_transform(theta, p),
            theta_ref: theta,
        }
    }

    /// The pair this state describes, from components 0 and 1.
    #[must_use]
    pub fn key(&self) -> PairKey {
        PairKey::new(
            id_from_component(self.components[0]),
            id_from_component(self.components[1]),
        )
    }

    /// The global action in this state's reference frame (`docs/spec/features.md` §6.2).
    #[must_use]
    pub fn local_action(&self, action: Action) -> Vector2<f64> {
        local_action(self.theta_ref, action)
    }

    /// `[ι (8), a_local (2)]`, the input of the ACs, the ACS and the global
    /// AIM (`docs/spec/interaction-model.md` §3).
    #[must_use]
    pub fn input(&self, action: Action) -> [f64; INTERACTION_INPUT_DIM] {
        let a = self.local_action(action);
        let c = &self.components;
        [c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], a.x, a.y]
    }

    /// Global object states encoded by this state, through its attached `T`
    /// (`docs/spec/features.md` §6.4); unrounded.
    #[must_use]
    pub fn extract(&self) -> ExtractedPair {
        let c = &self.components;
        let p1 = apply_homogeneous(&self.t, Vector2::new(c[2], c[3]));
        let p2 = apply_homogeneous(&self.t, Vector2::new(c[5], c[6]));
        ExtractedPair {
            reference_id: id_from_component(c[0]),
            reference: ObjectState::new(p1.x, p1.y, c[4] + self.theta_ref),
            secondary_id: id_from_component(c[1]),
            secondary: ObjectState::new(p2.x, p2.y, 0.0),
        }
    }
}

/// `a_local = R(θ_ref)ᵀ a`, not rounded (`docs/spec/features.md` §6.2).
#[must_use]
pub fn local_action(theta_ref: f64, action: Action) -> Vector2<f64> {
    local_vec(theta_ref, action.to_vector())
}

/// Every interaction state of a world (`docs/spec/features.md` §6.1): ι(n1, n2) for each
/// object `n1` other than the actuator and each object `n2 ≠ n1`.
#[must_use]
pub fn interaction_states(poses: &Poses) -> BTreeMap<PairKey, InteractionState> {
    let objects: Vec<(u32, ObjectState)> = poses.objects().collect();
    let mut states = BTreeMap::new();
    for (n1, s1) in objects.iter().filter(|(id, _)| *id != ACTUATOR_ID) {
        for (n2, s2) in objects.iter().filter(|(id, _)| id != n1) {
            states.insert(
                PairKey::new(*n1, *n2),
                InteractionState::new(*n1, s1, *n2, s2),
            );
        }
    }
    states
}

/// The episode difference `d(pre, post)` (`docs/spec/features.md` §6.3): `post`
/// re-expressed in `pre`'s frame, minus `pre`; not rounded.
#[must_use]
pub fn episode_difference(
    pre: &InteractionState,
    post: &InteractionState,
) -> [f64; INTERACTION_DIM] {
    let m = mat_mul(&pre.t_inv, &post.t);
    let src = &post.components;
    let mut star = *src;
    let own = apply_homogeneous(&m, Vector2::new(src[2], src[3]));
    (star[2], star[3]) = (own.x, own.y);
    star[4] = src[4] + post.theta_ref - pre.theta_ref;
    let other = apply_homogeneous(&m, Vector2::new(src[5], src[6]));
    (star[5], star[6]) = (other.x, other.y);
    std::array::from_fn(|i| star[i] - pre.components[i])
}

/// The changed-feature set `S = { i : |d_i| > ε_noise }`, ascending
/// (`docs/spec/features.md` §6.3). Strict: a change of exactly ε_noise is noise.
#[must_use]
pub fn changed_features(d: &[f64], eps_noise: f64) -> Vec<usize> {
    d.iter()
        .enumerate()
        .filter(|(_, v)| v.abs() > eps_noise)
        .map(|(i, _)| i)
        .collect()
}

/// Object states from predicted interaction states ("finalisation",
/// `docs/spec/interaction-model.md` §5): each state's pair is extracted in key order,
/// later pairs overwriting earlier ones. `None` if no state yields the
/// actuator (e.g. an empty map).
#[must_use]
pub fn poses_from_states(states: &BTreeMap<PairKey, InteractionState>) -> Option<Poses> {
    let mut objects: BTreeMap<u32, ObjectState> = BTreeMap::new();
    for state in states.values() {
        let e = state.extract();
        objects.insert(e.reference_id, e.reference);
        objects.insert(e.secondary_id, e.secondary);
    }
    let actuator = objects.remove(&ACTUATOR_ID)?;
    Some(Poses {
        actuator,
        blocks: objects,
    })
}

/// The target interaction state (`docs/spec/features.md` §6.5): ι(target block, dummy
/// actuator at (0, 0, 0) with id 8). Planning uses only components
/// [`TARGET_FEATURES`] of differences to it.
#[must_use]
pub fn target_interaction_state(target: &Target) -> InteractionState {
    InteractionState::new(
        target.id,
        &target.pose,
        ACTUATOR_ID,
        &ObjectState::default(),
    )
}

#[cfg(test)]
mod tests {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_3, PI};

    use super::*;
    use crate::types::{BLUE_ID, RED_ID};

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-4
    }

    fn assert_mat(got: &Matrix3<f64>, want: [[f64; 3]; 3]) {
        for (r, row) in want.iter().enumerate() {
            for (c, w) in row.iter().enumerate() {
                assert!(
                    close(got[(r, c)], *w),
                    "({r},{c}): got {got}, want {want:?}"
                );
            }
        }
    }

    fn blue_at(x: f64, y: f64, theta: f64) -> ObjectState {
        ObjectState::new(x, y, theta)
    }

    /// docs/spec/features.md §7 example 6.
    #[test]
    fn example_6_interaction_state() {
        let s = InteractionState::new(
            BLUE_ID,
            &blue_at(0.0, 0.5, 0.0),
            ACTUATOR_ID,
            &ObjectState::default(),
        );
        assert_eq!(&s.components[..7], &[15.0, 8.0, 0.0, 0.0, 0.0, 0.0, -0.5]);
        assert_eq!(s.components[7], 0.0);
        assert_mat(&s.t, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.5], [0.0, 0.0, 1.0]]);
        assert_mat(
            &s.t_inv,
            [[1.0, 0.0, 0.0], [0.0, 1.0, -0.5], [0.0, 0.0, 1.0]],
        );
        assert_eq!(s.theta_ref, 0.0);
        assert_eq!(s.key(), PairKey::new(15, 8));

        let s = InteractionState::new(
            BLUE_ID,
            &blue_at(0.0, 0.5, FRAC_PI_2),
            ACTUATOR_ID,
            &ObjectState::default(),
        );
        assert_eq!((s.components[5], s.components[6]), (-0.5, 0.0));
        assert_eq!(s.components[7], -FRAC_PI_2);

        let s = InteractionState::new(
            BLUE_ID,
            &blue_at(3.0, 2.0, FRAC_PI_3),
            ACTUATOR_ID,
            &ObjectState::new(2.5, -1.1, 0.0),
        );
        assert_eq!((s.components[5], s.components[6]), (-2.935, -1.117));
        assert!(close(s.t_inv[(0, 2)], -3.2321) && close(s.t_inv[(1, 2)], 1.5981));
        let (c, sn) = (FRAC_PI_3.cos(), FRAC_PI_3.sin());
        assert_eq!(s.t_inv[(0, 2)], -(3.0 * c + 2.0 * sn));
        assert_eq!(s.t_inv[(1, 2)], -(-3.0 * sn + 2.0 * c));
    }

    #[test]
    fn relative_orientation_is_a_plain_difference() {
        let s = InteractionState::new(
            BLUE_ID,
            &blue_at(0.0, 0.5, 3.0),
            ACTUATOR_ID,
            &ObjectState::new(0.0, 0.0, -3.0),
        );
        assert_eq!(s.components[7], -6.0);
    }

    /// docs/spec/features.md §7 example 7.
    #[test]
    fn example_7_episode_difference_and_changed_set() {
        let block = blue_at(0.0, 0.5, 0.0);
        let pre = InteractionState::new(BLUE_ID, &block, ACTUATOR_ID, &ObjectState::default());
        let post = InteractionState::new(
            BLUE_ID,
            &block,
            ACTUATOR_ID,
            &ObjectState::new(0.0, 0.05, 0.0),
        );
        let d = episode_difference(&pre, &post);
        let want = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.05, 0.0];
        assert!(d.iter().zip(&want).all(|(g, w)| close(*g, *w)), "{d:?}");
        assert_eq!(changed_features(&d, EPS_NOISE_100HZ), vec![6]);

        let post2 = InteractionState {
            components: [15.0, 8.0, 0.0, 0.0, 0.0, 0.1, -0.45, 0.0],
            ..pre
        };
        let d = episode_difference(&pre, &post2);
        assert_eq!(changed_features(&d, EPS_NOISE_100HZ), vec![5, 6]);
    }

    #[test]
    fn episode_difference_uses_the_pre_frame() {
        // The block turns by π/2 in place and the actuator stays put: in the
        // pre frame the actuator did not move (d[5:7] ≈ 0) but the reference
        // turned (d[4] = π/2), and component 7 changes by −π/2.
        let pre = InteractionState::new(
            BLUE_ID,
            &blue_at(0.0, 0.5, 0.0),
            ACTUATOR_ID,
            &ObjectState::default(),
        );
        let post = InteractionState::new(
            BLUE_ID,
            &blue_at(0.0, 0.5, FRAC_PI_2),
            ACTUATOR_ID,
            &ObjectState::default(),
        );
        let d = episode_difference(&pre, &post);
        assert!(d[2].abs() < 1e-12 && d[3].abs() < 1e-12);
        assert!(close(d[4], FRAC_PI_2));
        assert!(d[5].abs() < 1e-3 && d[6].abs() < 1e-3);
        assert!(close(d[7], -FRAC_PI_2));
        assert_eq!(changed_features(&d, EPS_NOISE_100HZ), vec![4, 7]);

        // The block moves by (0.1, 0) under a frame turned by π/2: its own local
        // position change in the pre frame is (0, −0.1).
        let pre = InteractionState::new(
            BLUE_ID,
            &blue_at(0.0, 0.5, FRAC_PI_2),
            ACTUATOR_ID,
            &ObjectState::default(),
        );
        let post = InteractionState::new(
            BLUE_ID,
            &blue_at(0.1, 0.5, FRAC_PI_2),
            ACTUATOR_ID,
            &ObjectState::default(),
        );
        let d = episode_difference(&pre, &post);
        assert!(close(d[2], 0.0) && close(d[3], -0.1), "{d:?}");
    }

    #[test]
    fn episode_difference_is_not_rounded_and_does_not_wrap() {
        let pre = InteractionState::new(
            BLUE_ID,
            &blue_at(0.0, 0.0, 3.1),
            ACTUATOR_ID,
            &ObjectState::new(0.0, -0.2, 0.0),
        );
        let post = InteractionState::new(
            BLUE_ID,
            &blue_at(0.0, 0.0, -3.1),
            ACTUATOR_ID,
            &ObjectState::new(0.0, -0.2, 0.0),
        );
        let d = episode_difference(&pre, &post);
        // Turning "by 0.083" across ±π shows up as −6.2 (docs/spec/README.md §5).
        assert!(close(d[4], -6.2));
        assert!(close(d[7], 6.2));

        let pre = InteractionState::new(
            BLUE_ID,
            &blue_at(0.0, 0.5, 0.0),
            ACTUATOR_ID,
            &ObjectState::default(),
        );
        let post = InteractionState {
            components: [15.0, 8.0, 0.000_123_4, 0.0, 0.0, 0.0, -0.5, 0.0],
            ..pre
        };
        assert_eq!(episode_difference(&pre, &post)[2], 0.000_123_4);
    }

    #[test]
    fn changed_set_threshold_is_strict() {
        let d = [
            0.0,
            0.0,
            0.001,
            -0.001,
            0.001_000_1,
            -0.001_000_1,
            0.0,
            2.0 * PI,
        ];
        assert_eq!(changed_features(&d, 0.001), vec![4, 5, 7]);
        assert_eq!(changed_features(&d, 0.01), vec![7]);
        assert!(changed_features(&[0.0; 8], 0.0).is_empty());
        assert_eq!(changed_features(&[0.0, 1e-300], 0.0), vec![1]);
    }

    /// docs/spec/features.md §7 example 8.
    #[test]
    fn example_8_extraction() {
        let s = InteractionState {
            components: [15.0, 8.0, 0.0, 0.1, 0.0, -0.5, 0.1, 0.3],
            t: transform(FRAC_PI_2, Vector2::new(0.0, 0.5)),
            t_inv: inverse_transform(FRAC_PI_2, Vector2::new(0.0, 0.5)),
            theta_ref: FRAC_PI_2,
        };
        let e = s.extract();
        assert_eq!((e.reference_id, e.secondary_id), (15, 8));
        assert!(close(e.reference.x, -0.1) && close(e.reference.y, 0.5));
        assert_eq!(e.reference.theta, FRAC_PI_2);
        assert!(close(e.secondary.x, -0.1) && close(e.secondary.y, 0.0));
        // Component 7 is not used: the secondary's yaw is always 0.
        assert_eq!(e.secondary.theta, 0.0);
    }

    #[test]
    fn extraction_inverts_construction() {
        let block = blue_at(0.3, -0.2, 0.7);
        let act = ObjectState::new(0.1, -0.5, 0.0);
        let e = InteractionState::new(BLUE_ID, &block, ACTUATOR_ID, &act).extract();
        assert!(e.reference.distance_to(&block) < 1e-12);
        assert!(e.secondary.distance_to(&act) < 1e-3);
    }

    #[test]
    fn local_action_and_input() {
        let s = InteractionState::new(
            BLUE_ID,
            &blue_at(0.0, 0.5, FRAC_PI_2),
            ACTUATOR_ID,
            &ObjectState::default(),
        );
        let a = s.local_action(Action::new(0.0, 0.5));
        assert!(close(a.x, 0.5) && close(a.y, 0.0));
        // Not rounded.
        assert_ne!(a.y, 0.0);
        let x = s.input(Action::new(0.0, 0.5));
        assert_eq!(&x[..8], &s.components[..]);
        assert_eq!((x[8], x[9]), (a.x, a.y));
    }

    #[test]
    fn all_pairs_of_a_world() {
        let mut poses = Poses {
            actuator: ObjectState::new(0.0, 0.0, 0.2),
            blocks: BTreeMap::new(),
        };
        poses.blocks.insert(BLUE_ID, blue_at(0.0, 0.25, 0.0));
        let states = interaction_states(&poses);
        assert_eq!(
            states.keys().map(ToString::to_string).collect::<Vec<_>>(),
            vec!["15,8"]
        );
        assert!(close(states[&PairKey::new(15, 8)].components[7], 0.2));

        poses.blocks.insert(RED_ID, blue_at(-0.6, 0.35, 0.0));
        let keys: Vec<String> = interaction_states(&poses)
            .keys()
            .map(ToString::to_string)
            .collect();
        assert_eq!(keys, vec!["15,8", "15,27", "27,8", "27,15"]);
    }

    #[test]
    fn finalisation_round_trip() {
        let mut poses = Poses {
            actuator: ObjectState::new(0.05, 0.0, 0.0),
            blocks: BTreeMap::new(),
        };
        poses.blocks.insert(BLUE_ID, blue_at(0.0, 0.25, 0.4));
        let back = poses_from_states(&interaction_states(&poses)).unwrap();
        assert!(back.blocks[&BLUE_ID].distance_to(&poses.blocks[&BLUE_ID]) < 1e-12);
        assert!(back.actuator.distance_to(&poses.actuator) < 1e-3);
        assert_eq!(poses_from_states(&BTreeMap::new()), None);
    }

    #[test]
    fn target_state() {
        let target = Target::new(BLUE_ID, ObjectState::new(0.6, 0.7, -2.1));
        let t = target_interaction_state(&target);
        assert_eq!(t.theta_ref, -2.1);
        assert_eq!(&t.components[..5], &[15.0, 8.0, 0.0, 0.0, 0.0]);
        assert_eq!(t.components[7], 2.1);
        // Planning's difference to it: the block's own change in the current frame.
        let current = InteractionState::new(
            BLUE_ID,
            &blue_at(0.0, 0.25, 0.0),
            ACTUATOR_ID,
            &ObjectState::default(),
        );
        let d = episode_difference(&current, &t);
        assert!(
            close(d[2], 0.6) && close(d[3], 0.45) && close(d[4], -2.1),
            "{d:?}"
        );
        assert_eq!(TARGET_FEATURES, [2, 3, 4]);
    }

    #[test]
    fn pair_keys_as_strings() {
        let k: PairKey = "15,8".parse().unwrap();
        assert_eq!(k, PairKey::new(15, 8));
        assert_eq!(k.to_string(), "15,8");
        assert!("15".parse::<PairKey>().is_err());
        assert!("15,x".parse::<PairKey>().is_err());
        assert!(PairKey::new(15, 27) < PairKey::new(27, 8));
        let mut m = BTreeMap::new();
        m.insert(k, 1);
        let json = serde_json::to_string(&m).unwrap();
        assert_eq!(json, r#"{"15,8":1}"#);
        let back: BTreeMap<PairKey, i32> = serde_json::from_str(&json).unwrap();
        assert_eq!(back, m);
    }

    #[test]
    fn interaction_state_round_trips_through_json() {
        let s = InteractionState::new(
            BLUE_ID,
            &blue_at(0.1, 0.5, 0.3),
            ACTUATOR_ID,
            &ObjectState::new(0.0, 0.1, 0.0),
        );
        let back: InteractionState =
            serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
        assert_eq!(back, s);
    }
}
