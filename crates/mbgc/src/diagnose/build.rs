//! The models a diagnosis lacks, built around the material (`mbgc diagnose --build`).
//!
//! A candidate effect that no given model covers for this material cannot be evaluated. Instead
//! of a global campaign, a local model is enough: the set's known parameters stay fixed, the
//! searched ones and the effect's strength vary over their search ranges, and the sample sizes
//! (or any other value known per sample) over the samples' span. It is trained with
//! [`crate::train::train`] into a directory of its own, so a second call resumes it and a larger
//! budget extends its design instead of starting again. Its own error is compared with the
//! measurement sd: a first half of the budget builds a model over the whole search range, and
//! the second half is run only if that model is less precise than the measurements, in the box
//! where the set's fits with it lie (more runs near the material, not a longer equation).

use std::path::PathBuf;

use super::diagnosis::{limited_by_models, Diagnosis, Parameter};
use super::joint::{with_effect, Joint};
use super::measurements::{owns, switchable_effects, MeasurementSet};
use super::surrogate::Surrogate;
use crate::campaign::{experiment_by_name, ExperimentSettings};
use crate::error::{write_atomic, Error, Result};
use crate::metamodel::noise::replicate_noise_scaled;
use crate::metamodel::Metamodel;
use crate::train::{train, TrainObserver, TrainOutcome, TrainPaths, TrainRequest, TrainStage};
use mbgc_dem::contact::{EffectSpec, ModelClass, Pair};
use mbgc_sr as gp;

/// A local model to build: which class and experiment, under which name, over which space.
#[derive(Clone, Debug)]
pub struct LocalPlan {
    /// The candidate effect it adds to the set's class (`None`: the set's own class).
    pub effect: Option<&'static EffectSpec>,
    /// Its model class.
    pub class: ModelClass,
    /// The experiment of the samples it serves.
    pub experiment: String,
    /// Name of its designs, tables and model file.
    pub name: String,
    /// The text of its space file.
    pub space: String,
    /// The parameters it varies, with their ranges.
    pub varied: Vec<(String, [f64; 2])>,
    /// The responses it is fitted to, each with the median measurement sd of its samples: the
    /// precision the model's own error is compared with.
    pub responses: Vec<(String, f64)>,
    /// Why no given model served (the diagnosis's reason).
    pub reason: String,
    /// For an effect's model: the model of the set's class it extends (name, space text). Its
    /// runs lie on the face where the effect is off, so the effect model describes the set's
    /// class there exactly, not by extrapolating to a face its design only comes near.
    pub base: Option<(String, String)>,
}

/// How local models are built: the budget, where, and the fit's settings.
#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// DEM runs per local model, the validation runs included.
    pub budget_runs: usize,
    /// Directory that receives `spaces/`, `sampling/`, `training_data/` and `models/`.
    pub dir: PathBuf,
    /// Worker threads of the campaigns.
    pub threads: usize,
    /// Seed of the designs, the runs and the fit.
    pub seed: u64,
    /// The genetic-programming settings of the fits.
    pub config: gp::Config,
}

/// Fewest runs per local model: a validation set of 3, 2 replicates and ten training runs, the
/// least the five-fold cross-validation that picks the equation accepts.
pub const MIN_BUDGET: usize = 15;

impl BuildOptions {
    /// `budget_runs` runs per model into `dir`; one thread, seed 1, and GP settings for a few
    /// dozen rows in a handful of inputs (smaller and shorter than a global model's).
    pub fn new(budget_runs: usize, dir: PathBuf) -> BuildOptions {
        BuildOptions {
            budget_runs,
            dir,
            threads: 1,
            seed: 1,
            config: gp::Config {
                population: 2000,
                generations: 60,
                max_length: 32,
                parsimony: 1e-3,
                restarts: 2,
                ..gp::Config::default()
            },
        }
    }

    /// Validation runs of the first round's model: a fifth of its budget, at least 3.
    pub fn validation(&self) -> usize {
        split(rounds(self.budget_runs).0, false).3
    }
}

/// Refuses a budget too small to validate and fit a model, or larger than a train's design may
/// be.
pub fn check_budget(budget: usize) -> Result<()> {
    if budget < MIN_BUDGET {
        return Err(Error::invalid(format!(
            "--budget-runs {budget}: expected at least {MIN_BUDGET} runs per local model (3 to \
             validate it, 2 replicates of those for the DEM noise, 10 for the cross-validation \
             that picks its equation)"
        )));
    }
    if budget > crate::train::MAX_RUNS {
        return Err(Error::invalid(format!(
            "--budget-runs {budget}: expected at most {} runs per local model (each a DEM run)",
            crate::train::MAX_RUNS
        )));
    }
    Ok(())
}

/// A local model built (or resumed) and fitted.
#[derive(Clone, Debug)]
pub struct Built {
    /// What was built.
    pub plan: LocalPlan,
    /// The model file.
    pub path: PathBuf,
    /// The model.
    pub model: Metamodel,
    /// Training runs it was fitted on.
    pub training_runs: usize,
    /// Per response: its own error against the measurement sd.
    pub precision: Vec<Precision>,
    /// After a second round: the first round's model over the whole search range, which this
    /// one (over a narrower box) replaces.
    pub first: Option<Box<Built>>,
    /// After a second round: the search ranges it was built for, which the diagnosis with it
    /// keeps to ([`narrow`]).
    pub focus: Vec<(String, [f64; 2])>,
}

impl Built {
    /// Whether its own error stays below the measurement sd for every response.
    pub fn precise_enough(&self) -> bool {
        self.precision
            .iter()
            .all(|p| p.model_error() <= p.measurement_sd)
    }
}

