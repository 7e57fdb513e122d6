//! The shear cell (a translational split cell after Jenike, ASTM D6128; the procedure of a ring
//! shear tester, ASTM D6773): the material is poured into a box split horizontally at mid
//! height, consolidated under a servo-controlled lid, pre-sheared at the pre-shear normal stress
//! until the shear stress is steady, then sheared to failure at smaller normal stresses. The
//! failure points form the yield locus.
//!
//! Why a split box rather than periodic boundaries: the engine has walls, not periodic images,
//! and a split box is the laboratory's own geometry (Jenike's cell); its end walls push the
//! upper half over the lower, so the lid needs no roughness. Its limit is the travel: the halves
//! must not slide far apart. Measured at k = 12 (10 mm spheres, 5 kPa, one run pre-sheared to
//! the 4.8 d50 the shelf allows, stress ratio over the last 0.5 d50): 0.49 at 0.5 d50, 0.72 at
//! 1, 0.83 at 1.5, 0.85 at 2, 0.86 at 2.5, 0.91 at 3, 0.93 at 3.5, then 0.76 at 4 and 0.68 at
//! 4.5. The ratio levels off from 1.5 to 2.5 d50 and the cell breaks down beyond about 15 % of
//! its length (the eighth of eight replicates that stopped its pre-shear at the first two
//! matching windows ran to 4.3 d50 and gave 0.66 against the others' 0.82-0.90). So the
//! pre-shear runs a fixed [`PRESHEAR_TRAVEL`] of 2 d50, the same for every run, and its
//! steadiness is tested, not waited for: the mean stress ratio of its last 0.5 d50 must lie
//! within [`STEADY_TOLERANCE`] of the 0.5 d50 before, or the run says it was not steady.
//!
//! **Known limit (issue 36, measured): for most of the metamodel's space the split box reaches
//! no steady pre-shear before it breaks down.** Three of the first four runs of the campaign
//! over `examples/space_shear_cell.toml` failed the steadiness test, the ratio still rising by
//! 14-21 % over the last d50. One of them (mu_pp 0.99, mu_r_pp 0.035, E 4.5 MPa, 8.9 kPa),
//! pre-sheared by a temporary change over 4.5 d50: 0.19, 0.37, 0.49, 0.58, 0.63, 0.66, 0.68 at
//! 0.5-3.5 d50, then 0.65 and 0.59; the same run in a cell 3k long: 0.40 at 2 d50, 0.49 at 3,
//! 0.58 at 4, 0.63 at 5, 0.64 at 5.5, then falling. In both lengths the stress ratio climbs
//! until about 15 % of the cell's length and falls after it: the course is set by the cell
//! (likely the shear zone spreading from the pushing end wall), not by the material. Periodic boundaries in the shear direction (a rough lid and floor, no end walls)
//! are the way to a steady state; the engine has none yet. The `warnings` column gives each
//! run's stress ratio per 0.5 d50 of pre-shear, so a table shows where it stood.
//!
//! Geometry, in units of d_max (the PSD's Q3 99 % diameter) so that the cell holds the same
//! number of particles at every size: length 2k, width k, the bed about k tall, split at k/2
//! (k = `cell_scale`, 12 by default: at k = 8 three cohesionless replicates at 5 kPa scattered
//! 0.77-0.90 in shear ratio with locus intercepts of 95-687 Pa; at k = 12, 0.83-0.85 and -175 to
//! 154 Pa, docs/data/shear_cell/). Each failure point starts from a copy of the one
//! pre-sheared state (the laboratory re-shears before each point to get the same state).
//!
//! Stresses: the normal stress on the shear plane is the lid's plus the weight of the material
//! above the plane per area; the shear stress is the horizontal force on the upper half (its
//! walls and the lid) per plan area. The shear is quasi-static: the upper half moves at
//! `0.02 sqrt(sigma_pre / rho_p)`, an inertial number I of 2e-3 over a shear band 10 d50 wide
//! (4e-3 if it is 5 d50). Dense flow's mu(I) law (GDR MiDi 2004; Jop et al. 2006: mu_s +
//! (mu_2 - mu_s) / (I_0 / I + 1), mu_2 - mu_s about 0.26, I_0 about 0.28) raises the stress ratio
//! by under 0.004 there, a tenth of one run's noise; half that speed needs 1.75 times the time
//! steps (docs/shear_cell.md).
//!
//! Responses: `internal_friction` (degrees, the slope of the linear yield locus through the
//! failure points), `cohesion` (Pa, its intercept), `unconfined_yield_strength` (Pa, the Mohr
//! circle through the origin tangent to the locus), `bulk_density` (kg/m^3, under the lid at
//! steady pre-shear) and `shear_ratio` (steady pre-shear stress over the pre-shear normal
//! stress).

