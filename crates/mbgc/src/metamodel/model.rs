//! The model file: equations per response, input transforms, domain, metrics, Pareto front,
//! settings, seed and data hash, saved and loaded as JSON.

use super::error_model::ErrorModel;
use super::rigid_limit::{decades_beyond, Form, Place, RigidLimit, COHESION_POWER};
use super::training_table::TrainingTable;
use crate::error::{read_to_string, write_atomic, Error, Result};
use crate::similarity::{Group, Monomial};
use mbgc_dem::contact::{ModelClass, Pair};
use mbgc_sr::{self as gp, Node};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `format` tag every model file carries; a JSON file without it is not a metamodel.
pub const FORMAT: &str = "mbgc-metamodel";
/// Deepest equation tree a model file may hold (`mbgc fit` limits trees to 64 nodes).
pub const MAX_TREE_DEPTH: usize = 512;

/// Depth of the tree a valid postfix program encodes (a single leaf has depth 1).
fn tree_depth(program: &[Node]) -> usize {
    let mut stack: Vec<usize> = Vec::with_capacity(program.len());
    let mut deepest = 0;
    for n in program {
        let d = match n.arity() {
            0 => 1,
            1 => stack.pop().unwrap_or(0) + 1,
            _ => {
                let r = stack.pop().unwrap_or(0);
                let l = stack.pop().unwrap_or(0);
                l.max(r) + 1
            }
        };
        deepest = deepest.max(d);
        stack.push(d);
    }
    deepest
}
/// Version of the model-file layout this library writes and reads; other versions are refused.
pub const VERSION: u32 = 1;

/// How a physical input becomes the equation's variable: `(t(x) - offset) / width`, with `t` the
/// identity or the natural log. Stored as the two numbers used, so exports compute bit for bit
/// the same value.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Transform {
    /// The physical value itself (an input the space fixes, an absorbed input, a fit without a
    /// space file).
    Identity,
    /// `(x - offset) / width`: a linear-scale parameter mapped to [0, 1] over its space bounds.
    Linear {
        /// The lower bound of the parameter, in its physical unit.
        offset: f64,
        /// Upper minus lower bound, in the physical unit.
        width: f64,
    },
    /// `(ln x - offset) / width`: a log-scale parameter (moduli, groups spanning decades) mapped
    /// to [0, 1]; `x` must be positive.
    Log {
        /// `ln` of the lower end of the range (a space bound, or a group's smallest value in
        /// the data).
        offset: f64,
        /// `ln(upper) - ln(lower)`, the width of the range in natural-log units.
        width: f64,
    },
}

impl Transform {
    /// The equation's variable for the physical value `x` (not finite for `x <= 0` under `Log`).
    #[inline]
    pub fn apply(&self, x: f64) -> f64 {
        match self {
            Transform::Identity => x,
            Transform::Linear { offset, width } => (x - offset) / width,
            Transform::Log { offset, width } => (x.ln() - offset) / width,
        }
    }
}

/// One input of the metamodel: a DEM parameter (or PSD parameter) as the equations read it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Input {
    /// The parameter's name in the space file and the training table (`mu_pp`, `E_p`, `d50`).
    pub name: String,
    /// How the physical value is scaled before the equations see it.
    pub transform: Transform,
    /// Smallest and largest value in the data the model was fitted on: its valid domain.
    pub domain: [f64; 2],
}

impl Input {
    /// The name of the variable the equations use (the input itself when not transformed).
    pub fn symbol(&self) -> String {
        match self.transform {
            Transform::Identity => self.name.clone(),
            _ => format!("{}_u", self.name),
        }
    }
}

/// A number that serde_json wrote as `null` (it writes NaN so) reads back as NaN.
fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// Accuracy of an equation on a set of rows, in the response's physical unit.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub struct Metrics {
    /// Rows scored.
    pub rows: usize,
    // NaN (R^2 of a single test row) is written as JSON null, and must read back.
    /// Coefficient of determination `1 - SS_res / SS_tot`; NaN when the observed values do not
    /// vary (a single row). Negative when the equation is worse than the rows' mean.
    #[serde(deserialize_with = "nan_if_null")]
    pub r2: f64,
    /// Root-mean-square residual, in the response's unit: compare it with the measurement's sd.
    #[serde(deserialize_with = "nan_if_null")]
    pub rmse: f64,
    /// Mean absolute residual, in the response's unit.
    #[serde(deserialize_with = "nan_if_null")]
    pub mae: f64,
    /// Largest absolute residual, in the response's unit: the worst run the equation misses.
    #[serde(deserialize_with = "nan_if_null")]
    pub max_abs_error: f64,
}

impl Metrics {
    /// Scores `predicted` against `observed` (same length); all zero for no rows.
    pub fn of(observed: &[f64], predicted: &[f64]) -> Metrics {
        let n = observed.len();
        if n == 0 {
            return Metrics::default();
        }
        let mean = observed.iter().sum::<f64>() / n as f64;
        let ss_tot: f64 = observed.iter().map(|y| (y - mean).powi(2)).sum();
        let res: Vec<f64> = observed.iter().zip(predicted).map(|(y, p)| y - p).collect();
        let ss_res: f64 = res.iter().map(|r| r * r).sum();
        Metrics {
            rows: n,
            r2: if ss_tot > 0.0 {
                1.0 - ss_res / ss_tot
            } else {
                f64::NAN
            },
            rmse: (ss_res / n as f64).sqrt(),
            mae: res.iter().map(|r| r.abs()).sum::<f64>() / n as f64,
            max_abs_error: res.iter().fold(0.0, |m, r| m.max(r.abs())),
        }
    }
}

/// Residual (observed - predicted) quantiles.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Quantile {
    /// Probability level in [0, 1] (0 and 1: the smallest and largest residual).
    pub q: f64,
    /// The residual at that level, in the response's unit.
    pub residual: f64,
}

/// Levels at which a model file records its residual distribution: extremes, 5/95 %, quartiles
/// and median.
pub const QUANTILES: [f64; 7] = [0.0, 0.05, 0.25, 0.5, 0.75, 0.95, 1.0];

/// The residuals `observed - predicted` at each level of [`QUANTILES`], linearly interpolated
/// between order statistics; empty for no rows.
pub fn residual_quantiles(observed: &[f64], predicted: &[f64]) -> Vec<Quantile> {
    let mut r: Vec<f64> = observed.iter().zip(predicted).map(|(y, p)| y - p).collect();
    if r.is_empty() {
        return Vec::new();
    }
    r.sort_by(f64::total_cmp);
    QUANTILES
        .iter()
        .map(|&q| {
            let pos = q * (r.len() - 1) as f64;
            let (i, f) = (pos.floor() as usize, pos.fract());
            let v = if i + 1 < r.len() {
                r[i] * (1.0 - f) + r[i + 1] * f
            } else {
                r[i]
            };
            Quantile { q, residual: v }
        })
        .collect()
}

