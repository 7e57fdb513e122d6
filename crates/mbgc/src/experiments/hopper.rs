//! Flat-bottom hopper discharge (seed 000, Yan et al. 2015): a cylinder (D = 50 mm, H = 70 mm)
//! with a central orifice (D_o = 15 mm) in its flat bottom discharges onto a flat plate 70 mm
//! below. Responses: the flow rate, the repose angle of the material left in the container
//! (`repose_angle_top`) and of the pile on the plate (`repose_angle_bottom`).
//!
//! Procedure
//! 1. Fill: `fill_mass` of particles (d50 and sigma_ln; log-normal drawn by number with
//!    [`draw_by_number`], monosized when sigma_ln is absent or 0) poured at random, none
//!    touching, at a solid fraction of 0.2 in the cylinder above the closed orifice (a disk
//!    shutter); a fill tube above the rim holds the column if it is taller than the container.
//!    (Before the clogging silo's review the fill was a lattice spaced for the largest
//!    particle, which stood a wide distribution 2-3 m tall; docs/propagation.md.) Settle until
//!    the translational kinetic energy is small (EPSD2 has no rolling dashpot, so rotation keeps the total energy high long after
//!    the packing is at rest).
//! 2. Measure the bulk density of the settled fill: the solid fraction of the cylinder from the
//!    bottom to one d_max below the mean free surface (the rough top would count as voids),
//!    times rho_p. Wall layers are included, as in a measuring cylinder.
//! 3. Remove the shutter and discharge until no particle has passed the orifice for
//!    4 sqrt(D_o / g) and the particles in the container and on the plate have come to rest.
//!    Particles that roll off the collection plate (radius 3 D) fall onto a floor inside a catch
//!    cylinder: they stay in the simulation, count as discharged, and take no part in the rest
//!    criterion or the pile angle. The domain holds the catch cylinder, so nothing leaves it.
//!
//! Responses
//! - `flow_rate` (kg/s): slope of a least-squares line through the discharged mass against time
//!   between 10 % and 50 % of the finally discharged mass ([`FLOW_WINDOW`]). A particle counts as
//!   discharged when its centre is one d_max below the orifice plane; the mass is sampled every
//!   millisecond (times sqrt(scale)).
//! - `repose_angle_top`, `repose_angle_bottom` (degrees): the mean of four angles, one per
//!   quarter sector around the half-planes +x, +y, -x, -y (seed 000's orthoslices, widened to
//!   use all the material). A sector is cut into radial bins one d50 wide, each bin into cells
//!   of about 2 d50 of arc; the bin's surface height is the median over its cells of the highest
//!   particle top (a fixed cell size keeps the maximum from growing with the bin's area). A line
//!   is fitted to the bins' surface heights between 20 % and 80 % of the sector's highest,
//!   walking from the wall inward (top) or from the apex outward (bottom) and stopping at the
//!   first bin below 20 % or with fewer than half its cells occupied: the flat rest of a shallow
//!   fill, the crater floor, the toe of the pile and scattered particles are left out.
//! - a clog: a discharge that stops before half the material standing over the orifice has left
//!   ([`clogged`]: `discharged_fraction` below 0.5 (D_o / D)^2) was stopped by an arch. It has
//!   no steady flow, crater or pile, so `flow_rate`, `beverloo_ratio` and the repose angles
//!   ([`VOIDED_BY_CLOG`] and the sector angles) are NaN and the run warns; `discharged_fraction` is the avalanche
//!   before the arch. The event is `clogged` ([`Experiment::events`]), which a propagation
//!   counts.
//! - a late clog: a discharge that flowed past that share and came to rest with an arch over
//!   the orifice (`arch_held` > 0, [`clogged_late`]). Its flow, crater and pile are those of a
//!   discharge an arch cut short, not the ones seed 000 measures: after an early arch the
//!   flow-rate window (10-50 % of what left) lies in the first few per cent of the fill, where
//!   the arch was forming (row 8 of the gravel propagation, stopped at 8.8 %, ran at 1.09 kg/s
//!   against 1.66 or more for every free discharge). So the same responses as a clog's are NaN
//!   ([`VOIDED_BY_CLOG`]).
//!   The event is `clogged_late`; `clogged` and `clogged_late` together are the runs whose
//!   orifice ended blocked.
//! - an intermittent discharge: the binned flow rate falls below half its peak and rises again
//!   by a quarter of it ([`intermittent`]): an arch formed and collapsed. It has no steady
//!   rate, so `flow_rate` and `beverloo_ratio` are NaN ([`VOIDED_BY_INTERMITTENT`]) and the run
//!   warns; the angles stand. The event is `intermittent`, a lower bound (a stall after the
//!   last bin is not seen).
//! - diagnostics: `discharged_mass` (kg), `discharged_fraction`, `flow_R2` (of the flow-rate fit),
//!   `bulk_density` (kg/m^3, settled fill), `beverloo_ratio` (flow_rate over
//!   [`beverloo_flow_rate`] with the measured bulk density and d50), `arch_held` (the particles
//!   at rest wholly over the orifice at the end: 0 after a free discharge, whose crater walls
//!   stand outside the orifice's edge; NaN when the run ended before it came to rest).
//! - the flow rate against time: `flow_rate_t1` .. `flow_rate_t8` (kg/s), the mean rate in
//!   consecutive bins of `flow_bin_width` seconds from the opening of the shutter. The width is
//!   [`FLOW_BIN_WIDTH`] of the [`nominal_discharge_time`], which does not depend on friction or
//!   restitution, so every run of a campaign over those is binned at the same times; eight bins
//!   reach 1.2 nominal times, into the decline that follows the steady flow.
//! - the four sector angles of each surface, `repose_angle_top_1` .. `repose_angle_bottom_4`
//!   (seed 000 keeps its four orthoslice angles as replicates for the lack-of-fit test).
//!
//! The `scale` setting (default 1) multiplies every length of the apparatus (and the fill mass
//! by scale^3, so the fill height stays the same fraction of the container); the particles keep
//! their size. Use it to keep D_o / d and the particle count sensible for very small or large
//! particles. The angles have no length scale: scaling changes them only through D / d, D_o / d
//! and the drop height in d. The flow rate does: it follows Beverloo,
//! W = C rho_b sqrt(g) (scale D_o - k d)^(5/2), so a run with scale s and particles d matches the
//! unscaled apparatus with particles d / s when multiplied by s^(-5/2).
//!
//! For a campaign over d50, `scale = d50 / 2 mm` keeps the particle count, D / d and the pile
//! (in particles) of the 2 mm default: the bottom angle needs a pile of some 2500 particles
//! (measured: 2900 discharged 2 mm beads form a 27 degree pile, 700 of 3 mm a 10 degree mound,
//! and low friction spreads them into a layer with no angle at all: NaN and a warning).
//!
//! Cost (one core, default fill, E = 1e7 Pa): d50 = 3 mm, 1400 particles, ~110k steps, ~20 s;
//! d50 = 2 mm, 4800 particles, ~170k steps, ~1.5-2.5 min. Most of the simulated time is the
//! discharge (2-3 s, a third of it the slow trickle while the crater relaxes).
//!
//! Time step: 0.2 of the Rayleigh time of the smallest particle (E_p, nu_p, rho_p). Contact
//! model: the campaign's model class (by default Hertz-Mindlin with EPSD2 rolling friction). Seed 000
//! found the Young's modulus to change neither the flow rate nor the angles over 0.02-200 GPa;
//! a soft E_p (1e7 Pa) keeps a run affordable. Measured here (d50 = 3 mm, default fill): E_p =
//! E_w = 1e7 -> 1e8 Pa moved the flow rate from 0.0275 to 0.0271 kg/s and the top angle from 33
//! to 35 degrees (means over 3 and 2 seeds), inside the seed-to-seed scatter (9 %, 1-2 degrees).

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    materials_from, with_class_parameters, Diagnostics, Experiment, Outcome, ParamSet, RunOptions,
    RHO_RANGE,
};
use crate::error::{write_atomic, Error, Result};
use crate::psd::{draw_by_number, sizes_drawn, Distribution};
use mbgc_dem::analysis::sphere_box_volume;
use mbgc_dem::contact::{ModelClass, Pair};
use mbgc_dem::material::Materials;
use mbgc_dem::particles::Particles;
use mbgc_dem::sim::{Scene, Simulation};
use mbgc_dem::timestep::rayleigh_time;
use mbgc_dem::vec3::V3;
use mbgc_dem::walls::{Shape, Wall};

