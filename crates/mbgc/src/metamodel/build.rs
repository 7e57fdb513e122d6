//! Fitting a metamodel to a table in memory: split, scale, one GP run per response, metrics.
//! The rows come as a [`TrainingTable`] and the settings as checked [`FitSettings`]; the result
//! is the model plus each response's observed and predicted values, from which the caller may
//! draw figures ([`crate::plot::fit_figures::fit_figures`]) or not.

use super::fit_settings::FitSettings;
use super::model::{
    residual_quantiles, Constant, DataSource, FrontMember, GroupDomain, GroupedEquation, Input,
    Metamodel, Metrics, ResponseModel, Transform, FORMAT, VERSION,
};
use super::training_table::TrainingTable;
use crate::error::{Error, Result};
use crate::similarity::Monomial;
use crate::space::Scale;
use mbgc_dem::contact::{ModelClass, Pair};
use mbgc_sr::{self as gp, expr, Dataset};
use rand::seq::SliceRandom;
use rand::SeedableRng;

/// Rows per fitted constant below which an equation is reported as possibly following the noise
/// (the usual rule of thumb of ten observations per regression coefficient).
pub const ROWS_PER_CONSTANT: usize = 10;
/// Fewest rows whose R^2 is reported without a warning that it says little.
pub const MIN_SCORED_ROWS: usize = 10;

/// A fitted metamodel and what it was scored on.
#[derive(Clone, Debug)]
pub struct Fit {
    /// The model, ready to save, predict with or calibrate against.
    pub model: Metamodel,
    /// Each response's observed and predicted values on the training, test and validation rows,
    /// in the order of the model's responses.
    pub splits: Vec<ResponseSplits>,
    /// What the caller should tell the user (an equation not finite on some test rows, ...).
    pub warnings: Vec<String>,
}

/// Observed and predicted values of one response on one set of rows.
#[derive(Clone, Debug, PartialEq)]
pub struct SplitValues {
    /// The measured (simulated) values.
    pub observed: Vec<f64>,
    /// The model's values on the same rows.
    pub predicted: Vec<f64>,
}

/// One response's values on the rows trained on, held out and set aside for validation.
#[derive(Clone, Debug, PartialEq)]
pub struct ResponseSplits {
    /// The response's name.
    pub response: String,
    /// The training rows.
    pub train: SplitValues,
    /// The held-out test rows (`None` without any).
    pub test: Option<SplitValues>,
    /// The validation table's rows (`None` without one).
    pub validation: Option<SplitValues>,
}

fn transforms(settings: &FitSettings, absorbed: &[String]) -> Result<Vec<Transform>> {
    let Some(space) = &settings.space else {
        return Ok(vec![Transform::Identity; settings.inputs.len()]);
    };
    settings
        .inputs
        .iter()
        .map(|name| {
            // The composed equations read an absorbed input raw, inside the log of its group.
            if absorbed.contains(name) {
                return Ok(Transform::Identity);
            }
            let p = space.get(name).ok_or_else(|| {
                Error::input(
                    &space.source,
                    format!("parameters.{name}"),
                    format!("the input {name} to be defined (to scale it)"),
                )
            })?;
            Ok(if p.is_fixed() {
                Transform::Identity
            } else {
                match p.scale {
                    Scale::Linear => Transform::Linear {
                        offset: p.min,
                        width: p.max - p.min,
                    },
                    Scale::Log => Transform::Log {
                        offset: p.min.ln(),
                        width: p.max.ln() - p.min.ln(),
                    },
                }
            })
        })
        .collect()
}

/// The model class of the rows: the table's `model_class` column (one class for all rows; `-`
/// marks an experiment without a contact law), else the settings' class, else the space's `[model]
/// class`; `None` when nothing says (a table that did not come from DEM runs). Sources that
/// disagree are refused.
fn data_class(table: &TrainingTable, settings: &FitSettings) -> Result<Option<ModelClass>> {
    let file = &table.source;
    let mut from_table: Option<Option<ModelClass>> = None;
    if let Some(labels) = &table.model_class {
        let mut first: Option<(Option<ModelClass>, String, usize)> = None;
        for (row, label) in labels.iter().enumerate() {
            let c = if label == "-" {
                None
            } else {
                Some(ModelClass::parse(label).map_err(|e| {
                    Error::input(
                        file,
                        format!("column model_class (data row {})", row + 1),
                        e.to_string(),
                    )
                })?)
            };
            match &first {
                None => first = Some((c, label.to_string(), row + 1)),
                Some((c0, l0, r0)) if *c0 != c => {
                    return Err(Error::input(
                        file,
                        format!("column model_class (data row {})", row + 1),
                        format!(
                            "{label} here but {l0} in data row {r0}: one model class per fit (a \
                             metamodel describes one set of effects)"
                        ),
                    ))
                }
                Some(_) => {}
            }
        }
        from_table = first.map(|f| f.0);
    }
    let space = settings
        .space
        .as_ref()
        .and_then(|sp| sp.model_class.map(|c| (c, sp.source.clone())));
    let given = [
        from_table
            .flatten()
            .map(|c| (c, format!("column model_class of {file}"))),
        settings
            .model_class
            .map(|c| (c, "--model-class".to_string())),
        space.map(|(c, f)| (c, format!("[model] class of {f}"))),
    ];
    let given: Vec<(ModelClass, String)> = given.into_iter().flatten().collect();
    if let Some((c0, w0)) = given.first() {
        if let Some((c, w)) = given.iter().find(|(c, _)| c != c0) {
            return Err(Error::invalid(format!(
                "model class: {w0} says {c0} but {w} says {c}; expected one class"
            )));
        }
    }
    Ok(given.first().map(|g| g.0))
}

/// The columns a fit reads: inputs then targets, each the table's column of that name.
fn columns(table: &TrainingTable, settings: &FitSettings) -> Result<Vec<Vec<f64>>> {
    settings
        .inputs
        .iter()
        .chain(&settings.targets)
        .map(|n| table.column(n).map(<[f64]>::to_vec))
        .collect()
}

/// How the model's inputs reach GP: each input's scaling and domain, the dimensionless groups
/// with their log scaling, and the columns GP is offered (inputs not absorbed, then groups).
struct Scaling {
    inputs: Vec<Input>,
    groups: Vec<GroupDomain>,
    /// The support groups, after `groups` in the model (no GP column).
    support: Vec<GroupDomain>,
    /// Every input scaled, `xt[k][row]`.
    xt: Vec<Vec<f64>>,
    /// The inputs GP sees (indices into `inputs`); the groups follow them.
    gp_inputs: Vec<usize>,
    /// The columns GP sees: `xt` of `gp_inputs`, then each group's scaled value.
    gp_cols: Vec<Vec<f64>>,
    symbols: Vec<String>,
    gp_symbols: Vec<String>,
}

fn range(col: &[f64]) -> [f64; 2] {
    [
        col.iter().copied().fold(f64::INFINITY, f64::min),
        col.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    ]
}

fn var_of(settings: &FitSettings, name: &str) -> u16 {
    settings.inputs.iter().position(|n| n == name).unwrap_or(0) as u16
}

