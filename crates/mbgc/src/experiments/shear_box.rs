//! The scaled shear box of seed 004 (after Roessler et al. 2019): a box is filled and struck off
//! level, one side wall (the flap) is removed, the material flows out until it rests, and the
//! angle of the remaining flank is measured.
//!
//! Geometry: base l = w = 100 mm, h = 150 mm, scaled by S = k d_max / min(l, w, h), k = 10 by
//! default (`box_scale`), so the smallest side is k particle diameters whatever the PSD: the
//! responses are meant to be scale-free, and the particle count stays about the same across the
//! parameter space. The PSD is the log-normal of (d50, sigma_ln) drawn by number and truncated at
//! the Q3 quantiles 1 % and 99 % (`psd::default_range`): the log-normal tails are unbounded, and a
//! single particle from the far tail would set d_max and with it the box size.
//!
//! Responses: `bulk_density` (particle mass inside the box after striking off / box volume, with
//! the exact volume of spheres cut by the rim), `shear_angle` (degrees, least-squares line through
//! the top of the remaining flank), `flank_r2` and `flank_curvature` (largest gap between a
//! quadratic and the line over the flank, relative to the flank's height: seed 004 traced its
//! metamodel outliers to curved flanks).

use std::path::Path;
use std::time::Instant;

pub use super::shear_box_rest::{ChunkState, Phase, RestRule, Thresholds};
use super::{
    materials_from, with_class_parameters, Diagnostics, Experiment, Outcome, ParamSet, RunOptions,
    RHO_RANGE,
};
use crate::error::{Error, Result};
use crate::psd::draw::truncated_q3;
use crate::psd::{default_range, draw_by_number, Distribution, LogNormal, MassDistribution};
use crate::similarity::{Monomial, ScaledResponse, Similarity};
use mbgc_dem::analysis::sphere_box_volume;
use mbgc_dem::contact::{ModelClass, Pair};
use mbgc_dem::insertion::random_pack;
use mbgc_dem::particles::Particles;
use mbgc_dem::sim::{Scene, Simulation};
use mbgc_dem::timestep::rayleigh_time;
use mbgc_dem::vec3::V3;
use mbgc_dem::walls::Wall;

/// The shear box's responses in table order (the first two are the calibration responses); the
/// embedded run and the LIGGGHTS backend both name them through [`Responses::named`].
pub const RESPONSES: [&str; 5] = [
    "shear_angle",
    "bulk_density",
    "flank_r2",
    "flank_curvature",
    "outflow_fraction",
];

/// What one shear-box run measures, whichever solver ran it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Responses {
    /// Angle of the flank left after the outflow, degrees.
    pub shear_angle: f64,
    /// Bulk density of the filled box, kg/m^3.
    pub bulk_density: f64,
    /// R^2 of the straight line fitted to the flank.
    pub flank_r2: f64,
    /// Quadratic term of the flank relative to its height.
    pub flank_curvature: f64,
    /// Mass fraction that left the box.
    pub outflow_fraction: f64,
}

impl Responses {
    /// The responses under their table names, in [`RESPONSES`] order.
    pub fn named(self) -> Vec<(String, f64)> {
        let v = [
            self.shear_angle,
            self.bulk_density,
            self.flank_r2,
            self.flank_curvature,
            self.outflow_fraction,
        ];
        RESPONSES
            .iter()
            .zip(v)
            .map(|(n, x)| (n.to_string(), x))
            .collect()
    }
}

/// Box length, width and height at scale 1, mm (seed 004: 100 x 100 x 150 mm); each run scales
/// all three by k d_max / 100 mm.
pub const BASE_MM: [f64; 3] = [100.0, 100.0, 150.0];
const G: f64 = 9.81;
/// Solid fraction of the poured column. Random sequential insertion of spheres between walls
/// jams near 0.25 (0.38 for equal spheres in free space); 0.2 inserts every particle in a few
/// attempts each, in mbgc as in LIGGGHTS, while the column stands about 4 box heights tall
/// (the fall, and with it the fill's cost, grows with that height).
pub const FILL_FRACTION: f64 = 0.2;

/// The scaled shear-box experiment of seed 004. Parameters: [`OWN_PARAMETERS`] (d50 in mm), the
/// model class's, and sigma_ln (optional; 0 or absent: monosized).
#[derive(Debug, Clone)]
pub struct ShearBox {
    /// k: the smallest box side in units of d_max.
    pub box_scale: f64,
    /// Time step as a fraction of the Rayleigh time (seed 004: 0.25).
    pub dt_fraction: f64,
    /// Largest number of particles accepted (the run is refused above).
    pub max_particles: usize,
    /// The effects of the contact law.
    pub class: ModelClass,
    /// 0: diameters drawn from the continuous PSD (the experiment). n > 0: every drawn diameter
    /// is replaced by the representative of its class among n classes of equal mass
    /// ([`psd_classes`]), the way a LIGGGHTS user describes a PSD; for comparisons only.
    pub psd_classes: usize,
    /// Neighbour skin as a fraction of d_min. Only the cost depends on it: a wide skin lets the
    /// pouring column fall many steps between list builds, while the few extra pairs it lists in
    /// the settled bed are cheap to reject (docs/shear_box.md, cost section).
    pub skin: f64,
    /// When the fill and the outflow count as at rest.
    pub rest: RestRule,
}

/// Interval of the rest checks (and the relaxation after the strike-off) in units of the box's
/// own time scale sqrt(d_max / g). Every other time of the schedule is such a multiple too, so
/// that without cohesion a run depends on E_p, rho_p and d50 only through the dimensionless
/// stiffness E_p / (rho_p g d50) and its bulk density is rho_p times a solid fraction: the
/// shipped metamodel is fitted in those groups (docs/metamodel.md). Issue 13's runs used a
/// fixed 0.01 s, which is this value at d_max = 10.9 mm.
pub const CHUNK_TIME: f64 = 0.3;

