//! Decks for users who run the external code themselves: `mbgc simulate --backend liggghts
//! --write-decks DIR` writes one directory per run, `DIR/<run_id>/`, with everything LIGGGHTS
//! needs, plus the campaign that made them (`DIR/campaign.json` and a copy of the design,
//! `DIR/design.csv`) and a script that runs the decks not yet finished. `mbgc campaign import
//! --decks DIR --out T.csv` rebuilds the plan from these two files and reads back every
//! finished run into the campaign table, resumably: runs still missing are left for the next
//! import.

use std::collections::HashSet;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::backend::Backend;
use super::lock::TableLock;
use super::plan::{Plan, Shard};
use super::registry::ExperimentSettings;
use crate::error::{read_to_string, write_atomic, Error, Result};
use crate::experiments::Experiment;
use crate::liggghts::fill_run::{state, RunState, RUN_END};
use crate::liggghts::shear_box_fill::{FINAL_DUMP, INPUT, LOG};
use mbgc_dem::contact::ModelClass;

/// File in the deck directory recording the campaign that wrote it ([`DeckCampaign`] as JSON).
pub const CAMPAIGN_FILE: &str = "campaign.json";
/// Copy of the design in the deck directory, from which `campaign import` rebuilds the plan.
pub const DESIGN_FILE: &str = "design.csv";
/// Shell script in the deck directory that runs every deck not yet finished.
pub const RUN_SCRIPT: &str = "run_all.sh";

/// What made a deck directory: enough to rebuild its plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DeckCampaign {
    /// Experiment name, as on the command line (e.g. `shear-box`).
    pub experiment: String,
    /// Backend label (see [`Backend::label`]).
    pub backend: String,
    /// `+`-joined effect names.
    pub model_class: String,
    /// Shear-box scale k (smallest box side in d_max), if the experiment has one and it was set.
    pub box_scale: Option<f64>,
    /// Campaign seed from which every row's seed is derived.
    pub seed: u64,
    /// `--set` constants in the order given: the order of a run's inputs is part of its id.
    pub set: Vec<(String, f64)>,
    /// `K/N` when only a shard's decks were written.
    pub shard: Option<String>,
    /// The design as given when the decks were written (its copy is `design.csv`).
    pub design_given: String,
}

impl DeckCampaign {
    /// The record of a plan, to be written as [`CAMPAIGN_FILE`].
    pub fn of(plan: &Plan) -> DeckCampaign {
        DeckCampaign {
            experiment: plan.experiment.clone(),
            backend: plan.settings.backend.label().into(),
            model_class: plan.model_class_label(),
            box_scale: plan.settings.box_scale,
            seed: plan.seed,
            set: plan.set.clone(),
            shard: plan.shard.map(|s| s.to_string()),
            design_given: plan.design.display().to_string(),
        }
    }

    /// Reads [`CAMPAIGN_FILE`] from a deck directory; errors name the file.
    pub fn read(dir: &Path) -> Result<DeckCampaign> {
        let path = dir.join(CAMPAIGN_FILE);
        let text = read_to_string(&path)?;
        serde_json::from_str(&text).map_err(|e| {
            Error::input(
                path.display(),
                "JSON",
                format!("the campaign written by --write-decks: {e}"),
            )
        })
    }

    /// The settings the decks were written with, and the MPI processes the user ran them on
    /// (`campaign import --mpi`, recorded in the table's sidecar).
    pub fn settings(&self, dir: &Path, mpi: Option<usize>) -> Result<ExperimentSettings> {
        let file = dir.join(CAMPAIGN_FILE).display().to_string();
        let class = ModelClass::parse(&self.model_class.replace('+', ","))
            .map_err(|e| Error::input(&file, "model_class", e.to_string()))?;
        let backend = Backend::parse(&self.backend)
            .map_err(|e| Error::input(&file, "backend", e.to_string()))?;
        Ok(ExperimentSettings {
            box_scale: self.box_scale,
            model_class: Some(class),
            backend,
            mpi,
            // Decks are LIGGGHTS', which ends its phases by the kinetic rule only.
            rest_rule: None,
        })
    }

    /// The plan of the decks in `dir`, for `experiment` (built from `settings`).
    pub fn plan(
        &self,
        dir: &Path,
        experiment: &dyn Experiment,
        settings: &ExperimentSettings,
    ) -> Result<Plan> {
        let file = dir.join(CAMPAIGN_FILE).display().to_string();
        let shard = self
            .shard
            .as_deref()
            .map(Shard::parse)
            .transpose()
            .map_err(|e| Error::input(&file, "shard", e.to_string()))?;
        Plan::new(
            experiment,
            &dir.join(DESIGN_FILE),
            &self.set,
            self.seed,
            settings,
            shard,
        )
    }
}

/// What [`write_decks`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct WrittenDecks {
    /// Run directories whose deck was written now.
    pub written: usize,
    /// Directories whose deck was there already (identical: a deck is a function of its row).
    pub kept: usize,
}