fn scaling(
    table: &TrainingTable,
    settings: &FitSettings,
    absorbed: &[String],
    x_phys: &[Vec<f64>],
) -> Result<Scaling> {
    let transforms = transforms(settings, absorbed)?;
    let n = table.rows();
    // A group is fitted in its logarithm, unless it reaches zero (a cohesion switched off on
    // the effect-off face): then linearly, over its range.
    let mut group_transforms = Vec::new();
    for g in settings.similarity.iter().flat_map(|s| &s.groups) {
        let col: Vec<f64> = (0..n)
            .map(|r| {
                g.monomial
                    .value(|name| x_phys[var_of(settings, name) as usize][r])
            })
            .collect();
        if let Some(v) = col.iter().find(|v| **v < 0.0 || v.is_nan()) {
            return Err(Error::input(
                &table.source,
                format!("group {}", g.name),
                format!(
                    "{} = {} >= 0 on every row (a product of physical magnitudes), found {v}",
                    g.name,
                    g.monomial.text()
                ),
            ));
        }
        let transform = if col.iter().any(|v| *v <= 0.0) {
            let p = g
                .monomial
                .product_program(&|name| var_of(settings, name))
                .ok_or_else(|| {
                    Error::input(
                        &table.source,
                        format!("group {}", g.name),
                        format!(
                            "{} = {} reaches 0, so it is fitted linearly, which needs a \
                             factor of power 1",
                            g.name,
                            g.monomial.text()
                        ),
                    )
                })?;
            let [lo, hi] = range(&eval_program(&p, x_phys));
            Transform::Linear {
                offset: lo,
                width: if hi > lo { hi - lo } else { 1.0 },
            }
        } else {
            // The log of the group as the saved equation computes it (a sum of logs): its
            // smallest value is the offset, so that the scaled group is exactly 0 there, not
            // -1e-16 (which would make sqrt of it NaN at a training row of the saved model).
            let [lo, hi] = range(&ln_group(settings, &g.monomial, x_phys));
            Transform::Log {
                offset: lo,
                width: if hi > lo { hi - lo } else { 1.0 },
            }
        };
        group_transforms.push((transform, col));
    }
    let in_log_group = |name: &str| {
        settings
            .similarity
            .iter()
            .flat_map(|s| &s.groups)
            .zip(&group_transforms)
            .any(|(g, (t, _))| {
                matches!(t, Transform::Log { .. })
                    && g.monomial.powers.iter().any(|(n, _)| n == name)
            })
    };
    for (k, t) in transforms.iter().enumerate() {
        let logged = matches!(t, Transform::Log { .. })
            || (absorbed.contains(&settings.inputs[k]) && in_log_group(&settings.inputs[k]));
        if logged {
            if let Some(v) = x_phys[k].iter().find(|v| **v <= 0.0) {
                return Err(Error::input(
                    &table.source,
                    format!("column {}", settings.inputs[k]),
                    format!("positive values for its log scale, got {v}"),
                ));
            }
        }
    }
    let inputs: Vec<Input> = settings
        .inputs
        .iter()
        .zip(&transforms)
        .zip(x_phys)
        .map(|((name, t), col)| {
            // An absorbed input is valid wherever its groups are: over the space's bounds, not
            // only at the values the campaign held it at.
            let bounds = settings
                .space
                .as_ref()
                .filter(|_| absorbed.contains(name))
                .and_then(|sp| sp.get(name))
                .map(|p| [p.min, p.max]);
            Input {
                name: name.clone(),
                transform: t.clone(),
                domain: bounds.unwrap_or_else(|| range(col)),
            }
        })
        .collect();
    let mut groups: Vec<GroupDomain> = Vec::new();
    let mut group_cols: Vec<Vec<f64>> = Vec::new();
    for (g, (transform, col)) in settings
        .similarity
        .iter()
        .flat_map(|s| &s.groups)
        .zip(group_transforms)
    {
        let domain = range(&col);
        group_cols.push(scaled_group(settings, &g.monomial, &transform, x_phys));
        groups.push(GroupDomain {
            group: g.clone(),
            transform,
            domain,
            support: false,
        });
    }
    let support = settings
        .similarity
        .iter()
        .flat_map(|s| &s.support)
        .map(|g| {
            let col: Vec<f64> = (0..n)
                .map(|r| {
                    g.monomial
                        .value(|name| x_phys[var_of(settings, name) as usize][r])
                })
                .collect();
            let domain = range(&col);
            GroupDomain {
                group: g.clone(),
                // Not read by any equation: recorded as the identity of its range.
                transform: Transform::Linear {
                    offset: 0.0,
                    width: 1.0,
                },
                domain,
                support: true,
            }
        })
        .collect();
    let symbols: Vec<String> = inputs.iter().map(Input::symbol).collect();
    let xt: Vec<Vec<f64>> = inputs
        .iter()
        .zip(x_phys)
        .map(|(i, c)| c.iter().map(|&v| i.transform.apply(v)).collect())
        .collect();
    let gp_inputs: Vec<usize> = (0..settings.inputs.len())
        .filter(|&k| !absorbed.contains(&settings.inputs[k]))
        .collect();
    let gp_symbols: Vec<String> = gp_inputs
        .iter()
        .map(|&k| symbols[k].clone())
        .chain(groups.iter().map(|g| format!("{}_u", g.group.name)))
        .collect();
    let gp_cols: Vec<Vec<f64>> = gp_inputs
        .iter()
        .map(|&k| xt[k].clone())
        .chain(group_cols)
        .collect();
    Ok(Scaling {
        inputs,
        groups,
        support,
        xt,
        gp_inputs,
        gp_cols,
        symbols,
        gp_symbols,
    })
}

/// `ln(group)` per row, computed by the program the saved equation uses
/// ([`Monomial::ln_program`]), so that a fit and its saved model see bit-identical values.
fn ln_group(settings: &FitSettings, m: &Monomial, x_phys: &[Vec<f64>]) -> Vec<f64> {
    eval_program(&m.ln_program(&|name| var_of(settings, name)), x_phys)
}

/// The scaled group GP sees, `(ln(group) - offset) / width`, with the same operations as the
/// composed equation ([`Scaling::compose`]).
fn scaled_group(
    settings: &FitSettings,
    m: &Monomial,
    t: &Transform,
    x_phys: &[Vec<f64>],
) -> Vec<f64> {
    match *t {
        Transform::Log { offset, width } => ln_group(settings, m, x_phys)
            .into_iter()
            .map(|l| (l - offset) / width)
            .collect(),
        Transform::Linear { offset, width } => {
            let p = m
                .product_program(&|name| var_of(settings, name))
                .expect("a linear group has a factor of power 1 (checked in scaling)");
            eval_program(&p, x_phys)
                .into_iter()
                .map(|v| (v - offset) / width)
                .collect()
        }
        Transform::Identity => unreachable!("groups are scaled"),
    }
}

/// A program's value on every row of the physical inputs.
fn eval_program(p: &[gp::Node], x_phys: &[Vec<f64>]) -> Vec<f64> {
    let mut out = vec![0.0; x_phys.first().map_or(0, Vec::len)];
    gp::eval::Evaluator::new().eval(p, x_phys, &mut out);
    out
}

impl Scaling {
    /// A GP program over GP's own variables, written as one over the model's inputs (and
    /// multiplied back by the response's factor).
    fn compose(
        &self,
        settings: &FitSettings,
        p: &[gp::Node],
        factor: Option<&Monomial>,
    ) -> Vec<gp::Node> {
        let var_of = |name: &str| var_of(settings, name);
        let mut out = Vec::with_capacity(p.len() + 8);
        for node in p {
            match *node {
                gp::Node::Var(j) if (j as usize) < self.gp_inputs.len() => {
                    out.push(gp::Node::Var(self.gp_inputs[j as usize] as u16))
                }
                gp::Node::Var(j) => {
                    let g = &self.groups[j as usize - self.gp_inputs.len()];
                    let (offset, width) = match g.transform {
                        Transform::Log { offset, width } => {
                            out.extend(g.group.monomial.ln_program(&var_of));
                            (offset, width)
                        }
                        Transform::Linear { offset, width } => {
                            out.extend(
                                g.group
                                    .monomial
                                    .product_program(&var_of)
                                    .expect("a linear group has a factor of power 1"),
                            );
                            (offset, width)
                        }
                        Transform::Identity => unreachable!("groups are scaled"),
                    };
                    out.extend([
                        gp::Node::Const(offset),
                        gp::Node::Sub,
                        gp::Node::Const(width),
                        gp::Node::Div,
                    ]);
                }
                other => out.push(other),
            }
        }
        if let Some(f) = factor {
            out.extend(f.program(&var_of));
            out.push(gp::Node::Mul);
        }
        out
    }

    fn text(&self, p: &[gp::Node]) -> String {
        expr::infix(
            &expr::Expr::from_postfix(p),
            &self.symbols,
            &expr::exact_constant,
        )
    }
}

/// The equation on every row of `d`; `false` when it is not finite on some, whose values are
/// then NaN (the others keep theirs, so metrics over them are never computed on stand-ins).
fn predict(p: &[gp::Node], d: &Dataset) -> (bool, Vec<f64>) {
    let mut out = vec![0.0; d.rows()];
    let mut ev = gp::eval::Evaluator::new();
    if ev.eval(p, &d.x, &mut out) {
        return (true, out);
    }
    for (r, v) in out.iter_mut().enumerate() {
        let row: Vec<Vec<f64>> = d.x.iter().map(|c| vec![c[r]]).collect();
        let mut one = [0.0];
        *v = if ev.eval(p, &row, &mut one) {
            one[0]
        } else {
            f64::NAN
        };
    }
    (false, out)
}

fn pick(col: &[f64], idx: &[usize]) -> Vec<f64> {
    idx.iter().map(|&i| col[i]).collect()
}

/// Columns of numbers, `columns[k][row]`.
type Columns = Vec<Vec<f64>>;

/// The rows of one fit: which are trained on, which held out, and the validation set.
struct Rows<'a> {
    train: &'a [usize],
    test: &'a [usize],
    /// The validation table's columns (inputs then targets) and its scaled inputs.
    validation: Option<(Columns, Columns)>,
}

