//! The diagnosis of a measurement set: the joint calibration under the set's model class, where
//! its residuals are structured, and for each candidate effect how much of the misfit it
//! explains once its strength is fitted jointly (chi^2/dof, the Bayes factor from TMCMC
//! evidences, the structure left), ranked, with a verdict.

use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::joint::Joint;
use super::measurements::{switchable_effects, MeasurementSet};
use super::structure::{self, Point, Test};
use super::surrogate::Surrogate;
use crate::error::{Error, Result};

/// Settings of a diagnosis: fit starts, TMCMC samples, seed and test level.
#[derive(Clone, Debug)]
pub struct Options {
    /// L-BFGS starts of each joint fit.
    pub starts: usize,
    /// TMCMC samples per stage (evidence and posterior).
    pub samples: usize,
    /// Seed of the fit starts and of TMCMC; the same seed gives the same diagnosis.
    pub seed: u64,
    /// Family-wise level of the structure tests and of the chi^2 test.
    pub alpha: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            starts: 16,
            samples: 2000,
            seed: 1,
            alpha: 0.01,
        }
    }
}

impl Options {
    /// Refuses settings a diagnosis cannot run with, naming the option and what it takes.
    pub fn check(&self) -> Result<()> {
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            return Err(Error::invalid(format!(
                "--alpha: expected a level between 0 and 1, got {}",
                self.alpha
            )));
        }
        let max = crate::calibrate::tmcmc::MAX_SAMPLES;
        if !(100..=max).contains(&self.samples) {
            return Err(Error::invalid(format!(
                "--samples: expected 100 to {max} TMCMC samples per stage, got {}",
                self.samples
            )));
        }
        let max_starts = crate::calibrate::session::MAX_STARTS;
        if self.starts == 0 || self.starts > max_starts {
            return Err(Error::invalid(format!(
                "--starts {}: expected 1 to {max_starts}",
                self.starts
            )));
        }
        Ok(())
    }
}

/// ln 10: a Bayes factor of 10, "strong" evidence on Jeffreys' scale.
pub const STRONG: f64 = std::f64::consts::LN_10;

/// One searched parameter of a joint fit: best fit and posterior summary.
#[derive(Clone, Debug, Serialize)]
pub struct Parameter {
    /// Parameter name, as in the models.
    pub name: String,
    /// At the best fit.
    pub best: f64,
    /// Mean of the TMCMC posterior draws.
    pub posterior_mean: f64,
    /// 5 % quantile of the posterior draws (lower end of the 90 % interval).
    pub q05: f64,
    /// 95 % quantile of the posterior draws (upper end of the 90 % interval).
    pub q95: f64,
    /// `"upper"` or `"lower"` when the best fit lies where the models' data end (a group's
    /// training range, a model's limit or the search range): the posterior is cut there and the
    /// truth may lie beyond.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at_edge: Option<String>,
    /// The 90 % interval with every model's error taken as zero (each measured value's sd
    /// alone): how wide the measurements by themselves allow it to be. Much narrower than
    /// `[q05, q95]`: the models limit the answer; about as wide: the measurements do. Only its
    /// width means something, since it still rests on the models' predictions. `None` when a
    /// value has no sd of its own.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exact_models: Option<[f64; 2]>,
}

/// One measurement against the model's prediction at the best fit.
#[derive(Clone, Debug, Serialize)]
pub struct Residual {
    /// Sample name.
    pub sample: String,
    /// Response name (e.g. `shear_angle`).
    pub response: String,
    /// Measured value, in the response's unit.
    pub measured: f64,
    /// Model prediction at the best fit, in the response's unit.
    pub predicted: f64,
    /// Measurement standard deviation, in the response's unit.
    pub sd: f64,
    /// sd and model error together.
    pub sigma: f64,
    /// (measured - predicted) / sigma.
    pub z: f64,
}

/// How well the fit matches one sample, with the sample's PSD for plotting trends.
#[derive(Clone, Debug, Serialize)]
pub struct SampleError {
    /// Sample name.
    pub sample: String,
    /// Mass median particle size of the sample, mm, when known.
    pub d50: Option<f64>,
    /// Log-normal width sigma_ln of the sample's PSD, when known.
    pub sigma_ln: Option<f64>,
    /// Root mean square of its standardised residuals.
    pub rms_z: f64,
}

