//! The shear-box experiment run by LIGGGHTS 3.8 instead of mbgc's engine: the backend of
//! `mbgc simulate --backend liggghts`. Each run writes the self-filling deck
//! ([`super::shear_box_fill`]: LIGGGHTS' own insertion, mbgc's box, schedule and stop rules),
//! runs it, and measures the dumps with the embedded experiment's own functions
//! (`measure_flank`, `box_bulk_density`, `outflow_fraction`), so that the table has the same
//! columns and its numbers mean the same things. The PSD is [`CLASSES`] particle templates of
//! equal mass (LIGGGHTS has no continuous distribution); the comparison with mbgc's continuous
//! PSD is in `docs/shear_box.md`.
//!
//! In [`DeckMode::Import`] nothing is run: the run's directory holds a deck that a user ran
//! (`--write-decks`, then LIGGGHTS on their machine), and its results are read back after
//! checking that the deck there is the one this row would write and that it ran on the number
//! of MPI processes the import was told (part of the run's identity). A run directory kept with
//! `--decks` that holds this row's finished run is likewise read, not run again.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::binary::{require_binary, run_deck_on};
use super::fill_run::{state, FillRun, RunState, Spheres};
use super::shear_box::gran_model;
use super::shear_box_fill::{
    fill_deck, write_fill_deck, FillDeck, CLASSES, FILLED_DUMP, FINAL_DUMP, INPUT, INSERTED_DUMP,
    LOG, PRE_STRIKE_DUMP,
};
use crate::error::{read_to_string, Error, Result};
use crate::experiments::shear_box::{
    box_bulk_density, measure_flank, outflow_fraction, Responses, RestRule, ShearBox,
};
use crate::experiments::{Diagnostics, Experiment, Outcome, ParamSet, RunOptions};
use mbgc_dem::contact::ModelClass;
use mbgc_dem::particles::Particles;

/// What a run does with its directory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeckMode {
    /// Write the deck, run LIGGGHTS on `ranks` MPI processes, measure.
    Run {
        /// MPI processes LIGGGHTS runs on (>= 1).
        ranks: usize,
    },
    /// Measure a deck someone else ran on `ranks` MPI processes (the directory must be given).
    Import {
        /// MPI processes the imported run must have used (>= 1): another count is another,
        /// equally valid trajectory, which the row's id does not name, so it is refused.
        ranks: usize,
    },
}

/// The shear-box experiment run by LIGGGHTS 3.8: the self-filling deck of
/// [`super::shear_box_fill`], measured with the same functions as mbgc's own run.
#[derive(Debug, Clone)]
pub struct LiggghtsShearBox {
    /// The embedded experiment whose box, particles and schedule the deck reproduces.
    pub shear_box: ShearBox,
    /// Whether to run the deck here or measure a run someone else made.
    pub mode: DeckMode,
}

impl LiggghtsShearBox {
    /// Refuses a model class with an effect LIGGGHTS 3.8 lacks (naming it), zero ranks, and a
    /// rest rule other than the kinetic one, the only one the deck applies.
    pub fn new(shear_box: ShearBox, mode: DeckMode) -> Result<Self> {
        gran_model(&shear_box.class)?;
        if shear_box.rest != RestRule::Kinetic {
            return Err(Error::invalid(format!(
                "rest rule {:?}: the LIGGGHTS deck ends the fill and the outflow by the kinetic \
                 rule only (rms and largest speed), so it would be ignored",
                shear_box.rest
            )));
        }
        if matches!(
            mode,
            DeckMode::Run { ranks: 0 } | DeckMode::Import { ranks: 0 }
        ) {
            return Err(Error::invalid("--mpi 0: expected at least 1 process"));
        }
        Ok(LiggghtsShearBox { shear_box, mode })
    }

    /// The deck of one row: mbgc's layout for `seed` sizes the box and sets the total mass.
    pub fn deck(&self, p: &ParamSet, seed: u64) -> Result<FillDeck> {
        fill_deck(&self.shear_box, p, seed, CLASSES, None)
    }

