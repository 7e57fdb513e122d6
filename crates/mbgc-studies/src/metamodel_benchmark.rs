//! `mbgc bench metamodels`: mbgc's symbolic regression side by side with PyOperon (GP at the same
//! length limits), a Gaussian-process regressor (the accuracy ceiling) and a quadratic response
//! surface (what most DEM calibration papers fit), on the shipped shear-box campaign: identical
//! columns (the scaled inputs and dimensionless groups mbgc's GP is offered, from
//! [`mbgc::metamodel::regression_problems`]), identical training rows, and the validation table
//! none of them saw. Each method's validation RMSE is set against the replicate noise of single
//! runs; equations are measured by their node count under one rule for all (sympy's tree, see
//! `benches/metamodels/run_regressors.py`) and by each engine's own count.
//!
//! The Python tools are installed by the bench itself into a virtual environment (`--venv`,
//! pinned versions); nothing here runs in CI.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::Context as _;
use serde::{Deserialize, Serialize};

use mbgc::campaign::{experiment_by_name, ExperimentSettings};
use mbgc::dem::contact::ModelClass;
use mbgc::error::write_atomic;
use mbgc::gp::{self, expr, Dataset};
use mbgc::metamodel::{regression_problems, FitSettings, Metamodel, RegressionProblem};
use mbgc::metamodel::{Metrics, TrainingTable};
use mbgc::space::Space;
use mbgc::train::{TrainPaths, TrainRecord};
use mbgc_output::{say, Output};

use crate::noise_floor::{replicate_noise, NoiseFloor};

/// Pinned versions of the Python side (what the report was made with).
const PIP_PACKAGES: [&str; 5] = [
    "pyoperon==0.6.2",
    "scikit-learn==1.9.1",
    "sympy==1.14.0",
    "numpy==2.4.6",
    "scipy",
];

/// `mbgc bench metamodels`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Args {
    /// Directory holding sampling/, training_data/ and models/ (as `mbgc train --out-dir`).
    #[cfg_attr(feature = "cli", arg(long, default_value = "."))]
    pub dir: PathBuf,
    /// Name of the trained model whose tables are used (as `mbgc train --name`).
    #[cfg_attr(feature = "cli", arg(long, default_value = "shear_box"))]
    pub name: String,
    /// Length limits (nodes of the tree before the linear scaling, as `--max-length`).
    #[cfg_attr(
        feature = "cli",
        arg(long, value_delimiter = ',', default_value = "10,20,30,40")
    )]
    pub limits: Vec<usize>,
    /// PyOperon's length limits (default: `--limits`). Operon counts a weighted variable `w*x` as
    /// one node, so its equations at a limit are longer than mbgc's; more limits let the report
    /// also compare the two at equal counted nodes.
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ','))]
    pub operon_limits: Option<Vec<usize>>,
    /// mbgc's population (the shipped model: 5000).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 2000))]
    pub population: usize,
    /// mbgc's generations (the shipped model: 300).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 100))]
    pub generations: usize,
    /// mbgc's independent restarts (the shipped model: 4).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 2))]
    pub restarts: usize,
    /// mbgc's share of each island whose constants are tuned every generation (default: the
    /// shipped model's); 1 tunes every tree, as Operon does.
    #[cfg_attr(feature = "cli", arg(long))]
    pub tune_fraction: Option<f64>,
    /// mbgc's Levenberg-Marquardt steps per tuning during the search (default: the shipped
    /// model's).
    #[cfg_attr(feature = "cli", arg(long))]
    pub tune_iterations: Option<usize>,
    /// Fit mbgc only (no Python tools): for measuring mbgc's own settings against each other.
    #[cfg_attr(feature = "cli", arg(long))]
    pub mbgc_only: bool,
    /// PyOperon's generations, population and evaluation budget.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 1000))]
    pub operon_generations: usize,
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 1000))]
    pub operon_population: usize,
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 1_000_000))]
    pub operon_evaluations: usize,
    /// Seed of every method's first run.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 1))]
    pub seed: u64,
    /// Runs per engine and limit (mbgc's seeds `restarts` apart, so that no two runs share a
    /// restart; PyOperon's `seed`, `seed + 1`, ...): one run's error varies with its seed as much
    /// as between engines, so the report gives mean and spread.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 1))]
    pub seeds: u64,
    /// Virtual environment of the Python tools, made (and filled) when it lacks them.
    #[cfg_attr(feature = "cli", arg(long, default_value = "target/venv-metamodels"))]
    pub venv: PathBuf,
    /// The Python that makes the virtual environment.
    #[cfg_attr(feature = "cli", arg(long, default_value = "python3"))]
    pub python: String,
    /// Where the results of every method are kept (JSON).
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value = "docs/data/metamodel_benchmark.json")
    )]
    pub results: PathBuf,
    /// Markdown report.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value = "docs/metamodel_benchmark.md")
    )]
    pub report: PathBuf,
    /// Write the report from the kept results (`--results`) without fitting anything.
    #[cfg_attr(feature = "cli", arg(long))]
    pub from_results: bool,
    /// Standard output holds one JSON object (where the report went); text goes to standard
    /// error.
    #[cfg_attr(feature = "cli", arg(long))]
    pub json: bool,
}

