//! `mbgc simulate`: a calibration experiment for every row of a design, appended to a table that
//! a restart of the same command resumes.

use mbgc::outputs::refuse_overwriting_inputs;
use mbgc_output::say;
use mbgc_output::Output;
use std::path::PathBuf;

use clap::Args;

use mbgc::dem::contact::ModelClass;
use mbgc::experiments::shear_box::RestRule;

use mbgc::campaign::decks::write_decks;
use mbgc::campaign::{
    experiment_by_name, parse_set, run_campaign, worker_threads, Backend, CampaignOptions,
    ExperimentSettings, Plan, Shard,
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
    #[arg(
        long,
        value_name = "CSV",
        required_unless_present = "write_decks",
        conflicts_with = "write_decks"
    )]
    pub out: Option<PathBuf>,
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
    /// When a shear-box run's fill and outflow are at rest: kinetic (speeds only, every shipped
    /// campaign's rule) or response (also when the measured density or angle has stood still
    /// for 5 chunks: 0.84 of the steps on a rerun validation design, docs/rest_validation.md).
    /// Recorded in the table's sidecar and, when not kinetic, in each run id; other
    /// experiments and the LIGGGHTS backend refuse it.
    #[arg(long, value_name = "RULE", value_parser = parse_rest_rule)]
    pub rest_rule: Option<RestRule>,
    /// Run again the rows whose earlier run failed (their failed lines are replaced).
    #[arg(long)]
    pub retry_failed: bool,
    /// Code that simulates: embedded (mbgc's DEM) or liggghts (LIGGGHTS 3.8 on the `liggghts`
    /// executable, shear-box and shear-cell only). Recorded in the table's `backend` column and in each run id.
    #[arg(long, default_value = "embedded", value_parser = parse_backend)]
    pub backend: Backend,
    /// MPI processes per LIGGGHTS run (`mpirun -np N`); --threads then defaults to cores / N.
    #[arg(long, value_name = "N")]
    pub mpi: Option<usize>,
    /// Keep each LIGGGHTS run's deck, log and dumps in DIR/<run_id>/ (default: a temporary
    /// directory, removed after the run).
    #[arg(long, value_name = "DIR")]
    pub decks: Option<PathBuf>,
    /// Write the LIGGGHTS decks into DIR/<run_id>/ without running them (with DIR/run_all.sh);
    /// `mbgc campaign import --decks DIR` reads the results back. --out is then not written.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["decks", "threads", "retry_failed", "vtk"])]
    pub write_decks: Option<PathBuf>,
    /// Standard output holds one JSON object (the run counts); text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

/// `--backend` as clap reads it.
pub fn parse_backend(s: &str) -> Result<Backend, String> {
    Backend::parse(s).map_err(|e| e.to_string())
}

/// `--rest-rule` as clap reads it.
pub fn parse_rest_rule(s: &str) -> Result<RestRule, String> {
    RestRule::parse(s)
}

/// `--model-class` as clap reads it (the message names the option and the known effects).
pub fn parse_model_class(s: &str) -> Result<ModelClass, String> {
    ModelClass::parse(s).map_err(|e| e.to_string())
}

/// The `--experiment` help, listing the experiments the registry knows.
pub fn experiment_help() -> String {
    format!(
        "Experiment run on every row: {}",
        mbgc::campaign::experiment_names().join(", ")
    )
}

