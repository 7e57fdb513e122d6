//! `mbgc diagnose`: compare a measurement set with the model, show where it fails, rank the
//! candidate missing effects, and (with a model of the extended class) the error ladder.

use std::path::PathBuf;

use clap::Args;

use mbgc::diagnose::build::{self, BuildOptions};
use mbgc::diagnose::report::{figures, json, markdown};
use mbgc::diagnose::{diagnose, MeasurementSet, Options, Surrogate};
use mbgc::shipped;
use mbgc_output::say;
use mbgc_output::Output;

#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    /// Measurement set: several samples of one material (see `docs/diagnose.md`).
    #[arg(long)]
    pub measurements: PathBuf,
    /// Metamodels: one of the set's class, and models of classes with a candidate effect (a
    /// model of a richer class also serves the poorer one, with the extra effect off)
    /// [default: the shipped models/shear_box.json, models/shear_cell.json and their cohesive
    /// extensions models/shear_box_sjkr.json and models/shear_cell_sjkr.json, built into mbgc].
    #[arg(long)]
    pub model: Vec<PathBuf>,
    /// L-BFGS starts of each joint fit.
    #[arg(long, default_value_t = 16)]
    pub starts: usize,
    /// TMCMC samples per stage (evidences and posterior intervals).
    #[arg(long, default_value_t = 2000)]
    pub samples: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Family-wise significance level of the chi^2 test and the residual-structure tests.
    #[arg(long, default_value_t = 0.01)]
    pub alpha: f64,
    /// Directory for the figures (parity, residual against d50, error ladder).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Standard output holds one JSON object; text goes to standard error.
    #[arg(long)]
    pub json: bool,
    /// Build the models the diagnosis lacks before it runs: for each candidate effect (all, or
    /// those named, e.g. `--build sjkr`) that no model covers for this material, a local model
    /// around it (known values fixed; searched ones, the effect's strength and the samples' span
    /// varied), trained into --build-dir and resumed by the next call. When the given models
    /// cover everything but limit the diagnosis (their own error above the measurements' sd and
    /// no candidate decisive), a local model of the best candidate (or of those named) instead,
    /// which replaces them for its experiment.
    #[arg(long, value_name = "EFFECTS", num_args = 0.., value_delimiter = ',')]
    pub build: Option<Vec<String>>,
    /// DEM runs per local model, in two rounds: half over the whole search range (a fifth
    /// validating it, a quarter of that repeating validation runs for the DEM noise, a quarter of
    /// the training runs of the set's own class), and what is left only if that model is less
    /// precise than the measurements: near the material, or extending the first round [default:
    /// 60].
    #[arg(long, value_name = "N")]
    pub budget_runs: Option<usize>,
    /// Directory of the local models (spaces/, sampling/, training_data/, models/) [default:
    /// diagnose_models].
    #[arg(long, value_name = "DIR")]
    pub build_dir: Option<PathBuf>,
    /// Worker threads of the local models' campaigns [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
}

const BUDGET_RUNS: usize = 60;
const BUILD_DIR: &str = "diagnose_models";