    fn run_in(&self, p: &ParamSet, seed: u64, dir: &Path) -> Result<Outcome> {
        let clock = Instant::now();
        let deck = self.deck(p, seed)?;
        // A run that finished here before (a crash of mbgc after LIGGGHTS was done, or a
        // restart) is read, not run again, if its deck is this row's.
        let reuse = matches!(self.mode, DeckMode::Run { .. })
            && state(dir) == RunState::Finished
            && self.check_deck(p, &deck, dir).is_ok();
        match self.mode {
            DeckMode::Run { .. } if reuse => {}
            DeckMode::Run { ranks } => {
                let binary = require_binary()?;
                std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
                // A rerun (after a crash, or --retry-failed) must not read the last attempt's files.
                for stale in [INSERTED_DUMP, PRE_STRIKE_DUMP, FILLED_DUMP, FINAL_DUMP, LOG] {
                    let f = dir.join(stale);
                    if f.exists() {
                        std::fs::remove_file(&f).map_err(|e| Error::io(&f, e))?;
                    }
                }
                write_fill_deck(dir, p, &deck)?;
                run_deck_on(&binary, dir, INPUT, LOG, ranks)?;
            }
            DeckMode::Import { .. } => self.check_deck(p, &deck, dir)?,
        }
        let run = FillRun::read(dir)?;
        let mut o = self
            .measure(p, &deck, &run)
            .map_err(|e| Error::invalid(format!("{}: {e}", dir.display())))?;
        o.diagnostics.wall_time_s = match self.mode {
            DeckMode::Run { .. } if !reuse => clock.elapsed().as_secs_f64(),
            _ => run.loop_seconds,
        };
        Ok(o)
    }

    /// The deck in `dir` must be the one this row writes: a directory of another row, design or
    /// mbgc version would otherwise be imported as this row's run.
    fn check_deck(&self, p: &ParamSet, deck: &FillDeck, dir: &Path) -> Result<()> {
        let fresh = tempfile::tempdir().map_err(|e| Error::invalid(format!("temp dir: {e}")))?;
        write_fill_deck(fresh.path(), p, deck)?;
        let want = read_to_string(&fresh.path().join(INPUT))?;
        let path = dir.join(INPUT);
        let found = read_to_string(&path)?;
        if found != want {
            let line = found
                .lines()
                .zip(want.lines())
                .position(|(a, b)| a != b)
                .unwrap_or(found.lines().count().min(want.lines().count()));
            return Err(Error::input(
                path.display(),
                format!("line {}", line + 1),
                format!(
                    "the deck this row writes ({:?}), found {:?}: the directory holds another \
                     run's deck or an edited one; remove {} and write the decks again \
                     (--write-decks), then run and import it (--retry-failed)",
                    want.lines().nth(line).unwrap_or(""),
                    found.lines().nth(line).unwrap_or(""),
                    dir.display()
                ),
            ));
        }
        Ok(())
    }

