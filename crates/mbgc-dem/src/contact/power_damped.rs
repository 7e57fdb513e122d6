//! Hertz elasticity with power-law damping (seed 003, Table 1):
//! F_n = 4/3 Y* sqrt(R*) d^(3/2) + gamma_n d^alpha d', with d' = -v_n the overlap rate.
//! alpha = 1/4 is Tsuji's model (M1), 1/2 Kuwabara-Kono's (M2), a free alpha is M3. The three
//! effects share one kernel; the exponent is a per-pair constant.

use super::effects::NormalForce;
use super::kinematics::Contact;
use super::spec::{EffectSpec, ParamSpec, Slot};
use crate::material::PairConstants;

/// The damping constant gamma_n of the power-law dashpot, N s/m^(1+alpha), in [0, 1e12]. Its
/// unit depends on alpha, so a value calibrated for one exponent means nothing for another.
pub const GAMMA_N: ParamSpec = ParamSpec {
    names: ["gamma_n_pp", "gamma_n_pw"],
    unit: "N s/m^(1+alpha)",
    range: (0.0, 1e12),
    default: None,
    variable: true,
    off: None,
    what: "normal damping constant of the power-law dashpot",
};

/// The exponent alpha of the overlap in the power-law dashpot, dimensionless, in [0, 2]
/// (0: a linear dashpot, 1/4 Tsuji, 1/2 Kuwabara-Kono).
pub const ALPHA_N: ParamSpec = ParamSpec {
    names: ["alpha_n_pp", "alpha_n_pw"],
    unit: "-",
    range: (0.0, 2.0),
    default: None,
    variable: true,
    off: None,
    what: "exponent of the overlap in the power-law dashpot",
};

/// The `tsuji` effect: dashpot gamma_n d^(1/4) (seed 003's M1), which for Hertz elasticity
/// gives a restitution independent of the impact speed.
pub const TSUJI: EffectSpec = EffectSpec {
    name: "tsuji",
    slot: Slot::Normal,
    what: "Hertz elasticity, dashpot gamma_n d^(1/4) (Tsuji et al. 1992)",
    params: &[GAMMA_N],
    install: |v, i| {
        i.damping_gamma_n = v[0];
        i.damping_alpha = 0.25;
    },
    liggghts: None,
};

/// The `kuwabara-kono` effect: dashpot gamma_n d^(1/2) (seed 003's M2), the viscoelastic
/// solution, whose restitution falls with impact speed.
pub const KUWABARA_KONO: EffectSpec = EffectSpec {
    name: "kuwabara-kono",
    slot: Slot::Normal,
    what: "Hertz elasticity, dashpot gamma_n d^(1/2) (Kuwabara & Kono 1987)",
    params: &[GAMMA_N],
    install: |v, i| {
        i.damping_gamma_n = v[0];
        i.damping_alpha = 0.5;
    },
    liggghts: None,
};

/// The `power-damped` effect: dashpot gamma_n d^alpha with alpha a parameter (seed 003's M3).
pub const POWER_DAMPED: EffectSpec = EffectSpec {
    name: "power-damped",
    slot: Slot::Normal,
    what: "Hertz elasticity, dashpot gamma_n d^alpha_n with a free exponent (seed 003's M3)",
    params: &[GAMMA_N, ALPHA_N],
    install: |v, i| {
        i.damping_gamma_n = v[0];
        i.damping_alpha = v[1];
    },
    liggghts: None,
};

/// The kernel of the three power-law damped normal effects:
/// F_n = 4/3 Y* sqrt(R* d) d - gamma_n d^alpha v_n, with gamma_n and alpha per-pair constants.
#[derive(Debug, Clone, Copy, Default)]
pub struct PowerDamped;

impl NormalForce for PowerDamped {
    #[inline(always)]
    fn normal(&self, c: &Contact, p: &PairConstants) -> f64 {
        let elastic = (4.0 / 3.0) * p.y_eff * c.sqrt_rd * c.overlap;
        elastic - p.damping_gamma_n * c.overlap.powf(p.damping_alpha) * c.v_n
    }
}
