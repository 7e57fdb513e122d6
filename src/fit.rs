//! `mbgc fit`: one readable equation per response by genetic programming, saved as a model file.

use mbgc::outputs::refuse_overwriting_inputs;
use mbgc_output::say;
use mbgc_output::Output;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use mbgc::gp::select::Selection;
use mbgc::gp::Config;
use mbgc::metamodel::{fit, FitSettings, TrainingTable};
use mbgc::plot::fit_figures::fit_figures;
use mbgc::space::Space;

#[derive(Debug, Args)]
pub struct FitArgs {
    /// Training table (CSV; campaign tables: rows whose status is not `done` are skipped).
    #[arg(long)]
    pub data: PathBuf,
    /// Input columns, comma-separated.
    #[arg(long, value_delimiter = ',', required = true)]
    pub inputs: Vec<String>,
    /// Response columns, comma-separated: one equation each.
    #[arg(long, value_delimiter = ',', required = true)]
    pub targets: Vec<String>,
    /// Model file to write (JSON).
    #[arg(long)]
    pub out: PathBuf,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long, default_value_t = 5000)]
    pub population: usize,
    #[arg(long, default_value_t = 20)]
    pub generations: usize,
    /// Wall-clock limit per response, e.g. 90s, 10m, 1h (results then depend on machine speed).
    #[arg(long, value_parser = parse_duration)]
    pub time_limit: Option<f64>,
    /// Share of rows held out for the test metrics (seeded shuffle).
    #[arg(long, default_value_t = 0.1)]
    pub test_fraction: f64,
    /// Scale inputs to [0, 1] as this space file says (linear or log); stored in the model.
    #[arg(long)]
    pub space: Option<PathBuf>,
    /// Function set, comma-separated (add,sub,mul,div,neg,square,cube,sqrt,log,exp,tanh,sin,cos).
    #[arg(long, default_value = mbgc::gp::node::SEED004_FUNCTIONS)]
    pub functions: String,
    /// Penalty per node on the normalised error 1 - R^2.
    #[arg(long, default_value_t = 0.001)]
    pub parsimony: f64,
    #[arg(long, default_value_t = 4)]
    pub islands: usize,
    /// Independent searches (seeds seed, seed + 1, ...) whose Pareto fronts are merged before the
    /// equation is picked; the time limit applies to each.
    #[arg(long, default_value_t = 1)]
    pub restarts: usize,
    /// How the equation is picked from the Pareto front: `best` (PySR's knee: the steepest
    /// error drop per node, for discovering a law) or `cv` (the smallest 5-fold cross-validated
    /// error, constants re-tuned per fold: for accuracy at new points).
    #[arg(long, default_value = "best", value_parser = parse_selection)]
    pub select: Selection,
    #[arg(long, default_value_t = 20)]
    pub tournament: usize,
    /// Longest tree (nodes) a child may have.
    #[arg(long, default_value_t = 64)]
    pub max_length: usize,
    /// Fit y directly instead of a + b * tree.
    #[arg(long)]
    pub no_linear_scaling: bool,
    /// Directory for the parity plot and residual histogram of each response
    /// (default: next to the model, `<out stem>_figures/`).
    #[arg(long)]
    pub figures: Option<PathBuf>,
    /// Do not draw figures.
    #[arg(long)]
    pub no_figures: bool,
    /// Model class of the data when the table has no `model_class` column (campaign tables
    /// have one, and it must agree; so must a --space file's `[model]`); recorded in the model.
    /// Without any, the model records none.
    #[arg(long, value_name = "EFFECTS", value_parser = crate::simulate::parse_model_class)]
    pub model_class: Option<mbgc::dem::contact::ModelClass>,
    /// Fit in the dimensionless groups of this experiment's similarity (e.g. shear-box: K_p,
    /// K_w and the solid fraction); the equations are written back in the inputs. An
    /// experiment without one is refused.
    #[arg(long, value_name = "EXPERIMENT")]
    pub similarity: Option<String>,
    /// A separate table (same columns) never trained on: its metrics are saved per response.
    #[arg(long, value_name = "CSV")]
    pub validation: Option<PathBuf>,
    /// Fit only what the data add to this model's equations (for the responses it predicts):
    /// the saved equation is its equation plus the fitted correction. Its inputs must be among
    /// --inputs.
    #[arg(long, value_name = "MODEL.json")]
    pub correct: Option<PathBuf>,
    /// Standard output holds one JSON object (equations and metrics); text goes to standard
    /// error.
    #[arg(long)]
    pub json: bool,
}

