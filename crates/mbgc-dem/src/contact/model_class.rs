//! A model class: the effects of the contact law switched on for a campaign, named by the user
//! (`--model-class hertz,mindlin,epsd2,sjkr`), and the parameters they need.

use std::fmt;

use super::kinds::{cohesion, normal, rolling, tangential};
use super::spec::{EffectSpec, Pair, ParamSpec, Slot};
use crate::error::{Error, Result};
use crate::material::Interaction;
use crate::param_set::ParamSet;

/// Cohesion: `None`, or `Sjkr` (simplified JKR, an attraction of k_c times the contact area;
/// LIGGGHTS `cohesion sjkr`).
pub use cohesion::Kind as CohesionKind;
/// Normal force: `Hertz` (restitution-based dashpot, LIGGGHTS `model hertz`), or Hertz elasticity
/// with a power-law dashpot gamma_n d^alpha: `Tsuji` (alpha 1/4), `KuwabaraKono` (1/2),
/// `PowerDamped` (free alpha).
pub use normal::Kind as NormalKind;
/// Rolling resistance: `None`, `Epsd2` (elastic-plastic spring, LIGGGHTS `rolling_friction
/// epsd2`) or `Cdt` (constant directional torque, `rolling_friction cdt`).
pub use rolling::Kind as RollingKind;
/// Tangential force: the history spring with Coulomb cap as `Mindlin` (LIGGGHTS `tangential
/// history`), `StrictCoulomb` (spring plus dashpot capped) or `LinearSpring` (constant k_t).
pub use tangential::Kind as TangentialKind;

/// The name of the `limitForce` option of the normal force (not an effect: it has no slot and no
/// parameter).
pub const LIMIT_FORCE: &str = "limit-force";

/// The effects switched on, one per slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ModelClass {
    /// The normal force (always present).
    pub normal: NormalKind,
    /// The tangential force (always present).
    pub tangential: TangentialKind,
    /// The rolling resistance, `RollingKind::None` for none.
    pub rolling: RollingKind,
    /// The cohesion, `CohesionKind::None` for none.
    pub cohesion: CohesionKind,
    /// Keep the normal force from turning attractive near separation (LIGGGHTS
    /// `limitForce on`), with the damping re-solved so that e stays the restitution. Hertz only.
    pub limit_force: bool,
}

impl Default for ModelClass {
    /// Seed 004's class: Hertz-Mindlin with EPSD2 rolling resistance, no cohesion.
    fn default() -> Self {
        ModelClass {
            normal: NormalKind::Hertz,
            tangential: TangentialKind::Mindlin,
            rolling: RollingKind::Epsd2,
            cohesion: CohesionKind::None,
            limit_force: false,
        }
    }
}

/// Every registered effect (the empty slots `no-rolling`, `no-cohesion` included), slot by slot
/// in registry order.
pub fn all_effects() -> Vec<&'static EffectSpec> {
    let mut v: Vec<&'static EffectSpec> = Vec::new();
    v.extend(NormalKind::ALL.iter().map(|k| k.spec()));
    v.extend(TangentialKind::ALL.iter().map(|k| k.spec()));
    v.extend(RollingKind::ALL.iter().map(|k| k.spec()));
    v.extend(CohesionKind::ALL.iter().map(|k| k.spec()));
    v
}

/// The effect names accepted in a model class, for messages.
pub fn effect_names() -> Vec<&'static str> {
    let mut v: Vec<&'static str> = all_effects().iter().map(|s| s.name).collect();
    v.push(LIMIT_FORCE);
    v
}

fn names_of(slot: Slot) -> String {
    all_effects()
        .iter()
        .filter(|s| s.slot == slot)
        .map(|s| s.name)
        .collect::<Vec<_>>()
        .join(", ")
}

impl ModelClass {
    /// Parses `hertz,mindlin,epsd2,sjkr` (commas or `+` between names). The normal and the
    /// tangential force must be named; rolling resistance and cohesion are off unless named.
    ///
    /// ```
    /// use mbgc_dem::contact::{CohesionKind, ModelClass, RollingKind};
    /// // Seed 004's class is the default; `+` and `,` separate alike.
    /// let class = ModelClass::parse("hertz+mindlin+epsd2")?;
    /// assert_eq!(class, ModelClass::default());
    /// assert_eq!(class.label(), "hertz+mindlin+epsd2");
    /// // A cohesive class without rolling resistance, and the parameters its contacts need.
    /// let wet = ModelClass::parse("hertz,mindlin,sjkr")?;
    /// assert_eq!((wet.rolling, wet.cohesion), (RollingKind::None, CohesionKind::Sjkr));
    /// assert_eq!(
    ///     wet.parameter_names(&mbgc_dem::contact::Pair::BOTH),
    ///     ["e_pp", "e_pw", "mu_pp", "mu_pw", "ced_pp", "ced_pw"]
    /// );
    /// // Two effects for one slot are refused.
    /// assert!(ModelClass::parse("hertz,tsuji,mindlin").is_err());
    /// # Ok::<(), mbgc_dem::Error>(())
    /// ```
    pub fn parse(text: &str) -> Result<ModelClass> {
        let names: Vec<&str> = text.split([',', '+']).map(str::trim).collect();
        Self::from_names(&names)
    }

