//! Tangential force: the history spring with Coulomb cap of LIGGGHTS 3.8 `tangential history`
//! (`mindlin`), its strict-Coulomb variant, and the constant-stiffness spring of seed 003
//! (`linear-spring`). The three share one kernel; the variant is a per-pair constant, a branch
//! the processor predicts perfectly.

use super::effects::Tangential;
use super::hertz::SQRT_5_6;
use super::kinematics::Contact;
use super::spec::{EffectSpec, ParamSpec, Slot};
use crate::material::PairConstants;
use crate::vec3::*;

/// The Coulomb sliding friction coefficient mu, dimensionless, in [0, 10]: the tangential force
/// is capped at mu |F_n|. Shared by the three tangential effects.
pub const FRICTION: ParamSpec = ParamSpec {
    names: ["mu_pp", "mu_pw"],
    unit: "-",
    range: (0.0, 10.0),
    default: None,
    variable: true,
    off: None,
    what: "Coulomb sliding friction coefficient",
};

/// The constant tangential spring stiffness k_t of `linear-spring`, N/m, in [1e-12, 1e15]
/// (positive: zero would mean Mindlin's stiffness in the pair constants).
pub const STIFFNESS: ParamSpec = ParamSpec {
    names: ["k_t_pp", "k_t_pw"],
    unit: "N/m",
    range: (1e-12, 1e15),
    default: None,
    variable: true,
    off: None,
    what: "constant tangential spring stiffness",
};

/// The `mindlin` effect: LIGGGHTS 3.8's history spring, k_t = 8 G* sqrt(R* d), spring capped at
/// mu |F_n|.
pub const SPEC: EffectSpec = EffectSpec {
    name: "mindlin",
    slot: Slot::Tangential,
    what: "Mindlin's history spring k_t = 8 G* sqrt(R* d) with the spring capped at mu F_n \
           (LIGGGHTS 3.8 `tangential history`)",
    params: &[FRICTION],
    install: |v, i| i.friction = v[0],
    liggghts: Some("tangential history"),
};

/// The `strict-coulomb` effect: Mindlin's spring with spring plus dashpot capped at
/// mu max(F_n, 0), so that a sliding contact never exceeds the Coulomb force.
pub const STRICT_COULOMB: EffectSpec = EffectSpec {
    name: "strict-coulomb",
    slot: Slot::Tangential,
    what: "Mindlin's spring with spring plus dashpot capped at mu max(F_n, 0)",
    params: &[FRICTION],
    install: |v, i| {
        i.friction = v[0];
        i.strict_coulomb = true;
    },
    liggghts: None,
};

/// The `linear-spring` effect: a constant-stiffness history spring (Cundall-Strack, seed 003)
/// with LIGGGHTS' cap.
pub const LINEAR_SPRING: EffectSpec = EffectSpec {
    name: "linear-spring",
    slot: Slot::Tangential,
    what: "a constant-stiffness history spring k_t with Coulomb cap (Cundall-Strack, seed 003)",
    params: &[FRICTION, STIFFNESS],
    install: |v, i| {
        i.friction = v[0];
        i.tangential_stiffness = v[1];
    },
    liggghts: None,
};

/// The kernel of the three tangential effects, [`mindlin_history`] with the variant read from
/// the pair constants (`strict_coulomb`, `k_t_fixed`).
#[derive(Debug, Clone, Copy, Default)]
pub struct HistorySpring;

impl Tangential for HistorySpring {
    const LANES: bool = true;
    #[inline(always)]
    fn force(&self, c: &Contact, p: &PairConstants, f_n: f64, xi: &mut V3, dt: f64) -> V3 {
        mindlin_history(c, p, f_n, xi, dt, p.strict_coulomb)
    }
}

/// Advances the spring `xi` by the tangential relative velocity, keeps it in the tangent plane,
/// and returns the tangential force on i; k_t = 8 G* sqrt(R* d) (Mindlin) or the pair's constant
/// `k_t_fixed` when set (the linear Cundall-Strack spring of seed 003),
/// gamma_t = -2 sqrt(5/6) beta sqrt(k_t m*).
///
/// LIGGGHTS (`strict = false`): if the spring force k_t |xi| exceeds mu |F_n|, the force is the
/// cap and the spring is reset to it, without damping; otherwise F_t = -k_t xi - gamma_t v_t, and
/// this total may exceed the cap, by the dashpot.
///
/// Strict Coulomb (`strict = true`): the total -k_t xi - gamma_t v_t is capped at
/// mu max(F_n, 0), and when capped the spring alone is set to the cap, so that sliding goes on at
/// exactly mu F_n. (Setting the spring so that spring plus dashpot equal the cap, as LAMMPS
/// `mindlin` does, leaves the spring pointing the wrong way after a fast slip and under-counts
/// friction in the following steps.)
#[inline(always)]
pub fn mindlin_history(
    c: &Contact,
    p: &PairConstants,
    f_n: f64,
    xi: &mut V3,
    dt: f64,
    strict: bool,
) -> V3 {
    add_assign(xi, scale(c.v_t, dt));
    let xn = dot(*xi, c.n);
    sub_assign(xi, scale(c.n, xn));
    let fixed = p.k_t_fixed > 0.0;
    let k_t = if fixed {
        p.k_t_fixed
    } else {
        8.0 * p.g_eff * c.sqrt_rd
    };
    // -2 sqrt(5/6) beta sqrt(k_t m*), in Mindlin's case with the operations in LIGGGHTS' order.
    let damping = || {
        if fixed {
            -2.0 * SQRT_5_6 * p.beta * (p.k_t_fixed * c.m_eff).sqrt()
        } else {
            -2.0 * SQRT_5_6 * p.beta * p.sqrt_8g * c.damp_root
        }
    };
    if strict {
        let gamma_t = damping();
        let mut f_t = sub(scale(*xi, -k_t), scale(c.v_t, gamma_t));
        let cap = p.friction * f_n.max(0.0);
        let mag2 = norm2(f_t);
        if mag2 > cap * cap {
            f_t = if mag2 > 0.0 {
                scale(f_t, cap / mag2.sqrt())
            } else {
                f_t
            };
            *xi = scale(f_t, -1.0 / k_t);
        }
        return f_t;
    }
    let mut f_t = scale(*xi, -k_t);
    let f_shear2 = norm2(f_t);
    let f_friction = p.friction * f_n.abs();
    if f_shear2 > f_friction * f_friction {
        let f_shear = f_shear2.sqrt();
        if f_shear > 0.0 {
            f_t = scale(f_t, f_friction / f_shear);
            *xi = scale(f_t, -1.0 / k_t);
        }
    } else {
        let gamma_t = damping();
        sub_assign(&mut f_t, scale(c.v_t, gamma_t));
    }
    f_t
}