/// A local model's error in one response, and the precision it is compared with.
#[derive(Clone, Debug)]
pub struct Precision {
    /// Response name.
    pub response: String,
    /// Validation RMSE: the model's own error and one run's DEM noise together.
    pub validation_rmse: f64,
    /// One run's DEM noise, from the replicate pairs, at its 95 % lower confidence bound
    /// ([`crate::metamodel::noise::lower_bound`]; `None`: no pair measured the response).
    pub replicate_sd: Option<f64>,
    /// Median measurement sd of the set's samples.
    pub measurement_sd: f64,
}

impl Precision {
    /// The model's own error: the validation RMSE less the replicate noise it holds (the whole
    /// RMSE when the noise is unknown).
    pub fn model_error(&self) -> f64 {
        match self.replicate_sd {
            Some(n) => (self.validation_rmse.powi(2) - n * n).max(0.0).sqrt(),
            None => self.validation_rmse,
        }
    }
}

/// The local models that `set` needs and `models` lack: one per candidate effect (of those in
/// `wanted`, or all when it is empty) and experiment that no model covers. The set's own class
/// gets one only if no effect model is planned for that experiment: an effect model describes
/// the set's class too, on the face where the effect is off.
pub fn plan(
    set: &MeasurementSet,
    models: &[Surrogate],
    wanted: &[String],
) -> Result<Vec<LocalPlan>> {
    let effects = candidate_effects(set);
    for w in wanted {
        if !effects.iter().any(|e| e.name == w) {
            return Err(Error::invalid(format!(
                "--build {w}: not a candidate effect of the set's class {} (candidates: {})",
                set.class,
                effects
                    .iter()
                    .map(|e| e.name)
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
    }
    let experiments = experiments_of(set);
    let mut plans = Vec::new();
    for exp in experiments {
        let sub = only_experiment(set, exp);
        let mut planned_effect = false;
        for &e in &effects {
            if !wanted.is_empty() && !wanted.iter().any(|w| w == e.name) {
                continue;
            }
            if !has_free_parameter(&sub, e) {
                continue;
            }
            if let Some(reason) = lacks(&sub, models, Some(e)) {
                plans.push(local_plan(&sub, models, exp, Some(e), reason)?);
                planned_effect = true;
            }
        }
        if !planned_effect {
            if let Some(reason) = lacks(&sub, models, None) {
                plans.push(local_plan(&sub, models, exp, None, reason)?);
            }
        }
    }
    Ok(plans)
}

/// Local models for a set the given models cover, but less precisely than its measurements
/// (`d`, its diagnosis with them, says so per experiment:
/// [`super::diagnosis::limited_by_models`]): for each experiment of the set where they limit
/// it, a model of each effect in `wanted`, or of the best-ranked candidate when `wanted` is
/// empty (an effect with every parameter fixed has nothing to fit and is skipped). An effect
/// model also describes the set's class (with the effect off), so the diagnosis then weighs
/// both classes on models of one precision; the given models it stands for give way to it
/// ([`replaced_by`]). Empty when the models limit no experiment.
pub fn plan_sharper(
    set: &MeasurementSet,
    models: &[Surrogate],
    wanted: &[String],
    d: &Diagnosis,
) -> Result<Vec<LocalPlan>> {
    let effects = candidate_effects(set);
    let names: Vec<String> = if wanted.is_empty() {
        d.ranking
            .first()
            .map(|r| r.effect.clone())
            .into_iter()
            .collect()
    } else {
        wanted.to_vec()
    };
    let mut plans = Vec::new();
    let experiments = experiments_of(set);
    for exp in experiments {
        let Some(limit) = limited_by_models(d, set, Some(exp)) else {
            continue;
        };
        let sub = only_experiment(set, exp);
        for name in &names {
            let Some(&e) = effects.iter().find(|e| e.name == name) else {
                return Err(Error::invalid(format!(
                    "--build {name}: not a candidate effect of the set's class {}",
                    set.class
                )));
            };
            if !has_free_parameter(&sub, e) {
                continue;
            }
            plans.push(local_plan(
                &sub,
                models,
                exp,
                Some(e),
                format!(
                    "the given models cover it, but their own error exceeds the measurements' \
                     sd ({limit})"
                ),
            )?);
        }
    }
    Ok(plans)
}

/// Whether a given model gives way to the local model `plan` sharpened ([`plan_sharper`]) for
/// a set of class `set_class`: a model of the same experiment (or of none, which could stand in
/// for any) and of a class the local model stands for, the set's or the plan's. Models of other
/// classes stay for the other candidates.
pub fn replaced_by(model: &Surrogate, plan: &LocalPlan, set_class: &ModelClass) -> bool {
    model
        .experiment
        .as_deref()
        .is_none_or(|e| e == plan.experiment)
        && (model.class == *set_class || model.class == plan.class)
}

/// The candidate effects of a set: its class's switchable ones and those it names.
fn candidate_effects(set: &MeasurementSet) -> Vec<&'static EffectSpec> {
    let mut effects = switchable_effects(&set.class);
    for c in &set.candidates {
        if !effects.iter().any(|e| e.name == c.effect.name) {
            effects.push(c.effect);
        }
    }
    effects
}

/// The experiments of a set's samples, in order of first appearance.
fn experiments_of(set: &MeasurementSet) -> Vec<&str> {
    let mut experiments: Vec<&str> = Vec::new();
    for s in &set.samples {
        if !experiments.contains(&s.experiment.as_str()) {
            experiments.push(&s.experiment);
        }
    }
    experiments
}

/// Whether the set leaves a parameter of `effect` to fit (not every one fixed by its candidate).
fn has_free_parameter(set: &MeasurementSet, effect: &'static EffectSpec) -> bool {
    let settings = set.candidate(effect);
    effect.params.iter().any(|p| {
        Pair::BOTH
            .iter()
            .any(|&pair| !settings.fixed.iter().any(|(n, _)| n == p.name(pair)))
    })
}

/// The set with the samples of one experiment only.
fn only_experiment(set: &MeasurementSet, experiment: &str) -> MeasurementSet {
    let mut sub = set.clone();
    sub.samples.retain(|s| s.experiment == experiment);
    sub
}

/// Why no model covers the class with `effect` for these samples; `None` when one does (or when
/// what fails is not coverage, which the diagnosis itself reports).
fn lacks(
    set: &MeasurementSet,
    models: &[Surrogate],
    effect: Option<&'static EffectSpec>,
) -> Option<String> {
    let settings = effect.map(|e| set.candidate(e));
    match Joint::new(set, models, settings.as_ref()) {
        Ok(_) => None,
        Err(reason) if reason.starts_with("no model describes") => Some(reason),
        Err(_) => None,
    }
}

/// A name that is safe as a file name: lower-case letters, digits and `_`.
fn slug(text: &str) -> String {
    let mut s = String::new();
    for c in text.chars() {
        if c.is_ascii_alphanumeric() {
            s.push(c.to_ascii_lowercase());
        } else if !s.ends_with('_') && !s.is_empty() {
            s.push('_');
        }
    }
    let s: String = s.trim_end_matches('_').chars().take(48).collect();
    if s.is_empty() {
        "set".into()
    } else {
        s.trim_end_matches('_').to_string()
    }
}

/// Units of the experiments' own parameters, for the space file (informative only: similarity
/// reads units from the effects' specs).
fn unit(name: &str, effect_unit: Option<&str>) -> String {
    if let Some(u) = effect_unit {
        return u.to_string();
    }
    match name {
        "E_p" | "E_w" => "Pa",
        "rho_p" => "kg/m3",
        "d50" => "mm",
        "impact_speed" => "m/s",
        "impact_angle" => "deg",
        "spin" => "rad/s",
        _ => "-",
    }
    .to_string()
}

/// Every sample knows the parameter: its values, one per sample.
fn per_sample_values(set: &MeasurementSet, name: &str) -> Result<Option<Vec<f64>>> {
    let mut values = Vec::new();
    for s in &set.samples {
        let from_psd = match (&s.psd, name) {
            (Some(p), "d50" | "sigma_ln") => {
                let (d50, sigma) = p.parameters()?;
                Some(if name == "d50" { d50 } else { sigma })
            }
            _ => None,
        };
        match from_psd.or_else(|| s.fixed.iter().find(|(n, _)| n == name).map(|(_, v)| *v)) {
            Some(v) => values.push(v),
            None if values.is_empty() => {}
            None => {
                return Err(Error::input(
                    &set.source,
                    format!("{}.fixed.{name}", s.field),
                    format!(
                        "{name} for every sample or none: some samples give it, sample \"{}\" \
                         does not, and a local model needs to know whether to vary it",
                        s.name
                    ),
                ))
            }
        }
    }
    if !values.is_empty() && values.len() != set.samples.len() {
        let s = &set.samples[0];
        return Err(Error::input(
            &set.source,
            format!("{}.fixed.{name}", s.field),
            format!("{name} for every sample or none: the first sample does not give it"),
        ));
    }
    Ok((!values.is_empty()).then_some(values))
}

/// A span of known values, padded so that a design of a few dozen points holds every sample
/// inside the range of its runs (a model's domain is the range of its data, not of its space).
fn padded(lo: f64, hi: f64) -> ([f64; 2], bool) {
    if lo > 0.0 && hi / lo >= 2.0 {
        let f = (hi / lo).powf(0.1).max(1.05);
        ([lo / f, hi * f], true)
    } else {
        let pad = 0.1 * (hi - lo);
        let lo2 = if lo > 0.0 {
            (lo - pad).max(0.5 * lo)
        } else {
            lo - pad
        };
        ([lo2, hi + pad], false)
    }
}

fn local_plan(
    set: &MeasurementSet,
    models: &[Surrogate],
    experiment: &str,
    effect: Option<&'static EffectSpec>,
    reason: String,
) -> Result<LocalPlan> {
    let class = match effect {
        Some(e) => with_effect(&set.class, e).map_err(Error::invalid)?,
        None => set.class,
    };
    let settings = ExperimentSettings {
        model_class: Some(class),
        ..Default::default()
    };
    let exp = experiment_by_name(experiment, &settings)?;
    let candidate = effect.map(|e| set.candidate(e));
    let specs = class.parameters(exp.pairs());
    let mut lines = Vec::new();
    let mut varied = Vec::new();
    // An experiment's optional inputs (the shear box's sigma_ln) join the space when the set
    // gives them: left out, the runs would take the experiment's default (monosized spheres)
    // while the samples were measured on their own size distributions.
    let optional = exp.optional_parameters();
    for name in exp.parameters().into_iter().chain(optional.iter().copied()) {
        let spec = specs
            .iter()
            .find(|(n, _, _)| *n == name)
            .map(|(_, s, _)| *s);
        let owned = effect.is_some_and(|e| owns(e, name));
        let fixed = candidate
            .as_ref()
            .filter(|_| owned)
            .and_then(|c| c.fixed.iter().find(|(n, _)| n == name))
            .or_else(|| set.fixed.iter().find(|(n, _)| n == name))
            .map(|(_, v)| *v);
        if optional.contains(&name) && fixed.is_none() && per_sample_values(set, name)?.is_none() {
            continue;
        }
        let what = spec.map_or(String::new(), |s| s.what.to_string());
        let unit = unit(name, spec.map(|s| s.unit));
        let entry = |min: f64, max: f64, log: bool, fixed: Option<f64>| {
            let mut e = format!(
                "{name} = {{ unit = {}, min = {min:?}, max = {max:?}",
                quoted(&unit)
            );
            if log {
                e.push_str(", scale = \"log\"");
            }
            if let Some(v) = fixed {
                e.push_str(&format!(", fixed = {v:?}"));
            }
            e.push_str(&format!(", what = {} }}", quoted(&what)));
            e
        };
        let fixed_entry = |v: f64| {
            let (lo, hi) = if v == 0.0 {
                (0.0, 1.0)
            } else {
                (v - 0.5 * v.abs(), v + 0.5 * v.abs())
            };
            entry(lo, hi, false, Some(v))
        };
        if let Some(v) = fixed {
            lines.push(fixed_entry(v));
            continue;
        }
        if let Some(values) = per_sample_values(set, name)? {
            let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if lo == hi {
                lines.push(fixed_entry(lo));
            } else {
                let ([a, b], log) = padded(lo, hi);
                lines.push(entry(a, b, log, None));
                varied.push((name.to_string(), [a, b]));
            }
            continue;
        }
        // Searched: the set's (or the candidate's) range, else the range a given model was
        // trained over.
        let given = if owned {
            candidate
                .as_ref()
                .and_then(|c| c.bounds.iter().find(|(n, _)| n == name))
        } else {
            set.bounds.iter().find(|(n, _)| n == name)
        }
        .map(|(_, b)| *b);
        let from_model = || {
            models
                .iter()
                .filter(|m| m.experiment.as_deref().is_none_or(|e| e == experiment))
                .chain(models.iter())
                .find_map(|m| m.input(name).map(|k| m.domains[k]))
        };
        let Some([mut lo, hi]) = given.or_else(from_model) else {
            return Err(Error::input(
                &set.source,
                if owned {
                    format!("candidates.{}.bounds.{name}", effect.map_or("", |e| e.name))
                } else {
                    format!("bounds.{name}")
                },
                format!(
                    "a search range [min, max] of {name}: the local model of {class} varies it, \
                     and no model given has it to take the range from (or fix it in [fixed])"
                ),
            ));
        };
        // The effect's range reaches the value that switches it off, so the model also
        // describes the set's own class.
        if let Some(off) = spec.filter(|_| owned).and_then(|s| s.off) {
            lo = lo.min(off);
        }
        // A little wider than searched, within what a run accepts, so that the runs' range (the
        // model's domain) holds the search range.
        let pad = 0.05 * (hi - lo);
        let (valid_lo, valid_hi) = spec.map_or(
            (
                if lo >= 0.0 { 0.0 } else { f64::NEG_INFINITY },
                f64::INFINITY,
            ),
            |s| s.range,
        );
        let (lo, hi) = ((lo - pad).max(valid_lo), (hi + pad).min(valid_hi));
        lines.push(entry(lo, hi, false, None));
        varied.push((name.to_string(), [lo, hi]));
    }
    let mut responses: Vec<(String, f64)> = Vec::new();
    for s in &set.samples {
        for m in &s.measured {
            if !responses.iter().any(|(r, _)| *r == m.response) {
                let mut sd: Vec<f64> = set
                    .samples
                    .iter()
                    .flat_map(|t| &t.measured)
                    .filter(|q| q.response == m.response)
                    .map(|q| q.sd)
                    .collect();
                sd.sort_by(f64::total_cmp);
                responses.push((
                    m.response.clone(),
                    crate::numeric::quantile_sorted(&sd, 0.5),
                ));
            }
        }
    }
    let name = format!(
        "{}_{}_{}",
        slug(&set.name),
        experiment.replace('-', "_"),
        effect.map_or("base", |e| e.name)
    )
    .replace('-', "_");
    let space = format!(
        "# A local model around the material of {source}, written by `mbgc diagnose --build`:\n\
         # its known values fixed, the searched ones and the samples' span varied.\n\
         name = {title}\n\n[model]\nclass = \"{class}\"\n\n[parameters]\n{body}\n",
        source = set.source,
        title = quoted(&format!("local model of {}: {class}", set.name)),
        body = lines.join("\n")
    );
    let base = match effect {
        Some(_) => {
            let b = local_plan(set, models, experiment, None, String::new())?;
            Some((b.name, b.space))
        }
        None => None,
    };
    Ok(LocalPlan {
        effect,
        class,
        experiment: experiment.to_string(),
        name,
        space,
        varied,
        responses,
        reason,
        base,
    })
}

fn quoted(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// Writes a space file under `dir/spaces/`, or checks that the one there is the same.
fn write_space(dir: &std::path::Path, name: &str, text: &str) -> Result<PathBuf> {
    let spaces = dir.join("spaces");
    let path = spaces.join(format!("{name}.toml"));
    match std::fs::read_to_string(&path) {
        Ok(old) if old == text => {}
        Ok(_) => {
            return Err(Error::input(
                path.display().to_string(),
                "parameters",
                "the space this measurement set needs, but the file holds another (the set \
                 changed since the model was built): its runs would not match; pass another \
                 --build-dir or remove that directory",
            ))
        }
        Err(_) => {
            std::fs::create_dir_all(&spaces).map_err(|e| Error::io(&spaces, e))?;
            write_atomic(&path, text.as_bytes())?;
        }
    }
    Ok(path)
}

/// How a round's budget is spent: `(base training, base validation, all training, validation,
/// replicates)` runs, the effect model's counts including the base runs it copies. The
/// replicates run the first validation inputs again with another seed: a validation run holds one
/// run's DEM noise besides the model's own error, and only the pairs tell the two apart.
pub fn split(budget: usize, with_base: bool) -> (usize, usize, usize, usize, usize) {
    let validation = (budget / 5).max(3);
    let replicates = (validation / 4).max(2);
    let total = budget - validation - replicates;
    let (base, base_validation) = if with_base {
        ((total / 4).max(5), (validation / 4).max(1))
    } else {
        (0, 0)
    };
    (base, base_validation, total, validation, replicates)
}

/// The budgets of the two rounds: the whole search range, then the box where the first model's
/// posteriors lie (`0`: no second round, the budget is too small to split).
pub fn rounds(budget: usize) -> (usize, usize) {
    if budget >= 2 * MIN_BUDGET {
        (budget / 2, budget - budget / 2)
    } else {
        (budget, 0)
    }
}

/// Builds (or resumes) one local model in up to two rounds of `opts.budget_runs` together.
///
/// The first round spends half the budget over the whole search range: for an effect, a quarter
/// of it as the model of the set's class (the effect off), which the effect model extends. If
/// that model's validation error exceeds the measurement sd of a response, the second half is
/// spent where it matters (more runs near the material, not a longer equation): the set is
/// fitted with the first model, with and without the effect, and a second model of the same
/// kind is built over a box around both fits ([`focus_box`]), fitted on its new runs and the
/// first round's runs inside the box. It replaces the first, and it is validated in that box.
/// When the box is not at least twice smaller than the first range, the first model's designs
/// are extended to the whole budget instead.
pub fn build(
    set: &MeasurementSet,
    plan: &LocalPlan,
    opts: &BuildOptions,
    observer: &dyn TrainObserver,
) -> Result<Built> {
    check_budget(opts.budget_runs)?;
    if opts.dir.exists() && !opts.dir.is_dir() {
        return Err(Error::input(
            opts.dir.display().to_string(),
            "--build-dir",
            "a directory for the local models (this is a file)",
        ));
    }
    let (first, second) = rounds(opts.budget_runs);
    let with_base = plan.base.is_some();
    let counts = split(first, with_base);
    // The whole budget over the first range: its designs extended, the base runs as they were
    // (the effect design starts with them).
    let (_, _, total, validation, replicates) = split(opts.budget_runs, with_base);
    let extended = (counts.0, counts.1, total, validation, replicates);
    // The box an earlier call chose for a second round is kept: its runs were made there (a
    // later version's fits may differ slightly and would otherwise start the round again).
    let box_file = opts
        .dir
        .join("spaces")
        .join(format!("{}_focus.box.json", plan.name));
    // An earlier call that extended the first model to the whole budget decided so: resume
    // that decision.
    let paths = TrainPaths::new(&opts.dir, &plan.name);
    if second > 0 && !box_file.exists() && rows(&paths.design) >= total {
        return round(plan, extended, Vec::new(), opts, observer);
    }
    let built = round(plan, counts, Vec::new(), opts, observer)?;
    // The second round gets what the first left of the budget (a first round resumed from a
    // larger earlier design may have used more than half).
    let used =
        rows(&paths.design) + rows(&paths.validation_design) + rows(&replicates_design(&paths));
    let second = if second > 0 {
        opts.budget_runs.saturating_sub(used)
    } else {
        0
    };
    if built.precise_enough() || second < MIN_BUDGET {
        if !built.precise_enough() && second > 0 {
            observer.note(
                TrainStage::Fit,
                &format!(
                    "local model {}: {second} runs of the budget left, fewer than the {MIN_BUDGET} \
                     a second round needs",
                    plan.name
                ),
            );
        }
        return Ok(built);
    }
    let sub = only_experiment(set, &plan.experiment);
    let model = surrogate(&built)?;
    let saved: Option<Vec<(String, [f64; 2])>> = match std::fs::read_to_string(&box_file) {
        Ok(text) => Some(serde_json::from_str(&text).map_err(|e| {
            Error::input(
                box_file.display().to_string(),
                "box",
                format!("a list of [name, [min, max]] as `mbgc diagnose --build` writes it: {e}"),
            )
        })?),
        Err(_) => None,
    };
    let focus = match saved {
        Some(f) => f,
        None => {
            let diag_opts = super::diagnosis::Options {
                starts: 8,
                samples: 1000,
                seed: opts.seed,
                ..Default::default()
            };
            let d = match super::diagnosis::diagnose(&sub, std::slice::from_ref(&model), &diag_opts)
            {
                Ok(d) => d,
                Err(e) => {
                    observer.note(
                        TrainStage::Fit,
                        &format!(
                            "local model {}: the set could not be fitted with it ({e}); no \
                             second round",
                            plan.name
                        ),
                    );
                    return Ok(built);
                }
            };
            let fitted: Vec<&Parameter> = std::iter::once(&d.base)
                .chain(
                    d.extended
                        .iter()
                        .filter(|f| f.effect.as_deref() == plan.effect.map(|e| e.name)),
                )
                .flat_map(|f| &f.parameters)
                .collect();
            focus_box(plan, &fitted)
        }
    };
    let narrowed = narrowed_set(&sub, plan.effect, &focus);
    let mut focused = local_plan(
        &narrowed,
        std::slice::from_ref(&model),
        &plan.experiment,
        plan.effect,
        plan.reason.clone(),
    )?;
    focused.name = format!("{}_focus", plan.name);
    // One base per effect's box: two effects' second rounds have different boxes.
    if let Some((b, _)) = focused.base.as_mut() {
        *b = format!("{}_base", focused.name);
    }
    let shrink: f64 = focused
        .varied
        .iter()
        .filter_map(|(n, [a, b])| {
            let (_, [a0, b0]) = plan.varied.iter().find(|(m, _)| m == n)?;
            Some((b - a) / (b0 - a0))
        })
        .product();
    if shrink > 0.5 {
        observer.note(
            TrainStage::Sample,
            &format!(
                "local model {}: the set's fits with it span {:.0} % of its range, so the rest \
                 of the budget extends it there",
                plan.name,
                100.0 * shrink
            ),
        );
        return round(plan, extended, Vec::new(), opts, observer);
    }
    observer.note(
        TrainStage::Sample,
        &format!(
            "local model {}: {}; second round over {}",
            plan.name,
            precision_text(&built),
            ranges_text(&focused.varied)
        ),
    );
    let text = serde_json::to_string_pretty(&focus)
        .map_err(|e| Error::invalid(format!("{}: {e}", box_file.display())))?;
    if std::fs::read_to_string(&box_file).ok().as_deref() != Some(text.as_str()) {
        write_atomic(&box_file, text.as_bytes())?;
    }
    let wide = TrainPaths::new(&opts.dir, &plan.name);
    let also = vec![(wide.table, wide.validation_table)];
    let mut second_built = round(&focused, split(second, with_base), also, opts, observer)?;
    second_built.first = Some(Box::new(built));
    second_built.focus = focus;
    Ok(second_built)
}

/// The box a second round searches, a trust region around the first model's fits: per searched
/// parameter of the plan, the span of the fits' best values, widened on each side by half the
/// span of their 90 % intervals, but by at least 5 % and at most 20 % of the first range (an
/// imprecise first model gives wide intervals, and a box as wide as the first range would gain
/// nothing), within the first range. A later fit at the box's edge is flagged as cut there.
fn focus_box(plan: &LocalPlan, fitted: &[&Parameter]) -> Vec<(String, [f64; 2])> {
    let mut out = Vec::new();
    for (name, [lo0, hi0]) in &plan.varied {
        let ps: Vec<&Parameter> = fitted.iter().copied().filter(|p| p.name == *name).collect();
        if ps.is_empty() {
            // Not searched (a span of the samples' known values): kept as it was.
            continue;
        }
        let min = |f: fn(&Parameter) -> f64| ps.iter().map(|p| f(p)).fold(f64::INFINITY, f64::min);
        let max =
            |f: fn(&Parameter) -> f64| ps.iter().map(|p| f(p)).fold(f64::NEG_INFINITY, f64::max);
        let range = hi0 - lo0;
        let pad = (0.5 * (max(|p| p.q95) - min(|p| p.q05))).clamp(0.05 * range, 0.2 * range);
        let mut lo = (min(|p| p.best) - pad).max(*lo0);
        // The effect's strength keeps the value that switches it off: the model describes the
        // set's class there.
        if let Some(off) = plan
            .effect
            .filter(|e| owns(e, name))
            .and_then(|e| {
                e.params
                    .iter()
                    .find(|p| Pair::BOTH.iter().any(|&q| p.name(q) == name))
            })
            .and_then(|p| p.off)
        {
            lo = lo.min(off);
        }
        out.push((name.clone(), [lo, (max(|p| p.best) + pad).min(*hi0)]));
    }
    out
}

/// The set with the search ranges a second round's model was built for: the diagnosis with that
/// model searches there (its fits are flagged where they reach the box's edge).
pub fn narrow(set: &MeasurementSet, built: &Built) -> MeasurementSet {
    narrowed_set(set, built.plan.effect, &built.focus)
}

/// The set with the focus box as its search ranges (the effect's own in its candidate's).
fn narrowed_set(
    set: &MeasurementSet,
    effect: Option<&'static EffectSpec>,
    focus: &[(String, [f64; 2])],
) -> MeasurementSet {
    let mut s = set.clone();
    // Within the set's own range, where it gives one (the first range is a little wider).
    let within = |given: &mut Vec<(String, [f64; 2])>, name: &str, b: [f64; 2]| {
        let b = match given.iter().find(|(n, _)| n == name) {
            Some((_, [lo, hi])) if b[0].max(*lo) < b[1].min(*hi) => [b[0].max(*lo), b[1].min(*hi)],
            _ => b,
        };
        given.retain(|(n, _)| n != name);
        given.push((name.to_string(), b));
    };
    for (name, b) in focus {
        match effect.filter(|e| owns(e, name)) {
            Some(e) => {
                let mut c = s.candidate(e);
                within(&mut c.bounds, name, *b);
                s.candidates.retain(|c| c.effect.name != e.name);
                s.candidates.push(c);
            }
            None => within(&mut s.bounds, name, *b),
        }
    }
    s
}

/// One round: for an effect, the model of the set's class without it first (its runs only),
/// then the effect model extending it, fitted once (with the rows of `also_fit` inside its
/// space), and the replicates that measure its DEM noise.
fn round(
    plan: &LocalPlan,
    counts: (usize, usize, usize, usize, usize),
    also_fit: Vec<(PathBuf, PathBuf)>,
    opts: &BuildOptions,
    observer: &dyn TrainObserver,
) -> Result<Built> {
    let space_path = write_space(&opts.dir, &plan.name, &plan.space)?;
    let (base_n, base_validation, total, validation, replicates) = counts;
    let request = |space: PathBuf, name: &str, n: usize, validation: usize| TrainRequest {
        validation,
        out_dir: opts.dir.clone(),
        name: Some(name.to_string()),
        seed: opts.seed,
        threads: opts.threads,
        responses: plan.responses.iter().map(|(r, _)| r.clone()).collect(),
        figures: false,
        config: opts.config.clone(),
        ..TrainRequest::new(space, &plan.experiment, n)
    };
    // A design an earlier call made larger is resumed at its size (a train never drops rows).
    if let Some((base_name, base_space)) = &plan.base {
        let path = write_space(&opts.dir, base_name, base_space)?;
        let bp = TrainPaths::new(&opts.dir, base_name);
        let req = TrainRequest {
            no_fit: true,
            ..request(
                path,
                base_name,
                base_n.max(rows(&bp.design)),
                base_validation.max(rows(&bp.validation_design)),
            )
        };
        train(&req, observer)?;
    }
    let paths = TrainPaths::new(&opts.dir, &plan.name);
    let n = total.max(rows(&paths.design));
    let validation = validation.max(rows(&paths.validation_design));
    let req = TrainRequest {
        extends: plan.base.as_ref().map(|(b, _)| b.clone()),
        also_fit,
        ..request(space_path, &plan.name, n, validation)
    };
    let TrainOutcome::Fitted { model, paths, .. } = train(&req, observer)? else {
        return Err(Error::invalid(
            "the local model's train stopped before its fit",
        ));
    };
    let mut model = *model;
    let noise = replicate_runs(plan, &paths, replicates, opts, observer)
        .and_then(|table| {
            let m = &model;
            let names: Vec<String> = plan.responses.iter().map(|(r, _)| r.clone()).collect();
            // Each pair brought to the factor the model's errors are read at (its validation
            // runs' mean rho_p for a bulk density).
            replicate_noise_scaled(
                &paths.validation_table,
                &table,
                &m.input_names(),
                &names,
                &|k, x| {
                    m.responses
                        .iter()
                        .find(|r| r.name == names[k])
                        .map_or(1.0, |r| {
                            let s = m.error_scale(r, x);
                            if s.is_finite() && s > 0.0 {
                                1.0 / s
                            } else {
                                1.0
                            }
                        })
                },
            )
        })
        .map_err(|e| {
            observer.note(
                TrainStage::Fit,
                &format!(
                    "local model {}: no replicate noise ({e}); its validation RMSE is taken as \
                     its own error",
                    plan.name
                ),
            )
        })
        .ok();
    if let Some(noise) = &noise {
        for r in model.responses.iter_mut() {
            let n = noise.iter().find(|n| n.response == r.name);
            r.replicate_sd = n.map(|n| n.sd);
            r.replicate_pairs = n.map(|n| n.pairs);
        }
        model.save(&paths.model)?;
    }
    let precision = plan
        .responses
        .iter()
        .map(|(r, sd)| {
            let m = model.responses.iter().find(|m| m.name == *r);
            Precision {
                response: r.clone(),
                validation_rmse: m
                    .and_then(|m| m.validation.or(m.test))
                    .map_or(f64::INFINITY, |v| v.rmse),
                replicate_sd: m.and_then(|m| {
                    m.replicate_sd
                        .map(|sd| crate::metamodel::noise::lower_bound(sd, m.replicate_pairs))
                }),
                measurement_sd: *sd,
            }
        })
        .collect();
    let built = Built {
        plan: plan.clone(),
        path: paths.model.clone(),
        model,
        training_runs: n,
        precision,
        first: None,
        focus: Vec::new(),
    };
    observer.note(
        TrainStage::Fit,
        &format!(
            "local model {} at {n} runs: {}",
            plan.name,
            precision_text(&built)
        ),
    );
    Ok(built)
}

/// Rows of a design file (0 when there is none yet).
fn rows(path: &std::path::Path) -> usize {
    std::fs::read_to_string(path).map_or(0, |t| t.lines().count().saturating_sub(1))
}

/// The design of a model's replicate runs, beside its validation design.
fn replicates_design(paths: &TrainPaths) -> PathBuf {
    let name = paths
        .validation_design
        .file_name()
        .and_then(|n| n.to_str())
        .map_or(String::new(), |n| {
            n.replace("_validation.csv", "_replicates.csv")
        });
    paths.validation_design.with_file_name(name)
}

/// Runs the first `k` rows of the validation design again with another campaign seed (into
/// `training_data/<name>_replicates.csv`, resumed like every table) and returns the table.
fn replicate_runs(
    plan: &LocalPlan,
    paths: &TrainPaths,
    k: usize,
    opts: &BuildOptions,
    observer: &dyn TrainObserver,
) -> Result<PathBuf> {
    let design_text = std::fs::read_to_string(&paths.validation_design)
        .map_err(|e| Error::io(&paths.validation_design, e))?;
    let design = replicates_design(paths);
    let old = std::fs::read_to_string(&design).map_or(0, |t| t.lines().count());
    let lines: Vec<&str> = design_text.lines().collect();
    let keep = (k + 1).max(old).min(lines.len());
    let text = lines[..keep].join("\n") + "\n";
    if std::fs::read_to_string(&design).ok().as_deref() != Some(text.as_str()) {
        write_atomic(&design, text.as_bytes())?;
    }
    let settings = ExperimentSettings {
        model_class: Some(plan.class),
        ..Default::default()
    };
    let exp = experiment_by_name(&plan.experiment, &settings)?;
    // Another stream than the training (seed) and validation (seed + 1) runs.
    let seed = opts.seed.wrapping_add(2);
    let p = crate::campaign::Plan::new(exp.as_ref(), &design, &[], seed, &settings, None)?;
    let table = paths
        .validation_table
        .with_file_name(format!("{}_replicates.csv", plan.name));
    let r = crate::campaign::run_campaign(
        exp.as_ref(),
        &p,
        &crate::campaign::CampaignOptions {
            observer: observer.campaign(&table),
            ..crate::campaign::CampaignOptions::new(table.clone(), opts.threads)
        },
    )?;
    observer.note(
        TrainStage::Simulate,
        &format!(
            "{} (replicates of the first {} validation inputs, seed {seed}): {} already done, \
             ran {} ({} done, {} failed)",
            table.display(),
            keep - 1,
            r.skipped,
            r.done + r.failed,
            r.done,
            r.failed
        ),
    );
    if let Some(note) = r.added_columns_note(&table) {
        observer.note(TrainStage::Simulate, &note);
    }
    Ok(table)
}

/// Each response's validation RMSE, the replicate noise it holds, the model's own error and the
/// measurement sd it is compared with.
pub fn precision_text(b: &Built) -> String {
    b.precision
        .iter()
        .map(|p| {
            format!(
                "{} validation RMSE {:.4} (noise >= {}, own error <= {:.4}; measurement sd {:.4})",
                p.response,
                p.validation_rmse,
                p.replicate_sd
                    .map_or("unknown".to_string(), |n| format!("{n:.4}")),
                p.model_error(),
                p.measurement_sd
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// `mu_pp [0.2000, 0.7000], ...`: parameter ranges for messages.
pub fn ranges_text(ranges: &[(String, [f64; 2])]) -> String {
    ranges
        .iter()
        .map(|(n, [lo, hi])| format!("{n} [{lo:.4}, {hi:.4}]"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Reads a built model back as a surrogate for the diagnosis.
pub fn surrogate(b: &Built) -> Result<Surrogate> {
    Surrogate::from_model(b.model.clone(), &b.path.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slugs_are_plain_file_names() {
        assert_eq!(
            slug("Spheres in 5 sieve fractions, ced = 2.5e4"),
            "spheres_in_5_sieve_fractions_ced_2_5e4"
        );
        assert_eq!(slug("***"), "set");
    }

    fn fitted(name: &str, best: f64, q05: f64, q95: f64) -> Parameter {
        Parameter {
            name: name.into(),
            best,
            posterior_mean: best,
            q05,
            q95,
            at_edge: None,
            exact_models: None,
        }
    }

    #[test]
    fn the_second_round_searches_near_the_fits_and_keeps_the_effect_off_face() {
        let sjkr = mbgc_dem::contact::all_effects()
            .iter()
            .find(|e| e.name == "sjkr")
            .copied()
            .unwrap();
        let plan = LocalPlan {
            effect: Some(sjkr),
            class: "hertz,mindlin,sjkr".parse().unwrap(),
            experiment: "shear-box".into(),
            name: "t".into(),
            space: String::new(),
            varied: vec![
                ("d50".into(), [1.0, 3.0]),
                ("mu_pp".into(), [0.0, 1.0]),
                ("ced_pp".into(), [0.0, 1e5]),
            ],
            responses: Vec::new(),
            reason: String::new(),
            base: None,
        };
        // A wide posterior: the box is the fits' best values +- 20 % of the first range.
        let a = fitted("mu_pp", 0.5, 0.1, 0.95);
        let b = fitted("mu_pp", 0.4, 0.2, 0.7);
        let c = fitted("ced_pp", 5e4, 1e4, 9e4);
        let focus = focus_box(&plan, &[&a, &b, &c]);
        assert_eq!(
            focus.len(),
            2,
            "{focus:?}: d50 is the samples' span, not searched"
        );
        let [lo, hi] = focus[0].1;
        assert!(
            (lo - 0.2).abs() < 1e-12 && (hi - 0.7).abs() < 1e-12,
            "{focus:?}"
        );
        // The cohesion's box reaches down to 0, where the set's own class lies.
        let [lo, hi] = focus[1].1;
        assert!(lo == 0.0 && (hi - 7e4).abs() < 1e-6, "{focus:?}");
        // A narrow posterior: half its span each side, but at least 5 % of the range.
        let d = fitted("mu_pp", 0.5, 0.49, 0.51);
        let [lo, hi] = focus_box(&plan, &[&d])[0].1;
        assert!((lo - 0.45).abs() < 1e-12 && (hi - 0.55).abs() < 1e-12);
    }

    /// Issue 35: the local models of the cohesive sets had been trained on monosized runs
    /// (sigma_ln, optional in the shear box, was left out of their space), which put their
    /// density 27 kg/m3 below the measurements at the true parameters.
    #[test]
    fn a_local_space_holds_the_samples_size_spread() {
        let set = |sigma: &str| {
            let mut t = String::from(
                "name = \"s\"\n[model]\nclass = \"hertz,mindlin,epsd2\"\n[fixed]\nE_p = 4.5e6\n\
                 E_w = 4.5e6\nnu_p = 0.3\ne_pp = 0.5\ne_pw = 0.5\nmu_pw = 0.3\nrho_p = 2600\n\
                 mu_r_pw = 0.001\n[bounds]\nmu_pp = [0.1, 1.0]\nmu_r_pp = [0.0, 0.5]\n",
            );
            for (d, s) in [(2, "0.12"), (8, sigma)] {
                t += &format!(
                    "[[sample]]\nname = \"{d} mm\"\nexperiment = \"shear-box\"\n\
                     psd = {{ d50_mm = {d}, sigma_ln = {s} }}\n\
                     measured.shear_angle = {{ value = 30, sd = 1 }}\n"
                );
            }
            MeasurementSet::from_toml_str(&t, "set.toml").unwrap()
        };
        let same = local_plan(&set("0.12"), &[], "shear-box", None, String::new()).unwrap();
        assert!(
            same.space
                .lines()
                .any(|l| l.starts_with("sigma_ln = ") && l.contains("fixed = 0.12")),
            "{}",
            same.space
        );
        let spread = local_plan(&set("0.2"), &[], "shear-box", None, String::new()).unwrap();
        assert!(
            spread
                .varied
                .iter()
                .any(|(n, [a, b])| n == "sigma_ln" && *a < 0.12 && *b > 0.2),
            "{:?}",
            spread.varied
        );
    }

    #[test]
    fn a_wide_span_is_padded_on_a_log_scale_and_a_narrow_one_linearly() {
        let ([a, b], log) = padded(1.0, 16.0);
        assert!(log && a < 1.0 && b > 16.0 && (16.0f64 / 1.0).ln() < (b / a).ln());
        let ([a, b], log) = padded(0.2, 0.3);
        assert!(!log && a < 0.2 && a > 0.0 && b > 0.3);
    }
}
