//! The joint problem of a measurement set under one model class: which model predicts each
//! sample, which parameters are known, searched once for all samples or per sample, and the
//! chi^2, likelihood and fit over all samples together.
//!
//! A class with an effect the set's class lacks (a candidate) uses a model of that class; a
//! model of a richer class serves a poorer one on the face of its space where the extra effect
//! is off (a rolling friction or a cohesion of 0).

use rayon::prelude::*;

use super::covariance::{Covariance, Entry};
use super::measurements::{owns, CandidateSettings, MeasurementSet};
use super::surrogate::Surrogate;
use crate::calibrate::problem::same_value;
use crate::calibrate::tmcmc::{tmcmc, TmcmcOptions, UniformBox};
use crate::calibrate::{minimize, starts, Objective};
use mbgc_dem::contact::{EffectSpec, ModelClass, Slot};

/// One measured value.
#[derive(Clone, Debug)]
pub struct Target {
    /// Index of the sample in the measurement set.
    pub sample: usize,
    /// Response name, as in the sample's model.
    pub response: String,
    /// Index of the response in the sample's model.
    model_response: usize,
    /// Measured value, in the response's unit.
    pub value: f64,
    /// Measurement standard deviation, in the response's unit (> 0 unless the model error is).
    pub sd: f64,
    /// The model's own error for this response.
    pub model_error: f64,
    /// Whether the set gives the model error (`[model_error]`), which then stays as given.
    error_given: bool,
    /// The model's validation RMSE (or the set's given error), before `model_error` is
    /// localised.
    global_error: f64,
    /// The DEM noise in `model_error` (the model's replicate sd), when known.
    noise: Option<f64>,
}

impl Target {
    /// Standard deviation of measured minus predicted: measurement and model error together.
    pub fn sigma(&self) -> f64 {
        self.sd.hypot(self.own_error())
    }

    /// The model's own miss: its error less the DEM noise of its validation runs, which the
    /// measurement sd already holds (a measured value scatters about the DEM mean by that noise,
    /// and the model predicts the mean, missing it by the rest); the whole error when the set
    /// gives it or the model does not know its noise.
    ///
    /// The noise is taken off the validation RMSE, where both are measured over the same runs;
    /// a localised error keeps the same share of it (subtracting the noise from a local
    /// estimate, itself scattered, could leave nothing of an error that is there).
    pub fn own_error(&self) -> f64 {
        match self.noise {
            Some(n) if !self.error_given && self.global_error > 0.0 => {
                let own = (self.global_error.powi(2) - n * n).max(0.0).sqrt();
                own * self.model_error / self.global_error
            }
            _ => self.model_error,
        }
    }

    /// The part of the model error shared between samples: the own miss, all of it when the set
    /// gives the error, none when the model does not know its noise (its error is then taken as
    /// independent between the samples).
    pub fn shared_error(&self) -> f64 {
        if self.error_given || self.noise.is_some() {
            self.own_error()
        } else {
            0.0
        }
    }
}

struct Row {
    model: usize,
    x: Vec<f64>,
    /// (model input, searched parameter) pairs.
    slots: Vec<(usize, usize)>,
}

/// The joint calibration problem of a measurement set under one model class: one parameter
/// vector theta for all samples, predicted by each sample's model.
pub struct Joint<'s> {
    /// The class compared (the set's, or with one candidate effect).
    pub class: ModelClass,
    /// The candidate effect added to the set's class, or `None` for the set's class itself.
    pub effect: Option<&'static EffectSpec>,
    surrogates: &'s [Surrogate],
    /// Searched parameters: `mu_pp`, or `mu_pw [2 mm]` for one searched per sample.
    pub names: Vec<String>,
    /// Lower bounds of the searched parameters, from the models' domains.
    pub lower: Vec<f64>,
    /// Upper bounds of the searched parameters, from the models' domains.
    pub upper: Vec<f64>,
    /// Indices into `names` of the candidate effect's parameters.
    pub effect_params: Vec<usize>,
    rows: Vec<Row>,
    /// Every measured value of every sample, in sample order.
    pub targets: Vec<Target>,
    /// Which model each sample uses, and what was decided on the user's behalf.
    pub notes: Vec<String>,
    /// Correlation of one model's error for one response between samples.
    pub correlation: f64,
    /// The residuals' covariance, refactored when the model errors change.
    cov: Covariance,
}