/// One method's model of one response.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MethodResult {
    /// `mbgc`, `pyoperon`, `quadratic` or `gaussian_process`.
    pub method: String,
    /// The length limit it was run with (none for the fixed-form models).
    pub limit: Option<usize>,
    /// The seed of the run (none for the deterministic models).
    #[serde(default)]
    pub seed: Option<u64>,
    /// The engine's own node count (mbgc and Operon: with the linear scaling's 4 nodes).
    pub own_length: Option<usize>,
    /// Nodes of the equation's sympy tree (the common rule).
    pub nodes: Option<usize>,
    /// The equation over the problem's columns (the kernel for the Gaussian process).
    pub equation: String,
    /// Fit time, s.
    pub seconds: f64,
    /// Predictions of the fitted quantity on the training and the validation rows.
    pub train_pred: Vec<f64>,
    pub validation_pred: Vec<f64>,
}

/// What the Python side prints.
#[derive(Debug, Deserialize)]
struct PythonOutput {
    versions: serde_json::Value,
    operon_settings: serde_json::Value,
    responses: Vec<PythonResponse>,
}

#[derive(Debug, Deserialize)]
struct PythonResponse {
    response: String,
    methods: Vec<MethodResult>,
    mbgc_nodes: Vec<usize>,
}

/// The whole benchmark's results, kept as JSON.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Results {
    /// The settings of mbgc's runs.
    pub mbgc_settings: gp::Config,
    /// Versions and settings of the Python side.
    pub python_versions: serde_json::Value,
    pub operon_settings: serde_json::Value,
    /// Per response, every method's model.
    pub responses: Vec<ResponseResults>,
    /// The command that made them.
    pub command: String,
}

/// Every method's model of one response, with the data it is scored on.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ResponseResults {
    pub response: String,
    pub fitted: String,
    pub symbols: Vec<String>,
    /// Observed response (physical units) and factor on the training and validation rows.
    pub train_observed: Vec<f64>,
    pub train_factor: Vec<f64>,
    pub validation_observed: Vec<f64>,
    pub validation_factor: Vec<f64>,
    /// Replicate noise of single runs, response units.
    pub noise_sd: f64,
    pub methods: Vec<MethodResult>,
}

/// The fitting settings of the shipped train (inputs, space, similarity, validation table).
fn settings(dir: &Path, paths: &TrainPaths) -> anyhow::Result<(TrainingTable, FitSettings)> {
    let record = TrainRecord::load(&paths.record)?;
    let space = Space::from_file(&dir.join(&record.space))?;
    let class = record
        .model_class
        .as_deref()
        .map(ModelClass::parse)
        .transpose()
        .map_err(|e| anyhow::anyhow!("{}: model_class: {e}", paths.record.display()))?;
    let experiment = experiment_by_name(
        &record.experiment,
        &ExperimentSettings {
            box_scale: record.box_scale,
            model_class: class,
            ..Default::default()
        },
    )?;
    let table = TrainingTable::read_csv(&paths.table, &record.inputs, &record.responses)?;
    let validation =
        TrainingTable::read_csv(&paths.validation_table, &record.inputs, &record.responses)?;
    let mut s = FitSettings::new(record.inputs.clone(), record.responses.clone())
        .test_fraction(0.0)
        .validation(validation);
    if let Some(sim) = experiment.similarity() {
        s = s.similarity(
            sim.without_constant_groups(|n| space.get(n).is_some_and(|p| p.is_fixed())),
        );
    }
    if let Some(c) = class {
        s = s.model_class(c);
    }
    Ok((table, s.space(space)))
}

