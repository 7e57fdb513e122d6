//! Hertz with restitution-based viscous damping, exactly as LIGGGHTS 3.8 `model hertz`.

use super::effects::NormalForce;
use super::kinematics::Contact;
use super::spec::{EffectSpec, ParamSpec, Slot};
use crate::material::PairConstants;

/// sqrt(5/6), the factor of LIGGGHTS' Hertz damping coefficient (also used by the contact-law
/// derivatives of `mbgc::sensitivity`).
pub const SQRT_5_6: f64 = 0.912_870_929_175_276_8;

/// The coefficient of restitution, shared by the effects whose damping follows from it.
pub const RESTITUTION: ParamSpec = ParamSpec {
    names: ["e_pp", "e_pw"],
    unit: "-",
    range: (0.05, 1.0),
    default: None,
    variable: true,
    off: None,
    what: "coefficient of restitution",
};

/// The `hertz` effect: Hertz elasticity with LIGGGHTS' restitution-based dashpot.
pub const SPEC: EffectSpec = EffectSpec {
    name: "hertz",
    slot: Slot::Normal,
    what: "Hertz elasticity with the restitution-based dashpot of LIGGGHTS 3.8",
    params: &[RESTITUTION],
    install: |v, i| i.restitution = v[0],
    liggghts: Some("model hertz"),
};

/// k_n = 4/3 Y* sqrt(R* d), S_n = 2 Y* sqrt(R* d), gamma_n = -2 sqrt(5/6) beta sqrt(S_n m*),
/// F_n = k_n d - gamma_n v_n. The attractive part near separation is not clamped (as LIGGGHTS;
/// the `limit-force` option clamps it).
#[derive(Debug, Clone, Copy, Default)]
pub struct Hertz;

impl NormalForce for Hertz {
    const LANES: bool = true;
    #[inline(always)]
    fn normal(&self, c: &Contact, p: &PairConstants) -> f64 {
        let k_n = (4.0 / 3.0) * p.y_eff * c.sqrt_rd;
        // sqrt(S_n m*) = sqrt(2 Y*) sqrt(sqrt(R* d) m*)
        let gamma_n = -2.0 * SQRT_5_6 * p.beta * p.sqrt_2y * c.damp_root;
        k_n * c.overlap - gamma_n * c.v_n
    }
}
