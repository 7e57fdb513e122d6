//! Rolling resistance.

use super::effects::Rolling;
use super::kinematics::Contact;
use crate::dem::material::PairConstants;
use crate::dem::vec3::*;

#[derive(Debug, Clone, Copy, Default)]
pub struct NoRolling;

impl Rolling for NoRolling {
    #[inline(always)]
    fn torque(&self, _: &Contact, _: &PairConstants, _: f64, _: &mut V3, _: f64) -> V3 {
        [0.0; 3]
    }
}

/// EPSD2 (LIGGGHTS 3.8 `rolling_friction epsd2`): an elastic-plastic spring on the relative
/// rolling rotation, k_r = k_t R*^2, capped at mu_r R* |F_n|; no dashpot (as LIGGGHTS).
#[derive(Debug, Clone, Copy, Default)]
pub struct Epsd2;

impl Rolling for Epsd2 {
    #[inline(always)]
    fn torque(&self, c: &Contact, p: &PairConstants, f_n: f64, m: &mut V3, dt: f64) -> V3 {
        let k_t = 8.0 * p.g_eff * c.sqrt_rd;
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
