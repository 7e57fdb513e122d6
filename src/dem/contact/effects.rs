//! The interfaces of the contact law's effects, one trait per slot; their implementations are
//! in one file per effect (`hertz`, `power_damped`, `mindlin`, `epsd2`, `cdt`, `sjkr`, `none`).

use super::kinematics::Contact;
use crate::dem::material::PairConstants;
use crate::dem::vec3::V3;

pub trait NormalForce: Copy + Default + Send + Sync {
    /// Normal force along n (positive pushes the bodies apart).
    fn normal(&self, c: &Contact, p: &PairConstants) -> f64;
}

pub trait Tangential: Copy + Default + Send + Sync {
    /// Advances the history spring `xi` and returns the tangential force on i.
    fn force(&self, c: &Contact, p: &PairConstants, f_n: f64, xi: &mut V3, dt: f64) -> V3;
}

pub trait Rolling: Copy + Default + Send + Sync {
    /// Rolling resistance torque on i (j gets the opposite); updates the history.
    fn torque(&self, c: &Contact, p: &PairConstants, f_n: f64, m: &mut V3, dt: f64) -> V3;
}

pub trait Cohesion: Copy + Default + Send + Sync {
    /// Whether the effect needs the contact area (skipped at compile time when not).
    const ACTIVE: bool = true;
    /// Attractive force magnitude (subtracted from the normal force).
    fn cohesion(&self, c: &Contact, p: &PairConstants) -> f64;
}