impl Joint<'_> {
    /// The models the samples use, each once, in sample order.
    pub fn models(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for r in &self.rows {
            let label = &self.surrogates[r.model].label;
            if !out.contains(label) {
                out.push(label.clone());
            }
        }
        out
    }
}

/// Weight of a derived group outside its fitted range (ln units squared).
const PENALTY: f64 = 1e6;

/// How far beyond a model's domain (share of its width) the value that switches an effect off
/// may lie and still be read at the domain's edge: a design rarely puts a point exactly on 0.
const OFF_TOLERANCE: f64 = 0.02;

/// How far a searched range may reach beyond a model's domain (share of its width) and be cut to
/// it, with a note: a design's runs come near its space's bounds but rarely onto them, so a local
/// model built over exactly the set's bounds has a domain a little inside them.
const RANGE_TOLERANCE: f64 = 0.05;

/// The class `base` with `effect` switched on in its slot.
pub fn with_effect(base: &ModelClass, effect: &EffectSpec) -> Result<ModelClass, String> {
    let mut names: Vec<&str> = base
        .effects()
        .iter()
        .filter(|e| e.slot != effect.slot)
        .map(|e| e.name)
        .collect();
    names.push(effect.name);
    if base.limit_force {
        names.push(mbgc_dem::contact::LIMIT_FORCE);
    }
    ModelClass::from_names(&names).map_err(|e| e.to_string())
}

fn in_slot(c: &ModelClass, slot: Slot) -> Option<&'static EffectSpec> {
    c.effects().into_iter().find(|e| e.slot == slot)
}

/// The effects `model` has beyond `want` (to be switched off), or why it cannot stand for `want`.
fn extra_effects(
    model: &ModelClass,
    want: &ModelClass,
) -> Result<Vec<&'static EffectSpec>, String> {
    if model.limit_force != want.limit_force {
        return Err(format!(
            "its class {model} differs from {want} in limit-force"
        ));
    }
    let mut extra = Vec::new();
    for slot in Slot::ALL {
        match (in_slot(want, slot), in_slot(model, slot)) {
            (Some(a), Some(b)) if a.name == b.name => {}
            (None, None) => {}
            (None, Some(b)) if !b.params.is_empty() && b.params.iter().all(|p| p.off.is_some()) => {
                extra.push(b)
            }
            (a, b) => {
                return Err(format!(
                    "its class {model} has {} where {want} has {}",
                    b.map_or("none", |e| e.name),
                    a.map_or("none", |e| e.name)
                ))
            }
        }
    }
    Ok(extra)
}

