//! Calibration experiments: scenes that measure what a laboratory measures.
//!
//! An [`Experiment`] takes a [`ParamSet`] (the parameter names of `examples/space_seed004.toml`,
//! E_p, E_w, nu_p, e_pp, e_pw, mu_pp, mu_pw, mu_r_pp, mu_r_pw, rho_p, d50 (mm), sigma_ln, plus
//! experiment settings and effect parameters), builds its scene, runs it to a stop criterion and
//! returns named responses with diagnostics. [`Experiment::check`] refuses an impossible set before
//! anything runs.

pub mod clogging_silo;
pub(crate) mod cylinder_fill;
pub mod hopper;
pub mod shear_box;
pub mod shear_box_rest;
pub mod shear_cell;
pub mod shear_test;
pub mod wall_impact;

use std::path::PathBuf;

use crate::error::Result;
use mbgc_dem::contact::{ModelClass, Pair};
use mbgc_dem::material::{Materials, Solid};
pub use mbgc_dem::param_set::ParamSet;

/// Physically allowed ranges of the material parameters (wider than the metamodel's space: an
/// experiment refuses only what cannot be simulated). The effects' parameters carry their own
/// ranges ([`mbgc_dem::contact::ParamSpec`]).
pub const E_RANGE: (f64, f64) = (1e3, 1e13);
/// Allowed Poisson ratio of particles and walls (dimensionless): the thermodynamic range
/// -1 < nu <= 0.5, cut at -0.99 because the shear modulus E / (2 (1 + nu)) diverges as nu -> -1.
pub const NU_RANGE: (f64, f64) = (-0.99, 0.5);
/// Allowed particle density, kg/m^3.
pub const RHO_RANGE: (f64, f64) = (1.0, 1e5);

/// The parameters of the particles and walls that every bulk experiment needs whatever the
/// model class: E_p, E_w, nu_p (walls share the particles' Poisson ratio, as in seed 004).
pub const MATERIAL_PARAMETERS: [&str; 3] = ["E_p", "E_w", "nu_p"];

/// Particle and wall materials from [`MATERIAL_PARAMETERS`], and their interactions from the
/// parameters of the model class's effects (`e_pp`, `mu_pw`, `ced_pp`, ...). Returns (materials,
/// particle material, wall material).
pub fn materials_from(p: &ParamSet, class: &ModelClass) -> Result<(Materials, u16, u16)> {
    let nu = p.require("nu_p", NU_RANGE.0, NU_RANGE.1)?;
    let mut m = Materials::new();
    let grain = m.add(Solid {
        name: "particle".into(),
        youngs_modulus: p.require("E_p", E_RANGE.0, E_RANGE.1)?,
        poisson: nu,
    })?;
    let wall = m.add(Solid {
        name: "wall".into(),
        youngs_modulus: p.require("E_w", E_RANGE.0, E_RANGE.1)?,
        poisson: nu,
    })?;
    let pp = class.interaction(p, Pair::ParticleParticle)?;
    let pw = class.interaction(p, Pair::ParticleWall)?;
    m.set_interaction(grain, grain, pp)?;
    m.set_interaction(grain, wall, pw.clone())?;
    m.set_interaction(wall, wall, pw)?;
    Ok((m, grain, wall))
}

/// An experiment's parameters: its own (`own`, geometry and particles), then the model class's
/// for the kinds of contact it has.
pub fn with_class_parameters(
    own: &[&'static str],
    class: &ModelClass,
    pairs: &[Pair],
) -> Vec<&'static str> {
    let mut v = own.to_vec();
    for n in class.parameter_names(pairs) {
        if !v.contains(&n) {
            v.push(n);
        }
    }
    v
}

/// What a run reports besides its responses.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Diagnostics {
    /// Whether the stop criterion (rest, end of flow) was reached rather than a step limit.
    pub settled: bool,
    /// DEM time steps taken.
    pub steps: u64,
    /// Particles in the scene at the end of the run.
    pub particles: usize,
    /// Wall-clock duration of the run, s.
    pub wall_time_s: f64,
    /// Non-fatal problems a user should see (e.g. a step limit reached, a response clamped).
    pub warnings: Vec<String>,
}

/// The result of one run: named responses and how the run went.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Named responses, in [`Experiment::responses`] order.
    pub responses: Vec<(String, f64)>,
    /// Convergence and cost of the run.
    pub diagnostics: Diagnostics,
}

impl Outcome {
    /// The response called `name`, if the experiment reports it.
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
    /// Where an external backend keeps this run's deck, log and dumps (kept after the run); it
    /// uses a temporary directory otherwise. mbgc's engine writes no such files, and the
    /// command line refuses the option for it.
    pub work_dir: Option<PathBuf>,
}

