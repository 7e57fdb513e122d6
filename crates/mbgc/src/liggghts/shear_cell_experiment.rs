//! The shear-cell experiment run by LIGGGHTS 3.8 instead of mbgc's engine: the backend of
//! `mbgc simulate --experiment shear-cell --backend liggghts`. Each run writes the deck of
//! [`super::shear_cell`] (mbgc's periodic cell, glued layers, schedule, dead load and stop rules in
//! LIGGGHTS' words), runs it, and measures what it printed with the definitions of
//! [`crate::experiments::shear_cell`] and [`crate::experiments::shear_test`], so that the table
//! has the same columns and its numbers mean the same things:
//!
//! - `shear_ratio`: the mean shear over the mean normal stress of the pre-shear's last five
//!   0.1 d50 bins of travel (the lid's contact force per area, as mbgc's); the pre-shear is
//!   tested for steadiness as mbgc tests it, and the deck's stop is checked against mbgc's loop
//!   replayed on the deck's samples;
//! - `bulk_density`: rho_p times the interior slab's solid fraction (every grain sliced between
//!   1 d_max above the floor layer and 1 d_max below the lid layer), averaged over the samples
//!   of the pre-shear's last 0.5 d50;
//! - failure points: per test, the largest running mean over three bins of the shear stress
//!   (with its normal stress) up to mbgc's stop, recomputed from the deck's samples (a test
//!   without a drop counts if it levelled off, as mbgc's); `internal_friction` and `cohesion`
//!   from mbgc's yield locus through the three points, `unconfined_yield_strength` from mbgc's
//!   own function.
//!
//! The run is refused as mbgc refuses it (grains through the lid), and also when LIGGGHTS' glued
//! layers are not mbgc's rule's (the fewest grains reaching the layer's mass) or grains left the
//! cell. Where the run differs from mbgc's (all in
//! [`super::shear_cell`]'s documentation): LIGGGHTS inserts its own particles (the same number,
//! mbgc's column), a failure test starts from a restart file instead of a clone in memory, a
//! PSD is five equal-mass templates, and the deck's numbers pass through 15 digits.
//!
//! [`DeckMode::Import`] reads a run a user made from `--write-decks`, as for the shear box.
//!
//! Checked at k = 12 against mbgc's engine (`hertz,mindlin,epsd2,sjkr` with ced_pp 0, 6 kPa,
//! three seeds each, `docs/data/shear_cell/periodic/liggghts/`): internal friction 27.19 +- 0.77
//! against 27.20 +- 1.11 degrees, cohesion -82 +- 10 against -9 +- 108 Pa, shear ratio 0.498 +-
//! 0.033 against 0.518 +- 0.015 (all within 1.2 standard errors), bulk density 1479.3 +- 1.4
//! against 1485.2 +- 3.2 kg/m^3 (-0.4 %, 2.9 standard errors; 1.7 with six seeds each); every
//! run steady at 2 d50, the same 227 grains glued in each layer; LIGGGHTS took 3.2 times mbgc's
//! time (107 s against 33 s a run, one core each).

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::binary::{require_binary, run_deck_on};
use super::shear_box::gran_model;
use super::shear_box_experiment::DeckMode;
use super::shear_cell::{
    cell_deck, state, write_cell_deck, CellDeck, CellRun, RunState, Sample, FINAL_DUMP, INPUT, LOG,
    PRESHEAR_DUMP, RESTART,
};
use crate::error::{read_to_string, Error, Result};
use crate::experiments::shear_cell::{ShearCell, FAILURE_FRACTIONS, LAYER};
use crate::experiments::shear_test::{responses, steadiness, yield_locus, Bins, Travels};
use crate::experiments::{Diagnostics, Experiment, Outcome, ParamSet, RunOptions, RHO_RANGE};
use mbgc_dem::contact::ModelClass;

/// The shear-cell experiment run by LIGGGHTS 3.8.
#[derive(Debug, Clone)]
pub struct LiggghtsShearCell {
    /// The embedded experiment whose cell, particles and schedule the deck reproduces.
    pub cell: ShearCell,
    /// Whether to run the deck here or measure a run someone else made.
    pub mode: DeckMode,
}