/// One equation of the Pareto front of size against error that GP returned for a response: the
/// simplest equation at each accuracy, kept so a user can trade readability for accuracy.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FrontMember {
    /// Nodes of the equation as GP fitted it (over the groups, when fitted in groups): its
    /// complexity.
    pub size: usize,
    /// R^2 on the training rows in the fitted response (with a similarity, the dimensionless one).
    pub train_r2: f64,
    /// R^2 on the held-out test rows, in the physical response; `None` without test rows or where
    /// the equation is not finite on one of them.
    pub test_r2: Option<f64>,
    /// 1 - the cross-validated normalised error, when the selection rule computed it (in the
    /// fitted response: with a similarity, the dimensionless one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cv_r2: Option<f64>,
    /// The equation in the input symbols (Python/sympy syntax, constants exact).
    pub equation: String,
    /// The equation as a postfix program over the transformed inputs.
    pub program: Vec<Node>,
}

/// The fitted equation of one response (a bulk measurement such as the shear angle or bulk
/// density) with its accuracy, its Pareto front and how it was found.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ResponseModel {
    /// The response's column name in the training table and a material's `[measured]` key.
    pub name: String,
    /// The equation in the input symbols (Python/sympy syntax, constants exact).
    pub equation: String,
    /// The equation as a postfix program over the transformed inputs (what predictions evaluate).
    pub program: Vec<Node>,
    /// Nodes of the selected equation as GP fitted it (before groups and factor are written
    /// out): its position on the Pareto front.
    pub size: usize,
    /// Inputs the equation reads.
    pub uses: Vec<String>,
    /// Accuracy on the rows the equation was fitted to.
    pub train: Metrics,
    /// Accuracy on the held-out test rows (`None` with a test fraction of 0).
    pub test: Option<Metrics>,
    /// Distribution of the training residuals at the levels of [`QUANTILES`].
    pub train_residual_quantiles: Vec<Quantile>,
    /// Distribution of the test residuals (empty without test rows).
    pub test_residual_quantiles: Vec<Quantile>,
    /// The non-dominated equations of size against error, smallest first; the selected one is
    /// among them.
    pub pareto_front: Vec<FrontMember>,
    /// The rule that picked the equation from the front, in words.
    pub selection_rule: String,
    /// GP populations evaluated (the most of any restart; fewer than asked when the error
    /// converged).
    pub generations: usize,
    /// Nodes times rows evaluated, constant tuning included: the machine-independent cost.
    pub node_evals: u64,
    /// Wall-clock time of the search, s.
    pub seconds: f64,
    /// With a similarity: the equation as fitted, in the groups and the dimensionless response
    /// (what `program` computes once the groups and the factor are written out).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grouped: Option<GroupedEquation>,
    /// Metrics on a separate validation table never trained on (`mbgc train`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub validation: Option<Metrics>,
    /// The equation's own error as a function of the inputs, fitted to the validation
    /// residuals ([`Metamodel::error_at`]); `None` without enough validation rows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error_model: Option<ErrorModel>,
    /// The sd of one DEM run of this response at fixed inputs, from replicate runs (`mbgc
    /// noise`): the part of the validation error that is the data's, not the equation's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub replicate_sd: Option<f64>,
    /// How many replicate pairs measured `replicate_sd` (`None`: not recorded). Few pairs give a
    /// loose estimate, which [`super::noise::lower_bound`] allows for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub replicate_pairs: Option<usize>,
    /// For a response that is a factor times its fitted group (bulk density = rho_p phi): the
    /// factor's value on the runs the validation RMSE, the error model and the replicate sd were
    /// measured on (a campaign that held rho_p at 2600 kg/m3: 2600). Those errors are in the
    /// response's unit there; at another factor they scale with it, as the prediction does (a
    /// material of rho_p 500 misses by a fifth as many kg/m3). `None`: not scaled (no factor,
    /// or a file from before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error_reference: Option<f64>,
}

impl ResponseModel {
    /// Whether the response is a factor times its fitted group (bulk density = rho_p phi), whose
    /// errors then scale with the factor ([`ResponseModel::error_reference`]).
    pub fn has_factor(&self) -> bool {
        self.grouped.as_ref().is_some_and(|g| g.factor.is_some())
    }
}

/// An equation in dimensionless groups: `fitted = equation` over the group and input symbols.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GroupedEquation {
    /// Name of the fitted (dimensionless) response, e.g. `phi` for bulk density over rho_p; the
    /// response's own name when it was fitted unscaled.
    pub fitted: String,
    /// The equation GP fitted, over the scaled symbols of the inputs it was offered (`mu_pp_u`)
    /// and of the groups (`K_p_u`).
    pub equation: String,
    /// `response = factor * fitted` (None: the response itself was fitted).
    pub factor: Option<Monomial>,
}

/// A dimensionless group the equations read, with the scaling the fit gave it and the range of
/// the data (the model's valid domain in that group).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GroupDomain {
    /// The group: its name, meaning and monomial in the inputs (e.g. K_p = E_p / (rho_p g d50)).
    pub group: Group,
    /// `u = (ln G - offset) / width` is the variable the fitted equation read.
    pub transform: Transform,
    /// Smallest and largest value of the group over the data: calibration keeps it inside.
    pub domain: [f64; 2],
    /// A support group ([`crate::similarity::Similarity::support`]): the equations do not read
    /// it, its range bounds the model all the same.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub support: bool,
}

/// Which data a model was fitted to and how the rows were split, so a fit can be traced and
/// repeated.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DataSource {
    /// The training table's path (or the label of a table built in memory).
    pub file: String,
    /// FNV-1a 64 of the file's bytes, hex.
    pub fnv1a64: String,
    /// Usable rows (finished runs with every value).
    pub rows: usize,
    /// Rows the equations were fitted to.
    pub train_rows: usize,
    /// Rows held out for the test metrics (a seeded shuffle).
    pub test_rows: usize,
    /// The requested held-out share, in [0, 0.9].
    pub test_fraction: f64,
    /// Campaign rows left out because their run did not finish.
    pub skipped_rows: usize,
    /// Finished runs without a value of some response (NaN), left out.
    #[serde(default)]
    pub no_value_rows: usize,
    /// Finished runs that did not come to rest (`settled` false), left out.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub unsettled_rows: usize,
    /// Finished runs outside the space's constraints, left out.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub outside_rows: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// A global metamodel: one readable equation per response of a calibration experiment, valid over