/// Skin of the campaign runs, in units of d_min (0.2 before issue 13).
pub const SKIN: f64 = 1.0;

/// The parameters the shear box needs whatever the model class (d50 in mm).
pub const OWN_PARAMETERS: [&str; 5] = ["E_p", "E_w", "nu_p", "rho_p", "d50"];

impl Default for ShearBox {
    fn default() -> Self {
        ShearBox {
            box_scale: 10.0,
            dt_fraction: 0.25,
            max_particles: 200_000,
            class: ModelClass::default(),
            psd_classes: 0,
            skin: SKIN,
            rest: RestRule::default(),
        }
    }
}

/// Box and particles of one parameter set.
#[derive(Debug, Clone)]
pub struct Layout {
    /// l, w, h in m.
    pub size: V3,
    /// Particle diameters in m, in insertion order.
    pub diameters: Vec<f64>,
    /// Smallest drawn diameter, m: the Q3 quantile 1 % (d50 for a monosized set).
    pub d_min: f64,
    /// Largest drawn diameter, m: the Q3 quantile 99 %; it sets the box size.
    pub d_max: f64,
}

impl ShearBox {
    /// Draws the particles and sizes the box. Overfills by a margin so that the settled bed
    /// surely reaches the rim (it is struck off there).
    pub fn layout(&self, p: &ParamSet, seed: u64) -> Result<Layout> {
        let d50_mm = p.require("d50", 1e-3, 1e4)?;
        let sigma = p.optional("sigma_ln", 0.0, 0.0, 2.0)?;
        if !(self.box_scale >= 3.0 && self.box_scale.is_finite()) {
            return Err(Error::invalid(format!(
                "box scale k = {}: expected at least 3 particle diameters across the box",
                self.box_scale
            )));
        }
        let (diam_mm, d_min_mm, d_max_mm) = if sigma < 1e-6 {
            (vec![d50_mm], d50_mm, d50_mm)
        } else {
            let dist = Distribution::LogNormal(LogNormal::new(d50_mm, sigma)?);
            let (lo, hi) = default_range(&dist);
            // Number needed: solid volume of 0.78 box volumes (a loose bed of packing 0.55-0.65
            // then stands 20-40 % above the rim); the number-based mean volume comes from a
            // first draw.
            let probe = draw_by_number(&dist, (Some(lo), Some(hi)), 2000, seed, "shear box PSD")?;
            (
                quantize(&dist, (lo, hi), self.psd_classes, probe.diameters_mm),
                lo,
                hi,
            )
        };
        let scale = self.box_scale * d_max_mm / BASE_MM[0].min(BASE_MM[1]).min(BASE_MM[2]);
        let size = [
            BASE_MM[0] * scale * 1e-3,
            BASE_MM[1] * scale * 1e-3,
            BASE_MM[2] * scale * 1e-3,
        ];
        let v_box = size[0] * size[1] * size[2];
        let mean_vol = diam_mm.iter().map(|d| (d * 1e-3).powi(3)).sum::<f64>()
            / diam_mm.len() as f64
            * std::f64::consts::PI
            / 6.0;
        let n = (0.78 * v_box / mean_vol).ceil() as usize;
        if n > self.max_particles {
            // The count follows box_scale (the box is k d_max wide) and the PSD's width; name
            // both, the box scale first, since it is the setting the user chose.
            return Err(Error::invalid(format!(
                "--box-scale {}: the box ({:.0} x {:.0} x {:.0} mm, k d_max with d_max = {d_max_mm:.2} \
                 mm for d50 = {d50_mm} mm, sigma_ln = {sigma}) would hold about {n} particles, \
                 more than the limit {}; expected a smaller box scale or a narrower PSD",
                self.box_scale,
                size[0] * 1e3,
                size[1] * 1e3,
                size[2] * 1e3,
                self.max_particles
            )));
        }
        let diameters = if sigma < 1e-6 {
            vec![d50_mm * 1e-3; n]
        } else {
            let dist = Distribution::LogNormal(LogNormal::new(d50_mm, sigma)?);
            let drawn = draw_by_number(
                &dist,
                (Some(d_min_mm), Some(d_max_mm)),
                n,
                seed ^ 0x5eed,
                "shear box PSD",
            )?
            .diameters_mm;
            quantize(&dist, (d_min_mm, d_max_mm), self.psd_classes, drawn)
                .into_iter()
                .map(|d| d * 1e-3)
                .collect()
        };
        Ok(Layout {
            size,
            diameters,
            d_min: d_min_mm * 1e-3,
            d_max: d_max_mm * 1e-3,
        })
    }
}

/// The numbers of the procedure (column, time step, rest thresholds, time limits), shared by the
/// run and by the LIGGGHTS deck of the same procedure so that the two cannot drift apart.
#[derive(Debug, Clone)]
pub struct Schedule {
    /// Top of the poured column, m (it starts on the floor).
    pub column_top: f64,
    /// Height of the walls that hold the column, m.
    pub wall_h: f64,
    /// Time step, s: `dt_fraction` of the Rayleigh time of the smallest particle.
    pub dt: f64,
    /// Neighbour-list skin, m.
    pub skin: f64,
    /// Steps between rest checks: [`CHUNK_TIME`] sqrt(d_max / g), about 0.01 s at d50 = 8 mm.
    pub chunk: u64,
    /// Rest: translational rms speed below this, m/s.
    pub v_rest: f64,
    /// Outflow still running: a particle in the box faster than this in x-z, m/s.
    pub v_move: f64,
    /// Free-fall time from the column's top, s: no rest is declared before it.
    pub fall: f64,
    /// Step limit of pouring and settling: the free fall plus 40 sqrt(h / g).
    pub max_fill_steps: u64,
    /// The outflow runs at least this long, s.
    pub min_flow_time: f64,
    /// Step limit of the outflow: 60 sqrt(h / g).
    pub max_flow_steps: u64,
    /// Particles below this height have left the box over the floor's edge, m.
    pub removal_height: f64,
    /// Particles outside leave the run with an error: they escaped, m.
    pub domain: (V3, V3),
}

