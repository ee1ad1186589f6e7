//! Parsing a world-state [`Frame`] into object states (`docs/spec/features.md` §1,
//! `docs/spec/protocol.md` §4), and the reverse yaw → quaternion conversion.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::round::Precision;
use super::shape::Shape;
use crate::types::{Frame, ObjectState, Observation, Poses, ACTUATOR_ID, ACTUATOR_NAME};

/// Why a [`Frame`] could not be parsed. Parsing never panics on what the world
/// sends.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum ParseError {
    #[error("the frame has no model named \"{ACTUATOR_NAME}\"")]
    NoActuator,
    #[error("the frame has more than one model named \"{ACTUATOR_NAME}\"")]
    DuplicateActuator,
    /// The ids are feature components (`docs/spec/README.md` §7.1), so a renumbered
    /// actuator would silently change every feature vector.
    #[error("the actuator has id {id}, expected {ACTUATOR_ID}")]
    ActuatorId { id: u32 },
    /// Only ids with an entry in the shape table (`docs/spec/features.md` §4) other than
    /// the actuator's can be blocks.
    #[error("model {name:?} has id {id}, which is not a block id of the learner's shape table")]
    UnknownBlock { name: String, id: u32 },
    #[error("models {first:?} and {second:?} share the block id {id}")]
    DuplicateBlock {
        id: u32,
        first: String,
        second: String,
    },
    #[error("model {name:?}: {field} is not a finite number ({value})")]
    NonFinite {
        name: String,
        field: &'static str,
        value: f64,
    },
    /// Finite, but so large that `r3` overflows.
    #[error("model {name:?}: {field} = {value} is too large to round to 3 decimals")]
    OutOfRange {
        name: String,
        field: &'static str,
        value: f64,
    },
}

/// What parsing does with the actuator's yaw (`docs/spec/features.md` §1 step 4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ActuatorYaw {
    /// The gate model: `θ := 0` after parsing.
    ForceZero,
    /// The interaction model: keep the reported, rounded yaw.
    #[default]
    Keep,
}

// The skip rule and the yaw are the vocabulary's, so that the wire, the world
// and the Python extension read the same bodies and yaws as the models.
pub use pushlearn_core::body::is_skipped;
pub use pushlearn_core::orientation::{from_yaw as yaw_to_quaternion, yaw as quaternion_to_yaw};

fn finite(name: &str, field: &'static str, value: f64) -> Result<f64, ParseError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ParseError::NonFinite {
            name: name.to_owned(),
            field,
            value,
        })
    }
}

fn rounded(
    name: &str,
    field: &'static str,
    value: f64,
    precision: Precision,
) -> Result<f64, ParseError> {
    let r = precision.round(value);
    if r.is_finite() {
        Ok(r)
    } else {
        Err(ParseError::OutOfRange {
            name: name.to_owned(),
            field,
            value,
        })
    }
}

/// `s = (r3(x), r3(y), r3(yaw))` of one observation (`docs/spec/features.md` §1 steps
/// 1–3). The z coordinate is not read, so it is not checked either.
pub fn parse_observation(obs: &Observation) -> Result<ObjectState, ParseError> {
    parse_observation_at(obs, Precision::Thesis)
}

/// [`parse_observation`] rounded at `precision`.
pub fn parse_observation_at(
    obs: &Observation,
    precision: Precision,
) -> Result<ObjectState, ParseError> {
    let name = obs.name.as_str();
    let px = finite(name, "position.x", obs.position[0])?;
    let py = finite(name, "position.y", obs.position[1])?;
    const Q_FIELDS: [&str; 4] = [
        "orientation.x",
        "orientation.y",
        "orientation.z",
        "orientation.w",
    ];
    for (field, &value) in Q_FIELDS.into_iter().zip(&obs.orientation) {
        finite(name, field, value)?;
    }
    Ok(ObjectState {
        x: rounded(name, "position.x", px, precision)?,
        y: rounded(name, "position.y", py, precision)?,
        // atan2 lies in [−π, π], r3 cannot overflow there.
        theta: precision.round(quaternion_to_yaw(obs.orientation)),
    })
}

