//! Argument values that several commands take, parsed one way: a pose
//! (`--target` of `pushlearn experiment move-to-target` and `pushlearn
//! learn`) and an action.

use learner::{Action, ObjectState};

/// `X,Y,ORI` as three finite numbers.
pub fn parse_pose(text: &str) -> Result<ObjectState, String> {
    let v = parse_numbers(text, 3)?;
    Ok(ObjectState::new(v[0], v[1], v[2]))
}

/// `n` comma-separated finite numbers.
fn parse_numbers(text: &str, n: usize) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = text
        .split(',')
        .map(|s| {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("'{s}' is not a finite number"))
        })
        .collect::<Result<_, _>>()?;
    if v.len() == n {
        Ok(v)
    } else {
        Err(format!(
            "expected {n} comma-separated numbers, got {}",
            v.len()
        ))
    }
}

/// `VX,VY` as two finite numbers.
pub fn parse_action(text: &str) -> Result<Action, String> {
    let v = parse_numbers(text, 2)?;
    Ok(Action::new(v[0], v[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poses_and_actions_parse_strictly() {
        assert_eq!(parse_action("0,-0.5"), Ok(Action::new(0.0, -0.5)));
        assert!(parse_action("0,0,0").is_err());
        assert_eq!(
            parse_pose("-0.6, 0.7,0.75"),
            Ok(ObjectState::new(-0.6, 0.7, 0.75))
        );
        assert!(parse_pose("1,2").unwrap_err().contains("expected 3"));
        assert!(parse_pose("1,nan,2").unwrap_err().contains("finite"));
        assert!(parse_pose("1,x,2").is_err());
        assert_eq!(parse_numbers("0,0.5", 2), Ok(vec![0.0, 0.5]));
    }
}