/// Refuses a population, tournament, generation count, restart count, island count or tree
/// length outside the range the GP engine allows (`Config::sizes`), naming the flag: a zero too
/// many must not abort on an allocation or run for days.
pub fn gp_sizes(config: &Config) -> anyhow::Result<()> {
    match config.sizes().iter().find(|s| !s.holds()) {
        Some(size) => anyhow::bail!("{}", size.refusal(&size.flag())),
        None => Ok(()),
    }
}

/// `90`, `90s`, `10m`, `1.5h` -> seconds.
pub fn parse_duration(s: &str) -> Result<f64, String> {
    let s = s.trim();
    let (num, unit) = match s.chars().last() {
        Some('s') => (&s[..s.len() - 1], 1.0),
        Some('m') => (&s[..s.len() - 1], 60.0),
        Some('h') => (&s[..s.len() - 1], 3600.0),
        _ => (s, 1.0),
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v * unit),
        _ => Err(format!(
            "expected a positive duration like 90s, 10m or 1h, got \"{s}\""
        )),
    }
}

/// The similarity of experiment `name` under `class`; an experiment without one is refused.
pub fn similarity_of(
    name: &str,
    class: Option<mbgc::dem::contact::ModelClass>,
) -> anyhow::Result<mbgc::similarity::Similarity> {
    let settings = mbgc::campaign::ExperimentSettings {
        box_scale: None,
        model_class: class,
        ..Default::default()
    };
    let e = mbgc::campaign::experiment_by_name(name, &settings)?;
    e.similarity().ok_or_else(|| {
        anyhow::anyhow!(
            "--similarity {name}: {name} has no dimensionless groups{} (an effect parameter \
             of a dimension other than a stress, such as a spring in N/m, would need its own); \
             fit without it",
            class
                .map(|c| format!(" with the effects {c}"))
                .unwrap_or_default()
        )
    })
}

