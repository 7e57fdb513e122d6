//! The `train` pipeline as one library call: designs, campaigns and the fit under an output
//! directory, each stage resumed from the files the last call left. What happens is told to a
//! [`TrainObserver`] (the command line prints it and draws progress bars; a program may log it
//! or ignore it).

use std::path::{Path, PathBuf};

use super::extend::{self, Extension};
use super::stages::{
    ensure_design, fit_inputs, plan, samplers, seeds, space_parameters, ExtendsRecord, TrainPaths,
    TrainRecord,
};
use crate::campaign::{
    experiment_by_name, run_campaign, CampaignOptions, ExperimentSettings, ObserverHandle, Shard,
};
use crate::error::{read_to_string, write_atomic, Error, Result};
use crate::experiments::shear_box::RestRule;
use crate::export::{export, Format};
use crate::metamodel::{fit, FitSettings, Metamodel, TrainingTable};
use crate::space::Space;
use mbgc_dem::contact::{ModelClass, Pair};
use mbgc_sr as gp;

/// The stages of a train, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrainStage {
    /// Projecting the extended model's designs onto the new space (`extends` only).
    Extend,
    /// Creating or extending the training and validation designs.
    Sample,
    /// Running (or resuming) the DEM campaigns.
    Simulate,
    /// Fitting the metamodel.
    Fit,
}

impl std::fmt::Display for TrainStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            TrainStage::Extend => "0/3 extend",
            TrainStage::Sample => "1/3 sample",
            TrainStage::Simulate => "2/3 simulate",
            TrainStage::Fit => "3/3 fit",
        })
    }
}

/// Told what a train does. Every method has a default that does nothing.
pub trait TrainObserver {
    /// A stage's news, one line (a design extended, a campaign resumed, a provisional fit).
    fn note(&self, _stage: TrainStage, _text: &str) {}
    /// The observer of the campaign about to run into `table` (a progress bar), if any.
    fn campaign(&self, _table: &Path) -> Option<ObserverHandle> {
        None
    }
    /// A generation of the fit of `response` finished.
    fn fit_progress(&self, _response: &str, _progress: &gp::Progress) {}
}

/// An observer that ignores everything.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl TrainObserver for Silent {}

/// What to train: the space, the experiment, the sizes of the designs, where the files go and
/// how the equations are fitted. Build with [`TrainRequest::new`] and set the public fields.
#[derive(Debug, Clone)]
pub struct TrainRequest {
    /// The parameter-space file (its `[model] class` is the default model class); the train
    /// record names it, so an extension can read it again.
    pub space: PathBuf,
    /// The experiment's name, as `mbgc simulate --experiment` takes it.
    pub experiment: String,
    /// Training runs (an FSSF-f design; a larger `n` than an earlier train extends it).
    pub n: usize,
    /// Validation runs: a separate uniform random design, never trained on (0: none).
    pub validation: usize,
    /// The directory that receives `sampling/`, `training_data/` and `models/`.
    pub out_dir: PathBuf,
    /// Name of the designs, tables and model (default: the experiment's, `-` as `_`).
    pub name: Option<String>,
    /// Seed of the training design and runs; the validation set uses `seed + 1`.
    pub seed: u64,
    /// Worker threads: one run each while simulating, then the fit's.
    pub threads: usize,
    /// Simulate only this shard of both tables, then stop (no fit).
    pub shard: Option<Shard>,
    /// Size factor of the experiment's box (default: the experiment's).
    pub box_scale: Option<f64>,
    /// Effects of the contact law (default: the space's class, else seed 004's).
    pub model_class: Option<ModelClass>,
    /// The shear box's rest rule (default: kinetic); other experiments refuse it.
    pub rest_rule: Option<RestRule>,
    /// Responses to fit (default: the experiment's calibration responses).
    pub responses: Vec<String>,
    /// Fit in the raw inputs even where the experiment has dimensionless groups.
    pub no_similarity: bool,
    /// Add effects to a trained model: its name (trained into the same directory) or its model
    /// file (`<root>/models/<name>.json`, its tables and record under `<root>`: the shipped model,
    /// or any train's), with the same seed.
    pub extends: Option<String>,
    /// With `extends`: fit only what the new runs add to the extended model's equations.
    pub correction: bool,
    /// Fit only what the data add to this model's equations (any model whose inputs are among
    /// this train's, e.g. a base model widened since `extends` was trained): the saved equation
    /// is its equation plus the fitted correction.
    pub correct: Option<PathBuf>,
    /// Groups of the experiment's similarity the fitted equations may not read; their range
    /// over the rows still bounds the model (`Similarity::with_unread`).
    pub unread_groups: Vec<String>,
    /// Support groups whose range over the rows does not bound the model
    /// (`Similarity::without_support`).
    pub unbounded_groups: Vec<String>,
    /// Tables of an earlier train over a wider space, as (training, validation): their runs
    /// that lie inside this space's ranges are fitted (and validated) with this train's own, so
    /// that a train near a material reuses the runs a wider one made there.
    pub also_fit: Vec<(PathBuf, PathBuf)>,
    /// Stop after the simulate stage.
    pub no_fit: bool,
    /// Skip the simulate stage and fit the rows the tables hold now (a provisional model).
    pub partial: bool,
    /// Draw the parity plots and residual histograms into `models/<name>_figures/`.
    pub figures: bool,
    /// The genetic-programming settings of the fit (its seed is set to `seed`).
    pub config: gp::Config,
}

impl TrainRequest {
    /// Train `n` runs of `experiment` over the space in `space`, into the current directory,
    /// seed 1, one thread, no validation set, figures drawn, the default GP settings.
    pub fn new(space: PathBuf, experiment: &str, n: usize) -> TrainRequest {
        TrainRequest {
            space,
            experiment: experiment.to_string(),
            n,
            validation: 0,
            out_dir: PathBuf::from("."),
            name: None,
            seed: 1,
            threads: 1,
            shard: None,
            box_scale: None,
            model_class: None,
            rest_rule: None,
            responses: Vec::new(),
            no_similarity: false,
            extends: None,
            correction: false,
            correct: None,
            unread_groups: Vec::new(),
            unbounded_groups: Vec::new(),
            also_fit: Vec::new(),
            no_fit: false,
            partial: false,
            figures: true,
            config: gp::Config::default(),
        }
    }
}

/// How a train ended.
#[derive(Debug, Clone)]
pub enum TrainOutcome {
    /// The model was fitted and saved (with its `.rs` and `.tex` exports).
    Fitted {
        /// The saved model.
        model: Box<Metamodel>,
        /// Where everything was written.
        paths: TrainPaths,
        /// The figures drawn.
        figures: Vec<PathBuf>,
        /// What the fit warned of.
        warnings: Vec<String>,
    },
    /// A shard's runs are done; the shards are to be merged and the train run again.
    ShardDone(Shard),
    /// The runs are done and no fit was asked for.
    Simulated(TrainPaths),
}