/// The misfit of one response over all samples.
#[derive(Clone, Debug, Serialize)]
pub struct ResponseError {
    /// Response name.
    pub response: String,
    /// Root mean square of measured minus predicted over the samples, in the response's unit.
    pub rmse: f64,
}

/// One model class fitted to the whole set.
#[derive(Clone, Debug, Serialize)]
pub struct ClassFit {
    /// The model class fitted, as effect names.
    pub class: String,
    /// The effect added to the set's class (None: the set's class itself).
    pub effect: Option<String>,
    /// Which model each sample uses, and what was decided on the user's behalf.
    pub notes: Vec<String>,
    /// The models used, each once.
    pub models: Vec<String>,
    /// The searched parameters of the joint fit, in the joint problem's order.
    pub parameters: Vec<Parameter>,
    /// chi^2 at the best fit: `r^T C^-1 r`, C the covariance of measured minus predicted.
    pub chi2: f64,
    /// Degrees of freedom: measurements minus searched parameters (may be <= 0).
    pub dof: isize,
    /// chi^2 / dof; near 1 when the class explains the data within their uncertainty (NaN for
    /// dof <= 0).
    pub chi2_dof: f64,
    /// P(chi^2 >= observed) under the class; NaN without degrees of freedom.
    pub p_value: f64,
    /// Natural log of the model evidence estimated by TMCMC; differences between classes are log
    /// Bayes factors.
    pub ln_evidence: f64,
    /// Every measurement's residual at the best fit.
    pub residuals: Vec<Residual>,
    /// Per sample: the RMS standardised residual.
    pub samples: Vec<SampleError>,
    /// Per response: the RMS residual in the response's unit.
    pub rmse: Vec<ResponseError>,
    /// Every structure test of the residuals (offsets and trends in d50 and sigma_ln).
    pub structure: Vec<Test>,
    /// Tests significant at the family-wise level.
    pub structured: Vec<Test>,
}

/// A candidate effect and how much of the misfit it explains.
#[derive(Clone, Debug, Serialize)]
pub struct Ranked {
    /// Name of the candidate effect added to the set's class.
    pub effect: String,
    /// chi^2 / dof of the joint fit with the effect.
    pub chi2_dof_after: f64,
    /// P(chi^2 >= observed) with the effect; NaN without degrees of freedom.
    pub p_value_after: f64,
    /// ln(evidence with the effect / evidence without).
    pub log_bayes_factor: f64,
    /// chi^2 without the effect over chi^2 with it.
    pub chi2_ratio: f64,
    /// Whether significant structure is left in the residuals with the effect.
    pub structure_left: bool,
    /// The effect's parameters: best fit and 90 % posterior interval.
    pub strength: Vec<Parameter>,
}

/// A candidate effect that could not be evaluated, with the reason.
#[derive(Clone, Debug, Serialize)]
pub struct Unavailable {
    /// Name of the effect.
    pub effect: String,
    /// Why it was not evaluated (e.g. no model for its class, or all its parameters fixed).
    pub reason: String,
}

/// The result of `mbgc diagnose`: the fit under the set's class, the candidate effects ranked
/// by log Bayes factor (then chi^2/dof), and a verdict.
#[derive(Clone, Debug, Serialize)]
pub struct Diagnosis {
    /// Name of the measurement set.
    pub set: String,
    /// The set's own model class.
    pub class: String,
    /// Number of measured values fitted.
    pub measurements: usize,
    /// chi^2 / dof of the set's own class (same as `base.chi2_dof`).
    pub chi2_dof: f64,
    /// P(chi^2 >= observed) under the set's own class.
    pub p_value: f64,
    /// The full fit under the set's own class.
    pub base: ClassFit,
    /// Candidates that could be evaluated, best first.
    pub ranking: Vec<Ranked>,
    /// Candidates that could not be evaluated, with reasons.
    pub unavailable: Vec<Unavailable>,
    /// The fits with each ranked effect, in ranking order (the error ladder: base, then these).
    pub extended: Vec<ClassFit>,
    /// One-sentence conclusion: consistent, explained by an effect, or helped but not explained.
    pub verdict: String,
    /// The options the diagnosis ran with, for reproducing it.
    pub settings: Settings,
}

/// The [`Options`] a diagnosis ran with, as written to its report.
#[derive(Clone, Debug, Serialize)]
pub struct Settings {
    /// L-BFGS starts of each joint fit.
    pub starts: usize,
    /// TMCMC samples per stage.
    pub samples: usize,
    /// Seed of the fit starts and of TMCMC.
    pub seed: u64,
    /// Family-wise level of the structure tests and of the chi^2 test.
    pub alpha: f64,
}