use std::time::Instant;

use super::shear_test::{responses, steadiness, yield_locus, Bins, Travels, SERVO_GAIN};
use super::{
    materials_from, with_class_parameters, Diagnostics, Experiment, Outcome, ParamSet, RunOptions,
    RHO_RANGE,
};
use crate::error::{Error, Result};
use crate::psd::{default_range, draw_by_number, Distribution, LogNormal};
use crate::similarity::{Monomial, ScaledResponse, Similarity};
use mbgc_dem::contact::ModelClass;
use mbgc_dem::insertion::random_pack;
use mbgc_dem::particles::Particles;
use mbgc_dem::sim::{Scene, Simulation};
use mbgc_dem::timestep::rayleigh_time;
use mbgc_dem::vec3::V3;
use mbgc_dem::walls::{Shape, Wall};

const G: f64 = 9.81;

/// The shear cell's responses, in table order.
pub const RESPONSES: [&str; 5] = [
    "internal_friction",
    "cohesion",
    "unconfined_yield_strength",
    "bulk_density",
    "shear_ratio",
];

/// The parameters the shear cell needs whatever the model class (d50 in mm, normal_stress in
/// Pa: the pre-shear normal stress on the shear plane).
pub const OWN_PARAMETERS: [&str; 6] = ["E_p", "E_w", "nu_p", "rho_p", "d50", "normal_stress"];

/// Normal stresses of the failure points, as fractions of the pre-shear normal stress (the
/// range a ring shear tester's standard procedure spans).
pub const FAILURE_FRACTIONS: [f64; 3] = [0.25, 0.5, 0.75];

/// Speed of the upper half in units of sqrt(normal stress / rho_p) (the module's documentation
/// gives the inertial number and why it is quasi-static).
const SHEAR_SPEED: f64 = 0.02;

/// Pre-shear travel in d50 (the module's documentation gives the measurement behind it).
pub const PRESHEAR_TRAVEL: f64 = 2.0;

/// Solid fraction of the poured column (random insertion jams near 0.25; see the shear box).
const FILL_FRACTION: f64 = 0.2;

/// Solid volume poured, in cell volumes (length x width x k): a bed about k tall.
const SOLID_SHARE: f64 = 0.6;

/// The shear cell. Parameters: [`OWN_PARAMETERS`], the model class's, sigma_ln (optional).
#[derive(Debug, Clone)]
pub struct ShearCell {
    /// k: the cell's width and bed height in units of d_max (its length is 2k).
    pub cell_scale: f64,
    /// Time step as a fraction of the Rayleigh time of the smallest particle.
    pub dt_fraction: f64,
    /// Largest number of particles accepted.
    pub max_particles: usize,
    /// The effects of the contact law.
    pub class: ModelClass,
}

impl Default for ShearCell {
    fn default() -> Self {
        ShearCell {
            cell_scale: 12.0,
            dt_fraction: 0.25,
            max_particles: 100_000,
            class: ModelClass::default(),
        }
    }
}

/// Cell and particles of one parameter set.
#[derive(Debug, Clone)]
pub struct Layout {
    /// Length (shear direction), width and nominal bed height, m.
    pub size: V3,
    /// Height of the split plane, m.
    pub split: f64,
    /// Particle diameters, m.
    pub diameters: Vec<f64>,
    /// d50, the smallest and the largest diameter, m.
    pub d50: f64,
    /// Smallest drawn diameter (Q3 1 %), m.
    pub d_min: f64,
    /// Largest drawn diameter (Q3 99 %), m.
    pub d_max: f64,
}

