//! Normal force models.

use super::effects::NormalForce;
use super::kinematics::Contact;
use crate::dem::material::PairConstants;

/// sqrt(5/6), from LIGGGHTS' damping coefficient.
const SQRT_5_6: f64 = 0.912_870_929_175_276_8;

/// Hertz with restitution-based viscous damping, exactly as LIGGGHTS 3.8 `model hertz`:
/// k_n = 4/3 Y* sqrt(R* d), S_n = 2 Y* sqrt(R* d), gamma_n = -2 sqrt(5/6) beta sqrt(S_n m*),
/// F_n = k_n d - gamma_n v_n. The attractive part near separation is not clamped (as LIGGGHTS).
#[derive(Debug, Clone, Copy, Default)]
pub struct Hertz;

impl NormalForce for Hertz {
    #[inline(always)]
    fn normal(&self, c: &Contact, p: &PairConstants) -> f64 {
        let k_n = (4.0 / 3.0) * p.y_eff * c.sqrt_rd;
        // sqrt(S_n m*) = sqrt(2 Y*) sqrt(sqrt(R* d) m*)
        let gamma_n = -2.0 * SQRT_5_6 * p.beta * p.sqrt_2y * c.damp_root;
        k_n * c.overlap - gamma_n * c.v_n
    }
}

/// Hertz elasticity with power-law damping (seed 003, Table 1):
/// F_n = 4/3 Y* sqrt(R*) d^(3/2) + gamma_n d^alpha d', with d' = -v_n the overlap rate.
/// alpha = 1/4 is Tsuji's model (M1), 1/2 Kuwabara-Kono's (M2), a free alpha is M3.
#[derive(Debug, Clone, Copy)]
pub struct PowerDamped {
    pub alpha: f64,
}

impl NormalForce for PowerDamped {
    #[inline(always)]
    fn normal(&self, c: &Contact, p: &PairConstants) -> f64 {
        let elastic = (4.0 / 3.0) * p.y_eff * c.sqrt_rd * c.overlap;
        elastic - p.damping_gamma_n * c.overlap.powf(self.alpha) * c.v_n
    }
}
