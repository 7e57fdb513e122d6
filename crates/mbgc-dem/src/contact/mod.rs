//! The contact law as a sum of effects, one per slot.
//!
//! A contact is described once ([`Contact`]: normal, overlap, effective radius and mass, relative
//! velocities at the contact point); each slot's effect then adds its part:
//!
//! 1. a normal force: Hertz with restitution-based damping as LIGGGHTS 3.8 ([`hertz`]), or the
//!    power-law damped classes of seed 003 ([`power_damped`]: Tsuji, Kuwabara-Kono, free
//!    exponent);
//! 2. cohesion, optional: simplified JKR ([`sjkr`], LIGGGHTS `cohesion sjkr`);
//! 3. the tangential history spring with Coulomb cap ([`mindlin`]: Mindlin as LIGGGHTS, strict
//!    Coulomb, constant stiffness);
//! 4. rolling resistance, optional: EPSD2 ([`epsd2`]) or constant directional torque ([`cdt`]).
//!
//! A [`ModelClass`] names the effects switched on; each effect's file holds its kernel and its
//! [`EffectSpec`] (name, parameters with units and ranges). [`registry`] lists them, one line
//! each; the slot enums and the dispatch [`with_law!`](crate::with_law) are generated from it, so
//! the force loop is monomorphised for the chosen kernels and a contact pays for no dynamic
//! dispatch.

pub mod cdt;
mod effects;
pub mod epsd2;
pub mod hertz;
#[doc(hidden)]
pub mod kinds;
mod kinematics;
pub(crate) mod lanes;
#[doc(hidden)]
pub mod law;
pub mod mindlin;
mod model_class;
pub mod none;
pub mod power_damped;
pub mod registry;
pub mod sjkr;
pub mod spec;