/// Most runs of a train's design, and of its validation set: each is a DEM simulation (minutes),
/// so more would run for years, and the design alone is sampled in memory.
pub const MAX_RUNS: usize = 100_000;

/// Runs (or resumes) a train: sample, simulate, fit.
pub fn train(req: &TrainRequest, observer: &dyn TrainObserver) -> Result<TrainOutcome> {
    if !(5..=MAX_RUNS).contains(&req.n) {
        return Err(Error::invalid(format!(
            "--n {}: expected 5 to {MAX_RUNS} training runs",
            req.n
        )));
    }
    if req.validation > MAX_RUNS {
        return Err(Error::invalid(format!(
            "--validation {}: expected 0 to {MAX_RUNS} validation runs",
            req.validation
        )));
    }
    if req.threads == 0 {
        return Err(Error::invalid("--threads: expected at least 1"));
    }
    if req.partial && (req.no_fit || req.shard.is_some()) {
        return Err(Error::invalid(
            "--partial fits the rows there are: it cannot be combined with --no-fit or --shard",
        ));
    }
    if req.correction && req.extends.is_none() {
        return Err(Error::invalid(
            "--correction corrects the model given with --extends; none was",
        ));
    }
    if req.correction && req.correct.is_some() {
        return Err(Error::invalid(
            "--correction corrects the extended model and --correct another one: give one",
        ));
    }
    for (flag, names) in [
        ("--unread-groups", &req.unread_groups),
        ("--unbounded-groups", &req.unbounded_groups),
    ] {
        if !names.is_empty() && req.no_similarity {
            return Err(Error::invalid(format!(
                "{flag} names groups of the similarity, which --no-similarity switches off"
            )));
        }
    }
    let fit_flags = req.correct.is_some()
        || !req.also_fit.is_empty()
        || !req.unread_groups.is_empty()
        || !req.unbounded_groups.is_empty();
    if fit_flags && (req.no_fit || req.shard.is_some()) {
        return Err(Error::invalid(
            "--correct, --also-fit, --unread-groups and --unbounded-groups set the fit, and a \
             train with --no-fit or --shard does not fit: give them to the train that fits",
        ));
    }
    if let Some(g) = req
        .unbounded_groups
        .iter()
        .find(|g| req.unread_groups.contains(g))
    {
        return Err(Error::invalid(format!(
            "--unbounded-groups {g}: it is left unread (--unread-groups), so its range is the \
             only thing that still holds its inputs to the runs; it cannot also be unbounded"
        )));
    }
    if req.validation == 0 && !req.also_fit.is_empty() {
        return Err(Error::invalid(
            "--also-fit: its validation table would be read for nothing, since --validation is 0",
        ));
    }
    if req.extends.is_some() && req.shard.is_some() {
        return Err(Error::invalid(
            "--extends cannot be combined with --shard: extend first, then shard",
        ));
    }
    // The fit's settings are checked before any run: a train must not simulate for hours and
    // then refuse to fit.
    if !req.no_fit && req.shard.is_none() {
        req.config
            .check()
            .map_err(|e| Error::invalid(format!("GP settings: {e}")))?;
        let need = 2 * gp::select::FOLDS;
        if req.config.selection == gp::select::Selection::CrossValidation && req.n < need {
            return Err(Error::invalid(format!(
                "--n {}: the equation is picked by {}-fold cross-validation (--select cv), \
                 which needs at least {need} training runs; pass --n {need} or more, or \
                 --select best",
                req.n,
                gp::select::FOLDS
            )));
        }
    }
    let space = Space::from_file(&req.space)?;
    let class = req.model_class.or(space.model_class);
    let settings = ExperimentSettings {
        box_scale: req.box_scale,
        model_class: class,
        rest_rule: req.rest_rule,
        ..Default::default()
    };
    let experiment = experiment_by_name(&req.experiment, &settings)?;
    // Files the fit reads are checked before any run, like its settings.
    let corrected = req
        .correct
        .as_ref()
        .map(|m| -> Result<Metamodel> {
            let model = Metamodel::load(m)?;
            check_corrected(&model, m, req, &space, class.as_ref())?;
            Ok(model)
        })
        .transpose()?;
    for (t, v) in &req.also_fit {
        for f in [t, v] {
            also_fit_header(f)?;
        }
    }
    let name = req
        .name
        .clone()
        .unwrap_or_else(|| req.experiment.replace('-', "_"));
    if name.is_empty() || name.contains(['/', '\\']) {
        return Err(Error::invalid(format!(
            "--name {name:?}: expected a plain file name"
        )));
    }
    // "." is written as nothing, so that paths read as in a hand-run `mbgc simulate`.
    let dir = if req.out_dir == Path::new(".") {
        PathBuf::new()
    } else {
        req.out_dir.clone()
    };
    let paths = TrainPaths::new(&dir, &name);
    let similarity = if req.no_similarity {
        None
    } else {
        experiment
            .similarity()
            .map(|s| s.without_constant_groups(|n| space.get(n).is_some_and(|p| p.is_fixed())))
            .map(|s| s.with_unread(&req.unread_groups))
            .transpose()
            .map_err(|e| Error::invalid(format!("--unread-groups: {e}")))?
            .map(|s| s.without_support(&req.unbounded_groups))
            .transpose()
            .map_err(|e| Error::invalid(format!("--unbounded-groups: {e}")))?
    };
    if (!req.unread_groups.is_empty() || !req.unbounded_groups.is_empty()) && similarity.is_none() {
        return Err(Error::invalid(format!(
            "--unread-groups, --unbounded-groups: {} has no similarity, so there are no groups",
            req.experiment
        )));
    }
    let responses: Vec<String> = if req.responses.is_empty() {
        experiment
            .calibration_responses()
            .iter()
            .map(|s| s.to_string())
            .collect()
    } else {
        let known = experiment.responses();
        for r in &req.responses {
            if !known.contains(&r.as_str()) {
                return Err(Error::invalid(format!(
                    "--responses {r}: not a response of {} (it has: {})",
                    req.experiment,
                    known.join(", ")
                )));
            }
        }
        req.responses.clone()
    };

    // Stage 0 of an extension: the old designs projected onto the new space's effect-off face.
    let (seed, vseed) = seeds(req.seed);
    let extension = match &req.extends {
        None => None,
        Some(from) => Some(prepare_extension(
            req,
            &dir,
            from,
            &name,
            &space,
            class,
            experiment.pairs(),
            observer,
        )?),
    };

    // Stage 1: the designs, made for this space only.
    refuse_another_space(&paths, &space, &req.space, req.rest_rule)?;
    let (fssf, random) = samplers();
    let changed = |before: usize, after: usize| {
        if before == after {
            "unchanged".to_string()
        } else {
            format!("{} new", after - before)
        }
    };
    let (before, after) = ensure_design(&paths.design, &space, fssf.as_ref(), req.n, seed)?;
    observer.note(
        TrainStage::Sample,
        &format!(
            "{}: {after} rows (FSSF-f, seed {seed}; {})",
            paths.design.display(),
            changed(before, after)
        ),
    );
    let mut tables = vec![(&paths.design, &paths.table, seed, "training")];
    if req.validation > 0 {
        let (b, v) = ensure_design(
            &paths.validation_design,
            &space,
            random.as_ref(),
            req.validation,
            vseed,
        )?;
        observer.note(
            TrainStage::Sample,
            &format!(
                "{}: {v} rows (random, seed {vseed}; {})",
                paths.validation_design.display(),
                changed(b, v)
            ),
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
            std::fs::create_dir_all(parent).map_err(|e| Error::io(parent, e))?;
        }
    }
    let mut incomplete = Vec::new();
    for (design, table, s, what) in &tables {
        if req.partial {
            if !table.exists() {
                return Err(Error::invalid(format!(
                    "--partial: {} holds no runs yet",
                    table.display()
                )));
            }
            // Over the whole design (a table written by shards records its own shard only),
            // the rows outside the space's constraints excepted: they are never run.
            let p = plan(experiment.as_ref(), design, *s, &settings, None)?;
            let outside = outside_rows(&space, &p);
            let present = table_run_ids(table)?;
            let missing = p
                .rows
                .iter()
                .filter(|r| !outside.contains(&r.run_id) && !present.contains(&r.run_id))
                .count();
            observer.note(
                TrainStage::Simulate,
                &format!(
                    "{} ({what}): skipped (--partial), {missing} rows not yet simulated",
                    table.display()
                ),
            );
            if missing > 0 {
                incomplete.push(format!("{}: {missing} rows missing", table.display()));
            }
            continue;
        }
        let p = plan(experiment.as_ref(), design, *s, &settings, req.shard)?;
        if let Some((old, ext)) = &extension {
            let old_table = if *what == "training" {
                old.table.clone()
            } else {
                old.validation_table.clone()
            };
            if !table.exists() && old_table.exists() {
                let n = extend::copy_table(&old_table, &p, table, ext)?;
                observer.note(
                    TrainStage::Simulate,
                    &format!(
                        "{} ({what}): copied {n} runs of {} ({})",
                        table.display(),
                        old_table.display(),
                        ext.old_runs()
                    ),
                );
            }
        }
        // Rows outside the space's constraints are not run (nor fitted): the model is valid
        // inside them only, and a calibration is kept there.
        let outside = outside_rows(&space, &p);
        let inside: Option<std::collections::HashSet<String>> = (!outside.is_empty()).then(|| {
            p.selected()
                .filter(|r| !outside.contains(&r.run_id))
                .map(|r| r.run_id.clone())
                .collect()
        });
        if !outside.is_empty() {
            observer.note(
                TrainStage::Simulate,
                &format!(
                    "{} ({what}): {} of {} design rows lie outside the space's constraints ({}): \
                     not run",
                    table.display(),
                    outside.len(),
                    p.rows.len(),
                    constraint_texts(&space)
                ),
            );
        }
        let r = run_campaign(
            experiment.as_ref(),
            &p,
            &CampaignOptions {
                observer: observer.campaign(table),
                only: inside,
                ..CampaignOptions::new((*table).clone(), req.threads)
            },
        )?;
        observer.note(
            TrainStage::Simulate,
            &format!(
                "{} ({what}): {} already done, ran {} ({} done, {} failed) in {:.0} s",
                table.display(),
                r.skipped,
                r.done + r.failed,
                r.done,
                r.failed,
                r.elapsed_s
            ),
        );
        if let Some(note) = r.added_columns_note(table) {
            observer.note(TrainStage::Simulate, &note);
        }
        if req.shard.is_none() {
            let present = table_run_ids(table)?;
            let missing = p
                .selected()
                .filter(|r| !outside.contains(&r.run_id) && !present.contains(&r.run_id))
                .count();
            if missing > 0 {
                incomplete.push(format!("{}: {missing} rows missing", table.display()));
            }
        }
    }
    let record = TrainRecord {
        mbgc_version: env!("CARGO_PKG_VERSION").into(),
        space: req.space.display().to_string(),
        experiment: req.experiment.clone(),
        model_class: experiment.class().map(|c| c.to_string()),
        box_scale: req
            .box_scale
            .or_else(|| (req.experiment == "shear-box").then_some(10.0)),
        rest_rule: rest_label(req.rest_rule),
        n: req.n,
        validation: req.validation,
        design_method: "fssf-f".into(),
        validation_method: "random".into(),
        seed,
        validation_seed: vseed,
        responses: responses.clone(),
        inputs: fit_inputs(
            &space,
            &similarity
                .as_ref()
                .map(|s| s.needed_inputs())
                .unwrap_or_default(),
        ),
        groups: similarity
            .iter()
            .flat_map(|s| &s.groups)
            .map(|g| format!("{} = {}", g.name, g.monomial.text()))
            .collect(),
        extends: extension.as_ref().map(|(_, e)| ExtendsRecord {
            from: req.extends.clone().unwrap_or_default(),
            added: e.added.clone(),
            off_face: e.off_face.clone(),
            widened: e.widened.clone(),
            correction: req.correction,
        }),
        space_parameters: Some(space_parameters(&space)),
        correct: req.correct.as_ref().map(|m| m.display().to_string()),
        unread_groups: req.unread_groups.clone(),
        unbounded_groups: req.unbounded_groups.clone(),
        also_fit: req
            .also_fit
            .iter()
            .map(|(t, v)| (t.display().to_string(), v.display().to_string()))
            .collect(),
    };
    let record_json = serde_json::to_string_pretty(&record)
        .map_err(|e| Error::invalid(format!("{}: {e}", paths.record.display())))?;
    write_atomic(&paths.record, record_json.as_bytes())?;
    if let Some(k) = req.shard {
        return Ok(TrainOutcome::ShardDone(k));
    }
    if req.no_fit {
        return Ok(TrainOutcome::Simulated(paths));
    }
    if !incomplete.is_empty() && req.partial {
        observer.note(
            TrainStage::Fit,
            &format!(
                "provisional: {}; train again without --partial to finish them",
                incomplete.join("; ")
            ),
        );
    } else if !incomplete.is_empty() {
        return Err(Error::invalid(format!(
            "not fitting: {}; run train again to finish them",
            incomplete.join("; ")
        )));
    }

    // Stage 3: the fit, checked on the validation table.
    let inside = {
        let space = space.clone();
        move |row: &[(String, f64)]| {
            row.iter()
                .all(|(n, v)| space.get(n).is_none_or(|p| p.contains(*v)))
        }
    };
    let mut fit_settings = FitSettings::new(record.inputs.clone(), responses.clone())
        .test_fraction(0.0)
        .config(gp::Config {
            seed: req.seed,
            ..req.config.clone()
        })
        .space(space.clone());
    fit_settings.model_class = class;
    fit_settings.similarity = similarity;
    if req.correction {
        let (old, _) = extension.as_ref().ok_or_else(|| {
            Error::invalid("--correction corrects the model given with --extends; none was")
        })?;
        fit_settings.extends = Some(Box::new(Metamodel::load(&old.model)?));
    }
    if let Some(m) = corrected {
        fit_settings.extends = Some(Box::new(m));
    }
    fit_settings.check()?;
    // Taken before the tables are read for the fit: a row a running campaign appends in between
    // then makes the stamp older than the fit, which only fits again.
    let stamp = FitStamp::new(req, &record, &paths, &extension)?;
    let mut table = TrainingTable::read_csv(&paths.table, &record.inputs, &responses)?;
    let mut validation = (req.validation > 0)
        .then(|| TrainingTable::read_csv(&paths.validation_table, &record.inputs, &responses))
        .transpose()?;
    let also = AlsoFit {
        inputs: &record.inputs,
        responses: &responses,
        class: class.as_ref(),
        pairs: experiment.pairs(),
        space: &space,
    };
    for (t, v) in &req.also_fit {
        let before = table.rows();
        table = table.with_rows_of(&also.read(t)?, &inside)?;
        let added = table.rows() - before;
        if let Some(val) = validation.take() {
            validation = Some(val.with_rows_of(&also.read(v)?, &inside)?);
        }
        if added == 0 {
            return Err(Error::input(
                t.display(),
                "rows",
                "a run inside this space that this train's tables do not hold already (--also-fit \
                 would add nothing)",
            ));
        }
    }
    if !req.also_fit.is_empty() {
        observer.note(
            TrainStage::Fit,
            &format!(
                "fitting {} rows ({}){}",
                table.columns.first().map_or(0, |c| c.1.len()),
                table.source,
                validation.as_ref().map_or(String::new(), |v| format!(
                    "; validating on {} rows ({})",
                    v.columns.first().map_or(0, |c| c.1.len()),
                    v.source
                ))
            ),
        );
    }
    // A correction adds to the corrected model's value: where that model does not hold (a wall
    // friction below its runs', where a material without cohesion slides off the walls and has
    // no angle) there is nothing to add to, so such rows are left out and the new model's
    // ranges are those of the rows it keeps.
    if let Some(base) = fit_settings.extends.as_deref() {
        let base_name = req
            .correct
            .as_ref()
            .map(|m| m.display().to_string())
            .or_else(|| {
                extension
                    .as_ref()
                    .map(|(o, _)| o.model.display().to_string())
            })
            .unwrap_or_default();
        table = inside_corrected(table, base, &base_name, "training", observer)?;
        validation = validation
            .map(|v| inside_corrected(v, base, &base_name, "validation", observer))
            .transpose()?;
        if validation.as_ref().is_some_and(|v| v.rows() == 0) {
            return Err(Error::invalid(format!(
                "every validation run lies outside where {base_name} holds, so the corrected fit \
                 would have nothing to be validated on; widen that model or the validation design"
            )));
        }
    }
    fit_settings.validation = validation;
    // A resumed train whose tables, record and settings are those of the saved fit would only
    // fit the same equations again (a GP search of up to hours): the saved model is kept.
    // A response the experiment records but this fit does not read leaves the stamp alone: a
    // table widened with one since the fit (`with_added_responses`) still holds its rows.
    let unread: Vec<&str> = experiment
        .responses()
        .into_iter()
        .filter(|r| !responses.iter().any(|f| f == r))
        .collect();
    if paths.model.exists()
        && std::fs::read_to_string(&paths.fit_stamp)
            .is_ok_and(|s| stamp.matches(&s, &unread).unwrap_or(false))
    {
        let model = Metamodel::load(&paths.model)?;
        observer.note(
            TrainStage::Fit,
            &format!(
                "{}: fitted on these rows with these settings already; kept (remove {} to fit \
                 again)",
                paths.model.display(),
                paths.fit_stamp.display()
            ),
        );
        return Ok(TrainOutcome::Fitted {
            model: Box::new(model),
            paths,
            figures: Vec::new(),
            warnings: Vec::new(),
        });
    }
    // The GP's population is spread over rayon's threads; its own pool keeps --threads a bound
    // on the fit as on the runs. Each individual draws from its own seeded stream, so the
    // equations do not depend on the thread count.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(req.threads)
        .build()
        .map_err(|e| Error::invalid(format!("--threads {}: {e}", req.threads)))?;
    // The observer need not be Sync: the fit runs on a thread of its own and sends its progress
    // here, where the observer hears it.
    let (tx, rx) = std::sync::mpsc::channel::<(String, gp::Progress)>();
    let fitted = std::thread::scope(|scope| {
        let fitting = scope.spawn(|| {
            pool.install(move || {
                fit(&table, &fit_settings, move |target, p| {
                    // A closed receiver only means nobody listens any more.
                    let _ = tx.send((target.to_string(), p.clone()));
                })
            })
        });
        for (target, p) in rx {
            observer.fit_progress(&target, &p);
        }
        fitting
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    })?;
    let figures = if req.figures {
        crate::plot::fit_figures::fit_figures(&paths.figures, &fitted)?
    } else {
        Vec::new()
    };
    let model = fitted.model;
    if let Some(parent) = paths.model.parent() {
        if !parent.as_os_str().is_empty() {
            std::fs::create_dir_all(parent).map_err(|e| Error::io(parent, e))?;
        }
    }
    model.save(&paths.model)?;
    for (format, ext) in [(Format::Rust, "rs"), (Format::Latex, "tex")] {
        write_atomic(
            &paths.model.with_extension(ext),
            export(&model, format).as_bytes(),
        )?;
    }
    // Last: a crash before it leaves no stamp, and the next train fits again.
    write_atomic(&paths.fit_stamp, stamp.text().as_bytes())?;
    Ok(TrainOutcome::Fitted {
        model: Box::new(model),
        paths,
        figures,
        warnings: fitted.warnings,
    })
}

