//! Clogging silo (issue 41): avalanches of grains through an orifice of a few particle diameters
//! in a flat-bottomed silo, each ended by an arch that clogs the orifice and broken by a puff
//! from below, the numerical stand-in for the air blow or tap with which silo experiments
//! restart the flow (Zuriguel et al. 2005, Phys. Rev. E 71, 051303, measured avalanches between
//! such restarts). The question it answers is one a plant asks: will
//! this material flow through this outlet, and how much passes between blockages? The
//! published trend: avalanche sizes are exponentially distributed beyond the smallest (their
//! standard deviation near their mean), and their mean grows steeply with the orifice, diverging
//! near D_o / d ~ 5 for spheres (Zuriguel et al. 2005; To et al. 2001 in 2D).
//!
//! Everything is in particle diameters, so a material drives the silo at its own size: the
//! orifice D_o = `orifice` d50, the silo diameter the larger of [`SILO_DIAMETER`] d50 and
//! 3 D_o.
//!
//! Procedure
//! 1. Fill: `fill` grains (d50, and sigma_ln when given: log-normal in mass about d50, drawn
//!    by number) inserted at random, none touching, in the silo above the closed orifice
//!    (a column about three times as tall as the settled fill whatever the size distribution;
//!    a lattice spaced for the largest grain stood 6.7 m tall for 3000 grains of sigma_ln
//!    0.26); settle until the translational kinetic energy per particle is that of a grain
//!    moving at 1 % of sqrt(g d50).
//! 2. Open the orifice. A grain passes when its centre is one d_max below the orifice plane;
//!    grains three d_max below it are removed, so that nothing piles up under the silo.
//! 3. A clog: no grain has passed for [`QUIET_TIMES`] sqrt(D_o / g) (the hopper's criterion)
//!    since the last grain passed or since the last puff's grains fell back (2 v / g after
//!    the puff, v its largest upward speed). The grains that passed since the flow
//!    (re)started make one avalanche. A puff then gives every grain whose centre lies within
//!    D_o of the orifice's centre a random velocity: upward between 0.5 and 1 times
//!    sqrt(2 g D_o) (enough to lift it by up to D_o), sideways up to half that, from the run's
//!    seed. A puff after which no grain passes is counted (`failed_puffs`), and the silo is
//!    puffed again, harder ([`PUFF_BOOST`]), at most [`MAX_FAILED_PUFFS`] times in a row. A
//!    fill that clogs as the orifice opens, before a grain has passed, is puffed as well; that
//!    is no failed puff.
//! 4. Stop when `max_avalanches` avalanches are complete, or when fewer than half the fill is left
//!    in the silo (the head over the orifice then falls; a silo's pressure at the orifice
//!    does not depend on the head only above about one silo diameter, Janssen), or at a time
//!    limit. An avalanche still flowing then is cut off: its size so far is `open_avalanche`;
//!    it is no avalanche of `avalanches` or `avalanche_cv`, but its grains are in
//!    `mean_avalanche`.
//!
//! Responses
//! - `mean_avalanche`: grains passed per clog, (sum of the complete avalanches + the open one)
//!   / complete avalanches. Without an open avalanche that is their mean; with one it is the
//!   maximum-likelihood mean of an exponential distribution whose last sample was cut off by
//!   the end of the run, which the plain mean of the complete ones underestimates (long
//!   avalanches are the ones cut off). NaN without a clog: `discharged` is then a lower bound,
//!   and the run has the event [`NO_CLOG`] ([`NO_FLOW`] if no grain passed at all), whose
//!   share over a posterior `mbgc propagate` reports.
//! - `avalanche_cv`: the complete avalanches' standard deviation over their mean (1 for an
//!   exponential distribution; NaN with fewer than 2).
//! - `avalanches`: complete avalanches; `open_avalanche`: the censored one's size (0 if the
//!   run ended clogged); `discharged`: grains passed in all; `failed_puffs`.
//! - `bulk_density` (kg/m^3): the settled fill's, below one d_max under its free surface.
//! - the diagnostic `settled`: the run ended by its own rule (`max_avalanches`, or half the
//!   fill passed), not at its time limit or on an arch that [`MAX_FAILED_PUFFS`] puffs did not
//!   break (both warn).
//!
//! The first avalanche starts from a settled fill, the others from a puffed arch; experiments
//! count both alike (To et al. refilled for every avalanche, Zuriguel et al. puffed).
//! [`ClogSiloRun::sizes`] keeps every avalanche in order for a distribution. With a VTK
//! directory a run writes the fill, the settled fill, every clog and the end.

