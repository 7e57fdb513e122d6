//! Fitting a metamodel to a table: split, scale, one GP run per response, metrics, figures.

use super::model::{
    residual_quantiles, Constant, DataSource, FrontMember, GroupDomain, GroupedEquation, Input,
    Metamodel, Metrics, ResponseModel, Transform, FORMAT, VERSION,
};
use super::table::{read_columns_skipping_nan, Columns};
use crate::dem::contact::{ModelClass, Pair};
use crate::error::{Error, Result};
use crate::gp::{self, expr, Dataset};
use crate::numeric::fnv1a64;
use crate::similarity::Similarity;
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
    /// Fit in the experiment's dimensionless groups (inputs they absorb are not offered to GP;
    /// scaled responses are fitted divided by their factor); the equations are composed back
    /// into the physical inputs.
    pub similarity: Option<Similarity>,
    /// A separate table whose rows are never trained on: each response's `validation` metrics.
    pub validation: Option<PathBuf>,
}

pub struct FitReport {
    pub model: Metamodel,
    pub figures: Vec<PathBuf>,
}

fn transforms(opts: &FitOptions, absorbed: &[String]) -> Result<Vec<Transform>> {
    let Some(path) = &opts.space else {
        return Ok(vec![Transform::Identity; opts.inputs.len()]);
    };
    let space = Space::from_file(path)?;
    let file = path.display().to_string();
    opts.inputs
        .iter()
        .map(|name| {
            // The composed equations read an absorbed input raw, inside the log of its group.
            if absorbed.contains(name) {
                return Ok(Transform::Identity);
            }
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
    let absorbed = opts
        .similarity
        .as_ref()
        .map(Similarity::absorbed)
        .unwrap_or_default();
    for a in &absorbed {
        if !opts.inputs.contains(a) {
            return Err(Error::invalid(format!(
                "--inputs: the experiment's groups are made of {}, so {a} must be an input",
                absorbed.join(", ")
            )));
        }
    }
    let transforms = transforms(opts, &absorbed)?;
    let bytes = std::fs::read(&opts.data).map_err(|e| Error::io(&opts.data, e))?;
    let names: Vec<String> = opts.inputs.iter().chain(&opts.targets).cloned().collect();
    let cols = read_columns_skipping_nan(&opts.data, &names, opts.inputs.len())?;
    let space = opts.space.as_deref().map(Space::from_file).transpose()?;
    let space_class = match (&space, &opts.space) {
        (Some(sp), Some(p)) => sp.model_class.map(|c| (c, p.display().to_string())),
        _ => None,
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
        let logged = matches!(t, Transform::Log { .. }) || absorbed.contains(&opts.inputs[k]);
        if logged {
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

    let range = |col: &[f64]| {
        [
            col.iter().copied().fold(f64::INFINITY, f64::min),
            col.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        ]
    };
    let inputs: Vec<Input> = opts
        .inputs
        .iter()
        .zip(&transforms)
        .zip(x_phys)
        .map(|((name, t), col)| {
            // An absorbed input is valid wherever its groups are: over the space's bounds, not
            // only at the values the campaign held it at.
            let bounds = space
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
    let var_of = |name: &str| opts.inputs.iter().position(|n| n == name).unwrap_or(0) as u16;
    // The groups: their values on every row, and the log scaling to the unit interval.
    let mut groups: Vec<GroupDomain> = Vec::new();
    let mut group_cols: Vec<Vec<f64>> = Vec::new();
    for g in opts.similarity.iter().flat_map(|s| &s.groups) {
        let col: Vec<f64> = (0..n)
            .map(|r| g.monomial.value(|name| x_phys[var_of(name) as usize][r]))
            .collect();
        let domain = range(&col);
        let (lo, hi) = (domain[0].ln(), domain[1].ln());
        let transform = Transform::Log {
            offset: lo,
            width: if hi > lo { hi - lo } else { 1.0 },
        };
        group_cols.push(col.iter().map(|&v| transform.apply(v)).collect());
        groups.push(GroupDomain {
            group: g.clone(),
            transform,
            domain,
        });
    }
    let symbols: Vec<String> = inputs.iter().map(Input::symbol).collect();
    let xt: Vec<Vec<f64>> = inputs
        .iter()
        .zip(x_phys)
        .map(|(i, c)| c.iter().map(|&v| i.transform.apply(v)).collect())
        .collect();
    // What GP sees: the inputs not absorbed, then the groups.
    let gp_inputs: Vec<usize> = (0..n_in)
        .filter(|&k| !absorbed.contains(&opts.inputs[k]))
        .collect();
    let gp_symbols: Vec<String> = gp_inputs
        .iter()
        .map(|&k| symbols[k].clone())
        .chain(groups.iter().map(|g| format!("{}_u", g.group.name)))
        .collect();
    let gp_cols: Vec<&Vec<f64>> = gp_inputs
        .iter()
        .map(|&k| &xt[k])
        .chain(group_cols.iter())
        .collect();
    // A GP program over its own variables, written as one over the model's inputs.
    let compose = |p: &[gp::Node], factor: Option<&crate::similarity::Monomial>| {
        let mut out = Vec::with_capacity(p.len() + 8);
        for node in p {
            match *node {
                gp::Node::Var(j) if (j as usize) < gp_inputs.len() => {
                    out.push(gp::Node::Var(gp_inputs[j as usize] as u16))
                }
                gp::Node::Var(j) => {
                    let g = &groups[j as usize - gp_inputs.len()];
                    let Transform::Log { offset, width } = g.transform else {
                        unreachable!("groups are log-scaled")
                    };
                    out.extend(g.group.monomial.ln_program(&var_of));
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
    };
    let pick = |col: &[f64], idx: &[usize]| idx.iter().map(|&i| col[i]).collect::<Vec<f64>>();
    let validation = match &opts.validation {
        Some(path) => {
            let v = read_columns_skipping_nan(path, &names, opts.inputs.len())?;
            let x: Vec<Vec<f64>> = inputs
                .iter()
                .zip(&v.values[..n_in])
                .map(|(i, c)| c.iter().map(|&x| i.transform.apply(x)).collect())
                .collect();
            Some((v, x))
        }
        None => None,
    };

    let mut responses = Vec::new();
    let mut figures = Vec::new();
    for (t, target) in opts.targets.iter().enumerate() {
        let y = &cols.values[n_in + t];
        let scaled = opts.similarity.as_ref().and_then(|s| s.scaled(target));
        let factor = scaled.map(|s| &s.factor);
        // The response GP fits: divided by its factor when the similarity has one.
        let y_fit: Vec<f64> = match factor {
            Some(f) => (0..n)
                .map(|r| y[r] / f.value(|name| x_phys[var_of(name) as usize][r]))
                .collect(),
            None => y.clone(),
        };
        let train = Dataset::new(
            xt.iter().map(|c| pick(c, &train_idx)).collect(),
            pick(y, &train_idx),
        );
        let gp_train = Dataset::new(
            gp_cols.iter().map(|c| pick(c, &train_idx)).collect(),
            pick(&y_fit, &train_idx),
        );
        if gp_train.y_var() <= 0.0 {
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
        let res = gp::fit(&gp_train, &opts.config, |p| progress(target, p))
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
            .enumerate()
            .map(|(i, e)| {
                let program = compose(&e.program, factor);
                let test_r2 = (test.rows() > 0)
                    .then(|| {
                        let (ok, out) = predict(&program, &test);
                        ok.then(|| Metrics::of(&test.y, &out).r2)
                    })
                    .flatten();
                FrontMember {
                    size: e.size,
                    train_r2: 1.0 - e.train_nmse,
                    test_r2,
                    cv_r2: res.cv_nmse.as_ref().map(|cv| 1.0 - cv[i]),
                    equation: text(&program),
                    program,
                }
            })
            .collect();
        let best = res.best();
        let program = compose(&best.program, factor);
        let (_, train_pred) = predict(&program, &train);
        let (test_ok, test_pred) = predict(&program, &test);
        if test.rows() > 0 && !test_ok {
            eprintln!(
                "warning: the equation for {target} is not finite on some test rows \
                 (they lie outside the training box)"
            );
        }
        let test_metrics = (test.rows() > 0).then(|| Metrics::of(&test.y, &test_pred));
        let validation_set = validation.as_ref().map(|(v, x)| {
            let d = Dataset::new(x.clone(), v.values[n_in + t].clone());
            let (_, pred) = predict(&program, &d);
            (d, pred)
        });
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
            if let Some((d, pred)) = &validation_set {
                splits.push(crate::plot::parity::Split {
                    label: "validation",
                    observed: &d.y,
                    predicted: pred,
                });
            }
            let parity = dir.join(format!("{target}_parity.svg"));
            let hist = dir.join(format!("{target}_residuals.svg"));
            crate::plot::parity::parity(&parity, target, &splits)?;
            crate::plot::parity::residual_histogram(&hist, target, &splits)?;
            figures.push(parity);
            figures.push(hist);
        }
        let grouped = opts.similarity.as_ref().map(|_| GroupedEquation {
            fitted: scaled.map_or_else(|| target.clone(), |s| s.fitted.clone()),
            equation: expr::infix(
                &expr::Expr::from_postfix(&best.program),
                &gp_symbols,
                &expr::exact_constant,
            ),
            factor: factor.cloned(),
        });
        responses.push(ResponseModel {
            name: target.clone(),
            equation: text(&program),
            size: best.size,
            uses: gp::program::used_variables(&program)
                .into_iter()
                .map(|k| opts.inputs[k].clone())
                .collect(),
            program,
            train: Metrics::of(&train.y, &train_pred),
            test: test_metrics,
            train_residual_quantiles: residual_quantiles(&train.y, &train_pred),
            test_residual_quantiles: residual_quantiles(&test.y, &test_pred),
            pareto_front: front,
            selection_rule: opts.config.selection.describe(),
            generations: res.generations,
            node_evals: res.node_evals,
            seconds: res.seconds,
            grouped,
            validation: validation_set.map(|(d, pred)| Metrics::of(&d.y, &pred)),
        });
    }
    // What the campaign held fixed and is not an input: the model holds only there.
    let sidecar = crate::campaign::status::Meta::read(&opts.data)?;
    let mut constants: Vec<Constant> = Vec::new();
    if let Some(path) = &opts.space {
        for p in &Space::from_file(path)?.parameters {
            if let (Some(v), false) = (p.fixed, opts.inputs.contains(&p.name)) {
                constants.push(Constant {
                    name: p.name.clone(),
                    value: v,
                });
            }
        }
    }
    for (name, v) in sidecar.iter().flat_map(|m| m.set.iter()) {
        if !opts.inputs.contains(name) && !constants.iter().any(|c| c.name == *name) {
            constants.push(Constant {
                name: name.clone(),
                value: *v,
            });
        }
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
            no_value_rows: cols.no_value,
        },
        groups,
        experiment: sidecar.as_ref().map(|m| m.experiment.clone()),
        constants,
    };
    Ok(FitReport { model, figures })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::similarity::{Group, Monomial, ScaledResponse};

    /// A table held at one rho and one d (as the shipped campaign is), whose density is
    /// rho * (0.5 + 0.02 ln K) with K = E / (rho d): the fitted model must be right at other rho
    /// and d too, since it is written in K and rho.
    #[test]
    fn a_fit_in_groups_extends_to_the_absorbed_inputs() {
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
        let opts = FitOptions {
            data,
            inputs: vec!["E".into(), "rho".into(), "d".into(), "mu".into()],
            targets: vec!["density".into(), "angle".into()],
            test_fraction: 0.0,
            space: None,
            config: gp::Config {
                population: 300,
                generations: 5,
                ..gp::Config::default()
            },
            plots: None,
            model_class: None,
            similarity: Some(similarity),
            validation: None,
        };
        let m = fit_table(&opts, |_, _| {}).unwrap().model;
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
        // K beyond the data is outside the domain, named by the group.
        let out = m.outside_domain(&[1e9, 2000.0, 4.0, 0.5]);
        assert!(out.iter().any(|o| o.0 == "K"), "{out:?}");
        assert!(m.outside_domain(&[1e7, 2000.0, 4.0, 0.5]).is_empty());
    }
}