/// Run ids of the plan's rows that violate a constraint of the space.
fn outside_rows(space: &Space, plan: &crate::campaign::Plan) -> std::collections::HashSet<String> {
    if space.constraints.is_empty() {
        return Default::default();
    }
    plan.rows
        .iter()
        .filter(|r| {
            let x: Vec<f64> = space
                .names()
                .iter()
                .map(|n| r.params.get(n).unwrap_or(f64::NAN))
                .collect();
            space.violated(&x).is_some()
        })
        .map(|r| r.run_id.clone())
        .collect()
}

/// The constraints as written, for messages.
fn constraint_texts(space: &Space) -> String {
    space
        .constraints
        .iter()
        .map(|c| c.text.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Run ids of the lines a campaign table holds (done or failed).
fn table_run_ids(table: &Path) -> Result<std::collections::HashSet<String>> {
    Ok(crate::campaign::read_table(table)?
        .records
        .into_iter()
        .map(|(_, r)| r[0].to_string())
        .collect())
}

/// The fingerprint of a fit: the version, the record (space, inputs, groups, responses, class,
/// extension), the GP settings and seed, the flags that change the fit, and the bytes of every
/// file it reads. The stamp file holds the hash and, for each campaign table, its header then.
struct FitStamp {
    /// The hash of everything but the files.
    settings: crate::numeric::Fnv1a,
    /// Each file the fit reads, with its bytes.
    files: Vec<(PathBuf, Vec<u8>)>,
}

impl FitStamp {
    fn new(
        req: &TrainRequest,
        record: &TrainRecord,
        paths: &TrainPaths,
        extension: &Option<(TrainPaths, Extension)>,
    ) -> Result<FitStamp> {
        let mut h = crate::numeric::Fnv1a::default();
        h.str(env!("CARGO_PKG_VERSION"));
        // The record without the space's path as typed (`./space.toml` is `space.toml`); the
        // space file's bytes stand for it, constraints and scales included.
        let mut record = record.clone();
        record.space = String::new();
        // Likewise the other files as typed: their bytes are hashed below. The record holds the
        // groups left unread or unbounded (absent when none, so older stamps still match).
        record.correct = record.correct.map(|_| String::new());
        for pair in &mut record.also_fit {
            *pair = (String::new(), String::new());
        }
        h.str(&serde_json::to_string(&record).map_err(|e| Error::invalid(e.to_string()))?);
        h.str(&format!(
            "{:?} seed {} correction {} no_similarity {}",
            req.config, req.seed, req.correction, req.no_similarity
        ));
        let mut files = vec![req.space.clone(), paths.table.clone()];
        if req.validation > 0 {
            files.push(paths.validation_table.clone());
        }
        for (t, v) in &req.also_fit {
            files.push(t.clone());
            if req.validation > 0 {
                files.push(v.clone());
            }
        }
        if let (true, Some((old, _))) = (req.correction, extension) {
            files.push(old.model.clone());
        }
        if let Some(m) = &req.correct {
            files.push(m.clone());
        }
        let files = files
            .into_iter()
            .map(|f| {
                let bytes = std::fs::read(&f).map_err(|e| Error::io(&f, e))?;
                Ok((f, bytes))
            })
            .collect::<Result<_>>()?;
        Ok(FitStamp { settings: h, files })
    }

    /// The hash over the files' bytes, each transformed by `view` (its index and bytes).
    fn hash(&self, view: impl Fn(usize, &[u8]) -> Result<Vec<u8>>) -> Result<String> {
        let mut h = crate::numeric::Fnv1a(self.settings.0);
        // Contents only: another spelling of the same directory fits the same.
        for (k, (_, bytes)) in self.files.iter().enumerate() {
            let bytes = view(k, bytes)?;
            h.u64(bytes.len() as u64);
            h.bytes(&bytes);
        }
        Ok(format!("{:016x}", h.0))
    }

    /// The stamp file's text: the hash, then `header <k> <columns>` for each campaign table
    /// among the files.
    fn text(&self) -> String {
        let mut out = self.hash(|_, b| Ok(b.to_vec())).unwrap_or_default();
        for (k, (_, bytes)) in self.files.iter().enumerate() {
            if let Some(h) = campaign_header(bytes) {
                let line = crate::campaign::table::csv_line(&h).unwrap_or_default();
                out.push_str(&format!(
                    "\nheader {k} {}",
                    String::from_utf8_lossy(&line).trim_end()
                ));
            }
        }
        out.push('\n');
        out
    }

    /// Whether the stamp file's `text` was written for these files, where a table may since
    /// have gained the columns of `unread` responses, which the fit does not read. A stamp file
    /// of one line (written before the headers were kept) matches the bytes as they are.
    fn matches(&self, text: &str, unread: &[&str]) -> Result<bool> {
        let mut lines = text.lines();
        let hash = lines.next().unwrap_or("").trim();
        let mut then: Vec<Option<Vec<String>>> = vec![None; self.files.len()];
        for l in lines {
            let Some(rest) = l.strip_prefix("header ") else {
                continue;
            };
            let Some((k, cols)) = rest.split_once(' ') else {
                return Ok(false);
            };
            match (k.parse::<usize>(), campaign_header(cols.as_bytes())) {
                (Ok(k), Some(h)) if k < then.len() => then[k] = Some(h),
                _ => return Ok(false),
            }
        }
        let projected = self.hash(|k, bytes| {
            let (Some(then), Some(now)) = (&then[k], campaign_header(bytes)) else {
                return Ok(bytes.to_vec());
            };
            let gained: Vec<&str> = now
                .iter()
                .filter(|c| !then.contains(c))
                .map(String::as_str)
                .collect();
            if gained.iter().all(|c| unread.contains(c)) {
                without_columns(&self.files[k].0, bytes, &gained)
            } else {
                Ok(bytes.to_vec())
            }
        })?;
        Ok(projected == hash)
    }
}

/// The header of a campaign table's CSV `bytes` (`None` for another file: a space, a model).
fn campaign_header(bytes: &[u8]) -> Option<Vec<String>> {
    let first = bytes.split(|&b| b == b'\n').next()?;
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(first);
    let h = r.byte_records().next()?.ok()?;
    let h: Vec<String> = h
        .iter()
        .map(|c| String::from_utf8_lossy(c).into_owned())
        .collect();
    (h.iter().any(|c| c == "run_id") && h.iter().any(|c| c == "status")).then_some(h)
}

/// The CSV `bytes` of the file `path` without the columns named `drop`, each line written as
/// the campaign writes its table's lines, so that a table widened with such columns gives back
/// the bytes it had before. A file with none of them is returned as it is.
fn without_columns(path: &Path, bytes: &[u8], drop: &[&str]) -> Result<Vec<u8>> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(bytes);
    let mut records = r.byte_records();
    let header = match records.next() {
        Some(Ok(h)) => h,
        _ => return Ok(bytes.to_vec()),
    };
    let keep: Vec<bool> = header
        .iter()
        .map(|c| !drop.iter().any(|d| d.as_bytes() == c))
        .collect();
    if keep.iter().all(|&k| k) {
        return Ok(bytes.to_vec());
    }
    let line = |rec: &csv::ByteRecord| {
        crate::campaign::table::csv_line(
            rec.iter()
                .zip(keep.iter().chain(std::iter::repeat(&true)))
                .filter_map(|(f, &k)| k.then_some(f)),
        )
    };
    let mut out = line(&header)?;
    for rec in records {
        let rec = rec.map_err(|e| Error::input(path.display(), "CSV", e.to_string()))?;
        out.extend(line(&rec)?);
    }
    Ok(out)
}

/// The header of an `--also-fit` table, read before any run.
fn also_fit_header(path: &Path) -> Result<Vec<String>> {
    csv::Reader::from_path(path)
        .and_then(|mut r| r.headers().map(|h| h.iter().map(str::to_string).collect()))
        .map_err(|e| Error::input(path.display(), "header", format!("a CSV header ({e})")))
}

/// How `--also-fit` reads another campaign's table into this train's columns.
struct AlsoFit<'a> {
    inputs: &'a [String],
    responses: &'a [String],
    class: Option<&'a ModelClass>,
    pairs: &'a [Pair],
    space: &'a Space,
}