impl ShearCell {
    /// Draws the particles and sizes the cell.
    pub fn layout(&self, p: &ParamSet, seed: u64) -> Result<Layout> {
        let d50_mm = p.require("d50", 1e-3, 1e4)?;
        let sigma = p.optional("sigma_ln", 0.0, 0.0, 2.0)?;
        if !(self.cell_scale >= 4.0 && self.cell_scale.is_finite()) {
            return Err(Error::invalid(format!(
                "--box-scale {} (the shear cell's k): expected at least 4 particle diameters \
                 across the cell",
                self.cell_scale
            )));
        }
        let dist = (sigma >= 1e-6)
            .then(|| LogNormal::new(d50_mm, sigma).map(Distribution::LogNormal))
            .transpose()?;
        let (d_min_mm, d_max_mm) = dist.as_ref().map_or((d50_mm, d50_mm), default_range);
        let d_max = d_max_mm * 1e-3;
        let k = self.cell_scale;
        let size = [2.0 * k * d_max, k * d_max, k * d_max];
        let mean_vol = match &dist {
            None => std::f64::consts::PI / 6.0 * (d50_mm * 1e-3).powi(3),
            Some(d) => {
                let probe = draw_by_number(
                    d,
                    (Some(d_min_mm), Some(d_max_mm)),
                    2000,
                    seed,
                    "shear cell PSD",
                )?;
                probe
                    .diameters_mm
                    .iter()
                    .map(|d| (d * 1e-3).powi(3))
                    .sum::<f64>()
                    / probe.diameters_mm.len() as f64
                    * std::f64::consts::PI
                    / 6.0
            }
        };
        let n = (SOLID_SHARE * size[0] * size[1] * size[2] / mean_vol).ceil() as usize;
        if n > self.max_particles {
            return Err(Error::invalid(format!(
                "--box-scale {k}: the shear cell would hold {n} particles (d_max = \
                 {d_max_mm:.3} mm for d50 = {d50_mm} mm, sigma_ln = {sigma}), more than the limit {}; expected a smaller box scale \
                 or a narrower PSD",
                self.max_particles
            )));
        }
        let diameters = match &dist {
            None => vec![d50_mm * 1e-3; n],
            Some(d) => draw_by_number(
                d,
                (Some(d_min_mm), Some(d_max_mm)),
                n,
                seed ^ 0x5eed,
                "shear cell PSD",
            )?
            .diameters_mm
            .into_iter()
            .map(|d| d * 1e-3)
            .collect(),
        };
        Ok(Layout {
            size,
            split: 0.5 * size[2],
            diameters,
            d50: d50_mm * 1e-3,
            d_min: d_min_mm * 1e-3,
            d_max,
        })
    }
}

/// The numbers of the procedure, in units of d50, d_max and sqrt(d_max / g), so that the run
/// depends on E, rho_p, d50 and the stresses only through their dimensionless groups.
#[derive(Debug, Clone)]
pub struct Schedule {
    /// Time step, s.
    pub dt: f64,
    /// Top of the poured column, m.
    pub column_top: f64,
    /// Steps between rest checks of the fill.
    pub chunk: u64,
    /// Fill at rest: rms speed below this, m/s.
    pub v_rest: f64,
    /// Free-fall time of the column, s.
    pub fall: f64,
    /// Step limit of the fill.
    pub max_fill_steps: u64,
    /// Speed of the upper half, m/s.
    pub v_shear: f64,
    /// Top speed of the lid, m/s.
    pub v_servo: f64,
    /// Steps between stress samples (and servo updates): 0.002 d50 of travel.
    pub sample: u64,
    /// Travel per averaging bin, m (0.1 d50).
    pub bin: f64,
    /// Pre-shear travel, m ([`PRESHEAR_TRAVEL`] d50).
    pub preshear: f64,
    /// Steps of the consolidation before the pre-shear (the lid settles onto the bed).
    pub consolidate_steps: u64,
    /// Failure: travel limit, m (2 d50).
    pub max_failure: f64,
}

