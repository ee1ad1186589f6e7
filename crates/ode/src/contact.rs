//! Contact surfaces and what the near-callback sees of a colliding pair.

use std::ops::BitOr;

use ode_sys::{dContactGeom, dSurfaceParameters};

use crate::check::check_range;
use crate::{BodyHandle, GeomHandle, OdeError};

/// ODE's `dContact*` mode flags.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ContactMode(u32);

impl ContactMode {
    pub const NONE: ContactMode = ContactMode(0);
    pub const MU2: ContactMode = ContactMode(ode_sys::dContactMu2);
    pub const BOUNCE: ContactMode = ContactMode(ode_sys::dContactBounce);
    pub const SOFT_ERP: ContactMode = ContactMode(ode_sys::dContactSoftERP);
    pub const SOFT_CFM: ContactMode = ContactMode(ode_sys::dContactSoftCFM);
    pub const SLIP1: ContactMode = ContactMode(ode_sys::dContactSlip1);
    pub const SLIP2: ContactMode = ContactMode(ode_sys::dContactSlip2);
    /// Friction pyramid approximation in both friction directions.
    pub const APPROX1: ContactMode = ContactMode(ode_sys::dContactApprox1);

    pub fn contains(self, other: ContactMode) -> bool {
        self.0 & other.0 == other.0
    }

    pub fn bits(self) -> u32 {
        self.0
    }
}

impl BitOr for ContactMode {
    type Output = ContactMode;
    fn bitor(self, rhs: ContactMode) -> ContactMode {
        ContactMode(self.0 | rhs.0)
    }
}

/// Contact surface settings as plain data; [`SurfaceParams::check`] turns
/// them into a [`Surface`] that can be handed to ODE.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceParams {
    pub mode: ContactMode,
    /// Coulomb friction (first direction); `f64::INFINITY` means no slip.
    pub mu: f64,
    /// Second-direction friction (used with [`ContactMode::MU2`]).
    pub mu2: f64,
    /// Restitution, 0..=1.
    pub bounce: f64,
    /// Minimum incoming speed for bouncing, m/s.
    pub bounce_vel: f64,
    pub soft_erp: f64,
    pub soft_cfm: f64,
    pub slip1: f64,
    pub slip2: f64,
}

impl Default for SurfaceParams {
    fn default() -> Self {
        SurfaceParams {
            mode: ContactMode::NONE,
            mu: 0.0,
            mu2: 0.0,
            bounce: 0.0,
            bounce_vel: 0.0,
            soft_erp: 0.0,
            soft_cfm: 0.0,
            slip1: 0.0,
            slip2: 0.0,
        }
    }
}

fn non_negative(what: &'static str, v: f64) -> Result<(), OdeError> {
    check_range(what, v, 0.0, f64::MAX, "[0, ∞)")
}

fn friction(what: &'static str, v: f64) -> Result<(), OdeError> {
    if v == f64::INFINITY {
        return Ok(());
    }
    check_range(what, v, 0.0, f64::MAX, "[0, ∞]")
}

impl SurfaceParams {
    pub fn check(self) -> Result<Surface, OdeError> {
        friction("mu", self.mu)?;
        friction("mu2", self.mu2)?;
        check_range("bounce", self.bounce, 0.0, 1.0, "[0, 1]")?;
        non_negative("bounce_vel", self.bounce_vel)?;
        check_range("soft_erp", self.soft_erp, 0.0, 1.0, "[0, 1]")?;
        non_negative("soft_cfm", self.soft_cfm)?;
        non_negative("slip1", self.slip1)?;
        non_negative("slip2", self.slip2)?;
        Ok(Surface(self))
    }
}

/// Validated contact surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface(SurfaceParams);

impl Surface {
    pub fn params(&self) -> &SurfaceParams {
        &self.0
    }

    pub(crate) fn to_raw(self) -> dSurfaceParameters {
        let p = self.0;
        dSurfaceParameters {
            mode: p.mode.0 as i32,
            mu: p.mu,
            mu2: p.mu2,
            bounce: p.bounce,
            bounce_vel: p.bounce_vel,
            soft_erp: p.soft_erp,
            soft_cfm: p.soft_cfm,
            slip1: p.slip1,
            slip2: p.slip2,
            ..dSurfaceParameters::default()
        }
    }
}

/// One geom of a colliding pair, as the near-callback sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GeomInfo {
    pub geom: GeomHandle,
    /// `None` for static geoms.
    pub body: Option<BodyHandle>,
    /// The tag given in [`GeomBuilder::tag`](crate::GeomBuilder::tag).
    pub tag: u32,
}

/// One contact point reported by ODE's collider.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPoint {
    pub position: [f64; 3],
    /// Points into the first geom of the pair.
    pub normal: [f64; 3],
    /// Penetration depth, m.
    pub depth: f64,
}

/// A pair of geoms that touch in this step, with their contact points.
pub struct ContactPair<'a> {
    pub first: GeomInfo,
    pub second: GeomInfo,
    pub(crate) raw: &'a [dContactGeom],
}

impl ContactPair<'_> {
    pub fn len(&self) -> usize {
        self.raw.len()
    }

    pub fn is_empty(&self) -> bool {
        self.raw.is_empty()
    }

    pub fn points(&self) -> impl Iterator<Item = ContactPoint> + '_ {
        self.raw.iter().map(|c| ContactPoint {
            position: [c.pos[0], c.pos[1], c.pos[2]],
            normal: [c.normal[0], c.normal[1], c.normal[2]],
            depth: c.depth,
        })
    }

    /// Whether the pair consists of geoms tagged `a` and `b`, in either order.
    pub fn is_between_tags(&self, a: u32, b: u32) -> bool {
        (self.first.tag == a && self.second.tag == b)
            || (self.first.tag == b && self.second.tag == a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surface_checks_ranges() {
        let ok = SurfaceParams {
            mode: ContactMode::MU2 | ContactMode::SOFT_CFM,
            mu: f64::INFINITY,
            ..SurfaceParams::default()
        };
        assert!(ok.check().is_ok());
        for bad in [
            SurfaceParams { mu: -1.0, ..ok },
            SurfaceParams {
                mu2: f64::NAN,
                ..ok
            },
            SurfaceParams {
                soft_erp: 2.0,
                ..ok
            },
            SurfaceParams {
                soft_cfm: f64::INFINITY,
                ..ok
            },
        ] {
            assert!(bad.check().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn mode_flags_combine() {
        let m = ContactMode::APPROX1 | ContactMode::MU2;
        assert!(m.contains(ContactMode::MU2));
        assert!(!m.contains(ContactMode::BOUNCE));
        assert_eq!(m.bits(), 0x7001);
    }
}