use std::f64::consts::PI;
use std::time::Instant;

use rand::RngExt;

use super::{
    materials_from, with_class_parameters, Diagnostics, Experiment, Outcome, ParamSet, RunOptions,
    RHO_RANGE,
};
use crate::error::{Error, Result};
use crate::psd::{draw_by_number, sizes_drawn, Distribution};
use mbgc_dem::contact::{ModelClass, Pair};
use mbgc_dem::material::Materials;
use mbgc_dem::sim::{Scene, Simulation};
use mbgc_dem::timestep::rayleigh_time;
use mbgc_dem::walls::{Shape, Wall};

/// Smallest silo diameter in d50: three orifices of 4 d50, where a default run already sees
/// only a few clogs (docs/clogging_silo.md), and small enough to keep a fill cheap.
pub const SILO_DIAMETER: f64 = 12.0;
/// Default orifice diameter in d50: avalanches of some tens of grains for frictional spheres.
pub const DEFAULT_ORIFICE: f64 = 3.0;
/// Accepted orifice diameters in d50: below 1.5 a single grain stops the flow; above 8 a clog
/// would need far more grains than a run holds (at 4 d50 the mean avalanche of frictional beads
/// is already about 450, docs/clogging_silo.md).
pub const ORIFICE_RANGE: (f64, f64) = (1.5, 8.0);
/// Default fill, grains.
pub const DEFAULT_FILL: f64 = 3000.0;
/// Default number of avalanches a run records.
pub const DEFAULT_AVALANCHES: f64 = 30.0;
/// A clog is declared after no grain has passed for this many sqrt(D_o / g).
pub const QUIET_TIMES: f64 = 4.0;
/// Puffs in a row after which no grain passes before a run gives up (and warns).
pub const MAX_FAILED_PUFFS: usize = 20;
/// A puff after k failed ones in a row is `1 + PUFF_BOOST k` times as fast, up to
/// [`MAX_PUFF_BOOST`] times: an operator blows harder on an arch that held. A puff of fixed
/// strength left two of three bead runs at 2 d stopped on 20 failed puffs; with the boost one
/// of three still was (docs/clogging_silo.md), so at 2 d a run may end on an unbroken arch.
pub const PUFF_BOOST: f64 = 0.25;
/// The strongest puff, in units of the first.
pub const MAX_PUFF_BOOST: f64 = 3.0;
/// Time step as a fraction of the Rayleigh time of the smallest particle.
pub const DT_FRACTION: f64 = 0.2;
/// Gravitational acceleration, m/s^2, along -z.
pub const GRAVITY: f64 = 9.81;
/// Most grains a run may hold.
pub const MAX_PARTICLES: f64 = 500_000.0;

/// The parameters the silo needs whatever the model class.
pub const OWN_PARAMETERS: [&str; 5] = ["E_p", "E_w", "nu_p", "rho_p", "d50"];

/// The response names, in output order.
pub const RESPONSES: [&str; 7] = [
    "mean_avalanche",
    "avalanche_cv",
    "avalanches",
    "open_avalanche",
    "discharged",
    "failed_puffs",
    "bulk_density",
];

/// The event of a run that ended without a clog (half the fill passed in one avalanche, or the
/// time limit came first): its mean avalanche is only known to exceed `discharged`.
pub const NO_CLOG: &str = "no_clog";
/// The event of a run in which no grain passed: the fill arched as the orifice opened and no
/// puff broke the arch.
pub const NO_FLOW: &str = "no_flow";
/// What either event leaves without a value.
const VOIDED: [&str; 2] = ["mean_avalanche", "avalanche_cv"];

/// The clogging silo. Parameters: [`OWN_PARAMETERS`] (d50 in mm) and the model class's;
/// optional `sigma_ln` (0 or absent: monosized), `orifice` (D_o / d50, default
/// [`DEFAULT_ORIFICE`]), `fill` (grains, default [`DEFAULT_FILL`]) and
/// `max_avalanches` (default [`DEFAULT_AVALANCHES`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct ClogSilo {
    /// The effects of the contact law.
    pub class: ModelClass,
}

