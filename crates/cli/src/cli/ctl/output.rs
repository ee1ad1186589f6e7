//! How `ctl` prints states and the Hello: an aligned table for people, JSON
//! lines (`--json`) for programs.

use std::io::{self, Write};

use pushlearn::wire::pb;
use serde_json::{json, Value};

pub struct Output {
    json: bool,
    header_printed: bool,
    /// `watch --body`: the bodies shown; empty shows all.
    only: Vec<String>,
}

/// Column widths of the state table. Every cell is exactly this wide
/// whatever its value ([`cell`], [`name_cell`]), so the columns never shift.
const COUNTER: usize = 10;
/// A u64 in full (`applied_seq` is clock-based, about 16 digits).
const SEQ: usize = 20;
/// `blockAShadowTarget` and every name of the built-in scenes fit.
const NAME: usize = 18;
const TIME: usize = 10;
const POSITION: usize = 11;
const ANGLE: usize = 9;

impl Output {
    pub fn new(json: bool) -> Self {
        Self {
            json,
            header_printed: false,
            only: Vec::new(),
        }
    }

    /// Shows only the bodies named in `bodies` from now on (all if empty).
    pub fn only(&mut self, bodies: &[String]) {
        self.only = bodies.to_vec();
    }

    /// A line saying what a command did, for people: JSON output carries
    /// states alone, so that every line parses as one.
    pub fn note(&mut self, line: &str) -> io::Result<()> {
        if self.json {
            return Ok(());
        }
        writeln!(io::stdout().lock(), "{line}")
    }

    fn shown<'a>(&'a self, state: &'a pb::WorldState) -> impl Iterator<Item = &'a pb::ModelState> {
        state
            .models()
            .iter()
            .filter(|m| self.only.is_empty() || self.only.contains(&m.name))
    }

    /// One JSON line per state, or one table row per body.
    pub fn state(&mut self, state: &pb::WorldState) -> io::Result<()> {
        let mut out = io::stdout().lock();
        if self.json {
            let bodies: Vec<Value> = self.shown(state).map(model_json).collect();
            return writeln!(out, "{}", state_json_with(state, bodies));
        }
        if !self.header_printed {
            writeln!(out, "{}", header())?;
            self.header_printed = true;
        }
        for model in self.shown(state) {
            writeln!(out, "{}", row(state, model))?;
        }
        Ok(())
    }

    pub fn hello(&mut self, hello: &pb::Hello) -> io::Result<()> {
        let mut out = io::stdout().lock();
        if self.json {
            let value = json!({
                "scene": hello.scene,
                "step_size": hello.step_size,
                "publish_rate": hello.publish_rate,
                "timing_mode": hello.timing_mode,
                "max_speed": hello.max_speed,
                "bodies": hello.bodies.iter().map(model_json).collect::<Vec<_>>(),
            });
            return writeln!(out, "{value}");
        }
        writeln!(out, "scene:        {}", hello.scene)?;
        writeln!(out, "timing mode:  {}", hello.timing_mode)?;
        writeln!(out, "step size:    {} s", hello.step_size)?;
        writeln!(out, "publish rate: {} Hz", hello.publish_rate)?;
        match hello.max_speed {
            Some(limit) => writeln!(out, "speed limit:  {} m/s (Move)", number(limit))?,
            None => writeln!(out, "speed limit:  not announced by this world")?,
        }
        writeln!(out, "bodies (start poses):")?;
        for body in &hello.bodies {
            let [x, y, z] = position(body);
            writeln!(
                out,
                "  {:<14} id {:>3}{}  x {:.4}  y {:.4}  z {:.4}  yaw {:.4}",
                body.name,
                body.id,
                if body.is_static { " static" } else { "" },
                x,
                y,
                z,
                yaw(body)
            )?;
        }
        Ok(())
    }
}

fn vector(v: Option<&pb::Vector3d>) -> [f64; 3] {
    v.map_or([0.0; 3], |v| [v.x, v.y, v.z])
}

fn position(model: &pb::ModelState) -> [f64; 3] {
    vector(model.pose.as_ref().and_then(|p| p.position.as_ref()))
}

fn orientation(model: &pb::ModelState) -> pb::Quaternion {
    model
        .pose
        .and_then(|p| p.orientation)
        .unwrap_or(pb::Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        })
}

fn yaw(model: &pb::ModelState) -> f64 {
    orientation(model).yaw()
}

fn model_json(model: &pb::ModelState) -> Value {
    let q = orientation(model);
    json!({
        "name": model.name,
        "id": model.id,
        "position": position(model),
        "orientation": [q.x, q.y, q.z, q.w],
        "yaw": q.yaw(),
        "lin_vel": vector(model.lin_vel.as_ref()),
        "ang_vel": vector(model.ang_vel.as_ref()),
    })
}

fn state_json_with(state: &pb::WorldState, bodies: Vec<Value>) -> Value {
    json!({
        "publish_seq": state.publish_seq,
        "step": state.step,
        "sim_time": state.sim_time,
        "applied_seq": state.applied_seq,
        "bodies": bodies,
    })
}

fn header() -> String {
    format!(
        "{:>COUNTER$} {:>COUNTER$} {:>TIME$} {:>SEQ$}  {:<NAME$} {:>POSITION$} {:>POSITION$} {:>POSITION$} {:>ANGLE$} {:>ANGLE$} {:>ANGLE$}",
        "publish", "step", "sim_time", "applied_seq", "body", "x", "y", "z", "yaw", "vx", "vy"
    )
}

