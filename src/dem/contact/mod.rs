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
pub mod normal;
pub mod rolling;
pub mod tangential;

use super::material::PairConstants;
use super::vec3::*;
use crate::error::{Error, Result};

/// Per-contact state carried from step to step (and across neighbour-list rebuilds).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct History {
    /// Tangential spring displacement xi.
    pub shear: V3,
    /// Rolling resistance torque M (EPSD2).
    pub rolling: V3,
}

impl History {
    pub fn is_zero(&self) -> bool {
        self.shear == [0.0; 3] && self.rolling == [0.0; 3]
    }
}

/// Geometry and kinematics of one touching contact between particle i and a partner j (another
/// particle or a wall).
#[derive(Debug, Clone, Copy)]
pub struct Contact {
    /// Unit normal pointing from j to i.
    pub n: V3,
    /// Overlap delta > 0.
    pub overlap: f64,
    pub r_eff: f64,
    pub m_eff: f64,
    /// sqrt(R* delta), shared by the Hertz and Mindlin stiffnesses.
    pub sqrt_rd: f64,
    /// sqrt(sqrt(R* delta) m*), shared by the normal and tangential dashpots.
    pub damp_root: f64,
    /// Normal relative velocity (v_i - v_j).n: negative while approaching.
    pub v_n: f64,
    /// Tangential relative velocity of the contact points.
    pub v_t: V3,
    /// Relative angular velocity w_i - w_j with its twisting part removed.
    pub w_roll: V3,
    /// Lever arms from the centres to the contact point.
    pub lever_i: f64,
    pub lever_j: f64,
    /// Area of the contact circle, used by cohesion.
    pub area: f64,
}

impl Contact {
    /// Builds the contact from the state of both bodies. `lever_i`/`lever_j` are the distances
    /// from the centres to the contact point; `area` is the overlap circle area.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn new(
        n: V3,
        overlap: f64,
        r_eff: f64,
        m_eff: f64,
        v_rel: V3,
        w_i: V3,
        w_j: V3,
        lever_i: f64,
        lever_j: f64,
        area: f64,
    ) -> Self {
        let v_n = dot(v_rel, n);
        let v_t0 = sub(v_rel, scale(n, v_n));
        let w_sum = add(scale(w_i, lever_i), scale(w_j, lever_j));
        let v_t = sub(v_t0, cross(w_sum, n));
        let w_rel = sub(w_i, w_j);
        let w_roll = sub(w_rel, scale(n, dot(w_rel, n)));
        let sqrt_rd = (r_eff * overlap).sqrt();
        Contact {
            n,
            overlap,
            r_eff,
            m_eff,
            sqrt_rd,
            damp_root: (sqrt_rd * m_eff).sqrt(),
            v_n,
            v_t,
            w_roll,
            lever_i,
            lever_j,
            area,
        }
    }
}

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

pub trait NormalForce: Copy + Send + Sync {
    /// Normal force along n (positive pushes the bodies apart).
    fn normal(&self, c: &Contact, p: &PairConstants) -> f64;
}

pub trait Cohesion: Copy + Send + Sync {
    /// Whether the effect needs the contact area (skipped at compile time when not).
    const ACTIVE: bool = true;
    /// Attractive force magnitude (subtracted from the normal force).
    fn cohesion(&self, c: &Contact, p: &PairConstants) -> f64;
}

pub trait Rolling: Copy + Send + Sync {
    /// Rolling resistance torque on i (j gets the opposite); updates the history.
    fn torque(&self, c: &Contact, p: &PairConstants, f_n: f64, m: &mut V3, dt: f64) -> V3;
}

/// The contact law for one combination of effects.
#[derive(Debug, Clone, Copy)]
pub struct Law<N, C, R> {
    pub normal: N,
    pub cohesion: C,
    pub rolling: R,
    /// Keep the normal force (before cohesion) from turning attractive, as LIGGGHTS'
    /// `limitForce on`, with the damping re-solved so that e stays the restitution.
    pub limit_force: bool,
    /// Cap spring plus dashpot at mu max(F_n, 0) (LAMMPS `mindlin`) instead of LIGGGHTS' cap
    /// on the spring alone.
    pub strict_coulomb: bool,
}