/// Container diameter, height, orifice diameter and orifice-to-plate distance of seed 000, m.
pub const CONTAINER_DIAMETER: f64 = 0.050;
/// Container height at scale 1, m (seed 000: 70 mm).
pub const CONTAINER_HEIGHT: f64 = 0.070;
/// Orifice diameter at scale 1, m (seed 000: 15 mm, ~7 d of 2 mm particles).
pub const ORIFICE_DIAMETER: f64 = 0.015;
/// Distance from the orifice plane down to the collection plate at scale 1, m (seed 000: 70 mm).
pub const DROP_HEIGHT: f64 = 0.070;
/// Collection plate radius in container diameters: the piles of the default fill reach about
/// 1 D from the axis.
pub const PLATE_RADIUS_FACTOR: f64 = 3.0;
/// Default fill mass at scale 1, kg: a fill about 20 mm high (settled bulk density ~1330
/// kg/m^3), ~1.3 D_o, the least at which the flow reaches its steady (Beverloo) rate, and high
/// enough for a crater of up to ~45 degrees to run from the orifice edge to the wall. That is
/// ~4800 particles at d50 = 2 mm and ~1400 at 3 mm, a third of seed 000's fill (~14,700 of
/// 2 mm, 0.154 kg); the discharge then takes 2-3 s of simulated time.
pub const DEFAULT_FILL_MASS: f64 = 0.05;
/// Beverloo constants (Beverloo et al. 1961; Nedderman 1992): C ~ 0.58, k ~ 1.5.
pub const BEVERLOO_C: f64 = 0.58;
/// Beverloo's empty-annulus constant k: the orifice acts as if it were k d narrower.
pub const BEVERLOO_K: f64 = 1.5;
/// Gravitational acceleration, m/s^2, acting along -z.
pub const GRAVITY: f64 = 9.81;
/// Fractions of the finally discharged mass between which the flow rate is fitted. The rate is
/// constant until the crater reaches the orifice; for fills lower than the container diameter
/// that happens well before 80 % has left, so 20-80 % would mix in the decay. Measured at
/// d50 = 3 mm: a 20 mm fill gives 0.0247 kg/s in 10-50 % against 0.0248 for a 46 mm fill, while
/// its 20-80 % slope is 25 % lower.
pub const FLOW_WINDOW: (f64, f64) = (0.1, 0.5);
/// Flow rate against time: the mean rate in [`FLOW_BINS`] consecutive bins, each
/// [`FLOW_BIN_WIDTH`] nominal discharge times wide ([`nominal_discharge_time`]).
pub const FLOW_BINS: usize = 8;
/// Width of each flow-rate bin as a fraction of the nominal discharge time; 8 bins of 0.15 cover
/// 1.2 nominal times.
pub const FLOW_BIN_WIDTH: f64 = 0.15;
/// Packing fraction of the nominal discharge time: a typical settled random packing.
pub const NOMINAL_PACKING: f64 = 0.6;
/// Time step as a fraction of the Rayleigh time of the smallest particle.
pub const DT_FRACTION: f64 = 0.2;
/// Most particles a run may hold.
pub const MAX_PARTICLES: usize = 2_000_000;
/// Smallest orifice diameter in largest particle diameters: below ~4 d_max the orifice bridges.
pub const MIN_ORIFICE_RATIO: f64 = 4.0;
/// The share of the fill that stands over the orifice, (D_o / D)^2 = 0.09: the settled fill is a
/// flat layer, and a discharge that no arch stops empties this column at least down to a
/// vertical rathole, because the material left behind rises from the orifice's edge.
pub const OVER_ORIFICE_SHARE: f64 =
    (ORIFICE_DIAMETER / CONTAINER_DIAMETER) * (ORIFICE_DIAMETER / CONTAINER_DIAMETER);

/// A discharge that stopped below this share of the fill clogged ([`clogged`]): half the column
/// over the orifice, so that a free discharge leaving a near-vertical rathole (about the whole
/// column, give or take its scatter) is not taken for a clog. Measured on the gravel
/// propagation (docs/propagation.md): clogged runs stopped at 1.9-3.1 %, free ones at 21 % or
/// more.
pub const CLOG_SHARE: f64 = 0.5 * OVER_ORIFICE_SHARE;

/// The responses a clogged run has no value of, besides the sector angles
/// ([`SECTOR_ANGLE_NAMES`]): the flow rate (the few particles before the arch are no steady
/// flow), Beverloo's ratio, and the angles of the crater and the pile it never formed. A reader
/// of an older table voids the same ([`Experiment::voided_by`]).
pub const VOIDED_BY_CLOG: [&str; 4] = [
    "flow_rate",
    "beverloo_ratio",
    "repose_angle_top",
    "repose_angle_bottom",
];

/// The event of a clogged orifice ([`clogged`]).
pub const CLOGGED: &str = "clogged";
/// The event of an orifice an arch blocked after a steady flow ([`clogged_late`]).
pub const CLOGGED_LATE: &str = "clogged_late";

/// The event of a discharge that stalled and started again ([`intermittent`]).
pub const INTERMITTENT: &str = "intermittent";

/// An intermittent discharge: the binned flow rate fell below this share of its peak so far...
pub const STALL_SHARE: f64 = 0.5;
/// ...and then rose again by at least this share of that peak. A free discharge declines
/// steadily once its crater reaches the wall; its tail bins wobble by a few hundredths of the
/// peak. On the 89 hopper runs in docs/data (53 draws of the gravel propagation and seed 000's
/// 36-run sensitivity design) one run qualifies: row 22 of the gravel propagation, 1.02, 0.41, 0.24, then 0.87 and
/// 1.22 kg/s, a rise of 0.96 of its peak; the largest rise after a dip among the others is 0.027
/// of the peak (row 27).
pub const RESTART_SHARE: f64 = 0.25;

/// The responses an intermittent run has no value of: a flow that stalls has no steady rate,
/// so neither `flow_rate` nor Beverloo's ratio means anything. The crater and the pile it
/// leaves are measured as usual.
pub const VOIDED_BY_INTERMITTENT: [&str; 2] = ["flow_rate", "beverloo_ratio"];

/// Whether the binned flow rates (`flow_rate_t1` ..) show a discharge that stalled and
/// restarted: after falling below [`STALL_SHARE`] of its peak so far, the rate rose again by
/// [`RESTART_SHARE`] of that peak (an arch that formed and collapsed). False when a bin is not
/// finite (an unfinished series). Like [`clogged`], a lower bound: a stall after the last bin,
/// or shorter than a bin, is not seen.
pub fn intermittent(bins: &[f64]) -> bool {
    if bins.iter().any(|b| !b.is_finite()) {
        return false;
    }
    let (mut peak, mut low) = (0.0f64, f64::INFINITY);
    for &b in bins {
        if low.is_finite() && b - low >= RESTART_SHARE * peak {
            return true;
        }
        if b > peak {
            peak = b;
            low = f64::INFINITY;
        } else if b < STALL_SHARE * peak {
            low = low.min(b);
        }
    }
    false
}

/// Whether a discharge that stopped at `discharged_fraction` of the fill clogged: an arch over
/// the orifice stopped it before half the material standing over the orifice had left
/// ([`CLOG_SHARE`]). The rule reads only a recorded response, so a table written before runs
/// were voided is read alike. An arch that forms later is [`clogged_late`]; a flow that stops
/// and starts again is [`intermittent`].
pub fn clogged(discharged_fraction: f64) -> bool {
    discharged_fraction < CLOG_SHARE
}

/// Whether a discharge that flowed past [`CLOG_SHARE`] came to rest with `arch_held` particles
/// held over the orifice: an arch that formed late. False when the count is not finite (a run
/// that ended before it came to rest, or a table written before the hopper recorded it, whose
/// late arches are then only in the warnings).
pub fn clogged_late(discharged_fraction: f64, arch_held: f64) -> bool {
    discharged_fraction.is_finite()
        && !clogged(discharged_fraction)
        && arch_held.is_finite()
        && arch_held > 0.0
}

/// Beverloo's mass flow rate W = C rho_b sqrt(g) (D_o - k d)^(5/2), kg/s (SI units; 0 if
/// D_o <= k d).
pub fn beverloo_flow_rate(bulk_density: f64, orifice_diameter: f64, particle_diameter: f64) -> f64 {
    let free = (orifice_diameter - BEVERLOO_K * particle_diameter).max(0.0);
    BEVERLOO_C * bulk_density * GRAVITY.sqrt() * free.powf(2.5)
}

