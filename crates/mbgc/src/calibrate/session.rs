//! One calibration session: a material against one saved metamodel, from loading the model to
//! everything `mbgc calibrate` reports (optima, solution set, posterior, the calibrated
//! parameter file). The command line only prints and writes what [`Session`] holds.

use std::fmt::Write as _;

use super::bayes::{self, Posterior};
use super::optimize::{calibrate, Calibration, Optimum};
use super::problem::Problem;
use crate::error::{Error, Result};
use crate::material::Material;
use crate::metamodel::Metamodel;

/// How a material is calibrated: built with [`SessionOptions::default`] and the setters, checked
/// by [`SessionOptions::check`] (which [`run`] calls first).
#[derive(Clone, Debug)]
pub struct SessionOptions {
    /// L-BFGS starts (Sobol points of the search box), 1 to [`MAX_STARTS`].
    pub starts: usize,
    /// Seed of the starts and of the posterior sampler.
    pub seed: u64,
    /// Also sample the posterior by TMCMC.
    pub bayes: bool,
    /// TMCMC samples per stage.
    pub samples: usize,
    /// Upper bound of the uniform prior of the relative model error sigma (>= 0; 0: none).
    pub sigma_max: f64,
}

/// More starts than this find nothing new and only cost memory (each start keeps its optimum).
pub const MAX_STARTS: usize = 65_536;

impl Default for SessionOptions {
    /// `mbgc calibrate`'s defaults: 64 starts, seed 1, no posterior (2000 samples per stage and
    /// sigma_max 0.1 when one is asked for).
    fn default() -> Self {
        SessionOptions {
            starts: 64,
            seed: 1,
            bayes: false,
            samples: 2000,
            sigma_max: 0.1,
        }
    }
}

impl SessionOptions {
    /// Uses `starts` L-BFGS starts.
    pub fn starts(mut self, starts: usize) -> Self {
        self.starts = starts;
        self
    }

    /// Seeds the starts and the sampler.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Also samples the posterior by TMCMC with `samples` per stage.
    pub fn bayes(mut self, samples: usize) -> Self {
        self.bayes = true;
        self.samples = samples;
        self
    }

    /// Refuses options no session can honour.
    pub fn check(&self) -> Result<()> {
        if self.starts == 0 || self.starts > MAX_STARTS {
            return Err(Error::invalid(format!(
                "--starts {}: expected 1 to {MAX_STARTS} starting points",
                self.starts
            )));
        }
        if self.bayes {
            let max = super::tmcmc::MAX_SAMPLES;
            if !(10..=max).contains(&self.samples) {
                return Err(Error::invalid(format!(
                    "--samples {}: expected 10 to {max} TMCMC samples per stage",
                    self.samples
                )));
            }
            if !(self.sigma_max.is_finite() && self.sigma_max >= 0.0) {
                return Err(Error::invalid(format!(
                    "--sigma-max: expected a relative error >= 0, got {}",
                    self.sigma_max
                )));
            }
        }
        Ok(())
    }
}

/// A measured response as the session matched it.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// The response's name.
    pub name: String,
    /// The measured value, in the response's unit.
    pub value: f64,
    /// Its standard deviation, same unit.
    pub sd: f64,
}