impl<'s> Joint<'s> {
    /// The joint problem of `set` under its class, or with `candidate` switched on; `Err` says
    /// why no model (or no consistent choice) describes it.
    pub fn new(
        set: &MeasurementSet,
        surrogates: &'s [Surrogate],
        candidate: Option<&CandidateSettings>,
    ) -> Result<Joint<'s>, String> {
        let effect = candidate.map(|c| c.effect);
        let class = match effect {
            Some(e) => with_effect(&set.class, e)?,
            None => set.class,
        };
        let mut names: Vec<String> = Vec::new();
        let mut lower: Vec<f64> = Vec::new();
        let mut upper: Vec<f64> = Vec::new();
        let mut rows = Vec::new();
        let mut targets = Vec::new();
        let mut notes = Vec::new();
        let mut used_fixed: Vec<String> = Vec::new();
        for (si, s) in set.samples.iter().enumerate() {
            // The models that can stand for the class, fewest effects to switch off first (first
            // given first among equals); the first whose domain holds the sample's known values.
            let mut reasons = Vec::new();
            let mut ordered: Vec<(usize, Vec<&'static EffectSpec>)> = Vec::new();
            for (mi, m) in surrogates.iter().enumerate() {
                let why = if m.experiment.as_deref().is_some_and(|e| e != s.experiment) {
                    Err(format!(
                        "it models {}",
                        m.experiment.as_deref().unwrap_or("")
                    ))
                } else if let Some(r) = s
                    .measured
                    .iter()
                    .find(|r| m.response(&r.response).is_none())
                {
                    Err(format!("it does not predict {}", r.response))
                } else {
                    extra_effects(&m.class, &class)
                };
                match why {
                    Ok(extra) => ordered.push((mi, extra)),
                    Err(w) => reasons.push(format!("{}: {w}", m.label)),
                }
            }
            ordered.sort_by_key(|(mi, e)| (e.len(), *mi));
            let mut chosen: Option<Row> = None;
            for (mi, off) in ordered {
                let saved = (
                    names.clone(),
                    lower.clone(),
                    upper.clone(),
                    notes.clone(),
                    used_fixed.clone(),
                );
                let attempt = (|| -> Result<Row, String> {
                    let m = &surrogates[mi];
                    notes.push(format!(
                        "sample \"{}\": {}{}",
                        s.name,
                        m.label,
                        if off.is_empty() {
                            String::new()
                        } else {
                            format!(
                                " with {} off",
                                off.iter().map(|e| e.name).collect::<Vec<_>>().join(", ")
                            )
                        }
                    ));
                    // Known values, and where they come from (for messages).
                    let mut known: Vec<(String, f64, String)> = Vec::new();
                    for e in &off {
                        for p in e.params {
                            for n in p.names {
                                known.push((
                                    n.to_string(),
                                    p.off.unwrap_or(0.0),
                                    format!("{} off", e.name),
                                ));
                            }
                        }
                    }
                    if let Some(c) = candidate {
                        for (n, v) in &c.fixed {
                            known.push((
                                n.clone(),
                                *v,
                                format!("candidates.{}.fixed", c.effect.name),
                            ));
                        }
                    }
                    for (n, v) in &set.fixed {
                        known.push((n.clone(), *v, "fixed".into()));
                    }
                    for (n, v) in &s.fixed {
                        known.push((n.clone(), *v, format!("{}.fixed", s.field)));
                    }
                    if let Some(psd) = &s.psd {
                        let (d50, sigma) = psd.parameters().map_err(|e| e.to_string())?;
                        known.push(("d50".into(), d50, format!("{}.psd", s.field)));
                        known.push(("sigma_ln".into(), sigma, format!("{}.psd", s.field)));
                    }
                    for (c, v) in &m.constants {
                        match known.iter().find(|(n, _, _)| n == c) {
                            Some((_, w, from)) if !same_value(*v, *w) => {
                                return Err(format!(
                                    "{} holds {c} at {v} but {from} gives {w} (sample \"{}\")",
                                    m.label, s.name
                                ))
                            }
                            Some(_) => {}
                            None => {
                                return Err(format!(
                                "{} holds {c} at {v}, which the set searches (sample \"{}\"); fix \
                                 {c} = {v} in the set to compare with this model",
                                m.label, s.name
                            ))
                            }
                        }
                    }
                    let mut x = vec![f64::NAN; m.inputs.len()];
                    let mut slots = Vec::new();
                    for (k, input) in m.inputs.iter().enumerate() {
                        let d = m.domains[k];
                        if let Some((_, v, from)) = known.iter().find(|(n, _, _)| n == input) {
                            let mut v = *v;
                            if !(v >= d[0] && v <= d[1]) {
                                let tol = OFF_TOLERANCE * (d[1] - d[0]);
                                if from.ends_with(" off") && v >= d[0] - tol && v <= d[1] + tol {
                                    let edge = v.clamp(d[0], d[1]);
                                    let note = format!(
                                    "{input} = {v} ({from}) read at the edge {edge:.4} of {}'s domain",
                                    m.label
                                );
                                    if !notes.contains(&note) {
                                        notes.push(note);
                                    }
                                    v = edge;
                                } else {
                                    return Err(format!(
                                    "sample \"{}\": {input} = {v} (from {from}) lies outside {}'s \
                                     domain [{}, {}]; outside it the equations extrapolate",
                                    s.name, m.label, d[0], d[1]
                                ));
                                }
                            }
                            x[k] = v;
                            if from == "fixed" && !used_fixed.contains(input) {
                                used_fixed.push(input.clone());
                            }
                            continue;
                        }
                        let per_sample = set.per_sample.contains(input);
                        let name = if per_sample {
                            format!("{input} [{}]", s.name)
                        } else {
                            input.clone()
                        };
                        let range = if effect.is_some_and(|e| owns(e, input)) {
                            candidate.and_then(|c| {
                                c.bounds.iter().find(|(n, _)| n == input).map(|(_, b)| *b)
                            })
                        } else {
                            set.bounds.iter().find(|(n, _)| n == input).map(|(_, b)| *b)
                        };
                        let tol = RANGE_TOLERANCE * (d[1] - d[0]);
                        let (lo, hi) = match range {
                        Some([lo, hi]) if lo >= d[0] && hi <= d[1] => (lo, hi),
                        Some([lo, hi]) if lo >= d[0] - tol && hi <= d[1] + tol => {
                            let (a, b) = (lo.max(d[0]), hi.min(d[1]));
                            let note = format!(
                                "{input} searched in [{a:.4}, {b:.4}], the part of [{lo}, {hi}] \
                                 inside {}'s domain",
                                m.label
                            );
                            if !notes.contains(&note) {
                                notes.push(note);
                            }
                            (a, b)
                        }
                        Some([lo, hi]) => return Err(format!(
                            "the range [{lo}, {hi}] of {input} reaches outside {}'s domain [{}, {}]",
                            m.label, d[0], d[1]
                        )),
                        None => (d[0], d[1]),
                    };
                        let j = match names.iter().position(|n| *n == name) {
                            Some(j) => {
                                lower[j] = lower[j].max(lo);
                                upper[j] = upper[j].min(hi);
                                if lower[j] >= upper[j] {
                                    return Err(format!(
                                        "{name}: the domains of the models used do not overlap"
                                    ));
                                }
                                j
                            }
                            None => {
                                names.push(name);
                                lower.push(lo);
                                upper.push(hi);
                                names.len() - 1
                            }
                        };
                        slots.push((k, j));
                    }
                    // A size spread the model never saw would be silently dropped: its runs
                    // took the experiment's default (monosized spheres), which pack and shear
                    // otherwise.
                    if let Some((_, v, from)) =
                        known.iter().find(|(n, v, _)| n == "sigma_ln" && *v != 0.0)
                    {
                        let reads = m.inputs.iter().any(|i| i == "sigma_ln")
                            || m.constants.iter().any(|(c, _)| c == "sigma_ln");
                        if !reads {
                            return Err(format!(
                                "sample \"{}\": {from} gives sigma_ln = {v}, but {} has no \
                                 sigma_ln (its runs used the experiment's default, monosized \
                                 spheres); use a model trained at this size spread",
                                s.name, m.label
                            ));
                        }
                    }
                    // A group its fixed inputs already put outside the training range has no
                    // point of the search box inside it: say which, instead of a likelihood
                    // that is zero everywhere.
                    if let Some((g, v, [lo, hi])) = m.groups_fixed_outside(&x).into_iter().next() {
                        return Err(format!(
                            "sample \"{}\": {g} is {v:.4e} from the set's fixed values and the \
                             sample's PSD, outside {}'s range [{lo:.4e}, {hi:.4e}] (its \
                             training runs, and a rigid limit's stiffness lines where it has \
                             one); check \
                             the fixed values it is made of, or build a local model for this \
                             material (`mbgc diagnose --build`)",
                            s.name, m.label
                        ));
                    }
                    Ok(Row {
                        model: mi,
                        x,
                        slots,
                    })
                })();
                match attempt {
                    Ok(row) => {
                        chosen = Some(row);
                        break;
                    }
                    Err(w) => {
                        (names, lower, upper, notes, used_fixed) = saved;
                        reasons.push(format!("{}: {w}", surrogates[mi].label));
                    }
                }
            }
            let Some(row) = chosen else {
                return Err(format!(
                    "no model describes {class} for sample \"{}\" ({}): {}",
                    s.name,
                    s.experiment,
                    if reasons.is_empty() {
                        "no model given".into()
                    } else {
                        reasons.join("; ")
                    }
                ));
            };
            let m = &surrogates[row.model];
            for r in &s.measured {
                let model_response = m.response(&r.response).unwrap_or(0);
                let given = set
                    .model_error
                    .iter()
                    .find(|(n, _)| *n == r.response)
                    .map(|(_, e)| *e);
                let model_error = given.unwrap_or(m.error[model_response]);
                targets.push(Target {
                    sample: si,
                    response: r.response.clone(),
                    model_response,
                    value: r.value,
                    sd: r.sd,
                    model_error,
                    global_error: model_error,
                    error_given: given.is_some(),
                    noise: m.noise[model_response],
                });
            }
            rows.push(row);
        }
        for (n, _) in &set.fixed {
            let constant = rows
                .iter()
                .any(|r| surrogates[r.model].constants.iter().any(|(c, _)| c == n));
            if !used_fixed.contains(n) && !constant {
                return Err(format!(
                    "fixed.{n}: no model used for {class} reads it (a value that would do nothing)"
                ));
            }
        }
        if set.model_error_correlation > 0.0 {
            let mut seen: Vec<usize> = Vec::new();
            for t in &targets {
                let mi = rows[t.sample].model;
                let shared_by = rows.iter().filter(|r| r.model == mi).count();
                if t.noise.is_none() && !t.error_given && shared_by > 1 && !seen.contains(&mi) {
                    seen.push(mi);
                    notes.push(format!(
                        "{} records no replicate noise (`mbgc noise`): its error is taken as \
                         independent between the samples",
                        surrogates[mi].label
                    ));
                }
            }
        }
        // Shared first, per-sample next, the candidate's parameters last: the same order in every
        // class, so that tables line up.
        let mut order: Vec<usize> = (0..names.len()).collect();
        let rank = |j: usize| {
            if effect.is_some_and(|e| owns(e, &names[j])) {
                2
            } else if names[j].contains(" [") {
                1
            } else {
                0
            }
        };
        order.sort_by_key(|&j| (rank(j), j));
        let mut inverse = vec![0; order.len()];
        for (new, &old) in order.iter().enumerate() {
            inverse[old] = new;
        }
        for r in &mut rows {
            for s in &mut r.slots {
                s.1 = inverse[s.1];
            }
        }
        let names: Vec<String> = order.iter().map(|&j| names[j].clone()).collect();
        let lower = order.iter().map(|&j| lower[j]).collect();
        let upper = order.iter().map(|&j| upper[j]).collect();
        let effect_params = (0..names.len())
            .filter(|&j| effect.is_some_and(|e| owns(e, &names[j])))
            .collect();
        let correlation = set.model_error_correlation;
        let cov = covariance(&rows, &targets, correlation);
        Ok(Joint {
            class,
            effect,
            surrogates,
            names,
            lower,
            upper,
            effect_params,
            rows,
            targets,
            notes,
            correlation,
            cov,
        })
    }

