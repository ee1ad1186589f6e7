//! The actuator's speed limit, shared by the world that applies it and the
//! clients that report it (`pushlearn ctl move`), so both compute the same
//! velocity from the same request.

/// `v` scaled down to length `max` if it is longer, its direction kept; `v`
/// itself otherwise. Huge components do not overflow (the length is taken
/// of `v` divided by its largest component).
#[must_use]
pub fn clamp_speed(v: [f64; 3], max: f64) -> [f64; 3] {
    let largest = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if largest == 0.0 {
        return v;
    }
    let norm = largest * v.iter().map(|x| (x / largest).powi(2)).sum::<f64>().sqrt();
    if norm > max {
        v.map(|x| x / norm * max)
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_clamp_keeps_direction() {
        assert_eq!(clamp_speed([0.0, 0.5, 0.0], 0.5), [0.0, 0.5, 0.0]);
        assert_eq!(clamp_speed([0.0, 0.0, 0.0], 0.5), [0.0; 3]);
        let v = clamp_speed([3.0, 4.0, 0.0], 0.5);
        assert!((v[0] - 0.3).abs() < 1e-15 && (v[1] - 0.4).abs() < 1e-15);
        let huge = clamp_speed([1e300, 1e300, 0.0], 0.5);
        assert!((huge[0] - 0.5 / 2f64.sqrt()).abs() < 1e-15);
        assert_eq!(clamp_speed([-1e300, 0.0, 0.0], 0.5), [-0.5, 0.0, 0.0]);
    }
}