/// Fits one response and scores it.
#[allow(clippy::too_many_arguments)]
fn fit_response(
    table: &TrainingTable,
    settings: &FitSettings,
    scaling: &Scaling,
    x_phys: &[Vec<f64>],
    y: &[f64],
    target: &str,
    t: usize,
    rows: &Rows,
    progress: &mut impl FnMut(&str, &gp::Progress),
    warnings: &mut Vec<String>,
) -> Result<(ResponseModel, ResponseSplits)> {
    let n = table.rows();
    let n_in = settings.inputs.len();
    let scaled = settings.similarity.as_ref().and_then(|s| s.scaled(target));
    let factor = scaled.map(|s| &s.factor);
    // An extended model's equation for this response, over this fit's inputs: GP fits what the
    // data add to it.
    let (base, base_size) = match settings.extends.as_deref() {
        Some(b) => match b.responses.iter().position(|r| r.name == target) {
            Some(k) => (
                Some(super::rebase::rebase_program(b, k, &scaling.inputs)?),
                b.responses[k].size,
            ),
            None => {
                return Err(Error::invalid(format!(
                    "the extended model has no equation for {target} (it has: {}): a \
                     correction needs one",
                    b.responses
                        .iter()
                        .map(|r| r.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )))
            }
        },
        None => (None, 0),
    };
    let base_pred: Option<Vec<f64>> = base.as_ref().map(|p| {
        let (_, out) = predict(p, &Dataset::new(scaling.xt.clone(), vec![0.0; n]));
        out
    });
    if let Some(r) = base_pred
        .as_ref()
        .and_then(|b| b.iter().position(|v| !v.is_finite()))
    {
        return Err(Error::input(
            &table.source,
            format!("column {target}"),
            format!(
                "the extended model's {target} finite on every usable row (it is not on \
                 usable row {}: the row lies outside where that equation holds)",
                r + 1
            ),
        ));
    }
    let residual = |r: usize| y[r] - base_pred.as_ref().map_or(0.0, |b| b[r]);
    // The response GP fits: divided by its factor when the similarity has one.
    let y_fit: Vec<f64> = match factor {
        Some(f) => (0..n)
            .map(|r| residual(r) / f.value(|name| x_phys[var_of(settings, name) as usize][r]))
            .collect(),
        None => (0..n).map(residual).collect(),
    };
    let compose = |p: &[gp::Node]| {
        let mut out = scaling.compose(settings, p, factor);
        if let Some(b) = &base {
            out.extend(b.iter().copied());
            out.push(gp::Node::Add);
        }
        out
    };
    let train = Dataset::new(
        scaling.xt.iter().map(|c| pick(c, rows.train)).collect(),
        pick(y, rows.train),
    );
    let gp_train = Dataset::new(
        scaling
            .gp_cols
            .iter()
            .map(|c| pick(c, rows.train))
            .collect(),
        pick(&y_fit, rows.train),
    );
    if gp_train.y_var() <= 0.0 {
        return Err(Error::input(
            &table.source,
            format!("column {target}"),
            "a response that varies (all training values are equal)",
        ));
    }
    let test = Dataset::new(
        scaling.xt.iter().map(|c| pick(c, rows.test)).collect(),
        pick(y, rows.test),
    );
    let res = gp::fit(&gp_train, &settings.config, |p| progress(target, p))
        .map_err(|e| Error::invalid(format!("fitting {target}: {e}")))?;
    let front: Vec<FrontMember> = res
        .front
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let program = compose(&e.program);
            let test_r2 = (test.rows() > 0)
                .then(|| {
                    let (ok, out) = predict(&program, &test);
                    ok.then(|| Metrics::of(&test.y, &out).r2)
                })
                .flatten();
            FrontMember {
                size: e.size + base_size,
                // Of the response, not of the correction GP saw.
                train_r2: if base.is_some() {
                    let (_, out) = predict(&program, &train);
                    Metrics::of(&train.y, &out).r2
                } else {
                    1.0 - e.train_nmse
                },
                test_r2,
                cv_r2: res.cv_nmse.as_ref().map(|cv| 1.0 - cv[i]),
                equation: scaling.text(&program),
                program,
            }
        })
        .collect();
    let best = res.best();
    let program = compose(&best.program);
    let (train_ok, train_pred) = predict(&program, &train);
    if !train_ok {
        let bad = train_pred.iter().filter(|v| !v.is_finite()).count();
        warnings.push(format!(
            "the saved equation for {target} is not finite on {bad} of the {} training rows \
             (its training metrics are NaN): report this as a bug",
            train.rows()
        ));
    }
    let (test_ok, test_pred) = predict(&program, &test);
    if test.rows() > 0 && !test_ok {
        warnings.push(format!(
            "the equation for {target} is not finite on some test rows (they lie outside the \
             training box)"
        ));
    }
    // What a reader of the metrics should know: an equation with more constants than its rows
    // support can follow the noise, and a score on a handful of rows says little.
    let constants = best
        .program
        .iter()
        .filter(|n| matches!(n, gp::Node::Const(_)))
        .count();
    if constants * ROWS_PER_CONSTANT > train.rows() {
        warnings.push(format!(
            "the equation for {target} has {constants} constants fitted to {} rows (fewer than \
             {ROWS_PER_CONSTANT} rows per constant): it may follow the noise; judge it by its \
             validation or test error, or ask for a shorter one (--max-length, --parsimony)",
            train.rows()
        ));
    }
    for (set, rows) in [
        ("test", test.rows()),
        (
            "validation",
            rows.validation.as_ref().map_or(0, |v| v.0[0].len()),
        ),
    ] {
        if rows > 0 && rows < MIN_SCORED_ROWS {
            warnings.push(format!(
                "{target}: only {rows} {set} rows; an R^2 on fewer than {MIN_SCORED_ROWS} rows \
                 says little about the equation's error"
            ));
        }
    }
    let test_metrics = (test.rows() > 0).then(|| Metrics::of(&test.y, &test_pred));
    let validation = rows.validation.as_ref().map(|(v, x)| {
        let d = Dataset::new(x.clone(), v[n_in + t].clone());
        let (_, pred) = predict(&program, &d);
        SplitValues {
            observed: d.y,
            predicted: pred,
        }
    });
    let grouped = settings.similarity.as_ref().map(|_| GroupedEquation {
        fitted: {
            let fitted = scaled.map_or_else(|| target.to_string(), |s| s.fitted.clone());
            if base.is_some() {
                format!("{fitted} beyond the extended model's")
            } else {
                fitted
            }
        },
        equation: expr::infix(
            &expr::Expr::from_postfix(&best.program),
            &scaling.gp_symbols,
            &expr::exact_constant,
        ),
        factor: factor.cloned(),
    });
    let model = ResponseModel {
        name: target.to_string(),
        equation: scaling.text(&program),
        size: best.size + base_size,
        uses: gp::program::used_variables(&program)
            .into_iter()
            .map(|k| settings.inputs[k].clone())
            .collect(),
        program,
        train: Metrics::of(&train.y, &train_pred),
        test: test_metrics,
        train_residual_quantiles: residual_quantiles(&train.y, &train_pred),
        test_residual_quantiles: residual_quantiles(&test.y, &test_pred),
        pareto_front: front,
        selection_rule: settings.config.selection.describe(),
        generations: res.generations,
        node_evals: res.node_evals,
        seconds: res.seconds,
        grouped,
        validation: validation
            .as_ref()
            .map(|v| Metrics::of(&v.observed, &v.predicted)),
        error_model: None,
        replicate_sd: None,
        replicate_pairs: None,
        // Set with the error model, from the validation runs ([`Metamodel::fit_error_models`]).
        error_reference: None,
    };
    let splits = ResponseSplits {
        response: target.to_string(),
        train: SplitValues {
            observed: train.y,
            predicted: train_pred,
        },
        test: (test.rows() > 0).then_some(SplitValues {
            observed: test.y,
            predicted: test_pred,
        }),
        validation,
    };
    Ok((model, splits))
}

/// What the campaign held fixed and is not an input: the model holds only there.
fn constants(table: &TrainingTable, settings: &FitSettings) -> Vec<Constant> {
    let mut constants: Vec<Constant> = Vec::new();
    if let Some(space) = &settings.space {
        for p in &space.parameters {
            if let (Some(v), false) = (p.fixed, settings.inputs.contains(&p.name)) {
                constants.push(Constant {
                    name: p.name.clone(),
                    value: v,
                });
            }
        }
    }
    for (name, v) in table.campaign.iter().flat_map(|m| m.set.iter()) {
        if !settings.inputs.contains(name) && !constants.iter().any(|c| c.name == *name) {
            constants.push(Constant {
                name: name.clone(),
                value: *v,
            });
        }
    }
    constants
}

/// The rows of `table` inside the constraints of `settings.space` (`None`: there are none, or
/// every row is inside) and how many lie outside. A constraint's names are the table's columns
/// or the model's constants.
fn inside_constraints(
    table: &TrainingTable,
    settings: &FitSettings,
    constants: &[Constant],
) -> Result<(Option<TrainingTable>, usize)> {
    let Some(space) = settings
        .space
        .as_ref()
        .filter(|s| !s.constraints.is_empty())
    else {
        return Ok((None, 0));
    };
    let mut keep = vec![true; table.rows()];
    for c in &space.constraints {
        let mut g = vec![c.constant; table.rows()];
        for (n, coef) in &c.terms {
            if let Ok(col) = table.column(n) {
                for (g, x) in g.iter_mut().zip(col) {
                    *g += coef * x;
                }
            } else if let Some(k) = constants.iter().find(|k| &k.name == n) {
                for g in &mut g {
                    *g += coef * k.value;
                }
            } else {
                return Err(Error::input(
                    &table.source,
                    format!("column {n}"),
                    format!(
                        "missing: the space's constraint \"{}\" needs {n} (pass it with \
                         --inputs, or fix it in the space)",
                        c.text
                    ),
                ));
            }
        }
        for (k, g) in keep.iter_mut().zip(&g) {
            *k &= *g <= 1e-9;
        }
    }
    let outside = keep.iter().filter(|k| !**k).count();
    if outside == 0 {
        return Ok((None, 0));
    }
    Ok((Some(table.retain_rows(&keep)), outside))
}