/// mbgc's GP on one problem at one length limit, with the shipped model's settings otherwise.
fn run_mbgc(p: &RegressionProblem, cfg: &gp::Config) -> anyhow::Result<MethodResult> {
    let train = Dataset::new(p.train.x.clone(), p.train.y.clone());
    let t = Instant::now();
    let res = gp::fit(&train, cfg, |_| {}).map_err(|e| anyhow::anyhow!("{}: {e}", p.response))?;
    let seconds = t.elapsed().as_secs_f64();
    let best = res.best();
    let predict = |x: &[Vec<f64>]| {
        let mut out = vec![0.0; x.first().map_or(0, Vec::len)];
        gp::eval::Evaluator::new().eval(&best.program, x, &mut out);
        out
    };
    let v = p
        .validation
        .as_ref()
        .context("the benchmark needs a validation table")?;
    Ok(MethodResult {
        method: "mbgc".into(),
        limit: Some(cfg.max_length),
        seed: Some(cfg.seed),
        own_length: Some(best.size),
        nodes: None,
        equation: expr::infix(
            &expr::Expr::from_postfix(&best.program),
            &p.symbols,
            &expr::exact_constant,
        ),
        seconds,
        train_pred: predict(&p.train.x),
        validation_pred: predict(&v.x),
    })
}

/// PyOperon, the Gaussian process and the quadratic surface on the same problems, through the
/// Python script in the bench's virtual environment; it also counts mbgc's equations' nodes.
fn other_regressors(
    a: &Args,
    out: &Output,
    problems: &[RegressionProblem],
    ours: &[Vec<MethodResult>],
) -> anyhow::Result<PythonOutput> {
    let python = venv_python(a, out)?;
    let spec = serde_json::json!({
        "problems": problems.iter().zip(ours).map(|(p, o)| {
            let v = p.validation.as_ref().expect("checked in run_mbgc");
            serde_json::json!({
                "response": p.response,
                "symbols": p.symbols,
                "train_x": p.train.x,
                "train_y": p.train.y,
                "validation_x": v.x,
                "limits": a.operon_limits.as_ref().unwrap_or(&a.limits),
                "seeds": (a.seed..a.seed + a.seeds).collect::<Vec<u64>>(),
                "mbgc_equations": o.iter().map(|r| r.equation.clone()).collect::<Vec<_>>(),
            })
        }).collect::<Vec<_>>(),
    });
    let work = tempfile::tempdir()?;
    let spec_path = work.path().join("problems.json");
    std::fs::write(&spec_path, serde_json::to_vec(&spec)?)?;
    say!(
        out,
        "running {} (PyOperon, Gaussian process, quadratic)",
        script().display()
    );
    let run = Command::new(&python)
        .arg(script())
        .arg("--problems")
        .arg(&spec_path)
        .args(["--operon-generations", &a.operon_generations.to_string()])
        .args(["--operon-population", &a.operon_population.to_string()])
        .args(["--operon-evaluations", &a.operon_evaluations.to_string()])
        .stderr(std::process::Stdio::inherit())
        .output()
        .with_context(|| format!("running {}", python.display()))?;
    anyhow::ensure!(run.status.success(), "{} failed", script().display());
    let theirs: PythonOutput = serde_json::from_slice(&run.stdout)
        .with_context(|| format!("{} printed no result object", script().display()))?;

    Ok(theirs)
}

