//! `mbgc train`: sample (FSSF-f) -> simulate -> fit, every stage resumable (`mbgc::train`).

use std::path::PathBuf;

use clap::Args;
use mbgc::campaign::Shard;
use mbgc::dem::contact::ModelClass;
use mbgc::train::{train, TrainOutcome, TrainRequest};

#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Parameter space (its `[model] class` is the default model class).
    #[arg(long, value_name = "TOML")]
    pub space: PathBuf,
    #[arg(long, help = crate::simulate::experiment_help())]
    pub experiment: String,
    /// Training runs (an FSSF-f design; a larger n than an earlier train extends it).
    #[arg(long)]
    pub n: usize,
    /// Validation runs: a separate uniform random design, never trained on (0: none).
    #[arg(long, default_value_t = 0)]
    pub validation: usize,
    /// Directory that receives sampling/, training_data/ and models/.
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub out_dir: PathBuf,
    /// Name of the designs, tables and model [default: the experiment, e.g. shear_box].
    #[arg(long)]
    pub name: Option<String>,
    /// Seed of the training design and runs; the validation set uses seed + 1.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads: one DEM run each, then the fit's [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// Simulate only the rows with row % N == K - 1 of both tables, then stop (no fit): for job
    /// arrays; gather the shards with `mbgc campaign merge`, then train again to fit.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Size factor of the experiment's box (shear box: k) [default: the experiment's].
    #[arg(long, value_name = "K")]
    pub box_scale: Option<f64>,
    /// Effects of the contact law [default: the space's [model] class, else seed 004's].
    #[arg(long, value_name = "EFFECTS", value_parser = crate::simulate::parse_model_class)]
    pub model_class: Option<ModelClass>,
    /// Shear box: kinetic or response, as for `mbgc simulate` [default: kinetic]; recorded in
    /// the train's record, and an extension or a resume under another rule is refused.
    #[arg(long, value_name = "RULE", value_parser = crate::simulate::parse_rest_rule)]
    pub rest_rule: Option<mbgc::experiments::shear_box::RestRule>,
    /// Responses to fit, comma-separated [default: the experiment's measured ones].
    #[arg(long, value_delimiter = ',')]
    pub responses: Vec<String>,
    /// Fit in the raw inputs even where the experiment has dimensionless groups.
    #[arg(long)]
    pub no_similarity: bool,
    /// Add effects to a trained model: its name (trained into the same --out-dir) or its model
    /// file `<dir>/models/<name>.json` wherever it lies (e.g. the shipped
    /// models/shear_box.json; its tables and record are read under <dir>), with the same --seed.
    /// --space is its space plus the added effects' parameters, each with a range holding the
    /// value that switches it off. Its runs become the new design's first rows on that face and
    /// are copied into --out-dir, not rerun; only the new rows are simulated.
    #[arg(long, value_name = "NAME|MODEL.json", conflicts_with = "shard")]
    pub extends: Option<String>,
    /// With --extends: fit only what the new runs add to the extended model's equations (the
    /// saved equation is its equation plus the fitted correction) instead of refitting whole.
    #[arg(long, requires = "extends")]
    pub correction: bool,
    /// Fit only what the data add to this model's equations (the saved equation is its equation
    /// plus the fitted correction): like --correction, for a model other than the extended one,
    /// e.g. a cohesive train's runs corrected onto a base model widened since. Its inputs must be
    /// among this train's.
    #[arg(long, value_name = "MODEL.json", conflicts_with = "correction")]
    pub correct: Option<PathBuf>,
    /// Groups of the experiment's similarity the equations may not read, comma-separated (e.g.
    /// K_p,K_w); their range over the runs still bounds the model. With --correct and the
    /// cohesive shear box, the correction then reads the stiffness only through the cohesion's
    /// contact pull Ca = C K^(-2/3), the similarity measured in the DEM beyond the cohesive runs
    /// (docs/cohesion_stiffness.md).
    #[arg(long, value_delimiter = ',', value_name = "GROUPS")]
    pub unread_groups: Vec<String>,
    /// Support groups whose range over the runs should not bound the model, comma-separated
    /// (e.g. C_pp,C_pw): with --unread-groups K_p,K_w a cohesion's reach at a stiffness is its
    /// contact pull's range (Ca), which the DEM keeps at fixed Ca over K, not the C range the
    /// runs held at their own stiffness.
    #[arg(long, value_delimiter = ',', value_name = "GROUPS")]
    pub unbounded_groups: Vec<String>,
    /// Another campaign's tables, TRAIN.csv,VALIDATION.csv, whose runs inside this space are
    /// fitted and validated with this train's own (repeatable). A run equal to one already there
    /// is not counted twice; an input the table lacks must be the parameter of an effect its runs
    /// were made without, taken at its off value (ced = 0 for a base model's runs).
    #[arg(long, value_name = "TRAIN.csv,VALIDATION.csv", value_parser = parse_table_pair)]
    pub also_fit: Vec<(PathBuf, PathBuf)>,
    /// Stop after the simulate stage.
    #[arg(long)]
    pub no_fit: bool,
    /// Skip the simulate stage and fit on the rows the tables hold now (a campaign still running,
    /// e.g. in the background or as shards): a provisional model; it records how many rows it saw.
    #[arg(long, conflicts_with_all = ["no_fit", "shard"])]
    pub partial: bool,
    #[arg(long, default_value_t = 5000)]
    pub population: usize,
    /// Generations of the fit: more than `fit`'s gplearn-like 20, since a trained model is made
    /// once and used many times (300 took about 3 min on 2 cores for the shear box's 2 responses
    /// at 240 rows).
    #[arg(long, default_value_t = 300)]
    pub generations: usize,
    /// Penalty per node on the normalised error 1 - R^2 of the fit. Keep it below the noise's
    /// share of the variance: a node must pay for itself (shear box: noise about 0.1 % of the
    /// bulk density's variance, so 1e-4 rather than `fit`'s generic 1e-3).
    #[arg(long, default_value_t = 1e-4)]
    pub parsimony: f64,
    /// Longest tree (nodes) of the fit.
    #[arg(long, default_value_t = 64)]
    pub max_length: usize,
    /// Independent searches per response (seeds seed, seed + 1, ...) whose Pareto fronts are
    /// merged before the equation is picked: one search's error varies with its seed (shear
    /// angle at 297 rows: validation RMSE 1.68 to 1.75 deg over two seeds).
    #[arg(long, default_value_t = 4)]
    pub restarts: usize,
    /// How the equation is picked from the Pareto front: `cv` (the smallest 5-fold
    /// cross-validated error: the model is inverted at new points, so accuracy there decides) or
    /// `best` (PySR's knee, smaller equations).
    #[arg(long, default_value = "cv", value_parser = crate::fit::parse_selection)]
    pub select: mbgc::gp::select::Selection,
    /// Wall-clock limit per response of the fit, e.g. 10m (results then depend on machine speed).
    #[arg(long, value_parser = crate::fit::parse_duration)]
    pub time_limit: Option<f64>,
}