/// The time Beverloo's rate takes to discharge `fill_mass` at a packing of [`NOMINAL_PACKING`],
/// s. It depends on the fill, the apparatus and the particles' size and density only, not on
/// friction or restitution, so the flow-rate bins of a campaign over those sit at the same
/// times in every run (seed 000 compares the flow rate of its 36 runs at t = 1, 2, 3, 4 s).
pub fn nominal_discharge_time(
    fill_mass: f64,
    rho_p: f64,
    orifice_diameter: f64,
    particle_diameter: f64,
) -> f64 {
    fill_mass / beverloo_flow_rate(NOMINAL_PACKING * rho_p, orifice_diameter, particle_diameter)
}

/// Mean flow rate (kg/s) in the bins [(k - 1) w, k w], k = 1..=bins, of the discharge series
/// (mass interpolated linearly between samples). A bin that starts after a finished discharge
/// (`finished`) has rate 0; one that runs past the end of an unfinished series is NaN.
pub fn binned_flow_rates(
    series: &DischargeSeries,
    width: f64,
    bins: usize,
    finished: bool,
) -> Vec<f64> {
    let end = series.time_s.last().copied().unwrap_or(0.0);
    let mass_at = |t: f64| -> f64 {
        let ts = &series.time_s;
        let ms = &series.mass_kg;
        if ts.is_empty() {
            return 0.0;
        }
        if t >= end {
            return ms[ms.len() - 1];
        }
        let k = ts.partition_point(|&x| x <= t).max(1);
        let (t0, t1) = (ts[k - 1], ts[k]);
        let f = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
        ms[k - 1] + f * (ms[k] - ms[k - 1])
    };
    (1..=bins)
        .map(|k| {
            let (a, b) = ((k - 1) as f64 * width, k as f64 * width);
            if b > end && !finished {
                f64::NAN
            } else {
                (mass_at(b) - mass_at(a)) / width
            }
        })
        .collect()
}

/// Response names of the flow-rate bins ([`FLOW_BINS`] of them).
pub const FLOW_BIN_NAMES: [&str; FLOW_BINS] = [
    "flow_rate_t1",
    "flow_rate_t2",
    "flow_rate_t3",
    "flow_rate_t4",
    "flow_rate_t5",
    "flow_rate_t6",
    "flow_rate_t7",
    "flow_rate_t8",
];

/// Response names of the per-sector angles (sectors around +x, +y, -x, -y): seed 000's four
/// orthoslice angles per surface, kept so that a fit can use them as replicates.
pub const SECTOR_ANGLE_NAMES: [&str; 8] = [
    "repose_angle_top_1",
    "repose_angle_top_2",
    "repose_angle_top_3",
    "repose_angle_top_4",
    "repose_angle_bottom_1",
    "repose_angle_bottom_2",
    "repose_angle_bottom_3",
    "repose_angle_bottom_4",
];

/// The apparatus at a given scale, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// Container radius, m.
    pub radius: f64,
    /// Container height above the orifice plane, m.
    pub height: f64,
    /// Orifice radius, m.
    pub orifice_radius: f64,
    /// Distance from the orifice plane (z = 0) down to the collection plate.
    pub drop: f64,
    /// Radius of the collection plate, m; particles beyond it fall into the catch cylinder.
    pub plate_radius: f64,
}

impl Geometry {
    /// Seed 000's apparatus with every length multiplied by `scale` (> 0).
    pub fn scaled(scale: f64) -> Geometry {
        Geometry {
            radius: 0.5 * CONTAINER_DIAMETER * scale,
            height: CONTAINER_HEIGHT * scale,
            orifice_radius: 0.5 * ORIFICE_DIAMETER * scale,
            drop: DROP_HEIGHT * scale,
            plate_radius: PLATE_RADIUS_FACTOR * CONTAINER_DIAMETER * scale,
        }
    }
}

/// Discharged mass against time since the shutter opened.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DischargeSeries {
    /// Sample times since the shutter opened, s, every millisecond times sqrt(scale).
    pub time_s: Vec<f64>,
    /// Mass discharged by each sample time, kg (particle centres one d_max below the orifice
    /// plane).
    pub mass_kg: Vec<f64>,
}

impl DischargeSeries {
    /// The series as CSV text with the header `time_s,discharged_mass_kg`.
    pub fn to_csv(&self) -> String {
        let mut s = String::with_capacity(32 * self.time_s.len() + 32);
        s.push_str("time_s,discharged_mass_kg\n");
        for (t, m) in self.time_s.iter().zip(&self.mass_kg) {
            let _ = writeln!(s, "{t:.6},{m:.9e}");
        }
        s
    }
}

/// Writes the discharge series as CSV (atomically).
pub fn write_series_csv(path: &Path, series: &DischargeSeries) -> Result<()> {
    write_atomic(path, series.to_csv().as_bytes())
}

/// Least-squares slope (kg/s) and R^2 of the discharged mass against time between the fractions
/// `lo` and `hi` of the final discharged mass; NaN when fewer than three samples lie there.
pub fn flow_rate_fit(series: &DischargeSeries, lo: f64, hi: f64) -> (f64, f64) {
    let total = series.mass_kg.last().copied().unwrap_or(0.0);
    let pts: Vec<(f64, f64)> = series
        .time_s
        .iter()
        .zip(&series.mass_kg)
        .filter(|(_, &m)| m >= lo * total && m <= hi * total)
        .map(|(&t, &m)| (t, m))
        .collect();
    if total <= 0.0 {
        return (f64::NAN, f64::NAN);
    }
    match line_fit(&pts) {
        Some((slope, _, r2)) => (slope, r2),
        None => (f64::NAN, f64::NAN),
    }
}

/// Least-squares line y = a x + b: (a, b, R^2), or None with fewer than 3 points or no spread
/// in x.
fn line_fit(pts: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    if pts.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = pts.iter().map(|p| (p.1 - my).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let a = sxy / sxx;
    let r2 = if syy > 0.0 {
        sxy * sxy / (sxx * syy)
    } else {
        1.0
    };
    Some((a, my - a * mx, r2))
}

/// Which surface a repose angle is measured on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Surface {
    /// Material left in the container: rises from the orifice to the wall.
    Top,
    /// Pile on the plate: falls from the apex outward.
    Bottom,
}

/// Repose angles (degrees) in the four quarter sectors around the half-planes +x, +y, -x, -y
/// (NaN where fewer than three surface points qualify); see the module doc. `base` is the height
/// of the supporting plate, `reach` the largest radius considered, `d` the radial bin width.
pub fn repose_angles(
    x: &[V3],
    r: &[f64],
    surface: Surface,
    base: f64,
    reach: f64,
    d: f64,
) -> [f64; 4] {
    let bins = ((reach / d).ceil() as usize).max(1);
    // Cells of about 2 d of arc per radial bin: the same area everywhere, so the highest top per
    // cell is not biased upward where a bin holds more particles.
    let cells: Vec<usize> = (0..bins)
        .map(|b| ((0.5 * PI * (b as f64 + 0.5) * d / (2.0 * d)) as usize).max(1))
        .collect();
    let start: Vec<usize> = cells
        .iter()
        .scan(0, |acc, &c| {
            let s = *acc;
            *acc += c;
            Some(s)
        })
        .collect();
    let total = start[bins - 1] + cells[bins - 1];
    std::array::from_fn(|k| {
        let centre = 0.5 * PI * k as f64;
        let mut top = vec![f64::NEG_INFINITY; total];
        for (xi, &ri) in x.iter().zip(r) {
            let rho = xi[0].hypot(xi[1]);
            if rho >= reach {
                continue;
            }
            // Azimuth relative to the sector's centre, in [-pi, pi).
            let phi = (xi[1].atan2(xi[0]) - centre + 3.0 * PI).rem_euclid(2.0 * PI) - PI;
            if phi.abs() >= 0.25 * PI {
                continue;
            }
            let b = ((rho / d) as usize).min(bins - 1);
            let c = (((phi + 0.25 * PI) / (0.5 * PI) * cells[b] as f64) as usize).min(cells[b] - 1);
            let t = &mut top[start[b] + c];
            *t = t.max(xi[2] + ri - base);
        }
        // Surface per bin: the median of its cells' highest tops; a bin with fewer than half its
        // cells occupied has no surface (the crater floor, the toe of the pile).
        let prof: Vec<Option<f64>> = (0..bins)
            .map(|b| {
                let mut h: Vec<f64> = top[start[b]..start[b] + cells[b]]
                    .iter()
                    .copied()
                    .filter(|v| v.is_finite())
                    .collect();
                if 2 * h.len() < cells[b] || h.is_empty() {
                    return None;
                }
                h.sort_by(f64::total_cmp);
                Some(h[h.len() / 2])
            })
            .collect();
        let h_max = prof.iter().flatten().copied().fold(0.0, f64::max);
        let (lo, hi) = (0.2 * h_max, 0.8 * h_max);
        // Walk from the high end of the surface to the low end and keep the last contiguous run
        // of bins inside [lo, hi]: a bin above hi (roughness at the upper edge of the band)
        // starts the run afresh, the first empty bin or bin below lo after it ends it.
        let order: Vec<usize> = match surface {
            Surface::Top => (0..bins).rev().collect(),
            Surface::Bottom => (0..bins).collect(),
        };
        let mut pts = Vec::new();
        for b in order {
            match prof[b] {
                Some(h) if h <= hi && h >= lo => pts.push(((b as f64 + 0.5) * d, h)),
                Some(h) if h > hi => pts.clear(),
                None if pts.is_empty() => {}
                _ => break,
            }
        }
        match line_fit(&pts) {
            Some((a, _, _)) => {
                let slope = if surface == Surface::Top { a } else { -a };
                slope.atan().to_degrees()
            }
            None => f64::NAN,
        }
    })
}

