//! The shear box in mbgc against an independent LIGGGHTS 3.8 shear box that fills itself
//! ([`mbgc::liggghts::shear_box_fill`]): the bulk density is decided by the fill, which the
//! replay study cannot see. Both final states are measured by the same code as in the replay
//! study, and so are the states along the way (the insertion column, the bed before the
//! strike-off), so that a density gap can be traced to the stage where it opens.

use std::path::Path;

use mbgc::dem::analysis::sphere_box_volume;
use mbgc::dem::particles::Particles;
use mbgc::dem::vec3::V3;
use mbgc::error::{Error, Result};
use mbgc::experiments::shear_box::{box_bulk_density, measure_flank, RunRecord, ShearBox};
use mbgc::experiments::{ParamSet, RunOptions};
use mbgc::liggghts::fill_run::FillRun;
pub use mbgc::liggghts::shear_box_fill::fill_deck;
use mbgc::liggghts::shear_box_fill::{
    write_fill_deck, FillDeck, FILLED_DUMP, FINAL_DUMP, INPUT, INSERTED_DUMP, LOG, PRE_STRIKE_DUMP,
};
use mbgc::liggghts::{require_binary, run_deck};

/// One run of either code, measured by the same functions.
#[derive(Debug, Clone, Default)]
pub struct FillMeasure {
    pub shear_angle: f64,
    pub bulk_density: f64,
    pub flank_r2: f64,
    /// Particles created, and left in the box after the strike-off.
    pub inserted: usize,
    pub filled: usize,
    /// Solid fraction and height (m) of the insertion column: solid volume over base x height.
    pub column_fraction: f64,
    pub column_height: f64,
    /// Mean top of the bed before the strike-off, in box heights.
    pub bed_top: f64,
    /// Solid fraction before the strike-off in the core of the box, one d_max away from the
    /// walls, the floor and the rim: the packing without the wall layers.
    pub core_fraction: f64,
    /// Solid fraction of the whole box before the strike-off (spheres cut by the box's faces).
    pub box_fraction_pre: f64,
    /// The bulk density the bed before the strike-off gives under another strike-off rule, one
    /// a LIGGGHTS user may well write: every particle reaching above the rim deleted (not only
    /// those whose centre is above), the rest counted whole.
    pub top_rule_density: f64,
    pub fill_steps: u64,
    /// Time steps of the whole run (LIGGGHTS: summed over its `run` commands).
    pub steps: u64,
}

/// (radius, position) of particles.
type Spheres = Vec<(f64, V3)>;

fn solid_in(s: &Spheres, lo: V3, hi: V3) -> f64 {
    s.iter()
        .map(|(r, x)| sphere_box_volume(*x, *r, lo, hi))
        .sum()
}

/// Column fraction and height of the initial particles.
fn column(s: &Spheres, size: V3) -> (f64, f64) {
    let (z0, z1) = s
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (r, x)| {
            (a.min(x[2] - r), b.max(x[2] + r))
        });
    let v: f64 = s
        .iter()
        .map(|(r, _)| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3))
        .sum();
    (v / (size[0] * size[1] * (z1 - z0)), z1 - z0)
}

/// Mean top of the bed over columns of width d_max, in box heights.
fn bed_top(s: &Spheres, size: V3, d_max: f64) -> f64 {
    let n = ((size[0] / d_max).floor() as usize).max(1);
    let m = ((size[1] / d_max).floor() as usize).max(1);
    let mut top = vec![f64::NAN; n * m];
    for (r, x) in s {
        if x[0] < 0.0 || x[0] >= size[0] || x[1] < 0.0 || x[1] >= size[1] {
            continue;
        }
        let k = ((x[1] / size[1] * m as f64) as usize).min(m - 1) * n
            + ((x[0] / size[0] * n as f64) as usize).min(n - 1);
        if top[k].is_nan() || x[2] + r > top[k] {
            top[k] = x[2] + r;
        }
    }
    let t: Vec<f64> = top.into_iter().filter(|t| !t.is_nan()).collect();
    t.iter().sum::<f64>() / t.len().max(1) as f64 / size[2]
}

