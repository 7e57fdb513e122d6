//! `mbgc slurm`: a campaign as a Slurm job array (one shard per array task) and a merge job,
//! written as scripts and, with `--submit`, submitted.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::simulate::{experiment_help, parse_backend, parse_model_class};
use mbgc::campaign::slurm::{check_time, submit, JobArray, SUBMIT_SCRIPT};
use mbgc::campaign::{experiment_by_name, parse_set, Backend, ExperimentSettings, Plan};
use mbgc::dem::contact::ModelClass;
use mbgc::outputs::refuse_overwriting_inputs;
use mbgc_output::say;
use mbgc_output::Output;

#[derive(Debug, Args)]
pub struct SlurmArgs {
    /// Design CSV, as for `mbgc simulate`.
    #[arg(long, value_name = "CSV")]
    pub design: PathBuf,
    #[arg(long, help = experiment_help())]
    pub experiment: String,
    /// The merged campaign table the merge job writes.
    #[arg(long, value_name = "CSV")]
    pub out: PathBuf,
    /// Array tasks, one shard of the design each.
    #[arg(long, value_name = "N")]
    pub shards: usize,
    /// Slurm partition [default: the cluster's].
    #[arg(long, value_name = "P")]
    pub partition: Option<String>,
    /// Time limit of each array task, as Slurm reads it (e.g. 2:00:00) [default: the partition's].
    #[arg(long, value_name = "T")]
    pub time: Option<String>,
    /// CPUs of each array task: it runs that many runs at a time (divided by --mpi).
    #[arg(long, value_name = "C", default_value_t = 1)]
    pub cpus_per_task: usize,
    /// Directory of the scripts, shard tables and logs [default: <out>.slurm].
    #[arg(long, value_name = "DIR")]
    pub dir: Option<PathBuf>,
    /// Submit the array and the merge job (sbatch) after writing the scripts.
    #[arg(long)]
    pub submit: bool,
    /// Campaign seed, as for `mbgc simulate`.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Constant parameter for every row (repeatable), as for `mbgc simulate`.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Size factor of the shear box, as for `mbgc simulate`.
    #[arg(long, value_name = "K", allow_negative_numbers = true)]
    pub box_scale: Option<f64>,
    /// Effects of the contact law, as for `mbgc simulate`.
    #[arg(long, value_name = "EFFECTS", value_parser = parse_model_class)]
    pub model_class: Option<ModelClass>,
    /// kinetic or response, as for `mbgc simulate`.
    #[arg(long, value_name = "RULE", value_parser = crate::simulate::parse_rest_rule)]
    pub rest_rule: Option<mbgc::experiments::shear_box::RestRule>,
    /// embedded or liggghts, as for `mbgc simulate`.
    #[arg(long, default_value = "embedded", value_parser = parse_backend)]
    pub backend: Backend,
    /// MPI processes per LIGGGHTS run.
    #[arg(long, value_name = "N")]
    pub mpi: Option<usize>,
    /// Tasks rerun the rows whose earlier run failed.
    #[arg(long)]
    pub retry_failed: bool,
    /// Standard output holds one JSON object; the text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

fn absolute(p: &Path, cwd: &Path) -> PathBuf {
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        cwd.join(p)
    }
}