/// Writes the decks of the plan's shard into `dir`, with the campaign, the design's copy and the
/// run script. A directory that already holds decks of another campaign is refused.
pub fn write_decks(experiment: &dyn Experiment, plan: &Plan, dir: &Path) -> Result<WrittenDecks> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::invalid(format!(
            "--write-decks {}: is a file; expected a directory",
            dir.display()
        )));
    }
    // Files of someone else's must not be replaced by a campaign.json, design.csv or deck.
    let foreign = dir.is_dir()
        && !dir.join(CAMPAIGN_FILE).exists()
        && std::fs::read_dir(dir)
            .map_err(|e| Error::io(dir, e))?
            .next()
            .is_some();
    if foreign {
        return Err(Error::invalid(format!(
            "--write-decks {}: holds files but no {CAMPAIGN_FILE}, so it is no deck directory of \
             mbgc's; expected a new or empty directory",
            dir.display()
        )));
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    // Two writers (two shards at once) would each keep only their own shard in campaign.json.
    let _lock = TableLock::acquire(&dir.join(CAMPAIGN_FILE))?;
    let mut campaign = DeckCampaign::of(plan);
    let design_copy = dir.join(DESIGN_FILE);
    let design_bytes = std::fs::read(&plan.design).map_err(|e| Error::io(&plan.design, e))?;
    if dir.join(CAMPAIGN_FILE).exists() {
        let old = DeckCampaign::read(dir)?;
        let same_design = std::fs::read(&design_copy).is_ok_and(|b| b == design_bytes);
        let same = DeckCampaign {
            design_given: old.design_given.clone(),
            shard: old.shard.clone(),
            ..campaign.clone()
        } == old;
        if !same || !same_design {
            return Err(Error::invalid(format!(
                "--write-decks {}: holds the decks of another campaign ({}); choose another \
                 directory",
                dir.display(),
                dir.join(CAMPAIGN_FILE).display()
            )));
        }
        // Decks of several shards in one directory: the import then covers every row.
        if old.shard != campaign.shard {
            campaign.shard = None;
        }
    }
    write_atomic(&design_copy, &design_bytes)?;
    let mut written = WrittenDecks {
        written: 0,
        kept: 0,
    };
    for run in plan.selected() {
        let d = dir.join(&run.run_id);
        if d.join(INPUT).exists() {
            // A deck is a function of its row: one that differs was edited (or written by
            // another mbgc). Unrun, it is replaced; run, its results would not be this row's.
            let fresh =
                tempfile::tempdir().map_err(|e| Error::invalid(format!("temp dir: {e}")))?;
            experiment.write_deck(&run.params, run.seed, fresh.path())?;
            let same =
                std::fs::read(fresh.path().join(INPUT)).ok() == std::fs::read(d.join(INPUT)).ok();
            if same {
                written.kept += 1;
                continue;
            }
            if d.join(LOG).exists() {
                return Err(Error::input(
                    d.join(INPUT).display(),
                    "deck",
                    format!(
                        "row {}'s deck, found another one that has been run ({}); remove {} to \
                         write and run it again",
                        run.row,
                        LOG,
                        d.display()
                    ),
                ));
            }
        }
        experiment.write_deck(&run.params, run.seed, &d)?;
        written.written += 1;
    }
    let json = serde_json::to_string_pretty(&campaign)
        .map_err(|e| Error::invalid(format!("{CAMPAIGN_FILE}: {e}")))?;
    write_atomic(&dir.join(CAMPAIGN_FILE), format!("{json}\n").as_bytes())?;
    write_atomic(&dir.join(RUN_SCRIPT), run_script().as_bytes())?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let script = dir.join(RUN_SCRIPT);
        std::fs::set_permissions(&script, std::fs::Permissions::from_mode(0o755))
            .map_err(|e| Error::io(&script, e))?;
    }
    Ok(written)
}

/// A script that runs, N at a time, every deck whose run has not finished; it exits non-zero
/// when a run failed.
fn run_script() -> String {
    format!(
        "#!/bin/sh\n\
         # Runs every deck here whose run has not finished, N at a time:\n\
         #   ./{RUN_SCRIPT} [N] [COMMAND]   (COMMAND, split at spaces: default liggghts; e.g.\n\
         #   \"mpirun -np 4 liggghts\", then import with --mpi 4)\n\
         # Then: mbgc campaign import --decks <this directory> --out <table.csv>\n\
         cd \"$(dirname \"$0\")\" || exit 1\n\
         N=\"${{1:-1}}\"\n\
         case \"$N\" in ''|*[!0-9]*|0) echo \"{RUN_SCRIPT}: N must be a whole number >= 1, found '$N'\" >&2; exit 2;; esac\n\
         LMP=\"${{2:-liggghts}}\"\n\
         export LMP\n\
         for d in */; do [ -f \"${{d}}{INPUT}\" ] && printf '%s\\0' \"${{d%/}}\"; done | \\\n\
         xargs -0 -n 1 -P \"$N\" sh -c '\n\
           cd \"$1\" || exit 1\n\
           grep -q \"^{RUN_END}\" {LOG} 2>/dev/null && [ -f {FINAL_DUMP} ] && exit 0\n\
           $LMP -in {INPUT} -log {LOG} -screen /dev/null > /dev/null 2>&1 || {{ echo \"$1: failed (see $1/{LOG})\" >&2; exit 1; }}\n\
         ' sh\n"
    )
}

/// Subdirectories of `dir` that are no run of the plan (all shards): decks of another
/// campaign, or renamed ones, which an import would otherwise pass over in silence.
pub fn stray_dirs(plan: &Plan, dir: &Path) -> Result<Vec<String>> {
    let ids: HashSet<&str> = plan.rows.iter().map(|r| r.run_id.as_str()).collect();
    let mut stray = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if entry.path().is_dir() && !ids.contains(name.as_str()) {
            stray.push(name);
        }
    }
    stray.sort();
    Ok(stray)
}

/// The run ids of the plan's shard split into those with results to import (finished or
/// failed in the external code) and those not run yet.
pub fn ready_runs(plan: &Plan, dir: &Path) -> (HashSet<String>, Vec<usize>) {
    let mut ready = HashSet::new();
    let mut missing = Vec::new();
    for run in plan.selected() {
        match state(&dir.join(&run.run_id)) {
            RunState::Finished | RunState::Failed(_) => {
                ready.insert(run.run_id.clone());
            }
            RunState::NotRun | RunState::Unfinished => missing.push(run.row),
        }
    }
    (ready, missing)
}
