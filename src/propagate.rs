//! `mbgc propagate`: posterior samples -> draws -> DEM runs of a process experiment -> the
//! robust band of each quantity beside the best-fit point's value (`mbgc::propagate`).

use std::path::{Path, PathBuf};

use clap::Args;
use mbgc::campaign::{
    experiment_by_name, parse_set, run_campaign, worker_threads, CampaignOptions,
    ExperimentSettings, Plan,
};
use mbgc::dem::contact::ModelClass;
use mbgc::error::{read_to_string, write_atomic};
use mbgc::experiments::Experiment;
use mbgc::outputs::refuse_overwriting_inputs;
use mbgc::propagate::{self, resample, Band, DrawDesign, EventRate, PosteriorFile, RecordedRuns};
use mbgc_output::{say, Output};

/// `--metamodel-outside`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MetamodelOutside {
    /// Refuse the band when a draw lies outside the model's domain.
    Refuse,
    /// Leave such draws out of the metamodel's band, counted and listed in the report.
    Skip,
}

#[derive(Debug, Args)]
pub struct PropagateArgs {
    /// Posterior samples written by `mbgc calibrate --bayes --posterior-out`.
    #[arg(long)]
    pub posterior: PathBuf,
    #[arg(long, default_value = "hopper", help = crate::simulate::experiment_help())]
    pub experiment: String,
    /// Directory of the propagation: design.csv and runs.csv (resumable: the same command goes
    /// on where it stopped), best_design.csv and best.csv with --params.
    #[arg(long)]
    pub out_dir: PathBuf,
    /// Draws from the posterior (systematic resampling by weight), each a DEM run per seed.
    #[arg(long, default_value_t = 100)]
    pub draws: usize,
    /// Runs per draw, each with its own seed: with 2 or more the run-to-run scatter is told
    /// apart from the spread the posterior causes.
    #[arg(long, default_value_t = 1)]
    pub seeds: usize,
    /// Seed of the draws and of the runs (row r runs with a seed derived from it and r).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The calibrated point (`mbgc calibrate --out`): its runs (as many seeds as a draw) give
    /// the single best-fit prediction beside the band.
    #[arg(long)]
    pub params: Option<PathBuf>,
    /// A metamodel of the quantities (e.g. a hopper model from `mbgc train`): the draws also go
    /// through its equations, with and without its own error, beside the DEM band.
    #[arg(long, value_name = "MODEL.json")]
    pub metamodel: Option<PathBuf>,
    /// What a draw outside the metamodel's domain does: `refuse` the band, or `skip` the draw
    /// (left out of the metamodel's band, counted and listed in the report).
    #[arg(long, value_enum, default_value_t = MetamodelOutside::Refuse, requires = "metamodel")]
    pub metamodel_outside: MetamodelOutside,
    /// Constants the experiment needs beyond the posterior's parameters (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Effects of the contact law [default: hertz,mindlin,epsd2]; every effect parameter the
    /// posterior holds must belong to it.
    #[arg(long, value_name = "EFFECTS", value_parser = crate::simulate::parse_model_class)]
    pub model_class: Option<ModelClass>,
    /// Quantities to report, comma-separated [default: the experiment's measured responses].
    #[arg(long, value_delimiter = ',')]
    pub responses: Vec<String>,
    /// Worker threads, one run each [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// Directory for the figures: one robust CDF per quantity (`<quantity>.svg`).
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Markdown report of the bands.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Standard output holds one JSON object (the bands); text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

/// Writes a design, or checks that the one there is the same: a propagation's directory holds
/// one propagation, and its runs are only resumed under the design that made them. A design
/// whose table `runs` does not exist yet (nothing ran) is replaced.
fn put_design(path: &Path, text: &str, runs: &Path) -> anyhow::Result<()> {
    if path.exists() && runs.exists() {
        if read_to_string(path)? != text {
            anyhow::bail!(
                "{}: holds the design of another propagation (other draws, seeds or \
                 posterior), whose runs are in this directory; choose another --out-dir to keep \
                 both",
                path.display()
            );
        }
        return Ok(());
    }
    write_atomic(path, text.as_bytes())?;
    Ok(())
}

/// The runs of `plan` in the table at `out`: per design row, the recorded values of `names`
/// (NaN where the run has none or the table no such column), `None` for a row that has not
/// finished (not run yet, or failed). The shape [`RecordedRuns::new`] takes.
fn recorded(out: &Path, plan: &Plan, names: &[&str]) -> anyhow::Result<Vec<Option<Vec<f64>>>> {
    let mut reader =
        csv::Reader::from_path(out).map_err(|e| anyhow::anyhow!("{}: {e}", out.display()))?;
    let header = reader
        .headers()
        .map_err(|e| anyhow::anyhow!("{}: header: {e}", out.display()))?
        .clone();
    let col = |name: &str| {
        header.iter().position(|h| h == name).ok_or_else(|| {
            anyhow::anyhow!(
                "{}: column {name}: expected in the campaign table",
                out.display()
            )
        })
    };
    let (row_col, status_col) = (col("row")?, col("status")?);
    let value_cols: Vec<Option<usize>> = names
        .iter()
        .map(|n| header.iter().position(|h| h == *n))
        .collect();
    let mut v = vec![None; plan.rows.len()];
    for (i, rec) in reader.records().enumerate() {
        let rec = rec.map_err(|e| anyhow::anyhow!("{}: line {}: {e}", out.display(), i + 2))?;
        let row: usize = rec[row_col].parse().map_err(|_| {
            anyhow::anyhow!(
                "{}: line {}, column row: expected a row number, found \"{}\"",
                out.display(),
                i + 2,
                &rec[row_col]
            )
        })?;
        if rec[status_col] == *"done" {
            if let Some(slot) = v.get_mut(row) {
                *slot = Some(
                    value_cols
                        .iter()
                        .map(|c| c.and_then(|c| rec[c].parse().ok()).unwrap_or(f64::NAN))
                        .collect(),
                );
            }
        }
    }
    Ok(v)
}

/// Runs the design at `path` into the table `out`; returns the plan.
fn run_design(
    experiment: &dyn Experiment,
    design: &Path,
    out: &Path,
    set: &[(String, f64)],
    a: &PropagateArgs,
    settings: &ExperimentSettings,
) -> anyhow::Result<Plan> {
    let plan = Plan::new(experiment, design, set, a.seed, settings, None)?;
    let threads = worker_threads(a.threads, None)?;
    let s = run_campaign(
        experiment,
        &plan,
        &CampaignOptions {
            observer: Some(crate::campaign_progress::bar()),
            ..CampaignOptions::new(out.to_path_buf(), threads)
        },
    )?;
    crate::campaign_progress::note_added_columns(out, &s);
    Ok(plan)
}

/// Formats a number with 4 significant digits.
fn num(v: f64) -> String {
    if !v.is_finite() {
        return "-".into();
    }
    let (s, e) = mbgc::numeric::four_significant(v);
    match e {
        Some(e) => format!("{s}e{e}"),
        None => s,
    }
}

pub fn run(a: &PropagateArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    let post = PosteriorFile::read(&a.posterior)?;
    let set = a
        .set
        .iter()
        .map(|s| parse_set(s))
        .collect::<Result<Vec<_>, _>>()?;
    let settings = ExperimentSettings {
        model_class: a.model_class,
        ..Default::default()
    };
    let experiment = experiment_by_name(&a.experiment, &settings)?;
    let responses: Vec<String> = if a.responses.is_empty() {
        experiment
            .calibration_responses()
            .into_iter()
            .map(String::from)
            .collect()
    } else {
        a.responses.clone()
    };
    let known = experiment.responses();
    if let Some(r) = responses.iter().find(|r| !known.contains(&r.as_str())) {
        anyhow::bail!(
            "--responses {r}: {} reports no {r} (it reports {})",
            a.experiment,
            known.join(", ")
        );
    }
    let draws = resample::systematic(&post.weights, a.draws, a.seed)?;
    let d = propagate::design(&post, experiment.as_ref(), &draws, a.seeds, &set)?;
    // The cheap path first: a model that cannot take the draws is refused before any run.
    let through_model = match &a.metamodel {
        None => None,
        Some(m) => {
            let model = mbgc::metamodel::Metamodel::load(m)?;
            if let Some(e) = model.experiment.as_ref().filter(|e| **e != a.experiment) {
                anyhow::bail!(
                    "--metamodel {}: a model of {e} runs, not of --experiment {}",
                    m.display(),
                    a.experiment
                );
            }
            if let (Some(c), Some(mine)) = (model.class()?, experiment.class()) {
                if c != *mine {
                    anyhow::bail!(
                        "--metamodel {}: fitted on runs of class {c}, the propagation runs {mine}",
                        m.display()
                    );
                }
            }
            let draws_only: Vec<Vec<f64>> = d.rows.iter().step_by(d.seeds).cloned().collect();
            let mut header = d.header.clone();
            let mut rows = draws_only;
            for (k, v) in &set {
                header.push(k.clone());
                rows.iter_mut().for_each(|r| r.push(*v));
            }
            Some(propagate::through_metamodel(
                &model,
                &header,
                &rows,
                &responses,
                a.seed,
                a.metamodel_outside == MetamodelOutside::Skip,
            )?)
        }
    };
    let best = match &a.params {
        None => None,
        Some(p) => {
            let (params, _, params_class, _) = crate::validate::read_params(p)?;
            // A calibrated value the propagation would not use is refused, as is another class.
            for (k, v) in params.iter() {
                let given = set.iter().find(|(s, _)| s == k).map(|(_, x)| *x);
                if !post.inputs.iter().any(|i| i == k) && given != Some(v) {
                    anyhow::bail!(
                        "{}: [parameters] {k} = {v}: the posterior does not hold {k}, so the \
                         best-fit point would run without this value{}; drop it or pass --set \
                         {k}={v}",
                        p.display(),
                        given.map_or(String::new(), |g| format!(" (--set gives {g})"))
                    );
                }
            }
            if let (Some(c), Some(mine)) = (params_class, experiment.class()) {
                if c != *mine {
                    anyhow::bail!(
                        "{}: [model] class {c}: the propagation runs {mine} (--model-class); the \
                         best-fit point must run the class it was calibrated in",
                        p.display()
                    );
                }
            }
            let row: Vec<f64> = post
                .inputs
                .iter()
                .map(|n| {
                    params.get(n).ok_or_else(|| {
                        anyhow::anyhow!(
                            "{}: [parameters] {n}: expected a value (the posterior holds {n})",
                            p.display()
                        )
                    })
                })
                .collect::<anyhow::Result<_>>()?;
            let one = PosteriorFile {
                rows: vec![row],
                sigma: vec![0.0],
                weights: vec![1.0],
                ..post.clone()
            };
            Some(propagate::design(
                &one,
                experiment.as_ref(),
                &[0],
                a.seeds,
                &set,
            )?)
        }
    };
    std::fs::create_dir_all(&a.out_dir)
        .map_err(|e| anyhow::anyhow!("--out-dir {}: {e}", a.out_dir.display()))?;
    let path = |f: &str| a.out_dir.join(f);
    let mut inputs: Vec<(&str, &Path)> = vec![("--posterior", &a.posterior)];
    if let Some(p) = &a.params {
        inputs.push(("--params", p));
    }
    if let Some(m) = &a.metamodel {
        inputs.push(("--metamodel", m));
    }
    let own = [
        "design.csv",
        "runs.csv",
        "runs.csv.meta.json",
        "runs.csv.lock",
        "best_design.csv",
        "best.csv",
        "best.csv.meta.json",
        "best.csv.lock",
    ];
    for f in own {
        refuse_overwriting_inputs("--out-dir", &path(f), &inputs)?;
    }
    if let Some(r) = &a.report {
        refuse_overwriting_inputs("--report", r, &inputs)?;
        let outputs: Vec<(&str, PathBuf)> = own.iter().map(|f| (*f, path(f))).collect();
        let outputs: Vec<(&str, &Path)> = outputs.iter().map(|(f, p)| (*f, p.as_path())).collect();
        refuse_overwriting_inputs("--report", r, &outputs)?;
    }
    // Everything the runs would refuse is refused before the design is written.
    worker_threads(a.threads, None)?;
    put_design(&path("design.csv"), &d.csv(), &path("runs.csv"))?;
    say!(
        out,
        "{}: {} draws of {} x {} seed(s) = {} runs of {} ({}{})",
        path("design.csv").display(),
        d.draws.len(),
        a.posterior.display(),
        d.seeds,
        d.rows.len(),
        a.experiment,
        post.material,
        d.sized_by
            .map(|k| format!(", one {k} for every draw, by the median draw's particles"))
            .unwrap_or_default()
    );
    let plan = run_design(
        experiment.as_ref(),
        &path("design.csv"),
        &path("runs.csv"),
        &set,
        a,
        &settings,
    )?;
    let best_plan = match &best {
        None => None,
        Some(b) => {
            put_design(&path("best_design.csv"), &b.csv(), &path("best.csv"))?;
            Some(run_design(
                experiment.as_ref(),
                &path("best_design.csv"),
                &path("best.csv"),
                &set,
                a,
                &settings,
            )?)
        }
    };
    let read = |table: &str, plan: &Plan| -> anyhow::Result<RecordedRuns> {
        let names = experiment.responses();
        let runs = recorded(&path(table), plan, &names)?;
        Ok(RecordedRuns::new(experiment.as_ref(), runs))
    };
    let runs = read("runs.csv", &plan)?;
    let best_runs = match &best_plan {
        Some(p) => Some(read("best.csv", p)?),
        None => None,
    };
    // A best-fit run an event voided drops out of the best-fit value: the report says so.
    let best_events = best_runs.as_ref().map(RecordedRuns::event_counts);
    let events: Vec<EventRate> = experiment
        .events()
        .into_iter()
        .filter_map(|e| EventRate::of(e, &runs.event_by_draw(e, d.seeds)))
        .collect();
    let mut rows = Vec::new();
    let mut values_by_draw = Vec::new();
    for r in &responses {
        let per_draw = d.by_draw(&runs.values(r));
        let band = Band::of(&per_draw);
        let best_value = best_runs.as_ref().and_then(|b| {
            let v: Vec<f64> = b.values(r).into_iter().filter(|v| v.is_finite()).collect();
            (!v.is_empty()).then(|| mbgc::numeric::mean_sd(&v).0)
        });
        rows.push((r.clone(), band, best_value));
        values_by_draw.push(per_draw);
    }
    if let Some(dir) = &a.plot {
        for ((r, _, best), per_draw) in rows.iter().zip(&values_by_draw) {
            if per_draw.iter().flatten().all(|v| !v.is_finite()) {
                continue;
            }
            let model = through_model
                .as_ref()
                .and_then(|m| m.iter().find(|b| &b.response == r))
                .map(|b| b.predictions.as_slice());
            let file = dir.join(format!("{r}.svg"));
            mbgc::plot::propagation::robust_cdf(
                &file,
                &mbgc::plot::propagation::PropagationFigure {
                    response: r,
                    per_draw,
                    metamodel: model,
                    best_fit: *best,
                },
            )?;
            say!(out, "wrote {}", file.display());
        }
    }
    let text = report(
        a,
        &post,
        &d,
        &rows,
        &events,
        best_events.as_ref(),
        through_model.as_deref(),
    );
    if let Some(r) = &a.report {
        write_atomic(r, text.as_bytes())?;
        say!(out, "wrote {}", r.display());
    } else {
        say!(out, "{text}");
    }
    out.object(&serde_json::json!({
        "design": path("design.csv"),
        "table": path("runs.csv"),
        "draws": d.draws.len(),
        "seeds": d.seeds,
        "bands": rows.iter().map(|(r, b, best)| serde_json::json!({
            "response": r,
            "best_fit": best,
            "band": b.as_ref().map(|b| serde_json::json!({
                "draws": b.draws, "runs": b.runs, "missing": b.missing,
                "mean": b.mean, "sd": b.sd, "q05": b.q05, "q50": b.q50, "q95": b.q95,
                "cov": b.cov, "scatter_sd": b.scatter_sd, "parametric_sd": b.parametric_sd,
            })),
        })).collect::<Vec<_>>(),
        "best_fit_events": best_events.as_ref().map(|(runs, counts)| serde_json::json!({
            "runs": runs,
            "events": counts.iter().map(|(e, k)| serde_json::json!({"event": e, "count": k}))
                .collect::<Vec<_>>(),
        })),
        "events": events.iter().map(|e| serde_json::json!({
            "event": e.event, "count": e.count, "runs": e.runs, "draws": e.draws,
            "share": e.share, "q05": e.q05, "q95": e.q95, "effective_runs": e.effective_runs,
        })).collect::<Vec<_>>(),
        "metamodel": through_model.as_ref().map(|bands| bands.iter().map(|m| serde_json::json!({
            "response": m.response,
            "mean": m.without_error.mean,
            "sd": m.without_error.sd,
            "q05": m.without_error.q05,
            "q95": m.without_error.q95,
            "with_error": m.with_error.as_ref().map(|b| serde_json::json!({
                "mean": b.mean, "sd": b.sd, "q05": b.q05, "q95": b.q95,
            })),
            "error_source": m.error_source,
            "outside": m.outside.iter().map(|(k, what)| serde_json::json!({
                "draw": k, "what": what,
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>()),
    }))
}

/// The Markdown report: one line per quantity.
fn report(
    a: &PropagateArgs,
    post: &PosteriorFile,
    d: &DrawDesign,
    rows: &[(String, Option<Band>, Option<f64>)],
    events: &[EventRate],
    best_events: Option<&(usize, Vec<(&'static str, usize)>)>,
    model: Option<&[propagate::MetamodelBand]>,
) -> String {
    let mut s = format!(
        "# Propagation of {} to {}\n\n\
         Posterior `{}` (model `{}`, {} samples) -> {} draws by systematic resampling (seed {}) \
         -> {} DEM run(s) per draw{}.\n\n\
         | quantity | best fit | robust mean | sd | 5 % | 50 % | 95 % | COV | run scatter sd | \
         parametric sd | runs (missing) |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
        post.material,
        a.experiment,
        a.posterior.display(),
        post.model,
        post.rows.len(),
        d.draws.len(),
        a.seed,
        d.seeds,
        d.sized_by
            .map(|k| format!("; one `{k}` for every draw, sized to the median draw's particles"))
            .unwrap_or_default(),
    );
    for (r, b, best) in rows {
        let best = best.map_or("-".into(), num);
        match b {
            Some(b) => s.push_str(&format!(
                "| {r} | {best} | {} | {} | {} | {} | {} | {} | {} | {} | {} ({}) |\n",
                num(b.mean),
                num(b.sd),
                num(b.q05),
                num(b.q50),
                num(b.q95),
                num(b.cov),
                b.scatter_sd.map_or("-".into(), num),
                b.parametric_sd.map_or("-".into(), num),
                b.runs,
                b.missing
            )),
            None => s.push_str(&format!(
                "| {r} | {best} | no run has a value | | | | | | | | |\n"
            )),
        }
    }
    s.push_str(
        "\nThe band is over every run of every draw (the posterior's spread and the run scatter \
         together); with two or more seeds per draw the two are told apart. No model-error term \
         is added: the DEM is the model of these quantities, and the posterior's sigma is the \
         calibration metamodel's relative error.\n",
    );
    if let Some((runs, counts)) = best_events.filter(|(_, c)| !c.is_empty()) {
        s.push_str(&format!(
            "\nThe best-fit point's runs had events: {} of its {runs} finished run(s). A \
             quantity an event voids is the mean of the point's other runs, `-` where none is \
             left.\n",
            counts
                .iter()
                .map(|(e, k)| format!("{e} in {k}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if !events.is_empty() {
        s.push_str(
            "\n## Events\n\nRuns that finished without some of their measured quantities, and \
             why. They count as missing above in what their event voids. The share of the \
             finished runs estimates the posterior mean of the event's probability, as a lower \
             bound where the experiment cannot catch every case (a hopper's late arch in a run \
             that has no `arch_held`, recorded since 2026-11-30, or a stall after its last \
             flow bin); the share is the mean over the draws of their runs' share. The interval \
             is Jeffreys' (Beta(k + 1/2, n - k + 1/2)) with n the independent runs: all of them \
             with one run per draw, else the effective number (Korn and Graubard), since the \
             seeds of one draw share its parameters.\n\n\
             | event | runs with it | of finished runs | share | 90 % interval | effective runs \
             | draws with it |\n|---|---|---|---|---|---|---|\n",
        );
        for e in events {
            s.push_str(&format!(
                "| {} | {} | {} | {} | [{}, {}] | {} | {} |\n",
                e.event,
                e.count,
                e.runs,
                num(e.share),
                num(e.q05),
                num(e.q95),
                num(e.effective_runs),
                e.draws
            ));
        }
    }
    if let (Some(bands), Some(m)) = (model, &a.metamodel) {
        s.push_str(&format!(
            "\n## Through the metamodel `{}`\n\nThe same draws through its equations (one \
             prediction per draw), then with its own error added (normal, per draw), which is \
             what a single DEM run per draw should match.\n\n\
             | quantity | mean | sd | 5 % | 95 % | with error: sd | 5 % | 95 % | error |\n\
             |---|---|---|---|---|---|---|---|---|\n",
            m.display()
        ));
        for b in bands {
            let w = &b.without_error;
            let (esd, e05, e95) = b
                .with_error
                .as_ref()
                .map_or(("-".to_string(), "-".to_string(), "-".to_string()), |e| {
                    (num(e.sd), num(e.q05), num(e.q95))
                });
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {esd} | {e05} | {e95} | {} |\n",
                b.response,
                num(w.mean),
                num(w.sd),
                num(w.q05),
                num(w.q95),
                b.error_source
            ));
        }
        if let Some(out) = bands.first().map(|b| &b.outside).filter(|o| !o.is_empty()) {
            s.push_str(&format!(
                "\n{} of {} draws lie outside the metamodel's domain and are left out of its \
                 band (`--metamodel-outside skip`): {}. The band is of the others, so it is \
                 biased where the quantity differs there; the DEM band above holds them.\n",
                out.len(),
                bands[0].predictions.len(),
                out.iter()
                    .map(|(k, what)| format!("draw {k} ({what})"))
                    .collect::<Vec<_>>()
                    .join("; ")
            ));
        }
        let missing: Vec<&String> = rows
            .iter()
            .map(|(r, ..)| r)
            .filter(|r| !bands.iter().any(|b| &b.response == *r))
            .collect();
        if !missing.is_empty() {
            s.push_str(&format!(
                "\nThe metamodel predicts no {}.\n",
                missing
                    .iter()
                    .map(|r| r.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    }
    s
}