impl ShearCell {
    /// The schedule for the layout, particle density `rho`, modulus `e`, Poisson `nu` and
    /// pre-shear normal stress `sigma`.
    pub fn schedule(&self, lay: &Layout, rho: f64, e: f64, nu: f64, sigma: f64) -> Schedule {
        let [l, w, _] = lay.size;
        let v_solid: f64 = lay
            .diameters
            .iter()
            .map(|d| std::f64::consts::PI / 6.0 * d.powi(3))
            .sum();
        let column_top = v_solid / (FILL_FRACTION * l * w);
        let dt = self.dt_fraction * rayleigh_time(0.5 * lay.d_min, rho, e, nu);
        let t0 = (lay.d_max / G).sqrt();
        let fall = (2.0 * column_top / G).sqrt();
        let v_shear = SHEAR_SPEED * (sigma / rho).sqrt();
        let steps = |t: f64| ((t / dt).ceil() as u64).max(1);
        Schedule {
            dt,
            column_top,
            chunk: steps(0.3 * t0).max(10),
            v_rest: 0.01 * (G * lay.d_max).sqrt(),
            fall,
            max_fill_steps: steps(fall + 40.0 * (lay.size[2] / G).sqrt()),
            v_shear,
            v_servo: v_shear,
            sample: steps(0.002 * lay.d50 / v_shear),
            bin: 0.1 * lay.d50,
            preshear: PRESHEAR_TRAVEL * lay.d50,
            consolidate_steps: steps(2.0 * lay.d_max / v_shear),
            max_failure: 2.0 * lay.d50,
        }
    }
}

/// Wall indices of the cell.
const UPPER: [usize; 4] = [5, 6, 7, 8];
const LID: usize = 9;
const SHELF: usize = 10;

/// The walls: floor, the lower half's four sides up to the split, the upper half's four sides
/// above it, the lid, and a shelf at the split's height beyond the lower half's far end. The
/// upper half moves over the shelf as it shears, so the material it carries past the lower
/// half's end is held at the split instead of falling out; the shelf's forces are taken out of
/// the stresses on the shear plane, whose area shrinks to (length - travel) x width.
fn walls(lay: &Layout, top: f64, shelf: f64, wall_mat: u16) -> Result<Vec<Wall>> {
    let [l, w, _] = lay.size;
    let zs = lay.split;
    let hu = top - zs;
    let rect = |name: &str, center: V3, u: V3, v: V3, hu: f64, hv: f64| {
        Wall::rect(name, center, (u, v), (hu, hv), wall_mat)
    };
    let (ex, ey, ez) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
    Ok(vec![
        rect(
            "floor",
            [0.5 * l, 0.5 * w, 0.0],
            ex,
            ey,
            l,
            0.5 * w + lay.d_max,
        )?,
        rect(
            "lower_left",
            [0.0, 0.5 * w, 0.5 * zs],
            ey,
            ez,
            0.5 * w,
            0.5 * zs,
        )?,
        rect(
            "lower_right",
            [l, 0.5 * w, 0.5 * zs],
            ey,
            ez,
            0.5 * w,
            0.5 * zs,
        )?,
        rect(
            "lower_front",
            [0.5 * l, 0.0, 0.5 * zs],
            ex,
            ez,
            0.5 * l,
            0.5 * zs,
        )?,
        rect(
            "lower_back",
            [0.5 * l, w, 0.5 * zs],
            ex,
            ez,
            0.5 * l,
            0.5 * zs,
        )?,
        rect(
            "upper_left",
            [0.0, 0.5 * w, zs + 0.5 * hu],
            ey,
            ez,
            0.5 * w,
            0.5 * hu,
        )?,
        rect(
            "upper_right",
            [l, 0.5 * w, zs + 0.5 * hu],
            ey,
            ez,
            0.5 * w,
            0.5 * hu,
        )?,
        rect(
            "upper_front",
            [0.5 * l, 0.0, zs + 0.5 * hu],
            ex,
            ez,
            0.5 * l,
            0.5 * hu,
        )?,
        rect(
            "upper_back",
            [0.5 * l, w, zs + 0.5 * hu],
            ex,
            ez,
            0.5 * l,
            0.5 * hu,
        )?,
        rect("lid", [0.5 * l, 0.5 * w, top], ex, ey, 0.5 * l, 0.5 * w)?,
        rect(
            "shelf",
            [l + 0.5 * shelf, 0.5 * w, zs],
            ex,
            ey,
            0.5 * shelf,
            0.5 * w,
        )?,
    ])
}

/// The lid's height.
fn lid_height(sim: &Simulation) -> f64 {
    match sim.walls[LID].shape {
        Shape::Rect { center, .. } => center[2],
        _ => f64::NAN,
    }
}