/// Parse a frame into the actuator's and the blocks' states (`docs/spec/features.md` §1,
/// `docs/spec/protocol.md` §4).
///
/// The actuator is the model named exactly `actuator` and must carry id 8;
/// skipped models ([`is_skipped`]) are ignored without any check; every other
/// model is a block keyed by its id, which must be a block id of the shape
/// table (15 or 27) and unique. `actuator_yaw` is the model's yaw rule.
/// Previous states (§1 step 5) are the caller's: see
/// [`TrackedObject::fresh`](crate::types::TrackedObject::fresh).
pub fn parse_frame(frame: &Frame, actuator_yaw: ActuatorYaw) -> Result<Poses, ParseError> {
    parse_frame_at(frame, actuator_yaw, Precision::Thesis)
}

/// [`parse_frame`] with the states rounded at `precision`.
pub fn parse_frame_at(
    frame: &Frame,
    actuator_yaw: ActuatorYaw,
    precision: Precision,
) -> Result<Poses, ParseError> {
    let mut actuator: Option<ObjectState> = None;
    let mut blocks: BTreeMap<u32, (ObjectState, &str)> = BTreeMap::new();
    for obs in &frame.objects {
        if is_skipped(&obs.name) {
            continue;
        }
        if obs.name == ACTUATOR_NAME {
            if actuator.is_some() {
                return Err(ParseError::DuplicateActuator);
            }
            if obs.id != ACTUATOR_ID {
                return Err(ParseError::ActuatorId { id: obs.id });
            }
            let mut s = parse_observation_at(obs, precision)?;
            if actuator_yaw == ActuatorYaw::ForceZero {
                s.theta = 0.0;
            }
            actuator = Some(s);
            continue;
        }
        if obs.id == ACTUATOR_ID || Shape::of(obs.id).is_none() {
            return Err(ParseError::UnknownBlock {
                name: obs.name.clone(),
                id: obs.id,
            });
        }
        let s = parse_observation_at(obs, precision)?;
        if let Some((_, first)) = blocks.insert(obs.id, (s, obs.name.as_str())) {
            return Err(ParseError::DuplicateBlock {
                id: obs.id,
                first: first.to_owned(),
                second: obs.name.clone(),
            });
        }
    }
    let actuator = actuator.ok_or(ParseError::NoActuator)?;
    Ok(Poses {
        actuator,
        blocks: blocks.into_iter().map(|(id, (s, _))| (id, s)).collect(),
    })
}

#[cfg(test)]
mod tests {
    use std::f64::consts::{FRAC_PI_2, PI};

    use super::*;
    use crate::types::{BLUE_ID, RED_ID};

    fn obs(name: &str, id: u32, x: f64, y: f64, q: [f64; 4]) -> Observation {
        Observation {
            name: name.to_owned(),
            id,
            position: [x, y, 0.05],
            orientation: q,
            shape: None,
        }
    }

    fn yaw_q(theta: f64) -> [f64; 4] {
        yaw_to_quaternion(theta)
    }

    fn one_block(actuator_yaw: f64) -> Frame {
        Frame {
            objects: vec![
                obs("ground_plane", 0, 0.0, 0.0, [0.0, 0.0, 0.0, 1.0]),
                obs("actuator", 8, 0.123_45, -0.000_5, yaw_q(actuator_yaw)),
                obs("blockA", 15, 0.0, 0.25, yaw_q(0.3)),
            ],
        }
    }

    #[test]
    fn yaw_of_unit_quaternions() {
        for theta in [0.0, 0.3, -1.2, FRAC_PI_2, 3.0, -3.0] {
            assert!(
                (quaternion_to_yaw(yaw_q(theta)) - theta).abs() < 1e-12,
                "{theta}"
            );
        }
        // (−π, π]: a half turn is reported as +π.
        assert!((quaternion_to_yaw([0.0, 0.0, 1.0, 0.0]) - PI).abs() < 1e-15);
    }

