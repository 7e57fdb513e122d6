//! The search-setting and formulation levers of issue 34, measured on the shipped campaign's
//! regression problems (the columns `mbgc bench metamodels` gives every regressor), scored on the
//! validation table against the replicate noise (1.060 deg; 0.260 % of the bulk density).
//!
//! Run from the repository root; settings come from the environment, defaults are the shipped
//! model's settings at 100 generations and 2 restarts:
//!
//! ```text
//! RESP=bulk LIMITS=40 SEEDS=3 cargo run --release -p mbgc-studies --example metamodel_levers
//! ```
//!
//! `RESP` (shear, bulk or both), `LIMITS` (comma-separated `--max-length`s), `SEEDS` (runs, seeds
//! 1, 101, 201, ...), `POP`, `GEN`, `RESTARTS`, `TUNE` (tune fraction), `TUNE_IT`, `TOUR`
//! (tournament size), `LOGMU` (comma-separated frictions offered to GP as ln(mu) scaled to
//! [0, 1] instead of mu scaled linearly).
use anyhow::Context;
use mbgc::campaign::{experiment_by_name, ExperimentSettings};
use mbgc::dem::contact::ModelClass;
use mbgc::gp::{self, expr, Dataset};
use mbgc::metamodel::{regression_problems, FitSettings, Metamodel, TrainingTable};
use mbgc::space::Space;
use mbgc::train::{TrainPaths, TrainRecord};
use std::path::{Path, PathBuf};

fn env<T: std::str::FromStr>(k: &str, d: T) -> T {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

/// Replaces the linearly scaled friction `name` by ln(mu) scaled to [0, 1] over the training rows.
fn log_friction(p: &mut mbgc::metamodel::RegressionProblem, name: &str) -> anyhow::Result<()> {
    let k = p
        .symbols
        .iter()
        .position(|s| *s == format!("{name}_u"))
        .with_context(|| format!("LOGMU: no column {name}_u"))?;
    // The space's linear scaling of the frictions (examples/space_shear_box.toml).
    let (offset, width) = if name == "mu_pp" {
        (0.05, 0.95)
    } else {
        (0.0, 1.0)
    };
    let f = |u: f64| (offset + u * width).ln();
    let logs: Vec<f64> = p.train.x[k].iter().map(|&u| f(u)).collect();
    let lo = logs.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    for v in p.train.x[k].iter_mut() {
        *v = (f(*v) - lo) / (hi - lo);
    }
    if let Some(val) = p.validation.as_mut() {
        for v in val.x[k].iter_mut() {
            *v = (f(*v) - lo) / (hi - lo);
        }
    }
    p.symbols[k] = format!("ln{name}_u");
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let paths = TrainPaths::new(Path::new(""), "shear_box");
    let record = TrainRecord::load(&paths.record)?;
    let space = Space::from_file(&PathBuf::from(&record.space))?;
    let class = record
        .model_class
        .as_deref()
        .map(ModelClass::parse)
        .transpose()
        .map_err(|e| anyhow::anyhow!("model_class: {e}"))?
        .context("the record names no model class")?;
    let experiment = experiment_by_name(
        &record.experiment,
        &ExperimentSettings {
            box_scale: record.box_scale,
            model_class: Some(class),
            ..Default::default()
        },
    )?;
    let table = TrainingTable::read_csv(&paths.table, &record.inputs, &record.responses)?;
    let validation =
        TrainingTable::read_csv(&paths.validation_table, &record.inputs, &record.responses)?;
    let similarity = experiment.similarity().context("no similarity")?;
    let settings = FitSettings::new(record.inputs.clone(), record.responses.clone())
        .test_fraction(0.0)
        .validation(validation)
        .similarity(
            similarity.without_constant_groups(|n| space.get(n).is_some_and(|p| p.is_fixed())),
        )
        .model_class(class)
        .space(space);
    let mut problems = regression_problems(&table, &settings)?;
    let logmu: String = env("LOGMU", String::new());
    for p in problems.iter_mut() {
        for name in logmu.split(',').filter(|n| !n.is_empty()) {
            log_friction(p, name)?;
        }
    }
    let shipped = Metamodel::load(&paths.model)?;
    let which: String = env("RESP", "both".to_string());
    let limits: Vec<usize> = env("LIMITS", "40".to_string())
        .split(',')
        .map(|x| x.parse())
        .collect::<Result<_, _>>()
        .context("LIMITS")?;
    let seeds: u64 = env("SEEDS", 1);
    for p in &problems {
        if which != "both" && !p.response.starts_with(&which) {
            continue;
        }
        let v = p.validation.as_ref().context("no validation rows")?;
        let n = v.y.len() as f64;
        let mean: f64 = v.y.iter().zip(&v.factor).map(|(y, f)| y * f).sum::<f64>() / n;
        let noise = match p.response.as_str() {
            "shear_angle" => 1.060,
            _ => 0.0026 * mean,
        };
        for &limit in &limits {
            let mut ratios = vec![];
            for k in 0..seeds {
                let s = &shipped.settings;
                let cfg = gp::Config {
                    population: env("POP", 5000),
                    generations: env("GEN", 100),
                    restarts: env("RESTARTS", 2),
                    seed: 1 + k * 100,
                    max_length: limit,
                    tune_fraction: env("TUNE", s.tune_fraction),
                    tune_iterations: env("TUNE_IT", s.tune_iterations),
                    tournament: env("TOUR", s.tournament),
                    ..s.clone()
                };
                let train = Dataset::new(p.train.x.clone(), p.train.y.clone());
                let t = std::time::Instant::now();
                let res = gp::fit(&train, &cfg, |_| {}).map_err(|e| anyhow::anyhow!(e))?;
                let best = res.best();
                let mut out = vec![0.0; v.y.len()];
                gp::eval::Evaluator::new().eval(&best.program, &v.x, &mut out);
                let se: f64 = out
                    .iter()
                    .zip(&v.y)
                    .zip(&v.factor)
                    .map(|((o, y), f)| ((o - y) * f).powi(2))
                    .sum();
                let ratio = (se / n).sqrt() / noise;
                ratios.push(ratio);
                println!(
                    "{} L{limit} seed {} size {} RMSE/noise {ratio:.3} {:.1} s  {}",
                    p.response,
                    cfg.seed,
                    best.size,
                    t.elapsed().as_secs_f64(),
                    expr::infix(
                        &expr::Expr::from_postfix(&best.program),
                        &p.symbols,
                        &|c| format!("{c:.4}")
                    )
                );
            }
            println!(
                "== {} L{limit} mean RMSE/noise {:.3}",
                p.response,
                ratios.iter().sum::<f64>() / ratios.len() as f64
            );
        }
    }
    Ok(())
}
