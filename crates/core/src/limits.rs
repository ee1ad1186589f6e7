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

/// No body name is longer than this, in bytes: a world refuses a SetPose
/// naming a longer one, a scene file declaring one, and a learner daemon a
/// state carrying one. The built-in names are under 30 bytes; without a cap a
/// 100 KB name was echoed whole into every refusal and log line.
pub const MAX_NAME_BYTES: usize = 256;

/// `name` as refusals and logs show it: quoted, with control characters,
/// quotes and backslashes escaped (a name holding a newline cannot forge a
/// log line), and cut after [`MAX_NAME_BYTES`] bytes with its length said.
pub fn quoted(name: &str) -> String {
    let mut end = name.len().min(MAX_NAME_BYTES);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    let escaped: String = name[..end].chars().flat_map(char::escape_debug).collect();
    if end < name.len() {
        format!("'{escaped}…' ({} bytes)", name.len())
    } else {
        format!("'{escaped}'")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoted_names_cannot_break_a_line_or_run_long() {
        assert_eq!(quoted("blockA"), "'blockA'");
        assert_eq!(
            quoted("a\nINFO forged"),
            "'a\\nINFO forged'",
            "a newline is shown, never written"
        );
        let long = "x".repeat(100_000);
        let shown = quoted(&long);
        assert!(shown.len() < MAX_NAME_BYTES + 40, "{}", shown.len());
        assert!(shown.ends_with("(100000 bytes)"), "{shown}");
        // A cut inside a multi-byte character stays valid text.
        assert!(quoted(&"é".repeat(200)).contains("(400 bytes)"));
    }
}
