//! Calibration experiments: scenes that measure what a laboratory measures.
//!
//! An [`Experiment`] takes a [`ParamSet`] (the parameter names of `examples/space_seed004.toml`,
//! E_p, E_w, nu_p, e_pp, e_pw, mu_pp, mu_pw, mu_r_pp, mu_r_pw, rho_p, d50 (mm), sigma_ln, plus
//! experiment settings and effect parameters), builds its scene, runs it to a stop criterion and
//! returns named responses with diagnostics. [`Experiment::check`] refuses an impossible set before
//! anything runs.

pub mod hopper;
pub mod shear_box;
pub mod wall_impact;

use std::path::PathBuf;

use super::material::{Interaction, Material, Materials};
use crate::error::{Error, Result};

/// Named parameter values, in insertion order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParamSet {
    values: Vec<(String, f64)>,
}

impl ParamSet {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn from_pairs<S: AsRef<str>>(pairs: &[(S, f64)]) -> Self {
        let mut p = ParamSet::new();
        for (k, v) in pairs {
            p.set(k.as_ref(), *v);
        }
        p
    }

    /// Sets (or replaces) a value.
    pub fn set(&mut self, name: &str, value: f64) -> &mut Self {
        match self.values.iter_mut().find(|(k, _)| k == name) {
            Some(e) => e.1 = value,
            None => self.values.push((name.to_string(), value)),
        }
        self
    }

    pub fn get(&self, name: &str) -> Option<f64> {
        self.values.iter().find(|(k, _)| k == name).map(|(_, v)| *v)
    }

    pub fn iter(&self) -> impl Iterator<Item = (&str, f64)> {
        self.values.iter().map(|(k, v)| (k.as_str(), *v))
    }

    /// The value of a parameter that must lie in `[lo, hi]`; the error names the parameter.
    pub fn require(&self, name: &str, lo: f64, hi: f64) -> Result<f64> {
        let v = self.get(name).ok_or_else(|| {
            Error::invalid(format!(
                "parameter {name}: missing (expected a value in [{lo}, {hi}])"
            ))
        })?;
        if !(v.is_finite() && v >= lo && v <= hi) {
            return Err(Error::invalid(format!(
                "parameter {name} = {v}: expected a finite value in [{lo}, {hi}]"
            )));
        }
        Ok(v)
    }

    /// An optional value with a default, checked like [`ParamSet::require`].
    pub fn optional(&self, name: &str, default: f64, lo: f64, hi: f64) -> Result<f64> {
        match self.get(name) {
            None => Ok(default),
            Some(_) => self.require(name, lo, hi),
        }
    }
}

/// The parameters of seed 004's space (`examples/space_seed004.toml`) that the bulk experiments need.
pub const SEED004_PARAMETERS: [&str; 12] = [
    "E_p", "E_w", "nu_p", "e_pp", "e_pw", "mu_pp", "mu_pw", "mu_r_pp", "mu_r_pw", "rho_p", "d50",
    "sigma_ln",
];

/// Physically allowed ranges of the seed-004 parameters (wider than the metamodel's space: an
/// experiment refuses only what cannot be simulated).
pub const E_RANGE: (f64, f64) = (1e3, 1e13);
pub const NU_RANGE: (f64, f64) = (-0.99, 0.5);
pub const E_REST_RANGE: (f64, f64) = (0.05, 1.0);
pub const MU_RANGE: (f64, f64) = (0.0, 10.0);
pub const RHO_RANGE: (f64, f64) = (1.0, 1e5);

/// Particle and wall materials and their interactions from E_p, E_w, nu_p (walls share the
/// particles' Poisson ratio, as in seed 004), e_pp, e_pw, mu_pp, mu_pw, mu_r_pp, mu_r_pw, and
/// optionally `ced_pp`/`ced_pw` (cohesion energy density, J/m^3). Returns (materials, particle
/// material, wall material).
/// The optional parameters [`materials_from`] reads.
pub const MATERIAL_OPTIONAL: [&str; 2] = ["ced_pp", "ced_pw"];

pub fn materials_from(p: &ParamSet) -> Result<(Materials, u16, u16)> {
    let nu = p.require("nu_p", NU_RANGE.0, NU_RANGE.1)?;
    let mut m = Materials::new();
    let grain = m.add(Material {
        name: "particle".into(),
        youngs_modulus: p.require("E_p", E_RANGE.0, E_RANGE.1)?,
        poisson: nu,
    })?;
    let wall = m.add(Material {
        name: "wall".into(),
        youngs_modulus: p.require("E_w", E_RANGE.0, E_RANGE.1)?,
        poisson: nu,
    })?;
    let pp = Interaction {
        restitution: p.require("e_pp", E_REST_RANGE.0, E_REST_RANGE.1)?,
        friction: p.require("mu_pp", MU_RANGE.0, MU_RANGE.1)?,
        rolling_friction: p.require("mu_r_pp", MU_RANGE.0, MU_RANGE.1)?,
        cohesion_energy_density: p.optional("ced_pp", 0.0, 0.0, 1e9)?,
        damping_gamma_n: 0.0,
        tangential_stiffness: 0.0,
    };
    let pw = Interaction {
        restitution: p.require("e_pw", E_REST_RANGE.0, E_REST_RANGE.1)?,
        friction: p.require("mu_pw", MU_RANGE.0, MU_RANGE.1)?,
        rolling_friction: p.require("mu_r_pw", MU_RANGE.0, MU_RANGE.1)?,
        cohesion_energy_density: p.optional("ced_pw", 0.0, 0.0, 1e9)?,
        damping_gamma_n: 0.0,
        tangential_stiffness: 0.0,
    };
    m.set_interaction(grain, grain, pp)?;
    m.set_interaction(grain, wall, pw.clone())?;
    m.set_interaction(wall, wall, pw)?;
    Ok((m, grain, wall))
}

/// What a run reports besides its responses.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Diagnostics {
    /// Whether the stop criterion (rest, end of flow) was reached rather than a step limit.
    pub settled: bool,
    pub steps: u64,
    pub particles: usize,
    pub wall_time_s: f64,
    pub warnings: Vec<String>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Named responses, in [`Experiment::responses`] order.
    pub responses: Vec<(String, f64)>,
    pub diagnostics: Diagnostics,
}

impl Outcome {
    pub fn get(&self, name: &str) -> Option<f64> {
        self.responses
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| *v)
    }
}

/// Output requests of a run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Directory for VTK snapshots, if wanted.
    pub vtk_dir: Option<PathBuf>,
    /// Side-view picture of the final state (SVG or PNG), if wanted.
    pub picture: Option<PathBuf>,
    /// Threads inside one run (campaigns usually run one run per thread instead).
    pub threads: usize,
}

pub trait Experiment: Send + Sync {
    /// Name used on the command line, e.g. `shear-box`.
    fn name(&self) -> &'static str;
    /// Parameters the experiment needs.
    fn parameters(&self) -> Vec<&'static str>;
    /// Parameters it reads when given (with a default otherwise). A constant that is neither a
    /// parameter nor an optional one is refused by campaigns: it would do nothing.
    fn optional_parameters(&self) -> Vec<&'static str> {
        Vec::new()
    }
    /// Response names, in output order.
    fn responses(&self) -> Vec<&'static str>;
    /// Refuses an impossible parameter set before anything runs; the error names the parameter.
    fn check(&self, p: &ParamSet) -> Result<()>;
    /// Runs the experiment. Same parameters and seed give the same outcome.
    fn run(&self, p: &ParamSet, seed: u64, opts: &RunOptions) -> Result<Outcome>;
}
