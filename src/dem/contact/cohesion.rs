//! Cohesion.

use super::effects::Cohesion;
use super::kinematics::Contact;
use crate::dem::material::PairConstants;

#[derive(Debug, Clone, Copy, Default)]
pub struct NoCohesion;

impl Cohesion for NoCohesion {
    const ACTIVE: bool = false;
    #[inline(always)]
    fn cohesion(&self, _: &Contact, _: &PairConstants) -> f64 {
        0.0
    }
}

/// Simplified JKR (LIGGGHTS `cohesion sjkr`): an attraction equal to the cohesion energy density
/// times the area of the contact circle, acting only while the bodies overlap.
#[derive(Debug, Clone, Copy, Default)]
pub struct Sjkr;

impl Cohesion for Sjkr {
    #[inline(always)]
    fn cohesion(&self, c: &Contact, p: &PairConstants) -> f64 {
        p.cohesion_energy_density * c.area
    }
}