fn p_value(chi2: f64, dof: isize) -> f64 {
    if dof <= 0 {
        return f64::NAN;
    }
    ChiSquared::new(dof as f64).map_or(f64::NAN, |d| 1.0 - d.cdf(chi2))
}

/// Whether a small step of parameter `k` from the best fit `theta` (where the models' penalty
/// for leaving their data is `inside`) leaves the search range or the models' data (a group
/// beyond its training range, a model's limit): `"upper"`, `"lower"` or `None`.
fn edge(j: &Joint, theta: &[f64], inside: f64, k: usize) -> Option<String> {
    let step = 1e-3 * (j.upper[k] - j.lower[k]);
    for (dir, name) in [(1.0, "upper"), (-1.0, "lower")] {
        let mut t = theta.to_vec();
        t[k] += dir * step;
        let beyond = t[k] > j.upper[k] || t[k] < j.lower[k] || j.predictions(&t).1 > inside;
        if beyond {
            return Some(name.to_string());
        }
    }
    None
}

fn class_fit(set: &MeasurementSet, j: &mut Joint, opts: &Options) -> Result<ClassFit> {
    let mut fit = j.fit(opts.starts, opts.seed);
    // The models' error where the material lies, then the fit again with it.
    let global: Vec<f64> = j.targets.iter().map(|t| t.model_error).collect();
    let own = |t: &super::joint::Target| t.own_error();
    if j.localise_errors(&fit.theta) {
        fit = j.fit(opts.starts, opts.seed);
        let mut seen: Vec<&str> = Vec::new();
        let mut notes = Vec::new();
        for t in &j.targets {
            if seen.contains(&t.response.as_str()) {
                continue;
            }
            seen.push(&t.response);
            let (mut local, mut avg) = (Vec::new(), Vec::new());
            for (u, g) in j.targets.iter().zip(&global) {
                if u.response == t.response {
                    local.push(own(u));
                    avg.push(*g);
                }
            }
            let lo = local.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = local.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            notes.push(format!(
                "{}: the model's own error at the first best fit, {} (its validation RMSE {:.4})",
                t.response,
                if (hi - lo).abs() <= 1e-12 * hi.abs() {
                    format!("{lo:.4}")
                } else {
                    format!("{lo:.4} to {hi:.4} over the samples")
                },
                avg.iter().sum::<f64>() / avg.len() as f64
            ));
        }
        j.notes.extend(notes);
    }
    // A class that misfits badly is hardest to sample without model errors; the fit stands
    // without this comparison.
    let exact = match j.exact_model_draws(opts.samples, opts.seed) {
        Ok(d) => d,
        Err(e) => {
            j.notes.push(format!(
                "the intervals with exact models could not be sampled (TMCMC: {e})"
            ));
            None
        }
    };
    let j = &*j;
    let ev = j
        .evidence(opts.samples, opts.seed)
        .map_err(|e| Error::invalid(format!("TMCMC of {}: {e}", j.class)))?;
    let sorted = |draws: &[Vec<f64>], k: usize| {
        let mut v: Vec<f64> = draws.iter().map(|d| d[k]).collect();
        v.sort_by(f64::total_cmp);
        v
    };
    let (pred, inside) = j.predictions(&fit.theta);
    let parameters = j
        .names
        .iter()
        .enumerate()
        .map(|(k, n)| {
            let v = sorted(&ev.draws, k);
            let q = |p: f64| crate::numeric::quantile_sorted(&v, p);
            let exact_models = exact.as_ref().map(|d| {
                let e = sorted(d, k);
                [
                    crate::numeric::quantile_sorted(&e, 0.05),
                    crate::numeric::quantile_sorted(&e, 0.95),
                ]
            });
            Parameter {
                name: n.clone(),
                best: fit.theta[k],
                posterior_mean: v.iter().sum::<f64>() / v.len().max(1) as f64,
                q05: q(0.05),
                q95: q(0.95),
                at_edge: edge(j, &fit.theta, inside, k),
                exact_models,
            }
        })
        .collect();
    let residuals: Vec<Residual> = j
        .targets
        .iter()
        .zip(&pred)
        .map(|(t, p)| Residual {
            sample: set.samples[t.sample].name.clone(),
            response: t.response.clone(),
            measured: t.value,
            predicted: *p,
            sd: t.sd,
            sigma: t.sigma(),
            z: (t.value - p) / t.sigma(),
        })
        .collect();
    let psd: Vec<Option<(f64, f64)>> = set
        .samples
        .iter()
        .map(|s| {
            s.psd
                .as_ref()
                .and_then(|p| p.parameters().ok())
                .or_else(|| {
                    let get = |n: &str| {
                        s.fixed
                            .iter()
                            .chain(&set.fixed)
                            .find(|(k, _)| k == n)
                            .map(|(_, v)| *v)
                    };
                    get("d50").zip(get("sigma_ln"))
                })
        })
        .collect();
    let samples = set
        .samples
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let z: Vec<f64> = j
                .targets
                .iter()
                .zip(&residuals)
                .filter(|(t, _)| t.sample == i)
                .map(|(_, r)| r.z)
                .collect();
            SampleError {
                sample: s.name.clone(),
                d50: psd[i].map(|p| p.0),
                sigma_ln: psd[i].map(|p| p.1),
                rms_z: (z.iter().map(|z| z * z).sum::<f64>() / z.len().max(1) as f64).sqrt(),
            }
        })
        .collect();
    let mut rmse: Vec<ResponseError> = Vec::new();
    for r in &residuals {
        if !rmse.iter().any(|e| e.response == r.response) {
            let d: Vec<f64> = residuals
                .iter()
                .filter(|q| q.response == r.response)
                .map(|q| q.measured - q.predicted)
                .collect();
            rmse.push(ResponseError {
                response: r.response.clone(),
                rmse: (d.iter().map(|d| d * d).sum::<f64>() / d.len() as f64).sqrt(),
            });
        }
    }
    let points: Vec<Point> = j
        .targets
        .iter()
        .zip(&residuals)
        .map(|(t, r)| Point {
            response: t.response.clone(),
            experiment: set.samples[t.sample].experiment.clone(),
            d50: psd[t.sample].map(|p| p.0),
            sigma_ln: psd[t.sample].map(|p| p.1),
            z: r.z,
        })
        .collect();
    let tests = structure::tests(&points, j.z_correlation());
    let structured = structure::significant(&tests, opts.alpha)
        .into_iter()
        .cloned()
        .collect();
    // With the model error shared between samples, chi^2 is r^T C^-1 r, not the sum of z^2.
    let chi2 = j.chi2_of(&pred);
    let dof = j.dof();
    Ok(ClassFit {
        class: j.class.to_string(),
        effect: j.effect.map(|e| e.name.to_string()),
        notes: j.notes.clone(),
        models: j.models(),
        parameters,
        chi2,
        dof,
        chi2_dof: if dof > 0 { chi2 / dof as f64 } else { f64::NAN },
        p_value: p_value(chi2, dof),
        ln_evidence: ev.ln_evidence,
        residuals,
        samples,
        rmse,
        structure: tests,
        structured,
    })
}