/// Everything a run measured, beyond its [`Outcome`].
#[derive(Debug, Clone)]
pub struct ClogSiloRun {
    /// Responses and diagnostics as every experiment reports them.
    pub outcome: Outcome,
    /// The complete avalanches in the order they happened, grains.
    pub sizes: Vec<usize>,
    /// Simulated time of each complete avalanche, from the opening or the puff that started it
    /// to its last grain, s.
    pub durations: Vec<f64>,
    /// Orifice and silo diameters, m.
    pub orifice: f64,
    /// Silo diameter, m.
    pub silo: f64,
    /// Time step, s.
    pub dt: f64,
}

/// A checked parameter set.
struct Setup {
    materials: Materials,
    grain: u16,
    wall: u16,
    rho: f64,
    /// m.
    d50: f64,
    dist: Option<Distribution>,
    /// Size range drawn, m.
    d_min: f64,
    d_max: f64,
    /// Orifice and silo diameters, m.
    orifice: f64,
    silo: f64,
    particles: usize,
    avalanches: usize,
    dt: f64,
}

impl ClogSilo {
    fn setup(&self, p: &ParamSet) -> Result<Setup> {
        let (materials, grain, wall) = materials_from(p, &self.class)?;
        let rho = p.require("rho_p", RHO_RANGE.0, RHO_RANGE.1)?;
        let d50_mm = p.require("d50", 1e-3, 1e3)?;
        let sigma = p.optional("sigma_ln", 0.0, 0.0, 1.5)?;
        let ratio = p.optional("orifice", DEFAULT_ORIFICE, ORIFICE_RANGE.0, ORIFICE_RANGE.1)?;
        let count = p.optional("fill", DEFAULT_FILL, 50.0, MAX_PARTICLES)?;
        let avalanches = p.optional("max_avalanches", DEFAULT_AVALANCHES, 1.0, 1e5)?;
        for (name, v) in [("fill", count), ("max_avalanches", avalanches)] {
            if v.fract() != 0.0 {
                return Err(Error::invalid(format!(
                    "parameter {name} = {v}: expected a whole number"
                )));
            }
        }
        let (dist, d_min_mm, d_max_mm) = sizes_drawn(d50_mm, sigma)?;
        let d50 = d50_mm * 1e-3;
        let orifice = ratio * d50;
        if orifice <= d_max_mm * 1e-3 {
            return Err(Error::invalid(format!(
                "parameter orifice = {ratio}: the orifice ({:.3} mm) is no wider than the \
                 largest grain ({d_max_mm:.3} mm, sigma_ln = {sigma}); expected orifice > {:.3}",
                orifice * 1e3,
                d_max_mm / d50_mm
            )));
        }
        let silo = (SILO_DIAMETER * d50).max(3.0 * orifice);
        let mat = &materials.materials[grain as usize];
        let d_min = d_min_mm * 1e-3;
        let dt = DT_FRACTION * rayleigh_time(0.5 * d_min, rho, mat.youngs_modulus, mat.poisson);
        Ok(Setup {
            materials,
            grain,
            wall,
            rho,
            d50,
            dist,
            d_min,
            d_max: d_max_mm * 1e-3,
            orifice,
            silo,
            particles: count as usize,
            avalanches: avalanches as usize,
            dt,
        })
    }

    fn diameters(&self, s: &Setup, seed: u64) -> Result<Vec<f64>> {
        let Some(dist) = &s.dist else {
            return Ok(vec![s.d50; s.particles]);
        };
        let set = draw_by_number(
            dist,
            (Some(s.d_min * 1e3), Some(s.d_max * 1e3)),
            s.particles,
            seed,
            "clogging-silo",
        )?;
        Ok(set.diameters_mm.iter().map(|d| d * 1e-3).collect())
    }

