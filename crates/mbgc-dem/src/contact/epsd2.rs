//! EPSD2 rolling resistance (LIGGGHTS 3.8 `rolling_friction epsd2`, Wensrich & Katterfeld 2012):
//! an elastic-plastic spring on the relative rolling rotation, k_r = k_t R*^2, capped at
//! mu_r R* |F_n|; no dashpot (as LIGGGHTS).

use super::effects::Rolling;
use super::kinematics::Contact;
use super::spec::{EffectSpec, ParamSpec, Slot};
use crate::material::PairConstants;
use crate::vec3::*;

/// The rolling friction coefficient, shared by the rolling resistance effects.
pub const ROLLING_FRICTION: ParamSpec = ParamSpec {
    names: ["mu_r_pp", "mu_r_pw"],
    unit: "-",
    range: (0.0, 10.0),
    default: None,
    variable: true,
    off: Some(0.0),
    what: "rolling friction coefficient (torque cap mu_r R* F_n)",
};

/// The `epsd2` effect: LIGGGHTS 3.8 `rolling_friction epsd2`.
pub const SPEC: EffectSpec = EffectSpec {
    name: "epsd2",
    slot: Slot::Rolling,
    what: "elastic-plastic spring on the rolling rotation, k_r = k_t R*^2, capped at mu_r R* F_n",
    params: &[ROLLING_FRICTION],
    install: |v, i| i.rolling_friction = v[0],
    liggghts: Some("rolling_friction epsd2"),
};

/// The EPSD2 kernel: M += k_r w_roll dt with k_r = k_t R*^2 (k_t Mindlin's 8 G* sqrt(R* d), or
/// the pair's constant stiffness), then |M| capped at mu_r R* |F_n|. Without a dashpot a resting
/// packing keeps rocking: its rotational energy can stay far above its translational energy.
#[derive(Debug, Clone, Copy, Default)]
pub struct Epsd2;

impl Rolling for Epsd2 {
    const LANES: bool = true;
    #[inline(always)]
    fn torque(&self, c: &Contact, p: &PairConstants, f_n: f64, m: &mut V3, dt: f64) -> V3 {
        // The pair's tangential stiffness: Mindlin's, or the constant of `linear-spring`.
        let k_t = if p.k_t_fixed > 0.0 {
            p.k_t_fixed
        } else {
            8.0 * p.g_eff * c.sqrt_rd
        };
        let k_r = k_t * c.r_eff * c.r_eff;
        add_assign(m, scale(c.w_roll, k_r * dt));
        let cap = p.rolling_friction * c.r_eff * f_n.abs();
        let mag2 = norm2(*m);
        if mag2 > cap * cap {
            *m = scale(*m, cap / mag2.sqrt());
        }
        *m
    }
}