/// The virtual environment's Python, made and filled first when it cannot import the tools.
fn venv_python(a: &Args, out: &Output) -> anyhow::Result<PathBuf> {
    let py = a.venv.join("bin/python");
    let ready = |py: &Path| {
        Command::new(py)
            .args(["-c", "import pyoperon, sklearn, sympy, numpy"])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if ready(&py) {
        return Ok(py);
    }
    say!(
        out,
        "making {} ({})",
        a.venv.display(),
        PIP_PACKAGES.join(" ")
    );
    let status = Command::new(&a.python)
        .args(["-m", "venv"])
        .arg(&a.venv)
        .status()
        .with_context(|| format!("running {} -m venv", a.python))?;
    anyhow::ensure!(
        status.success(),
        "{} -m venv {} failed",
        a.python,
        a.venv.display()
    );
    let status = Command::new(&py)
        .args(["-m", "pip", "install", "--quiet"])
        .args(PIP_PACKAGES)
        .status()
        .with_context(|| format!("running {} -m pip", py.display()))?;
    anyhow::ensure!(
        status.success(),
        "pip install into {} failed",
        a.venv.display()
    );
    anyhow::ensure!(ready(&py), "{} still cannot import the tools", py.display());
    Ok(py)
}

fn script() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../benches/metamodels/run_regressors.py")
}