    /// As [`ModelClass::parse`], from names already split; refuses unknown names, two effects
    /// for one slot, a missing normal or tangential force, and `limit-force` without Hertz.
    pub fn from_names<S: AsRef<str>>(names: &[S]) -> Result<ModelClass> {
        let joined = names
            .iter()
            .map(|s| s.as_ref().trim())
            .collect::<Vec<_>>()
            .join(",");
        let bad = |why: String| Error::invalid(format!("model class \"{joined}\": {why}"));
        let mut normal = None;
        let mut tangential = None;
        let mut rolling = None;
        let mut cohesion = None;
        let mut limit_force = false;
        fn take<K: Copy>(
            slot: &mut Option<(K, &'static str)>,
            kind: K,
            name: &'static str,
            label: &str,
        ) -> std::result::Result<(), String> {
            match slot.replace((kind, name)) {
                Some((_, first)) => Err(format!(
                    "`{name}` and `{first}` are both a {label}; choose one"
                )),
                None => Ok(()),
            }
        }
        for name in names {
            let name = name.as_ref().trim();
            if name.is_empty() {
                return Err(bad("an empty name (two separators in a row?)".into()));
            }
            if name == LIMIT_FORCE {
                if limit_force {
                    return Err(bad(format!("`{LIMIT_FORCE}` is named twice")));
                }
                limit_force = true;
                continue;
            }
            let label = |s: Slot| s.label();
            let r = if let Some(k) = NormalKind::ALL.iter().find(|k| k.spec().name == name) {
                take(&mut normal, *k, k.spec().name, label(Slot::Normal))
            } else if let Some(k) = TangentialKind::ALL.iter().find(|k| k.spec().name == name) {
                take(&mut tangential, *k, k.spec().name, label(Slot::Tangential))
            } else if let Some(k) = RollingKind::ALL.iter().find(|k| k.spec().name == name) {
                take(&mut rolling, *k, k.spec().name, label(Slot::Rolling))
            } else if let Some(k) = CohesionKind::ALL.iter().find(|k| k.spec().name == name) {
                take(&mut cohesion, *k, k.spec().name, label(Slot::Cohesion))
            } else {
                Err(format!(
                    "unknown effect `{name}`; expected names from {} (leaving a slot out \
                     switches it off)",
                    effect_names().join(", ")
                ))
            };
            r.map_err(bad)?;
        }
        let normal = normal.ok_or_else(|| {
            bad(format!(
                "no normal force; name one of {}",
                names_of(Slot::Normal)
            ))
        })?;
        let tangential = tangential.ok_or_else(|| {
            bad(format!(
                "no tangential force; name one of {}",
                names_of(Slot::Tangential)
            ))
        })?;
        if limit_force && normal.0 != NormalKind::Hertz {
            return Err(bad(format!(
                "`{LIMIT_FORCE}` re-solves Hertz's restitution damping; `{}` has none",
                normal.1
            )));
        }
        Ok(ModelClass {
            normal: normal.0,
            tangential: tangential.0,
            rolling: rolling.map_or(RollingKind::None, |r| r.0),
            cohesion: cohesion.map_or(CohesionKind::None, |c| c.0),
            limit_force,
        })
    }

    /// The effects switched on, slot by slot (empty slots left out).
    pub fn effects(&self) -> Vec<&'static EffectSpec> {
        [
            self.normal.spec(),
            self.tangential.spec(),
            self.rolling.spec(),
            self.cohesion.spec(),
        ]
        .into_iter()
        .filter(|s| !s.is_none())
        .collect()
    }

    /// The names joined with `+`, for a CSV field (no quoting needed).
    pub fn label(&self) -> String {
        self.names().join("+")
    }

