//! `mbgc simulate`: a calibration experiment for every row of a design, appended to a table that
//! a restart of the same command resumes.

use crate::cli::output::Output;
use crate::outputs::refuse_overwriting_inputs;
use crate::say;
use std::path::PathBuf;

use clap::Args;

use crate::dem::contact::ModelClass;

use crate::campaign::{
    experiment_by_name, parse_set, run_campaign, CampaignOptions, ExperimentSettings, Plan, Shard,
};

#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Design CSV: a header of parameter names, one run per row (a column the experiment does not
    /// read is refused).
    #[arg(long, value_name = "CSV")]
    pub design: PathBuf,
    /// Experiment run on every row.
    #[arg(long, help = experiment_help())]
    pub experiment: String,
    /// Output table; if it exists, the campaign resumes where it stopped.
    #[arg(long, value_name = "CSV")]
    pub out: PathBuf,
    /// Worker threads, one run each [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// Run only the rows with row % N == K - 1 (rows 0-based, K 1-based), for job arrays.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Campaign seed; row r runs with a seed derived from this seed and r only.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Constant parameter for every row, e.g. --set impact_speed=3.9 (repeatable); a design
    /// column of the same name is an error.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Directory for VTK snapshots, one subdirectory per run id (experiments that write them).
    #[arg(long, value_name = "DIR")]
    pub vtk: Option<PathBuf>,
    /// Size factor of the shear box (k: the smallest side in d_max); other experiments refuse it.
    #[arg(long, value_name = "K", allow_negative_numbers = true)]
    pub box_scale: Option<f64>,
    /// Effects of the contact law, comma-separated, e.g. hertz,mindlin,epsd2,sjkr [default:
    /// hertz,mindlin,epsd2]; their parameters must be design columns or --set values, and a
    /// parameter of an effect not named is refused. Recorded in the table and in each run id.
    #[arg(long, value_name = "EFFECTS", value_parser = parse_model_class)]
    pub model_class: Option<ModelClass>,
    /// Run again the rows whose earlier run failed (their failed lines are replaced).
    #[arg(long)]
    pub retry_failed: bool,
    /// Standard output holds one JSON object (the run counts); text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

/// `--model-class` as clap reads it (the message names the option and the known effects).
pub fn parse_model_class(s: &str) -> Result<ModelClass, String> {
    ModelClass::parse(s).map_err(|e| e.to_string())
}

/// The `--experiment` help, listing the experiments the registry knows.
pub fn experiment_help() -> String {
    format!(
        "Experiment run on every row: {}",
        crate::campaign::experiment_names().join(", ")
    )
}

pub fn run(a: &SimulateArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    refuse_overwriting_inputs("--out", &a.out, &[("--design", &a.design)])?;
    let settings = ExperimentSettings {
        box_scale: a.box_scale,
        model_class: a.model_class,
    };
    let experiment = experiment_by_name(&a.experiment, &settings)?;
    let shard = a.shard.as_deref().map(Shard::parse).transpose()?;
    let set = a
        .set
        .iter()
        .map(|s| parse_set(s))
        .collect::<Result<Vec<_>, _>>()?;
    let threads = match a.threads {
        Some(0) => anyhow::bail!("--threads: expected at least 1"),
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let plan = Plan::new(
        experiment.as_ref(),
        &a.design,
        &set,
        a.seed,
        &settings,
        shard,
    )?;
    let s = run_campaign(
        experiment.as_ref(),
        &plan,
        &CampaignOptions {
            out: a.out.clone(),
            threads,
            vtk_dir: a.vtk.clone(),
            progress: true,
            retry_failed: a.retry_failed,
        },
    )?;
    if s.truncated_bytes > 0 {
        eprintln!(
            "{}: removed an incomplete last line ({} bytes, an interrupted write); its run was \
             redone",
            a.out.display(),
            s.truncated_bytes
        );
    }
    let ran = s.done + s.failed;
    say!(
        out,
        "{}: {} ({}) on {} ({} rows{}): {} already in the table, ran {ran} ({} done, {} failed) in \
         {:.2} s{}",
        a.out.display(),
        plan.experiment,
        plan.model_class_label(),
        a.design.display(),
        plan.rows.len(),
        shard
            .map(|k| format!(", shard {k}: {}", s.planned))
            .unwrap_or_default(),
        s.skipped,
        s.done,
        s.failed,
        s.elapsed_s,
        if ran > 0 {
            format!(
                ", {:.1} runs/s on {} threads",
                ran as f64 / s.elapsed_s,
                s.threads
            )
        } else {
            String::new()
        }
    );
    if s.retried > 0 {
        eprintln!(
            "{}: {} failed run(s) of earlier attempts removed and run again",
            a.out.display(),
            s.retried
        );
    }
    out.object(&serde_json::json!({
        "out": a.out,
        "experiment": plan.experiment,
        "model_class": plan.model_class.map(|c| c.to_string()),
        "design": a.design,
        "design_rows": plan.rows.len(),
        "shard": shard.map(|k| k.to_string()),
        "planned": s.planned,
        "skipped": s.skipped,
        "done": s.done,
        "failed": s.failed,
        "failed_before": s.failed_before,
        "retried": s.retried,
        "truncated_bytes": s.truncated_bytes,
        "threads": s.threads,
        "elapsed_s": s.elapsed_s,
    }))?;
    // A cluster job array must see failures in the exit code, including those of an earlier
    // attempt that this resume skipped.
    let failed = s.failed + s.failed_before;
    if failed > 0 {
        anyhow::bail!(
            "{failed} of the {} runs of {} failed ({} in this invocation, {} earlier): they have \
             status=failed and their reason in the error column; rerun with --retry-failed",
            s.planned,
            a.out.display(),
            s.failed,
            s.failed_before
        );
    }
    Ok(())
}
