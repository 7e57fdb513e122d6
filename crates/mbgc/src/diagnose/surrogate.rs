//! What a diagnosis needs of a model: its class, its experiment, its inputs with their valid
//! domains, the values its campaign held fixed, its responses with the model's own error, and a
//! prediction. A saved metamodel provides them; tests give an exact function instead.

use std::path::Path;
use std::sync::Arc;

use crate::error::{Error, Result};
use crate::metamodel::Metamodel;
use mbgc_dem::contact::ModelClass;

type Predict = dyn Fn(usize, &[f64]) -> f64 + Send + Sync;
type ErrorAt = dyn Fn(usize, &[f64]) -> Option<f64> + Send + Sync;
type Outside = dyn Fn(&[f64]) -> f64 + Send + Sync;
/// Groups decided by the known inputs and outside their range: `(group = formula, value,
/// range)`.
type FixedOutside = dyn Fn(&[f64]) -> Vec<(String, f64, [f64; 2])> + Send + Sync;

/// A model as a diagnosis uses it: class, experiment, input domains, fixed constants, responses
/// with their own error, and a prediction function.
pub struct Surrogate {
    /// How reports name it (the model file).
    pub label: String,
    /// The model class its training campaign simulated.
    pub class: ModelClass,
    /// `None`: the model does not say; any sample whose responses it predicts may use it.
    pub experiment: Option<String>,
    /// Input names, in the order `predict` takes them.
    pub inputs: Vec<String>,
    /// Valid range `[min, max]` of each input, in its unit: the range it was trained on.
    pub domains: Vec<[f64; 2]>,
    /// Values its campaign held fixed; a sample must agree with them to use the model.
    pub constants: Vec<(String, f64)>,
    /// Response names, indexed by `predict`'s first argument.
    pub responses: Vec<String>,
    /// The model's own error per response, in the response's unit (its validation RMSE).
    pub error: Vec<f64>,
    /// The sd of one DEM run per response, where replicate runs measured it: the part of
    /// `error` that is the validation data's noise, not the equations' miss.
    pub noise: Vec<Option<f64>>,
    predict: Box<Predict>,
    /// The model's own error at a point, where it has an error model.
    error_at: Box<ErrorAt>,
    /// Squared distance (in ln units) of derived groups outside their fitted range; 0 inside.
    outside: Box<Outside>,
    /// The groups that the known inputs of `x` (free ones NaN) already put outside their range.
    fixed_outside: Box<FixedOutside>,
}

impl Surrogate {
    /// A saved metamodel. Its error per response is the RMSE on its validation table (which holds
    /// one run's noise as well: conservative), else on its test rows.
    pub fn from_metamodel(path: &Path) -> Result<Surrogate> {
        Surrogate::from_model(Metamodel::load(path)?, &path.display().to_string())
    }

    /// A metamodel already in memory, named `label` in reports and errors.
    pub fn from_model(m: Metamodel, label: &str) -> Result<Surrogate> {
        let label = label.to_string();
        let class = m.class()?.ok_or_else(|| {
            Error::input(
                &label,
                "model_class",
                "the model class the metamodel was trained on (this file records none): a \
                 diagnosis compares classes",
            )
        })?;
        let error = m
            .responses
            .iter()
            .map(|r| r.validation.or(r.test).map_or(0.0, |v| v.rmse))
            .collect();
        let m = Arc::new(m);
        let (mp, mo, mf, me) = (m.clone(), m.clone(), m.clone(), m.clone());
        Ok(Surrogate {
            label,
            class,
            experiment: m.experiment.clone(),
            inputs: m.input_names(),
            domains: m.inputs.iter().map(|i| i.domain).collect(),
            constants: m
                .constants
                .iter()
                .map(|c| (c.name.clone(), c.value))
                .collect(),
            responses: m.responses.iter().map(|r| r.name.clone()).collect(),
            // The noise at its lower confidence bound: only what surely is noise is taken off
            // the model's error.
            noise: m
                .responses
                .iter()
                .map(|r| {
                    r.replicate_sd
                        .map(|sd| crate::metamodel::noise::lower_bound(sd, r.replicate_pairs))
                })
                .collect(),
            error,
            predict: Box::new(move |r, x| mp.predict_point(&mp.responses[r], x)),
            // Beyond the stiffness data the rigid limit's sd joins the error (over the
            // validation RMSE when the model has no error model).
            error_at: Box::new(move |r, x| {
                let rm = &me.responses[r];
                if me.extrapolation_sd(rm, x) != 0.0 {
                    me.prediction_error(rm, x)
                } else {
                    me.error_at(rm, x)
                }
            }),
            fixed_outside: Box::new(move |x| {
                mf.groups
                    .iter()
                    .filter_map(|gd| {
                        let v = mf.group_read_value(&gd.group, x);
                        let range = mf.group_range(gd);
                        (v.is_finite() && !(v >= range[0] && v <= range[1])).then(|| {
                            (
                                format!("{} = {}", gd.group.name, gd.group.monomial.text()),
                                v,
                                range,
                            )
                        })
                    })
                    .collect()
            }),
            outside: Box::new(move |x| {
                mo.groups
                    .iter()
                    .map(|gd| {
                        let v = mo.group_read_value(&gd.group, x).ln();
                        let range = mo.group_range(gd);
                        let (lo, hi) = (range[0].ln(), range[1].ln());
                        if v > hi {
                            (v - hi).powi(2)
                        } else if v < lo {
                            (v - lo).powi(2)
                        } else if v.is_nan() {
                            f64::INFINITY
                        } else {
                            0.0
                        }
                    })
                    .sum::<f64>()
                    + mo.constraint_excess(x)
            }),
        })
    }