    /// Number of searched parameters.
    pub fn dim(&self) -> usize {
        self.names.len()
    }

    fn x(&self, row: &Row, theta: &[f64]) -> Vec<f64> {
        let mut x = row.x.clone();
        for &(k, j) in &row.slots {
            x[k] = theta[j];
        }
        x
    }

    /// Predictions of every target, and the penalty of derived groups outside their range.
    pub fn predictions(&self, theta: &[f64]) -> (Vec<f64>, f64) {
        let xs: Vec<Vec<f64>> = self.rows.iter().map(|r| self.x(r, theta)).collect();
        let outside = self
            .rows
            .iter()
            .zip(&xs)
            .map(|(r, x)| self.surrogates[r.model].outside(x))
            .sum();
        let p = self
            .targets
            .iter()
            .map(|t| {
                let r = &self.rows[t.sample];
                self.surrogates[r.model].predict(t.model_response, &xs[t.sample])
            })
            .collect();
        (p, outside)
    }

    /// Standardised residuals `(measured - predicted) / sigma`.
    pub fn residuals(&self, theta: &[f64]) -> Vec<f64> {
        let (p, _) = self.predictions(theta);
        self.targets
            .iter()
            .zip(p)
            .map(|(t, p)| (t.value - p) / t.sigma())
            .collect()
    }