/// The result of one session. Plain data: it no longer borrows the model.
#[derive(Clone, Debug)]
pub struct Session {
    /// The material's name (its `name`, else the file stem).
    pub material: String,
    /// The material file.
    pub source: String,
    /// The model file, as given.
    pub model: String,
    /// The model class the metamodel was trained on, if it records one.
    pub model_class: Option<String>,
    /// The experiment the metamodel's training runs measured, if it records one.
    pub experiment: Option<String>,
    /// The box scale of those runs, if the experiment has one.
    pub box_scale: Option<f64>,
    /// The rest rule of those runs when it was not the kinetic one.
    pub rest_rule: Option<String>,
    /// What was decided on the user's behalf (PSD fitted, parameters left free, ...).
    pub notes: Vec<String>,
    /// The material's fixed parameters, in file order.
    pub fixed: Vec<(String, f64)>,
    /// The measured responses matched, in the material's order.
    pub measured: Vec<Measurement>,
    /// The searched parameters, in search order.
    pub free: Vec<String>,
    /// The search box, `(lower, upper)` per free parameter in physical units.
    pub bounds: Vec<(f64, f64)>,
    /// Every model input at the best optimum (fixed ones included), in model order.
    pub best_inputs: Vec<(String, f64)>,
    /// The multi-start result: distinct optima best first (never empty), flat directions and
    /// solution ranges.
    pub calibration: Calibration,
    /// Free parameters absent from every equation of the measured responses: any value in
    /// range fits equally.
    pub unused: Vec<String>,
    /// The TMCMC posterior, when [`SessionOptions::bayes`] asked for one.
    pub posterior: Option<Posterior>,
    /// The `sigma_max` the posterior was sampled with (the range of its `sigma` axis).
    pub sigma_max: f64,
}

/// The equally weighted posterior samples of a session, every model input in each (fixed ones
/// at their value), with the relative model error and the weight: what `calibrate --bayes
/// --posterior-out` writes.
#[derive(Clone, Debug, PartialEq)]
pub struct PosteriorSamples {
    /// The model's inputs, in model order (the material's PSD among them: d50, sigma_ln).
    pub inputs: Vec<String>,
    /// The inputs the calibration searched; the others were fixed by the material.
    pub free: Vec<String>,
    /// Whether the relative model error sigma was sampled (otherwise its column is 0).
    pub sigma_sampled: bool,
    /// One row per sample: the inputs, then sigma, then the weight (1/n: TMCMC's last stage
    /// leaves equally weighted samples).
    pub rows: Vec<Vec<f64>>,
    /// The model the posterior is of, as the session names it.
    pub model: String,
    /// The material calibrated.
    pub material: String,
}

impl PosteriorSamples {
    /// The column names of [`PosteriorSamples::rows`]: the inputs, `sigma`, `weight`.
    pub fn columns(&self) -> Vec<String> {
        let mut c = self.inputs.clone();
        c.push("sigma".into());
        c.push("weight".into());
        c
    }
}

/// Axis ranges and the marked point of a corner plot.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// `(min, max)` of each axis: the free parameters, then sigma when it was sampled.
    pub ranges: Vec<(f64, f64)>,
    /// The marked value on each axis (the best optimum; the posterior mean of sigma).
    pub marks: Vec<f64>,
}