fn bed(s: &Spheres, size: V3, d_max: f64, rho: f64, m: &mut FillMeasure) {
    let [l, w, h] = size;
    let lo = [d_max; 3];
    let hi = [l - d_max, w - d_max, h - d_max];
    let core_vol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    m.core_fraction = solid_in(s, lo, hi) / core_vol;
    m.box_fraction_pre = solid_in(s, [0.0; 3], size) / (l * w * h);
    m.bed_top = bed_top(s, size, d_max);
    m.top_rule_density = rho
        * s.iter()
            .filter(|(r, x)| x[2] + r <= h)
            .map(|(r, x)| sphere_box_volume(*x, *r, [0.0; 3], size))
            .sum::<f64>()
        / (l * w * h);
}

/// mbgc's own run, with the extra measures taken from its run record (returned for a replay).
pub fn run_mbgc(sb: &ShearBox, p: &ParamSet, seed: u64) -> Result<(FillMeasure, RunRecord)> {
    let (o, rec) = sb.run_recorded(p, seed, &RunOptions::default())?;
    let size = rec.layout.size;
    let initial: Spheres = rec
        .layout
        .diameters
        .iter()
        .map(|d| 0.5 * d)
        .zip(rec.initial_positions.iter().copied())
        .collect();
    let (column_fraction, column_height) = column(&initial, size);
    let mut m = FillMeasure {
        shear_angle: o.get("shear_angle").unwrap_or(f64::NAN),
        bulk_density: o.get("bulk_density").unwrap_or(f64::NAN),
        flank_r2: o.get("flank_r2").unwrap_or(f64::NAN),
        inserted: initial.len(),
        filled: o.diagnostics.particles,
        column_fraction,
        column_height,
        fill_steps: rec.fill_steps,
        ..Default::default()
    };
    let rho = p.get("rho_p").unwrap_or(f64::NAN);
    bed(&rec.filled, size, rec.layout.d_max, rho, &mut m);
    Ok((m, rec))
}

/// Runs the deck in `dir` and measures it as mbgc's run is measured.
pub fn run_liggghts(dir: &Path, p: &ParamSet, deck: &FillDeck, d_max: f64) -> Result<FillMeasure> {
    let binary = require_binary()?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    for stale in [INSERTED_DUMP, PRE_STRIKE_DUMP, FILLED_DUMP, FINAL_DUMP, LOG] {
        let f = dir.join(stale);
        if f.exists() {
            std::fs::remove_file(&f).map_err(|e| Error::io(&f, e))?;
        }
    }
    write_fill_deck(dir, p, deck)?;
    run_deck(&binary, dir, INPUT, LOG)?;
    let run = FillRun::read(dir)?;
    let size = deck.size;
    let rho = p.get("rho_p").unwrap_or(f64::NAN);
    let mut fp = Particles::new();
    for (r, x) in &run.last {
        // Density is irrelevant to the geometric measures.
        let _ = fp.add(*x, *r, 1.0, 0);
    }
    let flank = measure_flank(&fp, size, d_max);
    let (column_fraction, column_height) = column(&run.inserted, size);
    let mut m = FillMeasure {
        shear_angle: (-flank.slope).atan().to_degrees(),
        bulk_density: box_bulk_density(run.filled.iter().copied(), rho, size),
        flank_r2: flank.r2,
        inserted: run.inserted.len(),
        filled: run.filled.len(),
        column_fraction,
        column_height,
        fill_steps: run.fill_steps,
        steps: run.steps,
        ..Default::default()
    };
    bed(&run.pre_strike, size, d_max, rho, &mut m);
    Ok(m)
}

/// Mean and standard error.
pub fn mean_se(v: &[f64]) -> (f64, f64) {
    let (m, sd) = mbgc::numeric::mean_sd(v);
    (m, sd / (v.len() as f64).sqrt())
}

impl FillMeasure {
    /// One tab-separated row (see [`FillMeasure::HEADER`]).
    pub fn row(&self) -> String {
        format!(
            "{:.3}\t{:.1}\t{:.3}\t{}\t{}\t{:.4}\t{:.4}\t{:.4}\t{:.4}\t{:.4}\t{:.1}\t{}",
            self.shear_angle,
            self.bulk_density,
            self.flank_r2,
            self.inserted,
            self.filled,
            self.column_fraction,
            self.column_height,
            self.bed_top,
            self.core_fraction,
            self.box_fraction_pre,
            self.top_rule_density,
            self.fill_steps
        )
    }
    pub const HEADER: &'static str = "angle\tbulk\tr2\tinserted\tfilled\tcol_frac\tcol_h\tbed_top\tcore_frac\tbox_frac_pre\ttop_rule_bulk\tfill_steps";
}
