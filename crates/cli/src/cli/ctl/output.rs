//! How `ctl` prints states and the Hello: an aligned table for people, JSON
//! lines (`--json`) for programs.

use std::io::{self, Write};

use pushlearn::wire::pb;
use serde_json::{json, Value};

pub struct Output {
    json: bool,
    header_printed: bool,
}

impl Output {
    pub fn new(json: bool) -> Self {
        Self {
            json,
            header_printed: false,
        }
    }

    /// One JSON line per state, or one table row per body.
    pub fn state(&mut self, state: &pb::WorldState) -> io::Result<()> {
        let mut out = io::stdout().lock();
        if self.json {
            return writeln!(out, "{}", state_json(state));
        }
        if !self.header_printed {
            writeln!(
                out,
                "{:>8} {:>8} {:>9} {:>16}  {:<14} {:>9} {:>9} {:>9} {:>8} {:>8} {:>8}",
                "publish",
                "step",
                "sim_time",
                "applied_seq",
                "body",
                "x",
                "y",
                "z",
                "yaw",
                "vx",
                "vy"
            )?;
            self.header_printed = true;
        }
        for model in state.models() {
            let [x, y, z] = position(model);
            let [vx, vy, _] = vector(model.lin_vel.as_ref());
            writeln!(
                out,
                "{:>8} {:>8} {:>9.3} {:>16}  {:<14} {:>9.5} {:>9.5} {:>9.5} {:>8.4} {:>8.4} {:>8.4}",
                state.publish_seq,
                state.step,
                state.sim_time,
                state.applied_seq,
                model.name,
                x,
                y,
                z,
                yaw(model),
                vx,
                vy
            )?;
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
                "bodies": hello.bodies.iter().map(model_json).collect::<Vec<_>>(),
            });
            return writeln!(out, "{value}");
        }
        writeln!(out, "scene:        {}", hello.scene)?;
        writeln!(out, "timing mode:  {}", hello.timing_mode)?;
        writeln!(out, "step size:    {} s", hello.step_size)?;
        writeln!(out, "publish rate: {} Hz", hello.publish_rate)?;
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

pub fn state_json(state: &pb::WorldState) -> Value {
    json!({
        "publish_seq": state.publish_seq,
        "step": state.step,
        "sim_time": state.sim_time,
        "applied_seq": state.applied_seq,
        "bodies": state.models().iter().map(model_json).collect::<Vec<_>>(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let value = state_json(&state);
        assert_eq!(value["step"], 10);
        assert_eq!(value["applied_seq"], 7);
        assert_eq!(value["bodies"][0]["name"], "blockA");
        assert_eq!(value["bodies"][0]["id"], 15);
        assert_eq!(value["bodies"][0]["position"][1], 0.25);
        let yaw = value["bodies"][0]["yaw"].as_f64().unwrap_or(f64::NAN);
        assert!((yaw - 0.5).abs() < 1e-12, "{yaw}");
    }
}
