//! Value checks shared by every entry point, and the one place where the
//! public `[x, y, z, w]` quaternion order meets ODE's `[w, x, y, z]`
//! (`quat_to_ode` / `quat_from_ode`).

use ode_sys::dReal;

use crate::OdeError;

pub(crate) fn check_finite(what: &'static str, value: f64) -> Result<(), OdeError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(OdeError::NotFinite { what, value })
    }
}

pub(crate) fn check_positive(what: &'static str, value: f64) -> Result<(), OdeError> {
    check_finite(what, value)?;
    if value > 0.0 {
        Ok(())
    } else {
        Err(OdeError::NotPositive { what, value })
    }
}

pub(crate) fn check_finite3(what: &'static str, v: [f64; 3]) -> Result<(), OdeError> {
    v.iter().try_for_each(|&x| check_finite(what, x))
}

pub(crate) fn check_range(
    what: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    range: &'static str,
) -> Result<(), OdeError> {
    check_finite(what, value)?;
    if (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(OdeError::OutOfRange { what, range, value })
    }
}

/// A unit vector for a direction that ODE would otherwise normalise itself
/// (plane normals), refusing zero and non-finite input.
pub(crate) fn unit_direction(what: &'static str, v: [f64; 3]) -> Result<[f64; 3], OdeError> {
    check_finite3(what, v)?;
    let largest = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if largest == 0.0 {
        return Err(OdeError::ZeroLength { what });
    }
    let scaled = v.map(|x| x / largest);
    let norm = scaled.iter().map(|x| x * x).sum::<f64>().sqrt();
    Ok(scaled.map(|c| c / norm))
}

/// Public `[x, y, z, w]` → ODE `[w, x, y, z]`, normalised. Only an exactly
/// zero (or non-finite) quaternion is refused: scaling by the largest
/// component first keeps tiny and huge inputs from under- or overflowing,
/// which is where ODE's own normalisation would abort.
pub(crate) fn quat_to_ode(q: [f64; 4]) -> Result<[dReal; 4], OdeError> {
    q.iter().try_for_each(|&x| check_finite("quaternion", x))?;
    let largest = q.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if largest == 0.0 {
        return Err(OdeError::ZeroLength { what: "quaternion" });
    }
    let scaled = q.map(|x| x / largest);
    let norm = scaled.iter().map(|x| x * x).sum::<f64>().sqrt();
    let [x, y, z, w] = scaled.map(|c| c / norm);
    Ok([w, x, y, z])
}

/// ODE `[w, x, y, z]` → public `[x, y, z, w]`.
pub(crate) fn quat_from_ode(q: [dReal; 4]) -> [f64; 4] {
    let [w, x, y, z] = q;
    [x, y, z, w]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_round_trips() {
        assert_eq!(
            quat_to_ode([0.0, 0.0, 0.0, 2.0]).unwrap(),
            [1.0, 0.0, 0.0, 0.0]
        );
        assert_eq!(
            quat_to_ode([0.0, 3.0, 0.0, 0.0]).unwrap(),
            [0.0, 0.0, 1.0, 0.0]
        );
        assert_eq!(quat_from_ode([0.1, 0.2, 0.3, 0.4]), [0.2, 0.3, 0.4, 0.1]);
        let q = [0.5, -0.5, 0.5, 0.5];
        assert_eq!(quat_from_ode(quat_to_ode(q).unwrap()), q);
    }

    #[test]
    fn zero_and_non_finite_quaternions_are_refused() {
        assert_eq!(
            quat_to_ode([0.0; 4]),
            Err(OdeError::ZeroLength { what: "quaternion" })
        );
        assert!(quat_to_ode([f64::NAN, 0.0, 0.0, 1.0]).is_err());
        assert!(quat_to_ode([0.0, f64::INFINITY, 0.0, 1.0]).is_err());
    }

    #[test]
    fn extreme_magnitudes_are_normalised() {
        let big = quat_to_ode([1e300, 1e300, 0.0, 0.0]).unwrap();
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((big[1] - h).abs() < 1e-15 && (big[2] - h).abs() < 1e-15);
        assert_eq!(
            quat_to_ode([0.0, 0.0, 0.0, 1e-300]).unwrap(),
            [1.0, 0.0, 0.0, 0.0]
        );
    }
}