/// Mean free-surface height: the highest particle top in square columns 4 r_max wide, averaged
/// over the columns. As `analysis::free_surface_height`, but summed in column order: that one
/// sums in hash-map order, which changes the last bits from run to run.
fn surface_height(x: &[V3], r: &[f64]) -> f64 {
    let side = 4.0 * r.iter().copied().fold(0.0, f64::max);
    let mut tops = std::collections::BTreeMap::new();
    for (p, &ri) in x.iter().zip(r) {
        let col = ((p[0] / side).floor() as i64, (p[1] / side).floor() as i64);
        let t = tops.entry(col).or_insert(f64::NEG_INFINITY);
        *t = f64::max(*t, p[2] + ri);
    }
    tops.values().sum::<f64>() / tops.len() as f64
}

/// Solid fraction of the cylinder of radius `radius` from the bottom (z = 0) up to `height`: the
/// volume of the spheres' parts inside that slab over the slab's volume (all particles are inside
/// the cylinder, so a square in x-y cuts nothing more). Measured a d_max below the free surface,
/// whose roughness would otherwise count as empty volume.
fn fill_fraction(p: &Particles, radius: f64, height: f64) -> f64 {
    if height.is_nan() || height <= 0.0 {
        return f64::NAN;
    }
    let (lo, hi) = ([-radius, -radius, 0.0], [radius, radius, height]);
    let solid: f64 =
        p.x.iter()
            .zip(&p.r)
            .map(|(x, &r)| sphere_box_volume(*x, r, lo, hi))
            .sum();
    solid / (PI * radius * radius * height)
}

/// Mean of the finite values, NaN if none.
fn finite_mean(v: &[f64]) -> f64 {
    let f: Vec<f64> = v.iter().copied().filter(|a| a.is_finite()).collect();
    if f.is_empty() {
        f64::NAN
    } else {
        f.iter().sum::<f64>() / f.len() as f64
    }
}

/// The flat-bottom hopper discharge experiment. Parameters: [`OWN_PARAMETERS`] (d50 in mm), the
/// model class's (seed 004's class: e_pp, e_pw, mu_pp, mu_pw, mu_r_pp, mu_r_pw), sigma_ln
/// (optional, 0 or absent: monosized); settings `fill_mass` (kg at scale 1, default
/// [`DEFAULT_FILL_MASS`]) and `scale` (default 1).
#[derive(Debug, Clone, Copy, Default)]
pub struct Hopper {
    /// The effects of the contact law.
    pub class: ModelClass,
}

/// The parameters the hopper needs whatever the model class.
pub const OWN_PARAMETERS: [&str; 5] = ["E_p", "E_w", "nu_p", "rho_p", "d50"];

/// Everything a run measured, beyond the [`Outcome`].
#[derive(Debug, Clone)]
pub struct HopperRun {
    /// Responses and diagnostics as every experiment reports them.
    pub outcome: Outcome,
    /// Discharged mass against time, from which the flow rate and its time bins are computed.
    pub series: DischargeSeries,
    /// The apparatus as run (at the run's `scale`).
    pub geometry: Geometry,
    /// Per quarter sector (around +x, +y, -x, -y), degrees; NaN where no surface qualified.
    pub top_angles: [f64; 4],
    /// Repose angles of the pile on the plate per quarter sector, degrees; NaN where no surface
    /// qualified.
    pub bottom_angles: [f64; 4],
    /// Particles at the end: in the container (above the orifice plane, inside the cylinder),
    /// below the orifice plane on the plate, and fallen off the plate.
    pub in_container: usize,
    /// Particles on the collection plate at the end (below the orifice plane, within its radius).
    pub on_plate: usize,
    /// Particles that rolled off the plate into the catch cylinder; they count as discharged.
    pub off_plate: usize,
    /// Particles that ever passed one d_max below the orifice plane.
    pub passed: usize,
    /// Mean free-surface height of the settled fill above the orifice plane, m.
    pub fill_height: f64,
    /// Bulk density of the settled fill, kg/m^3: rho_p times the solid fraction below one d_max
    /// under the free surface.
    pub bulk_density: f64,
    /// Time steps of the fill-and-settle stage.
    pub settle_steps: u64,
    /// Simulated time from opening the shutter to the stop criterion, s.
    pub discharge_time: f64,
    /// Time step, s: 0.2 of the Rayleigh time of the smallest particle.
    pub dt: f64,
}

/// A checked parameter set.
struct Setup {
    materials: Materials,
    grain: u16,
    wall: u16,
    rho: f64,
    /// d50, m.
    d50: f64,
    dist: Option<Distribution>,
    /// Size range drawn, m.
    d_min: f64,
    d_max: f64,
    scale: f64,
    /// Fill mass at this scale, kg.
    fill_mass: f64,
    geo: Geometry,
    dt: f64,
}

/// Packing fraction assumed by [`Experiment::check`] to see whether a fill fits (looser than any
/// settled random packing, so a fill that passes fits).
const CHECK_PACKING: f64 = 0.5;

impl Hopper {
    fn setup(&self, p: &ParamSet) -> Result<Setup> {
        let (materials, grain, wall) = materials_from(p, &self.class)?;
        let rho = p.require("rho_p", RHO_RANGE.0, RHO_RANGE.1)?;
        let d50_mm = p.require("d50", 1e-3, 1e3)?;
        let sigma = p.optional("sigma_ln", 0.0, 0.0, 1.5)?;
        let scale = p.optional("scale", 1.0, 0.01, 100.0)?;
        let fill_mass_1 = p.optional("fill_mass", DEFAULT_FILL_MASS, 1e-9, 1e6)?;
        let (dist, d_min_mm, d_max_mm) = sizes_drawn(d50_mm, sigma)?;
        let geo = Geometry::scaled(scale);
        let d_max = d_max_mm * 1e-3;
        let d_o = 2.0 * geo.orifice_radius;
        if d_o < MIN_ORIFICE_RATIO * d_max {
            return Err(Error::invalid(format!(
                "parameter d50 = {d50_mm} mm (largest particle {d_max_mm:.3} mm, sigma_ln = \
                 {sigma}): the orifice ({:.2} mm at scale {scale}) is smaller than \
                 {MIN_ORIFICE_RATIO} largest particles and would bridge; expected d_max <= {:.3} \
                 mm (lower d50 or sigma_ln, or raise scale)",
                d_o * 1e3,
                d_o / MIN_ORIFICE_RATIO * 1e3
            )));
        }
        let fill_mass = fill_mass_1 * scale.powi(3);
        let area = PI * geo.radius * geo.radius;
        let est_height = fill_mass / (CHECK_PACKING * rho * area);
        if est_height > 0.9 * geo.height {
            return Err(Error::invalid(format!(
                "parameter fill_mass = {fill_mass_1} kg: the fill would stand about {:.1} mm high \
                 in the {:.1} mm container (at rho_p = {rho}); expected at most {:.4} kg",
                est_height * 1e3,
                geo.height * 1e3,
                0.9 * geo.height * CHECK_PACKING * rho * area / scale.powi(3)
            )));
        }
        let d_min = d_min_mm * 1e-3;
        // Mean particle mass by number is at least that of d_min: an upper bound on the count.
        let m_min = rho * PI / 6.0 * d_min.powi(3);
        let m_est = match dist {
            None => rho * PI / 6.0 * (d50_mm * 1e-3).powi(3),
            // Log-normal by number: E[d^3] = d50_0^3 exp(4.5 sigma^2) with d50_0 = d50 e^(-3 s^2).
            Some(_) => {
                rho * PI / 6.0
                    * (d50_mm * 1e-3).powi(3)
                    * (-9.0 * sigma * sigma).exp()
                    * (4.5 * sigma * sigma).exp()
            }
        }
        .max(m_min);
        let n_est = fill_mass / m_est;
        if n_est > MAX_PARTICLES as f64 {
            return Err(Error::invalid(format!(
                "parameter fill_mass = {fill_mass_1} kg: about {n_est:.0} particles of d50 = \
                 {d50_mm} mm at scale {scale}; at most {MAX_PARTICLES} (lower fill_mass or scale)"
            )));
        }
        if n_est < 20.0 {
            return Err(Error::invalid(format!(
                "parameter fill_mass = {fill_mass_1} kg: only about {n_est:.0} particles of d50 \
                 = {d50_mm} mm; expected at least 20"
            )));
        }
        let mat = &materials.materials[grain as usize];
        let dt = DT_FRACTION * rayleigh_time(0.5 * d_min, rho, mat.youngs_modulus, mat.poisson);
        Ok(Setup {
            materials,
            grain,
            wall,
            rho,
            d50: d50_mm * 1e-3,
            dist,
            d_min,
            d_max,
            scale,
            fill_mass,
            geo,
            dt,
        })
    }