/// Runs the diagnosis of `set` against the models.
pub fn diagnose(set: &MeasurementSet, models: &[Surrogate], opts: &Options) -> Result<Diagnosis> {
    let mut base_joint = Joint::new(set, models, None).map_err(|e| {
        Error::input(
            &set.source,
            "model.class",
            format!("a model for the set's class: {e}"),
        )
    })?;
    if base_joint.dof() < 0 {
        return Err(Error::input(
            &set.source,
            "sample",
            format!(
                "at least as many measurements as searched parameters: {} measurements, {} searched \
                 ({}); fix known values or measure more",
                base_joint.targets.len(),
                base_joint.dim(),
                base_joint.names.join(", ")
            ),
        ));
    }
    let base = class_fit(set, &mut base_joint, opts)?;
    let mut effects = switchable_effects(&set.class);
    for c in &set.candidates {
        if !effects.iter().any(|e| e.name == c.effect.name) {
            effects.push(c.effect);
        }
    }
    let mut ranked: Vec<(Ranked, ClassFit)> = Vec::new();
    let mut unavailable = Vec::new();
    for e in effects {
        let settings = set.candidate(e);
        let mut j = match Joint::new(set, models, Some(&settings)) {
            Ok(j) => j,
            Err(reason) => {
                unavailable.push(Unavailable {
                    effect: e.name.to_string(),
                    reason,
                });
                continue;
            }
        };
        if j.effect_params.is_empty() {
            unavailable.push(Unavailable {
                effect: e.name.to_string(),
                reason: "every parameter of it is fixed: nothing to fit".into(),
            });
            continue;
        }
        let fit = class_fit(set, &mut j, opts)?;
        let strength = j
            .effect_params
            .iter()
            .map(|&k| fit.parameters[k].clone())
            .collect();
        ranked.push((
            Ranked {
                effect: e.name.to_string(),
                chi2_dof_after: fit.chi2_dof,
                p_value_after: fit.p_value,
                log_bayes_factor: fit.ln_evidence - base.ln_evidence,
                chi2_ratio: base.chi2 / fit.chi2,
                structure_left: !fit.structured.is_empty(),
                strength,
            },
            fit,
        ));
    }
    ranked.sort_by(|a, b| {
        b.0.log_bayes_factor
            .total_cmp(&a.0.log_bayes_factor)
            .then(a.0.chi2_dof_after.total_cmp(&b.0.chi2_dof_after))
    });
    // Without degrees of freedom (p NaN) the chi^2 test cannot reject.
    let consistent = not_rejected(base.p_value, opts.alpha) && base.structured.is_empty();
    let limit = models_limit(set, &base, ranked.first().map(|(r, f)| (r, f)));
    let mut verdict = verdict(
        &base,
        consistent,
        ranked.first().map(|r| &r.0),
        &unavailable,
        opts.alpha,
        limit.is_some(),
    );
    if let Some(tie) = inseparable(&base, &ranked, opts.alpha) {
        verdict = format!("{tie}; {verdict}");
    }
    if let Some(limit) = limit {
        verdict.push_str(&limit);
    }
    Ok(Diagnosis {
        set: set.name.clone(),
        class: set.class.to_string(),
        measurements: set.measurements(),
        chi2_dof: base.chi2_dof,
        p_value: base.p_value,
        base,
        ranking: ranked.iter().map(|r| r.0.clone()).collect(),
        extended: ranked.into_iter().map(|r| r.1).collect(),
        unavailable,
        verdict,
        settings: Settings {
            starts: opts.starts,
            samples: opts.samples,
            seed: opts.seed,
            alpha: opts.alpha,
        },
    })
}