/// One stress sample: normal and shear stress on the shear plane, Pa, and the lid's height.
#[derive(Debug, Clone, Copy)]
struct Stress {
    normal: f64,
    shear: f64,
}

/// Mass of the particles above the shear plane: their weight is part of its normal stress.
fn mass_above(sim: &Simulation, lay: &Layout) -> f64 {
    let p = &sim.particles;
    (0..p.len())
        .filter(|&i| p.x[i][2] > lay.split)
        .map(|i| p.m[i])
        .sum()
}

fn stress(sim: &Simulation, lay: &Layout, travel: f64) -> Stress {
    let area = (lay.size[0] - travel) * lay.size[1];
    let above = mass_above(sim, lay);
    let lid = sim.wall_force(LID);
    let shelf = sim.wall_force(SHELF);
    let push: f64 = UPPER
        .iter()
        .chain([&LID])
        .map(|&w| sim.wall_force(w)[0])
        .sum();
    Stress {
        normal: (lid[2] + above * G + shelf[2]) / area,
        shear: (-push - shelf[0]) / area,
    }
}

/// Removes the particles that left the cell (over an end wall, or off the shelf); returns their
/// mass.
fn spill(sim: &mut Simulation, lay: &Layout) -> f64 {
    let [l, w, _] = lay.size;
    let p = &sim.particles;
    let out: Vec<bool> =
        p.x.iter()
            .map(|x| {
                x[0] < -lay.d_max
                    || x[1] < -lay.d_max
                    || x[1] > w + lay.d_max
                    || (x[0] > l && x[2] < lay.split - lay.d_max)
            })
            .collect();
    let mass = (0..out.len()).filter(|&i| out[i]).map(|i| p.m[i]).sum();
    if mass > 0.0 {
        sim.remove_particles(&out);
    }
    mass
}

/// The lid's vertical speed for a target normal stress: proportional to the relative error,
/// at most `v_servo`.
fn servo(sim: &mut Simulation, s: &Stress, target: f64, v_servo: f64) {
    let e = (SERVO_GAIN * (target - s.normal) / target).clamp(-1.0, 1.0);
    sim.walls[LID].velocity[2] = -v_servo * e;
}

fn set_shear(sim: &mut Simulation, v: f64) {
    for w in UPPER.iter().chain([&LID]) {
        sim.walls[*w].velocity[0] = v;
    }
}