    /// Runs the experiment and returns every avalanche as well.
    pub fn run_detailed(&self, p: &ParamSet, seed: u64, opts: &RunOptions) -> Result<ClogSiloRun> {
        let clock = Instant::now();
        let s = self.setup(p)?;
        let mut warnings = Vec::new();
        let diam = self.diameters(&s, seed)?;
        let n = diam.len();
        let mut rng = crate::sampling::rng(seed);
        // The diameters used the seed's first stream; the fill the second, the puffs the third.
        rng.set_stream(1);
        let radius = 0.5 * s.silo;
        let particles =
            super::cylinder_fill::random_fill(&diam, radius, s.d_max, s.rho, s.grain, &mut rng)?;
        rng.set_stream(2);
        let z_top = particles.x.iter().map(|x| x[2]).fold(0.0, f64::max) + s.d_max;
        let (w, r_o) = (s.wall, 0.5 * s.orifice);
        let z_floor = -5.0 * s.d_max;
        let walls = vec![
            Wall::new(
                "silo",
                Shape::Cylinder {
                    center: [0.0; 3],
                    radius,
                    z_min: 0.0,
                    z_max: z_top,
                },
                w,
            )?,
            Wall::new(
                "bottom",
                Shape::OrificePlate {
                    center: [0.0; 3],
                    orifice_radius: r_o,
                    outer_radius: radius,
                },
                w,
            )?,
            Wall::new(
                "shutter",
                Shape::OrificePlate {
                    center: [0.0; 3],
                    orifice_radius: 0.0,
                    outer_radius: r_o,
                },
                w,
            )?,
            // Below the removal level: a grain that reaches it is removed at the next check.
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
                [-radius - margin, -radius - margin, z_floor - margin],
                [radius + margin, radius + margin, z_top + margin],
            ),
            max_dt_fraction: 0.3,
            periodic: [false; 3],
        };
        let mut sim = Simulation::new(scene)?;
        sim.set_threads(opts.threads);
        let blew = |stage: &str, e: mbgc_dem::BlowUp| {
            Error::invalid(format!("clogging-silo run ({stage}) stopped: {e}"))
        };
        let g = GRAVITY;
        let m_mean = sim.particles.m.iter().sum::<f64>() / n as f64;
        let ke_rest = 0.5 * m_mean * 1e-4 * g * s.d50;
        // Checks every 0.05 sqrt(d50 / g): 1 ms at 4 mm.
        let chunk = ((0.05 * (s.d50 / g).sqrt() / s.dt).round() as u64).max(1);

        let mut vtk_index = 0usize;
        let mut vtk = |sim: &Simulation, label: &str| -> Result<()> {
            if let Some(dir) = &opts.vtk_dir {
                let path = dir.join(format!("silo_{vtk_index:04}.vtk"));
                super::write_vtk(&path, &sim.particles, label)?;
                vtk_index += 1;
            }
            Ok(())
        };
        vtk(&sim, "clogging silo: filled")?;

        // 1. Settle.
        let t_fall = (2.0 * z_top / g).sqrt();
        let settle_cap = 2.0 * t_fall + 40.0 * (s.d50 / g).sqrt();
        if let Some(w) = super::cylinder_fill::settle(
            &mut sim,
            chunk,
            t_fall,
            settle_cap,
            ke_rest,
            "clogging-silo",
        )? {
            warnings.push(format!("{w}; opened anyway"));
        }
        let bulk_density = settled_density(&sim, radius, s.d_max, s.rho);
        vtk(&sim, "clogging silo: settled")?;