    #[test]
    fn yaw_normalises_the_quaternion() {
        // The formula is homogeneous, so normalising changes the angle only in
        // the last bits: what is pinned is the exact arithmetic (bit equality
        // with the normalised formula) and that extreme scales still work.
        let [x, y, z, w] = yaw_q(0.7);
        let scaled = [2.5 * x, 2.5 * y, 2.5 * z, 2.5 * w];
        assert!((quaternion_to_yaw(scaled) - 0.7).abs() < 1e-12);
        // Non-planar quaternion: yaw from the full formula.
        let q = [0.1, 0.2, 0.3, 0.9];
        let n = (0.01f64 + 0.04 + 0.09 + 0.81).sqrt();
        let (x, y, z, w) = (0.1 / n, 0.2 / n, 0.3 / n, 0.9 / n);
        let expected = (2.0 * (x * y + w * z)).atan2(w * w + x * x - y * y - z * z);
        assert_eq!(quaternion_to_yaw(q), expected);
        // Huge or tiny components do not overflow or underflow into a wrong yaw.
        for scale in [1e300, 1e-300] {
            let q = [0.0, 0.0, scale * (0.35f64).sin(), scale * (0.35f64).cos()];
            assert!((quaternion_to_yaw(q) - 0.7).abs() < 1e-12, "{scale}");
        }
    }

    #[test]
    fn zero_quaternion_has_yaw_zero() {
        assert_eq!(quaternion_to_yaw([0.0, 0.0, 0.0, 0.0]), 0.0);
        let s = parse_observation(&obs("blockA", 15, 0.0, 0.25, [0.0; 4])).unwrap();
        assert_eq!(s.theta, 0.0);
    }