    fn misses(&self, predicted: &[f64]) -> Vec<f64> {
        self.targets
            .iter()
            .zip(predicted)
            .map(|(t, p)| t.value - p)
            .collect()
    }

    /// `r^T C^-1 r` of the predictions, with `C` the residuals' covariance (measurement sd and
    /// the model error shared between samples); NaN where a prediction is not finite.
    pub fn chi2_of(&self, predicted: &[f64]) -> f64 {
        if predicted.iter().any(|p| !p.is_finite()) {
            return f64::NAN;
        }
        self.cov.chi2(&self.misses(predicted))
    }

    /// chi^2 plus the penalty of groups outside their range; NaN where a prediction is not finite.
    pub fn chi2(&self, theta: &[f64]) -> f64 {
        let (p, outside) = self.predictions(theta);
        self.chi2_of(&p) + PENALTY * outside
    }

    /// Gaussian log-likelihood of the measurements at `theta` (-inf outside a group's range).
    pub fn ln_likelihood(&self, theta: &[f64]) -> f64 {
        let (p, outside) = self.predictions(theta);
        if outside > 0.0 || p.iter().any(|p| !p.is_finite()) {
            return f64::NEG_INFINITY;
        }
        self.cov.ln_likelihood(&self.misses(&p))
    }

    /// Correlation of the z-scores `(measured - predicted) / sigma` between targets.
    pub fn z_correlation(&self) -> &[Vec<f64>] {
        self.cov.z_correlation()
    }