impl Schedule {
    /// The thresholds the rest rules read.
    pub fn thresholds(&self) -> Thresholds {
        Thresholds {
            v_rest: self.v_rest,
            v_move: self.v_move,
            fall: self.fall,
            min_flow_time: self.min_flow_time,
        }
    }
}

impl ShearBox {
    /// The schedule for the drawn layout, particle density `rho`, modulus `e` and Poisson `nu`.
    pub fn schedule(&self, lay: &Layout, rho: f64, e: f64, nu: f64) -> Schedule {
        let [l, w, h] = lay.size;
        let v_solid: f64 = lay
            .diameters
            .iter()
            .map(|d| std::f64::consts::PI / 6.0 * d.powi(3))
            .sum();
        let column_top = v_solid / (FILL_FRACTION * l * w);
        let wall_h = column_top.max(h) + lay.d_max;
        let dt = self.dt_fraction * rayleigh_time(0.5 * lay.d_min, rho, e, nu);
        let fall = (2.0 * column_top / G).sqrt();
        let margin = 4.0 * lay.d_max + 0.5 * h;
        Schedule {
            column_top,
            wall_h,
            dt,
            skin: self.skin * lay.d_min,
            chunk: ((CHUNK_TIME * (lay.d_max / G).sqrt() / dt).ceil() as u64).max(10),
            v_rest: 0.01 * (G * lay.d_max).sqrt(),
            v_move: 0.05 * (G * lay.d_max).sqrt(),
            fall,
            max_fill_steps: ((fall + 40.0 * (h / G).sqrt()) / dt) as u64,
            min_flow_time: 4.0 * (h / G).sqrt(),
            max_flow_steps: (60.0 * (h / G).sqrt() / dt) as u64,
            removal_height: -2.0 * lay.d_max,
            domain: (
                [-margin - l, -margin, -margin - h],
                [2.0 * l + margin, w + margin, wall_h + margin],
            ),
        }
    }
}

/// Representative diameters (mm) of `n` classes of equal mass of `dist` truncated to `range`:
/// class j spans the truncated Q3 from j/n to (j+1)/n, and its representative is the Q3
/// quantile at the class's middle, so each class carries 1/n of the mass.
pub fn psd_classes(dist: &Distribution, range: (f64, f64), n: usize) -> Vec<f64> {
    let (q_lo, q_hi) = (dist.q3(range.0), dist.q3(range.1));
    (0..n)
        .map(|j| dist.q3_inv(q_lo + (q_hi - q_lo) * (j as f64 + 0.5) / n as f64))
        .collect()
}

/// Each diameter replaced by its class representative (`n` = 0: unchanged). A drawn set keeps
/// its mass per class, so the mass fractions stay close to 1/n each.
fn quantize(dist: &Distribution, range: (f64, f64), n: usize, d: Vec<f64>) -> Vec<f64> {
    if n == 0 {
        return d;
    }
    let reps = psd_classes(dist, range, n);
    d.into_iter()
        .map(|x| {
            let j = (truncated_q3(dist, range, x) * n as f64).floor() as usize;
            reps[j.min(n - 1)]
        })
        .collect()
}

/// How a run went, so that another code can replay it: the initial particles and the schedule.
#[derive(Debug, Clone)]
pub struct RunRecord {
    /// The contact law the run used (a replay must write the same one).
    pub class: ModelClass,
    /// Box size and particle diameters.
    pub layout: Layout,
    /// Particle centres at creation (the poured column), m, in [`Layout::diameters`] order.
    pub initial_positions: Vec<V3>,
    /// (radius, position) of every particle at the end of the fill, before the strike-off.
    pub filled: Vec<(f64, V3)>,
    /// Time step, s.
    pub dt: f64,
    /// Neighbour-list skin, m.
    pub skin: f64,
    /// Steps from the start to the strike-off.
    pub fill_steps: u64,
    /// Steps between strike-off and opening the flap (relaxation).
    pub relax_steps: u64,
    /// Steps with the flap open; particles below the floor are removed every `chunk` steps.
    pub flow_steps: u64,
    /// Steps between rest checks and particle removals.
    pub chunk: u64,
    /// Particles below this height are removed (m).
    pub removal_height: f64,
    /// Lower and upper corners of the simulation domain, m.
    pub domain: (V3, V3),
    /// Wall-clock seconds of the fill (creation to strike-off, relaxation included) and of the
    /// outflow, for the cost breakdown of a whole run.
    pub fill_seconds: f64,
    /// Wall-clock seconds of the outflow, from opening the flap to rest.
    pub flow_seconds: f64,
    /// Particles created, and left in the box after the strike-off.
    pub created: usize,
    /// The state after every chunk of steps, fill and outflow: what the rest criteria saw, and
    /// the response measured as if the run had stopped there.
    pub trace: Vec<ChunkState>,
}

/// The flank profile and its fits.
#[derive(Debug, Clone, Default)]
pub struct Flank {
    /// (x, top height) of each column on the flank.
    pub points: Vec<(f64, f64)>,
    /// Slope dz/dx of the least-squares line through the flank points, negative as the flank
    /// falls towards the open flap; the shear angle is atan(-slope) in degrees (NaN with fewer
    /// than 3 points).
    pub slope: f64,
    /// Height of that line at x = 0, m.
    pub intercept: f64,
    /// R^2 of the line (1 for a perfectly flat flank, NaN with fewer than 3 points).
    pub r2: f64,
    /// Largest gap between the least-squares quadratic and the line, relative to the height the
    /// line spans: 0 for a straight flank.
    pub curvature: f64,
}