        // 2.-4. Avalanches.
        sim.set_wall_active(SHUTTER, false);
        let (z_pass, z_remove) = (-s.d_max, -3.0 * s.d_max);
        let t_quiet = QUIET_TIMES * (s.orifice / g).sqrt();
        let v_puff = (2.0 * g * s.orifice).sqrt();
        // The fastest puffed grain is back down after 2 v / g: the quiet time after a puff
        // counts from then, not while the puffed grains are still in the air.
        let t_flight = 2.0 * MAX_PUFF_BOOST * v_puff / g;
        let mut passed = vec![false; n];
        let (mut discharged, mut current) = (0usize, 0usize);
        let (mut sizes, mut durations) = (Vec::new(), Vec::new());
        let (mut failed_puffs, mut failed_in_a_row) = (0usize, 0usize);
        let mut started = sim.time;
        let mut last_pass = sim.time;
        let mut last_event = sim.time;
        // Whether the flow was last restarted by a puff (false at the opening): a clog with no
        // grain passed is a failed puff only then.
        let mut after_puff = false;
        // Generous: eight quiet times and the longest puff's flight per avalanche and per failed
        // puff allowed in a row, and half the fill flowing out at no less than 20 grains per
        // quiet time.
        let t_cap = sim.time
            + (s.avalanches + MAX_FAILED_PUFFS) as f64 * (8.0 * t_quiet + t_flight)
            + n as f64 * t_quiet / 20.0;
        let t_open = sim.time;
        // Whether the run ended by its own rule (its avalanches, or half the fill passed), not
        // at the time limit or on an arch no puff breaks.
        let mut settled = false;
        loop {
            sim.run(chunk).map_err(|e| blew("discharge", e))?;
            let t = sim.time;
            let p = &sim.particles;
            let mut remove = vec![false; p.len()];
            let mut any_removed = false;
            for ((x, &id), gone) in p.x.iter().zip(&p.id).zip(remove.iter_mut()) {
                let id = id as usize;
                if !passed[id] && x[2] < z_pass {
                    passed[id] = true;
                    discharged += 1;
                    current += 1;
                    last_pass = t;
                }
                if x[2] < z_remove {
                    *gone = true;
                    any_removed = true;
                }
            }
            if any_removed {
                sim.remove_particles(&remove);
            }
            let in_silo = n - discharged;
            if 2 * in_silo < n {
                settled = true;
                break;
            }
            if t - last_pass.max(last_event) < t_quiet {
                if t > t_cap {
                    warnings.push(format!(
                        "stopped at the time limit ({:.2} s after opening) with {} of {} \
                         avalanches",
                        t - t_open,
                        sizes.len(),
                        s.avalanches
                    ));
                    break;
                }
                continue;
            }
            // Clogged.
            vtk(&sim, "clogging silo: clogged")?;
            if current > 0 {
                sizes.push(current);
                durations.push(last_pass - started);
                current = 0;
                failed_in_a_row = 0;
            } else if after_puff {
                failed_puffs += 1;
                failed_in_a_row += 1;
            }
            if sizes.len() >= s.avalanches {
                settled = true;
                break;
            }
            if failed_in_a_row >= MAX_FAILED_PUFFS {
                warnings.push(format!(
                    "{MAX_FAILED_PUFFS} puffs in a row did not restart the flow; stopped with {} \
                     avalanches",
                    sizes.len()
                ));
                break;
            }
            let boost = (1.0 + PUFF_BOOST * failed_in_a_row as f64).min(MAX_PUFF_BOOST);
            puff(&mut sim, s.orifice, boost * v_puff, &mut rng);
            after_puff = true;
            started = sim.time;
            last_event = sim.time + 2.0 * boost * v_puff / g;
        }
        vtk(&sim, "clogging silo: final")?;
        let open_avalanche = current;
        if sizes.len() < s.avalanches && 2 * (n - discharged) < n {
            warnings.push(format!(
                "half the fill has passed after {} of {} avalanches (raise fill for more)",
                sizes.len(),
                s.avalanches
            ));
        }
        let (_, cv) = mean_and_cv(&sizes);
        let mean = if sizes.is_empty() {
            f64::NAN
        } else {
            discharged as f64 / sizes.len() as f64
        };
        let responses = vec![
            ("mean_avalanche".to_string(), mean),
            ("avalanche_cv".into(), cv),
            ("avalanches".into(), sizes.len() as f64),
            ("open_avalanche".into(), open_avalanche as f64),
            ("discharged".into(), discharged as f64),
            ("failed_puffs".into(), failed_puffs as f64),
            ("bulk_density".into(), bulk_density),
        ];
        Ok(ClogSiloRun {
            outcome: Outcome {
                responses,
                diagnostics: Diagnostics {
                    settled,
                    steps: sim.step,
                    particles: n,
                    wall_time_s: clock.elapsed().as_secs_f64(),
                    warnings,
                },
            },
            sizes,
            durations,
            orifice: s.orifice,
            silo: s.silo,
            dt: s.dt,
        })
    }
}

/// The puff that breaks an arch: every grain whose centre lies within `orifice` of the
/// orifice's centre gets a random velocity, upward between 0.5 and 1 times `v`, sideways up to
/// half of `v` along each horizontal axis.
fn puff(sim: &mut Simulation, orifice: f64, v: f64, rng: &mut rand_chacha::ChaCha8Rng) {
    let p = &mut sim.particles;
    for i in 0..p.len() {
        let x = p.x[i];
        if x[0] * x[0] + x[1] * x[1] + x[2] * x[2] < orifice * orifice {
            let mut side = || (rng.random::<f64>() - 0.5) * v;
            let (vx, vy) = (side(), side());
            let vz = (0.5 + 0.5 * rng.random::<f64>()) * v;
            p.v[i] = [vx, vy, vz];
        }
    }
}

