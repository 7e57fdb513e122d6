//! Simplified JKR cohesion (LIGGGHTS 3.8 `cohesion sjkr`): an attraction equal to the cohesion
//! energy density times the area of the contact circle, acting only while the bodies overlap.

use super::effects::Cohesion;
use super::kinematics::Contact;
use super::spec::{EffectSpec, ParamSpec, Slot};
use crate::material::PairConstants;

/// The cohesion energy density k_c, J/m^3 (= N/m^2, a tensile stress over the contact area), in
/// [0, 1e9]; 0 switches cohesion off.
pub const ENERGY_DENSITY: ParamSpec = ParamSpec {
    names: ["ced_pp", "ced_pw"],
    unit: "J/m^3",
    range: (0.0, 1e9),
    default: None,
    variable: true,
    off: Some(0.0),
    what: "cohesion energy density (attraction = ced x contact area)",
};

/// The `sjkr` effect: LIGGGHTS 3.8 `cohesion sjkr`.
pub const SPEC: EffectSpec = EffectSpec {
    name: "sjkr",
    slot: Slot::Cohesion,
    what: "simplified JKR: attraction ced x area of the contact circle while overlapping",
    params: &[ENERGY_DENSITY],
    install: |v, i| i.cohesion_energy_density = v[0],
    liggghts: Some("cohesion sjkr"),
};

/// The SJKR kernel: attraction k_c A, A the area of the contact circle (pi a^2 with a the radius
/// of the intersection circle of the two spheres; pi (2 r d - d^2) against a wall). It acts only
/// while the bodies overlap: no neck forms and breaks as in full JKR.
#[derive(Debug, Clone, Copy, Default)]
pub struct Sjkr;

impl Cohesion for Sjkr {
    #[inline(always)]
    fn cohesion(&self, c: &Contact, p: &PairConstants) -> f64 {
        p.cohesion_energy_density * c.area
    }
}
