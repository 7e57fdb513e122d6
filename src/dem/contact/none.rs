//! Empty slots: no rolling resistance, no cohesion.

use super::effects::{Cohesion, Rolling};
use super::kinematics::Contact;
use super::spec::{none, EffectSpec, Slot};
use crate::dem::material::PairConstants;
use crate::dem::vec3::V3;

pub const NO_ROLLING: EffectSpec = none(Slot::Rolling, "no-rolling");
pub const NO_COHESION: EffectSpec = none(Slot::Cohesion, "no-cohesion");

#[derive(Debug, Clone, Copy, Default)]
pub struct NoRolling;

impl Rolling for NoRolling {
    #[inline(always)]
    fn torque(&self, _: &Contact, _: &PairConstants, _: f64, _: &mut V3, _: f64) -> V3 {
        [0.0; 3]
    }
}

#[derive(Debug, Clone, Copy, Default)]
pub struct NoCohesion;

impl Cohesion for NoCohesion {
    const ACTIVE: bool = false;
    #[inline(always)]
    fn cohesion(&self, _: &Contact, _: &PairConstants) -> f64 {
        0.0
    }
}