fn command(a: &Args) -> String {
    let list = |v: &[usize]| -> String {
        v.iter()
            .map(|l| l.to_string())
            .collect::<Vec<_>>()
            .join(",")
    };
    let mut operon = a
        .operon_limits
        .as_ref()
        .map(|o| format!(" --operon-limits {}", list(o)))
        .unwrap_or_default();
    if let Some(t) = a.tune_fraction {
        operon += &format!(" --tune-fraction {t}");
    }
    if let Some(t) = a.tune_iterations {
        operon += &format!(" --tune-iterations {t}");
    }
    if a.mbgc_only {
        operon += " --mbgc-only";
    }
    format!(
        "cargo run --release -- bench metamodels --limits {}{operon} --population {} \
         --generations {} --restarts {} --operon-generations {} --operon-population {} \
         --operon-evaluations {} --seed {} --seeds {} (the report alone, from the kept results: \
         add --from-results)",
        list(&a.limits),
        a.population,
        a.generations,
        a.restarts,
        a.operon_generations,
        a.operon_population,
        a.operon_evaluations,
        a.seed,
        a.seeds
    )
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    anyhow::ensure!(
        !a.limits.is_empty() && a.limits.iter().all(|&l| (1..=1000).contains(&l)),
        "--limits: expected lengths from 1 to 1000"
    );
    if let Some(o) = &a.operon_limits {
        anyhow::ensure!(
            !o.is_empty() && o.iter().all(|&l| (1..=1000).contains(&l)),
            "--operon-limits: expected lengths from 1 to 1000"
        );
    }
    anyhow::ensure!(
        (1..=100).contains(&a.seeds),
        "--seeds {}: expected 1 to 100 runs per engine and limit",
        a.seeds
    );
    let dir = if a.dir == Path::new(".") {
        PathBuf::new()
    } else {
        a.dir.clone()
    };
    let paths = TrainPaths::new(&dir, &a.name);
    for (flag, p) in [("--report", &a.report), ("--results", &a.results)] {
        mbgc::outputs::refuse_overwriting_inputs(
            flag,
            p,
            &[
                ("the training table", &paths.table),
                ("the validation table", &paths.validation_table),
                ("the train record", &paths.record),
            ],
        )?;
    }
    let replicates = paths
        .validation_table
        .with_file_name(format!("{}_replicates.csv", a.name));
    let noise: NoiseFloor = replicate_noise(&paths.validation_table, &replicates)?
        .with_context(|| format!("{}: no replicate runs", replicates.display()))?;
    if a.from_results {
        let text =
            std::fs::read_to_string(&a.results).with_context(|| a.results.display().to_string())?;
        let results: Results =
            serde_json::from_str(&text).with_context(|| a.results.display().to_string())?;
        let text = report(&results, &noise, &a.results);
        write_atomic(&a.report, text.as_bytes())?;
        crate::report_written(
            a.json,
            &a.report,
            serde_json::json!({ "results": a.results }),
        );
        return Ok(());
    }
    let (table, settings) = settings(&dir, &paths)?;
    let problems = regression_problems(&table, &settings)?;
    let shipped = Metamodel::load(&paths.model)?;
    let base = gp::Config {
        population: a.population,
        generations: a.generations,
        restarts: a.restarts,
        seed: a.seed,
        tune_fraction: a.tune_fraction.unwrap_or(shipped.settings.tune_fraction),
        tune_iterations: a
            .tune_iterations
            .unwrap_or(shipped.settings.tune_iterations),
        ..shipped.settings.clone()
    };
    base.check()
        .map_err(|e| anyhow::anyhow!("mbgc's settings: {e}"))?;

    // mbgc first: its equations go to the Python side to be counted by the common rule.
    let mut ours: Vec<Vec<MethodResult>> = Vec::new();
    for p in &problems {
        let mut v = Vec::new();
        for &limit in &a.limits {
            // A run with r restarts uses the seeds seed..seed + r: runs r apart share none.
            let step = base.restarts.max(1) as u64;
            for seed in (0..a.seeds).map(|k| a.seed + k * step) {
                let cfg = gp::Config {
                    max_length: limit,
                    seed,
                    ..base.clone()
                };
                let r = run_mbgc(p, &cfg)?;
                say!(
                    out,
                    "{}: mbgc limit {limit} seed {seed}: size {}, {:.1} s: {}",
                    p.response,
                    r.own_length.unwrap_or(0),
                    r.seconds,
                    r.equation
                );
                v.push(r);
            }
        }
        ours.push(v);
    }

    let theirs = if a.mbgc_only {
        PythonOutput {
            versions: serde_json::json!({}),
            operon_settings: serde_json::json!({}),
            responses: problems
                .iter()
                .map(|p| PythonResponse {
                    response: p.response.clone(),
                    methods: Vec::new(),
                    mbgc_nodes: Vec::new(),
                })
                .collect(),
        }
    } else {
        other_regressors(a, &out, &problems, &ours)?
    };

    let mut responses = Vec::new();
    for ((p, mut o), t) in problems.iter().zip(ours).zip(theirs.responses) {
        anyhow::ensure!(t.response == p.response, "responses out of order");
        for (r, n) in o.iter_mut().zip(&t.mbgc_nodes) {
            r.nodes = Some(*n);
        }
        o.extend(t.methods);
        let v = p.validation.as_ref().expect("checked in run_mbgc");
        let observed =
            |y: &[f64], f: &[f64]| -> Vec<f64> { y.iter().zip(f).map(|(y, f)| y * f).collect() };
        let mean_v = observed(&v.y, &v.factor).iter().sum::<f64>() / v.y.len() as f64;
        responses.push(ResponseResults {
            response: p.response.clone(),
            fitted: p.fitted.clone(),
            symbols: p.symbols.clone(),
            train_observed: observed(&p.train.y, &p.train.factor),
            train_factor: p.train.factor.clone(),
            validation_observed: observed(&v.y, &v.factor),
            validation_factor: v.factor.clone(),
            noise_sd: match p.response.as_str() {
                "shear_angle" => noise.angle_sd,
                "bulk_density" => noise.bulk_rel_sd * mean_v,
                other => anyhow::bail!("no replicate noise for the response {other}"),
            },
            methods: o,
        });
    }
    let results = Results {
        mbgc_settings: base,
        python_versions: theirs.versions,
        operon_settings: theirs.operon_settings,
        responses,
        command: command(a),
    };
    write_atomic(
        &a.results,
        serde_json::to_string_pretty(&results)?.as_bytes(),
    )?;
    let text = report(&results, &noise, &a.results);
    write_atomic(&a.report, text.as_bytes())?;
    say!(out, "{text}");
    say!(
        out,
        "wrote {} and {}",
        a.report.display(),
        a.results.display()
    );
    crate::report_written(
        a.json,
        &a.report,
        serde_json::json!({ "results": a.results }),
    );
    Ok(())
}

/// Metrics of one method in response units: training and validation.
pub struct Scored {
    pub train: Metrics,
    pub validation: Metrics,
}