/// Two candidates that both explain the data, with evidence within a factor of 10 of each other:
/// these measurements cannot tell them apart, and choosing the first would be a guess. Said with
/// the correlation of the corrections the two fits make to the base fit's predictions (in units
/// of each measurement's sigma): near 1, the effects move every measurement alike.
fn inseparable(base: &ClassFit, ranked: &[(Ranked, ClassFit)], alpha: f64) -> Option<String> {
    let explains = |r: &Ranked| {
        r.log_bayes_factor > STRONG && not_rejected(r.p_value_after, alpha) && !r.structure_left
    };
    let [(a, fa), (b, fb), ..] = ranked else {
        return None;
    };
    if !(explains(a) && explains(b) && a.log_bayes_factor - b.log_bayes_factor < STRONG) {
        return None;
    }
    let shift = |f: &ClassFit| -> Vec<f64> {
        f.residuals
            .iter()
            .zip(&base.residuals)
            .map(|(r, r0)| (r.predicted - r0.predicted) / r0.sigma)
            .collect()
    };
    let r = crate::numeric::correlation(&shift(fa), &shift(fb));
    Some(format!(
        "{} and {} both explain it and these data cannot separate them (ln Bayes factors {:.1} \
         and {:.1}, within ln 10; the corrections they make to the predictions correlate at r = \
         {:.2}): a measurement that responds to one and not the other would decide",
        a.effect, b.effect, a.log_bayes_factor, b.log_bayes_factor, r
    ))
}