/// Calibrates `material` against `model` (named `model_name` in the session's record). Fails
/// with [`Error::OutOfDomain`] when a value the material fixes lies outside the model's domain,
/// [`Error::NoSolution`] when no start converged and [`Error::Infeasible`] when the best optimum
/// still violates the material's constraints.
pub fn run(
    material: &Material,
    model: &Metamodel,
    model_name: &str,
    opts: &SessionOptions,
) -> Result<Session> {
    opts.check()?;
    let problem = Problem::new(model, material)?;
    let cal = calibrate(&problem, opts.starts, opts.seed);
    let Some(best) = cal.optima.first() else {
        return Err(Error::NoSolution(
            "no start converged: the model's equations are not finite anywhere in the search box"
                .into(),
        ));
    };
    if best.violation > 1e-8 {
        // The groups first: a material whose fixed values put a group outside the training
        // range has no point in the box, whatever the constraints.
        let outside = problem.groups_outside(&best.x);
        if !outside.is_empty() {
            let what: Vec<String> = outside
                .iter()
                .map(|(name, text, v, [lo, hi])| {
                    format!(
                        "{name} = {text} is {v:.4e} at best, outside the model's range [{lo:.4e}, \
                         {hi:.4e}]"
                    )
                })
                .collect();
            return Err(Error::out_of_domain(
                &material.source,
                "fixed",
                format!(
                    "values that keep the model's dimensionless groups inside the range of its \
                     training runs, but {}; change the fixed values the group is made of (within \
                     its range) or use a model trained over this range",
                    what.join("; ")
                ),
            ));
        }
        // Then the model's own limits: fixed values may leave no point inside them.
        if let Some(c) = model.violated_constraint(&problem.full(&best.x)) {
            return Err(Error::out_of_domain(
                &material.source,
                "fixed",
                format!(
                    "values that leave room inside the model's limit {c} (where its training \
                     runs were), but even the best point lies beyond it; change the fixed \
                     values or use a model trained there"
                ),
            ));
        }
        let list: Vec<&str> = problem
            .constraints
            .iter()
            .map(|(c, _)| c.text.as_str())
            .collect();
        return Err(Error::Infeasible(format!(
            "{}: the constraints [{}] cannot be met inside the search box (smallest violation^2 {:.3e})",
            material.source,
            list.join(", "),
            best.violation
        )));
    }
    let posterior = if opts.bayes {
        Some(bayes::posterior(
            &problem,
            opts.samples,
            opts.sigma_max,
            opts.seed,
        )?)
    } else {
        None
    };
    let free: Vec<String> = problem.free_names().iter().map(|s| s.to_string()).collect();
    let unused = free
        .iter()
        .filter(|n| {
            !problem
                .targets
                .iter()
                .any(|t| model.responses[t.response].uses.iter().any(|u| u == *n))
        })
        .cloned()
        .collect();
    let best_inputs = problem
        .names
        .iter()
        .cloned()
        .zip(problem.full(&best.x))
        .collect();
    Ok(Session {
        material: material.name.clone(),
        source: material.source.clone(),
        model: model_name.to_string(),
        model_class: model.model_class.clone(),
        experiment: model.experiment.clone(),
        box_scale: model.box_scale,
        rest_rule: model.rest_rule.clone(),
        notes: problem.notes.clone(),
        fixed: material.fixed.clone(),
        measured: problem
            .targets
            .iter()
            .map(|t| Measurement {
                name: t.name.clone(),
                value: t.value,
                sd: t.sd,
            })
            .collect(),
        free,
        bounds: problem
            .lower
            .iter()
            .copied()
            .zip(problem.upper.iter().copied())
            .collect(),
        best_inputs,
        calibration: cal,
        unused,
        posterior,
        sigma_max: opts.sigma_max,
    })
}

impl Session {
    /// The best optimum (lowest chi^2, plus the rigid limit's sd term beyond the model's
    /// data): the calibrated parameter set.
    pub fn best(&self) -> &Optimum {
        &self.calibration.optima[0]
    }

    /// The optima as good as the best (-2 ln L within 1): points of one solution set when the
    /// data cannot fix every parameter.
    pub fn equally_good(&self) -> Vec<&Optimum> {
        let limit = self.best().chi2 + self.best().sd_term + 1.0;
        self.calibration
            .optima
            .iter()
            .filter(|o| o.chi2 + o.sd_term <= limit)
            .collect()
    }

    /// The chi^2 below which an optimum fits the measurements: the 95 % quantile of the chi^2
    /// distribution with one degree of freedom per measurement (what measurement noise alone
    /// exceeds one time in twenty).
    pub fn fit_threshold(&self) -> f64 {
        let n = self.measured.len().max(1) as f64;
        statrs::distribution::ChiSquared::new(n)
            .map(|d| statrs::distribution::ContinuousCDF::inverse_cdf(&d, 0.95))
            .unwrap_or(f64::INFINITY)
    }

    /// Whether an optimum fits the measurements (chi^2 within [`Session::fit_threshold`]).
    pub fn fits(&self, o: &Optimum) -> bool {
        o.chi2 <= self.fit_threshold()
    }