/// Scores a method on its response (predictions times the factor).
pub fn score(r: &ResponseResults, m: &MethodResult) -> Scored {
    let phys = |p: &[f64], f: &[f64]| -> Vec<f64> { p.iter().zip(f).map(|(p, f)| p * f).collect() };
    Scored {
        train: Metrics::of(&r.train_observed, &phys(&m.train_pred, &r.train_factor)),
        validation: Metrics::of(
            &r.validation_observed,
            &phys(&m.validation_pred, &r.validation_factor),
        ),
    }
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// `mean` for one value, `mean ± sd (min-max)` for several.
fn spread(v: &[f64]) -> String {
    if v.len() < 2 {
        return format!("{:.2}", mean(v));
    }
    let m = mean(v);
    let sd = (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt();
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    format!("{m:.2} ± {sd:.2} ({lo:.2}-{hi:.2})")
}

fn label(method: &str) -> &str {
    match method {
        "mbgc" => "mbgc GP",
        "pyoperon" => "PyOperon",
        "quadratic" => "quadratic response surface",
        "gaussian_process" => "Gaussian process (ARD Matern 5/2 + white)",
        m => m,
    }
}

/// Each mbgc limit against PyOperon at the same counted size: the longest Operon limit whose
/// mean node count (the common sympy rule) is at most mbgc's at that limit. Operon's own length
/// counts `w*x` as one node, so comparing at the same nominal limit gives it longer equations.
fn equal_nodes(r: &ResponseResults) -> Vec<String> {
    let rmse = |m: &MethodResult| score(r, m).validation.rmse / r.noise_sd;
    let summary = |method: &str| -> Vec<(usize, f64, f64)> {
        let mut limits: Vec<usize> = r
            .methods
            .iter()
            .filter(|m| m.method == method)
            .filter_map(|m| m.limit)
            .collect();
        limits.sort_unstable();
        limits.dedup();
        limits
            .into_iter()
            .filter_map(|l| {
                let g: Vec<&MethodResult> = r
                    .methods
                    .iter()
                    .filter(|m| m.method == method && m.limit == Some(l))
                    .collect();
                let nodes: Vec<f64> = g.iter().filter_map(|m| m.nodes).map(|n| n as f64).collect();
                (!nodes.is_empty()).then(|| {
                    let e: Vec<f64> = g.iter().map(|m| rmse(m)).collect();
                    (l, mean(&nodes), mean(&e))
                })
            })
            .collect()
    };
    let theirs = summary("pyoperon");
    summary("mbgc")
        .into_iter()
        .map(|(l, nodes, ours)| {
            match theirs
                .iter()
                .filter(|t| t.1 <= nodes)
                .max_by(|a, b| a.1.total_cmp(&b.1))
            {
                Some(&(tl, tn, te)) => format!(
                    "mbgc {l} ({nodes:.0} nodes) {ours:.2}, PyOperon {tl} ({tn:.0} nodes) {te:.2} \
                     ({})",
                    if ours <= te {
                        "mbgc no worse"
                    } else {
                        "PyOperon better"
                    }
                ),
                None => format!("mbgc {l} ({nodes:.0} nodes) {ours:.2}, no PyOperon run as short"),
            }
        })
        .collect()
}

/// The Markdown report.
pub fn report(res: &Results, noise: &NoiseFloor, results_path: &Path) -> String {
    let mut w = String::new();
    let _ = writeln!(
        w,
        "# Metamodels side by side: mbgc's GP, PyOperon, a Gaussian process and a quadratic \
         surface\n\nRegenerate: `{}` (minutes; the Python tools are installed into a virtual \
         environment by the bench). Every number below is in `{}`.\n",
        res.command,
        results_path.display()
    );
    let _ = writeln!(
        w,
        "All methods fit the same problem: the shipped campaign `training_data/shear_box.csv` \
         (every usable row), the columns mbgc's GP is offered (each input scaled to [0, 1] over \
         its range, the stiffness groups K_p and K_w log-scaled), the bulk density as the solid \
         fraction (bulk density / rho_p); they are scored in physical units on \
         `training_data/shear_box_validation.csv`, a random design none of them saw. Noise: the \
         seed-to-seed spread of single runs from {} validation rows rerun with another seed \
         (`training_data/shear_box_replicates.csv`): {:.3} deg and {:.3} % of the bulk density. \
         An exact model would still show an RMSE of 1x the noise.\n",
        noise.points,
        noise.angle_sd,
        100.0 * noise.bulk_rel_sd
    );
    let _ = writeln!(
        w,
        "mbgc: population {}, {} generations, {} restarts, constants of {} of each island tuned \
         every generation ({} Levenberg-Marquardt steps), parsimony {}, functions {}, selection \
         by 5-fold cross-validation, linear scaling, `--max-length` = the limit. PyOperon {}: \
         the same functions, `max_length` = the limit, population {}, {} generations, at most {} \
         evaluations, Levenberg-Marquardt on the constants, its minimum-description-length \
         model selection. Both count the linear scaling's 4 nodes on top of the limit; Operon's \
         variable nodes carry a weight (`w*x` is one node to it). 'nodes' counts every \
         equation by one rule: the nodes of its sympy tree (a - b is a + (-1)*b, a/b is \
         a*b^(-1)).\n",
        res.mbgc_settings.population,
        res.mbgc_settings.generations,
        res.mbgc_settings.restarts,
        res.mbgc_settings.tune_fraction,
        res.mbgc_settings.tune_iterations,
        res.mbgc_settings.parsimony,
        res.mbgc_settings.functions,
        res.python_versions["pyoperon"].as_str().unwrap_or("?"),
        res.operon_settings["population"],
        res.operon_settings["generations"],
        res.operon_settings["max_evaluations"],
    );
    for r in &res.responses {
        let _ = writeln!(
            w,
            "## {}\n\nNoise sd {:.3}; validation rows {}, training rows {}.\n\nWith several seeds: the mean of each \
             column, and for RMSE / noise the mean ± sd (min-max).\n\n| method | limit | runs | \
             own length | nodes | validation RMSE | RMSE / noise | validation R^2 | training R^2 \
             | fit s |\n|---|---|---|---|---|---|---|---|---|---|",
            r.response,
            r.noise_sd,
            r.validation_observed.len(),
            r.train_observed.len()
        );
        let mut groups: Vec<(&str, Option<usize>)> = r
            .methods
            .iter()
            .map(|m| (m.method.as_str(), m.limit))
            .collect();
        groups.sort_by_key(|(m, l)| (l.unwrap_or(usize::MAX), *m != "mbgc", m.to_string()));
        groups.dedup();
        let runs = |method: &str, limit: Option<usize>| -> Vec<&MethodResult> {
            r.methods
                .iter()
                .filter(|m| m.method == method && m.limit == limit)
                .collect()
        };
        let rmse = |m: &MethodResult| score(r, m).validation.rmse / r.noise_sd;
        for &(method, limit) in &groups {
            let g = runs(method, limit);
            let scores: Vec<Scored> = g.iter().map(|m| score(r, m)).collect();
            let ratio: Vec<f64> = scores
                .iter()
                .map(|s| s.validation.rmse / r.noise_sd)
                .collect();
            let opt_mean = |v: Vec<Option<usize>>| -> String {
                let v: Vec<f64> = v.into_iter().flatten().map(|x| x as f64).collect();
                if v.is_empty() {
                    "-".into()
                } else {
                    format!("{:.0}", mean(&v))
                }
            };
            let _ = writeln!(
                w,
                "| {} | {} | {} | {} | {} | {:.4} | {} | {:.4} | {:.4} | {:.1} |",
                label(method),
                limit.map_or("-".into(), |l| l.to_string()),
                g.len(),
                opt_mean(g.iter().map(|m| m.own_length).collect()),
                opt_mean(g.iter().map(|m| m.nodes).collect()),
                mean(&scores.iter().map(|s| s.validation.rmse).collect::<Vec<_>>()),
                spread(&ratio),
                mean(&scores.iter().map(|s| s.validation.r2).collect::<Vec<_>>()),
                mean(&scores.iter().map(|s| s.train.r2).collect::<Vec<_>>()),
                mean(&g.iter().map(|m| m.seconds).collect::<Vec<_>>()),
            );
        }
        let mut limits: Vec<usize> = r.methods.iter().filter_map(|m| m.limit).collect();
        limits.sort_unstable();
        limits.dedup();
        let mut lines = Vec::new();
        for l in limits {
            let at = |name: &str| {
                let v: Vec<f64> = runs(name, Some(l)).into_iter().map(rmse).collect();
                (!v.is_empty()).then(|| mean(&v))
            };
            if let (Some(ours), Some(theirs)) = (at("mbgc"), at("pyoperon")) {
                let verdict = if ours <= theirs {
                    "mbgc no worse"
                } else {
                    "PyOperon better"
                };
                lines.push(format!(
                    "{l}: mbgc {ours:.2}, PyOperon {theirs:.2} ({verdict})"
                ));
            }
        }
        let _ = writeln!(
            w,
            "\nRMSE / noise at each limit (mean over the seeds): {}.",
            lines.join("; ")
        );
        let _ = writeln!(
            w,
            "\nAt equal counted nodes (each mbgc limit against the longest PyOperon limit whose \
             equations have no more nodes on average, by the sympy rule): {}.",
            equal_nodes(r).join("; ")
        );
        let _ = writeln!(
            w,
            "\nEquations (over the scaled columns; `_u` = scaled to [0, 1]):\n"
        );
        for m in r.methods.iter().filter(|m| m.method != "gaussian_process") {
            if m.method == "quadratic" {
                continue;
            }
            let _ = writeln!(
                w,
                "- {} at {}{}: `{}`",
                label(&m.method),
                m.limit.map_or("-".into(), |l| l.to_string()),
                m.seed.map_or(String::new(), |s| format!(", seed {s}")),
                m.equation
            );
        }
        let _ = writeln!(w);
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    fn method(name: &str, limit: Option<usize>, err: f64) -> MethodResult {
        MethodResult {
            method: name.into(),
            limit,
            seed: limit.map(|_| 1),
            own_length: limit.map(|l| l + 4),
            nodes: None,
            equation: "x".into(),
            seconds: 1.0,
            train_pred: vec![1.0 + err, 2.0 - err],
            validation_pred: vec![1.0 + err, 2.0 - err, 3.0 + err],
        }
    }

    /// Scores are in the response's units (prediction times factor), judged against the noise,
    /// and the summary names the better engine at each limit from those scores.
    #[test]
    fn the_report_scores_in_physical_units_and_says_who_is_better() {
        let r = ResponseResults {
            response: "bulk_density".into(),
            fitted: "solid_fraction".into(),
            symbols: vec!["x".into()],
            train_observed: vec![2.0, 4.0],
            train_factor: vec![2.0, 2.0],
            validation_observed: vec![2.0, 4.0, 6.0],
            validation_factor: vec![2.0, 2.0, 2.0],
            noise_sd: 0.5,
            methods: vec![
                method("mbgc", Some(10), 0.1),
                method("pyoperon", Some(10), 0.2),
                method("mbgc", Some(20), 0.3),
                method("pyoperon", Some(20), 0.1),
                // A second seed of mbgc at 20 nodes: its mean is reported.
                method("mbgc", Some(20), 0.1),
            ],
        };
        let s = score(&r, &r.methods[0]);
        assert!(
            (s.validation.rmse - 0.2).abs() < 1e-12,
            "{}",
            s.validation.rmse
        );
        let res = Results {
            mbgc_settings: gp::Config::default(),
            python_versions: serde_json::json!({"pyoperon": "0.6.2"}),
            operon_settings: serde_json::json!({}),
            responses: vec![r],
            command: "cmd".into(),
        };
        let noise = NoiseFloor {
            angle_sd: 1.0,
            bulk_rel_sd: 0.01,
            points: 3,
            runs: 6,
        };
        let text = report(&res, &noise, Path::new("r.json"));
        assert!(
            text.contains("10: mbgc 0.40, PyOperon 0.80 (mbgc no worse); 20: mbgc 0.80, PyOperon 0.40 (PyOperon better)"),
            "{text}"
        );
        // Two runs at 20 nodes: 1.20 and 0.40 times the noise.
        assert!(text.contains("| mbgc GP | 20 | 2 |"), "{text}");
        assert!(text.contains("0.80 ± 0.57 (0.40-1.20)"), "{text}");
    }
}