/// Where no candidate reaches a Bayes factor of 10 and the models' own error exceeds the
/// measurements' sd, the models, not the measurements, cap the evidence: a candidate that
/// removes most of the misfit is then penalised for the error of its model as much as it is
/// rewarded for the fit. Said with the numbers (median over the samples, per response, at each
/// class's best fit), so the user knows which to improve. `None` when a candidate is strong,
/// the models are more precise than the measurements, or the set states their error itself
/// (`[model_error]`: no model built would change it).
fn models_limit(
    set: &MeasurementSet,
    base: &ClassFit,
    best: Option<(&Ranked, &ClassFit)>,
) -> Option<String> {
    let (ranked, fit) = best?;
    let parts = precision_limit(set, None, base, ranked, fit)?;
    let mut models: Vec<&str> = Vec::new();
    for m in base.models.iter().chain(&fit.models) {
        if !models.contains(&m.as_str()) {
            models.push(m);
        }
    }
    Some(format!(
        "; the models, not the measurements, limit this verdict: their own error (the set's \
         class and {} at their best fits, median over the samples) exceeds the measurements' \
         sd: {parts}. An effect that moves the responses by less than that goes unseen ({} \
         lowers chi^2 {:.1}-fold, ln Bayes factor {:.1}); models as precise as the \
         measurements around this material would tell (`mbgc diagnose --model {} --build {}` \
         builds them; where they are such local models already, a larger `--budget-runs` \
         extends them)",
        ranked.effect,
        ranked.effect,
        ranked.chi2_ratio,
        ranked.log_bayes_factor,
        models.join(" --model "),
        ranked.effect
    ))
}

/// Whether the models, not the measurements, limit `d`, the diagnosis of `set`, in the samples
/// of `experiment` (all when `None`): no candidate reaches a Bayes factor of 10, and a model's
/// own error at its best fit exceeds the measurements' sd in a response whose error the set
/// does not state itself. Per response, the set's class's and the best candidate's own errors
/// against the sd. `None`: they do not.
pub fn limited_by_models(
    d: &Diagnosis,
    set: &MeasurementSet,
    experiment: Option<&str>,
) -> Option<String> {
    precision_limit(
        set,
        experiment,
        &d.base,
        d.ranking.first()?,
        d.extended.first()?,
    )
}

fn precision_limit(
    set: &MeasurementSet,
    experiment: Option<&str>,
    base: &ClassFit,
    ranked: &Ranked,
    fit: &ClassFit,
) -> Option<String> {
    if ranked.log_bayes_factor > STRONG {
        return None;
    }
    let keep = |r: &Residual| {
        !set.model_error.iter().any(|(n, _)| *n == r.response)
            && experiment.is_none_or(|e| {
                set.samples
                    .iter()
                    .any(|s| s.name == r.sample && s.experiment == e)
            })
    };
    let median = |mut v: Vec<f64>| -> f64 {
        v.sort_by(f64::total_cmp);
        match v.len() {
            0 => f64::NAN,
            n if n % 2 == 1 => v[n / 2],
            n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
        }
    };
    let own = |f: &ClassFit, response: &str| {
        median(
            f.residuals
                .iter()
                .filter(|r| r.response == response && keep(r))
                .map(|r| (r.sigma * r.sigma - r.sd * r.sd).max(0.0).sqrt())
                .collect(),
        )
    };
    let mut responses: Vec<&str> = Vec::new();
    for r in base.residuals.iter().filter(|r| keep(r)) {
        if !responses.contains(&r.response.as_str()) {
            responses.push(&r.response);
        }
    }
    let mut parts = Vec::new();
    let mut limited = false;
    for resp in responses {
        let sd = median(
            base.residuals
                .iter()
                .filter(|r| r.response == resp && keep(r))
                .map(|r| r.sd)
                .collect(),
        );
        let (e0, e1) = (own(base, resp), own(fit, resp));
        limited |= e0 > sd || e1 > sd;
        parts.push(format!(
            "{resp} {e0:.3} and {e1:.3} against an sd of {sd:.3}"
        ));
    }
    limited.then(|| parts.join("; "))
}

fn not_rejected(p: f64, alpha: f64) -> bool {
    p.is_nan() || p >= alpha
}

