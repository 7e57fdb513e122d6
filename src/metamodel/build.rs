//! Fitting a metamodel to a table: split, scale, one GP run per response, metrics, figures.

use super::model::{
    residual_quantiles, DataSource, FrontMember, Input, Metamodel, Metrics, ResponseModel,
    Transform, FORMAT, VERSION,
};
use super::table::{read_columns, Columns};
use crate::dem::contact::{ModelClass, Pair};
use crate::error::{Error, Result};
use crate::gp::{self, expr, Dataset};
use crate::numeric::fnv1a64;
use crate::space::{Scale, Space};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use std::path::PathBuf;

#[derive(Clone, Debug)]
pub struct FitOptions {
    pub data: PathBuf,
    pub inputs: Vec<String>,
    pub targets: Vec<String>,
    /// Share of rows held out (seeded shuffle), in [0, 0.9].
    pub test_fraction: f64,
    /// Scale inputs to the unit interval as the space file says (linear or log).
    pub space: Option<PathBuf>,
    pub config: gp::Config,
    /// Directory for the parity plot and residual histogram of each response.
    pub plots: Option<PathBuf>,
    /// The model class of the data when the table does not say (`--model-class`); a campaign
    /// table's `model_class` column and the space's `[model]` must agree with it.
    pub model_class: Option<ModelClass>,
}

pub struct FitReport {
    pub model: Metamodel,
    pub figures: Vec<PathBuf>,
}

