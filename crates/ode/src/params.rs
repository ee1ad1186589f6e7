//! The explicit, validated set of world-level solver settings.

use crate::check::{check_finite3, check_positive, check_range};
use crate::OdeError;

/// Largest number of contact points asked from `dCollide` per geom pair
/// (ODE keeps the count in the low 16 bits of its flags; more than this is
/// never useful for boxes and spheres).
pub const MAX_CONTACTS_LIMIT: usize = 256;

/// ODE's automatic disabling of resting bodies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AutoDisable {
    pub enabled: bool,
    /// Average linear speed below which a body counts as idle, m/s.
    pub linear_threshold: f64,
    /// Average angular speed below which a body counts as idle, rad/s.
    pub angular_threshold: f64,
    /// Idle time before disabling, s.
    pub idle_time: f64,
    /// Idle steps before disabling (both this and `idle_time` must elapse).
    pub idle_steps: u32,
    /// Number of velocity samples averaged for the idle test.
    pub average_samples: u32,
}

/// Everything that configures one world step. Gazebo 2.x's defaults (the
/// values the thesis world ran with) are [`StepParams::gazebo`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepParams {
    /// Integration step, s.
    pub step_size: f64,
    /// m/s².
    pub gravity: [f64; 3],
    /// Gauss–Seidel sweeps of `dWorldQuickStep`.
    pub quickstep_iterations: u32,
    /// Successive over-relaxation factor of QuickStep.
    pub sor_w: f64,
    /// Global error-reduction parameter, 0..=1.
    pub erp: f64,
    /// Global constraint-force mixing, ≥ 0.
    pub cfm: f64,
    /// Maximum velocity contacts may use to correct penetration, m/s
    /// (`f64::INFINITY` means unlimited, ODE's own default).
    pub contact_max_correcting_vel: f64,
    /// Penetration allowed before contacts push back, m.
    pub contact_surface_layer: f64,
    /// Fraction of linear velocity removed per step, 0..=1.
    pub linear_damping: f64,
    /// Fraction of angular velocity removed per step, 0..=1.
    pub angular_damping: f64,
    /// Contact points asked from `dCollide` per colliding geom pair.
    pub max_contacts_per_pair: usize,
    /// Applied to bodies created after the world (ODE copies it into each
    /// body at creation).
    pub auto_disable: AutoDisable,
}

impl StepParams {
    /// Gazebo 2.x's SDF defaults for the ODE engine.
    pub fn gazebo() -> Self {
        StepParams {
            step_size: 0.001,
            gravity: [0.0, 0.0, -9.81],
            quickstep_iterations: 50,
            sor_w: 1.3,
            erp: 0.2,
            cfm: 0.0,
            contact_max_correcting_vel: 100.0,
            contact_surface_layer: 0.001,
            linear_damping: 1e-4,
            angular_damping: 1e-4,
            max_contacts_per_pair: 10,
            auto_disable: AutoDisable {
                enabled: true,
                linear_threshold: 0.1,
                angular_threshold: 0.1,
                idle_time: 1.0,
                idle_steps: 5,
                average_samples: 1,
            },
        }
    }

    /// Checks every value that ODE would abort on or silently misuse.
    pub fn validate(&self) -> Result<(), OdeError> {
        check_positive("step_size", self.step_size)?;
        check_finite3("gravity", self.gravity)?;
        if self.quickstep_iterations == 0 || self.quickstep_iterations > i32::MAX as u32 {
            return Err(OdeError::OutOfRange {
                what: "quickstep_iterations",
                range: "1..=2^31-1",
                value: f64::from(self.quickstep_iterations),
            });
        }
        check_range("sor_w", self.sor_w, 0.0, 2.0, "(0, 2]")?;
        if self.sor_w <= 0.0 {
            return Err(OdeError::NotPositive {
                what: "sor_w",
                value: self.sor_w,
            });
        }
        check_range("erp", self.erp, 0.0, 1.0, "[0, 1]")?;
        check_range("cfm", self.cfm, 0.0, f64::MAX, "[0, ∞)")?;
        if self.contact_max_correcting_vel.is_nan() || self.contact_max_correcting_vel < 0.0 {
            return Err(OdeError::OutOfRange {
                what: "contact_max_correcting_vel",
                range: "[0, ∞]",
                value: self.contact_max_correcting_vel,
            });
        }
        check_range(
            "contact_surface_layer",
            self.contact_surface_layer,
            0.0,
            f64::MAX,
            "[0, ∞)",
        )?;
        check_range("linear_damping", self.linear_damping, 0.0, 1.0, "[0, 1]")?;
        check_range("angular_damping", self.angular_damping, 0.0, 1.0, "[0, 1]")?;
        if self.max_contacts_per_pair == 0 || self.max_contacts_per_pair > MAX_CONTACTS_LIMIT {
            return Err(OdeError::OutOfRange {
                what: "max_contacts_per_pair",
                range: "1..=256",
                value: self.max_contacts_per_pair as f64,
            });
        }
        let ad = &self.auto_disable;
        check_range(
            "auto_disable.linear_threshold",
            ad.linear_threshold,
            0.0,
            f64::MAX,
            "[0, ∞)",
        )?;
        check_range(
            "auto_disable.angular_threshold",
            ad.angular_threshold,
            0.0,
            f64::MAX,
            "[0, ∞)",
        )?;
        check_range(
            "auto_disable.idle_time",
            ad.idle_time,
            0.0,
            f64::MAX,
            "[0, ∞)",
        )?;
        if ad.idle_steps > i32::MAX as u32 {
            return Err(OdeError::OutOfRange {
                what: "auto_disable.idle_steps",
                range: "0..=2^31-1",
                value: f64::from(ad.idle_steps),
            });
        }
        if ad.average_samples == 0 {
            return Err(OdeError::NotPositive {
                what: "auto_disable.average_samples",
                value: 0.0,
            });
        }
        Ok(())
    }
}

impl Default for StepParams {
    fn default() -> Self {
        StepParams::gazebo()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gazebo_defaults_are_valid() {
        StepParams::gazebo().validate().unwrap();
    }

    #[test]
    fn bad_values_are_named() {
        let mut p = StepParams::gazebo();
        p.step_size = 0.0;
        assert!(matches!(
            p.validate(),
            Err(OdeError::NotPositive {
                what: "step_size",
                ..
            })
        ));
        let mut p = StepParams::gazebo();
        p.gravity[2] = f64::NAN;
        assert!(matches!(
            p.validate(),
            Err(OdeError::NotFinite {
                what: "gravity",
                ..
            })
        ));
        let mut p = StepParams::gazebo();
        p.erp = 1.5;
        assert!(matches!(
            p.validate(),
            Err(OdeError::OutOfRange { what: "erp", .. })
        ));
        let mut p = StepParams::gazebo();
        p.max_contacts_per_pair = 0;
        assert!(p.validate().is_err());
        let mut p = StepParams::gazebo();
        p.quickstep_iterations = 0;
        assert!(p.validate().is_err());
    }

    #[test]
    fn unlimited_correcting_velocity_is_allowed_but_nan_is_not() {
        let mut p = StepParams::gazebo();
        p.contact_max_correcting_vel = f64::INFINITY;
        p.validate().unwrap();
        p.contact_max_correcting_vel = f64::NAN;
        assert!(p.validate().is_err());
    }
}