pub use effects::{Cohesion, NormalForce, Rolling, Tangential};
pub use kinematics::{Contact, History};
pub use law::{ContactLaw, ContactOutput, Law};
pub use model_class::{
    all_effects, effect_names, CohesionKind, ModelClass, NormalKind, RollingKind, TangentialKind,
    LIMIT_FORCE,
};
pub use spec::{EffectSpec, Pair, ParamSpec, Slot};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::PairConstants;
    use crate::material::{Interaction, Solid};
    use crate::vec3::*;

    fn pc(e: f64, mu: f64, mu_r: f64, ced: f64) -> PairConstants {
        let m = Solid {
            name: "m".into(),
            youngs_modulus: 1e8,
            poisson: 0.25,
        };
        let i = Interaction {
            restitution: e,
            friction: mu,
            rolling_friction: mu_r,
            cohesion_energy_density: ced,
            damping_gamma_n: 2.0,
            ..Interaction::default()
        };
        PairConstants::new(&m, &m, &i)
    }

    fn contact(overlap: f64, v_n: f64, v_t: V3, w_rel: V3) -> Contact {
        Contact::new(
            [0.0, 0.0, 1.0],
            overlap,
            0.01,
            0.02,
            add([0.0, 0.0, v_n], v_t),
            w_rel,
            [0.0; 3],
            0.01,
            0.01,
            1e-5,
        )
    }

    #[test]
    fn hertz_is_elastic_hertz_plus_restitution_damping() {
        let p = pc(1.0, 0.5, 0.0, 0.0);
        let c = contact(1e-4, -0.3, [0.0; 3], [0.0; 3]);
        let f = hertz::Hertz.normal(&c, &p);
        assert!(
            (f - 4.0 / 3.0 * p.y_eff * (0.01f64).sqrt() * (1e-4f64).powf(1.5)).abs() < 1e-12 * f
        );
        let damped = hertz::Hertz.normal(&c, &pc(0.5, 0.5, 0.0, 0.0));
        assert!(damped > f, "damping resists approach");
    }

    #[test]
    fn power_damping_scales_with_overlap_to_alpha() {
        let p = pc(0.5, 0.5, 0.0, 0.0);
        let elastic = |d: f64| 4.0 / 3.0 * p.y_eff * (0.01 * d).sqrt() * d;
        let damp = |d: f64, a: f64| {
            let p = PairConstants {
                damping_alpha: a,
                ..p
            };
            power_damped::PowerDamped.normal(&contact(d, -1.0, [0.0; 3], [0.0; 3]), &p) - elastic(d)
        };
        for a in [0.25, 0.5, 0.8] {
            let ratio = damp(4e-4, a) / damp(1e-4, a);
            assert!((ratio - 4f64.powf(a)).abs() < 1e-9, "alpha {a}: {ratio}");
        }
    }

    #[test]
    fn tangential_spring_sticks_then_caps_at_coulomb() {
        let p = pc(1.0, 0.3, 0.0, 0.0);
        let c = contact(1e-4, 0.0, [0.01, 0.0, 0.0], [0.0; 3]);
        let mut xi = [0.0; 3];
        let f = mindlin::mindlin_history(&c, &p, 100.0, &mut xi, 1e-5, false);
        let k_t = 8.0 * p.g_eff * c.sqrt_rd;
        assert!((f[0] + k_t * 1e-7).abs() < 1e-12 * k_t, "stick: -k_t xi");
        for strict in [false, true] {
            let mut xi = [1.0, 0.0, 0.0];
            let f = mindlin::mindlin_history(&c, &p, 100.0, &mut xi, 1e-5, strict);
            assert!(
                (norm(f) - 30.0).abs() < 1e-9 && f[0] < 0.0,
                "slide: mu F_n against the slip"
            );
        }
    }

    #[test]
    fn a_constant_tangential_stiffness_replaces_mindlins() {
        let mut p = pc(1.0, 0.3, 0.0, 0.0);
        p.k_t_fixed = 5e4;
        let c = contact(1e-4, 0.0, [0.01, 0.0, 0.0], [0.0; 3]);
        let mut xi = [0.0; 3];
        let f = mindlin::mindlin_history(&c, &p, 100.0, &mut xi, 1e-5, false);
        assert!((f[0] + 5e4 * 1e-7).abs() < 1e-15, "stick: -k_t xi, {f:?}");
        let mut xi = [1.0, 0.0, 0.0];
        let f = mindlin::mindlin_history(&c, &p, 100.0, &mut xi, 1e-5, false);
        assert!((norm(f) - 30.0).abs() < 1e-9, "slide: mu F_n");
        assert!(
            (xi[0] - 30.0 / 5e4).abs() < 1e-15,
            "spring reset to the cap"
        );
    }

    #[test]
    fn epsd2_torque_grows_with_rotation_and_caps() {
        let p = pc(0.5, 0.5, 0.2, 0.0);
        let c = contact(1e-4, 0.0, [0.0; 3], [0.0, 1.0, 0.0]);
        let mut m = [0.0; 3];
        let t = epsd2::Epsd2.torque(&c, &p, 100.0, &mut m, 1e-6);
        let k_r = 8.0 * p.g_eff * c.sqrt_rd * 0.01 * 0.01;
        assert!((t[1] - k_r * 1e-6).abs() < 1e-12 * k_r);
        for _ in 0..1_000_000 {
            epsd2::Epsd2.torque(&c, &p, 100.0, &mut m, 1e-3);
        }
        assert!(
            (norm(m) - 0.2 * 0.01 * 100.0).abs() < 1e-12,
            "cap mu_r R* F_n: {m:?}"
        );
        // Twisting about the normal is not rolling.
        let c = contact(1e-4, 0.0, [0.0; 3], [0.0, 0.0, 5.0]);
        let mut m = [0.0; 3];
        assert_eq!(epsd2::Epsd2.torque(&c, &p, 100.0, &mut m, 1e-3), [0.0; 3]);
    }

    #[test]
    fn cdt_torque_is_constant_and_against_the_rolling() {
        let p = pc(0.5, 0.5, 0.2, 0.0);
        for w in [1e-6, 1.0, 1e3] {
            let c = contact(1e-4, 0.0, [0.0; 3], [0.0, w, 0.0]);
            let mut m = [0.0; 3];
            let t = cdt::Cdt.torque(&c, &p, 100.0, &mut m, 1e-3);
            assert!((t[1] - 0.2 * 0.01 * 100.0).abs() < 1e-12, "{w}: {t:?}");
            assert_eq!(m, [0.0; 3], "no history");
        }
        let c = contact(1e-4, 0.0, [0.0; 3], [0.0; 3]);
        assert_eq!(
            cdt::Cdt.torque(&c, &p, 100.0, &mut [0.0; 3], 1e-3),
            [0.0; 3]
        );
    }

    #[test]
    fn sjkr_pulls_with_energy_density_times_area() {
        let p = pc(0.5, 0.5, 0.0, 3e4);
        let c = contact(1e-4, 0.0, [0.0; 3], [0.0; 3]);
        assert_eq!(sjkr::Sjkr.cohesion(&c, &p), 3e4 * 1e-5);
        assert_eq!(none::NoCohesion.cohesion(&c, &p), 0.0);
    }
}