    /// Diameters (m) whose total mass first reaches the fill mass.
    fn diameters(&self, s: &Setup, seed: u64) -> Result<Vec<f64>> {
        let mass = |d: f64| s.rho * PI / 6.0 * d.powi(3);
        let Some(dist) = &s.dist else {
            let n = (s.fill_mass / mass(s.d50)).round().max(1.0) as usize;
            return Ok(vec![s.d50; n]);
        };
        let mut n = 1024usize;
        loop {
            let set = draw_by_number(
                dist,
                (Some(s.d_min * 1e3), Some(s.d_max * 1e3)),
                n,
                seed,
                "hopper",
            )?;
            let mut acc = 0.0;
            for (k, &d) in set.diameters_mm.iter().enumerate() {
                acc += mass(d * 1e-3);
                if acc >= s.fill_mass {
                    return Ok(set.diameters_mm[..=k].iter().map(|d| d * 1e-3).collect());
                }
            }
            if n > 2 * MAX_PARTICLES {
                return Err(Error::invalid(format!(
                    "parameter fill_mass: more than {MAX_PARTICLES} particles needed"
                )));
            }
            n *= 2;
        }
    }

    /// Runs the experiment and returns the discharge series and the measurements behind the
    /// responses as well.
    pub fn run_detailed(&self, p: &ParamSet, seed: u64, opts: &RunOptions) -> Result<HopperRun> {
        let clock = Instant::now();
        let s = self.setup(p)?;
        let geo = s.geo;
        let mut warnings = Vec::new();
        let diam = self.diameters(&s, seed)?;
        let n = diam.len();

        let mut rng = crate::sampling::rng(seed);
        // An own stream: the diameters used the seed's first stream.
        rng.set_stream(1);
        let particles = super::cylinder_fill::random_fill(
            &diam, geo.radius, s.d_max, s.rho, s.grain, &mut rng,
        )?;
        let z_top = particles.x.iter().map(|x| x[2]).fold(0.0, f64::max) + s.d_max;

        // Walls: container, bottom plate, shutter, fill tube, collection plate, catch cylinder
        // and floor.
        let w = s.wall;
        let catch_radius = geo.plate_radius + (0.02 * s.scale).max(3.0 * s.d_max);
        let z_plate = -geo.drop;
        let z_floor = z_plate - (0.02 * s.scale).max(3.0 * s.d_max);
        let top = z_top.max(geo.height) + s.d_max;
        let mut walls = vec![
            Wall::new(
                "container",
                Shape::Cylinder {
                    center: [0.0; 3],
                    radius: geo.radius,
                    z_min: 0.0,
                    z_max: geo.height,
                },
                w,
            )?,
            Wall::new(
                "bottom",
                Shape::OrificePlate {
                    center: [0.0; 3],
                    orifice_radius: geo.orifice_radius,
                    outer_radius: geo.radius,
                },
                w,
            )?,
            Wall::new(
                "shutter",
                Shape::OrificePlate {
                    center: [0.0; 3],
                    orifice_radius: 0.0,
                    outer_radius: geo.orifice_radius,
                },
                w,
            )?,
            Wall::new(
                "collection plate",
                Shape::OrificePlate {
                    center: [0.0, 0.0, z_plate],
                    orifice_radius: 0.0,
                    outer_radius: geo.plate_radius,
                },
                w,
            )?,
            Wall::new(
                "catch",
                Shape::Cylinder {
                    center: [0.0; 3],
                    radius: catch_radius,
                    z_min: z_floor,
                    z_max: top,
                },
                w,
            )?,
            Wall::new(
                "floor",
                Shape::Plane {
                    point: [0.0, 0.0, z_floor],
                    normal: [0.0, 0.0, 1.0],
                },
                w,
            )?,
        ];
        const SHUTTER: usize = 2;
        let tube = (z_top > geo.height).then_some(walls.len());
        if tube.is_some() {
            walls.push(Wall::new(
                "fill tube",
                Shape::Cylinder {
                    center: [0.0; 3],
                    radius: geo.radius,
                    z_min: geo.height,
                    z_max: top,
                },
                w,
            )?);
        }
        let margin = 2.0 * s.d_max;
        let scene = Scene {
            particles,
            walls,
            materials: s.materials.clone(),
            class: self.class,
            gravity: [0.0, 0.0, -GRAVITY],
            dt: s.dt,
            skin: 0.25 * s.d_min,
            domain: (
                [
                    -catch_radius - margin,
                    -catch_radius - margin,
                    z_floor - margin,
                ],
                [catch_radius + margin, catch_radius + margin, top + margin],
            ),
            max_dt_fraction: 0.3,
            periodic: [false; 3],
        };
        let mut sim = Simulation::new(scene)?;
        sim.set_threads(opts.threads);
        let blew = |stage: &str, e: mbgc_dem::BlowUp| {
            Error::invalid(format!("hopper run ({stage}) stopped: {e}"))
        };

        // Rest: mean translational energy per particle below that of a particle moving at
        // 1 % of sqrt(g d50) (1.4 mm/s at 2 mm).
        let m_mean = sim.particles.m.iter().sum::<f64>() / n as f64;
        let ke_rest = 0.5 * m_mean * 1e-4 * GRAVITY * s.d50;
        let sample_dt = 1e-3 * s.scale.sqrt();
        let chunk = ((sample_dt / s.dt).round() as u64).max(1);
        let mut vtk_index = 0usize;
        let mut vtk = |sim: &Simulation, label: &str| -> Result<()> {
            if let Some(dir) = &opts.vtk_dir {
                let path = dir.join(format!("hopper_{vtk_index:04}.vtk"));
                super::write_vtk(&path, &sim.particles, label)?;
                vtk_index += 1;
            }
            Ok(())
        };
        vtk(&sim, "hopper: filled")?;

        // 1. Settle: at least the free-fall time from the top of the column, then until rest.
        let t_fall = (2.0 * z_top / GRAVITY).sqrt();
        let settle_cap = 2.0 * t_fall + 2.0 * s.scale.sqrt();
        if let Some(w) =
            super::cylinder_fill::settle(&mut sim, chunk, t_fall, settle_cap, ke_rest, "hopper")?
        {
            warnings.push(format!("{w}; discharged anyway"));
        }
        let settle_steps = sim.step;
        vtk(&sim, "hopper: settled")?;

        // 2. Bulk density of the fill.
        let fill_height = surface_height(&sim.particles.x, &sim.particles.r);
        let total_mass: f64 = sim.particles.m.iter().sum();
        // A fill only a few particles deep is measured to half its height.
        let measured = (fill_height - s.d_max).max(0.5 * fill_height);
        let bulk_density = s.rho * fill_fraction(&sim.particles, geo.radius, measured);
        if fill_height > geo.height {
            warnings.push(format!(
                "the settled fill ({:.1} mm) stands above the container rim ({:.1} mm)",
                fill_height * 1e3,
                geo.height * 1e3
            ));
        }

        // 3. Discharge.
        sim.set_wall_active(SHUTTER, false);
        if let Some(t) = tube {
            sim.set_wall_active(t, false);
        }
        let t0 = sim.time;
        let z_pass = -s.d_max;
        let mut passed = vec![false; n];
        let mut passed_mass = 0.0;
        let mut passed_count = 0usize;
        let mut last_pass = t0;
        let mut series = DischargeSeries {
            time_s: vec![0.0],
            mass_kg: vec![0.0],
        };
        let t_quiet = 4.0 * (2.0 * geo.orifice_radius / GRAVITY).sqrt();
        let w_bev = beverloo_flow_rate(bulk_density, 2.0 * geo.orifice_radius, s.d50);
        let t_cap = 5.0 * total_mass / w_bev.max(1e-12) + 2.0 * s.scale.sqrt();
        let vtk_every = 0.1 * s.scale.sqrt();
        let mut next_vtk = t0 + vtk_every;
        let mut settled = false;
        loop {
            sim.run(chunk).map_err(|e| blew("discharge", e))?;
            let p = &sim.particles;
            let mut ke = 0.0;
            let mut active = 0usize;
            for i in 0..p.len() {
                let id = p.id[i] as usize;
                if !passed[id] && p.x[i][2] < z_pass {
                    passed[id] = true;
                    passed_mass += p.m[i];
                    passed_count += 1;
                    last_pass = sim.time;
                }
                // Particles that fell off the plate no longer matter.
                if p.x[i][2] > z_plate {
                    let v = p.v[i];
                    ke += 0.5 * p.m[i] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                    active += 1;
                }
            }
            series.time_s.push(sim.time - t0);
            series.mass_kg.push(passed_mass);
            if opts.vtk_dir.is_some() && sim.time >= next_vtk {
                vtk(&sim, "hopper: discharging")?;
                next_vtk += vtk_every;
            }
            let quiet = sim.time - last_pass >= t_quiet && sim.time - t0 >= t_quiet;
            if quiet && ke < ke_rest * active.max(1) as f64 {
                settled = true;
                break;
            }
            if sim.time - t0 > t_cap {
                warnings.push(format!(
                    "discharge not finished after {:.2} s (last particle passed at {:.2} s); \
                     measured as it stands",
                    sim.time - t0,
                    last_pass - t0
                ));
                break;
            }
        }
        let discharge_time = sim.time - t0;
        vtk(&sim, "hopper: final")?;

        // 4. Responses.
        let (flow_rate, flow_r2) = flow_rate_fit(&series, FLOW_WINDOW.0, FLOW_WINDOW.1);
        if passed_count == 0 {
            warnings.push("no particle left the container (the orifice bridged)".into());
        }
        let p = &sim.particles;
        let (mut in_container, mut on_plate, mut off_plate) = (0, 0, 0);
        let (mut xc, mut rc, mut xb, mut rb) = (vec![], vec![], vec![], vec![]);
        for i in 0..p.len() {
            let x = p.x[i];
            let rho_xy = x[0].hypot(x[1]);
            if x[2] >= z_pass {
                if rho_xy < geo.radius && x[2] < top {
                    in_container += 1;
                }
                xc.push(x);
                rc.push(p.r[i]);
            } else if x[2] > z_plate && rho_xy < geo.plate_radius {
                on_plate += 1;
                xb.push(x);
                rb.push(p.r[i]);
            } else {
                off_plate += 1;
            }
        }
        let top_angles = repose_angles(&xc, &rc, Surface::Top, 0.0, geo.radius, s.d50);
        let bottom_angles =
            repose_angles(&xb, &rb, Surface::Bottom, z_plate, geo.plate_radius, s.d50);
        let (mut top_angles, mut bottom_angles) = (top_angles, bottom_angles);
        let (mut flow_rate, discharged_fraction) = (flow_rate, passed_mass / total_mass);
        // Particles wholly over the hole, at rest, at any height in the container: after a free
        // discharge the crater's walls stand outside the orifice's edge, so only an arch (which
        // domes above the plane) can hold them.
        let held = (0..p.len())
            .filter(|&i| {
                let x = p.x[i];
                x[2] >= z_pass && x[2] < top && x[0].hypot(x[1]) + p.r[i] < geo.orifice_radius
            })
            .count();
        // Particles still moving over the hole may be falling through it.
        let arch_held = if settled { held as f64 } else { f64::NAN };
        let t_unit = FLOW_BIN_WIDTH
            * nominal_discharge_time(s.fill_mass, s.rho, 2.0 * geo.orifice_radius, s.d50);
        let bins = binned_flow_rates(&series, t_unit, FLOW_BINS, settled);
        let stalled = !clogged(discharged_fraction) && intermittent(&bins);
        if stalled {
            warnings.push(format!(
                "the discharge stalled and restarted (flow rate by bin, kg/s: {}); flow_rate and \
                 beverloo_ratio are NaN (no steady flow)",
                bins.iter()
                    .map(|b| format!("{b:.3}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
            flow_rate = f64::NAN;
        }
        if clogged(discharged_fraction) {
            warnings.push(format!(
                "the orifice clogged: the discharge stopped after {:.1} % of the fill, less than \
                 half the {:.0} % standing over the orifice; flow_rate, beverloo_ratio and the \
                 repose angles are NaN (no steady flow, no crater, no pile)",
                100.0 * discharged_fraction,
                100.0 * OVER_ORIFICE_SHARE
            ));
            flow_rate = f64::NAN;
            top_angles = [f64::NAN; 4];
            bottom_angles = [f64::NAN; 4];
        } else if clogged_late(discharged_fraction, arch_held) {
            // The wording up to the count is what `backfill` reads in tables from before the
            // column.
            warnings.push(format!(
                "an arch holds {held} particles over the orifice after {:.1} % of the fill left: \
                 the discharge stopped by a late clog; flow_rate, beverloo_ratio and the repose \
                 angles are NaN (a flow, a crater and a pile cut short)",
                100.0 * discharged_fraction,
            ));
            flow_rate = f64::NAN;
            top_angles = [f64::NAN; 4];
            bottom_angles = [f64::NAN; 4];
        }
        let top = finite_mean(&top_angles);
        let bottom = finite_mean(&bottom_angles);
        for (name, a) in [("top", &top_angles), ("bottom", &bottom_angles)] {
            let bad = a.iter().filter(|v| !v.is_finite()).count();
            if bad > 0
                && !clogged(discharged_fraction)
                && !clogged_late(discharged_fraction, arch_held)
            {
                warnings.push(format!(
                    "repose angle {name}: {bad} of 4 sectors had too few surface points"
                ));
            }
        }
        let mut responses = vec![
            ("flow_rate".to_string(), flow_rate),
            ("repose_angle_top".into(), top),
            ("repose_angle_bottom".into(), bottom),
            ("discharged_mass".into(), passed_mass),
            ("discharged_fraction".into(), discharged_fraction),
            ("flow_R2".into(), flow_r2),
            ("bulk_density".into(), bulk_density),
            ("beverloo_ratio".into(), flow_rate / w_bev),
        ];
        responses.push(("flow_bin_width".into(), t_unit));
        responses.extend(FLOW_BIN_NAMES.iter().map(|n| n.to_string()).zip(bins));
        let sectors = top_angles.iter().chain(&bottom_angles).copied();
        responses.extend(
            SECTOR_ANGLE_NAMES
                .iter()
                .map(|n| n.to_string())
                .zip(sectors),
        );
        // Last, so that a table written before the hopper recorded it gains only a final
        // response column.
        responses.push(("arch_held".into(), arch_held));
        let outcome = Outcome {
            responses,
            diagnostics: Diagnostics {
                settled,
                steps: sim.step,
                particles: n,
                wall_time_s: 0.0,
                warnings,
            },
        };
        let mut run = HopperRun {
            outcome,
            series,
            geometry: geo,
            top_angles,
            bottom_angles,
            in_container,
            on_plate,
            off_plate,
            passed: passed_count,
            fill_height,
            bulk_density,
            settle_steps,
            discharge_time,
            dt: s.dt,
        };
        if let Some(path) = &opts.picture {
            draw_side_view(path, &sim, &run, s.d50)?;
        }
        run.outcome.diagnostics.wall_time_s = clock.elapsed().as_secs_f64();
        Ok(run)
    }
}

impl Experiment for Hopper {
    fn name(&self) -> &'static str {
        "hopper"
    }

    fn parameters(&self) -> Vec<&'static str> {
        with_class_parameters(&OWN_PARAMETERS, &self.class, &Pair::BOTH)
    }

    fn optional_parameters(&self) -> Vec<&'static str> {
        vec!["fill_mass", "scale", "sigma_ln"]
    }

    fn class(&self) -> Option<&ModelClass> {
        Some(&self.class)
    }

    /// `scale` = d50 / 2 mm: the apparatus and its fill in particle diameters as at the 2 mm
    /// default (D_o / d50 = 7.5, some 4800 particles), so the pile and the orifice keep their
    /// size in particles whatever the material (the module's notes on a campaign over d50).
    fn sized_to(&self, p: &ParamSet) -> Option<(&'static str, f64)> {
        p.get("d50").map(|d50| ("scale", d50 / 2.0))
    }

    /// Seed 000's three measured responses; the rest are diagnostics and per-bin or
    /// per-sector parts of these.
    fn calibration_responses(&self) -> Vec<&'static str> {
        vec!["flow_rate", "repose_angle_top", "repose_angle_bottom"]
    }

