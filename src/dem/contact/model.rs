//! The choice of effects for a scene, by name.

use crate::error::{Error, Result};

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
    /// See [`Law::limit_force`](super::law::Law::limit_force). Off by default, as in LIGGGHTS.
    pub limit_force: bool,
    /// See [`Law::strict_coulomb`](super::law::Law::strict_coulomb). Off by default, as in LIGGGHTS.
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
