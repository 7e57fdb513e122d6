//! Empty slots: no rolling resistance, no cohesion.

use super::effects::{Cohesion, Rolling};
use super::kinematics::Contact;
use super::spec::{none, EffectSpec, Slot};
use crate::material::PairConstants;
use crate::vec3::V3;

/// The `no-rolling` spec: the rolling slot left empty.
pub const NO_ROLLING: EffectSpec = none(Slot::Rolling, "no-rolling");
/// The `no-cohesion` spec: the cohesion slot left empty.
pub const NO_COHESION: EffectSpec = none(Slot::Cohesion, "no-cohesion");

/// No rolling resistance: zero torque, the history untouched.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoRolling;

impl Rolling for NoRolling {
    #[inline(always)]
    fn torque(&self, _: &Contact, _: &PairConstants, _: f64, _: &mut V3, _: f64) -> V3 {
        [0.0; 3]
    }
}

/// No cohesion: zero attraction, and the contact area is not computed.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoCohesion;

impl Cohesion for NoCohesion {
    const ACTIVE: bool = false;
    #[inline(always)]
    fn cohesion(&self, _: &Contact, _: &PairConstants) -> f64 {
        0.0
    }
}