pub fn run(a: &SimulateArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    if let Some(o) = &a.out {
        refuse_overwriting_inputs("--out", o, &[("--design", &a.design)])?;
    }
    let settings = ExperimentSettings {
        box_scale: a.box_scale,
        model_class: a.model_class,
        backend: a.backend,
        mpi: a.mpi,
        rest_rule: a.rest_rule,
    };
    if a.backend == Backend::Embedded {
        for (option, given) in [
            ("--decks", a.decks.is_some()),
            ("--write-decks", a.write_decks.is_some()),
        ] {
            if given {
                anyhow::bail!(
                    "{option}: the embedded backend writes no decks, so it would do nothing; use \
                     it with --backend liggghts"
                );
            }
        }
    }
    if let (Backend::Liggghts, Some(v)) = (a.backend, &a.vtk) {
        anyhow::bail!(
            "--vtk {}: the LIGGGHTS backend writes no VTK snapshots, so it would do nothing; its \
             dumps are kept with --decks DIR",
            v.display()
        );
    }
    if let (Some(n), Some(_)) = (a.mpi, &a.write_decks) {
        anyhow::bail!(
            "--mpi {n}: --write-decks runs nothing, so it would do nothing; choose the processes \
             when running the decks (run_all.sh N \"mpirun -np {n} liggghts\")"
        );
    }
    let experiment = experiment_by_name(&a.experiment, &settings)?;
    if a.backend == Backend::Liggghts && a.write_decks.is_none() {
        // Checked before the table is touched: otherwise every row would become a failed line.
        mbgc::liggghts::require_binary()?;
        if a.mpi.unwrap_or(1) > 1 {
            mbgc::liggghts::require_mpirun()?;
        }
        if let Some(d) = &a.decks {
            if d.join(mbgc::campaign::decks::CAMPAIGN_FILE).exists() {
                anyhow::bail!(
                    "--decks {}: holds decks written by --write-decks; read their runs with \
                     `mbgc campaign import --decks {}`",
                    d.display(),
                    d.display()
                );
            }
            std::fs::create_dir_all(d)
                .and_then(|()| tempfile::tempfile_in(d).map(drop))
                .map_err(|e| {
                    anyhow::anyhow!(
                        "--decks {}: cannot write there ({e}); expected a writable directory",
                        d.display()
                    )
                })?;
        }
    }
    let shard = a.shard.as_deref().map(Shard::parse).transpose()?;
    let set = a
        .set
        .iter()
        .map(|s| parse_set(s))
        .collect::<Result<Vec<_>, _>>()?;
    let threads = worker_threads(a.threads, a.mpi)?;
    let plan = Plan::new(
        experiment.as_ref(),
        &a.design,
        &set,
        a.seed,
        &settings,
        shard,
    )?;
    if let Some(dir) = &a.write_decks {
        let w = write_decks(experiment.as_ref(), &plan, dir)?;
        say!(
            out,
            "{}: {} decks written, {} already there ({} of {} rows{}); run them with {}/{} [N], \
             then: mbgc campaign import --decks {} --out TABLE.csv",
            dir.display(),
            w.written,
            w.kept,
            plan.selected().count(),
            plan.rows.len(),
            shard.map(|k| format!(", shard {k}")).unwrap_or_default(),
            dir.display(),
            mbgc::campaign::decks::RUN_SCRIPT,
            dir.display(),
        );
        return out.object(&serde_json::json!({
            "decks": dir,
            "written": w.written,
            "kept": w.kept,
            "rows": plan.selected().count(),
        }));
    }
    let Some(out_path) = a.out.clone() else {
        anyhow::bail!("--out: expected the campaign table (or --write-decks DIR)");
    };
    let a_out = &out_path;
    let s = run_campaign(
        experiment.as_ref(),
        &plan,
        &CampaignOptions {
            vtk_dir: a.vtk.clone(),
            observer: Some(crate::campaign_progress::bar()),
            retry_failed: a.retry_failed,
            work_dir: a.decks.clone(),
            ..CampaignOptions::new(out_path.clone(), threads)
        },
    )?;
    crate::campaign_progress::note_added_columns(a_out, &s);
    if s.truncated_bytes > 0 {
        eprintln!(
            "{}: removed an incomplete last line ({} bytes, an interrupted write); its run was \
             redone",
            a_out.display(),
            s.truncated_bytes
        );
    }
    let ran = s.done + s.failed;
    say!(
        out,
        "{}: {} ({}{}) on {} ({} rows{}): {} already in the table, ran {ran} ({} done, {} failed) \
         in {:.2} s{}",
        a_out.display(),
        plan.experiment,
        plan.model_class_label(),
        if a.backend.is_recorded() {
            format!(", {}", a.backend)
        } else {
            String::new()
        },
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
    if s.no_value > 0 {
        eprintln!(
            "{}: {} of the {} runs done measured no value of some response (NaN in the table; \
             a fit leaves them out): look at their warnings column",
            a_out.display(),
            s.no_value,
            s.done
        );
    }
    if s.retried > 0 {
        eprintln!(
            "{}: {} failed run(s) of earlier attempts removed and run again",
            a_out.display(),
            s.retried
        );
    }
    out.object(&s.json(&plan, a_out))?;
    // A cluster job array must see failures in the exit code, including those of an earlier
    // attempt that this resume skipped.
    let failed = s.failed + s.failed_before;
    if failed > 0 {
        anyhow::bail!(
            "{failed} of the {} runs of {} failed ({} in this invocation, {} earlier): they have \
             status=failed and their reason in the error column; rerun with --retry-failed{}",
            s.planned,
            a_out.display(),
            s.failed,
            s.failed_before,
            s.first_failure
                .as_ref()
                .map(|(id, e)| format!("\nthe first failed here, run {id}: {e}"))
                .unwrap_or_default()
        );
    }
    Ok(())
}
