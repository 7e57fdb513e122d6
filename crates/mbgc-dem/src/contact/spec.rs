//! What the user-facing side knows of an effect: its name, the slot of the contact law it fills,
//! its parameters (names, unit, allowed range, default, whether a metamodel may vary it) and how
//! their values reach the per-pair constants of the kernel.

use crate::material::Interaction;

/// The parts of the contact law; a model class holds one effect per slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slot {
    /// The normal force along the line of centres: elasticity and damping (always filled).
    Normal,
    /// The tangential force in the contact plane: history spring, dashpot and Coulomb cap
    /// (always filled).
    Tangential,
    /// A torque resisting the relative rolling of the bodies (optional).
    Rolling,
    /// An attraction between touching bodies (optional).
    Cohesion,
}

impl Slot {
    /// Every slot, in the order the contact law evaluates them and messages list them.
    pub const ALL: [Slot; 4] = [
        Slot::Normal,
        Slot::Tangential,
        Slot::Rolling,
        Slot::Cohesion,
    ];

    /// Its name in messages (`normal force`, `rolling resistance`).
    pub fn label(self) -> &'static str {
        match self {
            Slot::Normal => "normal force",
            Slot::Tangential => "tangential force",
            Slot::Rolling => "rolling resistance",
            Slot::Cohesion => "cohesion",
        }
    }
}

/// The two kinds of contact of a bulk experiment. Every effect applies to both; its parameters
/// are given for each (`mu_pp` and `mu_pw`), so an effect can be strong between particles and
/// weak against the walls, or absent there with a zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pair {
    /// Contacts between two particles (parameter names ending in `_pp`).
    ParticleParticle,
    /// Contacts between a particle and a wall (parameter names ending in `_pw`).
    ParticleWall,
}

impl Pair {
    /// Both kinds of contact, in the order of [`ParamSpec::names`].
    pub const BOTH: [Pair; 2] = [Pair::ParticleParticle, Pair::ParticleWall];

    /// Position in [`ParamSpec::names`]: 0 particle-particle, 1 particle-wall.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Its name in messages (`particle-wall`).
    pub fn label(self) -> &'static str {
        match self {
            Pair::ParticleParticle => "particle-particle",
            Pair::ParticleWall => "particle-wall",
        }
    }
}

/// One parameter of an effect.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// Its names for particle-particle and particle-wall contacts.
    pub names: [&'static str; 2],
    /// SI unit as printed in messages and tables (`-` for dimensionless, `J/m^3`).
    pub unit: &'static str,
    /// Values a run accepts (wider than any metamodel's space: only what cannot be simulated
    /// or means nothing is refused).
    pub range: (f64, f64),
    /// Used when the parameter is not given; `None`: a missing value is an error.
    pub default: Option<f64>,
    /// Whether a metamodel may take it as an input; a structural constant (an exponent that
    /// selects a model) is fixed in a space instead.
    pub variable: bool,
    /// The value at which the effect does nothing (a run of a class with it repeats the class
    /// without it: a rolling friction or a cohesion of 0). `None`: the effect cannot be switched
    /// off by a value (the normal force). A metamodel of a class with the effect then also
    /// describes the class without it, on this face of its space (`mbgc diagnose`).
    pub off: Option<f64>,
    /// What it means physically, for messages and listings.
    pub what: &'static str,
}

impl ParamSpec {
    /// Its name for contacts of kind `pair` (`mu_pw`).
    pub fn name(&self, pair: Pair) -> &'static str {
        self.names[pair.index()]
    }
}

/// An effect of the contact law, as a model class names it.
#[derive(Debug, Clone, Copy)]
pub struct EffectSpec {
    /// The name used in `--model-class` and `[model]` (`no-rolling`, `no-cohesion` for a slot
    /// left empty).
    pub name: &'static str,
    /// The part of the contact law it fills.
    pub slot: Slot,
    /// One-line description of the physics, for listings and messages.
    pub what: &'static str,
    /// Its parameters, in the order [`EffectSpec::install`] takes their values.
    pub params: &'static [ParamSpec],
    /// Writes the parameter values, in `params` order, into a pair's interaction.
    pub install: fn(&[f64], &mut Interaction),
    /// The LIGGGHTS 3.8 `pair_style granular` words of the effect, if LIGGGHTS has it.
    pub liggghts: Option<&'static str>,
}

impl EffectSpec {
    /// Whether the spec is an empty slot (`no-rolling`, `no-cohesion`).
    pub fn is_none(&self) -> bool {
        self.params.is_empty() && self.name.starts_with("no-")
    }
}

/// The spec of an empty slot, named `name` (`no-rolling`): naming it is the same as leaving the
/// slot out.
pub const fn none(slot: Slot, name: &'static str) -> EffectSpec {
    EffectSpec {
        name,
        slot,
        what: "switched off (the same as leaving the slot out)",
        params: &[],
        install: |_, _| {},
        liggghts: Some("off"),
    }
}
