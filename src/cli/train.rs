//! `mbgc train`: sample (FSSF-f) -> simulate -> fit, every stage resumable (`crate::train`).

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use crate::campaign::{
    experiment_by_name, run_campaign, CampaignOptions, ExperimentSettings, Shard,
};
use crate::dem::contact::{ModelClass, Pair};
use crate::error::write_atomic;
use crate::export::{export, Format};
use crate::metamodel::{fit_table, FitOptions};
use crate::space::Space;
use crate::train::extend::{self, Extension};
use crate::train::{
    ensure_design, fit_inputs, plan, samplers, seeds, ExtendsRecord, TrainPaths, TrainRecord,
};

#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Parameter space (its `[model] class` is the default model class).
    #[arg(long, value_name = "TOML")]
    pub space: PathBuf,
    #[arg(long, help = crate::cli::simulate::experiment_help())]
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
    /// Worker threads, one run each [default: all cores].
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
    #[arg(long, value_name = "EFFECTS", value_parser = crate::cli::simulate::parse_model_class)]
    pub model_class: Option<ModelClass>,
    /// Responses to fit, comma-separated [default: the experiment's measured ones].
    #[arg(long, value_delimiter = ',')]
    pub responses: Vec<String>,
    /// Fit in the raw inputs even where the experiment has dimensionless groups.
    #[arg(long)]
    pub no_similarity: bool,
    /// Add effects to the model trained under this name (same --out-dir and --seed): --space is
    /// its space plus the added effects' parameters, each with a range holding the value that
    /// switches it off. Its runs become the new design's first rows on that face and are copied,
    /// not rerun; only the new rows are simulated. --name must differ.
    #[arg(long, value_name = "NAME", conflicts_with = "shard")]
    pub extends: Option<String>,
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
    #[arg(long, default_value = "cv", value_parser = crate::cli::fit::parse_selection)]
    pub select: crate::gp::select::Selection,
    /// Wall-clock limit per response of the fit, e.g. 10m (results then depend on machine speed).
    #[arg(long, value_parser = crate::cli::fit::parse_duration)]
    pub time_limit: Option<f64>,
}

