//! How far from the origin and how fast anything in a world can be: the
//! world refuses commands beyond these, and a learner daemon refuses states
//! and actions beyond them, so both sides read the same numbers.

/// No body of a world is farther than this from the origin, in metres, on
/// any axis: the world refuses a SetPose beyond it (nothing in a table-top
/// world lives there, and ODE's collision arithmetic is not meant for such
/// magnitudes), and a learner daemon refuses a state beyond it (a model
/// trained on a jump to 1e296 m predicts NaN).
pub const MAX_POSITION: f64 = 1000.0;

/// No action a learner is asked about is faster than this, in m/s, in
/// either component: a world drives its actuator at its scene's top speed
/// (0.5 m/s in the thesis's world) whatever a Move asks, and a learner
/// daemon refuses an action beyond this (gate+ trained on −7.4e283 m/s
/// predicts NaN).
pub const MAX_ACTION_SPEED: f64 = 1000.0;
