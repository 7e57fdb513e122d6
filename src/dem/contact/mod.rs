//! The contact law as a sum of effects.
//!
//! A contact is described once ([`Contact`]: normal, overlap, effective radius and mass, relative
//! velocities at the contact point); each effect then adds its part:
//!
//! 1. a normal force ([`normal`]): Hertz with restitution-based damping as LIGGGHTS 3.8, or the
//!    power-law damped classes of seed 003 (Tsuji, Kuwabara-Kono, free exponent);
//! 2. cohesion ([`cohesion`]), optional: simplified JKR (LIGGGHTS `cohesion sjkr`);
//! 3. the tangential history spring with Coulomb cap ([`tangential`], Mindlin as LIGGGHTS);
//! 4. rolling resistance ([`rolling`]), optional: EPSD2.
//!
//! Effects are chosen by name when a scene is built ([`ContactModel::from_names`]) and the force
//! loop is monomorphised for the chosen combination ([`with_law!`](crate::with_law)), so a contact
//! pays for no dynamic dispatch. A new effect is a new type implementing its trait plus one arm
//! in the dispatch; the other effects are untouched.

pub mod cohesion;
mod effects;
mod kinematics;
mod law;
mod model;
pub mod normal;
pub mod rolling;
pub mod tangential;

pub use effects::{Cohesion, NormalForce, Rolling};
pub use kinematics::{Contact, History};
pub use law::{ContactOutput, Law};
pub use model::{CohesionKind, ContactModel, NormalKind, RollingKind, EFFECT_NAMES};

/// Runs `$body` with `$law` bound to the monomorphised [`Law`] of a [`ContactModel`].
#[macro_export]
macro_rules! with_law {
    ($model:expr, |$law:ident| $body:expr) => {{
        use $crate::dem::contact::{
            cohesion, normal, rolling, CohesionKind, Law, NormalKind, RollingKind,
        };
        let m: $crate::dem::contact::ContactModel = $model;
        let limit_force = m.limit_force;
        let strict_coulomb = m.strict_coulomb;
        macro_rules! inner {
            ($n:expr) => {
                match (m.cohesion, m.rolling) {
                    (CohesionKind::None, RollingKind::None) => {
                        let $law = Law {
                            normal: $n,
                            cohesion: cohesion::NoCohesion,
                            rolling: rolling::NoRolling,
                            limit_force,
                            strict_coulomb,
                        };
                        $body
                    }
                    (CohesionKind::None, RollingKind::Epsd2) => {
                        let $law = Law {
                            normal: $n,
                            cohesion: cohesion::NoCohesion,
                            rolling: rolling::Epsd2,
                            limit_force,
                            strict_coulomb,
                        };
                        $body
                    }
                    (CohesionKind::Sjkr, RollingKind::None) => {
                        let $law = Law {
                            normal: $n,
                            cohesion: cohesion::Sjkr,
                            rolling: rolling::NoRolling,
                            limit_force,
                            strict_coulomb,
                        };
                        $body
                    }
                    (CohesionKind::Sjkr, RollingKind::Epsd2) => {
                        let $law = Law {
                            normal: $n,
                            cohesion: cohesion::Sjkr,
                            rolling: rolling::Epsd2,
                            limit_force,
                            strict_coulomb,
                        };
                        $body
                    }
                }
            };
        }
        match m.normal {
            NormalKind::Hertz => inner!(normal::Hertz),
            NormalKind::PowerDamped { alpha } => inner!(normal::PowerDamped { alpha }),
        }
    }};
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::material::PairConstants;
    use crate::dem::material::{Interaction, Material};
    use crate::dem::vec3::*;

    fn pc(e: f64, mu: f64, mu_r: f64, ced: f64) -> PairConstants {
        let m = Material {
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
            tangential_stiffness: 0.0,
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
        let f = normal::Hertz.normal(&c, &p);
        assert!(
            (f - 4.0 / 3.0 * p.y_eff * (0.01f64).sqrt() * (1e-4f64).powf(1.5)).abs() < 1e-12 * f
        );
        let damped = normal::Hertz.normal(&c, &pc(0.5, 0.5, 0.0, 0.0));
        assert!(damped > f, "damping resists approach");
    }

    #[test]
    fn power_damping_scales_with_overlap_to_alpha() {
        let p = pc(0.5, 0.5, 0.0, 0.0);
        let elastic = |d: f64| 4.0 / 3.0 * p.y_eff * (0.01 * d).sqrt() * d;
        let damp = |d: f64, a: f64| {
            normal::PowerDamped { alpha: a }.normal(&contact(d, -1.0, [0.0; 3], [0.0; 3]), &p)
                - elastic(d)
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
        let f = tangential::mindlin_history(&c, &p, 100.0, &mut xi, 1e-5, false);
        let k_t = 8.0 * p.g_eff * c.sqrt_rd;
        assert!((f[0] + k_t * 1e-7).abs() < 1e-12 * k_t, "stick: -k_t xi");
        for strict in [false, true] {
            let mut xi = [1.0, 0.0, 0.0];
            let f = tangential::mindlin_history(&c, &p, 100.0, &mut xi, 1e-5, strict);
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
        let f = tangential::mindlin_history(&c, &p, 100.0, &mut xi, 1e-5, false);
        assert!((f[0] + 5e4 * 1e-7).abs() < 1e-15, "stick: -k_t xi, {f:?}");
        let mut xi = [1.0, 0.0, 0.0];
        let f = tangential::mindlin_history(&c, &p, 100.0, &mut xi, 1e-5, false);
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
        let t = rolling::Epsd2.torque(&c, &p, 100.0, &mut m, 1e-6);
        let k_r = 8.0 * p.g_eff * c.sqrt_rd * 0.01 * 0.01;
        assert!((t[1] - k_r * 1e-6).abs() < 1e-12 * k_r);
        for _ in 0..1_000_000 {
            rolling::Epsd2.torque(&c, &p, 100.0, &mut m, 1e-3);
        }
        assert!(
            (norm(m) - 0.2 * 0.01 * 100.0).abs() < 1e-12,
            "cap mu_r R* F_n: {m:?}"
        );
        // Twisting about the normal is not rolling.
        let c = contact(1e-4, 0.0, [0.0; 3], [0.0, 0.0, 5.0]);
        let mut m = [0.0; 3];
        assert_eq!(rolling::Epsd2.torque(&c, &p, 100.0, &mut m, 1e-3), [0.0; 3]);
    }

    #[test]
    fn sjkr_pulls_with_energy_density_times_area() {
        let p = pc(0.5, 0.5, 0.0, 3e4);
        let c = contact(1e-4, 0.0, [0.0; 3], [0.0; 3]);
        assert_eq!(cohesion::Sjkr.cohesion(&c, &p), 3e4 * 1e-5);
        assert_eq!(cohesion::NoCohesion.cohesion(&c, &p), 0.0);
    }
}