impl LiggghtsShearCell {
    /// Refuses a model class with an effect LIGGGHTS 3.8 lacks (naming it) and zero ranks.
    pub fn new(cell: ShearCell, mode: DeckMode) -> Result<Self> {
        gran_model(&cell.class)?;
        if matches!(
            mode,
            DeckMode::Run { ranks: 0 } | DeckMode::Import { ranks: 0 }
        ) {
            return Err(Error::invalid("--mpi 0: expected at least 1 process"));
        }
        Ok(LiggghtsShearCell { cell, mode })
    }

    /// The deck of one row.
    pub fn deck(&self, p: &ParamSet, seed: u64) -> Result<CellDeck> {
        cell_deck(&self.cell, p, seed)
    }

    fn ranks(&self) -> usize {
        match self.mode {
            DeckMode::Run { ranks } | DeckMode::Import { ranks } => ranks,
        }
    }

    fn run_in(&self, p: &ParamSet, seed: u64, dir: &Path) -> Result<Outcome> {
        let clock = Instant::now();
        let deck = self.deck(p, seed)?;
        let reuse = matches!(self.mode, DeckMode::Run { .. })
            && state(dir) == RunState::Finished
            && self.check_deck(p, &deck, dir).is_ok();
        match self.mode {
            DeckMode::Run { .. } if reuse => {}
            DeckMode::Run { ranks } => {
                let binary = require_binary()?;
                std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
                for stale in [LOG, PRESHEAR_DUMP, FINAL_DUMP, RESTART] {
                    let f = dir.join(stale);
                    if f.exists() {
                        std::fs::remove_file(&f).map_err(|e| Error::io(&f, e))?;
                    }
                }
                write_cell_deck(dir, p, &deck)?;
                run_deck_on(&binary, dir, INPUT, LOG, ranks)?;
            }
            DeckMode::Import { .. } => self.check_deck(p, &deck, dir)?,
        }
        let run = CellRun::read(dir)?;
        if run.procs != self.ranks() {
            return Err(Error::input(
                dir.join(LOG).display(),
                "Loop time",
                format!(
                    "a run on {r} MPI process(es) (--mpi {r}), found one on {p}; import it with \
                     --mpi {p}",
                    r = self.ranks(),
                    p = run.procs
                ),
            ));
        }
        let rho = p.require("rho_p", RHO_RANGE.0, RHO_RANGE.1)?;
        let mut o = measure(&deck, &run, rho)
            .map_err(|e| Error::invalid(format!("{}: {e}", dir.display())))?;
        o.diagnostics.wall_time_s = match self.mode {
            DeckMode::Run { .. } if !reuse => clock.elapsed().as_secs_f64(),
            _ => run.loop_seconds,
        };
        Ok(o)
    }