    /// The optima that fit the measurements, best first.
    pub fn fitting(&self) -> Vec<&Optimum> {
        self.calibration
            .optima
            .iter()
            .filter(|o| self.fits(o))
            .collect()
    }

    /// The equally good optima when they are worth drawing: the data leave a solution set and
    /// the starts found more than one point of it.
    pub fn solution_set(&self) -> Option<Vec<Vec<f64>>> {
        let good = self.equally_good();
        (self.calibration.excess_parameters > 0 && good.len() > 1 && !self.free.is_empty())
            .then(|| good.iter().map(|o| o.x.clone()).collect())
    }

    /// The posterior as a table a propagation or a script reads: one row per equally weighted
    /// TMCMC sample, with the columns [`PosteriorSamples::columns`]. `None` without a posterior;
    /// an error if a searched parameter is not among the model's inputs (a session built by
    /// hand).
    pub fn posterior_samples(&self) -> Result<Option<PosteriorSamples>> {
        let Some(post) = self.posterior.as_ref() else {
            return Ok(None);
        };
        let inputs: Vec<String> = self.best_inputs.iter().map(|(n, _)| n.clone()).collect();
        // Where each free parameter sits among the model inputs; the rest keep their fixed value.
        let at: Vec<usize> = self
            .free
            .iter()
            .map(|f| {
                inputs.iter().position(|n| n == f).ok_or_else(|| {
                    Error::invalid(format!(
                        "posterior of {}: the searched parameter {f} is not an input of the model \
                         (inputs: {})",
                        self.model,
                        inputs.join(", ")
                    ))
                })
            })
            .collect::<Result<_>>()?;
        let sampled_sigma = post.names.len() > self.free.len();
        let weight = 1.0 / post.draws.len().max(1) as f64;
        let rows = post
            .draws
            .iter()
            .map(|d| {
                let mut x: Vec<f64> = self.best_inputs.iter().map(|(_, v)| *v).collect();
                for (&k, &v) in at.iter().zip(d) {
                    x[k] = v;
                }
                x.push(if sampled_sigma {
                    d[self.free.len()]
                } else {
                    0.0
                });
                x.push(weight);
                x
            })
            .collect();
        Ok(Some(PosteriorSamples {
            inputs,
            free: self.free.clone(),
            sigma_sampled: sampled_sigma,
            rows,
            model: self.model.clone(),
            material: self.material.clone(),
        }))
    }

    /// Axes of a corner plot of the posterior: the search box with the best optimum marked,
    /// plus `[0, sigma_max]` and the posterior mean when sigma was sampled.
    pub fn posterior_frame(&self) -> Option<Frame> {
        let post = self.posterior.as_ref()?;
        let mut ranges = self.bounds.clone();
        let mut marks = self.best().x.clone();
        if post.names.len() > self.free.len() {
            ranges.push((0.0, self.sigma_max));
            marks.push(post.parameters.last().map_or(0.0, |s| s.mean));
        }
        Some(Frame { ranges, marks })
    }