/// Fits one equation per response of `settings` to the rows of `table`.
/// `progress(response, state)` is called every generation (a progress bar, a log, nothing).
pub fn fit(
    table: &TrainingTable,
    settings: &FitSettings,
    mut progress: impl FnMut(&str, &gp::Progress),
) -> Result<Fit> {
    settings.check()?;
    // Rows outside the space's constraints (run before the constraint was set, or by hand) are
    // not data of the model, which holds inside them only.
    let fixed = constants(table, settings);
    let texts: Vec<String> = settings
        .space
        .iter()
        .flat_map(|s| s.constraints.iter().map(|c| c.text.clone()))
        .collect();
    let (inside_table, outside) = inside_constraints(table, settings, &fixed)?;
    let table = inside_table.as_ref().unwrap_or(table);
    let inside_settings = match &settings.validation {
        Some(v) if !texts.is_empty() => {
            let (t, _) = inside_constraints(v, settings, &fixed)?;
            Some(FitSettings {
                validation: t.or_else(|| Some(v.clone())),
                ..settings.clone()
            })
        }
        _ => None,
    };
    let settings = inside_settings.as_ref().unwrap_or(settings);
    let absorbed = settings.absorbed();
    let cols = columns(table, settings)?;
    let class = data_class(table, settings)?;
    if let Some(class) = &class {
        for name in &settings.inputs {
            class
                .refuse_inactive(name, &Pair::BOTH, "the data")
                .map_err(|e| Error::invalid(format!("--inputs {name}: {e}")))?;
        }
    }
    let n = table.rows();
    let n_in = settings.inputs.len();
    let x_phys = &cols[..n_in];
    let scaling = scaling(table, settings, &absorbed, x_phys)?;
    let n_test = (settings.test_fraction * n as f64).round() as usize;
    if n - n_test < 5 {
        return Err(Error::input(
            &table.source,
            "rows",
            format!(
                "at least 5 training rows, got {} ({n} usable rows; left out: {} unfinished, {} \
                 without a value, {} not at rest)",
                n - n_test,
                table.skipped_rows,
                table.no_value_rows,
                table.unsettled_rows
            ),
        ));
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(
        settings.config.seed,
    ));
    let (test_idx, train_idx) = order.split_at(n_test);
    let (mut train_idx, mut test_idx) = (train_idx.to_vec(), test_idx.to_vec());
    train_idx.sort_unstable();
    test_idx.sort_unstable();
    let validation = match &settings.validation {
        Some(v) => {
            let vc = columns(v, settings)?;
            let x: Vec<Vec<f64>> = scaling
                .inputs
                .iter()
                .zip(&vc[..n_in])
                .map(|(i, c)| c.iter().map(|&x| i.transform.apply(x)).collect())
                .collect();
            Some((vc, x))
        }
        None => None,
    };
    let rows = Rows {
        train: &train_idx,
        test: &test_idx,
        validation,
    };
    let mut responses = Vec::new();
    let mut splits = Vec::new();
    let mut warnings = Vec::new();
    for (t, target) in settings.targets.iter().enumerate() {
        let (model, split) = fit_response(
            table,
            settings,
            &scaling,
            x_phys,
            &cols[n_in + t],
            target,
            t,
            &rows,
            &mut progress,
            &mut warnings,
        )?;
        responses.push(model);
        splits.push(split);
    }
    let mut model = Metamodel {
        model_class: class.map(|c| c.to_string()),
        format: FORMAT.into(),
        version: VERSION,
        created_by: format!("mbgc {}", env!("CARGO_PKG_VERSION")),
        inputs: scaling.inputs,
        responses,
        settings: settings.config.clone(),
        seed: settings.config.seed,
        data: DataSource {
            file: table.source.clone(),
            fnv1a64: table.fingerprint.clone(),
            rows: n,
            train_rows: train_idx.len(),
            test_rows: test_idx.len(),
            test_fraction: settings.test_fraction,
            skipped_rows: table.skipped_rows,
            no_value_rows: table.no_value_rows,
            unsettled_rows: table.unsettled_rows,
            outside_rows: 0,
        },
        groups: scaling.groups.into_iter().chain(scaling.support).collect(),
        experiment: table.campaign.as_ref().map(|m| m.experiment.clone()),
        box_scale: table.campaign.as_ref().and_then(|m| {
            crate::campaign::registry::effective_box_scale(&m.experiment, m.box_scale)
        }),
        rest_rule: table.campaign.as_ref().and_then(|m| m.rest_rule.clone()),
        constants: fixed,
        constraints: Vec::new(),
        constraint_terms: Vec::new(),
        rigid_limit: None,
    };
    if let Some(space) = &settings.space {
        model
            .set_constraints(&texts, &space.source)
            .map_err(|e| Error::invalid(format!("{e} (constraints.expr)")))?;
    }
    model.data.outside_rows = outside;
    if outside > 0 {
        warnings.push(format!(
            "{outside} rows of {} lie outside the space's constraints ({}): left out",
            table.source,
            texts.join(", ")
        ));
    }
    if let Some(v) = &settings.validation {
        model.fit_error_models(v)?;
    }
    Ok(Fit {
        model,
        splits,
        warnings,
    })
}

/// One response as the regression engine is offered it: the columns GP sees (scaled inputs, then
/// the log-scaled dimensionless groups), the quantity GP fits (the response divided by its
/// factor, e.g. the solid fraction) and that factor per row. Any regressor given these columns
/// solves exactly the problem mbgc's GP solves, which is what a benchmark against other
/// regressors needs.
#[derive(Clone, Debug, PartialEq)]
pub struct RegressionProblem {
    /// The physical response, e.g. `bulk_density`.
    pub response: String,
    /// What is fitted: the response itself or the scaled quantity (e.g. `solid_fraction`).
    pub fitted: String,
    /// Names of the columns (`mu_pp_u`, `K_p_u`, ...).
    pub symbols: Vec<String>,
    /// Every row of the table (no test split).
    pub train: ProblemRows,
    /// The rows of the settings' validation table, scaled as the training rows are.
    pub validation: Option<ProblemRows>,
}

/// Rows of a [`RegressionProblem`].
#[derive(Clone, Debug, PartialEq)]
pub struct ProblemRows {
    /// `x[column][row]`.
    pub x: Vec<Vec<f64>>,
    /// The fitted quantity.
    pub y: Vec<f64>,
    /// Response = `factor * y` (1 for an unscaled response).
    pub factor: Vec<f64>,
}