fn row(state: &pb::WorldState, model: &pb::ModelState) -> String {
    let [x, y, z] = position(model);
    let [vx, vy, _] = vector(model.lin_vel.as_ref());
    format!(
        "{:>COUNTER$} {:>COUNTER$} {} {:>SEQ$}  {} {} {} {} {} {} {}",
        state.publish_seq,
        state.step,
        cell(state.sim_time, TIME, 3),
        state.applied_seq,
        name_cell(&model.name),
        cell(x, POSITION, 5),
        cell(y, POSITION, 5),
        cell(z, POSITION, 5),
        cell(yaw(model), ANGLE, 4),
        cell(vx, ANGLE, 4),
        cell(vy, ANGLE, 4),
    )
}

/// `value` right-aligned in exactly `width` characters: with `decimals`
/// decimals if that fits, else in scientific notation with as many digits
/// as fit (a far-away or fast body must not push the columns apart).
fn cell(value: f64, width: usize, decimals: usize) -> String {
    let fixed = format!("{value:>width$.decimals$}");
    if fixed.chars().count() <= width {
        // -1e-12 rounds to "-0.00000": the sign is noise, not information.
        if fixed.trim_start().starts_with('-')
            && fixed.chars().all(|c| !c.is_ascii_digit() || c == '0')
        {
            return fixed.replacen('-', " ", 1);
        }
        return fixed;
    }
    for digits in (0..decimals).rev() {
        let scientific = format!("{value:>width$.digits$e}");
        if scientific.chars().count() <= width {
            return scientific;
        }
    }
    // Only reached for widths too small for any number: mark the overflow.
    format!("{:>width$}", "#".repeat(width))
}

/// A body name left-aligned in exactly [`NAME`] characters, cut with `…`
/// if longer.
fn name_cell(name: &str) -> String {
    if name.chars().count() <= NAME {
        return format!("{name:<NAME$}");
    }
    let cut: String = name.chars().take(NAME - 1).collect();
    format!("{cut}…")
}

/// A number for a sentence: at most 6 decimals, trailing zeros dropped
/// (0.30000000000000004 → 0.3), scientific notation when huge or tiny
/// (1e300 rather than 301 digits).
pub fn number(value: f64) -> String {
    let magnitude = value.abs();
    if magnitude != 0.0 && !(1e-4..1e9).contains(&magnitude) {
        return format!("{value:e}");
    }
    let fixed = format!("{value:.6}");
    let trimmed = fixed.trim_end_matches('0').trim_end_matches('.');
    match trimmed {
        "-0" => "0".to_owned(),
        other => other.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_keep_their_width_whatever_the_value() {
        for value in [
            0.0,
            -0.1,
            0.30000000000000004,
            -999.123456,
            1e300,
            -1e-300,
            f64::MAX,
        ] {
            assert_eq!(
                cell(value, POSITION, 5).chars().count(),
                POSITION,
                "{value}"
            );
            assert_eq!(cell(value, ANGLE, 4).chars().count(), ANGLE, "{value}");
        }
        assert_eq!(cell(0.30000000000000004, 9, 4), "   0.3000");
        assert_eq!(cell(-1e300, 9, 4), "-1.00e300");
        assert_eq!(cell(-1e-12, 9, 4), "   0.0000");
        assert_eq!(cell(-0.00004, 9, 4), "   0.0000");
        assert_eq!(cell(-0.00006, 9, 4), "  -0.0001");
        assert_eq!(name_cell("blockAShadowTarget").chars().count(), NAME);
        assert_eq!(name_cell("aVeryLongBodyNameIndeed"), "aVeryLongBodyName…");
    }

    #[test]
    fn numbers_in_sentences_have_no_noise() {
        assert_eq!(number(0.30000000000000004), "0.3");
        assert_eq!(number(0.5), "0.5");
        assert_eq!(number(-0.0), "0");
        assert_eq!(number(1e300), "1e300");
        assert_eq!(number(100.0), "100");
        assert_eq!(number(0.5 / 2f64.sqrt()), "0.353553");
    }

    #[test]
    fn state_json_carries_counters_and_poses() {
        let state = pb::WorldState {
            model_v: Some(pb::ModelStateV {
                models: vec![pb::ModelState {
                    name: "blockA".into(),
                    id: 15,
                    pose: Some(pb::Pose::from_position_yaw([0.0, 0.25, 0.05], 0.5)),
                    ..Default::default()
                }],
            }),
            step: 10,
            sim_time: 0.01,
            publish_seq: 3,
            applied_seq: 7,
        };
        let value = state_json_with(&state, state.models().iter().map(model_json).collect());
        assert_eq!(value["step"], 10);
        assert_eq!(value["applied_seq"], 7);
        assert_eq!(value["bodies"][0]["name"], "blockA");
        assert_eq!(value["bodies"][0]["id"], 15);
        assert_eq!(value["bodies"][0]["position"][1], 0.25);
        let yaw = value["bodies"][0]["yaw"].as_f64().unwrap_or(f64::NAN);
        assert!((yaw - 0.5).abs() < 1e-12, "{yaw}");
    }
}
