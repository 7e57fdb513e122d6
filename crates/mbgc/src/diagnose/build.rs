//! The models a diagnosis lacks, built around the material (`mbgc diagnose --build`).
//!
//! A candidate effect that no given model covers for this material cannot be evaluated. Instead
//! of a global campaign, a local model is enough: the set's known parameters stay fixed, the
//! searched ones and the effect's strength vary over their search ranges, and the sample sizes
//! (or any other value known per sample) over the samples' span. It is trained with
//! [`crate::train::train`] into a directory of its own, so a second call resumes it and a larger
//! budget extends its design instead of starting again. Its own error is compared with the
//! measurement sd: a first half of the budget is fitted, and the second half is run only if the
//! model is still less precise than the measurements (more runs near the material, not a longer
//! equation).

use std::path::PathBuf;

use super::joint::{with_effect, Joint};
use super::measurements::{owns, switchable_effects, MeasurementSet};
use super::surrogate::Surrogate;
use crate::campaign::{experiment_by_name, ExperimentSettings};
use crate::error::{write_atomic, Error, Result};
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

/// Fewest runs per local model: a validation set of 3 and ten training runs, the least the
/// five-fold cross-validation that picks the equation accepts.
pub const MIN_BUDGET: usize = 13;

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

    /// Validation runs of a model: a fifth of the budget, at least 3.
    pub fn validation(&self) -> usize {
        split(self.budget_runs, false).4
    }
}

/// Refuses a budget too small to validate and fit a model, or larger than a train's design may
/// be.
pub fn check_budget(budget: usize) -> Result<()> {
    if budget < MIN_BUDGET {
        return Err(Error::invalid(format!(
            "--budget-runs {budget}: expected at least {MIN_BUDGET} runs per local model (3 to \
             validate it, 10 for the cross-validation that picks its equation)"
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
    /// Per response: its validation RMSE and the measurement sd it was compared with.
    pub precision: Vec<(String, f64, f64)>,
}

impl Built {
    /// Whether its own error stays below the measurement sd for every response.
    pub fn precise_enough(&self) -> bool {
        self.precision.iter().all(|(_, e, sd)| e <= sd)
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
    let mut effects = switchable_effects(&set.class);
    for c in &set.candidates {
        if !effects.iter().any(|e| e.name == c.effect.name) {
            effects.push(c.effect);
        }
    }
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
    let mut experiments: Vec<&str> = Vec::new();
    for s in &set.samples {
        if !experiments.contains(&s.experiment.as_str()) {
            experiments.push(&s.experiment);
        }
    }
    let mut plans = Vec::new();
    for exp in experiments {
        let sub = only_experiment(set, exp);
        let mut planned_effect = false;
        for &e in &effects {
            if !wanted.is_empty() && !wanted.iter().any(|w| w == e.name) {
                continue;
            }
            let settings = sub.candidate(e);
            let free = e.params.iter().any(|p| {
                Pair::BOTH
                    .iter()
                    .any(|&pair| !settings.fixed.iter().any(|(n, _)| n == p.name(pair)))
            });
            if !free {
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
    for name in exp.parameters() {
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

/// How a budget is spent: `(base training, base validation, first round, all training,
/// validation)` runs, the effect model's counts including the base runs it copies.
pub fn split(budget: usize, with_base: bool) -> (usize, usize, usize, usize, usize) {
    let validation = (budget / 5).max(3);
    let total = budget - validation;
    let (base, base_validation) = if with_base {
        ((total / 4).max(5), (validation / 4).max(1))
    } else {
        (0, 0)
    };
    let first = (base + (total - base) / 2).max(10).min(total);
    (base, base_validation, first, total, validation)
}

/// Builds (or resumes) one local model: writes its space under `opts.dir/spaces/`; for an
/// effect, first runs a quarter of the budget as the model of the set's class (the effect off)
/// and extends it; runs half the remaining training budget and the validation set, fits, and
/// runs the rest and fits again only if the model's validation error exceeds the measurement sd
/// of a response.
pub fn build(plan: &LocalPlan, opts: &BuildOptions, observer: &dyn TrainObserver) -> Result<Built> {
    check_budget(opts.budget_runs)?;
    if opts.dir.exists() && !opts.dir.is_dir() {
        return Err(Error::input(
            opts.dir.display().to_string(),
            "--build-dir",
            "a directory for the local models (this is a file)",
        ));
    }
    let space_path = write_space(&opts.dir, &plan.name, &plan.space)?;
    let (base_n, base_validation, first, total, validation) =
        split(opts.budget_runs, plan.base.is_some());
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
    if let Some((base_name, base_space)) = &plan.base {
        let path = write_space(&opts.dir, base_name, base_space)?;
        let req = TrainRequest {
            no_fit: true,
            ..request(path, base_name, base_n, base_validation)
        };
        train(&req, observer)?;
    }
    // A design an earlier call extended is resumed at its size (a train never drops rows).
    let existing = std::fs::read_to_string(TrainPaths::new(&opts.dir, &plan.name).design)
        .map_or(0, |t| t.lines().count().saturating_sub(1));
    let total = total.max(existing);
    let mut result = None;
    for n in [first.max(existing), total] {
        if result
            .as_ref()
            .is_some_and(|b: &Built| b.precise_enough() || b.training_runs >= total)
        {
            break;
        }
        let req = TrainRequest {
            extends: plan.base.as_ref().map(|(b, _)| b.clone()),
            ..request(space_path.clone(), &plan.name, n, validation)
        };
        let TrainOutcome::Fitted { model, paths, .. } = train(&req, observer)? else {
            return Err(Error::invalid(
                "the local model's train stopped before its fit",
            ));
        };
        let precision = plan
            .responses
            .iter()
            .map(|(r, sd)| {
                let e = model
                    .responses
                    .iter()
                    .find(|m| m.name == *r)
                    .and_then(|m| m.validation.or(m.test))
                    .map_or(f64::INFINITY, |v| v.rmse);
                (r.clone(), e, *sd)
            })
            .collect();
        let built = Built {
            plan: plan.clone(),
            path: paths.model.clone(),
            model: *model,
            training_runs: n,
            precision,
        };
        observer.note(
            TrainStage::Fit,
            &format!(
                "local model {} at {n} runs: {}",
                plan.name,
                precision_text(&built)
            ),
        );
        result = Some(built);
    }
    result.ok_or_else(|| Error::invalid("no local model was fitted"))
}

/// `shear_angle 0.8 (sd 1.1), ...`: each response's validation RMSE beside the measurement sd.
pub fn precision_text(b: &Built) -> String {
    b.precision
        .iter()
        .map(|(r, e, sd)| format!("{r} validation RMSE {e:.4} (measurement sd {sd:.4})"))
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

    #[test]
    fn a_wide_span_is_padded_on_a_log_scale_and_a_narrow_one_linearly() {
        let ([a, b], log) = padded(1.0, 16.0);
        assert!(log && a < 1.0 && b > 16.0 && (16.0f64 / 1.0).ln() < (b / a).ln());
        let ([a, b], log) = padded(0.2, 0.3);
        assert!(!log && a < 0.2 && a > 0.0 && b > 0.3);
    }
}