/// The settled fill's bulk density: rho_p times the solid fraction of the silo from the bottom
/// to one d_max below the free surface, taken as the mean top of the highest tenth of the
/// grains (about the top layers of a default fill).
fn settled_density(sim: &Simulation, radius: f64, d_max: f64, rho: f64) -> f64 {
    let p = &sim.particles;
    let n = p.len();
    // The free surface: the mean height of the highest tenth of the grains' tops.
    let mut tops: Vec<f64> = (0..n).map(|i| p.x[i][2] + p.r[i]).collect();
    tops.sort_by(f64::total_cmp);
    let k = (n / 10).max(1);
    let surface = tops[n - k..].iter().sum::<f64>() / k as f64;
    let h = (surface - d_max).max(0.5 * surface);
    let solid: f64 = (0..n)
        .map(|i| {
            let (z, r) = (p.x[i][2], p.r[i]);
            // The part of the sphere below h, whole or a cap (the walls cut none: the grains
            // are inside the cylinder).
            let below = (h - (z - r)).clamp(0.0, 2.0 * r);
            PI * below * below * (3.0 * r - below) / 3.0
        })
        .sum();
    rho * solid / (PI * radius * radius * h)
}

/// Mean and coefficient of variation (sample sd over mean) of avalanche sizes; NaN where
/// undefined (no avalanche, or fewer than two for the CV).
pub fn mean_and_cv(sizes: &[usize]) -> (f64, f64) {
    if sizes.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let k = sizes.len() as f64;
    let mean = sizes.iter().sum::<usize>() as f64 / k;
    if sizes.len() < 2 {
        return (mean, f64::NAN);
    }
    let var = sizes
        .iter()
        .map(|&s| (s as f64 - mean).powi(2))
        .sum::<f64>()
        / (k - 1.0);
    (mean, var.sqrt() / mean)
}