/// the box its DEM runs covered. It replaces the DEM in calibration (microseconds instead of
/// hours per evaluation) and is saved and loaded as one JSON file.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Metamodel {
    /// Always [`FORMAT`].
    pub format: String,
    /// Always [`VERSION`].
    pub version: u32,
    /// The program and version that wrote the file (`mbgc 0.1.0`).
    pub created_by: String,
    /// The inputs in the order the equations number their variables and predictions take them.
    pub inputs: Vec<Input>,
    /// One fitted equation per response.
    pub responses: Vec<ResponseModel>,
    /// The GP settings of the fit, so it can be repeated.
    pub settings: gp::Config,
    /// The GP seed (also the seed of the train/test shuffle).
    pub seed: u64,
    /// The training table and its split.
    pub data: DataSource,
    /// The model class of the DEM runs the model was fitted on (comma-separated effects); null
    /// when the data did not say (a table not from DEM runs, or a model file written before
    /// model classes existed: no class is guessed for it).
    #[serde(default)]
    pub model_class: Option<String>,
    /// The dimensionless groups the equations were fitted in (their domains bound the model
    /// besides the inputs' own); empty for a fit in the inputs themselves.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub groups: Vec<GroupDomain>,
    /// The experiment the training runs measured (`shear-box`), from the campaign table's
    /// sidecar; null when the data did not say.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub experiment: Option<String>,
    /// The experiment's box scale in the training runs (the shear box's k, its smallest side in
    /// d_max), when it has one: a validation at another scale would compare other physics.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub box_scale: Option<f64>,
    /// The shear box's rest rule in the training runs when it was not the kinetic one
    /// (`--rest-rule`, from the table's sidecar): a validation reruns the DEM under it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest_rule: Option<String>,
    /// Parameters the campaign held at one value that are not inputs (a local space's known
    /// material values): the model describes runs at these values only.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub constants: Vec<Constant>,
    /// The space's constraints its training runs were kept inside (`ced_pp <= 0.01*E_p`), as
    /// written: beyond them the experiment did not measure, so the model does not hold there.
    /// Set with [`Metamodel::set_constraints`].
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub constraints: Vec<String>,
    /// `constraints` over the inputs: `(input index, coefficient)` terms and the constant (the
    /// model's constants folded in).
    #[serde(skip)]
    pub(super) constraint_terms: Vec<(Vec<(usize, f64)>, f64)>,
    /// How the model answers beyond its data in the stiffness group (the rigid limit, measured
    /// by `mbgc bench rigid-limit`); without it the group's domain bounds the model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rigid_limit: Option<RigidLimit>,
}

/// Where a point beyond the data in the rigid-limit groups is read.
#[derive(Clone, Debug, PartialEq)]
pub struct Reading {
    /// The point with the stiffness inputs on the edge and the cohesion carried there.
    pub clamped: Vec<f64>,
    /// Where the point lies.
    pub place: Place,
    /// Inside the limit's reach (else it does not answer).
    pub reached: bool,
    /// The cohesion groups carried.
    pub cohesion: Vec<Carried>,
}

/// One cohesion group carried to the edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Carried {
    /// Its index in the limit's `cohesion`.
    pub cohesion: usize,
    /// The input moved (`ced_pp`).
    pub input: usize,
    /// Decades of the contact's stiffness beyond the edge.
    pub decades: f64,
}

/// A prediction beyond the data in the rigid-limit group.
#[derive(Clone, Debug, PartialEq)]
pub struct Beyond {
    /// The point with the groups moved onto their domain's edge (where the equation is read).
    pub clamped: Vec<f64>,
    /// Where the point lies.
    pub place: Place,
    /// Prediction: the equation at `clamped` plus the curve's shift (NaN past the reach).
    pub value: f64,
    /// The curve's scatter there, in the response's unit: added to the model's own error.
    pub sd: f64,
}

/// A parameter held at one value in every training run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Constant {
    /// The parameter's name in the space.
    pub name: String,
    /// Its value in every run, in the parameter's physical unit.
    pub value: f64,
}

impl Metamodel {
    /// The model class the metamodel was trained on, if recorded.
    pub fn class(&self) -> Result<Option<ModelClass>> {
        self.model_class
            .as_deref()
            .map(ModelClass::parse)
            .transpose()
            .map_err(Into::into)
    }

    /// Reads a model file written by `mbgc fit` or `mbgc train`.
    pub fn load(path: &Path) -> Result<Metamodel> {
        Metamodel::from_json_str(&read_to_string(path)?, &path.display().to_string())
    }