    /// Sets each model error (unless the set gives it) to the model's own error at `theta`, for
    /// models that know how their error varies; returns whether any changed. A fit's intervals
    /// then carry the error of the equations where the material lies, not their average over the
    /// whole space.
    pub fn localise_errors(&mut self, theta: &[f64]) -> bool {
        let mut changed = false;
        for t in 0..self.targets.len() {
            if self.targets[t].error_given {
                continue;
            }
            let row = &self.rows[self.targets[t].sample];
            let x = self.x(row, theta);
            if let Some(e) = self.surrogates[row.model].error_at(self.targets[t].model_response, &x)
            {
                if e.is_finite() && e != self.targets[t].model_error {
                    self.targets[t].model_error = e;
                    changed = true;
                }
            }
        }
        if changed {
            self.cov = covariance(&self.rows, &self.targets, self.correlation);
        }
        changed
    }

    /// Posterior draws as if every model were exact up to its DEM noise: each measured value's
    /// sd alone, no model error. That is what the measurements by themselves allow; beside the
    /// real posterior it says whether the models or the measurements limit the intervals (a
    /// better model helps only in the first case, more or better measurements only in the
    /// second). `Ok(None)` when a value has no sd of its own (the model error was its only
    /// uncertainty, so there is no such limit). The model errors are restored afterwards.
    pub fn exact_model_draws(
        &mut self,
        samples: usize,
        seed: u64,
    ) -> Result<Option<Vec<Vec<f64>>>, String> {
        if self.dim() == 0 || self.targets.iter().any(|t| t.sd.is_nan() || t.sd <= 0.0) {
            return Ok(None);
        }
        let kept: Vec<(f64, bool)> = self
            .targets
            .iter()
            .map(|t| (t.model_error, t.error_given))
            .collect();
        for t in &mut self.targets {
            t.model_error = 0.0;
            t.error_given = true;
        }
        self.cov = covariance(&self.rows, &self.targets, self.correlation);
        let ev = self.evidence(samples, seed);
        for (t, (e, g)) in self.targets.iter_mut().zip(kept) {
            t.model_error = e;
            t.error_given = g;
        }
        self.cov = covariance(&self.rows, &self.targets, self.correlation);
        ev.map(|e| Some(e.draws))
    }