    /// The responses and diagnostics of a finished run, measured as the embedded run measures.
    fn measure(&self, p: &ParamSet, deck: &FillDeck, run: &FillRun) -> Result<Outcome> {
        let rho = p
            .get("rho_p")
            .ok_or_else(|| Error::invalid("parameter rho_p: missing"))?;
        let size = deck.size;
        let mass = |s: &Spheres| -> f64 {
            s.iter()
                .map(|(r, _)| rho * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3))
                .sum()
        };
        let mut last = Particles::new();
        for (r, x) in &run.last {
            last.add(*x, *r, rho, 0)?;
        }
        let flank = measure_flank(&last, size, deck.d_max);
        let mut warnings = Vec::new();
        if flank.points.len() < 3 {
            warnings.push(format!(
                "only {} flank columns: no shear angle",
                flank.points.len()
            ));
        }
        let filled_at_rest = run.fill_steps < deck.max_fill_steps;
        if !filled_at_rest {
            warnings.push("filling did not come to rest within the time limit".into());
        }
        let stopped = run.quiet_checks >= 5;
        if !stopped {
            warnings.push("outflow did not come to rest within the time limit".into());
        }
        let ranks = match self.mode {
            DeckMode::Run { ranks } | DeckMode::Import { ranks } => ranks,
        };
        if run.procs != ranks {
            // The process count is part of the run's identity: another count is another
            // (equally valid) trajectory, which this row's id does not name.
            return Err(Error::input(
                "log.shear_box_fill",
                "Loop time",
                format!(
                    "a run on {ranks} MPI process(es) (--mpi {ranks}), found one on {}; import \
                     it with --mpi {}",
                    run.procs, run.procs
                ),
            ));
        }
        let (m_filled, m_last) = (mass(&run.filled), mass(&run.last));
        Ok(Outcome {
            responses: Responses {
                shear_angle: (-flank.slope).atan().to_degrees(),
                bulk_density: box_bulk_density(run.filled.iter().copied(), rho, size),
                flank_r2: flank.r2,
                flank_curvature: flank.curvature,
                outflow_fraction: outflow_fraction(m_last, m_filled - m_last),
            }
            .named(),
            diagnostics: Diagnostics {
                settled: filled_at_rest && stopped,
                steps: run.steps,
                particles: run.filled.len(),
                wall_time_s: 0.0,
                warnings,
            },
        })
    }
}

impl Experiment for LiggghtsShearBox {
    fn name(&self) -> &'static str {
        self.shear_box.name()
    }
    fn calibration_responses(&self) -> Vec<&'static str> {
        self.shear_box.calibration_responses()
    }
    fn similarity(&self) -> Option<crate::similarity::Similarity> {
        self.shear_box.similarity()
    }
    fn parameters(&self) -> Vec<&'static str> {
        self.shear_box.parameters()
    }
    fn optional_parameters(&self) -> Vec<&'static str> {
        self.shear_box.optional_parameters()
    }
    fn class(&self) -> Option<&ModelClass> {
        self.shear_box.class()
    }
    fn responses(&self) -> Vec<&'static str> {
        self.shear_box.responses()
    }
    fn check(&self, p: &ParamSet) -> Result<()> {
        self.shear_box.check(p)
    }

    fn write_deck(&self, p: &ParamSet, seed: u64, dir: &Path) -> Result<()> {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        write_fill_deck(dir, p, &self.deck(p, seed)?)
    }

    fn run(&self, p: &ParamSet, seed: u64, opts: &RunOptions) -> Result<Outcome> {
        if opts.vtk_dir.is_some() || opts.picture.is_some() {
            return Err(Error::invalid(
                "--vtk/--picture: the LIGGGHTS backend writes no snapshots or pictures of its \
                 own (its dumps are kept with --decks DIR)",
            ));
        }
        match (&opts.work_dir, self.mode) {
            (Some(dir), _) => self.run_in(p, seed, dir),
            (None, DeckMode::Import { .. }) => Err(Error::invalid(
                "importing a LIGGGHTS run needs the directory it ran in",
            )),
            (None, DeckMode::Run { .. }) => {
                let tmp = tempfile::Builder::new()
                    .prefix("mbgc-liggghts-")
                    .tempdir()
                    .map_err(|e| Error::invalid(format!("temporary directory: {e}")))?;
                let dir: PathBuf = tmp.path().to_path_buf();
                self.run_in(p, seed, &dir)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rest_rule_the_deck_cannot_apply_is_refused_by_name() {
        let sb = ShearBox {
            rest: RestRule::CANDIDATE,
            ..ShearBox::default()
        };
        let Err(e) = LiggghtsShearBox::new(sb, DeckMode::Run { ranks: 1 }) else {
            panic!("a response rule was accepted");
        };
        let e = e.to_string();
        assert!(e.contains("rest rule") && e.contains("kinetic"), "{e}");
        assert!(LiggghtsShearBox::new(ShearBox::default(), DeckMode::Run { ranks: 1 }).is_ok());
    }
}