    fn names(&self) -> Vec<&'static str> {
        let mut v: Vec<&'static str> = self.effects().iter().map(|s| s.name).collect();
        if self.limit_force {
            v.push(LIMIT_FORCE);
        }
        v
    }

    /// The parameters the class needs for contacts of `pairs`, in slot order, each with its
    /// spec and the effect it belongs to.
    pub fn parameters(
        &self,
        pairs: &[Pair],
    ) -> Vec<(&'static str, &'static ParamSpec, &'static EffectSpec)> {
        let mut v: Vec<(&'static str, &'static ParamSpec, &'static EffectSpec)> = Vec::new();
        for e in self.effects() {
            for p in e.params {
                for &pair in pairs {
                    let name = p.name(pair);
                    if !v.iter().any(|(n, _, _)| *n == name) {
                        v.push((name, p, e));
                    }
                }
            }
        }
        v
    }

    /// The names of [`ModelClass::parameters`] alone (`e_pp`, `mu_pw`, ...).
    pub fn parameter_names(&self, pairs: &[Pair]) -> Vec<&'static str> {
        self.parameters(pairs)
            .into_iter()
            .map(|(n, _, _)| n)
            .collect()
    }

    /// Refuses a parameter that belongs to an effect of another class, or to a kind of contact
    /// the experiment does not have, naming the effect and how to switch it on. Names no
    /// effect owns are left to the caller.
    pub fn refuse_inactive(&self, name: &str, pairs: &[Pair], experiment: &str) -> Result<()> {
        if self.parameter_names(pairs).contains(&name) {
            return Ok(());
        }
        let owners: Vec<&'static EffectSpec> = all_effects()
            .into_iter()
            .filter(|e| e.params.iter().any(|p| p.names.contains(&name)))
            .collect();
        let Some(first) = owners.first() else {
            return Ok(());
        };
        // A parameter of a kind of contact the experiment lacks does nothing in any class.
        let pair = Pair::BOTH
            .into_iter()
            .find(|p| first.params.iter().any(|s| s.name(*p) == name))
            .unwrap_or(Pair::ParticleParticle);
        if !pairs.contains(&pair) {
            return Err(Error::invalid(format!(
                "parameter {name}: {experiment} has no {} contacts, so {name} would do nothing; \
                 remove it",
                pair.label()
            )));
        }
        let which = owners
            .iter()
            .map(|o| format!("'{}'", o.name))
            .collect::<Vec<_>>()
            .join(" or ");
        let mut with = self.names();
        // The suggestion replaces the class's effect in that slot, or adds one.
        let slot_effect = self
            .effects()
            .into_iter()
            .find(|e| e.slot == first.slot)
            .map(|e| e.name);
        match slot_effect {
            Some(old) => {
                for n in with.iter_mut() {
                    if *n == old {
                        *n = first.name;
                    }
                }
            }
            None => with.push(first.name),
        }
        Err(Error::invalid(format!(
            "parameter {name}: belongs to {} {which}, which the model class {self} does not \
             use, so it would do nothing; switch the effect on in the model class ({}), or \
             remove {name}",
            first.slot.label(),
            with.join(",")
        )))
    }

    /// The interaction of one kind of contact from the parameter values. A parameter the class
    /// needs and `p` lacks is an error naming it and its effect.
    pub fn interaction(&self, p: &ParamSet, pair: Pair) -> Result<Interaction> {
        // No restitution-based damping unless an effect sets a restitution (Hertz): with a
        // power-law dashpot, Mindlin's dashpot would otherwise damp with a value nobody chose.
        let mut i = Interaction {
            restitution: 1.0,
            ..Interaction::default()
        };
        for e in self.effects() {
            let mut values = Vec::with_capacity(e.params.len());
            for s in e.params {
                let name = s.name(pair);
                let (lo, hi) = s.range;
                let v = match (p.get(name), s.default) {
                    (Some(v), _) => v,
                    (None, Some(d)) => d,
                    (None, None) => {
                        return Err(Error::invalid(format!(
                            "parameter {name}: missing; {} '{}' of the model class {self} needs \
                             it ({}, {}, in [{lo}, {hi}])",
                            e.slot.label(),
                            e.name,
                            s.what,
                            s.unit
                        )))
                    }
                };
                if !(v.is_finite() && v >= lo && v <= hi) {
                    return Err(Error::invalid(format!(
                        "parameter {name} = {v}: expected a finite value in [{lo}, {hi}] {} ({} of \
                         {} '{}')",
                        s.unit,
                        s.what,
                        e.slot.label(),
                        e.name
                    )));
                }
                values.push(v);
            }
            (e.install)(&values, &mut i);
        }
        Ok(i)
    }

    /// Effects of `self` that `other` lacks (to refuse data of a richer class).
    pub fn missing_from(&self, other: &ModelClass) -> Vec<&'static str> {
        let theirs = other.names();
        self.names()
            .into_iter()
            .filter(|n| !theirs.contains(n))
            .collect()
    }
}

impl fmt::Display for ModelClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.names().join(","))
    }
}

impl std::str::FromStr for ModelClass {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        ModelClass::parse(s)
    }
}