impl AlsoFit<'_> {
    /// The table's columns `inputs` and `responses`. An input it lacks must be the parameter of
    /// an effect its runs were made without, taken at the value that switches the effect off (a
    /// base model's runs are a cohesive model's at ced = 0, as `--extends` copies them); its
    /// rows' model class must then be this train's without those effects, and otherwise this
    /// train's. A parameter this space fixes must hold that value in every row the table has a
    /// column for: a run of another material is refused, not fitted.
    fn read(&self, path: &Path) -> Result<TrainingTable> {
        let header = also_fit_header(path)?;
        let params = self
            .class
            .map(|c| c.parameters(self.pairs))
            .unwrap_or_default();
        let mut fills = Vec::new();
        let mut off_effects: Vec<&str> = Vec::new();
        for name in self.inputs.iter().filter(|n| !header.contains(n)) {
            let Some((off, effect)) = params
                .iter()
                .find(|(n, _, _)| *n == name.as_str())
                .and_then(|(_, spec, e)| spec.off.map(|o| (o, e.name)))
            else {
                return Err(Error::input(
                    path.display(),
                    format!("column {name}"),
                    format!(
                        "the input {name}; only the parameter of an effect the table's runs were \
                         made without may be missing (it is then taken at its off value)"
                    ),
                ));
            };
            fills.push((name.clone(), off));
            if !off_effects.contains(&effect) {
                off_effects.push(effect);
            }
        }
        let fixed: Vec<(String, f64)> = self
            .space
            .parameters
            .iter()
            .filter_map(|p| p.fixed.map(|v| (p.name.clone(), v)))
            .filter(|(n, _)| header.contains(n) && !self.inputs.contains(n))
            .collect();
        let present: Vec<String> = self
            .inputs
            .iter()
            .filter(|n| header.contains(n))
            .chain(fixed.iter().map(|(n, _)| n))
            .cloned()
            .collect();
        let mut t = TrainingTable::read_csv(path, &present, self.responses)?;
        for (name, want) in &fixed {
            let col = t.column(name)?;
            if let Some(r) = col.iter().position(|v| v != want) {
                return Err(Error::input(
                    path.display(),
                    format!("column {name}, usable row {}", r + 1),
                    format!(
                        "{want:?}, the value this space fixes {name} at; found {:?} (a run of \
                         another material)",
                        col[r]
                    ),
                ));
            }
        }
        if let (Some(class), Some(labels)) = (self.class, &t.model_class) {
            let want: Vec<&str> = class
                .effects()
                .iter()
                .map(|e| e.name)
                .filter(|e| !off_effects.contains(e))
                .collect();
            for (r, label) in labels.iter().enumerate() {
                let theirs = ModelClass::parse(&label.replace('+', ","))?;
                let got: Vec<&str> = theirs.effects().iter().map(|e| e.name).collect();
                if got != want {
                    return Err(Error::input(
                        path.display(),
                        format!("column model_class, usable row {}", r + 1),
                        format!(
                            "{} (this train's class{}), found {label}",
                            want.join("+"),
                            if off_effects.is_empty() {
                                String::new()
                            } else {
                                format!(" without {}", off_effects.join(", "))
                            }
                        ),
                    ));
                }
            }
        }
        let rows = t.rows();
        let mut read = std::mem::take(&mut t.columns).into_iter();
        let mut columns = Vec::with_capacity(self.inputs.len() + self.responses.len());
        for name in self.inputs {
            match fills.iter().find(|(n, _)| n == name) {
                Some((_, off)) => columns.push((name.clone(), vec![*off; rows])),
                None => columns.extend(read.next()),
            }
        }
        // The fixed columns were read after the inputs; the responses follow them.
        let rest: Vec<(String, Vec<f64>)> = read.collect();
        columns.extend(rest.into_iter().skip(fixed.len()));
        t.columns = columns;
        if !fills.is_empty() {
            t.model_class = None;
            t.source = format!(
                "{} (at {})",
                t.source,
                fills
                    .iter()
                    .map(|(n, v)| format!("{n} = {v}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        Ok(t)
    }
}

/// Refuses a `--correct` model made for another experiment, box scale, class or material than
/// this train: its equation would be corrected as if it described these runs.
fn check_corrected(
    model: &Metamodel,
    path: &Path,
    req: &TrainRequest,
    space: &Space,
    class: Option<&ModelClass>,
) -> Result<()> {
    let file = path.display();
    if let Some(e) = model.experiment.as_deref().filter(|e| *e != req.experiment) {
        return Err(Error::input(
            &file,
            "experiment",
            format!("{}, this train's experiment; found {e}", req.experiment),
        ));
    }
    let scale = req
        .box_scale
        .or_else(|| (req.experiment == "shear-box").then_some(10.0));
    if let (Some(m), Some(t)) = (model.box_scale, scale) {
        if m != t {
            return Err(Error::input(
                &file,
                "box_scale",
                format!("{t}, this train's box scale; found {m}"),
            ));
        }
    }
    if let (Some(label), Some(class)) = (&model.model_class, class) {
        let theirs = ModelClass::parse(&label.replace('+', ","))?;
        let ours: Vec<&str> = class.effects().iter().map(|e| e.name).collect();
        if let Some(e) = theirs.effects().iter().find(|e| !ours.contains(&e.name)) {
            return Err(Error::input(
                &file,
                "model_class",
                format!(
                    "a class whose effects this train's {} holds; found {label}, with {}",
                    class.label(),
                    e.name
                ),
            ));
        }
    }
    for c in &model.constants {
        match space.get(&c.name) {
            Some(p) if p.fixed == Some(c.value) => {}
            Some(p) => {
                return Err(Error::input(
                    &file,
                    format!("constants.{}", c.name),
                    format!(
                        "the value this train's space gives {} ({}); found {:?}: the model \
                         describes another material",
                        c.name,
                        match p.fixed {
                            Some(v) => format!("fixed at {v:?}"),
                            None => format!("varied over [{:?}, {:?}]", p.min, p.max),
                        },
                        c.value
                    ),
                ));
            }
            None => {}
        }
    }
    Ok(())
}

/// The rows of `table` inside where the corrected model `base` holds (its inputs' and groups'
/// ranges, its rigid limit's reach included); the rows left out are counted in a note naming
/// the bounds that left them out.
fn inside_corrected(
    table: TrainingTable,
    base: &Metamodel,
    base_name: &str,
    what: &str,
    observer: &dyn TrainObserver,
) -> Result<TrainingTable> {
    let columns: Vec<&[f64]> = base
        .inputs
        .iter()
        .map(|i| table.column(&i.name))
        .collect::<Result<_>>()?;
    let mut bounds: Vec<(String, usize)> = Vec::new();
    let keep: Vec<bool> = (0..table.rows())
        .map(|r| {
            let x: Vec<f64> = columns.iter().map(|c| c[r]).collect();
            let out = base.outside_domain(&x);
            for (name, _, _) in &out {
                match bounds.iter_mut().find(|(n, _)| n == name) {
                    Some((_, k)) => *k += 1,
                    None => bounds.push((name.to_string(), 1)),
                }
            }
            out.is_empty()
        })
        .collect();
    let left_out = keep.iter().filter(|k| !**k).count();
    if left_out == 0 {
        return Ok(table);
    }
    observer.note(
        TrainStage::Fit,
        &format!(
            "{left_out} of the {} {what} rows ({}) lie outside where {base_name} holds ({}): \
             left out, since a correction adds to that model's value and it has none there",
            table.rows(),
            table.source,
            bounds
                .iter()
                .map(|(n, k)| format!("{n} on {k}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    );
    Ok(table.retain_rows(&keep))
}

/// The rest rule as a train record holds it: absent for the kinetic rule (every record from
/// before the rule could be chosen), the rule's label otherwise.
fn rest_label(rule: Option<RestRule>) -> Option<String> {
    rule.filter(|r| *r != RestRule::Kinetic).map(|r| r.label())
}

/// A train resumed under a name whose designs were made for another space (a widened range, a
/// parameter fixed or freed) is refused: its rows would be taken as a sample of the new space.
fn refuse_another_space(
    paths: &TrainPaths,
    space: &Space,
    file: &Path,
    rule: Option<RestRule>,
) -> Result<()> {
    if !paths.record.exists() {
        return Ok(());
    }
    let record = TrainRecord::load(&paths.record)?;
    if record.rest_rule != rest_label(rule) {
        let label = |r: &Option<String>| r.clone().unwrap_or_else(|| "kinetic".into());
        return Err(Error::invalid(format!(
            "{}: --rest-rule: the runs under this name were made with the {} rule, this train \
             asks for the {} rule; give another --name or --out-dir",
            paths.record.display(),
            label(&record.rest_rule),
            label(&rest_label(rule))
        )));
    }
    let Some(before) = record.space_parameters else {
        return Ok(());
    };
    let now = space_parameters(space);
    if before != now {
        let changed: Vec<String> = now
            .iter()
            .filter(|p| !before.contains(p))
            .chain(before.iter().filter(|p| !now.contains(p)))
            .cloned()
            .collect();
        return Err(Error::invalid(format!(
            "{}: the designs under this name were made for another space (differing: {}); a \
             train extends its designs only in the space they fill: give another --name or \
             --out-dir",
            file.display(),
            changed.join("; ")
        )));
    }
    Ok(())
}

/// Checks an extension against the old train's record and, on the first call, writes the new
/// designs' first rows: the old designs on the added effects' off face.
#[allow(clippy::too_many_arguments)]
fn prepare_extension(
    req: &TrainRequest,
    dir: &Path,
    from: &str,
    name: &str,
    space: &Space,
    class: Option<ModelClass>,
    pairs: &[Pair],
    observer: &dyn TrainObserver,
) -> Result<(TrainPaths, Extension)> {
    let (old_root, old_name) = extended(dir, from)?;
    // The same directory however it is spelled ("", ".", an absolute path): extending a model
    // into itself would overwrite its own designs and tables.
    let resolve = |d: &Path| {
        let d = if d.as_os_str().is_empty() {
            Path::new(".")
        } else {
            d
        };
        std::fs::canonicalize(d).unwrap_or_else(|_| d.to_path_buf())
    };
    if old_name == name && resolve(&old_root) == resolve(dir) {
        return Err(Error::invalid(format!(
            "--extends {from}: --name must differ from the model it extends"
        )));
    }
    let old = TrainPaths::new(&old_root, &old_name);
    let text = read_to_string(&old.record).map_err(|e| {
        Error::invalid(format!(
            "--extends {from}: reading {} (written by `mbgc train --name {from}`): {e}",
            old.record.display()
        ))
    })?;
    let record = TrainRecord::from_json(&text, &old.record)?;
    if record.experiment != req.experiment {
        return Err(Error::invalid(format!(
            "--extends {from}: {from} was trained on {}, not {}",
            record.experiment, req.experiment
        )));
    }
    if record.seed != req.seed {
        return Err(Error::invalid(format!(
            "--seed {}: {from} was trained with --seed {}; an extension keeps it, so that the \
             copied runs are the rows the new campaign would run",
            req.seed, record.seed
        )));
    }
    let box_scale = req
        .box_scale
        .or_else(|| (req.experiment == "shear-box").then_some(10.0));
    if record.box_scale != box_scale {
        return Err(Error::invalid(format!(
            "--box-scale: {from} was run with {:?}, this train asks for {box_scale:?}",
            record.box_scale
        )));
    }
    let rule = rest_label(req.rest_rule);
    if record.rest_rule != rule {
        let label = |r: &Option<String>| r.clone().unwrap_or_else(|| "kinetic".into());
        return Err(Error::invalid(format!(
            "--rest-rule: {from} was run with the {} rule, this train asks for the {} rule; the \
             copied runs would not be the rows the new campaign runs",
            label(&record.rest_rule),
            label(&rule)
        )));
    }
    // A record names its space as `train --space` was given, relative to where train ran: the
    // extended model's root when it lies elsewhere (the shipped model's
    // `examples/space_shear_box.toml` is relative to the repository).
    let space_path = if old_root == dir || Path::new(&record.space).is_absolute() {
        PathBuf::from(&record.space)
    } else {
        old_root.join(&record.space)
    };
    let old_space = Space::from_file(&space_path).map_err(|e| {
        Error::invalid(format!(
            "the space of {from} (from {}): {e}",
            old.record.display()
        ))
    })?;
    let old_class = match &record.model_class {
        Some(c) => ModelClass::parse(c)?,
        None => {
            return Err(Error::invalid(format!(
                "--extends {from}: its record names no model class"
            )))
        }
    };
    let new_class = class.unwrap_or_default();
    let ext = extend::check(&old_space, &old_class, space, &new_class, pairs)?;
    let paths = TrainPaths::new(dir, name);
    // Every count is checked before any design is written: a refused extension leaves nothing
    // behind that a corrected one would take for its own.
    let mut projected = Vec::new();
    for (old_design, new_design, n, what) in [
        (&old.design, &paths.design, req.n, "--n"),
        (
            &old.validation_design,
            &paths.validation_design,
            req.validation,
            "--validation",
        ),
    ] {
        if new_design.exists() || !old_design.exists() {
            continue;
        }
        let d = extend::project_design(old_design, &old_space, space, &ext)?;
        // The validation runs may stay as they were (an independent design checks the new
        // region); the training runs must grow, or nothing is extended, unless the fit takes
        // something else new: another model to correct or another campaign's runs.
        let refit = req.correct.is_some() || !req.also_fit.is_empty();
        if n < d.len() || (what == "--n" && n == d.len() && !refit) {
            return Err(Error::invalid(format!(
                "{what} {n}: {from} has {} such runs already; an extension keeps them and {} \
                 (pass {} {}, or refit them onto another model with --correct or beside \
                 other runs with --also-fit)",
                d.len(),
                if what == "--n" {
                    "adds runs"
                } else {
                    "may add runs"
                },
                if what == "--n" {
                    "more than"
                } else {
                    "at least"
                },
                d.len()
            )));
        }
        projected.push((old_design, new_design, d));
    }
    for (old_design, new_design, d) in projected {
        if let Some(parent) = new_design.parent() {
            std::fs::create_dir_all(parent).map_err(|e| Error::io(parent, e))?;
        }
        d.write(new_design)?;
        observer.note(
            TrainStage::Extend,
            &format!(
                "{}: the {} rows of {}, {}",
                new_design.display(),
                d.len(),
                old_design.display(),
                ext.old_runs()
            ),
        );
    }
    Ok((old, ext))
}

/// Where the model `--extends` names lies: `(root, name)` with its record, designs and tables
/// under `root` as `train --out-dir root --name name` wrote them. A bare name is a train in this
/// train's directory `dir`; a path to a `.json` model file is `<root>/models/<name>.json`.
fn extended(dir: &Path, from: &str) -> Result<(PathBuf, String)> {
    let path = Path::new(from);
    if path.extension().is_none_or(|e| e != "json") {
        return Ok((dir.to_path_buf(), from.to_string()));
    }
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    let models = path.parent().unwrap_or(Path::new(""));
    if name.is_empty() || models.file_name().is_none_or(|n| n != "models") {
        return Err(Error::invalid(format!(
            "--extends {from}: expected a trained model's name or its model file \
             <dir>/models/<name>.json (the record and tables of a train lie beside models/, in \
             <dir>/training_data/)"
        )));
    }
    let root = models.parent().unwrap_or(Path::new("")).to_path_buf();
    Ok((root, name))
}

#[cfg(test)]
mod tests {
    use super::{without_columns, FitStamp};
    use crate::campaign::table::csv_line;
    use std::path::{Path, PathBuf};

    fn lines(rows: &[&[&str]]) -> Vec<u8> {
        rows.iter()
            .flat_map(|r| csv_line(r.iter()).unwrap())
            .collect()
    }

    fn tables() -> (Vec<u8>, Vec<u8>) {
        let old = lines(&[
            &["run_id", "status", "flow", "warnings", "error"],
            &["a", "done", "1.5", "an arch holds 3, \"late\"", ""],
            &["b", "failed", "", "", "no particles"],
        ]);
        let widened = lines(&[
            &["run_id", "status", "flow", "arch_held", "warnings", "error"],
            &["a", "done", "1.5", "3.0", "an arch holds 3, \"late\"", ""],
            &["b", "failed", "", "", "", "no particles"],
        ]);
        (old, widened)
    }

    #[test]
    fn a_table_less_its_gained_columns_is_the_table_it_was() {
        let (old, widened) = tables();
        let p = Path::new("runs.csv");
        assert_eq!(without_columns(p, &widened, &["arch_held"]).unwrap(), old);
        assert_ne!(without_columns(p, &widened, &["flow"]).unwrap(), old);
        assert_eq!(without_columns(p, &widened, &[]).unwrap(), widened);
        assert_eq!(without_columns(p, &old, &["arch_held"]).unwrap(), old);
        let toml = b"[parameters]\nmu = \"a, b\"\n".to_vec();
        assert_eq!(without_columns(p, &toml, &["arch_held"]).unwrap(), toml);
    }

    #[test]
    fn a_fit_is_kept_when_its_table_gained_only_a_response_it_does_not_read() {
        let (old, widened) = tables();
        let stamp = |table: &[u8]| FitStamp {
            settings: crate::numeric::Fnv1a::default(),
            files: vec![
                (PathBuf::from("space.toml"), b"[parameters]\n".to_vec()),
                (PathBuf::from("runs.csv"), table.to_vec()),
            ],
        };
        let written = stamp(&old).text();
        assert!(written.contains("\nheader 1 run_id,status,flow,warnings,error\n"));
        assert!(stamp(&old).matches(&written, &[]).unwrap());
        assert!(stamp(&widened).matches(&written, &["arch_held"]).unwrap());
        // A gained column the fit reads, or another row, is another fit.
        assert!(!stamp(&widened).matches(&written, &[]).unwrap());
        let mut more = widened.clone();
        more.extend(csv_line(["c", "done", "1.7", "0.0", "", ""]).unwrap());
        assert!(!stamp(&more).matches(&written, &["arch_held"]).unwrap());
        let changed = String::from_utf8(widened.clone())
            .unwrap()
            .replace("done,1.5,", "done,1.6,");
        assert!(!stamp(changed.as_bytes())
            .matches(&written, &["arch_held"])
            .unwrap());
        // A stamp file written before the headers were kept: its hash alone, on the bytes.
        let first = written.lines().next().unwrap().to_string();
        assert!(stamp(&old).matches(&first, &["arch_held"]).unwrap());
        assert!(!stamp(&widened).matches(&first, &["arch_held"]).unwrap());
    }
}