impl Experiment for ShearCell {
    fn name(&self) -> &'static str {
        "shear-cell"
    }

    fn parameters(&self) -> Vec<&'static str> {
        with_class_parameters(&OWN_PARAMETERS, &self.class, self.pairs())
    }

    fn optional_parameters(&self) -> Vec<&'static str> {
        vec!["sigma_ln"]
    }

    fn class(&self) -> Option<&ModelClass> {
        Some(&self.class)
    }

    fn similarity(&self) -> Option<Similarity> {
        let groups = crate::similarity::bulk_groups(
            &self.class,
            &[("S", "normal_stress", "pre-shear normal stress")],
        )?;
        let by = |n: &str| Monomial {
            coefficient: 1.0,
            powers: vec![(n.into(), 1.0)],
        };
        Some(Similarity {
            groups,
            scaled: vec![
                ScaledResponse {
                    response: "bulk_density".into(),
                    factor: by("rho_p"),
                    fitted: "solid_fraction".into(),
                },
                ScaledResponse {
                    response: "cohesion".into(),
                    factor: by("normal_stress"),
                    fitted: "cohesion_ratio".into(),
                },
                ScaledResponse {
                    response: "unconfined_yield_strength".into(),
                    factor: by("normal_stress"),
                    fitted: "strength_ratio".into(),
                },
            ],
        })
    }

    fn responses(&self) -> Vec<&'static str> {
        RESPONSES.to_vec()
    }

    fn check(&self, p: &ParamSet) -> Result<()> {
        materials_from(p, &self.class)?;
        p.require("rho_p", RHO_RANGE.0, RHO_RANGE.1)?;
        p.require("normal_stress", 1e-3, 1e9)?;
        self.layout(p, 0).map(|_| ())
    }

    fn run(&self, p: &ParamSet, seed: u64, opts: &RunOptions) -> Result<Outcome> {
        let clock = Instant::now();
        let (materials, grain, wall_mat) = materials_from(p, &self.class)?;
        let rho = p.require("rho_p", RHO_RANGE.0, RHO_RANGE.1)?;
        let sigma_pre = p.require("normal_stress", 1e-3, 1e9)?;
        let lay = self.layout(p, seed)?;
        let mat = &materials.materials[grain as usize];
        let sch = self.schedule(&lay, rho, mat.youngs_modulus, mat.poisson, sigma_pre);
        let [l, w, _] = lay.size;
        let mut warnings = Vec::new();
        let mut rng = crate::sampling::rng(seed);
        let mut particles = Particles::new();
        let centres = random_pack(&lay.diameters, [0.0; 3], [l, w, sch.column_top], &mut rng)?;
        for (&d, &x) in lay.diameters.iter().zip(&centres) {
            particles.add(x, 0.5 * d, rho, grain)?;
        }
        let n = particles.len();
        let top = sch.column_top + lay.d_max;
        let margin = 4.0 * lay.d_max;
        let scene = Scene {
            particles,
            walls: walls(
                &lay,
                top,
                sch.preshear + sch.max_failure + lay.d_max,
                wall_mat,
            )?,
            materials,
            class: self.class,
            gravity: [0.0, 0.0, -G],
            dt: sch.dt,
            skin: lay.d_min,
            domain: (
                [-margin - l, -margin, -margin],
                [2.0 * l + margin, w + margin, top + margin],
            ),
            max_dt_fraction: self.dt_fraction + 1e-9,
        };
        let mut sim = Simulation::new(scene)?;
        sim.set_threads(opts.threads.max(1));
        let mut spilled = 0.0;
        let total_mass: f64 = sim.particles.m.iter().sum();
        let blew =
            |e: mbgc_dem::BlowUp| Error::invalid(format!("shear cell: the DEM run blew up: {e}"));

        // Pour and settle.
        let mut settled = false;
        while sim.step < sch.max_fill_steps {
            sim.run(sch.chunk).map_err(blew)?;
            let v2 = sim
                .particles
                .v
                .iter()
                .map(|v| v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                .sum::<f64>();
            if sim.time > sch.fall && (v2 / n as f64).sqrt() < sch.v_rest {
                settled = true;
                break;
            }
        }
        if !settled {
            warnings.push("filling did not come to rest within the time limit".into());
        }
        // Lower the lid onto the bed and consolidate at the pre-shear normal stress.
        let bed_top = sim
            .particles
            .x
            .iter()
            .zip(&sim.particles.r)
            .map(|(x, r)| x[2] + r)
            .fold(0.0, f64::max);
        sim.place_wall(
            LID,
            Shape::Rect {
                center: [0.5 * l, 0.5 * w, bed_top + 0.05 * lay.d_min],
                u: [1.0, 0.0, 0.0],
                v: [0.0, 1.0, 0.0],
                half_u: 0.5 * l,
                half_v: 0.5 * w,
            },
        )?;
        let consolidate_end = sim.step + sch.consolidate_steps;
        while sim.step < consolidate_end {
            sim.run(sch.sample).map_err(blew)?;
            let s = stress(&sim, &lay, 0.0);
            servo(&mut sim, &s, sigma_pre, sch.v_servo);
        }

        // Pre-shear over a fixed travel, then test that it was steady.
        set_shear(&mut sim, sch.v_shear);
        let start = sim.time;
        let mut bins = Bins::new(sch.bin);
        let mut travel = 0.0;
        let mut heights = Vec::new();
        while travel < sch.preshear {
            sim.run(sch.sample).map_err(blew)?;
            travel = (sim.time - start) * sch.v_shear;
            spilled += spill(&mut sim, &lay);
            let s = stress(&sim, &lay, travel);
            servo(&mut sim, &s, sigma_pre, sch.v_servo);
            bins.add(travel, s.normal, s.shear);
            heights.push(lid_height(&sim));
        }
        let steady = match steadiness(&bins.done) {
            Ok(()) => true,
            Err(why) => {
                warnings.push(why);
                false
            }
        };
        // The pre-shear's course, for the table: whether it levelled off shows there.
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
        let k = (heights.len() / 4).max(1);
        let lid_mean = heights[heights.len() - k..].iter().sum::<f64>() / k as f64;
        let mass_in: f64 = (0..sim.particles.len())
            .filter(|&i| {
                let x = sim.particles.x[i];
                x[2] < lid_mean && x[2] > 0.0 && x[0] > 0.0 && x[0] < l + travel
            })
            .map(|i| sim.particles.m[i])
            .sum();
        let bulk_density = mass_in / (l * w * lid_mean);
        let preshear_travel = travel;

        // The normal stress on the shear plane holds the weight of the material above it, which
        // the lid cannot take off: a failure stress below that weight is never reached, and all
        // failure points would sit at the weight (a locus of one point, silently NaN).
        let overburden = mass_above(&sim, &lay) * G / ((lay.size[0] - travel) * lay.size[1]);
        let lowest = FAILURE_FRACTIONS[0] * sigma_pre;
        if lowest < overburden {
            return Err(Error::invalid(format!(
                "shear cell: normal_stress {sigma_pre} Pa puts the lowest failure point at \
                 {lowest:.0} Pa, below the {overburden:.0} Pa that the material above the shear \
                 plane weighs; expected normal_stress above {:.0} Pa for this cell",
                overburden / FAILURE_FRACTIONS[0]
            )));
        }

        // Failure at smaller normal stresses, each from a copy of the pre-sheared state.
        let mut locus = Vec::new();
        let mut failed_peaks = 0;
        let mut longest = 0.0f64;
        for f in FAILURE_FRACTIONS {
            let target = f * sigma_pre;
            let mut c = sim.clone();
            set_shear(&mut c, 0.0);
            let relax_end = c.step + sch.consolidate_steps / 2;
            while c.step < relax_end {
                c.run(sch.sample).map_err(blew)?;
                let s = stress(&c, &lay, travel);
                servo(&mut c, &s, target, sch.v_servo);
            }
            set_shear(&mut c, sch.v_shear);
            let start = c.time;
            // The peak of a running mean over 0.3 d50 of travel: the largest single bin would
            // pick the noise's largest excursion, a bias of the same size at every normal stress
            // that shows up as a cohesion.
            let mut bins = Bins::new(sch.bin);
            let mut peak: Option<(f64, f64)> = None;
            let mut past_peak = false;
            let mut t = 0.0;
            while t < sch.max_failure {
                c.run(sch.sample).map_err(blew)?;
                t = (c.time - start) * sch.v_shear;
                spill(&mut c, &lay);
                let s = stress(&c, &lay, travel + t);
                servo(&mut c, &s, target, sch.v_servo);
                let before = bins.done.len();
                bins.add(t, s.normal, s.shear);
                if bins.done.len() > before && bins.done.len() >= 3 {
                    let b = bins.last(3).unwrap();
                    if peak.is_none_or(|p| b.1 > p.1) {
                        peak = Some(b);
                    } else if t > 0.5 * lay.d50 && b.1 < 0.95 * peak.unwrap().1 {
                        past_peak = true;
                        break;
                    }
                }
            }
            longest = longest.max(t);
            if !past_peak {
                failed_peaks += 1;
            }
            if let Some(p) = peak {
                locus.push(p);
            }
        }
        if spilled > 1e-3 * total_mass {
            warnings.push(format!(
                "{:.2} % of the mass spilled out of the cell during the pre-shear",
                100.0 * spilled / total_mass
            ));
        }
        let (cohesion, phi, locus_valid) = yield_locus(
            &locus,
            Travels {
                preshear: travel / lay.d50,
                longest_failure: longest / lay.d50,
                max_failure: sch.max_failure / lay.d50,
                length: l / lay.d50,
            },
            failed_peaks,
            FAILURE_FRACTIONS.len(),
            &mut warnings,
        );
        let outside = sim
            .particles
            .x
            .iter()
            .filter(|x| x[1] < -lay.d_max || x[1] > w + lay.d_max)
            .count();
        if outside > 0 {
            return Err(Error::invalid(format!(
                "shear cell: {outside} particles escaped through a side wall"
            )));
        }
        Ok(Outcome {
            responses: responses(cohesion, phi, bulk_density, shear_ratio),
            diagnostics: Diagnostics {
                settled: settled && steady && locus_valid,
                steps: sim.step,
                particles: n,
                wall_time_s: clock.elapsed().as_secs_f64(),
                warnings: {
                    warnings.push(format!(
                        "pre-shear travel {:.2} d50 (stress ratio per 0.5 d50 of it: {}); \
                         failure points (normal, shear) in Pa: {}",
                        preshear_travel / lay.d50,
                        curve,
                        locus
                            .iter()
                            .map(|(s, t)| format!("({s:.4e}, {t:.4e})"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ));
                    warnings
                },
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small cell (k = 4, about 150 spheres) at d50 `d50` mm, moduli `e`, normal stress
    /// `sigma`.
    fn small_run(d50: f64, e: f64, sigma: f64) -> Outcome {
        let cell = ShearCell {
            cell_scale: 4.0,
            class: ModelClass::parse("hertz,mindlin,epsd2").unwrap(),
            ..ShearCell::default()
        };
        let p = ParamSet::from_pairs(&[
            ("E_p", e),
            ("E_w", e),
            ("nu_p", 0.3),
            ("rho_p", 2600.0),
            ("d50", d50),
            ("normal_stress", sigma),
            ("e_pp", 0.5),
            ("e_pw", 0.5),
            ("mu_pp", 0.5),
            ("mu_pw", 0.3),
            ("mu_r_pp", 0.1),
            ("mu_r_pw", 0.1),
        ]);
        cell.check(&p).unwrap();
        cell.run(&p, 3, &RunOptions::default()).unwrap()
    }

    #[test]
    fn a_small_cell_gives_a_yield_locus_and_scales_with_its_groups() {
        let base = small_run(4.0, 5e6, 2000.0);
        // A cell 8 d50 long is short for 2 d50 of pre-shear and the failure travel: the run
        // must say so, not hide it.
        assert!(!base.diagnostics.settled);
        assert!(
            base.diagnostics
                .warnings
                .iter()
                .any(|w| w.contains("short for its travel") && w.contains("length of 8.0 d50")),
            "{base:?}"
        );
        assert!(
            base.diagnostics
                .warnings
                .iter()
                .any(|w| w.contains("pre-shear travel 2.0")),
            "{base:?}"
        );
        let get = |o: &Outcome, n: &str| o.get(n).unwrap();
        let phi = get(&base, "internal_friction");
        let ratio = get(&base, "shear_ratio");
        let density = get(&base, "bulk_density");
        assert!((15.0..70.0).contains(&phi), "{base:?}");
        assert!((0.2..1.5).contains(&ratio), "{base:?}");
        assert!((0.4 * 2600.0..0.75 * 2600.0).contains(&density), "{base:?}");
        // Four times the size, modulus and stress: the same groups K and S, the same run.
        let big = small_run(16.0, 2e7, 8000.0);
        assert_eq!(
            get(&big, "internal_friction").to_bits(),
            phi.to_bits(),
            "{big:?}"
        );
        assert_eq!(get(&big, "bulk_density").to_bits(), density.to_bits());
        assert_eq!(
            get(&big, "cohesion").to_bits(),
            (4.0 * get(&base, "cohesion")).to_bits()
        );
    }

    /// Measured at k = 12, 10 mm and 1000 Pa: the three failure points all sat at the weight of
    /// the upper half (1.04e3 Pa) and the locus was NaN without a word. The run now says why.
    #[test]
    fn a_normal_stress_below_the_overburden_is_refused_by_name() {
        let cell = ShearCell {
            cell_scale: 4.0,
            class: ModelClass::parse("hertz,mindlin,epsd2").unwrap(),
            ..ShearCell::default()
        };
        let p = ParamSet::from_pairs(&[
            ("E_p", 5e6),
            ("E_w", 5e6),
            ("nu_p", 0.3),
            ("rho_p", 2600.0),
            ("d50", 4.0),
            ("normal_stress", 200.0),
            ("e_pp", 0.5),
            ("e_pw", 0.5),
            ("mu_pp", 0.5),
            ("mu_pw", 0.3),
            ("mu_r_pp", 0.1),
            ("mu_r_pw", 0.1),
        ]);
        let e = cell
            .run(&p, 3, &RunOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("normal_stress 200 Pa") && e.contains("weighs"),
            "{e}"
        );
    }
}
