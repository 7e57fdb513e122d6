//! The contact law: the effects summed into the force and torques of one contact.

use super::effects::{Cohesion, NormalForce, Rolling, Tangential};
use super::kinematics::{Contact, History};
use crate::material::PairConstants;
use crate::vec3::*;

/// What a contact does to its two bodies.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactOutput {
    /// Total force on i, N (j gets the opposite).
    pub force: V3,
    /// Torque on i about its centre, N m: the tangential force at lever arm c_i, minus the
    /// rolling torque.
    pub torque_i: V3,
    /// Torque on j about its centre, N m: the tangential force at lever arm c_j, plus the
    /// rolling torque. Not the opposite of `torque_i`: the lever arms differ.
    pub torque_j: V3,
    /// Normal force along n, N, positive when repulsive (including damping and cohesion), for
    /// diagnostics.
    pub f_n: f64,
}

/// What the force loop needs of a law: one generic parameter instead of one per slot.
pub trait ContactLaw: Sync {
    /// Whether the contact area must be computed (only cohesion uses it).
    const NEEDS_AREA: bool;
    /// The force and torques of contact `c` with pair constants `p`, advancing the contact's
    /// history `h` by the time step `dt` (s).
    fn force(&self, c: &Contact, p: &PairConstants, h: &mut History, dt: f64) -> ContactOutput;
    /// Whether this law is the one the four-lane kernel ([`super::lanes`]) computes, bit for
    /// bit (for pairs whose constants [`crate::material::Materials::lanes_ready`] accepts).
    fn four_lanes(&self) -> bool {
        false
    }
}

/// The contact law for one combination of effects.
#[derive(Debug, Clone, Copy, Default)]
pub struct Law<N, T, R, C> {
    /// The normal-force kernel.
    pub normal: N,
    /// The tangential-force kernel.
    pub tangential: T,
    /// The rolling-resistance kernel.
    pub rolling: R,
    /// The cohesion kernel.
    pub cohesion: C,
    /// Keep the normal force (before cohesion) from turning attractive, as LIGGGHTS'
    /// `limitForce on`, with the damping re-solved so that e stays the restitution.
    pub limit_force: bool,
}

impl<N: NormalForce, T: Tangential, R: Rolling, C: Cohesion> ContactLaw for Law<N, T, R, C> {
    const NEEDS_AREA: bool = C::ACTIVE;

    fn four_lanes(&self) -> bool {
        N::LANES && T::LANES && R::LANES && !C::ACTIVE && !self.limit_force
    }

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
        // The Coulomb and rolling caps scale with the load that presses the contact: the normal
        // force before cohesion, i.e. the net load plus the adhesive load (Thornton & Yin 1991's
        // mu (P + 2 P_c) for JKR; LIGGGHTS 3.8's sjkr without `tangential_reduce` does the same).
        // The net force vanishes in a cohesive contact at rest, which would leave it without
        // friction and rolling resistance. Without cohesion both are the same force.
        let f_t = self.tangential.force(c, p, f_normal, &mut h.shear, dt);
        // Torque of the tangential force: lever arm -c_i n for i, +c_j n for j (force -F_t).
        let nxf = cross(c.n, f_t);
        let mut torque_i = scale(nxf, -c.lever_i);
        let mut torque_j = scale(nxf, -c.lever_j);
        if C::ACTIVE {
            // Keep the stored rolling torque in the tangent plane, as the tangential spring is.
            // When the normal turns (a cohesive pair rolling round itself) a torque left in the
            // lab frame gains a twisting part that nothing opposes; with cohesion the caps no
            // longer trim it and it spins pairs up without bound (LIGGGHTS 3.8 does; see
            // tests/cohesion.rs). Without cohesion mbgc keeps LIGGGHTS' update bit for bit, the
            // one its shear box is validated against.
            let twist = dot(h.rolling, c.n);
            sub_assign(&mut h.rolling, scale(c.n, twist));
        }
        let m = self.rolling.torque(c, p, f_normal, &mut h.rolling, dt);
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