    fn events(&self) -> Vec<&'static str> {
        vec![CLOGGED, CLOGGED_LATE, INTERMITTENT]
    }

    fn voided_by(&self, event: &str) -> Vec<&'static str> {
        match event {
            CLOGGED => VOIDED_BY_CLOG
                .iter()
                .chain(&SECTOR_ANGLE_NAMES)
                .copied()
                .collect(),
            CLOGGED_LATE => VOIDED_BY_CLOG
                .iter()
                .chain(&SECTOR_ANGLE_NAMES)
                .copied()
                .collect(),
            INTERMITTENT => VOIDED_BY_INTERMITTENT.to_vec(),
            _ => Vec::new(),
        }
    }

    /// A clog first: its flow bins (an avalanche, then nothing) never restart. A late clog
    /// before a stall: the orifice ended blocked whatever the flow did before.
    fn event_of(&self, value: &dyn Fn(&str) -> Option<f64>) -> Option<&'static str> {
        let fraction = value("discharged_fraction").filter(|f| f.is_finite());
        if fraction.is_some_and(clogged) {
            return Some(CLOGGED);
        }
        if let (Some(f), Some(h)) = (fraction, value("arch_held")) {
            if clogged_late(f, h) {
                return Some(CLOGGED_LATE);
            }
        }
        let bins: Option<Vec<f64>> = FLOW_BIN_NAMES.iter().map(|n| value(n)).collect();
        bins.filter(|b| intermittent(b)).map(|_| INTERMITTENT)
    }

    /// `arch_held` of a run from before the column: the run warned of every late arch with
    /// its count, so a settled flowing run without that warning held none. An early clog's
    /// count and an unsettled run's are not known.
    fn backfill(&self, response: &str, cell: &dyn Fn(&str) -> Option<String>) -> Option<f64> {
        if response != "arch_held" {
            return None;
        }
        if let Some(w) = cell("warnings") {
            if let Some(rest) = w.split("an arch holds ").nth(1) {
                return rest.split(' ').next().and_then(|n| n.parse::<f64>().ok());
            }
        }
        let fraction = cell("discharged_fraction").and_then(|v| v.parse::<f64>().ok())?;
        (cell("settled").as_deref() == Some("true") && fraction.is_finite() && !clogged(fraction))
            .then_some(0.0)
    }

    fn responses(&self) -> Vec<&'static str> {
        let mut r = vec![
            "flow_rate",
            "repose_angle_top",
            "repose_angle_bottom",
            "discharged_mass",
            "discharged_fraction",
            "flow_R2",
            "bulk_density",
            "beverloo_ratio",
            "flow_bin_width",
        ];
        r.extend(FLOW_BIN_NAMES);
        r.extend(SECTOR_ANGLE_NAMES);
        r.push("arch_held");
        r
    }

    fn check(&self, p: &ParamSet) -> Result<()> {
        self.setup(p).map(|_| ())
    }

    fn run(&self, p: &ParamSet, seed: u64, opts: &RunOptions) -> Result<Outcome> {
        self.run_detailed(p, seed, opts).map(|r| r.outcome)
    }
}