impl<N: NormalForce, C: Cohesion, R: Rolling> Law<N, C, R> {
    #[inline(always)]
    pub fn force(&self, c: &Contact, p: &PairConstants, h: &mut History, dt: f64) -> ContactOutput {
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
        let f_t = tangential::mindlin_history(c, p, f_n, &mut h.shear, dt, self.strict_coulomb);
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

/// Normal force classes that can be chosen by name.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NormalKind {
    /// Hertz with restitution-based damping, as LIGGGHTS 3.8 `model hertz`.
    Hertz,
    /// Hertz elasticity with damping gamma_n delta^alpha (seed 003: Tsuji 1/4, Kuwabara-Kono 1/2).
    PowerDamped { alpha: f64 },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CohesionKind {
    None,
    Sjkr,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RollingKind {
    None,
    Epsd2,
}

/// The effects switched on for a scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactModel {
    pub normal: NormalKind,
    pub cohesion: CohesionKind,
    pub rolling: RollingKind,
    /// See [`Law::limit_force`]. Off by default, as in LIGGGHTS.
    pub limit_force: bool,
    /// See [`Law::strict_coulomb`]. Off by default, as in LIGGGHTS.
    pub strict_coulomb: bool,
}

impl Default for ContactModel {
    /// Seed 004's model: Hertz-Mindlin with EPSD2 rolling friction, no cohesion.
    fn default() -> Self {
        ContactModel {
            normal: NormalKind::Hertz,
            cohesion: CohesionKind::None,
            rolling: RollingKind::Epsd2,
            limit_force: false,
            strict_coulomb: false,
        }
    }
}

/// Names accepted by [`ContactModel::from_names`].
pub const EFFECT_NAMES: &[&str] = &[
    "hertz",
    "tsuji",
    "kuwabara-kono",
    "power-damped:<alpha>",
    "epsd2",
    "sjkr",
    "limit-force",
    "strict-coulomb",
];

impl ContactModel {
    /// Builds a model from effect names, e.g. `["hertz", "epsd2"]` or `["power-damped:0.4"]`.
    /// The tangential history spring is always on.
    pub fn from_names<S: AsRef<str>>(names: &[S]) -> Result<Self> {
        let mut normal = None;
        let mut cohesion = CohesionKind::None;
        let mut rolling = RollingKind::None;
        let mut limit_force = false;
        let mut strict_coulomb = false;
        let mut set_normal = |k: NormalKind, name: &str| {
            if normal.replace(k).is_some() {
                return Err(Error::invalid(format!(
                    "contact model: `{name}` is a second normal force; choose one"
                )));
            }
            Ok(())
        };
        for name in names {
            let name = name.as_ref().trim();
            match name {
                "hertz" => set_normal(NormalKind::Hertz, name)?,
                "tsuji" => set_normal(NormalKind::PowerDamped { alpha: 0.25 }, name)?,
                "kuwabara-kono" => set_normal(NormalKind::PowerDamped { alpha: 0.5 }, name)?,
                "epsd2" => rolling = RollingKind::Epsd2,
                "sjkr" => cohesion = CohesionKind::Sjkr,
                "limit-force" => limit_force = true,
                "strict-coulomb" => strict_coulomb = true,
                other => {
                    let alpha = other
                        .strip_prefix("power-damped:")
                        .and_then(|a| a.parse::<f64>().ok())
                        .filter(|a| a.is_finite() && *a >= 0.0);
                    match alpha {
                        Some(alpha) => set_normal(NormalKind::PowerDamped { alpha }, name)?,
                        None => {
                            return Err(Error::invalid(format!(
                                "contact model: unknown effect `{other}`; expected one of {}",
                                EFFECT_NAMES.join(", ")
                            )))
                        }
                    }
                }
            }
        }
        Ok(ContactModel {
            normal: normal.unwrap_or(NormalKind::Hertz),
            cohesion,
            rolling,
            limit_force,
            strict_coulomb,
        })
    }
}

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
    use crate::dem::material::{Interaction, Material};

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