pub fn run(a: &DiagnoseArgs) -> anyhow::Result<()> {
    let opts = Options {
        starts: a.starts,
        samples: a.samples,
        seed: a.seed,
        alpha: a.alpha,
    };
    opts.check()?;
    if a.build.is_none() {
        for (given, flag) in [
            (a.budget_runs.is_some(), "--budget-runs"),
            (a.build_dir.is_some(), "--build-dir"),
            (a.threads.is_some(), "--threads"),
        ] {
            if given {
                anyhow::bail!("{flag}: sets how local models are built, so it needs --build");
            }
        }
    }
    let threads = match a.threads {
        Some(0) => anyhow::bail!("--threads: expected at least 1"),
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let out = Output::new(a.json);
    let mut set = MeasurementSet::from_file(&a.measurements)?;
    let mut models = shipped::files_or_models(&a.model, shipped::DIAGNOSIS_MODELS)?
        .into_iter()
        .map(|(m, label)| Surrogate::from_model(m, &label))
        .collect::<mbgc::error::Result<Vec<_>>>()?;
    let mut build_opts = BuildOptions::new(
        a.budget_runs.unwrap_or(BUDGET_RUNS),
        a.build_dir
            .clone()
            .unwrap_or_else(|| PathBuf::from(BUILD_DIR)),
    );
    build_opts.threads = threads;
    if a.build.is_some() {
        build::check_budget(build_opts.budget_runs)?;
    }
    build_opts.seed = a.seed;
    let mut built_models = Vec::new();
    // A diagnosis already made with the models used for the final one.
    let mut first_diagnosis = None;
    if let Some(wanted) = &a.build {
        let plans = build::plan(&set, &models, wanted)?;
        // Each build sees the set as given; the diagnosis then searches where the built models
        // are valid (a second round's box narrows it).
        let original = set.clone();
        for p in &plans {
            let (model, json) = build_one(p, &original, &build_opts, &out, &mut set)?;
            models.push(model);
            built_models.push(json);
        }
        if plans.is_empty() {
            // Covered: but are the models as precise as the measurements? A first diagnosis
            // with them says.
            let first = diagnose(&set, &models, &opts)?;
            let sharper = build::plan_sharper(&set, &models, wanted, &first)?;
            if sharper.is_empty() {
                say!(
                    out,
                    "--build: the given models cover every candidate for this material{}; nothing \
                     to build",
                    if first.ranking.is_empty() {
                        " (none could be evaluated with them, so none can be sharpened)"
                    } else {
                        " and do not limit its diagnosis"
                    }
                );
                first_diagnosis = Some(first);
            }
            let mut local = Vec::new();
            for p in &sharper {
                say!(out, "--build: for {}, {}", p.experiment, p.reason);
                let (model, json) = build_one(p, &original, &build_opts, &out, &mut set)?;
                let before = models.len();
                models.retain(|m| !build::replaced_by(m, p, &set.class));
                say!(
                    out,
                    "the local model replaces the {} given model(s) of {} it stands for in this \
                     diagnosis",
                    before - models.len(),
                    p.experiment
                );
                local.push(model);
                built_models.push(json);
            }
            models.extend(local);
        }
    }
    let d = match first_diagnosis.map_or_else(|| diagnose(&set, &models, &opts), Ok) {
        Ok(d) => d,
        Err(e) if a.build.is_none() => match build::plan(&set, &models, &[]) {
            Ok(plans) if !plans.is_empty() => anyhow::bail!(
                "{e}\n`mbgc diagnose --measurements {} --build` would build what is missing \
                 around this material: {}",
                a.measurements.display(),
                plans
                    .iter()
                    .map(|p| plan_text(p, &build_opts))
                    .collect::<Vec<_>>()
                    .join("; ")
            ),
            _ => return Err(e.into()),
        },
        Err(e) => return Err(e.into()),
    };
    say!(out, "{}", markdown(&d).trim_end());
    if a.build.is_none() && !d.unavailable.is_empty() {
        match build::plan(&set, &models, &[]) {
            Ok(plans) if !plans.is_empty() => {
                say!(
                    out,
                    "\nThe missing models can be built around this material: `mbgc diagnose \
                     --measurements {} --build{}` would train",
                    a.measurements.display(),
                    if a.model.is_empty() {
                        String::new()
                    } else {
                        a.model
                            .iter()
                            .map(|m| format!(" --model {}", m.display()))
                            .collect::<String>()
                    }
                );
                for p in &plans {
                    say!(out, "- {}", plan_text(p, &build_opts));
                }
            }
            Ok(_) => {}
            Err(e) => say!(out, "\nThe missing models cannot be built here: {e}"),
        }
    }
    if let Some(dir) = &a.plot {
        for f in figures(&d, dir)? {
            say!(out, "figure: {}", f.display());
        }
    }
    let mut report = json(&d);
    report["built"] = serde_json::Value::Array(built_models);
    out.object(&report)?;
    Ok(())
}

/// Builds (or resumes) one local model and says what it is; narrows `set` to a second round's
/// box. Its surrogate and its entry of the report's `built`.
fn build_one(
    p: &build::LocalPlan,
    original: &MeasurementSet,
    build_opts: &BuildOptions,
    out: &Output,
    set: &mut MeasurementSet,
) -> anyhow::Result<(Surrogate, serde_json::Value)> {
    say!(out, "{}", plan_text(p, build_opts));
    let printer = crate::train_progress::Printer::new(build_opts.config.generations);
    let built = build::build(original, p, build_opts, &printer);
    printer.bar.finish_and_clear();
    let built = built?;
    if let Some(first) = &built.first {
        say!(
            out,
            "local model {} (first round, the whole search range): {} training runs; {}",
            first.path.display(),
            first.training_runs,
            build::precision_text(first)
        );
    }
    say!(
        out,
        "local model {}: {} training runs ({} finished rows fitted{}){}; {}",
        built.path.display(),
        built.training_runs,
        built.model.data.train_rows,
        if built.first.is_some() {
            ", the first round's inside its box among them"
        } else {
            ""
        },
        if built.first.is_some() {
            format!(" over {}", build::ranges_text(&built.plan.varied))
        } else {
            String::new()
        },
        build::precision_text(&built)
    );
    if !built.precise_enough() {
        say!(
            out,
            "warning: the local model's own error exceeds the measurement sd of a response, so \
             it, not the measurements, limits the diagnosis; a larger --budget-runs extends its \
             design (its runs are kept)"
        );
    }
    if !built.focus.is_empty() {
        say!(
            out,
            "the search ranges are those the second round's model was built for: {}",
            build::ranges_text(&built.focus)
        );
        *set = build::narrow(set, &built);
    }
    let json = serde_json::json!({
        "name": built.plan.name,
        "model": built.path,
        "class": built.plan.class.to_string(),
        "experiment": built.plan.experiment,
        "effect": built.plan.effect.map(|e| e.name),
        "reason": built.plan.reason,
        "varied": built.plan.varied,
        "training_runs": built.training_runs,
        "precision": precision_json(&built),
        "focus": built.focus,
        "first_round": built.first.as_ref().map(|f| serde_json::json!({
            "model": f.path,
            "varied": f.plan.varied,
            "training_runs": f.training_runs,
            "precision": precision_json(f),
        })),
    });
    Ok((build::surrogate(&built)?, json))
}

fn precision_json(b: &build::Built) -> Vec<serde_json::Value> {
    b.precision
        .iter()
        .map(|p| {
            serde_json::json!({
                "response": p.response,
                "validation_rmse": p.validation_rmse,
                "replicate_sd": p.replicate_sd,
                "model_error": p.model_error(),
                "measurement_sd": p.measurement_sd,
            })
        })
        .collect()
}

/// What a local model will be: class, experiment, what it varies and its budget.
fn plan_text(p: &build::LocalPlan, o: &BuildOptions) -> String {
    format!(
        "local model {} ({}, {}; {}) over {}, {} DEM runs at most ({} of them validation in a \
         first round over this range, the rest in a second round near the material if the first \
         model is less precise than the measurements) into {}",
        p.name,
        p.class,
        p.experiment,
        p.effect.map_or("the set's class".to_string(), |e| format!(
            "candidate {}",
            e.name
        )),
        p.varied
            .iter()
            .map(|(n, [lo, hi])| format!("{n} in [{lo:.4}, {hi:.4}]"))
            .collect::<Vec<_>>()
            .join(", "),
        o.budget_runs,
        o.validation(),
        o.dir.display()
    )
}