fn verdict(
    base: &ClassFit,
    consistent: bool,
    best: Option<&Ranked>,
    untested: &[Unavailable],
    alpha: f64,
    models_limit: bool,
) -> String {
    let strong = best.filter(|b| b.log_bayes_factor > STRONG);
    let main = verdict_without_caveat(base, consistent, best, strong, alpha, models_limit);
    // A candidate no model could evaluate is a caveat of every verdict, never silently dropped:
    // it might have explained the data as well or better.
    let (lacking, other): (Vec<&Unavailable>, Vec<&Unavailable>) = untested
        .iter()
        .partition(|u| u.reason.starts_with("no model describes"));
    let names = |v: &[&Unavailable]| {
        v.iter()
            .map(|u| u.effect.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut v = main;
    if !lacking.is_empty() {
        v.push_str(&format!(
            "; not evaluated for want of a model: {} (build a local one around this material \
             with `mbgc diagnose --build {}`, or a global one with `mbgc train --extends <model \
             file or name>`)",
            names(&lacking),
            lacking
                .iter()
                .map(|u| u.effect.as_str())
                .collect::<Vec<_>>()
                .join(",")
        ));
    }
    if !other.is_empty() {
        v.push_str(&format!(
            "; not evaluated: {} (every parameter of it fixed)",
            names(&other)
        ));
    }
    // A strength at the end of what the models cover is cut there, not measured: say so.
    if let Some(b) = best.filter(|b| b.log_bayes_factor > 0.0) {
        let cut: Vec<String> = b
            .strength
            .iter()
            .filter(|p| p.at_edge.as_deref() == Some("upper"))
            .map(|p| format!("{} = {:.4e}", p.name, p.best))
            .collect();
        if !cut.is_empty() {
            v.push_str(&format!(
                "; {}'s best fit {} lies at the upper end of what the models cover, so its \
                 interval is cut there and the truth may lie beyond (a model over a wider range \
                 would tell: with `[candidates.{}] bounds` reaching beyond it, `mbgc diagnose \
                 --model {} --build {}` builds one around this material)",
                b.effect,
                cut.join(", "),
                b.effect,
                base.models.join(" --model "),
                b.effect
            ));
        }
    }
    v
}

fn verdict_without_caveat(
    base: &ClassFit,
    consistent: bool,
    best: Option<&Ranked>,
    strong: Option<&Ranked>,
    alpha: f64,
    models_limit: bool,
) -> String {
    match (consistent, strong) {
        (true, None) => format!(
            "consistent, no effect needed: chi^2/dof {:.2} (p = {:.3}), no structure in the \
             residuals at the {alpha} level, and no candidate has a Bayes factor above 10",
            base.chi2_dof, base.p_value
        ),
        (_, Some(b)) if not_rejected(b.p_value_after, alpha) && !b.structure_left => format!(
            "{} explains it: chi^2/dof {:.2} -> {:.2}, ln Bayes factor {:.1}, no structure left",
            b.effect, base.chi2_dof, b.chi2_dof_after, b.log_bayes_factor
        ),
        (_, Some(b)) => format!(
            "{} helps most but does not explain everything: chi^2/dof {:.2} -> {:.2} (p = {:.2e}), \
             ln Bayes factor {:.1}{}",
            b.effect,
            base.chi2_dof,
            b.chi2_dof_after,
            b.p_value_after,
            b.log_bayes_factor,
            if b.structure_left { ", structure left in the residuals" } else { "" }
        ),
        // The misfit is real and a candidate removes it, but the data cannot yet tell the
        // extended class from the base decisively: say so rather than "none explains it".
        (false, None) => {
            match best.filter(|b| {
                b.log_bayes_factor > 0.0
                    && not_rejected(b.p_value_after, alpha)
                    && !b.structure_left
            }) {
                Some(b) => format!(
                "inconsistent (chi^2/dof {:.2}, p = {:.2e}{}); {} removes the misfit (chi^2/dof \
                 -> {:.2}, no structure left) but the evidence for it is weak (ln Bayes factor \
                 {:.1}, below ln 10){}",
                base.chi2_dof,
                base.p_value,
                if base.structured.is_empty() { "" } else { ", structured residuals" },
                b.effect,
                b.chi2_dof_after,
                b.log_bayes_factor,
                // Where the models limit it, the caveat that follows says what would decide.
                if models_limit { "" } else { ": more samples or repeats would decide" }
            ),
                None => format!(
                    "inconsistent (chi^2/dof {:.2}, p = {:.2e}{}) and none of the evaluated \
                 candidates explains it",
                    base.chi2_dof,
                    base.p_value,
                    if base.structured.is_empty() {
                        ""
                    } else {
                        ", structured residuals"
                    },
                ),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fit(predicted: &[f64]) -> ClassFit {
        ClassFit {
            class: "c".into(),
            effect: None,
            notes: vec![],
            models: vec![],
            parameters: vec![],
            chi2: 1.0,
            dof: 1,
            chi2_dof: 1.0,
            p_value: 0.5,
            ln_evidence: 0.0,
            residuals: predicted
                .iter()
                .map(|&p| Residual {
                    sample: "s".into(),
                    response: "shear_angle".into(),
                    measured: 0.0,
                    predicted: p,
                    sd: 1.0,
                    sigma: 1.0,
                    z: -p,
                })
                .collect(),
            samples: vec![],
            rmse: vec![],
            structure: vec![],
            structured: vec![],
        }
    }

    fn limited_by_models_in(
        set: &MeasurementSet,
        experiment: Option<&str>,
        base: &ClassFit,
        ranked: &Ranked,
        fit: &ClassFit,
    ) -> Option<String> {
        precision_limit(set, experiment, base, ranked, fit)
    }

    fn ranked(effect: &str, ln_bf: f64, p: f64) -> Ranked {
        Ranked {
            effect: effect.into(),
            chi2_dof_after: 1.0,
            p_value_after: p,
            log_bayes_factor: ln_bf,
            chi2_ratio: 10.0,
            structure_left: false,
            strength: vec![],
        }
    }

    /// A weak candidate with models less precise than the measurements: the verdict says the
    /// models limit it, with each response's own errors and sd; precise models or a strong
    /// candidate: nothing said.
    #[test]
    fn models_less_precise_than_the_measurements_are_named_as_the_limit() {
        let with_error = |model_error: f64| {
            let mut f = fit(&[0.0, 0.0]);
            for r in &mut f.residuals {
                r.sd = 1.0;
                r.sigma = 1f64.hypot(model_error);
            }
            f
        };
        let set = |extra: &str| {
            MeasurementSet::from_toml_str(
                &format!(
                    "name = \"t\"\n{extra}[model]\nclass = \"hertz,mindlin,epsd2\"\n\
                     [[sample]]\nname = \"s\"\nexperiment = \"shear-box\"\n\
                     psd = {{ d50_mm = 2, sigma_ln = 0.12 }}\n\
                     measured.shear_angle = {{ value = 30, sd = 1 }}\n"
                ),
                "t.toml",
            )
            .unwrap()
        };
        let plain = set("");
        let weak = ranked("sjkr", -1.5, 0.5);
        let text = models_limit(&plain, &with_error(2.0), Some((&weak, &with_error(3.0)))).unwrap();
        assert!(
            text.contains("limit this verdict")
                && text.contains("shear_angle 2.000 and 3.000 against an sd of 1.000"),
            "{text}"
        );
        assert!(
            text.contains("10.0-fold") && text.contains("-1.5"),
            "{text}"
        );
        assert!(models_limit(&plain, &with_error(0.5), Some((&weak, &with_error(0.8)))).is_none());
        let strong = ranked("sjkr", 3.0, 0.5);
        assert!(
            models_limit(&plain, &with_error(2.0), Some((&strong, &with_error(3.0)))).is_none()
        );
        assert!(models_limit(&plain, &with_error(2.0), None).is_none());
        // The set states the models' error itself: no model built would change it.
        let stated = set("[model_error]\nshear_angle = 2.0\n");
        assert!(models_limit(&stated, &with_error(2.0), Some((&weak, &with_error(3.0)))).is_none());
        // Samples of another experiment only: nothing limits this one.
        assert!(limited_by_models_in(
            &plain,
            Some("hopper"),
            &with_error(2.0),
            &weak,
            &with_error(3.0)
        )
        .is_none());
    }

    /// Two effects that both explain the data within a factor 10 of evidence are named together
    /// with the correlation of their corrections; a decisive gap or a rival that fails is not a
    /// tie.
    #[test]
    fn effects_the_data_cannot_separate_are_named_together() {
        let base = fit(&[0.0, 0.0, 0.0, 0.0]);
        let a = fit(&[1.0, 2.0, 3.0, 4.0]);
        let b = fit(&[1.5, 1.6, 3.9, 3.8]);
        let tie = [
            (ranked("sjkr", 9.0, 0.5), a.clone()),
            (ranked("epsd2", 8.0, 0.4), b.clone()),
        ];
        let text = inseparable(&base, &tie, 0.01).unwrap();
        assert!(
            text.starts_with("sjkr and epsd2 both explain it") && text.contains("r = 0.89"),
            "{text}"
        );
        let decisive = [
            (ranked("sjkr", 12.0, 0.5), a.clone()),
            (ranked("epsd2", 8.0, 0.4), b.clone()),
        ];
        assert!(inseparable(&base, &decisive, 0.01).is_none());
        let rival_fails = [
            (ranked("sjkr", 9.0, 0.5), a),
            (ranked("epsd2", 8.0, 0.001), b),
        ];
        assert!(inseparable(&base, &rival_fails, 0.01).is_none());
    }
}