pub fn run(a: &TrainArgs) -> anyhow::Result<()> {
    if a.n < 5 {
        anyhow::bail!("--n {}: expected at least 5 training runs", a.n);
    }
    let space = Space::from_file(&a.space)?;
    let class = a.model_class.or(space.model_class);
    let settings = ExperimentSettings {
        box_scale: a.box_scale,
        model_class: class,
        ..Default::default()
    };
    let experiment = experiment_by_name(&a.experiment, &settings)?;
    let name = a
        .name
        .clone()
        .unwrap_or_else(|| a.experiment.replace('-', "_"));
    if name.is_empty() || name.contains(['/', '\\']) {
        anyhow::bail!("--name {name:?}: expected a plain file name");
    }
    // "." is written as nothing, so that paths read as in a hand-run `mbgc simulate`.
    let dir = if a.out_dir == Path::new(".") {
        PathBuf::new()
    } else {
        a.out_dir.clone()
    };
    let paths = TrainPaths::new(&dir, &name);
    let shard = a.shard.as_deref().map(Shard::parse).transpose()?;
    let threads = match a.threads {
        Some(0) => anyhow::bail!("--threads: expected at least 1"),
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let similarity = if a.no_similarity {
        None
    } else {
        experiment.similarity()
    };
    let responses: Vec<String> = if a.responses.is_empty() {
        experiment
            .calibration_responses()
            .iter()
            .map(|s| s.to_string())
            .collect()
    } else {
        let known = experiment.responses();
        for r in &a.responses {
            if !known.contains(&r.as_str()) {
                anyhow::bail!(
                    "--responses {r}: not a response of {} (it has: {})",
                    a.experiment,
                    known.join(", ")
                );
            }
        }
        a.responses.clone()
    };

    // Stage 0 of an extension: the old designs projected onto the new space's effect-off face.
    let (seed, vseed) = seeds(a.seed);
    let extension = match &a.extends {
        None => None,
        Some(from) => Some(prepare_extension(
            a,
            &dir,
            from,
            &name,
            &space,
            class,
            experiment.pairs(),
        )?),
    };

    // Stage 1: the designs.
    let (fssf, random) = samplers();
    let (before, after) = ensure_design(&paths.design, &space, fssf.as_ref(), a.n, seed)?;
    eprintln!(
        "[1/3 sample] {}: {after} rows (FSSF-f, seed {seed}; {})",
        paths.design.display(),
        if before == after {
            "unchanged".to_string()
        } else {
            format!("{} new", after - before)
        }
    );
    let mut tables = vec![(&paths.design, &paths.table, seed, "training")];
    if a.validation > 0 {
        let (b, v) = ensure_design(
            &paths.validation_design,
            &space,
            random.as_ref(),
            a.validation,
            vseed,
        )?;
        eprintln!(
            "[1/3 sample] {}: {v} rows (random, seed {vseed}; {})",
            paths.validation_design.display(),
            if b == v {
                "unchanged".to_string()
            } else {
                format!("{} new", v - b)
            }
        );
        tables.push((
            &paths.validation_design,
            &paths.validation_table,
            vseed,
            "validation",
        ));
    }

    // Stage 2: the runs, resumed from the tables.
    if let Some(parent) = paths.table.parent() {
        if !parent.as_os_str().is_empty() {
            std::fs::create_dir_all(parent).with_context(|| parent.display().to_string())?;
        }
    }
    let mut incomplete = Vec::new();
    for (design, table, s, what) in &tables {
        if a.partial {
            if !table.exists() {
                anyhow::bail!("--partial: {} holds no runs yet", table.display());
            }
            // Over the whole design: a table written by shards records its own shard only.
            let st = crate::campaign::status(table, None)?;
            let rows = crate::sampling::design::Design::read(design, Some(&space))?.len();
            let missing = rows.saturating_sub(st.done + st.failed);
            eprintln!(
                "[2/3 simulate] {} ({what}): skipped (--partial), {missing} rows not yet simulated",
                table.display()
            );
            if missing > 0 {
                incomplete.push(format!("{}: {missing} rows missing", table.display()));
            }
            continue;
        }
        let p = plan(experiment.as_ref(), design, *s, &settings, shard)?;
        if let Some((from, ext)) = &extension {
            let old = TrainPaths::new(&dir, from);
            let old_table = if *what == "training" {
                old.table
            } else {
                old.validation_table
            };
            if !table.exists() && old_table.exists() {
                let n = extend::copy_table(&old_table, &p, table, ext)?;
                eprintln!(
                    "[2/3 simulate] {} ({what}): copied {n} runs of {} (without {})",
                    table.display(),
                    old_table.display(),
                    ext.added.join(", ")
                );
            }
        }
        let r = run_campaign(
            experiment.as_ref(),
            &p,
            &CampaignOptions {
                progress: true,
                ..CampaignOptions::new((*table).clone(), threads)
            },
        )?;
        eprintln!(
            "[2/3 simulate] {} ({what}): {} already done, ran {} ({} done, {} failed) in {:.0} s",
            table.display(),
            r.skipped,
            r.done + r.failed,
            r.done,
            r.failed,
            r.elapsed_s
        );
        if shard.is_none() {
            let st = crate::campaign::status(table, Some(design))?;
            if st.remaining.unwrap_or(0) > 0 {
                incomplete.push(format!(
                    "{}: {} rows missing",
                    table.display(),
                    st.remaining.unwrap_or(0)
                ));
            }
        }
    }
    let class_label = experiment.class().map(|c| c.to_string());
    let record = TrainRecord {
        mbgc_version: env!("CARGO_PKG_VERSION").into(),
        space: a.space.display().to_string(),
        experiment: a.experiment.clone(),
        model_class: class_label,
        box_scale: a
            .box_scale
            .or_else(|| (a.experiment == "shear-box").then_some(10.0)),
        n: a.n,
        validation: a.validation,
        design_method: "fssf-f".into(),
        validation_method: "random".into(),
        seed,
        validation_seed: vseed,
        responses: responses.clone(),
        inputs: fit_inputs(
            &space,
            &similarity
                .as_ref()
                .map(|s| s.absorbed())
                .unwrap_or_default(),
        ),
        groups: similarity
            .iter()
            .flat_map(|s| &s.groups)
            .map(|g| format!("{} = {}", g.name, g.monomial.text()))
            .collect(),
        extends: extension.as_ref().map(|(from, e)| ExtendsRecord {
            from: from.clone(),
            added: e.added.clone(),
            off_face: e.off_face.clone(),
        }),
    };
    write_atomic(
        &paths.record,
        serde_json::to_string_pretty(&record)?.as_bytes(),
    )?;
    if let Some(k) = shard {
        eprintln!(
            "shard {k} done; merge the shards' tables with `mbgc campaign merge`, then run train \
             again without --shard to fit"
        );
        return Ok(());
    }
    if a.no_fit {
        return Ok(());
    }
    if !incomplete.is_empty() && a.partial {
        eprintln!(
            "[3/3 fit] provisional: {}; train again without --partial to finish them",
            incomplete.join("; ")
        );
    } else if !incomplete.is_empty() {
        anyhow::bail!(
            "not fitting: {}; run train again to finish them",
            incomplete.join("; ")
        );
    }

    // Stage 3: the fit, checked on the validation table.
    let config = crate::gp::Config {
        population: a.population,
        generations: a.generations,
        time_limit: a.time_limit,
        seed: a.seed,
        parsimony: a.parsimony,
        max_length: a.max_length,
        restarts: a.restarts,
        selection: a.select,
        ..crate::gp::Config::default()
    };
    let opts = FitOptions {
        data: paths.table.clone(),
        inputs: record.inputs.clone(),
        targets: responses.clone(),
        test_fraction: 0.0,
        space: Some(a.space.clone()),
        config,
        plots: Some(paths.figures.clone()),
        model_class: class,
        similarity,
        validation: (a.validation > 0).then(|| paths.validation_table.clone()),
    };
    let bar = ProgressBar::new(a.generations as u64);
    bar.set_style(
        ProgressStyle::with_template("[3/3 fit] {prefix:>14} [{bar:30}] gen {pos}/{len} {msg}")
            .expect("static template")
            .progress_chars("=> "),
    );
    let mut current = String::new();
    let report = fit_table(&opts, |target, p| {
        if current != target {
            current = target.to_string();
            bar.reset();
            bar.set_prefix(current.clone());
        }
        bar.set_position(p.generation as u64 + 1);
        bar.set_message(format!("1-R2 {:.3e}", p.best_nmse));
    })?;
    bar.finish_and_clear();
    let model = report.model;
    if let Some(parent) = paths.model.parent() {
        if !parent.as_os_str().is_empty() {
            std::fs::create_dir_all(parent).with_context(|| parent.display().to_string())?;
        }
    }
    model.save(&paths.model)?;
    for (format, ext) in [(Format::Rust, "rs"), (Format::Latex, "tex")] {
        write_atomic(
            &paths.model.with_extension(ext),
            export(&model, format).as_bytes(),
        )?;
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
    eprintln!(
        "wrote {} (+ .rs, .tex, {})",
        paths.model.display(),
        paths.figures.display()
    );
    Ok(())
}

/// Checks an extension against the old train's record and, on the first call, writes the new
/// designs' first rows: the old designs on the added effects' off face.
fn prepare_extension(
    a: &TrainArgs,
    dir: &Path,
    from: &str,
    name: &str,
    space: &Space,
    class: Option<ModelClass>,
    pairs: &[Pair],
) -> anyhow::Result<(String, Extension)> {
    if from == name {
        anyhow::bail!("--extends {from}: --name must differ from the model it extends");
    }
    let old = TrainPaths::new(dir, from);
    let text = std::fs::read_to_string(&old.record).with_context(|| {
        format!(
            "--extends {from}: reading {} (written by `mbgc train --name {from}`)",
            old.record.display()
        )
    })?;
    let record: TrainRecord = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a train record", old.record.display()))?;
    if record.experiment != a.experiment {
        anyhow::bail!(
            "--extends {from}: {from} was trained on {}, not {}",
            record.experiment,
            a.experiment
        );
    }
    if record.seed != a.seed {
        anyhow::bail!(
            "--seed {}: {from} was trained with --seed {}; an extension keeps it, so that the \
             copied runs are the rows the new campaign would run",
            a.seed,
            record.seed
        );
    }
    let box_scale = a
        .box_scale
        .or_else(|| (a.experiment == "shear-box").then_some(10.0));
    if record.box_scale != box_scale {
        anyhow::bail!(
            "--box-scale: {from} was run with {:?}, this train asks for {box_scale:?}",
            record.box_scale
        );
    }
    let old_space = Space::from_file(Path::new(&record.space))
        .with_context(|| format!("the space of {from} (from {})", old.record.display()))?;
    let old_class = match &record.model_class {
        Some(c) => ModelClass::parse(c)?,
        None => anyhow::bail!("--extends {from}: its record names no model class"),
    };
    let new_class = class.unwrap_or_default();
    let ext = extend::check(&old_space, &old_class, space, &new_class, pairs)?;
    let paths = TrainPaths::new(dir, name);
    for (old_design, new_design, n, what) in [
        (&old.design, &paths.design, a.n, "--n"),
        (
            &old.validation_design,
            &paths.validation_design,
            a.validation,
            "--validation",
        ),
    ] {
        if new_design.exists() || !old_design.exists() {
            continue;
        }
        let d = extend::project_design(old_design, &old_space, space, &ext)?;
        if n <= d.len() {
            anyhow::bail!(
                "{what} {n}: {from} has {} such runs already; an extension adds runs (pass more \
                 than {})",
                d.len(),
                d.len()
            );
        }
        if let Some(parent) = new_design.parent() {
            std::fs::create_dir_all(parent).with_context(|| parent.display().to_string())?;
        }
        d.write(new_design)?;
        eprintln!(
            "[0/3 extend] {}: the {} rows of {} with {}",
            new_design.display(),
            d.len(),
            old_design.display(),
            ext.off_face
                .iter()
                .map(|(n, v)| format!("{n} = {v}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok((from.to_string(), ext))
}