    /// A model from the text of its JSON file (a model built into a program, or received);
    /// `source` names it in errors.
    pub fn from_json_str(text: &str, source: &str) -> Result<Metamodel> {
        let file = source.to_string();
        let m: Metamodel = serde_json::from_str(text).map_err(|e| {
            Error::input(
                &file,
                format!("line {} column {}", e.line(), e.column()),
                format!("a metamodel JSON file written by `mbgc fit` ({e})"),
            )
        })?;
        if m.format != FORMAT {
            return Err(Error::input(
                &file,
                "format",
                format!("\"{FORMAT}\", got \"{}\"", m.format),
            ));
        }
        let class = m
            .class()
            .map_err(|e| Error::input(&file, "model_class", e.to_string()))?;
        // An input of an effect the class lacks would be calibrated and then refused by the DEM.
        if let Some(c) = class {
            for i in &m.inputs {
                c.refuse_inactive(&i.name, &Pair::BOTH, "the model")
                    .map_err(|e| {
                        Error::input(&file, format!("inputs.{}", i.name), e.to_string())
                    })?;
            }
        }
        for g in &m.groups {
            if let Some((n, _)) = g
                .group
                .monomial
                .powers
                .iter()
                .find(|(n, _)| !m.inputs.iter().any(|i| &i.name == n))
            {
                return Err(Error::input(
                    &file,
                    format!("groups.{}", g.group.name),
                    format!("a product of the model's inputs, but {n} is not one"),
                ));
            }
        }
        if m.version != VERSION {
            return Err(Error::input(
                &file,
                "version",
                format!("{VERSION}, got {}", m.version),
            ));
        }
        for r in &m.responses {
            if let Some(v) = r.error_reference {
                if !(r.has_factor() && v.is_finite() && v > 0.0) {
                    return Err(Error::input(
                        &file,
                        format!("responses.{}.error_reference", r.name),
                        if !r.has_factor() {
                            format!(
                                "none: the response has no factor to scale its errors by, got {v}"
                            )
                        } else {
                            format!(
                                "the factor's value (> 0) where the errors were measured, got {v}"
                            )
                        },
                    ));
                }
            }
            if let Some(v) = r.replicate_sd {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(Error::input(
                        &file,
                        format!("responses.{}.replicate_sd", r.name),
                        format!("a standard deviation >= 0 in the response's unit, got {v}"),
                    ));
                }
            }
            let programs = std::iter::once(("program".to_string(), &r.program)).chain(
                r.pareto_front
                    .iter()
                    .enumerate()
                    .map(|(k, f)| (format!("pareto_front[{k}].program"), &f.program)),
            );
            for (field, program) in programs {
                let field = format!("responses.{}.{field}", r.name);
                if !gp::program::is_valid(program, m.inputs.len()) {
                    return Err(Error::input(
                        &file,
                        field,
                        format!(
                            "a well-formed postfix program over {} inputs",
                            m.inputs.len()
                        ),
                    ));
                }
                // Printing and simplifying walk the tree recursively; a fitted equation is a few
                // levels deep, a hand-made one of thousands would overflow the stack.
                let depth = tree_depth(program);
                if depth > MAX_TREE_DEPTH {
                    return Err(Error::input(
                        &file,
                        field,
                        format!("a tree at most {MAX_TREE_DEPTH} levels deep, found {depth}"),
                    ));
                }
            }
        }
        m.check_names_and_domains(&file)?;
        if let Some(lim) = &m.rigid_limit {
            lim.validate(&file)?;
            let pairs = std::iter::once((&lim.group, &lim.along))
                .chain(lim.wall.as_ref().map(|(g, a)| (g, a)));
            for c in &lim.curves {
                if !m.responses.iter().any(|r| r.name == c.response) {
                    return Err(Error::input(
                        &file,
                        "rigid_limit.curves",
                        format!("a response of the model, got \"{}\"", c.response),
                    ));
                }
            }
            for (i, c) in lim.cohesion.iter().enumerate() {
                let field = format!("rigid_limit.cohesion[{i}]");
                if let Some(n) = c
                    .contact
                    .iter()
                    .find(|n| !m.inputs.iter().any(|i| i.name == **n))
                {
                    return Err(Error::input(
                        &file,
                        field,
                        format!("contact moduli that are inputs of the model, got \"{n}\""),
                    ));
                }
                if let Some(cc) = c
                    .curves
                    .iter()
                    .find(|cc| !m.responses.iter().any(|r| r.name == cc.response))
                {
                    return Err(Error::input(
                        &file,
                        field,
                        format!("curves of the model's responses, got \"{}\"", cc.response),
                    ));
                }
                if let Some(e) = c.runs_edge {
                    // Its scatter joins the error inside the data, for every response.
                    if let Some(r) = m
                        .responses
                        .iter()
                        .find(|r| !c.curves.iter().any(|cc| cc.response == r.name))
                    {
                        return Err(Error::input(
                            &file,
                            format!("{field}.curves"),
                            format!(
                                "a scatter curve for every response with runs_edge, none for \"{}\"",
                                r.name
                            ),
                        ));
                    }
                    let domain = m
                        .groups
                        .iter()
                        .find(|g| g.group.name == lim.group)
                        .map(|g| g.domain);
                    if !domain.is_some_and(|[lo, hi]| e > lo && e < hi) {
                        return Err(Error::input(
                            &file,
                            format!("{field}.runs_edge"),
                            format!(
                                "a value of {} inside the model's range ({}), got {e}",
                                lim.group,
                                domain.map_or(
                                    "none: the model has no such group".to_string(),
                                    |[lo, hi]| { format!("{lo:.4e} to {hi:.4e}") }
                                )
                            ),
                        ));
                    }
                }
            }
            let pairs = pairs.chain(lim.cohesion.iter().map(|c| (&c.group, &c.along)));
            for (g, a) in pairs {
                if m.along_input(g, a).is_none() {
                    return Err(Error::input(
                        &file,
                        "rigid_limit",
                        format!(
                            "a group of the model ({g}) and an input ({a}) that enters it alone with power 1"
                        ),
                    ));
                }
            }
        }
        let mut m = m;
        let texts = std::mem::take(&mut m.constraints);
        m.set_constraints(&texts, &file)?;
        Ok(m)
    }

    /// Sets the constraints the model holds inside (linear inequalities between its inputs and
    /// constants, see [`Constraint`](crate::constraint::Constraint)); errors name `source`.
    pub fn set_constraints(&mut self, texts: &[String], source: &str) -> Result<()> {
        let mut parsed = Vec::new();
        for (i, text) in texts.iter().enumerate() {
            let field = format!("constraints[{i}]");
            let c = crate::constraint::Constraint::parse(text, source, &field)?;
            let mut terms = Vec::new();
            let mut constant = c.constant;
            for (n, coef) in &c.terms {
                if let Some(k) = self.inputs.iter().position(|i| &i.name == n) {
                    terms.push((k, *coef));
                } else if let Some(k) = self.constants.iter().find(|k| &k.name == n) {
                    constant += coef * k.value;
                } else {
                    return Err(Error::input(
                        source,
                        field,
                        format!("\"{n}\" is neither an input nor a constant of the model"),
                    ));
                }
            }
            parsed.push((terms, constant));
        }
        self.constraints = texts.to_vec();
        self.constraint_terms = parsed;
        Ok(())
    }

    /// How far inputs `x` (model order) lie outside the model's constraints: the sum over the
    /// violated ones of the squared violation relative to the size of its terms (0 inside; a
    /// ratio limit such as `ced_pp <= 0.01*E_p` exceeded by 10 % counts about 0.0023).
    pub fn constraint_excess(&self, x: &[f64]) -> f64 {
        self.constraint_terms
            .iter()
            .map(|(terms, constant)| {
                let g = terms.iter().map(|(k, c)| c * x[*k]).sum::<f64>() + constant;
                let size =
                    terms.iter().map(|(k, c)| (c * x[*k]).abs()).sum::<f64>() + constant.abs();
                if g.is_nan() {
                    f64::INFINITY
                } else if g > 0.0 {
                    (g / size.max(f64::MIN_POSITIVE)).powi(2)
                } else {
                    0.0
                }
            })
            .sum()
    }

    /// [`Metamodel::constraint_excess`] and its gradient over the inputs.
    pub fn constraint_excess_with_gradient(&self, x: &[f64]) -> (f64, Vec<f64>) {
        let mut grad = vec![0.0; x.len()];
        let mut total = 0.0;
        for (terms, constant) in &self.constraint_terms {
            let g = terms.iter().map(|(k, c)| c * x[*k]).sum::<f64>() + constant;
            if g.is_nan() {
                total = f64::INFINITY;
                continue;
            }
            if g <= 0.0 {
                continue;
            }
            let size = (terms.iter().map(|(k, c)| (c * x[*k]).abs()).sum::<f64>() + constant.abs())
                .max(f64::MIN_POSITIVE);
            let h = g / size;
            total += h * h;
            for (k, c) in terms {
                let dsize = c * (c * x[*k]).signum();
                grad[*k] += 2.0 * h * (c / size - g * dsize / (size * size));
            }
        }
        (total, grad)
    }

    /// The first constraint that inputs `x` violate, as written.
    pub fn violated_constraint(&self, x: &[f64]) -> Option<&str> {
        self.constraint_terms
            .iter()
            .zip(&self.constraints)
            .find(|((terms, constant), _)| {
                terms.iter().map(|(k, c)| c * x[*k]).sum::<f64>() + constant > 1e-9
            })
            .map(|(_, t)| t.as_str())
    }

    /// A hand-edited or foreign model file must still mean one thing: every input and response
    /// named once (a prediction looks them up by name), every domain an interval of finite
    /// numbers that its scaling can take, at least one input and one response.
    fn check_names_and_domains(&self, file: &str) -> Result<()> {
        if self.inputs.is_empty() {
            return Err(Error::input(
                file,
                "inputs",
                "at least one input, found none",
            ));
        }
        if self.responses.is_empty() {
            return Err(Error::input(
                file,
                "responses",
                "at least one response, found none",
            ));
        }
        if let Some(k) = self.box_scale.filter(|k| !(k.is_finite() && *k > 0.0)) {
            return Err(Error::input(
                file,
                "box_scale",
                format!("a box scale > 0 (the experiment's size in particle diameters), found {k}"),
            ));
        }
        if let Some(e) = &self.experiment {
            let known = crate::campaign::registry::experiment_names();
            if !known.contains(&e.as_str()) {
                return Err(Error::input(
                    file,
                    "experiment",
                    format!("one of {}, found \"{e}\"", known.join(", ")),
                ));
            }
        }
        let inputs: Vec<&str> = self.inputs.iter().map(|i| i.name.as_str()).collect();
        let responses: Vec<&str> = self.responses.iter().map(|r| r.name.as_str()).collect();
        for (what, names) in [("inputs", &inputs), ("responses", &responses)] {
            for (k, n) in names.iter().enumerate() {
                if n.trim().is_empty() {
                    return Err(Error::input(
                        file,
                        format!("{what}[{k}].name"),
                        "a name, found an empty one",
                    ));
                }
                if names[..k].contains(n) {
                    return Err(Error::input(
                        file,
                        format!("{what}[{k}].name"),
                        format!("each name once, but {n} appears twice"),
                    ));
                }
            }
        }
        if let Some(r) = responses.iter().find(|r| inputs.contains(r)) {
            return Err(Error::input(
                file,
                format!("responses.{r}"),
                format!("a response that is not also an input, but {r} is both"),
            ));
        }
        for i in &self.inputs {
            let [lo, hi] = i.domain;
            let field = format!("inputs.{}.domain", i.name);
            if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                return Err(Error::input(
                    file,
                    field,
                    format!("[min, max] of finite numbers with min <= max, found [{lo}, {hi}]"),
                ));
            }
            match i.transform {
                Transform::Identity => {}
                Transform::Linear { offset, width } | Transform::Log { offset, width } => {
                    if !(offset.is_finite() && width.is_finite() && width != 0.0) {
                        return Err(Error::input(
                            file,
                            format!("inputs.{}.transform", i.name),
                            format!(
                                "a finite offset and a finite non-zero width, found offset \
                                 {offset}, width {width}"
                            ),
                        ));
                    }
                    if matches!(i.transform, Transform::Log { .. }) && lo <= 0.0 {
                        return Err(Error::input(
                            file,
                            field,
                            format!("positive values for a log-scaled input, found min {lo}"),
                        ));
                    }
                }
            }
        }
        for g in &self.groups {
            let [lo, hi] = g.domain;
            let field = format!("groups.{}", g.group.name);
            match g.transform {
                Transform::Log { .. } => {
                    if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo <= hi) {
                        return Err(Error::input(
                            file,
                            format!("{field}.domain"),
                            format!(
                                "[min, max] with 0 < min <= max (a log-scaled group), found \
                                 [{lo}, {hi}]"
                            ),
                        ));
                    }
                }
                // A group that reaches zero (a cohesion off) is scaled linearly.
                Transform::Linear { .. } => {
                    if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi) {
                        return Err(Error::input(
                            file,
                            format!("{field}.domain"),
                            format!(
                                "[min, max] with 0 <= min <= max (a linearly scaled group), \
                                 found [{lo}, {hi}]"
                            ),
                        ));
                    }
                }
                Transform::Identity => {
                    return Err(Error::input(
                        file,
                        format!("{field}.transform"),
                        "a log or linear scaling (a group is fitted scaled), found identity",
                    ))
                }
            }
        }
        for (k, c) in self.constants.iter().enumerate() {
            if !c.value.is_finite()
                || inputs.contains(&c.name.as_str())
                || self.constants[..k].iter().any(|o| o.name == c.name)
            {
                return Err(Error::input(
                    file,
                    format!("constants.{}", c.name),
                    "a finite value of a parameter that is neither an input nor another constant",
                ));
            }
        }
        Ok(())
    }

    /// Writes the model as pretty-printed JSON, atomically (readers never see half a file).
    pub fn save(&self, path: &Path) -> Result<()> {
        let text = serde_json::to_string_pretty(self).map_err(|e| Error::invalid(e.to_string()))?;
        write_atomic(path, text.as_bytes())
    }

    /// The inputs' names, in model order.
    pub fn input_names(&self) -> Vec<String> {
        self.inputs.iter().map(|i| i.name.clone()).collect()
    }

    /// The variable names the equations use, in model order (`name_u` for a scaled input).
    pub fn symbols(&self) -> Vec<String> {
        self.inputs.iter().map(Input::symbol).collect()
    }

    /// The equation of the response called `name`.
    pub fn response(&self, name: &str) -> Option<&ResponseModel> {
        self.responses.iter().find(|r| r.name == name)
    }

    /// Transformed input columns from physical columns (`x[input][row]`).
    pub fn transform(&self, x: &[Vec<f64>]) -> Vec<Vec<f64>> {
        self.inputs
            .iter()
            .zip(x)
            .map(|(inp, col)| col.iter().map(|&v| inp.transform.apply(v)).collect())
            .collect()
    }

    /// Predictions of one response for physical input columns; NaN where the equation is not
    /// finite (outside its valid domain).
    pub fn predict(&self, response: &ResponseModel, x: &[Vec<f64>]) -> Vec<f64> {
        let xt = self.transform(x);
        let rows = x.first().map_or(0, Vec::len);
        let mut out = vec![0.0; rows];
        let mut ev = gp::eval::Evaluator::new();
        if !ev.eval(&response.program, &xt, &mut out) {
            // Row by row, to keep the finite ones.
            for (r, o) in out.iter_mut().enumerate() {
                let row: Vec<Vec<f64>> = xt.iter().map(|c| vec![c[r]]).collect();
                let mut one = [0.0];
                *o = if ev.eval(&response.program, &row, &mut one) {
                    one[0]
                } else {
                    f64::NAN
                };
            }
        }
        if self.rigid_limit.is_some() {
            for (r, o) in out.iter_mut().enumerate() {
                let point: Vec<f64> = x.iter().map(|c| c[r]).collect();
                if let Some(b) = self.beyond(response, &point) {
                    *o = b.value;
                }
            }
        }
        out
    }

    /// The equation alone at one point, without the rigid limit.
    pub(super) fn equation_at(&self, response: &ResponseModel, x: &[f64]) -> f64 {
        let xt: Vec<Vec<f64>> = self
            .inputs
            .iter()
            .zip(x)
            .map(|(i, &v)| vec![i.transform.apply(v)])
            .collect();
        let mut one = [0.0];
        if gp::eval::Evaluator::new().eval(&response.program, &xt, &mut one) {
            one[0]
        } else {
            f64::NAN
        }
    }

    /// The one fitted group the input `name` enters (`Ca_pp` for `ced_pp`); `None` when it
    /// enters none or several.
    pub fn group_of_input(&self, name: &str) -> Option<&GroupDomain> {
        let mut it = self
            .groups
            .iter()
            .filter(|g| !g.support && g.group.monomial.contains(name));
        let first = it.next()?;
        it.next().is_none().then_some(first)
    }

    /// The input `along` when it enters group `group` with power 1 and every other group it
    /// enters has an input of its own that can hold that group still (`ced_pp` in Ca_pp =
    /// ced_pp E_p^(-2/3) ..., which the rigid limit's cohesion carry moves as E_p moves):
    /// scaling it moves the point along that group only. Its index among the inputs.
    pub fn along_input(&self, group: &str, along: &str) -> Option<usize> {
        let gd = self.groups.iter().find(|g| g.group.name == group)?;
        let power = gd.group.monomial.powers.iter().find(|(n, _)| n == along)?.1;
        let has = |g: &GroupDomain, n: &str| g.group.monomial.contains(n);
        let own = |g: &GroupDomain, n: &str| {
            g.group
                .monomial
                .powers
                .iter()
                .any(|(m, p)| m == n && *p == 1.0)
                && self
                    .groups
                    .iter()
                    .all(|o| o.group.name == g.group.name || o.support || !has(o, n))
        };
        // A support group is not read by the equations: moving it moves no prediction.
        let held = self.groups.iter().all(|g| {
            g.group.name == group
                || g.support
                || !has(g, along)
                || g.group
                    .monomial
                    .powers
                    .iter()
                    .any(|(n, _)| n != along && !has(gd, n) && own(g, n))
        });
        (power == 1.0 && held)
            .then(|| self.inputs.iter().position(|i| i.name == along))
            .flatten()
    }

    /// Where a group's values make the model answer: its domain, or the rigid limit's reach for
    /// the groups the limit extends.
    pub fn group_range(&self, gd: &GroupDomain) -> [f64; 2] {
        match &self.rigid_limit {
            Some(lim) if lim.group == gd.group.name => [
                lim.reach[0].min(gd.domain[0]),
                lim.reach[1].max(gd.domain[1]),
            ],
            Some(lim) if lim.wall.as_ref().is_some_and(|(g, _)| *g == gd.group.name) => {
                // The reach is stored in the particle group's values; the wall's curves are
                // read at the same decades beyond its own edges.
                let Some(p) = self.groups.iter().find(|d| d.group.name == lim.group) else {
                    return gd.domain;
                };
                [
                    (gd.domain[0] * lim.reach[0] / p.domain[0]).min(gd.domain[0]),
                    (gd.domain[1] * lim.reach[1] / p.domain[1]).max(gd.domain[1]),
                ]
            }
            _ => gd.domain,
        }
    }

    /// Where the model reads a point beyond its data in the rigid limit's groups (`None`:
    /// inside, or a model without a rigid limit): the stiffness inputs moved so that their
    /// groups sit on the edge, and each cohesion group carried there
    /// ([`crate::metamodel::rigid_limit::Cohesion`]).
    pub fn reading(&self, x: &[f64]) -> Option<Reading> {
        let lim = self.rigid_limit.as_ref()?;
        let mut clamped = x.to_vec();
        let mut place = Place {
            decades: 0.0,
            wall_decades: 0.0,
        };
        let mut reached = true;
        let pairs = std::iter::once((&lim.group, &lim.along, false))
            .chain(lim.wall.as_ref().map(|(g, a)| (g, a, true)));
        for (g, a, wall) in pairs {
            let (Some(gd), Some(k)) = (
                self.groups.iter().find(|d| d.group.name == *g),
                self.along_input(g, a),
            ) else {
                continue;
            };
            let value = self.group_value(&gd.group, x);
            // The slack of `outside_domain`: a training row read back a last bit beyond its
            // edge is inside, and answered by the equation alone.
            let slack = 1e-12 * gd.domain[0].abs().max(gd.domain[1].abs());
            let d = decades_beyond(value, [gd.domain[0] - slack, gd.domain[1] + slack]);
            if d == 0.0 {
                continue;
            }
            let range = self.group_range(gd);
            reached &= value >= range[0] && value <= range[1];
            let edge = if d > 0.0 { gd.domain[1] } else { gd.domain[0] };
            clamped[k] = x[k] * (edge / value);
            if wall {
                place.wall_decades = d;
            } else {
                place.decades = d;
            }
        }
        if place.inside() {
            return None;
        }
        let index = |n: &str| self.inputs.iter().position(|i| i.name == n);
        let mut cohesion = Vec::new();
        for (c, coh) in lim.cohesion.iter().enumerate() {
            let (Some(k), Some(a), Some(b)) = (
                self.along_input(&coh.group, &coh.along),
                index(&coh.contact[0]),
                index(&coh.contact[1]),
            ) else {
                continue;
            };
            let compliance = |p: &[f64]| 1.0 / p[a] + 1.0 / p[b];
            // E*_edge / E* = compliance / compliance_edge.
            let ratio = compliance(x) / compliance(&clamped);
            clamped[k] = x[k] * ratio.powf(COHESION_POWER);
            cohesion.push(Carried {
                cohesion: c,
                input: k,
                decades: -ratio.log10(),
            });
        }
        Some(Reading {
            clamped,
            place,
            reached,
            cohesion,
        })
    }

    /// A group's value where the model reads it at `x`: a group of a carried cohesion input
    /// beyond the stiffness edge is read at its carried value ([`Metamodel::reading`]), any
    /// other at its own.
    pub fn group_read_value(&self, g: &Group, x: &[f64]) -> f64 {
        let carried = self
            .rigid_limit
            .as_ref()
            .is_some_and(|l| l.cohesion.iter().any(|c| g.monomial.contains(&c.along)));
        match self.reading(x).filter(|_| carried) {
            Some(r) => self.group_value(g, &r.clamped),
            None => self.group_value(g, x),
        }
    }

    /// The prediction at a point beyond the data in the rigid limit's groups (`None`: inside,
    /// or a model without a rigid limit): the equation on the domain's edge plus the measured
    /// curve. Its value is NaN past the curves' reach.
    pub fn beyond(&self, response: &ResponseModel, x: &[f64]) -> Option<Beyond> {
        let lim = self.rigid_limit.as_ref()?;
        let Reading {
            clamped,
            place,
            reached,
            cohesion,
        } = self.reading(x)?;
        let nan = |clamped: Vec<f64>| Beyond {
            clamped,
            place,
            value: f64::NAN,
            sd: f64::NAN,
        };
        let Some((v, form, sd)) = lim.shift(&response.name, place).filter(|_| reached) else {
            return Some(nan(clamped));
        };
        let f0 = self.equation_at(response, &clamped);
        let factor = self.factor_at(response, &clamped);
        let shift = match form {
            Form::Shift => v * factor,
            Form::Slope => {
                // The curves were measured without cohesion: the slope is the equation's
                // without it.
                let mut dry = clamped.clone();
                for c in &cohesion {
                    dry[c.input] = 0.0;
                }
                let along: Vec<usize> = std::iter::once((&lim.group, &lim.along))
                    .chain(lim.wall.as_ref().map(|(g, a)| (g, a)))
                    .filter_map(|(g, a)| self.along_input(g, a))
                    .collect();
                let Some(slope) = self.slope_per_decade(response, &dry, &along) else {
                    return Some(nan(clamped));
                };
                slope * v
            }
        };
        let Some(similarity) = self.similarity_var(response, x, &cohesion, &clamped) else {
            return Some(nan(clamped));
        };
        Some(Beyond {
            clamped,
            place,
            value: f0 + shift,
            sd: (sd * sd + similarity).sqrt() * factor,
        })
    }

    /// The variance (fitted unit) the cohesion similarity adds at `x`: per cohesion group of the
    /// rigid limit, its scatter curve at the decades beyond where the scatter counts from, in
    /// proportion to the cohesion carried there over the reference. A group whose scatter
    /// counts from the model's edge uses `carried`, the point's reading beyond it (empty
    /// inside the data), read at `clamped`; one whose effect's runs stop below the edge
    /// ([`crate::metamodel::rigid_limit::Cohesion::runs_edge`]) is moved from `x` along the
    /// lines (E_p and E_w together) onto that edge, inside the data as beyond it: both
    /// contacts then count their decades on K_p, as the lines moved the wall with the particles
    /// (where the cohesive runs' walls stopped is not recorded). `None`: a curve lacks the
    /// response.
    fn similarity_var(
        &self,
        response: &ResponseModel,
        x: &[f64],
        carried: &[Carried],
        clamped: &[f64],
    ) -> Option<f64> {
        let Some(lim) = self.rigid_limit.as_ref() else {
            return Some(0.0);
        };
        let mut var = 0.0;
        for (i, coh) in lim.cohesion.iter().enumerate() {
            let Some(gd) = self.groups.iter().find(|g| g.group.name == coh.group) else {
                continue;
            };
            let (decades, value) = match coh.runs_edge {
                None => match carried.iter().find(|c| c.cohesion == i) {
                    Some(c) => (c.decades, self.group_value(&gd.group, clamped)),
                    None => continue,
                },
                Some(edge) => {
                    let (Some(stiff), Some(k), Some(ced)) = (
                        self.groups.iter().find(|g| g.group.name == lim.group),
                        self.along_input(&lim.group, &lim.along),
                        self.along_input(&coh.group, &coh.along),
                    ) else {
                        continue;
                    };
                    let scale = edge / self.group_value(&stiff.group, x);
                    // Softer than the runs' edge, or no stiffness to read (NaN): none added.
                    if scale.is_nan() || scale >= 1.0 {
                        continue;
                    }
                    let mut moved = x.to_vec();
                    moved[k] *= scale;
                    if let Some(w) = lim.wall.as_ref().and_then(|(g, a)| self.along_input(g, a)) {
                        moved[w] *= scale;
                    }
                    moved[ced] *= scale.powf(COHESION_POWER);
                    (-scale.log10(), self.group_value(&gd.group, &moved))
                }
            };
            // No cohesion, no scatter (whether or not a curve exists).
            if value == 0.0 {
                continue;
            }
            let curve = coh.curves.iter().find(|k| k.response == response.name)?;
            var += (curve.sd_at(decades) * value / coh.reference).powi(2);
        }
        Some(var)
    }

    /// The similarity's scatter (response unit) at a point inside the stiffness data: nonzero
    /// only beyond a cohesion group's runs' edge (NaN where its curve lacks the response).
    fn inside_similarity_sd(&self, response: &ResponseModel, x: &[f64]) -> f64 {
        self.similarity_var(response, x, &[], x)
            .map_or(f64::NAN, |v| v.sqrt() * self.factor_at(response, x))
    }

    /// The equation's slope per decade of the inputs `along` moved together (scaling an input
    /// by 10 moves its group one decade), as the rigid limit's lines move the wall with the
    /// particles. From the gradient, or where that is not finite (a sqrt of a cohesion at 0,
    /// which does not move along them) by a central difference along the line.
    pub fn slope_per_decade(
        &self,
        response: &ResponseModel,
        x: &[f64],
        along: &[usize],
    ) -> Option<f64> {
        if let Some((_, g)) = self.equation_value_and_gradient(response, x) {
            return Some(
                along
                    .iter()
                    .map(|&k| g[k] * x[k] * std::f64::consts::LN_10)
                    .sum(),
            );
        }
        let h = 1e-4;
        let moved = |decades: f64| {
            let mut p = x.to_vec();
            for &k in along {
                p[k] *= 10f64.powf(decades);
            }
            self.equation_at(response, &p)
        };
        let s = (moved(h) - moved(-h)) / (2.0 * h);
        s.is_finite().then_some(s)
    }

    /// The dimensional factor of a response fitted dimensionless (rho_p for the bulk density,
    /// fitted as a solid fraction) at `x`; 1 for a response fitted as it is.
    pub(super) fn factor_at(&self, response: &ResponseModel, x: &[f64]) -> f64 {
        response
            .grouped
            .as_ref()
            .and_then(|g| g.factor.as_ref())
            .map_or(1.0, |m| {
                m.value(|n| {
                    self.inputs
                        .iter()
                        .position(|i| i.name == n)
                        .map_or(f64::NAN, |k| x[k])
                })
            })
    }

    /// The rigid limit's scatter at `x` for `response` (NaN past the reach), and inside the
    /// stiffness data the cohesion similarity's beyond its runs' edge (0 elsewhere or without a
    /// limit): what a prediction there adds to the model's own error.
    pub fn extrapolation_sd(&self, response: &ResponseModel, x: &[f64]) -> f64 {
        match self.beyond(response, x) {
            Some(b) => b.sd,
            None if self.rigid_limit.is_some() => self.inside_similarity_sd(response, x),
            None => 0.0,
        }
    }

    /// The inputs of `x` scaled to [0, 1] over the model's space (0.5 for an input the model
    /// does not scale, which the error model does not vary).
    fn unit(&self, x: &[f64]) -> Vec<f64> {
        // The groups too: an input absorbed into them (E_p, ced_pp) acts only through them,
        // and the error may grow with one (a strong cohesion is noisier).
        self.inputs
            .iter()
            .zip(x)
            .map(|(i, &v)| match &i.transform {
                Transform::Identity => 0.5,
                t => t.apply(v),
            })
            .chain(
                self.groups
                    .iter()
                    .map(|g| g.transform.apply(self.group_value(&g.group, x))),
            )
            .collect()
    }

    /// The equation's own standard error at `x` (physical inputs in `inputs` order), from its
    /// error model; `None` when it has none.
    ///
    /// Beyond the data in the rigid limit's group it is read on the edge and the curve's sd is
    /// added (in quadrature).
    pub fn error_at(&self, response: &ResponseModel, x: &[f64]) -> Option<f64> {
        let e = response.error_model.as_ref()?;
        let scale = self.error_scale(response, x);
        Some(match self.beyond(response, x) {
            Some(b) => (scale * e.sd(&self.unit(&b.clamped))).hypot(b.sd),
            None if self.rigid_limit.is_some() => {
                (scale * e.sd(&self.unit(x))).hypot(self.inside_similarity_sd(response, x))
            }
            None => scale * e.sd(&self.unit(x)),
        })
    }

    /// How the errors measured at the response's [`ResponseModel::error_reference`] scale at
    /// `x`: the factor there over the reference (1 without one).
    pub fn error_scale(&self, response: &ResponseModel, x: &[f64]) -> f64 {
        match response.error_reference {
            Some(r) => {
                let f = self.factor_at(response, x);
                if f.is_finite() && f > 0.0 {
                    f / r
                } else {
                    1.0
                }
            }
            None => 1.0,
        }
    }

    /// The error of a prediction at `x`: the equation's own error there ([`Metamodel::error_at`])
    /// or, without an error model, its validation (else test) RMSE; beyond the data in the
    /// rigid limit's group the limit's scatter is included. `None`: the model states no error.
    pub fn prediction_error(&self, response: &ResponseModel, x: &[f64]) -> Option<f64> {
        self.error_at(response, x).or_else(|| {
            let scale = self.error_scale(response, x);
            let rmse = response
                .validation
                .or(response.test)
                .map(|v| scale * v.rmse);
            let extra = self.extrapolation_sd(response, x);
            match rmse {
                Some(r) => Some(r.hypot(extra)),
                None => (extra != 0.0).then_some(extra),
            }
        })
    }

    /// Fits each response's error model to its residuals on `validation` (a table of runs never
    /// trained on, with the model's inputs and responses as columns). A response with fewer than
    /// [`crate::metamodel::error_model::MIN_POINTS`] finite residuals gets none.
    pub fn fit_error_models(&mut self, validation: &TrainingTable) -> Result<()> {
        let cols = self
            .inputs
            .iter()
            .map(|i| validation.column(&i.name).map(<[f64]>::to_vec))
            .collect::<Result<Vec<_>>>()?;
        let n = validation.rows();
        let u: Vec<Vec<f64>> = (0..n)
            .map(|r| self.unit(&cols.iter().map(|c| c[r]).collect::<Vec<_>>()))
            .collect();
        for k in 0..self.responses.len() {
            let observed = validation.column(&self.responses[k].name)?.to_vec();
            let predicted = self.predict(&self.responses[k], &cols);
            // A response with a factor misses in proportion to it: the residuals are brought to
            // the runs' mean factor, where the error model then holds.
            let has_factor = self.responses[k].has_factor();
            let factors: Vec<f64> = (0..n)
                .map(|i| {
                    let x: Vec<f64> = cols.iter().map(|c| c[i]).collect();
                    self.factor_at(&self.responses[k], &x)
                })
                .collect();
            let usable: Vec<f64> = factors
                .iter()
                .copied()
                .filter(|f| f.is_finite() && *f > 0.0)
                .collect();
            let reference = (has_factor && !usable.is_empty())
                .then(|| usable.iter().sum::<f64>() / usable.len() as f64);
            let r: Vec<f64> = observed
                .iter()
                .zip(&predicted)
                .zip(&factors)
                .map(|((o, p), f)| match reference {
                    Some(rf) => (o - p) * rf / f,
                    None => o - p,
                })
                .collect();
            self.responses[k].error_model = ErrorModel::fit(&u, &r);
            self.responses[k].error_reference = reference;
        }
        Ok(())
    }

    /// One prediction at a physical input point.
    pub fn predict_point(&self, response: &ResponseModel, x: &[f64]) -> f64 {
        let cols: Vec<Vec<f64>> = x.iter().map(|&v| vec![v]).collect();
        self.predict(response, &cols)[0]
    }

    /// Prediction and its gradient with respect to the physical inputs at one point; `None`
    /// where the equation is not finite.
    pub fn value_and_gradient(
        &self,
        response: &ResponseModel,
        x: &[f64],
    ) -> Option<(f64, Vec<f64>)> {
        let Some(b) = self.beyond(response, x) else {
            return self.equation_value_and_gradient(response, x);
        };
        if !b.value.is_finite() {
            return None;
        }
        // The shift is linear between knots: central differences are exact up to round-off
        // except on a knot, where they average the two sides.
        let mut g = vec![0.0; x.len()];
        for (k, gk) in g.iter_mut().enumerate() {
            let h = self.difference_step(k, x[k]);
            let (mut lo, mut hi) = (x.to_vec(), x.to_vec());
            lo[k] -= h;
            hi[k] += h;
            let (a, c) = (
                self.predict_point(response, &lo),
                self.predict_point(response, &hi),
            );
            *gk = if a.is_finite() && c.is_finite() {
                (c - a) / (2.0 * h)
            } else {
                0.0
            };
        }
        Some((b.value, g))
    }

    /// The step of a central difference in input `k` at `value`: 1e-6 of the value, or of a
    /// thousandth of the input's domain where the value is near 0 (a friction at 0 would
    /// otherwise get a step lost in round-off).
    pub fn difference_step(&self, k: usize, value: f64) -> f64 {
        let width = self
            .inputs
            .get(k)
            .map_or(0.0, |i| (i.domain[1] - i.domain[0]).abs());
        let scale = value.abs().max(1e-3 * width);
        1e-6 * if scale > 0.0 { scale } else { 1.0 }
    }

    /// [`Metamodel::value_and_gradient`] of the equation alone.
    pub(super) fn equation_value_and_gradient(
        &self,
        response: &ResponseModel,
        x: &[f64],
    ) -> Option<(f64, Vec<f64>)> {
        let xt: Vec<f64> = self
            .inputs
            .iter()
            .zip(x)
            .map(|(i, &v)| i.transform.apply(v))
            .collect();
        let (f, mut g) = gp::grad::value_and_gradient(&response.program, &xt)?;
        for ((gk, inp), &v) in g.iter_mut().zip(&self.inputs).zip(x) {
            *gk *= match inp.transform {
                Transform::Identity => 1.0,
                Transform::Linear { width, .. } => 1.0 / width,
                Transform::Log { width, .. } => 1.0 / (v * width),
            };
        }
        Some((f, g))
    }

    /// Inputs of a point outside the valid domain, as `(name, value, [min, max])`.
    pub fn outside_domain<'a>(&'a self, x: &[f64]) -> Vec<(&'a str, f64, [f64; 2])> {
        let mut v: Vec<(&str, f64, [f64; 2])> = self
            .inputs
            .iter()
            .zip(x)
            .filter(|(i, &v)| !(v >= i.domain[0] && v <= i.domain[1]))
            .map(|(i, &v)| (i.name.as_str(), v, i.domain))
            .collect();
        for g in &self.groups {
            let value = self.group_read_value(&g.group, x);
            let range = self.group_range(g);
            // A group is a product of powers: the same point computed along another path (a
            // file's digits read back, another order of factors) may differ in the last bits,
            // which must not put a training row outside its own domain.
            let slack = 1e-12 * range[0].abs().max(range[1].abs());
            if !(value >= range[0] - slack && value <= range[1] + slack) {
                v.push((g.group.name.as_str(), value, range));
            }
        }
        v
    }

    /// A group's value at a point of physical inputs (NaN if it names an input the model lacks).
    pub fn group_value(&self, g: &Group, x: &[f64]) -> f64 {
        g.monomial.value(|n| {
            self.inputs
                .iter()
                .position(|i| i.name == n)
                .map_or(f64::NAN, |k| x[k])
        })
    }
}