/// The regression problems of `settings`' responses on `table` (and on its validation table),
/// checked as [`fit`] checks them.
pub fn regression_problems(
    table: &TrainingTable,
    settings: &FitSettings,
) -> Result<Vec<RegressionProblem>> {
    settings.check()?;
    let absorbed = settings.absorbed();
    let cols = columns(table, settings)?;
    let n_in = settings.inputs.len();
    let scaling = scaling(table, settings, &absorbed, &cols[..n_in])?;
    let rows_of = |cols: &[Vec<f64>], gp_cols: Vec<Vec<f64>>, target: &str, t: usize| {
        let x_phys = &cols[..n_in];
        let n = cols[0].len();
        let factor: Vec<f64> = match settings.similarity.as_ref().and_then(|s| s.scaled(target)) {
            Some(sc) => (0..n)
                .map(|r| {
                    sc.factor
                        .value(|name| x_phys[var_of(settings, name) as usize][r])
                })
                .collect(),
            None => vec![1.0; n],
        };
        let y = cols[n_in + t]
            .iter()
            .zip(&factor)
            .map(|(v, f)| v / f)
            .collect();
        ProblemRows {
            x: gp_cols,
            y,
            factor,
        }
    };
    let validation_cols = match &settings.validation {
        Some(v) => {
            let vc = columns(v, settings)?;
            let mut gp_cols: Vec<Vec<f64>> = scaling
                .gp_inputs
                .iter()
                .map(|&k| {
                    vc[k]
                        .iter()
                        .map(|&x| scaling.inputs[k].transform.apply(x))
                        .collect()
                })
                .collect();
            for g in &scaling.groups {
                gp_cols.push(scaled_group(
                    settings,
                    &g.group.monomial,
                    &g.transform,
                    &vc[..n_in],
                ));
            }
            Some((vc, gp_cols))
        }
        None => None,
    };
    Ok(settings
        .targets
        .iter()
        .enumerate()
        .map(|(t, target)| RegressionProblem {
            response: target.clone(),
            fitted: settings
                .similarity
                .as_ref()
                .and_then(|s| s.scaled(target))
                .map_or_else(|| target.clone(), |s| s.fitted.clone()),
            symbols: scaling.gp_symbols.clone(),
            train: rows_of(&cols, scaling.gp_cols.clone(), target, t),
            validation: validation_cols
                .as_ref()
                .map(|(vc, g)| rows_of(vc, g.clone(), target, t)),
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::similarity::{Group, Monomial, ScaledResponse, Similarity};

    /// `coefficient` times the product of `powers`.
    fn mono(coefficient: f64, powers: &[(&str, f64)]) -> Monomial {
        Monomial {
            coefficient,
            powers: powers.iter().map(|(n, p)| (n.to_string(), *p)).collect(),
        }
    }

    /// K = E / (rho d) and the contact pull A = ced E^(-2/3) (rho d)^(-1/3).
    fn stiffness_and_pull() -> Vec<Group> {
        let third = 1.0 / 3.0;
        vec![
            group("K", mono(1.0, &[("E", 1.0), ("rho", -1.0), ("d", -1.0)])),
            group(
                "A",
                mono(
                    1.0,
                    &[
                        ("ced", 1.0),
                        ("rho", -third),
                        ("d", -third),
                        ("E", -2.0 * third),
                    ],
                ),
            ),
        ]
    }

    /// A group named (and described) `name`.
    fn group(name: &str, monomial: Monomial) -> Group {
        Group {
            name: name.into(),
            what: name.into(),
            monomial,
        }
    }

    /// The saved equation computes a group through a sum of logs; GP must have seen exactly those
    /// values, the smallest scaled to exactly 0 (a tree with sqrt(K_u) fitted on them was NaN at
    /// the training row of smallest K once saved, and its training metrics were computed on
    /// zeros).
    #[test]
    fn the_saved_equation_sees_the_groups_gp_saw_bit_for_bit() {
        let k = Monomial {
            coefficient: 1.0 / 9.81e-3,
            powers: vec![("E".into(), 1.0), ("rho".into(), -1.0), ("d".into(), -1.0)],
        };
        let similarity = Similarity {
            support: vec![],
            groups: vec![Group {
                name: "K".into(),
                what: "stiffness".into(),
                monomial: k,
            }],
            scaled: vec![],
        };
        let n = 50;
        let e: Vec<f64> = (0..n).map(|r| 2.5e6 * 1.0731f64.powi(r) + 0.137).collect();
        let table = TrainingTable::from_columns(
            "t.csv",
            vec![
                ("E".into(), e.clone()),
                ("rho".into(), vec![2600.0; n as usize]),
                ("d".into(), vec![10.0; n as usize]),
                ("y".into(), e.iter().map(|v| v.ln()).collect()),
            ],
        )
        .unwrap();
        let inputs: Vec<String> = vec!["E".into(), "rho".into(), "d".into()];
        let settings = FitSettings::new(inputs, vec!["y".into()])
            .test_fraction(0.0)
            .similarity(similarity);
        let cols = columns(&table, &settings).unwrap();
        let sc = scaling(&table, &settings, &settings.absorbed(), &cols[..3]).unwrap();
        let k_var = sc.gp_inputs.len() as u16;
        for tree in [
            vec![gp::Node::Var(k_var)],
            vec![gp::Node::Var(k_var), gp::Node::Sqrt],
        ] {
            let program = sc.compose(&settings, &tree, None);
            let (ok, saved) = predict(&program, &Dataset::new(cols[..3].to_vec(), vec![0.0; 50]));
            assert!(ok, "{tree:?} is not finite on the training rows");
            if tree.len() == 1 {
                assert_eq!(saved, sc.gp_cols[k_var as usize], "not bit for bit");
                assert_eq!(saved.iter().copied().fold(f64::INFINITY, f64::min), 0.0);
            }
        }
    }

    /// A table held at one rho and one d (as the shipped campaign is), whose density is
    /// rho * (0.5 + 0.02 ln K) with K = E / (rho d): the fitted model must be right at other rho
    /// and d too, since it is written in K and rho.
    #[test]
    fn an_extension_fits_only_the_correction_and_keeps_the_old_equation() {
        let dir = tempfile::tempdir().unwrap();
        let (old, new) = (dir.path().join("old.csv"), dir.path().join("new.csv"));
        let mut a = String::from("x,y\n");
        let mut b = String::from("x,z,y\n");
        for r in 0..40 {
            let x = 1.0 + 0.05 * r as f64;
            let z = (r as f64 * 0.618).fract();
            a.push_str(&format!("{x},{}\n", 3.0 + 2.0 * x));
            b.push_str(&format!("{x},{z},{}\n", 3.0 + 2.0 * x + 5.0 * z * x));
        }
        std::fs::write(&old, a).unwrap();
        std::fs::write(&new, b).unwrap();
        let config = gp::Config {
            population: 300,
            generations: 10,
            ..gp::Config::default()
        };
        let t = |p: &std::path::Path, inputs: &[&str]| {
            let inputs: Vec<String> = inputs.iter().map(|s| s.to_string()).collect();
            TrainingTable::read_csv(p, &inputs, &["y".into()]).unwrap()
        };
        let base = fit(
            &t(&old, &["x"]),
            &FitSettings::new(vec!["x".into()], vec!["y".into()])
                .test_fraction(0.0)
                .config(config.clone()),
            |_, _| {},
        )
        .unwrap()
        .model;
        let mut settings = FitSettings::new(vec!["x".into(), "z".into()], vec!["y".into()])
            .test_fraction(0.0)
            .config(config);
        settings.extends = Some(Box::new(base.clone()));
        let m = fit(&t(&new, &["x", "z"]), &settings, |_, _| {})
            .unwrap()
            .model;
        let y = &m.responses[0];
        assert!(y.train.r2 > 0.99999, "{:?} {}", y.train, y.equation);
        for x in [1.1, 2.3] {
            let got = m.predict_point(y, &[x, 0.7]);
            assert!((got - (3.0 + 2.0 * x + 3.5 * x)).abs() < 1e-3, "{got}");
        }
        // A fit whose inputs lack one the old equation reads is refused.
        let mut settings = FitSettings::new(vec!["z".into()], vec!["y".into()]).test_fraction(0.0);
        settings.extends = Some(Box::new(base));
        let e = fit(&t(&new, &["z"]), &settings, |_, _| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains("reads x"), "{e}");
    }

    #[test]
    fn a_group_that_reaches_zero_is_fitted_linearly_and_holds_at_other_sizes() {
        // y = 10 + 0.5 C with C = 0.1 ced / (rho d), ced from 0 (cohesion off) up.
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("t.csv");
        let mut text = String::from("ced,rho,d,y\n");
        for r in 0..40 {
            let ced = 500.0 * r as f64;
            text.push_str(&format!(
                "{ced},2000,4,{}\n",
                10.0 + 0.5 * 0.1 * ced / 8000.0
            ));
        }
        std::fs::write(&data, text).unwrap();
        let similarity = Similarity {
            support: vec![],
            groups: vec![Group {
                name: "C".into(),
                what: "cohesion".into(),
                monomial: Monomial {
                    coefficient: 0.1,
                    powers: vec![
                        ("ced".into(), 1.0),
                        ("rho".into(), -1.0),
                        ("d".into(), -1.0),
                    ],
                },
            }],
            scaled: vec![],
        };
        let inputs: Vec<String> = vec!["ced".into(), "rho".into(), "d".into()];
        let targets: Vec<String> = vec!["y".into()];
        let settings = FitSettings::new(inputs.clone(), targets.clone())
            .test_fraction(0.0)
            .config(gp::Config {
                population: 300,
                generations: 5,
                ..gp::Config::default()
            })
            .similarity(similarity);
        let table = TrainingTable::read_csv(&data, &inputs, &targets).unwrap();
        let m = fit(&table, &settings, |_, _| {}).unwrap().model;
        assert!(matches!(m.groups[0].transform, Transform::Linear { .. }));
        assert_eq!(m.groups[0].domain[0], 0.0);
        let y = &m.responses[0];
        assert!(y.train.r2 > 0.999999, "{:?}", y.train);
        // At another density and size, C decides: the same C, the same y, zero included.
        for (ced, rho, d) in [(0.0, 1000.0, 1.0), (1e4, 2500.0, 2.0), (3e3, 500.0, 9.0)] {
            let want = 10.0 + 0.05 * ced / (rho * d);
            let got = m.predict_point(y, &[ced, rho, d]);
            assert!((got - want).abs() < 1e-6 * want, "{got} {want}");
        }
    }

    /// A model fitted in K = E / (rho d) to density = rho (0.5 + 0.02 ln K) and angle = 20 +
    /// 15 mu, K from 125 to 2845, with its settings and table.
    fn grouped_fixture() -> (Metamodel, FitSettings, TrainingTable) {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("t.csv");
        let mut text = String::from("E,rho,d,mu,density,angle\n");
        for r in 0..60 {
            let e = 1e6 * (1.0 + 0.37 * r as f64);
            let mu = (r as f64 * 0.618).fract();
            let k: f64 = e / (2000.0 * 4.0);
            let density = 2000.0 * (0.5 + 0.02 * k.ln());
            text.push_str(&format!("{e},2000,4,{mu},{density},{}\n", 20.0 + 15.0 * mu));
        }
        std::fs::write(&data, text).unwrap();
        let k = Monomial {
            coefficient: 1.0,
            powers: vec![("E".into(), 1.0), ("rho".into(), -1.0), ("d".into(), -1.0)],
        };
        let similarity = Similarity {
            support: vec![],
            groups: vec![Group {
                name: "K".into(),
                what: "stiffness".into(),
                monomial: k,
            }],
            scaled: vec![ScaledResponse {
                response: "density".into(),
                factor: Monomial {
                    coefficient: 1.0,
                    powers: vec![("rho".into(), 1.0)],
                },
                fitted: "phi".into(),
            }],
        };
        let inputs: Vec<String> = vec!["E".into(), "rho".into(), "d".into(), "mu".into()];
        let targets: Vec<String> = vec!["density".into(), "angle".into()];
        let settings = FitSettings::new(inputs.clone(), targets.clone())
            .test_fraction(0.0)
            .config(gp::Config {
                population: 300,
                generations: 5,
                ..gp::Config::default()
            })
            .similarity(similarity);
        let table = TrainingTable::read_csv(&data, &inputs, &targets).unwrap();
        let m = fit(&table, &settings, |_, _| {}).unwrap().model;
        (m, settings, table)
    }

    #[test]
    fn a_fit_in_groups_extends_to_the_absorbed_inputs() {
        let (m, settings, table) = grouped_fixture();
        let density = &m.responses[0];
        assert!(density.train.r2 > 0.999999, "{:?}", density.train);
        let g = density.grouped.as_ref().unwrap();
        assert_eq!(g.fitted, "phi");
        assert!(
            !g.equation.contains("rho") && !g.equation.contains("E"),
            "{}",
            g.equation
        );
        // At another density and size with the same K range: rho * phi(K).
        for (e, rho, d) in [(2e7, 2600.0, 3.0), (1e7, 1000.0, 5.0)] {
            let kv: f64 = e / (rho * d);
            let want = rho * (0.5 + 0.02 * kv.ln());
            let got = m.predict_point(density, &[e, rho, d, 0.5]);
            assert!((got / want - 1.0).abs() < 1e-6, "{got} {want}");
            // Without a space file an absorbed input's bounds are the data's (one value); the
            // group is inside its range.
            let out = m.outside_domain(&[e, rho, d, 0.5]);
            assert!(
                out.iter().all(|o| ["E", "rho", "d"].contains(&o.0)),
                "{out:?}"
            );
            // Gradient by the chain rule through K and the factor.
            let (_, grad) = m.value_and_gradient(density, &[e, rho, d, 0.5]).unwrap();
            let want_drho = 0.5 + 0.02 * kv.ln() - 0.02;
            assert!((grad[1] / want_drho - 1.0).abs() < 1e-5, "{grad:?}");
        }
        // The angle's equation reads no group and no absorbed input.
        assert_eq!(m.responses[1].uses, vec!["mu".to_string()]);

        // The problems a benchmark hands to other regressors: the same columns, the density as
        // phi = density / rho with rho as its factor, the validation rows scaled alike.
        let settings = settings.validation(table.clone());
        let problems = regression_problems(&table, &settings).unwrap();
        assert_eq!(problems.len(), 2);
        let (dens, angle) = (&problems[0], &problems[1]);
        assert_eq!(dens.symbols, vec!["mu".to_string(), "K_u".to_string()]);
        assert_eq!(
            (dens.fitted.as_str(), angle.fitted.as_str()),
            ("phi", "angle")
        );
        let v = dens.validation.as_ref().unwrap();
        assert_eq!(v, &dens.train);
        let (k_lo, k_hi): (f64, f64) = (1e6 / 8000.0, 1e6 * (1.0 + 0.37 * 59.0) / 8000.0);
        for r in 0..60 {
            let k: f64 = 1e6 * (1.0 + 0.37 * r as f64) / 8000.0;
            assert!((dens.train.y[r] - (0.5 + 0.02 * k.ln())).abs() < 1e-12);
            assert_eq!(dens.train.factor[r], 2000.0);
            let k_u = (k.ln() - k_lo.ln()) / (k_hi.ln() - k_lo.ln());
            assert!((dens.train.x[1][r] - k_u).abs() < 1e-12, "row {r}");
            assert_eq!(angle.train.factor[r], 1.0);
        }
        // K beyond the data is outside the domain, named by the group.
        let out = m.outside_domain(&[1e9, 2000.0, 4.0, 0.5]);
        assert!(out.iter().any(|o| o.0 == "K"), "{out:?}");
        assert!(m.outside_domain(&[1e7, 2000.0, 4.0, 0.5]).is_empty());
    }

    #[test]
    fn the_rigid_limit_answers_beyond_the_data_with_the_lines_shift_and_scatter() {
        use crate::metamodel::rigid_fit::{fit_rigid_limit, Line, RigidFit};
        let (m, _, _) = grouped_fixture();
        let hi = m.groups[0].domain[1];
        // Lines at three frictions: beyond the stiffest data the solid fraction falls by
        // (0.010 + 0.004 mu) per decade and the angle rises by 0.5 deg per decade.
        let truth = |k: f64, mu: f64| -> [f64; 2] {
            let dec = (k / hi).log10().max(0.0);
            let phi = 0.5 + 0.02 * k.min(hi).ln() - (0.010 + 0.004 * mu) * dec;
            [2000.0 * phi, 20.0 + 15.0 * mu + 0.5 * dec]
        };
        let lines: Vec<Line> = [0.2, 0.5, 0.8]
            .iter()
            .map(|&mu| Line {
                label: format!("mu {mu}"),
                inputs: vec![1e6, 2000.0, 4.0, mu],
                runs: [1.0, 10.0, 100.0]
                    .iter()
                    .map(|f| (hi * f, truth(hi * f, mu).to_vec()))
                    .collect(),
            })
            .collect();
        let fit = RigidFit {
            group: "K",
            along: "E",
            wall: None,
            along_max: 1e12,
            source: "test".into(),
            edge_decades: crate::metamodel::rigid_fit::EDGE_DECADES,
        };
        let lm = fit_rigid_limit(&m, &fit, &lines).unwrap();
        let lim = lm.rigid_limit.as_ref().unwrap();
        assert!(
            (lim.reach[1] / (100.0 * hi) - 1.0).abs() < 1e-9,
            "{:?}",
            lim.reach
        );
        assert_eq!(lim.reach[0], m.groups[0].domain[0], "no soft lines");
        // Inside the data nothing changes, to the bit.
        let inside = [8e6, 2000.0, 4.0, 0.5];
        for r in &m.responses {
            assert_eq!(
                lm.predict_point(r, &inside).to_bits(),
                m.predict_point(r, &inside).to_bits()
            );
            assert_eq!(lm.extrapolation_sd(r, &inside), 0.0);
        }
        // Thirty times stiffer than the data, at another friction: the equation at the edge plus
        // the lines' shift, within the lines' scatter.
        let x = [30.0 * hi * 8000.0, 2000.0, 4.0, 0.35];
        assert!(
            lm.outside_domain(&x).is_empty(),
            "{:?}",
            lm.outside_domain(&x)
        );
        assert!(!m.outside_domain(&x).is_empty());
        let want = truth(30.0 * hi, 0.35);
        for (r, resp) in lm.responses.iter().enumerate() {
            let got = lm.predict_point(resp, &x);
            let sd = lm.extrapolation_sd(resp, &x);
            let w = want[r];
            let fit_err = 1e-3 * w.abs();
            assert!(
                (got - w).abs() < 2.0 * sd + fit_err,
                "{}: {got} {w} sd {sd}",
                resp.name
            );
            let (v, g) = lm.value_and_gradient(resp, &x).unwrap();
            assert_eq!(v.to_bits(), got.to_bits());
            assert!(g.iter().all(|g| g.is_finite()));
        }
        // The density's scatter comes from the friction the shift depends on; the angle's shift
        // is the same on every line.
        let dens = &lm.responses[0];
        assert!(lm.extrapolation_sd(dens, &x) > 0.0);
        assert!(lm.extrapolation_sd(&lm.responses[1], &x) < 1e-9);
        assert!(lm.prediction_error(dens, &x).unwrap() >= lm.extrapolation_sd(dens, &x));
        // Past the stiffest line the model does not answer.
        let far = [300.0 * hi * 8000.0, 2000.0, 4.0, 0.5];
        assert!(lm.outside_domain(&far).iter().any(|o| o.0 == "K"));
        assert!(lm.predict_point(dens, &far).is_nan());
        // The limit is saved with the model.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.json");
        lm.save(&path).unwrap();
        let back = Metamodel::load(&path).unwrap();
        assert_eq!(back.rigid_limit, lm.rigid_limit);
        assert_eq!(
            back.predict_point(dens, &x).to_bits(),
            lm.predict_point(dens, &x).to_bits()
        );
    }

    /// Lines run for another model's edge: their first run 0.0101 decades beyond this one's
    /// (the widened shear-box model's 9.77e6 against the lines' 1e7) stands for the edge only
    /// with a wider tolerance, which is bounded.
    #[test]
    fn a_line_run_just_off_the_edge_stands_for_it_only_within_the_stated_tolerance() {
        use crate::metamodel::rigid_fit::{fit_rigid_limit, Line, RigidFit, EDGE_DECADES};
        let (m, _, _) = grouped_fixture();
        let hi = m.groups[0].domain[1];
        let off = 10f64.powf(0.0101);
        let lines: Vec<Line> = [0.2, 0.8]
            .iter()
            .map(|&mu| Line {
                label: format!("mu {mu}"),
                inputs: vec![1e6, 2000.0, 4.0, mu],
                runs: [off, 10.0, 100.0]
                    .iter()
                    .map(|&f| {
                        let dec = f64::log10(f);
                        (hi * f, vec![1000.0 - 5.0 * dec, 30.0 + mu + 0.5 * dec])
                    })
                    .collect(),
            })
            .collect();
        let fit = |edge_decades: f64| RigidFit {
            group: "K",
            along: "E",
            wall: None,
            along_max: 1e12,
            source: "test".into(),
            edge_decades,
        };
        let err = fit_rigid_limit(&m, &fit(EDGE_DECADES), &lines).unwrap_err();
        assert!(err.to_string().contains("within 0.01 decades"), "{err}");
        let lim = fit_rigid_limit(&m, &fit(0.02), &lines)
            .unwrap()
            .rigid_limit
            .unwrap();
        assert!(
            (lim.reach[1] / (100.0 * hi) - 1.0).abs() < 1e-9,
            "{:?}",
            lim.reach
        );
        // The angle's shifts count from the run nearest the edge: +0.5 deg per decade beyond it.
        let angle = lim
            .curves
            .iter()
            .find(|c| c.response == m.responses[1].name && c.stiff)
            .unwrap();
        let last = angle.knots.last().unwrap();
        assert!((last.decades - 2.0).abs() < 1e-9, "{last:?}");
        assert!((last.value - 0.5 * (2.0 - 0.0101)).abs() < 1e-9, "{last:?}");
        for bad in [0.0, -0.01, 0.06, f64::NAN] {
            let err = fit_rigid_limit(&m, &fit(bad), &lines).unwrap_err();
            assert!(err.to_string().contains("edge tolerance"), "{bad}: {err}");
        }
    }

    #[test]
    fn a_support_group_bounds_the_model_where_the_fitted_groups_box_holds_no_run() {
        // Runs over K = E / (rho d) 250-2500 and C = ced / (rho d) 0-100, fitted in K and the
        // contact pull A = C K^(-2/3); the box of (K, A) holds high A at high K, where no run
        // has C that large: the support group C keeps that corner out.
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("t.csv");
        let mut text = String::from("E,rho,d,ced,y\n");
        for r in 0..40 {
            let e = 2e6 * (1.0 + 9.0 * (r as f64 * 0.377).fract());
            let ced = 8000.0 * 100.0 * (r as f64 * 0.618).fract();
            text.push_str(&format!("{e},2000,4,{ced},{}\n", 10.0 + ced / 8000.0));
        }
        std::fs::write(&data, text).unwrap();
        let inputs: Vec<String> = ["E", "rho", "d", "ced"].map(String::from).to_vec();
        let settings = FitSettings::new(inputs.clone(), vec!["y".into()])
            .test_fraction(0.0)
            .config(gp::Config {
                population: 100,
                generations: 2,
                ..gp::Config::default()
            })
            .similarity(Similarity {
                groups: stiffness_and_pull(),
                support: vec![group(
                    "C",
                    mono(1.0, &[("ced", 1.0), ("rho", -1.0), ("d", -1.0)]),
                )],
                scaled: vec![],
            });
        let table = TrainingTable::read_csv(&data, &inputs, &["y".to_string()]).unwrap();
        let m = fit(&table, &settings, |_, _| {}).unwrap().model;
        let names: Vec<(&str, bool)> = m
            .groups
            .iter()
            .map(|g| (g.group.name.as_str(), g.support))
            .collect();
        assert_eq!(names, [("K", false), ("A", false), ("C", true)]);
        let [k_lo, k_hi] = m.groups[0].domain;
        let a_hi = m.groups[1].domain[1];
        let c_hi = m.groups[2].domain[1];
        assert!(
            k_lo < 300.0 && k_hi > 2000.0 && c_hi > 90.0,
            "{k_lo} {k_hi} {c_hi}"
        );
        // E moves K alone: the pull's own input, ced, holds A.
        assert_eq!(m.along_input("K", "E"), Some(0));
        assert_eq!(m.along_input("A", "ced"), Some(3));
        assert_eq!(m.group_of_input("ced").unwrap().group.name, "A");
        // At the stiff end, 1.5 times the largest C: A is inside its box, C is not.
        let e = 0.99 * k_hi * 8000.0;
        let x = [e, 2000.0, 4.0, 1.5 * c_hi * 8000.0];
        let a = m.group_value(&m.groups[1].group, &x);
        assert!(a < a_hi, "{a} {a_hi}");
        // (ced, an input, is out too here: the runs held rho and d, so its range is C's.)
        let out = m.outside_domain(&x);
        assert!(out.iter().any(|o| o.0 == "C"), "{out:?}");
        assert!(!out.iter().any(|o| o.0 == "K" || o.0 == "A"), "{out:?}");
        assert!(m
            .outside_domain(&[e, 2000.0, 4.0, 0.5 * c_hi * 8000.0])
            .is_empty());
        // The flag is saved with the model.
        let path = dir.path().join("m.json");
        m.save(&path).unwrap();
        let back = Metamodel::load(&path).unwrap();
        assert!(back.groups[2].support && !back.groups[1].support);
    }

    #[test]
    fn a_group_left_unread_bounds_the_model_but_moves_no_prediction() {
        // y = 10 + 5 A with A = ced E^(-2/3) (rho d)^(-1/3): fitted in K and A with K left
        // unread, the equation cannot follow K, and K's range over the runs still bounds it.
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("t.csv");
        let third = 1.0 / 3.0;
        let a_of = |e: f64, ced: f64| ced * e.powf(-2.0 * third) * 8000f64.powf(-third);
        let mut text = String::from("E,rho,d,ced,y\n");
        for r in 0..40 {
            let e = 2e6 * (1.0 + 9.0 * (r as f64 * 0.377).fract());
            let ced = 8000.0 * 100.0 * (r as f64 * 0.618).fract();
            text.push_str(&format!("{e},2000,4,{ced},{}\n", 10.0 + 5.0 * a_of(e, ced)));
        }
        std::fs::write(&data, text).unwrap();
        let similarity = Similarity {
            groups: stiffness_and_pull(),
            support: vec![],
            scaled: vec![],
        };
        let err = similarity.clone().with_unread(&["Z".into()]).unwrap_err();
        assert!(err.contains("Z") && err.contains("K, A"), "{err}");
        let similarity = similarity.with_unread(&["K".into()]).unwrap();
        // A fitted group is no support group to drop; the unread one is.
        let err = similarity
            .clone()
            .without_support(&["A".into()])
            .unwrap_err();
        assert!(err.contains("A") && err.contains("(they are: K)"), "{err}");
        let unbounded = similarity.clone().without_support(&["K".into()]).unwrap();
        assert!(unbounded.support.is_empty() && unbounded.groups.len() == 1);
        // E enters only the unread K and A: still not a raw variable of the fit.
        assert_eq!(similarity.absorbed(), ["ced", "rho", "d", "E"]);
        let inputs: Vec<String> = ["E", "rho", "d", "ced"].map(String::from).to_vec();
        let settings = FitSettings::new(inputs.clone(), vec!["y".into()])
            .test_fraction(0.0)
            .config(gp::Config {
                population: 200,
                generations: 5,
                ..gp::Config::default()
            })
            .similarity(similarity);
        let table = TrainingTable::read_csv(&data, &inputs, &["y".to_string()]).unwrap();
        let m = fit(&table, &settings, |_, _| {}).unwrap().model;
        let names: Vec<(&str, bool)> = m
            .groups
            .iter()
            .map(|g| (g.group.name.as_str(), g.support))
            .collect();
        assert_eq!(names, [("A", false), ("K", true)]);
        // Two points with the same A and K 4x apart: the same prediction.
        let (e1, ced1) = (4e6, 2e5);
        let (e2, ced2) = (16e6, 2e5 * 4f64.powf(2.0 * third));
        assert!((a_of(e1, ced1) - a_of(e2, ced2)).abs() < 1e-12);
        let r = &m.responses[0];
        let p1 = m.predict_point(r, &[e1, 2000.0, 4.0, ced1]);
        let p2 = m.predict_point(r, &[e2, 2000.0, 4.0, ced2]);
        assert!(
            p1.is_finite() && (p1 - p2).abs() < 1e-9 * p1.abs(),
            "{p1} {p2}"
        );
        // K's range over the runs (E 2e6 to 2e7 at rho d 8000) bounds the model.
        let [k_lo, k_hi] = m.groups[1].domain;
        assert!(k_lo > 200.0 && k_hi < 2600.0, "{k_lo} {k_hi}");
        let out = m.outside_domain(&[5e7, 2000.0, 4.0, ced1]);
        assert!(out.iter().any(|o| o.0 == "K"), "{out:?}");
    }

    #[test]
    fn a_cohesion_group_is_carried_to_the_stiffness_edge_with_its_scatter() {
        use crate::metamodel::rigid_fit::{fit_cohesion, CohesionLine};
        use crate::metamodel::rigid_limit::{Curve, Form, Knot, LeaveOneOut, RigidLimit};
        // y = 10 + C with C = ced / (rho d), K = E / (rho d) from 125 to 2845, C from 0 to 100.
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("t.csv");
        let mut text = String::from("E,rho,d,ced,y\n");
        for r in 0..40 {
            let e = 1e6 * (1.0 + 0.566 * r as f64);
            let ced = 8000.0 * 100.0 * (r as f64 * 0.618).fract();
            text.push_str(&format!("{e},2000,4,{ced},{}\n", 10.0 + ced / 8000.0));
        }
        std::fs::write(&data, text).unwrap();
        let group = |name: &str, top: &str| Group {
            name: name.into(),
            what: name.into(),
            monomial: Monomial {
                coefficient: 1.0,
                powers: vec![(top.into(), 1.0), ("rho".into(), -1.0), ("d".into(), -1.0)],
            },
        };
        let inputs: Vec<String> = ["E", "rho", "d", "ced"].map(String::from).to_vec();
        let settings = FitSettings::new(inputs.clone(), vec!["y".into()])
            .test_fraction(0.0)
            .config(gp::Config {
                population: 200,
                generations: 3,
                ..gp::Config::default()
            })
            .similarity(Similarity {
                support: vec![],
                groups: vec![group("K", "E"), group("C", "ced")],
                scaled: vec![],
            });
        let table = TrainingTable::read_csv(&data, &inputs, &["y".to_string()]).unwrap();
        let mut m = fit(&table, &settings, |_, _| {}).unwrap().model;
        m.responses[0].replicate_sd = None;
        let hi = m.groups[0].domain[1];
        let c_hi = m.groups[1].domain[1];
        let y = &m.responses[0];
        assert!(y.train.rmse < 1e-6, "{:?}", y.train);
        m.rigid_limit = Some(RigidLimit {
            group: "K".into(),
            along: "E".into(),
            wall: None,
            reach: [m.groups[0].domain[0], 1000.0 * hi],
            curves: vec![Curve {
                response: "y".into(),
                stiff: true,
                form: Form::Shift,
                knots: vec![Knot {
                    decades: 3.0,
                    value: 0.0,
                    sd: 0.0,
                    scatter: 0.0,
                    lines: 2,
                }],
                leave_one_out: LeaveOneOut {
                    shift: Some(0.0),
                    slope: None,
                },
            }],
            lines: vec![],
            source: "test".into(),
            cohesion: vec![],
        });
        // The space's E and ced reach beyond the data's; the groups bound the model.
        m.inputs[0].domain[1] = 1e12;
        m.inputs[3].domain[1] = 1e12;
        // Lines that follow the similarity exactly (the cohesion effect at K beyond the edge
        // with C_e (K / K_e)^(2/3) is the edge's) and one that keeps its effect at the same C.
        let truth = |k: f64, c: f64| 10.0 + c * (hi / k.max(hi)).powf(2.0 / 3.0);
        let line = |label: &str, kept: f64| CohesionLine {
            label: label.into(),
            inputs: vec![1e6, 2000.0, 4.0, 0.0],
            runs: [(hi, 0.0), (hi, 50.0), (8.0 * hi, 0.0), (8.0 * hi, 200.0)]
                .iter()
                .map(|&(k, c)| (k, 8000.0 * c, vec![truth(k, c) + kept * c / 200.0]))
                .collect(),
        };
        let lines = [line("a", 0.0), line("b", 0.0)];
        let coh = fit_cohesion(&m, "C", "ced", ["E", "E"], &lines, "t".into(), None).unwrap();
        assert_eq!(coh.reference, 50.0);
        let k = &coh.curves[0].knots[0];
        assert!((k.decades - 8f64.log10()).abs() < 1e-12);
        assert!(k.sd < 1e-9 && k.mean.abs() < 1e-9, "{k:?}");
        let off = [line("a", 0.0), line("b", 4.0)];
        let coh_off = fit_cohesion(&m, "C", "ced", ["E", "E"], &off, "t".into(), None).unwrap();
        let k = &coh_off.curves[0].knots[0];
        // Line b gains 3 over the edge (4 at C 200 less 1 at C 50).
        assert!(
            (k.mean - 1.5).abs() < 1e-9 && (k.sd - 6.75f64.sqrt()).abs() < 1e-9,
            "{k:?}"
        );
        let mut coh = coh;
        coh.curves[0].knots[0].sd = 0.5;
        m.rigid_limit.as_mut().unwrap().cohesion = vec![coh];

        // Eight times stiffer than the data: the contact area a quarter, the cohesion read at
        // C / 4. A C twice the data's top is read inside it.
        let c = 2.0 * c_hi;
        let x = [8.0 * hi * 8000.0, 2000.0, 4.0, c * 8000.0];
        let y = &m.responses[0];
        let got = m.predict_point(y, &x);
        assert!((got - (10.0 + c / 4.0)).abs() < 1e-6, "{got}");
        assert!(
            m.outside_domain(&x).is_empty(),
            "{:?}",
            m.outside_domain(&x)
        );
        // The scatter at the carried C over the reference, the knot's sd at its decades.
        let sd = m.extrapolation_sd(y, &x);
        assert!((sd - 0.5 * (c / 4.0) / 50.0).abs() < 1e-9, "{sd}");
        // Twice the decades, twice the sd per unit of carried cohesion.
        let x2 = [64.0 * hi * 8000.0, 2000.0, 4.0, c * 8000.0];
        let sd2 = m.extrapolation_sd(y, &x2);
        assert!((sd2 - 2.0 * 0.5 * (c / 16.0) / 50.0).abs() < 1e-9, "{sd2}");
        // No cohesion, no scatter; inside the stiffness data, C is its own.
        assert_eq!(m.extrapolation_sd(y, &[x[0], 2000.0, 4.0, 0.0]), 0.0);
        let inside = [0.5 * hi * 8000.0, 2000.0, 4.0, c * 8000.0];
        assert!(m.outside_domain(&inside).iter().any(|o| o.0 == "C"));
        // A C that stays beyond the data at the edge is refused by name.
        let far = [8.0 * hi * 8000.0, 2000.0, 4.0, 5.0 * c_hi * 8000.0];
        assert!(m.outside_domain(&far).iter().any(|o| o.0 == "C"));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.json");
        m.save(&path).unwrap();
        let back = Metamodel::load(&path).unwrap();
        assert_eq!(back.rigid_limit, m.rigid_limit);

        // A correction fitted beyond its runs: they stop at hi / 8, so the lines' edge runs
        // are there and the scatter counts from there, inside the data as beyond it.
        let runs_edge = hi / 8.0;
        let early = |label: &str, kept: f64| CohesionLine {
            label: label.into(),
            inputs: vec![1e6, 2000.0, 4.0, 0.0],
            runs: [(runs_edge, 0.0), (runs_edge, 50.0), (hi, 0.0), (hi, 200.0)]
                .iter()
                .map(|&(k, c)| (k, 8000.0 * c, vec![10.0 + c * kept]))
                .collect(),
        };
        let coh = fit_cohesion(
            &m,
            "C",
            "ced",
            ["E", "E"],
            &[early("a", 0.0), early("b", 0.01)],
            "t".into(),
            Some(runs_edge),
        )
        .unwrap();
        assert_eq!(coh.runs_edge, Some(runs_edge));
        assert_eq!(coh.reference, 50.0);
        assert!((coh.curves[0].knots[0].decades - 8f64.log10()).abs() < 1e-12);
        for bad in [hi, 2.0 * hi] {
            let err = fit_cohesion(
                &m,
                "C",
                "ced",
                ["E", "E"],
                &[early("a", 0.0)],
                "t".into(),
                Some(bad),
            )
            .unwrap_err();
            assert!(
                err.to_string().contains("inside the model's range"),
                "{err}"
            );
        }
        let mut w = back;
        {
            let c = &mut w.rigid_limit.as_mut().unwrap().cohesion[0];
            c.runs_edge = Some(runs_edge);
        }
        let y = &w.responses[0];
        // Inside the data, four times stiffer than the runs' edge: C carried there is
        // C 4^(-2/3), the knot (sd 0.5 at 8x) read at 4x.
        let c = 0.5 * c_hi;
        let inside = [0.5 * hi * 8000.0, 2000.0, 4.0, c * 8000.0];
        let want = 0.5 * (4f64.log10() / 8f64.log10()) * c * 4f64.powf(-2.0 / 3.0) / 50.0;
        let sd = w.extrapolation_sd(y, &inside);
        assert!((sd - want).abs() < 1e-9, "{sd} against {want}");
        assert_eq!(w.prediction_error(y, &inside), Some(sd));
        assert_eq!(w.predict_point(y, &inside), m.predict_point(y, &inside));
        // Softer than the runs' edge: nothing added; no cohesion, nothing added.
        assert_eq!(
            w.extrapolation_sd(y, &[runs_edge * 4000.0, 2000.0, 4.0, c * 8000.0]),
            0.0
        );
        assert_eq!(w.extrapolation_sd(y, &[inside[0], 2000.0, 4.0, 0.0]), 0.0);
        // Beyond the model's edge the cohesion is still carried to it (the same prediction),
        // and the scatter counts 64x from the runs' edge: twice the knot's sd, at C / 16.
        let c = 2.0 * c_hi;
        let x = [8.0 * hi * 8000.0, 2000.0, 4.0, c * 8000.0];
        assert_eq!(w.predict_point(y, &x), m.predict_point(y, &x));
        let sd = w.extrapolation_sd(y, &x);
        assert!((sd - 2.0 * 0.5 * (c / 16.0) / 50.0).abs() < 1e-9, "{sd}");
        // A file's runs_edge must lie inside the stiffness group's range, with a scatter curve
        // for every response.
        let path = dir.path().join("edge.json");
        let lo = w.groups[0].domain[0];
        for (edge, good) in [(runs_edge, true), (2.0 * hi, false), (0.5 * lo, false)] {
            let mut v = w.clone();
            v.rigid_limit.as_mut().unwrap().cohesion[0].runs_edge = Some(edge);
            v.save(&path).unwrap();
            match Metamodel::load(&path) {
                Ok(_) => assert!(good, "{edge} was taken"),
                Err(e) => assert!(!good && e.to_string().contains("runs_edge"), "{edge}: {e}"),
            }
        }
        let mut v = w.clone();
        v.rigid_limit.as_mut().unwrap().cohesion[0].curves.clear();
        v.save(&path).unwrap();
        let err = Metamodel::load(&path).unwrap_err().to_string();
        assert!(err.contains("a scatter curve for every response"), "{err}");
    }
}