pub fn run(a: &SlurmArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    refuse_overwriting_inputs("--out", &a.out, &[("--design", &a.design)])?;
    if a.shards == 0 {
        anyhow::bail!("--shards 0: expected at least 1 array task");
    }
    if a.cpus_per_task == 0 {
        anyhow::bail!("--cpus-per-task 0: expected at least 1");
    }
    if let Some(t) = &a.time {
        check_time(t)?;
    }
    let mpi = a.mpi.unwrap_or(1);
    if a.cpus_per_task < mpi {
        anyhow::bail!(
            "--cpus-per-task {}: fewer than the {mpi} MPI processes of one run (--mpi)",
            a.cpus_per_task
        );
    }
    // Everything a task would refuse is refused here, before anything is submitted.
    let settings = ExperimentSettings {
        box_scale: a.box_scale,
        model_class: a.model_class,
        backend: a.backend,
        mpi: a.mpi,
        rest_rule: a.rest_rule,
    };
    let experiment = experiment_by_name(&a.experiment, &settings)?;
    let set = a
        .set
        .iter()
        .map(|s| parse_set(s))
        .collect::<Result<Vec<_>, _>>()?;
    let plan = Plan::new(
        experiment.as_ref(),
        &a.design,
        &set,
        a.seed,
        &settings,
        None,
    )?;
    if a.shards > plan.rows.len() {
        anyhow::bail!(
            "--shards {}: the design {} has {} rows; more tasks than rows would leave tasks empty",
            a.shards,
            a.design.display(),
            plan.rows.len()
        );
    }
    let cwd = std::env::current_dir()?;
    let mbgc = std::env::current_exe()?;
    let out_abs = absolute(&a.out, &cwd);
    let dir = a
        .dir
        .as_ref()
        .map(|d| absolute(d, &cwd))
        .unwrap_or_else(|| {
            let mut name = out_abs.file_name().unwrap_or_default().to_os_string();
            name.push(".slurm");
            out_abs.with_file_name(name)
        });
    if dir.is_file() || mbgc::outputs::same_path(&dir, &out_abs) {
        anyhow::bail!(
            "--dir {}: expected a directory for the scripts, other than --out (the merged table)",
            dir.display()
        );
    }
    let mut args = vec![
        "--design".to_string(),
        absolute(&a.design, &cwd).display().to_string(),
        "--experiment".into(),
        a.experiment.clone(),
        "--seed".into(),
        a.seed.to_string(),
        "--backend".into(),
        a.backend.label().into(),
    ];
    for s in &a.set {
        args.extend(["--set".into(), s.clone()]);
    }
    if let Some(k) = a.box_scale {
        args.extend(["--box-scale".into(), format!("{k:?}")]);
    }
    if let Some(c) = a.model_class {
        args.extend(["--model-class".into(), c.to_string()]);
    }
    if let Some(r) = a.rest_rule {
        args.extend(["--rest-rule".into(), r.label()]);
    }
    if let Some(n) = a.mpi {
        args.extend(["--mpi".into(), n.to_string()]);
    }
    if a.retry_failed {
        args.push("--retry-failed".into());
    }
    let stem = out_abs
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "campaign".into());
    let job = JobArray {
        mbgc,
        workdir: cwd,
        simulate_args: args,
        out: out_abs,
        dir: dir.clone(),
        shards: a.shards,
        job_name: format!("mbgc-{stem}"),
        partition: a.partition.clone(),
        time: a.time.clone(),
        cpus_per_task: a.cpus_per_task,
        mpi,
    };
    job.write()?;
    say!(
        out,
        "{}: {} array tasks over {} rows ({} ({}) on {}), merge into {}; submit with {}",
        dir.display(),
        a.shards,
        plan.rows.len(),
        plan.experiment,
        plan.model_class_label(),
        a.backend,
        job.out.display(),
        dir.join(SUBMIT_SCRIPT).display()
    );
    let ids = if a.submit {
        let (array, merge) = submit(&dir)?;
        say!(
            out,
            "submitted: array job {array} ({} tasks), merge job {merge} after it; rerun failed or \
             killed tasks by running {} again",
            a.shards,
            dir.join(SUBMIT_SCRIPT).display()
        );
        Some((array, merge))
    } else {
        None
    };
    out.object(&serde_json::json!({
        "dir": dir,
        "shards": a.shards,
        "rows": plan.rows.len(),
        "out": job.out,
        "shard_tables": (1..=a.shards).map(|k| job.shard_table(k)).collect::<Vec<_>>(),
        "array_job": ids.as_ref().map(|i| i.0.clone()),
        "merge_job": ids.as_ref().map(|i| i.1.clone()),
    }))
}