    /// The best parameter set as the TOML file `mbgc validate` reads.
    pub fn calibrated_toml(&self) -> String {
        let mut t = format!(
            "# Calibrated by mbgc from {} with {}\n",
            self.source, self.model
        );
        // The file holds one point; say when it is not the answer but one of many, or no answer.
        let fitting = self.fitting().len();
        if !self.fits(self.best()) {
            let _ = writeln!(
                t,
                "# The best optimum does NOT fit the measurements (chi2 {:.3e} > {:.2}): check the \
                 material, the model's domain, or a missing effect (mbgc diagnose).",
                self.best().chi2,
                self.fit_threshold()
            );
        } else if self.solution_set().is_some() || fitting > 1 {
            let _ = writeln!(
                t,
                "# NOT UNIQUE: {fitting} of the optima fit the measurements ({} free parameters, {} \
                 measurements); this is the best of them, one point of the solution set.",
                self.free.len(),
                self.measured.len()
            );
        }
        let _ = write!(t, "material = {:?}\n\n[parameters]\n", self.material);
        for (n, v) in &self.best_inputs {
            let _ = writeln!(t, "{n} = {v:?}");
        }
        t.push_str("\n[predicted]\n");
        for (m, p) in self.measured.iter().zip(&self.best().predictions) {
            let _ = writeln!(t, "{} = {p:?}", m.name);
        }
        // `mbgc validate` reruns the DEM with the effects the metamodel was trained on.
        if let Some(c) = &self.model_class {
            let _ = write!(t, "\n[model]\nclass = {c:?}\n");
        }
        // ... and in the experiment and at the scale its training runs had.
        if let Some(e) = &self.experiment {
            let _ = write!(t, "\n[experiment]\nname = {e:?}\n");
            if let Some(k) = self.box_scale {
                let _ = writeln!(t, "box_scale = {k:?}");
            }
            if let Some(r) = &self.rest_rule {
                let _ = writeln!(t, "rest_rule = {r:?}");
            }
        }
        t
    }

    /// The machine-readable result (`calibrate --json`): `solutions` best first, each with every
    /// model input by name (fixed ones included), the predicted responses and the objective;
    /// with a posterior, per parameter its mean, COV and 5/95 % quantiles, and the
    /// log-evidence. `calibration` keeps the full optimiser record.
    pub fn json(&self) -> serde_json::Value {
        use serde_json::{Map, Value};
        let solutions: Vec<Value> = self
            .calibration
            .optima
            .iter()
            .map(|o| {
                // Every model input: the inputs that no optimum varies (fixed in the material or by
                // its PSD) as at the best optimum, then this optimum's free values.
                let mut params = Map::new();
                for (name, v) in &self.best_inputs {
                    params.insert(name.clone(), Value::from(*v));
                }
                for (name, v) in self.free.iter().zip(&o.x) {
                    params.insert(name.clone(), Value::from(*v));
                }
                let predicted: Map<String, Value> = self
                    .measured
                    .iter()
                    .zip(&o.predictions)
                    .map(|(m, p)| (m.name.clone(), Value::from(*p)))
                    .collect();
                serde_json::json!({
                    "params": params,
                    "predicted": predicted,
                    "fits": self.fits(o),
                    "objective": o.chi2 + o.sd_term,
                    "constraint_violation": o.violation,
                    "starts": o.starts,
                })
            })
            .collect();
        let posterior = self.posterior.as_ref().map(|p| {
            p.parameters
                .iter()
                .map(|s| {
                    (
                        s.name.clone(),
                        serde_json::json!({
                            "mean": s.mean, "sd": s.sd, "cov": s.cov, "q05": s.q05, "q95": s.q95,
                        }),
                    )
                })
                .collect::<Map<String, Value>>()
        });
        serde_json::json!({
            "material": self.material,
            "model": self.model,
            "model_class": self.model_class,
            "notes": self.notes,
            "fit_threshold": self.fit_threshold(),
            "fitting": self.fitting().len(),
            "solutions": solutions,
            "posterior": posterior,
            "log_evidence": self.posterior.as_ref().map(|p| p.ln_evidence),
            "posterior_details": self.posterior,
            "calibration": self.calibration,
        })
    }
}

/// Log-evidence of each session (minus infinity without a posterior) and the posterior
/// probability of each model class under equal prior odds.
pub fn class_probabilities(sessions: &[Session]) -> (Vec<f64>, Vec<f64>) {
    let ln_z: Vec<f64> = sessions
        .iter()
        .map(|s| {
            s.posterior
                .as_ref()
                .map_or(f64::NEG_INFINITY, |p| p.ln_evidence)
        })
        .collect();
    let prob = bayes::class_probabilities(&ln_z);
    (ln_z, prob)
}