    /// An exact model: `f(response, x)` over `inputs` (name, domain), with the given responses
    /// (name, model error).
    pub fn from_fn(
        label: &str,
        class: ModelClass,
        experiment: Option<&str>,
        inputs: &[(&str, [f64; 2])],
        constants: &[(&str, f64)],
        responses: &[(&str, f64)],
        f: impl Fn(usize, &[f64]) -> f64 + Send + Sync + 'static,
    ) -> Surrogate {
        Surrogate {
            label: label.to_string(),
            class,
            experiment: experiment.map(str::to_string),
            inputs: inputs.iter().map(|(n, _)| n.to_string()).collect(),
            domains: inputs.iter().map(|(_, d)| *d).collect(),
            constants: constants.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
            responses: responses.iter().map(|(n, _)| n.to_string()).collect(),
            error: responses.iter().map(|(_, e)| *e).collect(),
            noise: vec![None; responses.len()],
            predict: Box::new(f),
            error_at: Box::new(|_, _| None),
            outside: Box::new(|_| 0.0),
            fixed_outside: Box::new(|_| Vec::new()),
        }
    }

    /// Prediction of response `response` (index into `responses`) at inputs `x`, in the response's
    /// unit.
    pub fn predict(&self, response: usize, x: &[f64]) -> f64 {
        (self.predict)(response, x)
    }

    /// The model's own error for `response` at `x`, where its error model says (`None`: only
    /// the constant [`Surrogate::error`] is known).
    pub fn error_at(&self, response: usize, x: &[f64]) -> Option<f64> {
        (self.error_at)(response, x)
    }

    /// An exact model (see [`Surrogate::from_fn`]) whose own error varies: `e(response, x)`.
    pub fn with_error_at(
        mut self,
        e: impl Fn(usize, &[f64]) -> Option<f64> + Send + Sync + 'static,
    ) -> Surrogate {
        self.error_at = Box::new(e);
        self
    }

    /// The model with each response's replicate noise known (see [`Surrogate::noise`]).
    pub fn with_noise(mut self, noise: &[f64]) -> Surrogate {
        self.noise = noise.iter().map(|&n| Some(n)).collect();
        self
    }

    /// Squared distance, in ln units, of the derived dimensionless groups at `x` outside their
    /// fitted range, plus the model's relative constraint excess; 0 inside. The joint fit penalises it to keep away from extrapolation.
    pub fn outside(&self, x: &[f64]) -> f64 {
        (self.outside)(x)
    }

    /// The dimensionless groups that the known entries of `x` (the free ones NaN) already place
    /// outside the model's range, whatever the free ones: `(group = formula, value, range)`.
    pub fn groups_fixed_outside(&self, x: &[f64]) -> Vec<(String, f64, [f64; 2])> {
        (self.fixed_outside)(x)
    }

    /// Index of input `name`, if the model has it.
    pub fn input(&self, name: &str) -> Option<usize> {
        self.inputs.iter().position(|n| n == name)
    }

    /// Index of response `name`, if the model predicts it.
    pub fn response(&self, name: &str) -> Option<usize> {
        self.responses.iter().position(|n| n == name)
    }
}