/// The bulk density of the struck-off box of size `size`: the mass of the (radius, centre)
/// spheres inside it, a sphere cut by a face counting by its part inside, over the box's volume.
/// Every backend measures its runs with this function.
pub fn box_bulk_density(spheres: impl IntoIterator<Item = (f64, V3)>, rho: f64, size: V3) -> f64 {
    let [l, w, h] = size;
    let mass_in: f64 = spheres
        .into_iter()
        .map(|(r, x)| rho * sphere_box_volume(x, r, [0.0; 3], size))
        .sum();
    mass_in / (l * w * h)
}

/// The fraction of the struck-off mass that left the box: `removed` over `left + removed`.
pub fn outflow_fraction(left: f64, removed: f64) -> f64 {
    1.0 - left / (left + removed)
}

/// Top surface of the remaining material in columns of width ~d_max across the box (away from
/// the side walls), keeping the columns on the slope: below the struck-off rim and above the
/// floor by a particle.
pub fn measure_flank(p: &Particles, size: V3, d_max: f64) -> Flank {
    let nx = ((size[0] / d_max).floor() as usize).max(1);
    let ny = ((size[1] / d_max).floor() as usize).max(1);
    let (bx, by) = (size[0] / nx as f64, size[1] / ny as f64);
    let mut top = vec![f64::NAN; nx * ny];
    for i in 0..p.len() {
        let x = p.x[i];
        if x[0] < 0.0 || x[0] >= size[0] || x[1] < 0.0 || x[1] >= size[1] || x[2] < 0.0 {
            continue;
        }
        let (ix, iy) = ((x[0] / bx) as usize, (x[1] / by) as usize);
        let t = &mut top[iy.min(ny - 1) * nx + ix.min(nx - 1)];
        let z = x[2] + p.r[i];
        if t.is_nan() || z > *t {
            *t = z;
        }
    }
    let mut points = Vec::new();
    for ix in 0..nx {
        // Skip the columns against the side walls: wall friction holds them up.
        let ys: Vec<f64> = (1..ny.saturating_sub(1).max(1))
            .filter_map(|iy| {
                let t = top[iy * nx + ix];
                (!t.is_nan()).then_some(t)
            })
            .collect();
        if ys.is_empty() {
            continue;
        }
        let z = ys.iter().sum::<f64>() / ys.len() as f64;
        if z < size[2] - 0.5 * d_max && z > 1.5 * d_max {
            points.push(((ix as f64 + 0.5) * bx, z));
        }
    }
    let mut f = Flank {
        points,
        ..Default::default()
    };
    if f.points.len() < 3 {
        f.slope = f64::NAN;
        f.r2 = f64::NAN;
        f.curvature = f64::NAN;
        return f;
    }
    let n = f.points.len() as f64;
    let mx = f.points.iter().map(|p| p.0).sum::<f64>() / n;
    let mz = f.points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = f.points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxz: f64 = f.points.iter().map(|p| (p.0 - mx) * (p.1 - mz)).sum();
    let szz: f64 = f.points.iter().map(|p| (p.1 - mz).powi(2)).sum();
    f.slope = sxz / sxx;
    f.intercept = mz - f.slope * mx;
    f.r2 = if szz > 0.0 {
        1.0 - f
            .points
            .iter()
            .map(|p| (p.1 - f.intercept - f.slope * p.0).powi(2))
            .sum::<f64>()
            / szz
    } else {
        1.0
    };
    f.curvature = quadratic_gap(&f.points, f.slope, f.intercept);
    f
}

/// Largest gap between the least-squares quadratic and the line over the points, relative to the
/// height the line spans there.
fn quadratic_gap(pts: &[(f64, f64)], slope: f64, intercept: f64) -> f64 {
    // Normal equations of z = a + b x + c x^2 in centred x, solved by Cramer's rule.
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let s = |k: i32| pts.iter().map(|p| (p.0 - mx).powi(k)).sum::<f64>();
    let t = |k: i32| pts.iter().map(|p| (p.0 - mx).powi(k) * p.1).sum::<f64>();
    let (s0, s1, s2, s3, s4) = (n, s(1), s(2), s(3), s(4));
    let (t0, t1, t2) = (t(0), t(1), t(2));
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let a = [[s0, s1, s2], [s1, s2, s3], [s2, s3, s4]];
    let d = det3(a);
    if d.abs() < 1e-300 {
        return 0.0;
    }
    let ca = det3([[t0, s1, s2], [t1, s2, s3], [t2, s3, s4]]) / d;
    let cb = det3([[s0, t0, s2], [s1, t1, s3], [s2, t2, s4]]) / d;
    let cc = det3([[s0, s1, t0], [s1, s2, t1], [s2, s3, t2]]) / d;
    let (xmin, xmax) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.0), b.max(p.0))
        });
    let height = (slope * (xmax - xmin)).abs().max(1e-12);
    pts.iter()
        .map(|p| {
            let u = p.0 - mx;
            let quad = ca + cb * u + cc * u * u;
            (quad - (intercept + slope * p.0)).abs()
        })
        .fold(0.0, f64::max)
        / height
}

/// Positions by particle id at the previous check, to measure how far particles moved since.
struct Moves(Vec<V3>);

impl Moves {
    fn new(p: &Particles) -> Self {
        let n = p.id.iter().map(|&i| i as usize + 1).max().unwrap_or(0);
        let mut x = vec![[f64::NAN; 3]; n];
        for (k, &i) in p.id.iter().enumerate() {
            x[i as usize] = p.x[k];
        }
        Moves(x)
    }