    /// The deck in `dir` must be the one this row writes.
    fn check_deck(&self, p: &ParamSet, deck: &CellDeck, dir: &Path) -> Result<()> {
        let fresh = tempfile::tempdir().map_err(|e| Error::invalid(format!("temp dir: {e}")))?;
        write_cell_deck(fresh.path(), p, deck)?;
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
}

/// The failure point of one test: mbgc's peak of the running mean over three bins, whether
/// the test failed (the stress fell past the peak, or levelled off over the last 0.5 d50: a
/// plateau, mbgc's rule for a bed without a peak), and the travel the test used.
fn failure_point(d: &CellDeck, start: u64, samples: &[Sample]) -> (Option<(f64, f64)>, bool, f64) {
    let mut bins = Bins::new(d.bin);
    let mut peak: Option<(f64, f64)> = None;
    let mut t = 0.0;
    for s in samples {
        t = d.travel(s.step.saturating_sub(start));
        let before = bins.done.len();
        bins.add(t, s.normal, s.shear);
        if bins.done.len() > before && bins.done.len() >= 3 {
            let b = bins.last(3).unwrap_or((f64::NAN, f64::NAN));
            if peak.is_none_or(|p| b.1 > p.1) {
                peak = Some(b);
            } else if t > 0.5 * d.d50 && peak.is_some_and(|p| b.1 < 0.95 * p.1) {
                return (peak, true, t);
            }
        }
        if t >= d.max_failure {
            break;
        }
    }
    (peak, steadiness(&bins.done).is_ok(), t)
}

/// Where mbgc's pre-shear loop stops on these samples (its steadiness test at every fifth bin
/// from the shortest pre-shear on, its longest pre-shear): the index of its last sample, or
/// None when it would go on past them.
fn preshear_stop(d: &CellDeck, start: u64, samples: &[Sample]) -> Option<usize> {
    let mut bins = Bins::new(d.bin);
    for (i, s) in samples.iter().enumerate() {
        let travel = d.travel(s.step.saturating_sub(start));
        let before = bins.done.len();
        bins.add(travel, s.normal, s.shear);
        if bins.done.len() > before
            && bins.done.len().is_multiple_of(5)
            && travel >= d.preshear - 0.5 * d.bin
            && (steadiness(&bins.done).is_ok() || travel >= d.max_preshear - 0.5 * d.bin)
        {
            return Some(i);
        }
    }
    None
}

/// The glued layers must be what mbgc glues: the fewest grains whose mass reaches the layer's
/// (so the heaviest template's grain taken off leaves less than it).
fn check_layers(d: &CellDeck, run: &CellRun, rho: f64) -> Result<()> {
    let grain = |dia: f64| rho * std::f64::consts::PI / 6.0 * dia.powi(3);
    let heaviest = d.classes.iter().map(|c| grain(c.0)).fold(0.0, f64::max);
    for (what, n, m) in [
        ("floor", run.glued.floor, run.glued.floor_mass),
        ("lid", run.glued.lid, run.glued.lid_mass),
    ] {
        if !(m >= d.layer_mass * (1.0 - 1e-12) && m - heaviest < d.layer_mass) {
            return Err(Error::invalid(format!(
                "shear cell: LIGGGHTS glued {n} grains of {m:.6e} kg as the {what}, expected the \
                 fewest lowest/highest grains whose mass reaches {:.6e} kg",
                d.layer_mass
            )));
        }
    }
    Ok(())
}

/// The responses and diagnostics of a finished run, measured as mbgc's run measures.
pub fn measure(d: &CellDeck, run: &CellRun, rho: f64) -> Result<Outcome> {
    let mut warnings = Vec::new();
    if !run.fill_settled {
        warnings.push("filling did not come to rest within the time limit".into());
    }
    check_layers(d, run, rho)?;
    if run.atoms != run.inserted {
        return Err(Error::invalid(format!(
            "shear cell: {} of the {} grains left the cell by the end of the pre-shear",
            run.inserted.saturating_sub(run.atoms),
            run.inserted
        )));
    }
    // The pre-shear: its bins, its steadiness, the interior's solid fraction per sample.
    let mut bins = Bins::new(d.bin);
    let mut travel = 0.0;
    let mut fractions = Vec::new();
    for s in &run.preshear {
        travel = d.travel(s.step.saturating_sub(run.preshear_start));
        bins.add(travel, s.normal, s.shear);
        fractions.push((travel, d.solid_fraction(s)));
    }
    let steady = match steadiness(&bins.done) {
        Ok(()) => true,
        Err(why) => {
            warnings.push(why);
            false
        }
    };
    let n = run.preshear.len();
    match preshear_stop(d, run.preshear_start, &run.preshear) {
        Some(i) if i + 1 == n => {}
        stop => warnings.push(format!(
            "LIGGGHTS' pre-shear stopped after {n} samples, where mbgc's rule on the same \
             samples {} (the deck's numbers carry 15 digits)",
            stop.map_or("goes on".into(), |i| format!("stops after {}", i + 1))
        )),
    }
    let curve = bins
        .done
        .chunks(5)
        .map(|c| {
            let (n, t) = c.iter().fold((0.0, 0.0), |a, x| (a.0 + x.0, a.1 + x.1));
            format!("{:.3}", t / n)
        })
        .collect::<Vec<_>>()
        .join(", ");
    let (pre_normal, pre_shear) = bins.last(5).unwrap_or((f64::NAN, f64::NAN));
    let shear_ratio = pre_shear / pre_normal;
    // The density over the same last 0.5 d50 as the shear ratio.
    let fractions: Vec<f64> = fractions
        .into_iter()
        .filter(|(t, f)| *t > travel - 5.0 * d.bin && f.is_finite())
        .map(|(_, f)| f)
        .collect();
    let bulk_density = rho * fractions.iter().sum::<f64>() / fractions.len() as f64;

    if run.failures.len() != FAILURE_FRACTIONS.len() {
        return Err(Error::input(
            LOG,
            "FAIL_START",
            format!(
                "{} failure tests, found {}",
                FAILURE_FRACTIONS.len(),
                run.failures.len()
            ),
        ));
    }
    let mut locus = Vec::new();
    let mut failed_peaks = 0;
    let mut longest = 0.0f64;
    for f in &run.failures {
        let (peak, failed, t) = failure_point(d, f.start, &f.samples);
        longest = longest.max(t);
        if !failed {
            failed_peaks += 1;
        }
        if let Some(p) = peak {
            locus.push(p);
        }
    }
    let (cohesion, phi, locus_valid) = yield_locus(
        &locus,
        Travels {
            preshear: travel / d.d50,
            longest_failure: longest / d.d50,
            max_failure: d.max_failure / d.d50,
            length: f64::INFINITY,
        },
        failed_peaks,
        FAILURE_FRACTIONS.len(),
        &mut warnings,
    );
    let lid = run.preshear.last().map_or(f64::NAN, |s| s.lid);
    let escaped = run
        .free
        .iter()
        .filter(|(_, x)| x[2] > lid + LAYER * d.d_max)
        .count();
    if escaped > 0 {
        return Err(Error::invalid(format!(
            "shear cell: {escaped} grains passed through the lid's glued layer (a PSD too \
             wide for a lid {LAYER} d_max thick)"
        )));
    }
    warnings.push(format!(
        "pre-shear travel {:.2} d50 (stress ratio per 0.5 d50 of it: {curve}); failure points \
         (normal, shear) in Pa: {}",
        travel / d.d50,
        locus
            .iter()
            .map(|(s, t)| format!("({s:.4e}, {t:.4e})"))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    Ok(Outcome {
        responses: responses(cohesion, phi, bulk_density, shear_ratio),
        diagnostics: Diagnostics {
            settled: run.fill_settled && steady && locus_valid,
            steps: run.preshear_end,
            particles: run.inserted,
            wall_time_s: 0.0,
            warnings,
        },
    })
}

impl Experiment for LiggghtsShearCell {
    fn name(&self) -> &'static str {
        self.cell.name()
    }
    fn calibration_responses(&self) -> Vec<&'static str> {
        self.cell.calibration_responses()
    }
    fn similarity(&self) -> Option<crate::similarity::Similarity> {
        self.cell.similarity()
    }
    fn parameters(&self) -> Vec<&'static str> {
        self.cell.parameters()
    }
    fn optional_parameters(&self) -> Vec<&'static str> {
        self.cell.optional_parameters()
    }
    fn class(&self) -> Option<&ModelClass> {
        self.cell.class()
    }
    fn responses(&self) -> Vec<&'static str> {
        self.cell.responses()
    }
    fn check(&self, p: &ParamSet) -> Result<()> {
        self.cell.check(p)
    }

    fn write_deck(&self, p: &ParamSet, seed: u64, dir: &Path) -> Result<()> {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        write_cell_deck(dir, p, &self.deck(p, seed)?)
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
    use super::super::shear_cell::{FailureRun, Glued};
    use super::*;
    use mbgc_dem::contact::ModelClass;

    fn params() -> ParamSet {
        ParamSet::from_pairs(&[
            ("E_p", 5e7),
            ("nu_p", 0.3),
            ("rho_p", 2600.0),
            ("d50", 10.0),
            ("normal_stress", 6000.0),
            ("e_pp", 0.5),
            ("mu_pp", 0.5),
            ("mu_r_pp", 0.1),
        ])
    }

    fn cell(k: f64) -> ShearCell {
        ShearCell {
            cell_scale: k,
            class: ModelClass::parse("hertz,mindlin,epsd2").unwrap(),
            ..ShearCell::default()
        }
    }

    /// A synthetic run: a level pre-shear at ratio 0.8 over 2 d50 (steady at mbgc's first
    /// test), an interior at solid fraction 0.6, and failure points on the line tau = 200 + 0.7
    /// sigma, each level at its peak up to 0.6 d50 and at half of it after.
    fn synthetic(d: &CellDeck) -> CellRun {
        let s = d.sample;
        let level = |step: u64, normal: f64, shear: f64| Sample {
            step,
            normal,
            shear,
            floor: 0.01,
            lid: 0.11,
            slab: 0.6 * d.area() * (0.1 - 2.0 * d.interior_gap()),
        };
        let n = (1..).find(|&n| d.travel(n * s) >= d.preshear).unwrap();
        let pre: Vec<Sample> = (1..=n)
            .map(|i| level(1000 + i * s, d.sigma, 0.8 * d.sigma))
            .collect();
        let failures = FAILURE_FRACTIONS
            .iter()
            .enumerate()
            .map(|(k, f)| {
                let start = 100_000 * (k as u64 + 1);
                let sn = f * d.sigma;
                let top = 200.0 + 0.7 * sn;
                let samples = (1..=d.failure_samples)
                    .map(|i| {
                        let t = d.travel(i * s);
                        level(
                            start + i * s,
                            sn,
                            if t < 0.6 * d.d50 { top } else { 0.5 * top },
                        )
                    })
                    .collect();
                FailureRun { start, samples }
            })
            .collect();
        let grain = 2600.0 * std::f64::consts::PI / 6.0 * d.d50.powi(3);
        let layer = (d.layer_mass / grain).ceil();
        CellRun {
            fill_steps: 500,
            fill_settled: true,
            inserted: 100,
            inserted_mass: 1.0,
            glued: Glued {
                floor: layer as usize,
                lid: layer as usize,
                floor_mass: layer * grain,
                lid_mass: layer * grain,
            },
            preshear_start: 1000,
            preshear_end: 1000 + n * s,
            preshear: pre,
            atoms: 100,
            // Free grains below the lid (0.11 m), one just under 1.5 d_max above it.
            free: vec![(0.005, [0.02, 0.02, 0.05]), (0.005, [0.02, 0.02, 0.124])],
            failures,
            steps: 0,
            loop_seconds: 0.0,
            procs: 1,
        }
    }

    #[test]
    fn a_run_is_measured_with_mbgcs_definitions() {
        let d = cell_deck(&cell(12.0), &params(), 3).unwrap();
        let run = synthetic(&d);
        let o = measure(&d, &run, 2600.0).unwrap();
        let get = |n: &str| o.get(n).unwrap();
        assert!((get("shear_ratio") - 0.8).abs() < 1e-12, "{o:?}");
        assert!(
            (get("internal_friction") - 0.7f64.atan().to_degrees()).abs() < 1e-9,
            "{o:?}"
        );
        assert!((get("cohesion") - 200.0).abs() < 1e-9, "{o:?}");
        assert!((get("bulk_density") - 0.6 * 2600.0).abs() < 1e-9, "{o:?}");
        assert!(o.diagnostics.settled, "{o:?}");
        assert_eq!(o.diagnostics.steps, run.preshear_end);
        // The periodic cell has no length to run out of: one warning, the run's course.
        assert_eq!(o.diagnostics.warnings.len(), 1, "{o:?}");
        assert!(o.diagnostics.warnings[0]
            .starts_with("pre-shear travel 2.00 d50 (stress ratio per 0.5 d50 of it: 0.800, "));
        // A test without a drop that levelled off fails at its plateau, as mbgc's (on the
        // locus: 200 + 0.7 x 3000 Pa).
        let mut flat = synthetic(&d);
        for s in &mut flat.failures[1].samples {
            s.shear = 2300.0;
        }
        let o = measure(&d, &flat, 2600.0).unwrap();
        assert!(o.diagnostics.settled, "{o:?}");
        assert!(
            o.diagnostics.warnings[0].contains("(3.0000e3, 2.3000e3)"),
            "{o:?}"
        );
        // A test still rising is named; a moving pre-shear too, and the deck's stop where
        // mbgc's loop would have gone on.
        let start = flat.failures[1].start;
        for s in &mut flat.failures[1].samples {
            s.shear = 1000.0 * (1.0 + d.travel(s.step - start) / d.d50);
        }
        let n = flat.preshear.len();
        for s in &mut flat.preshear[n - 250..] {
            s.shear *= 1.2;
        }
        let o = measure(&d, &flat, 2600.0).unwrap();
        assert!(!o.diagnostics.settled);
        let w = o.diagnostics.warnings.join(" | ");
        assert!(w.contains("1 of 3 failure points showed"), "{w}");
        assert!(w.contains("pre-shear not steady"), "{w}");
        assert!(
            w.contains("where mbgc's rule on the same samples goes on"),
            "{w}"
        );
        assert!(!w.contains("short for its travel"), "{w}");
    }

    #[test]
    fn the_pre_shear_stops_where_mbgcs_loop_stops() {
        let d = cell_deck(&cell(12.0), &params(), 3).unwrap();
        let run = synthetic(&d);
        let start = run.preshear_start;
        // Level: at the first test (20 bins, 2 d50).
        let n = run.preshear.len();
        assert_eq!(preshear_stop(&d, start, &run.preshear), Some(n - 1));
        // Rising by 3 % a bin for ever: never steady, stopped at the longest pre-shear (60 bins).
        let samples: Vec<Sample> = (1..=4 * n as u64)
            .map(|i| {
                let t = d.travel(i * d.sample);
                Sample {
                    shear: 0.5 * d.sigma * 1.03f64.powf(t / d.bin),
                    step: start + i * d.sample,
                    ..run.preshear[0]
                }
            })
            .collect();
        let stop = preshear_stop(&d, start, &samples).unwrap();
        let t = d.travel(samples[stop].step - start);
        assert!(
            t >= d.max_preshear && t < d.max_preshear + 0.05 * d.bin,
            "{t}"
        );
    }

    #[test]
    fn runs_mbgc_refuses_are_refused_as_mbgc_refuses_them() {
        let d = cell_deck(&cell(12.0), &params(), 3).unwrap();
        let mut run = synthetic(&d);
        run.free.push((0.005, [0.02, 0.02, 0.126]));
        let e = measure(&d, &run, 2600.0).unwrap_err().to_string();
        assert!(e.contains("1 grains passed through the lid"), "{e}");
        // A layer one grain heavier than mbgc's rule, or lighter than the layer's mass.
        let grain = 2600.0 * std::f64::consts::PI / 6.0 * 1e-6;
        for extra in [grain, -grain] {
            let mut run = synthetic(&d);
            run.glued.lid_mass += extra;
            let e = measure(&d, &run, 2600.0).unwrap_err().to_string();
            assert!(e.contains("as the lid"), "{e}");
        }
        let mut run = synthetic(&d);
        run.atoms = 99;
        let e = measure(&d, &run, 2600.0).unwrap_err().to_string();
        assert!(e.contains("1 of the 100 grains left the cell"), "{e}");
    }

    #[test]
    fn the_backend_has_the_engines_parameters() {
        for class in ["hertz,mindlin,epsd2", "hertz,mindlin,epsd2,sjkr"] {
            let c = ShearCell {
                class: ModelClass::parse(class).unwrap(),
                ..cell(12.0)
            };
            let e = LiggghtsShearCell::new(c.clone(), DeckMode::Run { ranks: 1 }).unwrap();
            assert_eq!(e.parameters(), c.parameters());
            assert_eq!(e.responses(), c.responses());
            assert!(!e
                .parameters()
                .iter()
                .any(|n| n.ends_with("_pw") || *n == "E_w"));
        }
    }

    #[test]
    fn zero_ranks_and_foreign_classes_are_refused() {
        let e = LiggghtsShearCell::new(cell(5.0), DeckMode::Run { ranks: 0 })
            .unwrap_err()
            .to_string();
        assert!(e.contains("--mpi 0"), "{e}");
        let c = ShearCell {
            class: ModelClass::parse("hertz,strict-coulomb,epsd2").unwrap(),
            ..cell(5.0)
        };
        let e = LiggghtsShearCell::new(c, DeckMode::Run { ranks: 1 })
            .unwrap_err()
            .to_string();
        assert!(e.contains("strict-coulomb"), "{e}");
    }

    /// A tiny cell (k = 5, about 150 spheres: the smallest cell mbgc accepts) through LIGGGHTS,
    /// when it is installed.
    #[test]
    #[ignore = "runs LIGGGHTS (about a minute)"]
    fn a_tiny_cell_runs_through_liggghts() {
        if super::super::binary::find_binary().is_none() {
            eprintln!("LIGGGHTS not installed: skipped");
            return;
        }
        let mut p = params();
        p.set("normal_stress", 2000.0)
            .set("E_p", 5e6)
            .set("d50", 4.0);
        let e = LiggghtsShearCell::new(cell(5.0), DeckMode::Run { ranks: 1 }).unwrap();
        e.check(&p).unwrap();
        let deck = e.deck(&p, 3).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let opts = RunOptions {
            work_dir: Some(dir.path().to_path_buf()),
            ..RunOptions::default()
        };
        let o = e.run(&p, 3, &opts).unwrap();
        let get = |n: &str| o.get(n).unwrap();
        assert!((100..200).contains(&o.diagnostics.particles), "{o:?}");
        let run = CellRun::read(dir.path()).unwrap();
        // The layers mbgc's rule glues (checked by the measurement), about 1.5 d_max of
        // grains each, and every grain still in the cell.
        let grain = 2600.0 * std::f64::consts::PI / 6.0 * 0.004f64.powi(3);
        assert_eq!(run.glued.floor, (deck.layer_mass / grain).ceil() as usize);
        assert_eq!(run.glued.lid, run.glued.floor);
        assert_eq!(run.atoms, run.inserted);
        // The load held the consolidation and pre-shear near their target on average.
        let mean = |s: &[Sample]| s.iter().map(|s| s.normal).sum::<f64>() / s.len() as f64;
        let last = &run.preshear[run.preshear.len() * 3 / 4..];
        assert!((mean(last) / 2000.0 - 1.0).abs() < 0.1, "{}", mean(last));
        for (f, t) in FAILURE_FRACTIONS.iter().zip(&run.failures) {
            let m = mean(&t.samples);
            assert!((m / (f * 2000.0) - 1.0).abs() < 0.15, "{f}: {m}");
        }
        // The pre-shear ran between mbgc's shortest and longest.
        let travel = deck.travel(run.preshear_end - run.preshear_start);
        assert!(
            travel >= deck.preshear - 0.5 * deck.bin && travel < deck.max_preshear + deck.bin,
            "{travel}"
        );
        // A cell this small gives a locus of noise in either engine: only that there is one
        // is tested.
        assert!(get("internal_friction").is_finite() && get("cohesion").is_finite());
        let points = o.diagnostics.warnings.last().unwrap();
        assert_eq!(
            points
                .split("in Pa: ")
                .nth(1)
                .map(|p| p.matches('(').count()),
            Some(3),
            "{o:?}"
        );
        // The bounds of mbgc's own small-cell test: a bed two grains thick between the layers
        // slides at ratios from about 0.17 to 0.55 from seed to seed in either engine.
        assert!((0.1..1.5).contains(&get("shear_ratio")), "{o:?}");
        assert!(
            (0.4 * 2600.0..0.75 * 2600.0).contains(&get("bulk_density")),
            "{o:?}"
        );
        // Read again from the finished directory, not run again: the same outcome.
        let again = e.run(&p, 3, &opts).unwrap();
        assert_eq!(again.responses, o.responses);
    }
}