impl Experiment for ClogSilo {
    fn name(&self) -> &'static str {
        "clogging-silo"
    }

    fn parameters(&self) -> Vec<&'static str> {
        with_class_parameters(&OWN_PARAMETERS, &self.class, &Pair::BOTH)
    }

    fn optional_parameters(&self) -> Vec<&'static str> {
        vec!["sigma_ln", "orifice", "fill", "max_avalanches"]
    }

    fn class(&self) -> Option<&ModelClass> {
        Some(&self.class)
    }

    fn calibration_responses(&self) -> Vec<&'static str> {
        vec!["mean_avalanche"]
    }

    fn responses(&self) -> Vec<&'static str> {
        RESPONSES.to_vec()
    }

    fn events(&self) -> Vec<&'static str> {
        vec![NO_CLOG, NO_FLOW]
    }

    fn voided_by(&self, event: &str) -> Vec<&'static str> {
        match event {
            NO_CLOG | NO_FLOW => VOIDED.to_vec(),
            _ => Vec::new(),
        }
    }

    fn event_of(&self, value: &dyn Fn(&str) -> Option<f64>) -> Option<&'static str> {
        let (clogs, passed) = (value("avalanches")?, value("discharged")?);
        match (clogs, passed) {
            (c, d) if c == 0.0 && d == 0.0 => Some(NO_FLOW),
            (c, d) if c == 0.0 && d > 0.0 => Some(NO_CLOG),
            _ => None,
        }
    }

    fn check(&self, p: &ParamSet) -> Result<()> {
        self.setup(p).map(|_| ())
    }

    fn run(&self, p: &ParamSet, seed: u64, opts: &RunOptions) -> Result<Outcome> {
        self.run_detailed(p, seed, opts).map(|r| r.outcome)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_without_a_clog_or_without_flow_is_an_event_that_voids_the_mean() {
        let silo = ClogSilo::default();
        let run = |clogs: f64, passed: f64| {
            move |n: &str| match n {
                "avalanches" => Some(clogs),
                "discharged" => Some(passed),
                _ => None,
            }
        };
        assert_eq!(silo.event_of(&run(0.0, 1500.0)), Some(NO_CLOG));
        assert_eq!(silo.event_of(&run(0.0, 0.0)), Some(NO_FLOW));
        assert_eq!(silo.event_of(&run(3.0, 900.0)), None);
        assert_eq!(silo.event_of(&|_: &str| None), None);
        for e in silo.events() {
            assert_eq!(silo.voided_by(e), vec!["mean_avalanche", "avalanche_cv"]);
        }
    }

    fn beads(orifice: f64, fill: f64, max_avalanches: f64) -> ParamSet {
        let mut p = ParamSet::new();
        for (k, v) in [
            ("E_p", 5e6),
            ("E_w", 5e6),
            ("nu_p", 0.3),
            ("rho_p", 2500.0),
            ("d50", 4.0),
            ("e_pp", 0.5),
            ("e_pw", 0.5),
            ("mu_pp", 0.5),
            ("mu_pw", 0.5),
            ("mu_r_pp", 0.1),
            ("mu_r_pw", 0.1),
            ("orifice", orifice),
            ("fill", fill),
            ("max_avalanches", max_avalanches),
        ] {
            p.set(k, v);
        }
        p
    }

    /// The published trend (Zuriguel et al. 2005 in 3D, To et al. 2001 in 2D) on a small
    /// silo of 600 frictional beads: the avalanche sizes spread like an exponential
    /// distribution (sd near the mean), and one more bead diameter of orifice multiplies the
    /// mean avalanche many times (on 3000 beads, three seeds: 9.4 grains at 2.5 d, 25.1 at 3 d,
    /// docs/clogging_silo.md).
    #[test]
    fn avalanches_are_exponential_and_grow_steeply_with_the_orifice() {
        let silo = ClogSilo::default();
        let opts = RunOptions::default();
        let narrow = silo
            .run_detailed(&beads(2.5, 600.0, 20.0), 1, &opts)
            .unwrap();
        assert_eq!(narrow.sizes.len(), 20, "{:?}", narrow.outcome);
        let (plain, cv) = mean_and_cv(&narrow.sizes);
        let mean = narrow.outcome.get("mean_avalanche").unwrap();
        assert!((3.0..25.0).contains(&mean), "{:?}", narrow.sizes);
        assert!((0.5..1.5).contains(&cv), "cv {cv}: {:?}", narrow.sizes);
        // Stopped at its 20th clog: nothing was cut off, so the estimate is the plain mean.
        assert_eq!(narrow.outcome.get("open_avalanche"), Some(0.0));
        assert_eq!(mean, plain);
        let wide = silo
            .run_detailed(&beads(3.5, 600.0, 20.0), 1, &opts)
            .unwrap();
        // Half the fill passes first: the wide orifice's avalanches are few and long. Without
        // any clog, what passed is a lower bound of the mean.
        let wide_mean = match wide.outcome.get("mean_avalanche").unwrap() {
            m if m.is_nan() => wide.outcome.get("discharged").unwrap(),
            m => m,
        };
        assert!(
            wide_mean > 5.0 * mean,
            "{wide_mean} vs {mean}: {:?} {:?}",
            wide.outcome,
            narrow.sizes
        );
        let responses: Vec<&str> = wide
            .outcome
            .responses
            .iter()
            .map(|r| r.0.as_str())
            .collect();
        assert_eq!(responses, RESPONSES);
        assert_eq!(
            wide.outcome.get("discharged").unwrap() as usize,
            wide.sizes.iter().sum::<usize>() + wide.outcome.get("open_avalanche").unwrap() as usize
        );
    }

    #[test]
    fn an_orifice_no_wider_than_a_grain_and_fractional_counts_are_refused() {
        let silo = ClogSilo::default();
        silo.check(&beads(1.5, 800.0, 5.0)).unwrap();
        let mut p = beads(1.5, 800.0, 5.0);
        p.set("sigma_ln", 0.3);
        let e2 = silo.check(&p).unwrap_err().to_string();
        assert!(
            e2.contains("orifice") && e2.contains("largest grain"),
            "{e2}"
        );
        let e3 = silo.check(&beads(3.0, 800.5, 5.0)).unwrap_err().to_string();
        assert!(e3.contains("fill") && e3.contains("whole number"), "{e3}");
        let e4 = silo.check(&beads(9.0, 800.0, 5.0)).unwrap_err().to_string();
        assert!(e4.contains("orifice"), "{e4}");
    }

    #[test]
    fn mean_and_cv_of_sizes() {
        let (m, cv) = mean_and_cv(&[2, 4, 6]);
        assert_eq!(m, 4.0);
        assert!((cv - 0.5).abs() < 1e-12);
        assert!(mean_and_cv(&[]).0.is_nan());
        assert!(mean_and_cv(&[3]).1.is_nan());
    }
}