    /// The largest displacement since the previous call of a particle in the box (x <= l);
    /// remembers the current positions.
    fn advance(&mut self, p: &Particles, l: f64) -> f64 {
        let mut most = 0.0f64;
        for (k, &i) in p.id.iter().enumerate() {
            let prev = &mut self.0[i as usize];
            if p.x[k][0] <= l {
                let d = mbgc_dem::vec3::norm2(mbgc_dem::vec3::sub(p.x[k], *prev));
                if d.is_finite() {
                    most = most.max(d);
                }
            }
            *prev = p.x[k];
        }
        most.sqrt()
    }
}

/// Largest x-z speed of a particle in the box (x <= l): the outflow's motion, without the
/// particles already past the flap.
fn max_xz_speed(p: &Particles, l: f64) -> f64 {
    (0..p.len())
        .filter(|&i| p.x[i][0] <= l)
        .map(|i| (p.v[i][0].powi(2) + p.v[i][2].powi(2)).sqrt())
        .fold(0.0, f64::max)
}

/// Translational rms speed of the particles.
fn rms_speed(p: &Particles) -> f64 {
    let (mut e, mut m) = (0.0, 0.0);
    for i in 0..p.len() {
        e += p.m[i] * (p.v[i][0].powi(2) + p.v[i][1].powi(2) + p.v[i][2].powi(2));
        m += p.m[i];
    }
    if m > 0.0 {
        (e / m).sqrt()
    } else {
        0.0
    }
}

impl Experiment for ShearBox {
    fn name(&self) -> &'static str {
        "shear-box"
    }

    fn parameters(&self) -> Vec<&'static str> {
        with_class_parameters(&OWN_PARAMETERS, &self.class, &Pair::BOTH)
    }

    fn optional_parameters(&self) -> Vec<&'static str> {
        vec!["sigma_ln"]
    }

    fn class(&self) -> Option<&ModelClass> {
        Some(&self.class)
    }

    /// Gravity, d50 and the box (k d_max) are the only lengths, and E_p, E_w and any effect
    /// parameter that is a stress (cohesion's energy density, J/m^3 = N/m^2) the only stresses:
    /// E_p, E_w, rho_p and d50 act through K_p = E_p / (rho_p g d50), K_w, and one such group per
    /// stress parameter (SJKR: Ca_pp = C_pp K_p^(-2/3), C_pp = ced_pp / (rho_p g d50), and Ca_pw;
    /// C_pp and C_pw bound the model as support groups), and the bulk density is
    /// rho_p times the solid fraction (bit-for-bit tests below). An effect parameter of any other
    /// dimension (a spring in N/m, a damper) would need a group of its own: no similarity then.
    fn similarity(&self) -> Option<Similarity> {
        Some(Similarity {
            groups: crate::similarity::bulk_groups(&self.class, &Pair::BOTH, &[])?,
            support: crate::similarity::bulk_support(&self.class, &Pair::BOTH),
            scaled: vec![ScaledResponse {
                response: "bulk_density".into(),
                factor: Monomial {
                    coefficient: 1.0,
                    powers: vec![("rho_p".into(), 1.0)],
                },
                fitted: "solid_fraction".into(),
            }],
        })
    }

    fn responses(&self) -> Vec<&'static str> {
        RESPONSES.to_vec()
    }

    fn calibration_responses(&self) -> Vec<&'static str> {
        RESPONSES[..2].to_vec()
    }

    fn check(&self, p: &ParamSet) -> Result<()> {
        materials_from(p, &self.class)?;
        p.require("rho_p", RHO_RANGE.0, RHO_RANGE.1)?;
        self.layout(p, 0).map(|_| ())
    }

    fn run(&self, p: &ParamSet, seed: u64, opts: &RunOptions) -> Result<Outcome> {
        self.run_recorded(p, seed, opts).map(|(o, _)| o)
    }
}

