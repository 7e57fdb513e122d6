//! The contact law: the effects summed into the force and torques of one contact.

use super::effects::{Cohesion, NormalForce, Rolling, Tangential};
use super::kinematics::{Contact, History};
use crate::dem::material::PairConstants;
use crate::dem::vec3::*;

/// What a contact does to its two bodies.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactOutput {
    /// Total force on i (j gets the opposite).
    pub force: V3,
    pub torque_i: V3,
    pub torque_j: V3,
    /// Normal force magnitude (including damping and cohesion), for diagnostics.
    pub f_n: f64,
}

/// What the force loop needs of a law: one generic parameter instead of one per slot.
pub trait ContactLaw: Sync {
    /// Whether the contact area must be computed (only cohesion uses it).
    const NEEDS_AREA: bool;
    fn force(&self, c: &Contact, p: &PairConstants, h: &mut History, dt: f64) -> ContactOutput;
}

/// The contact law for one combination of effects.
#[derive(Debug, Clone, Copy, Default)]
pub struct Law<N, T, R, C> {
    pub normal: N,
    pub tangential: T,
    pub rolling: R,
    pub cohesion: C,
    /// Keep the normal force (before cohesion) from turning attractive, as LIGGGHTS'
    /// `limitForce on`, with the damping re-solved so that e stays the restitution.
    pub limit_force: bool,
}

impl<N: NormalForce, T: Tangential, R: Rolling, C: Cohesion> ContactLaw for Law<N, T, R, C> {
    const NEEDS_AREA: bool = C::ACTIVE;

    #[inline(always)]
    fn force(&self, c: &Contact, p: &PairConstants, h: &mut History, dt: f64) -> ContactOutput {
        let limited;
        let p = if self.limit_force {
            limited = PairConstants {
                beta: p.beta_limited,
                ..*p
            };
            &limited
        } else {
            p
        };
        let mut f_normal = self.normal.normal(c, p);
        if self.limit_force && f_normal < 0.0 {
            f_normal = 0.0;
        }
        let f_n = f_normal - self.cohesion.cohesion(c, p);
        let f_t = self.tangential.force(c, p, f_n, &mut h.shear, dt);
        // Torque of the tangential force: lever arm -c_i n for i, +c_j n for j (force -F_t).
        let nxf = cross(c.n, f_t);
        let mut torque_i = scale(nxf, -c.lever_i);
        let mut torque_j = scale(nxf, -c.lever_j);
        let m = self.rolling.torque(c, p, f_n, &mut h.rolling, dt);
        sub_assign(&mut torque_i, m);
        add_assign(&mut torque_j, m);
        ContactOutput {
            force: add(scale(c.n, f_n), f_t),
            torque_i,
            torque_j,
            f_n,
        }
    }
}