    #[test]
    fn yaw_to_quaternion_is_planar() {
        let q = yaw_to_quaternion(FRAC_PI_2);
        assert_eq!(q[0], 0.0);
        assert_eq!(q[1], 0.0);
        assert!((q[2] - (0.5f64).sqrt()).abs() < 1e-15);
        assert!((q[3] - (0.5f64).sqrt()).abs() < 1e-15);
        assert_eq!(yaw_to_quaternion(0.0), [0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn positions_and_yaw_are_rounded() {
        let s = parse_observation(&obs("blockA", 15, 0.123_45, -0.000_5, yaw_q(0.300_49))).unwrap();
        assert_eq!(s.x, 0.123);
        assert_eq!(s.y, 0.0);
        assert!(s.y.is_sign_negative());
        assert_eq!(s.theta, 0.3);
    }

    #[test]
    fn gate_rule_forces_actuator_yaw_to_zero_interaction_rule_keeps_it() {
        let frame = one_block(0.2);
        let gate = parse_frame(&frame, ActuatorYaw::ForceZero).unwrap();
        assert_eq!(gate.actuator, ObjectState::new(0.123, -0.0, 0.0));
        let inter = parse_frame(&frame, ActuatorYaw::Keep).unwrap();
        assert_eq!(inter.actuator, ObjectState::new(0.123, -0.0, 0.2));
        // Blocks keep their yaw under both rules.
        assert_eq!(gate.blocks[&BLUE_ID].theta, 0.3);
        assert_eq!(inter.blocks[&BLUE_ID].theta, 0.3);
    }

    #[test]
    fn skip_rules() {
        assert!(is_skipped("ground_plane"));
        assert!(is_skipped("north_wall"));
        assert!(is_skipped("wall"));
        assert!(is_skipped("actuatorShadow"));
        assert!(is_skipped("blockAShadow"));
        assert!(!is_skipped("ground_plane2"));
        assert!(!is_skipped("Wall"));
        assert!(!is_skipped("shadow"));
        assert!(!is_skipped("actuator"));
        assert!(!is_skipped("blockA"));

        let mut frame = one_block(0.0);
        // Skipped models are not validated at all, not even their ids or numbers.
        frame
            .objects
            .push(obs("actuatorShadow", 8, f64::NAN, 0.0, [0.0; 4]));
        frame
            .objects
            .push(obs("blockAShadow", 15, 9.0, 9.0, yaw_q(1.0)));
        frame
            .objects
            .push(obs("wall_left", 3, 9.0, 9.0, yaw_q(1.0)));
        frame
            .objects
            .push(obs("blockB", 27, -0.6, 0.35, yaw_q(0.0)));
        let poses = parse_frame(&frame, ActuatorYaw::Keep).unwrap();
        assert_eq!(
            poses.blocks.keys().copied().collect::<Vec<_>>(),
            vec![BLUE_ID, RED_ID]
        );
        assert_eq!(poses.blocks[&BLUE_ID], ObjectState::new(0.0, 0.25, 0.3));
        assert_eq!(poses.actuator.x, 0.123);
    }

    #[test]
    fn the_actuator_is_found_by_exact_name_only() {
        let frame = Frame {
            objects: vec![
                obs("Actuator", 8, 0.0, 0.0, yaw_q(0.0)),
                obs("blockA", 15, 0.0, 0.25, yaw_q(0.0)),
            ],
        };
        // "Actuator" is not the actuator, so it is a block with the actuator's id.
        assert!(matches!(
            parse_frame(&frame, ActuatorYaw::Keep),
            Err(ParseError::UnknownBlock { id: 8, .. })
        ));
        // A name that merely contains "actuator" is not the actuator either.
        let mut frame = one_block(0.0);
        frame
            .objects
            .push(obs("actuator_old", 8, 0.0, 0.0, yaw_q(0.0)));
        assert!(matches!(
            parse_frame(&frame, ActuatorYaw::Keep),
            Err(ParseError::UnknownBlock { id: 8, .. })
        ));
        let frame = Frame {
            objects: vec![obs("blockA", 15, 0.0, 0.25, yaw_q(0.0))],
        };
        assert_eq!(
            parse_frame(&frame, ActuatorYaw::Keep),
            Err(ParseError::NoActuator)
        );
    }

    #[test]
    fn malformed_frames_are_errors() {
        let mut f = one_block(0.0);
        f.objects.push(obs("actuator", 8, 0.0, 0.0, yaw_q(0.0)));
        assert_eq!(
            parse_frame(&f, ActuatorYaw::Keep),
            Err(ParseError::DuplicateActuator)
        );

        let mut f = one_block(0.0);
        f.objects[1].id = 9;
        assert_eq!(
            parse_frame(&f, ActuatorYaw::Keep),
            Err(ParseError::ActuatorId { id: 9 })
        );

        let mut f = one_block(0.0);
        f.objects.push(obs("blockC", 42, 0.0, 0.0, yaw_q(0.0)));
        assert!(matches!(
            parse_frame(&f, ActuatorYaw::Keep),
            Err(ParseError::UnknownBlock { id: 42, .. })
        ));

        let mut f = one_block(0.0);
        f.objects.push(obs("blockA2", 15, 0.0, 0.0, yaw_q(0.0)));
        assert_eq!(
            parse_frame(&f, ActuatorYaw::Keep),
            Err(ParseError::DuplicateBlock {
                id: 15,
                first: "blockA".into(),
                second: "blockA2".into()
            })
        );
    }

    #[test]
    fn non_finite_numbers_are_errors() {
        let mut f = one_block(0.0);
        f.objects[2].position[1] = f64::INFINITY;
        assert!(matches!(
            parse_frame(&f, ActuatorYaw::Keep),
            Err(ParseError::NonFinite {
                field: "position.y",
                ..
            })
        ));
        let mut f = one_block(0.0);
        f.objects[1].orientation[3] = f64::NAN;
        assert!(matches!(
            parse_frame(&f, ActuatorYaw::ForceZero),
            Err(ParseError::NonFinite {
                field: "orientation.w",
                ..
            })
        ));
        let mut f = one_block(0.0);
        f.objects[2].position[0] = 1e306;
        assert!(matches!(
            parse_frame(&f, ActuatorYaw::Keep),
            Err(ParseError::OutOfRange {
                field: "position.x",
                ..
            })
        ));
        // z is never read.
        let mut f = one_block(0.0);
        f.objects[2].position[2] = f64::NAN;
        assert!(parse_frame(&f, ActuatorYaw::Keep).is_ok());
    }
}