pub fn run(a: &FitArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    let mut inputs: Vec<(&str, &std::path::Path)> = vec![("--data", &a.data)];
    if let Some(v) = &a.validation {
        inputs.push(("--validation", v));
    }
    if let Some(s) = &a.space {
        inputs.push(("--space", s));
    }
    if let Some(m) = &a.correct {
        inputs.push(("--correct", m));
    }
    refuse_overwriting_inputs("--out", &a.out, &inputs)?;
    // Values the engine would silently bend: 0 generations ran one, an infinite parsimony
    // made every tree equal.
    if !(a.parsimony.is_finite() && a.parsimony >= 0.0) {
        anyhow::bail!(
            "--parsimony {}: expected a finite penalty >= 0 (default 0.001)",
            a.parsimony
        );
    }
    let config = Config {
        population: a.population,
        generations: a.generations,
        islands: a.islands,
        tournament: a.tournament,
        parsimony: a.parsimony,
        functions: a.functions.clone(),
        max_length: a.max_length,
        linear_scaling: !a.no_linear_scaling,
        time_limit: a.time_limit,
        seed: a.seed,
        restarts: a.restarts,
        selection: a.select,
        ..Config::default()
    };
    gp_sizes(&config)?;
    let figures = if a.no_figures {
        None
    } else {
        Some(a.figures.clone().unwrap_or_else(|| {
            let stem = a
                .out
                .file_stem()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_else(|| "model".into());
            a.out.with_file_name(format!("{stem}_figures"))
        }))
    };
    if let Some(dir) = &figures {
        mbgc::outputs::refuse_figures_over_inputs("--figures", dir, &inputs)?;
    }
    let mut settings = FitSettings::new(a.inputs.clone(), a.targets.clone())
        .test_fraction(a.test_fraction)
        .config(config);
    settings.space = a.space.as_deref().map(Space::from_file).transpose()?;
    settings.model_class = a.model_class;
    settings.similarity = match &a.similarity {
        Some(name) => {
            // The groups depend on the effects (cohesion adds C_pp and C_pw): the class given,
            // else the space's, else the campaign's that made the table.
            let class = match a
                .model_class
                .or_else(|| settings.space.as_ref().and_then(|s| s.model_class))
            {
                Some(c) => Some(c),
                None => match mbgc::campaign::Meta::read(&a.data)? {
                    // "-": an experiment without a contact law.
                    Some(m) if m.model_class != "-" => Some(
                        mbgc::dem::contact::ModelClass::parse(&m.model_class).map_err(|e| {
                            anyhow::anyhow!(
                                "{}: model_class: {e}",
                                mbgc::campaign::meta_path(&a.data).display()
                            )
                        })?,
                    ),
                    _ => None,
                },
            };
            let sim = similarity_of(name, class)?;
            // A group whose inputs the space all fixes is a constant, not a fitting variable.
            Some(match &settings.space {
                Some(space) => {
                    sim.without_constant_groups(|n| space.get(n).is_some_and(|p| p.is_fixed()))
                }
                None => sim,
            })
        }
        None => None,
    };
    // Checked before any file is read, as the settings would be checked inside the fit.
    settings.check()?;
    let table = TrainingTable::read_csv(&a.data, &a.inputs, &a.targets)?;
    settings.extends = a
        .correct
        .as_deref()
        .map(mbgc::metamodel::Metamodel::load)
        .transpose()?
        .map(Box::new);
    settings.validation = a
        .validation
        .as_deref()
        .map(|v| TrainingTable::read_csv(v, &a.inputs, &a.targets))
        .transpose()?;
    let bar = ProgressBar::new(a.generations as u64);
    bar.set_style(
        ProgressStyle::with_template("{prefix:>14} [{bar:30}] gen {pos}/{len} {msg}")
            .expect("static template")
            .progress_chars("=> "),
    );
    let mut current = String::new();
    let fitted = fit(&table, &settings, |target, p| {
        if current != target {
            current = target.to_string();
            bar.reset();
            bar.set_prefix(current.clone());
        }
        bar.set_position(p.generation as u64 + 1);
        bar.set_message(format!(
            "1-R2 {:.3e}, front {}, {:.2e} node-evals/s",
            p.best_nmse,
            p.front_size,
            p.node_evals as f64 / p.seconds.max(1e-9)
        ));
    })?;
    bar.finish_and_clear();
    for w in &fitted.warnings {
        eprintln!("warning: {w}");
    }
    if fitted.model.experiment.is_none() && fitted.model.model_class.is_some() {
        eprintln!(
            "warning: {} has no campaign record beside it ({}.meta.json): the model records no \
             experiment and no box scale, so `validate` cannot check that it reruns the \
             experiment the model was trained on",
            a.data.display(),
            a.data.display()
        );
    }
    let figure_paths = match &figures {
        Some(dir) => fit_figures(dir, &fitted)?,
        None => Vec::new(),
    };
    let model = fitted.model;
    model
        .save(&a.out)
        .with_context(|| format!("writing {}", a.out.display()))?;
    for r in &model.responses {
        let mut test = r
            .test
            .map(|t| format!("test R2 {:.5} RMSE {:.4e}", t.r2, t.rmse))
            .unwrap_or_else(|| "no test rows".into());
        if let Some(v) = r.validation {
            test += &format!(
                ", validation R2 {:.5} RMSE {:.4e} ({} rows)",
                v.r2, v.rmse, v.rows
            );
        }
        say!(
            out,
            "{} = {}\n    size {}, train R2 {:.5} RMSE {:.4e}, {test}; {} generations, {:.1} s, {:.2e} node-evals/s",
            r.name,
            r.equation,
            r.size,
            r.train.r2,
            r.train.rmse,
            r.generations,
            r.seconds,
            r.node_evals as f64 / r.seconds.max(1e-9)
        );
    }
    say!(
        out,
        "wrote {} ({})",
        a.out.display(),
        match &model.model_class {
            Some(c) => format!("model class {c}"),
            None => "no model class: the table has no model_class column; pass --model-class \
                     if it holds DEM runs"
                .into(),
        }
    );
    for f in &figure_paths {
        say!(out, "wrote {}", f.display());
    }
    out.object(&serde_json::json!({
        "out": a.out,
        "model_class": model.model_class,
        "figures": figure_paths,
        "responses": model.responses.iter().map(|r| serde_json::json!({
            "name": r.name,
            "equation": r.equation,
            "size": r.size,
            "train": r.train,
            "test": r.test,
            "validation": r.validation,
            "generations": r.generations,
            "seconds": r.seconds,
        })).collect::<Vec<_>>(),
    }))
}

/// `--select`: `best` or `cv`.
pub fn parse_selection(s: &str) -> Result<Selection, String> {
    Selection::from_flag(s)
}