/// A calibration experiment: a DEM scene that turns a parameter set into measurable bulk
/// responses, the unit a campaign runs once per design point.
pub trait Experiment: Send + Sync {
    /// Name used on the command line, e.g. `shear-box`.
    fn name(&self) -> &'static str;
    /// The responses a metamodel of it is fitted to by default (`mbgc train`): the measured
    /// ones, not the diagnostics.
    fn calibration_responses(&self) -> Vec<&'static str> {
        self.responses()
    }
    /// The dimensionless groups its inputs act through, if it has such a similarity (the
    /// metamodel is then fitted in them, `crate::similarity`).
    fn similarity(&self) -> Option<crate::similarity::Similarity> {
        None
    }
    /// Parameters the experiment needs.
    fn parameters(&self) -> Vec<&'static str>;
    /// Parameters it reads when given (with a default otherwise). A constant that is neither a
    /// parameter nor an optional one is refused by campaigns: it would do nothing.
    fn optional_parameters(&self) -> Vec<&'static str> {
        Vec::new()
    }
    /// The model class the experiment was built with; `None` for one that has no contact law
    /// (a test stand-in). Its effects' parameters are among [`Experiment::parameters`].
    fn class(&self) -> Option<&ModelClass> {
        None
    }
    /// The kinds of contact the experiment has: the model class's parameters are needed for
    /// these only.
    fn pairs(&self) -> &'static [Pair] {
        &Pair::BOTH
    }
    /// The setting that sizes the apparatus to the material's particles, with its value for the
    /// parameters `p`, when the experiment has one: a propagation (`crate::propagate`) carries a
    /// calibrated material into it at the size its own particles call for. `None`: the
    /// experiment's size does not follow the particles (or is already in particle diameters).
    fn sized_to(&self, _p: &ParamSet) -> Option<(&'static str, f64)> {
        None
    }
    /// Events a finished run can have that leave it without some of its calibration responses
    /// ([`Experiment::voided_by`]; a hopper's clogged orifice: no flow rate, crater or pile), by
    /// name. A propagation (`crate::propagate`)
    /// reports how often each happened over the posterior.
    fn events(&self) -> Vec<&'static str> {
        Vec::new()
    }
    /// The responses a run with `event` (one of [`Experiment::events`]) has no value of (NaN
    /// in the run itself, and voided by readers of older tables). By default the calibration
    /// responses.
    fn voided_by(&self, _event: &str) -> Vec<&'static str> {
        self.calibration_responses()
    }
    /// The value of `response`, which the experiment records since a table was written, for a
    /// run of that table, from what its line holds (`cell` gives a cell by column name, the
    /// `warnings` and `settled` columns included): `None` when the line cannot tell (the cell
    /// then holds NaN). A hopper's late arch, for one, was named in the warnings before it had
    /// a column.
    fn backfill(&self, _response: &str, _cell: &dyn Fn(&str) -> Option<String>) -> Option<f64> {
        None
    }
    /// Which of [`Experiment::events`] a finished run had, from its recorded responses (`value`
    /// gives one by name, `None` when the table lacks it). The run itself already left its
    /// calibration responses NaN; reading the event from what a table records lets a table
    /// written before the experiment did so be read alike.
    fn event_of(&self, _value: &dyn Fn(&str) -> Option<f64>) -> Option<&'static str> {
        None
    }
    /// Response names, in output order.
    fn responses(&self) -> Vec<&'static str>;
    /// Refuses an impossible parameter set before anything runs; the error names the parameter.
    fn check(&self, p: &ParamSet) -> Result<()>;
    /// Runs the experiment. Same parameters and seed give the same outcome.
    fn run(&self, p: &ParamSet, seed: u64, opts: &RunOptions) -> Result<Outcome>;
    /// Writes the input files of one run into `dir` for an external code to run later, when the
    /// experiment runs in one (`mbgc simulate --write-decks`); an experiment of mbgc's own
    /// engine has nothing to write and refuses.
    fn write_deck(&self, _p: &ParamSet, _seed: u64, _dir: &std::path::Path) -> Result<()> {
        Err(crate::error::Error::invalid(format!(
            "{} runs in mbgc's own engine: it has no deck to write (--write-decks needs \
             --backend liggghts)",
            self.name()
        )))
    }
}

/// Writes a VTK snapshot of the particles atomically (the engine only renders the text).
pub(crate) fn write_vtk(
    path: &std::path::Path,
    particles: &mbgc_dem::Particles,
    title: &str,
) -> Result<()> {
    crate::error::write_atomic(path, mbgc_dem::vtk::to_vtk(particles, title).as_bytes())
}