/// Side view of the final state: all particles in light grey, the cross-section |y| < d50 (the
/// seed's xz orthoslice) in brown, the container, orifice plate and collection plate as lines.
fn draw_side_view(path: &Path, sim: &Simulation, run: &HopperRun, d50: f64) -> Result<()> {
    let geo = run.geometry;
    let p = &sim.particles;
    let reach =
        p.x.iter()
            .filter(|x| x[2] > -geo.drop)
            .map(|x| x[0].abs())
            .fold(geo.radius, f64::max)
            .min(geo.plate_radius)
            + 0.1 * geo.radius;
    let z_lo = -geo.drop - 0.1 * geo.radius;
    let z_hi = geo.height + 0.1 * geo.radius;
    let width = 1000u32;
    let plot_w = (width - 90) as f64;
    let height = (plot_w * (z_hi - z_lo) / (2.0 * reach)) as u32 + 110;
    let title = format!(
        "hopper: flow rate {:.4} kg/s, top {:.1} deg, bottom {:.1} deg",
        run.outcome.get("flow_rate").unwrap_or(f64::NAN),
        run.outcome.get("repose_angle_top").unwrap_or(f64::NAN),
        run.outcome.get("repose_angle_bottom").unwrap_or(f64::NAN)
    );
    let view = SideView {
        x: &p.x,
        r: &p.r,
        geo,
        reach,
        z: (z_lo, z_hi),
        slab: d50,
        title,
    };
    crate::draw_figure!(path, (width, height), draw_side(&view))
}

struct SideView<'a> {
    x: &'a [V3],
    r: &'a [f64],
    geo: Geometry,
    reach: f64,
    z: (f64, f64),
    slab: f64,
    title: String,
}