impl ShearBox {
    /// Runs the experiment and also returns what another code needs to replay it.
    pub fn run_recorded(
        &self,
        p: &ParamSet,
        seed: u64,
        opts: &RunOptions,
    ) -> Result<(Outcome, RunRecord)> {
        let clock = Instant::now();
        let (materials, grain, wall_mat) = materials_from(p, &self.class)?;
        let rho = p.require("rho_p", RHO_RANGE.0, RHO_RANGE.1)?;
        let lay = self.layout(p, seed)?;
        let [l, w, h] = lay.size;
        let mut warnings = Vec::new();

        // The material is poured: particles created at random, not overlapping, in a column over
        // the box's base at solid fraction FILL_FRACTION (LIGGGHTS' insert/pack does the same),
        // falling from rest.
        let mat = &materials.materials[grain as usize];
        let sched = self.schedule(&lay, rho, mat.youngs_modulus, mat.poisson);
        let col_top = sched.column_top;
        let mut rng = crate::sampling::rng(seed);
        let mut particles = Particles::new();
        let centres = random_pack(&lay.diameters, [0.0; 3], [l, w, col_top], &mut rng)?;
        for (&d, &x) in lay.diameters.iter().zip(&centres) {
            particles.add(x, 0.5 * d, rho, grain)?;
        }
        let initial_positions = particles.x.clone();
        let initial_positions_len = initial_positions.len();

        // Floor, back wall, two side walls and the flap, tall enough for the falling column.
        let wall_h = sched.wall_h;
        let rect = |name: &str, center: V3, u: V3, v: V3, hu: f64, hv: f64| {
            Wall::rect(name, center, (u, v), (hu, hv), wall_mat)
        };
        let (ex, ey, ez) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
        let walls = vec![
            rect("floor", [0.5 * l, 0.5 * w, 0.0], ex, ey, 0.5 * l, 0.5 * w)?,
            rect(
                "back",
                [0.0, 0.5 * w, 0.5 * wall_h],
                ey,
                ez,
                0.5 * w,
                0.5 * wall_h,
            )?,
            rect(
                "side_lo",
                [0.5 * l, 0.0, 0.5 * wall_h],
                ex,
                ez,
                0.5 * l,
                0.5 * wall_h,
            )?,
            rect(
                "side_hi",
                [0.5 * l, w, 0.5 * wall_h],
                ex,
                ez,
                0.5 * l,
                0.5 * wall_h,
            )?,
            rect(
                "flap",
                [l, 0.5 * w, 0.5 * wall_h],
                ey,
                ez,
                0.5 * w,
                0.5 * wall_h,
            )?,
        ];
        let flap = 4;
        let (dt, skin, domain) = (sched.dt, sched.skin, sched.domain);
        let scene = Scene {
            particles,
            walls,
            materials,
            class: self.class,
            gravity: [0.0, 0.0, -G],
            dt,
            skin,
            domain,
            max_dt_fraction: self.dt_fraction + 1e-9,
            periodic: [false; 3],
        };
        let mut sim = Simulation::new(scene)?;
        sim.set_threads(opts.threads.max(1));
        let blew =
            |e: mbgc_dem::BlowUp| Error::invalid(format!("shear box: the DEM run blew up: {e}"));

        // Fill: let the column fall and come to rest (translational speed; EPSD2 keeps particles
        // rocking, so rotational energy is no rest criterion).
        let (chunk, max_fill) = (sched.chunk, sched.max_fill_steps);
        let limits = sched.thresholds();
        let mut filled = false;
        let mut trace = Vec::new();
        let mut last = Moves::new(&sim.particles);
        while sim.step < max_fill {
            sim.run(chunk).map_err(blew)?;
            let rms = rms_speed(&sim.particles);
            let struck = (0..sim.particles.len())
                .filter(|&i| sim.particles.x[i][2] <= h)
                .map(|i| (sim.particles.r[i], sim.particles.x[i]));
            trace.push(ChunkState {
                phase: Phase::Fill,
                step: sim.step,
                time: sim.time,
                seconds: clock.elapsed().as_secs_f64(),
                rms_speed: rms,
                max_speed: max_xz_speed(&sim.particles, l),
                max_step: last.advance(&sim.particles, l),
                removed: 0,
                response: box_bulk_density(struck, rho, lay.size),
            });
            if self.rest.fill_done(&trace, &limits) {
                filled = true;
                break;
            }
        }
        if !filled {
            warnings.push("filling did not come to rest within the time limit".into());
        }
        let fill_steps = sim.step;
        let filled_state: Vec<(f64, V3)> = sim
            .particles
            .r
            .iter()
            .copied()
            .zip(sim.particles.x.iter().copied())
            .collect();
        // Strike off at the rim, then let the bed relax a little.
        let cut: Vec<bool> = sim.particles.x.iter().map(|x| x[2] > h).collect();
        sim.remove_particles(&cut);
        sim.run(chunk).map_err(blew)?;
        let bulk_density = box_bulk_density(
            sim.particles
                .r
                .iter()
                .copied()
                .zip(sim.particles.x.iter().copied()),
            rho,
            lay.size,
        );
        let n_filled = sim.particles.len();
        if let Some(dir) = &opts.vtk_dir {
            super::write_vtk(
                &dir.join("shear_box_filled.vtk"),
                &sim.particles,
                "shear box after filling",
            )?;
        }

        let fill_seconds = clock.elapsed().as_secs_f64();
        // Open the flap; material that falls off the floor's edge leaves the scene.
        sim.set_wall_active(flap, false);
        let open_step = sim.step;
        let open_time = sim.time;
        let max_flow = sim.step + sched.max_flow_steps;
        let flow_start = trace.len();
        let mut stopped = false;
        let mut left = 0;
        let mut left_mass = 0.0;
        while sim.step < max_flow {
            sim.run(chunk).map_err(blew)?;
            let gone: Vec<bool> = sim
                .particles
                .x
                .iter()
                .map(|x| x[2] < sched.removal_height)
                .collect();
            left_mass += (0..gone.len())
                .filter(|&i| gone[i])
                .map(|i| sim.particles.m[i])
                .sum::<f64>();
            let removed = sim.remove_particles(&gone);
            left += removed;
            let max_speed = max_xz_speed(&sim.particles, l);
            let rms = rms_speed(&sim.particles);
            trace.push(ChunkState {
                phase: Phase::Outflow,
                step: sim.step,
                time: sim.time,
                seconds: clock.elapsed().as_secs_f64(),
                rms_speed: rms,
                max_speed,
                max_step: last.advance(&sim.particles, l),
                removed,
                response: (-measure_flank(&sim.particles, lay.size, lay.d_max).slope)
                    .atan()
                    .to_degrees(),
            });
            if self
                .rest
                .outflow_done(&trace[flow_start..], open_time, &limits)
            {
                stopped = true;
                break;
            }
        }
        if !stopped {
            warnings.push("outflow did not come to rest within the time limit".into());
        }
        // Material still on its way out (beyond the flap line, above the floor level) is not flank.
        let flank = measure_flank(&sim.particles, lay.size, lay.d_max);
        if flank.points.len() < 3 {
            warnings.push(format!(
                "only {} flank columns: no shear angle",
                flank.points.len()
            ));
        }
        let shear_angle = (-flank.slope).atan().to_degrees();
        if let Some(path) = &opts.picture {
            side_view(path, &sim.particles, lay.size, &flank)?;
        }
        if let Some(dir) = &opts.vtk_dir {
            super::write_vtk(
                &dir.join("shear_box_final.vtk"),
                &sim.particles,
                "shear box at rest",
            )?;
        }
        let outside = sim
            .particles
            .x
            .iter()
            .filter(|x| x[0] < -lay.d_max || x[1] < -lay.d_max || x[1] > w + lay.d_max)
            .count();
        if outside > 0 {
            return Err(Error::invalid(format!(
                "shear box: {outside} particles escaped through a wall"
            )));
        }
        // Every particle is in the box, on its way out past the flap, or removed below the floor.
        if n_filled != sim.particles.len() + left {
            return Err(Error::invalid("shear box: particle bookkeeping failed"));
        }
        let mass_left: f64 = sim.particles.m.iter().sum();
        let outflow_fraction = outflow_fraction(mass_left, left_mass);
        let record = RunRecord {
            class: self.class,
            layout: lay.clone(),
            initial_positions,
            filled: filled_state,
            dt,
            skin,
            fill_steps,
            relax_steps: chunk,
            flow_steps: sim.step - open_step,
            chunk,
            removal_height: sched.removal_height,
            domain,
            fill_seconds,
            flow_seconds: clock.elapsed().as_secs_f64() - fill_seconds,
            created: initial_positions_len,
            trace,
        };
        let outcome = Outcome {
            responses: Responses {
                shear_angle,
                bulk_density,
                flank_r2: flank.r2,
                flank_curvature: flank.curvature,
                outflow_fraction,
            }
            .named(),
            diagnostics: Diagnostics {
                settled: filled && stopped,
                steps: sim.step,
                particles: n_filled,
                wall_time_s: clock.elapsed().as_secs_f64(),
                warnings,
            },
        };
        Ok((outcome, record))
    }
}

