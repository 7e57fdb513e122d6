//! The interfaces of the contact law's effects; their implementations are in `normal`,
//! `cohesion` and `rolling`.

use super::kinematics::Contact;
use crate::dem::material::PairConstants;
use crate::dem::vec3::V3;

pub trait NormalForce: Copy + Send + Sync {
    /// Normal force along n (positive pushes the bodies apart).
    fn normal(&self, c: &Contact, p: &PairConstants) -> f64;
}

pub trait Cohesion: Copy + Send + Sync {
    /// Whether the effect needs the contact area (skipped at compile time when not).
    const ACTIVE: bool = true;
    /// Attractive force magnitude (subtracted from the normal force).
    fn cohesion(&self, c: &Contact, p: &PairConstants) -> f64;
}

pub trait Rolling: Copy + Send + Sync {
    /// Rolling resistance torque on i (j gets the opposite); updates the history.
    fn torque(&self, c: &Contact, p: &PairConstants, f_n: f64, m: &mut V3, dt: f64) -> V3;
}