pub fn run(a: &TrainArgs) -> anyhow::Result<()> {
    let threads = match a.threads {
        Some(0) => anyhow::bail!("--threads: expected at least 1"),
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let config = mbgc::gp::Config {
        population: a.population,
        generations: a.generations,
        time_limit: a.time_limit,
        parsimony: a.parsimony,
        max_length: a.max_length,
        restarts: a.restarts,
        selection: a.select,
        ..mbgc::gp::Config::default()
    };
    // Before anything is sampled or simulated, also with --no-fit or --shard (a later train
    // fits with the same flags).
    crate::fit::gp_sizes(&config)?;
    let req = TrainRequest {
        validation: a.validation,
        out_dir: a.out_dir.clone(),
        name: a.name.clone(),
        seed: a.seed,
        threads,
        shard: a.shard.as_deref().map(Shard::parse).transpose()?,
        box_scale: a.box_scale,
        model_class: a.model_class,
        rest_rule: a.rest_rule,
        responses: a.responses.clone(),
        no_similarity: a.no_similarity,
        extends: a.extends.clone(),
        correction: a.correction,
        correct: a.correct.clone(),
        unread_groups: a.unread_groups.clone(),
        unbounded_groups: a.unbounded_groups.clone(),
        also_fit: a.also_fit.clone(),
        no_fit: a.no_fit,
        partial: a.partial,
        figures: true,
        config,
        ..TrainRequest::new(a.space.clone(), &a.experiment, a.n)
    };
    let observer = crate::train_progress::Printer::new(a.generations);
    let outcome = train(&req, &observer);
    observer.bar.finish_and_clear();
    match outcome? {
        TrainOutcome::ShardDone(k) => eprintln!(
            "shard {k} done; merge the shards' tables with `mbgc campaign merge`, then run train \
             again without --shard to fit"
        ),
        TrainOutcome::Simulated(_) => {}
        TrainOutcome::Fitted {
            model,
            paths,
            warnings,
            figures,
        } => {
            for w in &warnings {
                eprintln!("warning: {w}");
            }
            if model.data.skipped_rows + model.data.no_value_rows > 0 {
                eprintln!(
                    "{}: {} failed runs and {} without a value left out of the fit",
                    paths.table.display(),
                    model.data.skipped_rows,
                    model.data.no_value_rows
                );
            }
            for r in &model.responses {
                let v = r
                    .validation
                    .map(|m| format!("validation R2 {:.5} RMSE {:.4e}", m.r2, m.rmse))
                    .unwrap_or_else(|| "no validation set".into());
                eprintln!(
                    "{} = {}\n    size {}, train R2 {:.5} RMSE {:.4e}, {v}",
                    r.name,
                    r.grouped
                        .as_ref()
                        .filter(|g| g.equation != r.equation)
                        .map(|g| format!("{} with {} = {}", r.equation, g.fitted, g.equation))
                        .unwrap_or_else(|| r.equation.clone()),
                    r.size,
                    r.train.r2,
                    r.train.rmse
                );
            }
            // A model kept from an unchanged fit draws no figures (those of its fit remain).
            if figures.is_empty() {
                eprintln!("kept {}", paths.model.display());
            } else {
                eprintln!(
                    "wrote {} (+ .rs, .tex, {})",
                    paths.model.display(),
                    paths.figures.display()
                );
            }
        }
    }
    Ok(())
}

/// `TRAIN.csv,VALIDATION.csv` of `--also-fit`.
fn parse_table_pair(s: &str) -> Result<(PathBuf, PathBuf), String> {
    match s.split_once(',') {
        Some((t, v)) if !t.is_empty() && !v.is_empty() && !v.contains(',') => {
            Ok((PathBuf::from(t), PathBuf::from(v)))
        }
        _ => Err(format!(
            "expected TRAIN.csv,VALIDATION.csv (two paths, one comma), got `{s}`"
        )),
    }
}
