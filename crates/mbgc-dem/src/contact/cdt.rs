//! Constant directional torque (LIGGGHTS 3.8 `rolling_friction cdt`, Zhou et al. 1999): a torque
//! of magnitude mu_r R* |F_n| against the relative rolling rotation, whatever its speed. It
//! carries no history; at rest it flips with the sign of the rolling velocity, so packings at
//! rest jitter slightly (the reason EPSD2 exists).

use super::effects::Rolling;
use super::epsd2::ROLLING_FRICTION;
use super::kinematics::Contact;
use super::spec::{EffectSpec, Slot};
use crate::material::PairConstants;
use crate::vec3::*;

/// The `cdt` effect: LIGGGHTS 3.8 `rolling_friction cdt`.
pub const SPEC: EffectSpec = EffectSpec {
    name: "cdt",
    slot: Slot::Rolling,
    what: "constant torque mu_r R* F_n against the relative rolling rotation",
    params: &[ROLLING_FRICTION],
    install: |v, i| i.rolling_friction = v[0],
    liggghts: Some("rolling_friction cdt"),
};

/// The CDT kernel: a torque mu_r R* |F_n| along the relative rolling velocity (applied against
/// it by the law), zero when the bodies do not roll.
#[derive(Debug, Clone, Copy, Default)]
pub struct Cdt;

impl Rolling for Cdt {
    #[inline(always)]
    fn torque(&self, c: &Contact, p: &PairConstants, f_n: f64, _: &mut V3, _: f64) -> V3 {
        let w2 = norm2(c.w_roll);
        if w2 == 0.0 {
            return [0.0; 3];
        }
        scale(
            c.w_roll,
            p.rolling_friction * c.r_eff * f_n.abs() / w2.sqrt(),
        )
    }
}