fn transforms(opts: &FitOptions) -> Result<Vec<Transform>> {
    let Some(path) = &opts.space else {
        return Ok(vec![Transform::Identity; opts.inputs.len()]);
    };
    let space = Space::from_file(path)?;
    let file = path.display().to_string();
    opts.inputs
        .iter()
        .map(|name| {
            let p = space.get(name).ok_or_else(|| {
                Error::input(
                    &file,
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
/// marks an experiment without a contact law), else `--model-class`, else the space's `[model]
/// class`; `None` when nothing says (a table that did not come from DEM runs). Sources that
/// disagree are refused.
fn data_class(
    file: &str,
    cols: &Columns,
    flag: Option<ModelClass>,
    space: Option<(ModelClass, String)>,
) -> Result<Option<ModelClass>> {
    let mut table: Option<Option<ModelClass>> = None;
    if let Some(k) = cols.header.iter().position(|h| h == "model_class") {
        let mut first: Option<(Option<ModelClass>, String, usize)> = None;
        for (row, rec) in cols.records.iter().enumerate() {
            let label = rec.get(k).map(String::as_str).unwrap_or("");
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
        table = first.map(|f| f.0);
    }
    let given = [
        table
            .flatten()
            .map(|c| (c, format!("column model_class of {file}"))),
        flag.map(|c| (c, "--model-class".to_string())),
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

/// Fits one equation per target. `progress(target, state)` is called every generation.
pub fn fit_table(
    opts: &FitOptions,
    mut progress: impl FnMut(&str, &gp::Progress),
) -> Result<FitReport> {
    let file = opts.data.display().to_string();
    if opts.inputs.is_empty() {
        return Err(Error::invalid(
            "--inputs: expected at least one input column",
        ));
    }
    if opts.targets.is_empty() {
        return Err(Error::invalid(
            "--targets: expected at least one target column",
        ));
    }
    for (option, list) in [("--inputs", &opts.inputs), ("--targets", &opts.targets)] {
        if let Some((k, name)) = list
            .iter()
            .enumerate()
            .find(|(k, n)| list[..*k].contains(n))
        {
            return Err(Error::invalid(format!(
                "{option}: {name} is given twice (position {}); expected each column once",
                k + 1
            )));
        }
    }
    for t in &opts.targets {
        if opts.inputs.contains(t) {
            return Err(Error::invalid(format!(
                "--targets: {t} is also an input; a response cannot explain itself"
            )));
        }
    }
    if !(0.0..=0.9).contains(&opts.test_fraction) {
        return Err(Error::invalid(format!(
            "--test-fraction: expected a value in [0, 0.9], got {}",
            opts.test_fraction
        )));
    }
    opts.config
        .check()
        .map_err(|e| Error::invalid(format!("GP settings: {e}")))?;
    let transforms = transforms(opts)?;
    let bytes = std::fs::read(&opts.data).map_err(|e| Error::io(&opts.data, e))?;
    let names: Vec<String> = opts.inputs.iter().chain(&opts.targets).cloned().collect();
    let cols = read_columns(&opts.data, &names)?;
    let space_class = match &opts.space {
        Some(p) => Space::from_file(p)?
            .model_class
            .map(|c| (c, p.display().to_string())),
        None => None,
    };
    let class = data_class(&file, &cols, opts.model_class, space_class)?;
    if let Some(class) = &class {
        for name in &opts.inputs {
            class
                .refuse_inactive(name, &Pair::BOTH, "the data")
                .map_err(|e| Error::invalid(format!("--inputs {name}: {e}")))?;
        }
    }
    let n = cols.records.len();
    let n_in = opts.inputs.len();
    let x_phys = &cols.values[..n_in];
    for (k, t) in transforms.iter().enumerate() {
        if let Transform::Log { .. } = t {
            if let Some(v) = x_phys[k].iter().find(|v| **v <= 0.0) {
                return Err(Error::input(
                    &file,
                    format!("column {}", opts.inputs[k]),
                    format!("positive values for its log scale, got {v}"),
                ));
            }
        }
    }
    let n_test = (opts.test_fraction * n as f64).round() as usize;
    if n - n_test < 5 {
        return Err(Error::input(
            &file,
            "rows",
            format!(
                "at least 5 training rows, got {} ({n} usable rows)",
                n - n_test
            ),
        ));
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(
        opts.config.seed,
    ));
    let (test_idx, train_idx) = order.split_at(n_test);
    let (mut train_idx, mut test_idx) = (train_idx.to_vec(), test_idx.to_vec());
    train_idx.sort_unstable();
    test_idx.sort_unstable();

    let inputs: Vec<Input> = opts
        .inputs
        .iter()
        .zip(&transforms)
        .zip(x_phys)
        .map(|((name, t), col)| Input {
            name: name.clone(),
            transform: t.clone(),
            domain: [
                col.iter().copied().fold(f64::INFINITY, f64::min),
                col.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            ],
        })
        .collect();
    let symbols: Vec<String> = inputs.iter().map(Input::symbol).collect();
    let xt: Vec<Vec<f64>> = inputs
        .iter()
        .zip(x_phys)
        .map(|(i, c)| c.iter().map(|&v| i.transform.apply(v)).collect())
        .collect();
    let pick = |col: &[f64], idx: &[usize]| idx.iter().map(|&i| col[i]).collect::<Vec<f64>>();

    let mut responses = Vec::new();
    let mut figures = Vec::new();
    for (t, target) in opts.targets.iter().enumerate() {
        let y = &cols.values[n_in + t];
        let train = Dataset::new(
            xt.iter().map(|c| pick(c, &train_idx)).collect(),
            pick(y, &train_idx),
        );
        if train.y_var() <= 0.0 {
            return Err(Error::input(
                &file,
                format!("column {target}"),
                "a response that varies (all training values are equal)",
            ));
        }
        let test = Dataset::new(
            xt.iter().map(|c| pick(c, &test_idx)).collect(),
            pick(y, &test_idx),
        );
        let res = gp::fit(&train, &opts.config, |p| progress(target, p))
            .map_err(|e| Error::invalid(format!("fitting {target}: {e}")))?;
        let predict = |p: &[gp::Node], d: &Dataset| {
            let mut out = vec![0.0; d.rows()];
            let ok = gp::eval::Evaluator::new().eval(p, &d.x, &mut out);
            (ok, out)
        };
        let text = |p: &[gp::Node]| {
            expr::infix(
                &expr::Expr::from_postfix(p),
                &symbols,
                &expr::exact_constant,
            )
        };
        let front: Vec<FrontMember> = res
            .front
            .iter()
            .map(|e| {
                let test_r2 = (test.rows() > 0)
                    .then(|| {
                        let (ok, out) = predict(&e.program, &test);
                        ok.then(|| Metrics::of(&test.y, &out).r2)
                    })
                    .flatten();
                FrontMember {
                    size: e.size,
                    train_r2: 1.0 - e.train_nmse,
                    test_r2,
                    equation: text(&e.program),
                    program: e.program.clone(),
                }
            })
            .collect();
        let best = res.best();
        let (_, train_pred) = predict(&best.program, &train);
        let (test_ok, test_pred) = predict(&best.program, &test);
        if test.rows() > 0 && !test_ok {
            eprintln!(
                "warning: the equation for {target} is not finite on some test rows \
                 (they lie outside the training box)"
            );
        }
        let test_metrics = (test.rows() > 0).then(|| Metrics::of(&test.y, &test_pred));
        if let Some(dir) = &opts.plots {
            let mut splits = vec![crate::plot::parity::Split {
                label: "train",
                observed: &train.y,
                predicted: &train_pred,
            }];
            if test.rows() > 0 {
                splits.push(crate::plot::parity::Split {
                    label: "test",
                    observed: &test.y,
                    predicted: &test_pred,
                });
            }
            let parity = dir.join(format!("{target}_parity.svg"));
            let hist = dir.join(format!("{target}_residuals.svg"));
            crate::plot::parity::parity(&parity, target, &splits)?;
            crate::plot::parity::residual_histogram(&hist, target, &splits)?;
            figures.push(parity);
            figures.push(hist);
        }
        responses.push(ResponseModel {
            name: target.clone(),
            equation: text(&best.program),
            program: best.program.clone(),
            size: best.size,
            uses: gp::program::used_variables(&best.program)
                .into_iter()
                .map(|k| opts.inputs[k].clone())
                .collect(),
            train: Metrics::of(&train.y, &train_pred),
            test: test_metrics,
            train_residual_quantiles: residual_quantiles(&train.y, &train_pred),
            test_residual_quantiles: residual_quantiles(&test.y, &test_pred),
            pareto_front: front,
            selection_rule: format!(
                "PySR 'best': among front members with error within {}x of the most accurate, \
                 the largest -d ln(1 - R^2)/d size (errors floored at {:e})",
                gp::select::ACCURACY_FACTOR,
                gp::select::ERROR_FLOOR
            ),
            generations: res.generations,
            node_evals: res.node_evals,
            seconds: res.seconds,
        });
    }
    let model = Metamodel {
        model_class: class.map(|c| c.to_string()),
        format: FORMAT.into(),
        version: VERSION,
        created_by: format!("mbgc {}", env!("CARGO_PKG_VERSION")),
        inputs,
        responses,
        settings: opts.config.clone(),
        seed: opts.config.seed,
        data: DataSource {
            file,
            fnv1a64: format!("{:016x}", fnv1a64(&bytes)),
            rows: n,
            train_rows: train_idx.len(),
            test_rows: test_idx.len(),
            test_fraction: opts.test_fraction,
            skipped_rows: cols.skipped,
        },
    };
    Ok(FitReport { model, figures })
}