    /// Degrees of freedom: measurements minus searched parameters.
    pub fn dof(&self) -> isize {
        self.targets.len() as isize - self.dim() as isize
    }

    /// The best fit over `n_starts` L-BFGS runs from scrambled Sobol points.
    pub fn fit(&self, n_starts: usize, seed: u64) -> Fit {
        if self.dim() == 0 {
            return Fit {
                theta: Vec::new(),
                chi2: self.chi2(&[]),
            };
        }
        let best = starts(self.dim(), n_starts.max(1), seed)
            .par_iter()
            .filter_map(|u0| minimize(self, u0, 200))
            .map(|theta| Fit {
                chi2: self.chi2(&theta),
                theta,
            })
            .filter(|f| f.chi2.is_finite())
            .min_by(|a, b| a.chi2.total_cmp(&b.chi2));
        best.unwrap_or_else(|| {
            let mid: Vec<f64> = self
                .lower
                .iter()
                .zip(&self.upper)
                .map(|(a, b)| 0.5 * (a + b))
                .collect();
            Fit {
                chi2: self.chi2(&mid),
                theta: mid,
            }
        })
    }

    /// TMCMC over the uniform prior on the search box: the log-evidence and the posterior draws.
    pub fn evidence(&self, samples: usize, seed: u64) -> Result<Evidence, String> {
        if self.dim() == 0 {
            return Ok(Evidence {
                ln_evidence: self.ln_likelihood(&[]),
                draws: Vec::new(),
            });
        }
        let prior = UniformBox::new(self.lower.clone(), self.upper.clone())?;
        let opts = TmcmcOptions {
            samples,
            seed,
            burn_in: 10,
            ..TmcmcOptions::default()
        };
        let r = tmcmc(&prior, |th| self.ln_likelihood(th), &opts)?;
        Ok(Evidence {
            ln_evidence: r.ln_evidence,
            draws: r.samples,
        })
    }
}

fn covariance(rows: &[Row], targets: &[Target], rho: f64) -> Covariance {
    let entries: Vec<Entry> = targets
        .iter()
        .map(|t| Entry {
            sd: t.sd,
            model_error: t.own_error(),
            shared: t.shared_error(),
            group: (rows[t.sample].model, t.model_response),
        })
        .collect();
    Covariance::new(&entries, rho)
}

/// The best joint fit found by the L-BFGS starts.
#[derive(Clone, Debug)]
pub struct Fit {
    /// Searched parameter values at the best fit, in `names` order.
    pub theta: Vec<f64>,
    /// Sum of squared standardised residuals at `theta`.
    pub chi2: f64,
}

/// TMCMC's evidence estimate and posterior draws.
pub struct Evidence {
    /// Natural log of the model evidence (marginal likelihood) under the uniform prior on the
    /// bounds.
    pub ln_evidence: f64,
    /// Posterior draws of theta, one `Vec` per draw, in `names` order.
    pub draws: Vec<Vec<f64>>,
}

impl Objective for Joint<'_> {
    fn lower(&self) -> &[f64] {
        &self.lower
    }
    fn upper(&self) -> &[f64] {
        &self.upper
    }
    fn objective(&self, x: &[f64]) -> Option<(f64, Vec<f64>)> {
        let f = self.chi2(x);
        if !f.is_finite() {
            return None;
        }
        // Central differences: a few searched parameters and microsecond predictions.
        let mut g = vec![0.0; x.len()];
        let mut y = x.to_vec();
        for j in 0..x.len() {
            let h = 1e-6 * (self.upper[j] - self.lower[j]);
            let (lo, hi) = ((x[j] - h).max(self.lower[j]), (x[j] + h).min(self.upper[j]));
            y[j] = hi;
            let fp = self.chi2(&y);
            y[j] = lo;
            let fm = self.chi2(&y);
            y[j] = x[j];
            if !(fp.is_finite() && fm.is_finite()) || hi <= lo {
                return None;
            }
            g[j] = (fp - fm) / (hi - lo);
        }
        Some((f, g))
    }
}