fn draw_side<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    v: &SideView,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let mm = 1e3;
    let mut chart = ChartBuilder::on(root)
        .caption(&v.title, ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(50)
        .build_cartesian_2d(-v.reach * mm..v.reach * mm, v.z.0 * mm..v.z.1 * mm)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x / mm")
        .y_desc("z / mm")
        .draw()?;
    let px_per_mm = chart.plotting_area().dim_in_pixel().0 as f64 / (2.0 * v.reach * mm);
    let grey = RGBColor(0xcc, 0xcc, 0xcc);
    let brown = RGBColor(0x8c, 0x56, 0x3c);
    for front in [false, true] {
        let colour = if front { brown } else { grey };
        chart.draw_series(
            v.x.iter()
                .zip(v.r)
                .filter(|(x, _)| (x[1].abs() <= v.slab) == front)
                .map(|(x, &r)| {
                    Circle::new(
                        (x[0] * mm, x[2] * mm),
                        ((r * mm * px_per_mm).round() as i32).max(1),
                        colour.filled(),
                    )
                }),
        )?;
    }
    let g = v.geo;
    let (rc, ro, h, zp, rp) = (
        g.radius * mm,
        g.orifice_radius * mm,
        g.height * mm,
        -g.drop * mm,
        g.plate_radius * mm,
    );
    let wall = BLACK.stroke_width(2);
    let lines = [
        vec![(-rc, h), (-rc, 0.0), (-ro, 0.0)],
        vec![(ro, 0.0), (rc, 0.0), (rc, h)],
        vec![(-rp, zp), (rp, zp)],
    ];
    for l in lines {
        chart.draw_series(std::iter::once(PathElement::new(l, wall)))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The clog rule reads the recorded discharged fraction: half the 0.09 over the orifice is
    /// the line, and a table without the column, or without a value, has no event.
    #[test]
    fn a_run_that_left_less_than_the_column_over_the_orifice_clogged() {
        assert!((OVER_ORIFICE_SHARE - 0.09).abs() < 1e-12);
        assert!((CLOG_SHARE - 0.045).abs() < 1e-12);
        let hopper = Hopper {
            class: ModelClass::default(),
        };
        let event = |f: Option<f64>| {
            hopper.event_of(&|n: &str| if n == "discharged_fraction" { f } else { None })
        };
        assert_eq!(event(Some(0.023)), Some("clogged"));
        assert_eq!(event(Some(0.0)), Some("clogged"));
        assert_eq!(event(Some(0.25)), None);
        assert_eq!(event(Some(0.044)), Some("clogged"));
        assert_eq!(event(Some(0.046)), None);
        // A discharge that left a near-vertical rathole (about the column over the orifice) is
        // no clog.
        assert_eq!(event(Some(0.085)), None);
        assert_eq!(event(Some(f64::NAN)), None);
        assert_eq!(event(None), None);
        assert_eq!(
            hopper.events(),
            vec!["clogged", "clogged_late", "intermittent"]
        );
        // A late arch: the flow passed the line and came to rest with particles held over the
        // orifice. Without the count (an older table, or a run that never came to rest) it is
        // not seen; an early clog stays an early clog whatever the count.
        let late = |f: f64, held: Option<f64>| {
            hopper.event_of(&|n: &str| match n {
                "discharged_fraction" => Some(f),
                "arch_held" => held,
                _ => None,
            })
        };
        assert_eq!(late(0.088, Some(86.0)), Some("clogged_late"));
        assert_eq!(late(0.42, Some(1.0)), Some("clogged_late"));
        assert_eq!(late(0.42, Some(0.0)), None);
        assert_eq!(late(0.088, Some(f64::NAN)), None);
        assert_eq!(late(0.088, None), None);
        assert_eq!(late(0.02, Some(120.0)), Some("clogged"));
        assert!(!clogged_late(f64::NAN, 3.0));
    }

    /// A table from before `arch_held`: the count of a late arch is read from the run's
    /// warning (row 51 of docs/data/propagation/gravel/hopper/runs.csv), a settled flowing run
    /// without one held none, and an early clog or an unsettled run is not known.
    #[test]
    fn an_old_line_tells_the_arch_it_warned_of() {
        let hopper = Hopper {
            class: ModelClass::default(),
        };
        let line = |warnings: &str, settled: &str, fraction: &str| {
            let (w, s, f) = (
                warnings.to_string(),
                settled.to_string(),
                fraction.to_string(),
            );
            move |n: &str| match n {
                "warnings" => Some(w.clone()),
                "settled" => Some(s.clone()),
                "discharged_fraction" => Some(f.clone()),
                _ => None,
            }
        };
        let row51 = line(
            "an arch holds 190 particles over the orifice after 5.1 % of the fill left: the \
             discharge stopped by a late clog; flow_rate is that of the flow before it",
            "true",
            "0.051",
        );
        assert_eq!(hopper.backfill("arch_held", &row51), Some(190.0));
        assert_eq!(hopper.backfill("flow_rate", &row51), None);
        assert_eq!(
            hopper.backfill("arch_held", &line("", "true", "0.42")),
            Some(0.0)
        );
        assert_eq!(
            hopper.backfill("arch_held", &line("", "false", "0.42")),
            None
        );
        assert_eq!(
            hopper.backfill("arch_held", &line("", "true", "0.02")),
            None
        );
    }

    /// The stall rule on binned flow rates of real runs (docs/data/propagation/gravel/hopper):
    /// row 22 stalled and restarted; row 7 started late, row 27 wobbled in its tail, row 3
    /// clogged: none of them restarted. A bin that is NaN (an unfinished series) decides
    /// nothing.
    #[test]
    fn a_flow_that_stalls_and_restarts_is_intermittent() {
        let row22 = [1.02, 0.41, 0.24, 0.87, 1.22, 1.07, 0.55, 0.37];
        assert!(intermittent(&row22));
        assert!(!intermittent(&[
            1.10, 1.44, 2.19, 0.84, 0.60, 0.46, 0.18, 0.15
        ]));
        assert!(!intermittent(&[
            2.53, 2.37, 1.29, 0.86, 0.27, 0.15, 0.22, 0.12
        ]));
        assert!(!intermittent(&[0.45, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
        // At the lines (binary-exact values): a rise of exactly a quarter of the peak counts, a
        // dip to exactly half does not.
        assert!(intermittent(&[1.0, 0.25, 0.5]));
        assert!(!intermittent(&[1.0, 0.25, 0.49]));
        assert!(!intermittent(&[1.0, 0.5, 0.9]));
        let mut unfinished = row22;
        unfinished[7] = f64::NAN;
        assert!(!intermittent(&unfinished));
        let hopper = Hopper {
            class: ModelClass::default(),
        };
        let event = |fraction: f64, bins: [f64; 8]| {
            hopper.event_of(&|n: &str| {
                if n == "discharged_fraction" {
                    Some(fraction)
                } else {
                    FLOW_BIN_NAMES.iter().position(|b| *b == n).map(|k| bins[k])
                }
            })
        };
        assert_eq!(event(0.28, row22), Some("intermittent"));
        // A clog comes first.
        assert_eq!(event(0.02, row22), Some("clogged"));
        assert_eq!(
            hopper.voided_by("intermittent"),
            vec!["flow_rate", "beverloo_ratio"]
        );
        assert!(hopper.voided_by("clogged").contains(&"repose_angle_top_1"));
    }

    #[test]
    fn repose_angles_of_a_synthetic_cone_and_crater() {
        // One layer of spheres (d = 1 mm) on a cone of 30 degrees: apex height 20 mm.
        let d = 1e-3;
        let tan = 30f64.to_radians().tan();
        let (mut x, mut r) = (vec![], vec![]);
        let mut xi = -0.05;
        while xi <= 0.05 {
            let mut yi = -0.05;
            while yi <= 0.05 {
                let rho = f64::hypot(xi, yi);
                let h = (0.02 - rho * tan).max(0.0);
                x.push([xi, yi, h - 0.5 * d]);
                r.push(0.5 * d);
                // Crater: rises from 7.5 mm at 40 degrees.
                yi += 0.5e-3;
            }
            xi += 0.5e-3;
        }
        let a = repose_angles(&x, &r, Surface::Bottom, 0.0, 0.06, d);
        for v in a {
            assert!((v - 30.0).abs() < 1.0, "{a:?}");
        }
        let tan40 = 40f64.to_radians().tan();
        let (mut xc, mut rc) = (vec![], vec![]);
        for (p, &ri) in x.iter().zip(&r) {
            let rho = p[0].hypot(p[1]);
            if rho > 0.0075 && rho < 0.025 {
                // Flat rest of a shallow fill above 10 mm.
                let h = ((rho - 0.0075) * tan40).min(0.01);
                xc.push([p[0], p[1], h - 0.5 * d]);
                rc.push(ri);
            }
        }
        let a = repose_angles(&xc, &rc, Surface::Top, 0.0, 0.025, d);
        for v in a {
            assert!((v - 40.0).abs() < 1.5, "{a:?}");
        }
    }

    #[test]
    fn binned_flow_rates_follow_a_piecewise_linear_discharge() {
        // 0.02 kg/s for 1 s, then 0.01 kg/s until 1.5 s, then nothing.
        let time_s: Vec<f64> = (0..=150).map(|k| k as f64 * 0.01).collect();
        let mass_kg: Vec<f64> = time_s
            .iter()
            .map(|&t| {
                if t <= 1.0 {
                    0.02 * t
                } else {
                    0.02 + 0.01 * (t - 1.0)
                }
            })
            .collect();
        let s = DischargeSeries { time_s, mass_kg };
        let r = binned_flow_rates(&s, 0.5, 4, true);
        let want = [0.02, 0.02, 0.01, 0.0];
        for (a, b) in r.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{r:?}");
        }
        let cut = binned_flow_rates(&s, 0.5, 4, false);
        assert!(cut[3].is_nan() && (cut[2] - 0.01).abs() < 1e-12, "{cut:?}");
    }

    #[test]
    fn flow_rate_fit_recovers_a_line() {
        let t: Vec<f64> = (0..100).map(|k| k as f64 * 0.01).collect();
        let m: Vec<f64> = t.iter().map(|&t| (0.05 * t).min(0.04)).collect();
        let (w, r2) = flow_rate_fit(
            &DischargeSeries {
                time_s: t,
                mass_kg: m,
            },
            0.2,
            0.8,
        );
        assert!((w - 0.05).abs() < 1e-9 && r2 > 0.999_999, "{w} {r2}");
    }

    #[test]
    fn beverloo_of_seed_000() {
        // rho_b = 1500, D_o = 15 mm, d = 2 mm: 0.58 * 1500 * 3.132 * 0.012^2.5 = 0.0430 kg/s.
        let w = beverloo_flow_rate(1500.0, 0.015, 0.002);
        assert!((w - 0.0430).abs() < 2e-4, "{w}");
    }
}