/// Side view (x-z) of the particles left in the box, with the fitted flank line.
pub fn side_view(path: &Path, p: &Particles, size: V3, flank: &Flank) -> Result<()> {
    use plotters::coord::Shift;
    use plotters::prelude::*;
    fn draw<DB: DrawingBackend>(
        root: &DrawingArea<DB, Shift>,
        p: &Particles,
        size: V3,
        flank: &Flank,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        root.fill(&WHITE)?;
        let title = format!(
            "shear box, side view: flank {:.1} deg (R^2 {:.3})",
            (-flank.slope).atan().to_degrees(),
            flank.r2
        );
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(
                -0.1 * size[0]..1.3 * size[0],
                -0.05 * size[2]..1.05 * size[2],
            )?;
        chart
            .configure_mesh()
            .x_desc("x / m")
            .y_desc("z / m")
            .draw()?;
        let px_per_m = 700.0 / (1.4 * size[0]);
        chart.draw_series(
            (0..p.len())
                .filter(|&i| p.x[i][2] > -0.05 * size[2])
                .map(|i| {
                    Circle::new(
                        (p.x[i][0], p.x[i][2]),
                        ((p.r[i] * px_per_m) as i32).max(1),
                        RGBColor(120, 120, 120).mix(0.35).filled(),
                    )
                }),
        )?;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![
                (0.0, 0.0),
                (0.0, size[2]),
                (size[0], size[2]),
                (size[0], 0.0),
                (0.0, 0.0),
            ],
            BLACK,
        )))?;
        if flank.slope.is_finite() {
            let (x0, x1) = flank
                .points
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
                    (a.min(q.0), b.max(q.0))
                });
            chart.draw_series(std::iter::once(PathElement::new(
                vec![
                    (x0, flank.intercept + flank.slope * x0),
                    (x1, flank.intercept + flank.slope * x1),
                ],
                RED.stroke_width(2),
            )))?;
            chart.draw_series(flank.points.iter().map(|q| Cross::new(*q, 4, RED)))?;
        }
        Ok(())
    }
    crate::draw_figure!(path, (800, 640), draw(p, size, flank))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_oversized_box_is_refused_naming_the_box_scale() {
        let sb = ShearBox {
            max_particles: 1000,
            ..ShearBox::default()
        };
        let p = ParamSet::from_pairs(&[("d50", 5.0), ("sigma_ln", 0.3)]);
        let e = sb.layout(&p, 1).unwrap_err().to_string();
        assert!(
            e.starts_with("--box-scale 10") && e.contains("sigma_ln = 0.3") && e.contains("1000"),
            "{e}"
        );
    }

    #[test]
    fn psd_classes_carry_equal_mass_and_quantising_keeps_the_default_draw() {
        let p = ParamSet::from_pairs(&[("d50", 8.0), ("sigma_ln", 0.15)]);
        let plain = ShearBox::default().layout(&p, 3).unwrap();
        let five = ShearBox {
            psd_classes: 5,
            ..ShearBox::default()
        }
        .layout(&p, 3)
        .unwrap();
        let dist = Distribution::LogNormal(LogNormal::new(8.0, 0.15).unwrap());
        let reps = psd_classes(&dist, default_range(&dist), 5);
        // The middle class of five of equal mass is the mass median.
        assert!((reps[2] - 8.0).abs() < 1e-9, "{reps:?}");
        assert!(reps.windows(2).all(|w| w[0] < w[1]));
        assert!(five
            .diameters
            .iter()
            .all(|d| reps.iter().any(|r| (r * 1e-3 - d).abs() < 1e-12)));
        // Same box, about the same solid volume.
        assert_eq!(plain.size, five.size);
        let vol = |l: &Layout| l.diameters.iter().map(|d| d.powi(3)).sum::<f64>();
        assert!((vol(&five) / vol(&plain) - 1.0).abs() < 0.03);
    }

    /// A monodisperse scene scaled by powers of two: the scaled floating-point numbers are exact,
    /// so a run with the same dimensionless groups must repeat bit for bit.
    fn scaled_run(d50: f64, rho: f64, e: f64) -> (f64, f64, u64) {
        scaled_cohesive_run(d50, rho, e, None)
    }

    /// The scaled run, with SJKR cohesion of energy density `ced` (particle-particle; the wall's
    /// is half of it) when given.
    fn scaled_cohesive_run(d50: f64, rho: f64, e: f64, ced: Option<f64>) -> (f64, f64, u64) {
        let mut p = ParamSet::from_pairs(&[
            ("E_p", e),
            ("E_w", 2.0 * e),
            ("nu_p", 0.3),
            ("rho_p", rho),
            ("d50", d50),
            ("e_pp", 0.5),
            ("e_pw", 0.5),
            ("mu_pp", 0.5),
            ("mu_pw", 0.4),
            ("mu_r_pp", 0.3),
            ("mu_r_pw", 0.3),
        ]);
        let mut sb = ShearBox {
            box_scale: 5.0,
            ..ShearBox::default()
        };
        if let Some(c) = ced {
            p.set("ced_pp", c);
            p.set("ced_pw", 0.5 * c);
            sb.class = ModelClass::parse("hertz,mindlin,epsd2,sjkr").unwrap();
        }
        let o = sb.run(&p, 7, &RunOptions::default()).unwrap();
        let get = |n: &str| o.responses.iter().find(|r| r.0 == n).unwrap().1;
        (get("shear_angle"), get("bulk_density"), o.diagnostics.steps)
    }

    #[test]
    fn the_run_depends_on_e_rho_and_d50_only_through_the_dimensionless_stiffness() {
        let base = scaled_run(4.0, 2000.0, 4e6);
        assert!(base.0.is_finite() && base.0 > 5.0, "{base:?}");
        // Denser and stiffer by 4: the same solid fraction (density times 4) and angle.
        let heavy = scaled_run(4.0, 8000.0, 16e6);
        assert_eq!(heavy.0.to_bits(), base.0.to_bits(), "{heavy:?} {base:?}");
        assert_eq!(heavy.1.to_bits(), (4.0 * base.1).to_bits());
        assert_eq!(heavy.2, base.2);
        // Four times larger and stiffer: the same run in units of d and sqrt(d / g). Before the
        // check interval scaled with sqrt(d_max / g) the step counts differed.
        let big = scaled_run(16.0, 2000.0, 16e6);
        assert_eq!(big.0.to_bits(), base.0.to_bits(), "{big:?} {base:?}");
        assert_eq!(big.1.to_bits(), base.1.to_bits());
        assert_eq!(big.2, base.2);
        // And a different stiffness is a different run.
        let stiff = scaled_run(4.0, 2000.0, 16e6);
        assert_ne!(stiff.2, base.2);
    }

    /// With SJKR the energy density is one more stress: scaled with E (C = ced / (rho_p g d50)
    /// held), the run repeats bit for bit; the similarity offers the Hertz contact's pull
    /// Ca = C K^(-2/3) for each pair as groups.
    #[test]
    fn cohesion_acts_through_its_energy_density_per_particle_weight() {
        let base = scaled_cohesive_run(4.0, 2000.0, 4e6, Some(2e4));
        assert!(base.0.is_finite(), "{base:?}");
        let heavy = scaled_cohesive_run(4.0, 8000.0, 16e6, Some(8e4));
        assert_eq!(heavy.0.to_bits(), base.0.to_bits(), "{heavy:?} {base:?}");
        assert_eq!(heavy.1.to_bits(), (4.0 * base.1).to_bits());
        assert_eq!(heavy.2, base.2);
        let big = scaled_cohesive_run(16.0, 2000.0, 16e6, Some(8e4));
        assert_eq!(big.0.to_bits(), base.0.to_bits(), "{big:?} {base:?}");
        assert_eq!(big.1.to_bits(), base.1.to_bits());
        // Cohesion changes the run: it is not a group that does nothing.
        let dry = scaled_run(4.0, 2000.0, 4e6);
        assert_ne!(dry.2, base.2);
        let sb = ShearBox {
            class: ModelClass::parse("hertz,mindlin,epsd2,sjkr").unwrap(),
            ..ShearBox::default()
        };
        let sim = sb.similarity().expect("sjkr keeps a similarity");
        let names: Vec<&str> = sim.groups.iter().map(|g| g.name.as_str()).collect();
        assert_eq!(names, ["K_p", "K_w", "Ca_pp", "Ca_pw"]);
        let at = |n: &str| match n {
            "ced_pp" | "ced_pw" => 2e4,
            "rho_p" => 2000.0,
            "d50" => 4.0,
            "E_p" => 4e6,
            "E_w" => 32e6,
            _ => f64::NAN,
        };
        let weight = 2000.0 * G * 4e-3;
        let k = |e: f64| e / weight;
        let v = sim.groups[2].monomial.value(at);
        let want = 2e4 / weight * k(4e6).powf(-2.0 / 3.0);
        assert!((v / want - 1.0).abs() < 1e-12, "{v} {want}");
        // The wall's pull takes E_p (the limit of a stiffer wall), not E_w.
        let w = sim.groups[3].monomial.value(at);
        assert!((w / want - 1.0).abs() < 1e-12, "{w} {want}");
    }

    #[test]
    fn the_schedule_is_the_same_in_units_of_d_max_and_sqrt_d_max_over_g() {
        let sb = ShearBox::default();
        let sched = |d50: f64, e: f64| {
            let p = ParamSet::from_pairs(&[("d50", d50), ("sigma_ln", 0.2)]);
            let lay = sb.layout(&p, 3).unwrap();
            let t = (lay.d_max / G).sqrt();
            let s = sb.schedule(&lay, 2600.0, e, 0.3);
            (
                s.chunk,
                s.max_fill_steps,
                s.max_flow_steps,
                s.column_top / lay.d_max,
                s.min_flow_time / t,
                s.fall / t,
                s.v_rest / (G * lay.d_max).sqrt(),
            )
        };
        let (a, b) = (sched(2.0, 5e6), sched(18.0, 4.5e7));
        assert_eq!((a.0, a.1, a.2), (b.0, b.1, b.2));
        for (x, y) in [(a.3, b.3), (a.4, b.4), (a.5, b.5), (a.6, b.6)] {
            assert!((x / y - 1.0).abs() < 1e-9, "{a:?} {b:?}");
        }
    }
}
