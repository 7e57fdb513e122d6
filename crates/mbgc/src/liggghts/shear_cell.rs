//! The shear cell ([`crate::experiments::shear_cell`]) as a LIGGGHTS 3.8 deck that runs the
//! whole procedure itself: pour, glue the floor and lid layers, consolidation under a loaded lid,
//! pre-shear until steady, and three failure tests from copies of the pre-sheared state.
//! [`cell_deck`] takes every number from mbgc's own layout and schedule (period, column, time
//! step, sample interval, shear speed, step counts, travels), so that the two codes
//! do the same things at the same steps; [`CellRun`] reads a finished run back for
//! [`super::shear_cell_experiment`] to measure with mbgc's definitions.
//!
//! What the deck does, in mbgc's order:
//!
//! - The cell: `boundary p p f`, a period of k d_max in x (the shear direction) and y, z from 4
//!   d_max below the floor to 4 d_max above the poured column (mbgc's domain). One atom type:
//!   the grains. The floor is a plane at z = 0 (`wall/gran ... primitive type 1 zplane`) of the
//!   grains' own material, so every contact is a particle-particle one and no wall parameter
//!   (E_w, mu_pw, ...) is read; the deck writes type 1's properties only.
//! - Pour: LIGGGHTS' own `insert/pack` (the particle count of mbgc's layout when monosized, its
//!   mass as equal-mass templates of the PSD otherwise, as the shear-box backend) into mbgc's
//!   column over the whole period, fill until the unweighted rms speed falls below mbgc's
//!   threshold after the free-fall time, in mbgc's chunks.
//! - Glue: mbgc sorts the grains by centre height and glues the lowest ones until their volume
//!   reaches [`LAYER_SOLID`] x [`LAYER`] d_max x the plan area (the one that crosses included),
//!   and the highest ones likewise. The deck finds the same sets inside LIGGGHTS, by bisection
//!   on a height: `mass(all,region)` of a block below (above) a cut is the prefix (suffix) of
//!   the sorted grains, so halving the cut [`BISECTIONS`] times between the domain's ends
//!   brackets the centre of the grain whose volume crosses the threshold (all grains have the
//!   density rho_p, so mass counts volume). The cut's last two values differ in the 15th digit,
//!   where two grain centres never coincide. `group ... region` makes the layers `floor` and
//!   `lid`, `free` the rest. Chosen over stopping LIGGGHTS after the settle and letting Rust
//!   pick the ids for a second deck because the run stays one deck in one process: no second
//!   restart, nothing for a user of `--write-decks` to run between two stages, and `mbgc
//!   campaign import` reads it as it reads every other deck; the log's `GLUED` line (counts
//!   and masses of both layers) is checked against the rule when the run is measured.
//! - Gravity off from the glue on, as in mbgc's shear (`unfix gravity`: the normal stress the
//!   same at every depth). Glued grains (mbgc's driven particles): at rest, no spin, no
//!   integration (`fix nve/sphere` on `free` only), and no contacts between two of them
//!   (`neigh_modify exclude group glued glued`), so a contact with a glued grain is a normal
//!   particle-particle contact with both masses in the effective mass, as mbgc's. The floor is
//!   left where it settled; the lid moves rigidly by `fix move variable NULL NULL NULL v_vx
//!   v_zero v_vz` (every step: x += v dt, v set, the spin left at zero).
//! - Stresses, after each sample of `sample` steps, as mbgc's `stress`: the lid's contact force
//!   per plan area (period x period), normal = `fcm(lid,z)` / area, shear = -`fcm(lid,x)` /
//!   area (the forces of the sample's last step, as mbgc's).
//! - Load: the lid is mbgc's dead load (`run_loaded`): every step its vertical speed changes by
//!   dt (`fcm(lid,z)` - target x area) / `mass(lid)`, from its speed `vcm(lid,z)` of the step
//!   before (the equal-style variable `fix move` evaluates each step, with the forces of the
//!   last force computation, as mbgc's); its horizontal speed is 0 in consolidation and
//!   relaxation, the shear speed in pre-shear and failure.
//! - Consolidation (mbgc's step count, in samples), then the pre-shear in 0.1 d50 bins of
//!   travel: at every fifth finished bin from
//!   [`PRESHEAR_TRAVEL`](crate::experiments::shear_cell::PRESHEAR_TRAVEL) - 0.5 bin on, mbgc's
//!   steadiness test (the stress ratio of the last five bins within [`STEADY_TOLERANCE`] of the
//!   five before), computed in the deck; it stops when steady or at
//!   [`MAX_PRESHEAR_TRAVEL`](crate::experiments::shear_cell::MAX_PRESHEAR_TRAVEL) - 0.5 bin.
//!   The measurement replays mbgc's loop on the samples the deck printed and warns if it would
//!   have stopped elsewhere.
//! - The interior slab's solid volume per sample: every grain sliced exactly between 1 d_max
//!   above the floor layer's top and 1 d_max below the lid layer's bottom (the layers' mean
//!   heights -+ half of [`LAYER`] d_max, mbgc's `interior_solid_fraction`), by an atom-style
//!   variable of the spherical caps summed by `compute reduce`.
//! - The free grains are dumped after the pre-shear, for mbgc's check that none passed
//!   through the lid.
//! - The three failure points: mbgc clones its simulation; the deck writes a restart file after
//!   the pre-shear and starts each failure test with `clear` / `read_restart` (atoms, groups,
//!   contact histories, velocities: the lid's speed). Relaxation at rest under the failure
//!   load (the lid answering the new load from the pre-sheared state, as mbgc's), then shear
//!   until mbgc's peak criterion
//!   (running mean of three 0.1 d50 bins of the shear stress falling 5 % below its peak after
//!   0.5 d50) or 2 d50, computed in the deck; the responses are computed afterwards in Rust
//!   from every sample the deck printed, with mbgc's definitions (a test without a drop that
//!   levelled off over its last 0.5 d50 fails at its plateau, as mbgc's).
//!
//! Where the deck cannot do exactly what mbgc's engine does: LIGGGHTS inserts its own particles
//! (the same number, mbgc's column); a failure test restarts from a file (neighbour lists and
//! forces computed afresh, the only perturbation) instead of a clone in memory; a PSD is five
//! equal-mass templates; the numbers the deck carries between commands (bin means, the cut,
//! the load) pass through its variables at 15 significant digits; and the forces the
//! stresses are made of are those of the last step's force computation, as in mbgc, but
//! evaluated by LIGGGHTS' own contact code. [`LAYER_SOLID`] is the engine cell's own constant.
//!
//! LIGGGHTS 3.8 traps the deck works around: an equal- or atom-style variable is redefined by
//! deleting and appending it (and an exhausted loop variable is deleted), which moves every
//! later variable's index, while `fix move` and `compute reduce` keep the indices they found at
//! setup through runs without setup (`run N pre no`): so the variables they read (the lid's
//! speeds, the per-grain slice volume) are defined first and never redefined, and read
//! everything else by name; a compute is current between runs only if the thermo output of the
//! run's last step evaluated it, so the thermo line carries all three; `if` compares numbers
//! but computes nothing; loop variables and labels are unique, because a loop left by a jump is
//! never deleted and `jump SELF` finds the first label of its name.
//!
//! The deck prints one `SAMPLE` line per sample (phase, step, normal and shear stress, mean
//! floor and lid height, slab solid volume), markers for each stage, and ends with `RUN_END`
//! after its final dump. Its file names are those of the campaign's deck tools
//! (`in.shear_box_fill`, `log.shear_box_fill`, `final.dump`, [`super::shear_box_fill`]), so
//! `--write-decks`, their `run_all.sh` and `mbgc campaign import` handle shear-cell decks as
//! they handle shear-box ones.

use std::fmt::Write as _;
use std::path::Path;

use super::number::num;
use super::shear_box::{gran_model, GranModel};
use super::shear_box_fill::prime_seed;
use crate::error::{read_to_string, write_atomic, Error, Result};
use crate::experiments::shear_box::psd_classes;
use crate::experiments::shear_cell::{ShearCell, FAILURE_FRACTIONS, LAYER, LAYER_SOLID};
use crate::experiments::shear_test::STEADY_TOLERANCE;
use crate::experiments::ParamSet;
use crate::psd::{default_range, Distribution, LogNormal};
use mbgc_dem::contact::{ModelClass, Pair};
use mbgc_dem::vec3::V3;

pub use super::shear_box_fill::{FINAL_DUMP, INPUT, LOG};

/// Gravity, m/s^2 (mbgc's).
pub const G: f64 = 9.81;

/// Dump of the free grains at the end of the pre-shear (none may be above the lid).
pub const PRESHEAR_DUMP: &str = "preshear.dump";

/// The restart file the failure tests start from.
pub const RESTART: &str = "preshear.restart";

/// Particle templates of equal mass standing for a continuous PSD (as the shear-box backend).
pub const CLASSES: usize = 5;

/// Gap between a glued layer and the interior slab the bulk density is measured in, in d_max
/// (mbgc's `interior_solid_fraction`).
pub const INTERIOR_GAP: f64 = 1.0;

/// Halvings of the cut that finds a glued layer: the domain's height over 2^60 is far below
/// the 15 digits the deck's variables carry, so the bisection ends at their resolution.
pub const BISECTIONS: u32 = 60;

/// What the deck needs, in SI units, all from mbgc's layout and schedule for the row.
#[derive(Debug, Clone, PartialEq)]
pub struct CellDeck {
    /// The contact law, written effect by effect in LIGGGHTS' words.
    pub class: ModelClass,
    /// Period in x (the shear direction) and y, and nominal bed height, m.
    pub size: V3,
    /// (diameter m, mass fraction) of each particle template.
    pub classes: Vec<(f64, f64)>,
    /// Particles of mbgc's layout (inserted by number when monosized).
    pub count: usize,
    /// Their total mass, kg (inserted by mass when there are several templates).
    pub mass: f64,
    /// Top of the poured column, m.
    pub column_top: f64,
    /// Lower and upper corners of the simulation domain, m (x and y: one period).
    pub domain: (V3, V3),
    /// Time step, s.
    pub dt: f64,
    /// Neighbour-list skin, m.
    pub skin: f64,
    /// Steps between rest checks of the fill.
    pub chunk: u64,
    /// Fill at rest: unweighted rms speed below this, m/s.
    pub v_rest: f64,
    /// Steps before rest may be declared (the column's free fall).
    pub fall_steps: u64,
    /// Step limit of the fill.
    pub max_fill_steps: u64,
    /// Mass of each glued layer, kg: rho_p x [`LAYER_SOLID`] x [`LAYER`] d_max x the plan area.
    pub layer_mass: f64,
    /// d50, m.
    pub d50: f64,
    /// Smallest diameter, m.
    pub d_min: f64,
    /// Largest diameter, m.
    pub d_max: f64,
    /// Pre-shear normal stress, Pa.
    pub sigma: f64,
    /// Speed of the lid, m/s.
    pub v_shear: f64,
    /// Steps per sample.
    pub sample: u64,
    /// Travel per averaging bin, m.
    pub bin: f64,
    /// Samples of the consolidation.
    pub consolidate_samples: u64,
    /// Pre-shear travel before the first steadiness test, m.
    pub preshear: f64,
    /// Longest pre-shear, m.
    pub max_preshear: f64,
    /// Bound of the pre-shear loop, in samples (the steadiness rule stops it before).
    pub preshear_samples: u64,
    /// Samples of each failure test's relaxation at its normal stress.
    pub relax_samples: u64,
    /// Largest number of samples of a failure test (its travel limit).
    pub failure_samples: u64,
    /// Failure travel limit, m.
    pub max_failure: f64,
    /// Any number; made prime for LIGGGHTS.
    pub seed: u64,
}

impl CellDeck {
    /// Travel after `steps` steps at the shear speed, m (mbgc's `(time - start) * v_shear`).
    pub fn travel(&self, steps: u64) -> f64 {
        steps as f64 * self.dt * self.v_shear
    }

    /// Plan area of the cell, m^2.
    pub fn area(&self) -> f64 {
        self.size[0] * self.size[1]
    }

    /// Distance from a glued layer's mean centre height to the interior slab, m: half the
    /// layer plus [`INTERIOR_GAP`] d_max.
    pub fn interior_gap(&self) -> f64 {
        (0.5 * LAYER + INTERIOR_GAP) * self.d_max
    }

    /// The interior slab's solid fraction from a sample's mean floor and lid heights and its
    /// solid volume; NaN when the layers are too close for a slab (as mbgc's).
    pub fn solid_fraction(&self, s: &Sample) -> f64 {
        let (a, b) = (s.floor + self.interior_gap(), s.lid - self.interior_gap());
        if b <= a {
            return f64::NAN;
        }
        s.slab / (self.area() * (b - a))
    }
}

/// Samples of `sample` steps until the travel at `v` reaches `length` (mbgc's `while travel <
/// length` loop).
fn samples_for(length: f64, sample: u64, dt: f64, v: f64) -> u64 {
    let mut n = 0u64;
    loop {
        n += 1;
        if (n * sample) as f64 * dt * v >= length || n >= 100_000_000 {
            return n;
        }
    }
}

/// The deck of the shear cell `cell` for the row `p` and `seed`: mbgc's layout and schedule.
pub fn cell_deck(cell: &ShearCell, p: &ParamSet, seed: u64) -> Result<CellDeck> {
    let lay = cell.layout(p, seed)?;
    let rho = p.require("rho_p", crate::experiments::RHO_RANGE.0, 1e5)?;
    let e = p.require("E_p", crate::experiments::E_RANGE.0, 1e13)?;
    let nu = p.require("nu_p", crate::experiments::NU_RANGE.0, 0.5)?;
    let sigma = p.require("normal_stress", 1e-3, 1e9)?;
    let d50_mm = p.require("d50", 1e-3, 1e4)?;
    let sigma_ln = p.optional("sigma_ln", 0.0, 0.0, 2.0)?;
    let sch = cell.schedule(&lay, rho, e, nu, sigma);
    let classes: Vec<(f64, f64)> = if sigma_ln < 1e-6 {
        vec![(lay.d50, 1.0)]
    } else {
        let dist = Distribution::LogNormal(LogNormal::new(d50_mm, sigma_ln)?);
        psd_classes(&dist, default_range(&dist), CLASSES)
            .into_iter()
            .map(|d| (d * 1e-3, 1.0 / CLASSES as f64))
            .collect()
    };
    let mass: f64 = lay
        .diameters
        .iter()
        .map(|d| rho * std::f64::consts::PI / 6.0 * d.powi(3))
        .sum();
    let [l, w, _] = lay.size;
    let top = sch.column_top + lay.d_max;
    let margin = 4.0 * lay.d_max;
    let bin_samples = samples_for(sch.bin, sch.sample, sch.dt, sch.v_shear);
    Ok(CellDeck {
        class: cell.class,
        size: lay.size,
        classes,
        count: lay.diameters.len(),
        mass,
        column_top: sch.column_top,
        domain: ([0.0, 0.0, -margin], [l, w, top + margin]),
        dt: sch.dt,
        skin: lay.d_min,
        chunk: sch.chunk,
        v_rest: sch.v_rest,
        fall_steps: (sch.fall / sch.dt) as u64,
        max_fill_steps: sch.max_fill_steps,
        layer_mass: rho * LAYER_SOLID * LAYER * lay.d_max * l * w,
        d50: lay.d50,
        d_min: lay.d_min,
        d_max: lay.d_max,
        sigma,
        v_shear: sch.v_shear,
        sample: sch.sample,
        bin: sch.bin,
        consolidate_samples: sch.consolidate_steps.div_ceil(sch.sample),
        preshear: sch.preshear,
        max_preshear: sch.max_preshear,
        // The rule stops at the bin that reaches the longest pre-shear; one bin more is slack.
        preshear_samples: samples_for(sch.max_preshear, sch.sample, sch.dt, sch.v_shear)
            + bin_samples,
        relax_samples: (sch.consolidate_steps / 2).div_ceil(sch.sample),
        failure_samples: samples_for(sch.max_failure, sch.sample, sch.dt, sch.v_shear),
        max_failure: sch.max_failure,
        seed,
    })
}

/// The seed of the deck's `k`-th random stream (0: insertion, 1: the distribution, 2 + j:
/// template j), as the shear-box deck draws them.
fn stream_seed(seed: u64, k: u64) -> u64 {
    if k == 0 {
        prime_seed(seed)
    } else {
        prime_seed(seed.wrapping_mul(31).wrapping_add(k))
    }
}

/// The LIGGGHTS property of each particle-particle parameter a LIGGGHTS class can have.
const PROPERTIES: [(&str, &str); 4] = [
    ("e_pp", "coefficientRestitution"),
    ("mu_pp", "coefficientFriction"),
    ("mu_r_pp", "coefficientRollingFriction"),
    ("ced_pp", "cohesionEnergyDensity"),
];

/// The grains' material, the only one of the cell (atom type 1, which the floor plane has
/// too): modulus, Poisson ratio, and each particle-particle parameter of the class (its
/// default when the row leaves it out, as mbgc's contact law takes it).
fn write_grain_properties(s: &mut String, p: &ParamSet, class: &ModelClass) -> Result<()> {
    let get = |k: &str| {
        p.get(k)
            .ok_or_else(|| Error::invalid(format!("parameter {k}: missing")))
    };
    let _ = writeln!(
        s,
        "fix m1 all property/global youngsModulus peratomtype {}\n\
         fix m2 all property/global poissonsRatio peratomtype {}",
        num(get("E_p")?),
        num(get("nu_p")?)
    );
    let mut k = 3;
    for e in class.effects() {
        for spec in e.params {
            let name = spec.name(Pair::ParticleParticle);
            let property = PROPERTIES
                .iter()
                .find(|(n, _)| *n == name)
                .map(|(_, prop)| *prop)
                .ok_or_else(|| {
                    Error::invalid(format!(
                        "model class {class}: LIGGGHTS 3.8 has no property for {name} ({} '{}')",
                        e.slot.label(),
                        e.name
                    ))
                })?;
            let v = p.get(name).or(spec.default).ok_or_else(|| {
                Error::invalid(format!(
                    "parameter {name}: missing ({} '{}')",
                    e.slot.label(),
                    e.name
                ))
            })?;
            let _ = writeln!(
                s,
                "fix m{k} all property/global {property} peratomtypepair 1 {}",
                num(v)
            );
            k += 1;
        }
    }
    Ok(())
}

/// The part of the deck that a restart does not restore: neighbour lists, contact law, the
/// floor plane.
fn physics(s: &mut String, p: &ParamSet, d: &CellDeck, law: &GranModel) -> Result<()> {
    let _ = writeln!(
        s,
        "neighbor {} bin\nneigh_modify delay 0\ncommunicate single vel yes",
        num(d.skin)
    );
    write_grain_properties(s, p, &d.class)?;
    let GranModel { models, settings } = law;
    let _ = writeln!(
        s,
        "pair_style gran {models}{settings}\npair_coeff * *\ntimestep {}\n\
         fix floorplane all wall/gran {models} primitive type 1 zplane 0e0{settings}",
        num(d.dt)
    );
    Ok(())
}

/// The glued layers and their motion, the integration of the free grains (without gravity,
/// as mbgc's shear), the measuring computes and the thermo line that keeps them current: after
/// the glue and after a restart.
fn cell_fixes(s: &mut String) {
    let _ = writeln!(
        s,
        "neigh_modify exclude group glued glued\n\
         fix integrate free nve/sphere\n\
         fix movelid lid move variable NULL NULL NULL v_vx v_zero v_vz\n\
         compute zfl floor reduce ave z\ncompute zli lid reduce ave z\n\
         compute slab all reduce sum v_slice\n\
         thermo_style custom step atoms c_zfl c_zli c_slab\nthermo 0\n\
         thermo_modify lost ignore norm no"
    );
}

/// One sample: run, measure, print.
fn sample(s: &mut String, d: &CellDeck, phase: &str) {
    let _ = writeln!(
        s,
        "run {} pre ${{pre}} post no\nvariable pre string no\n\
         variable snow equal ${{sn}}\nvariable ssnow equal ${{ss}}\n\
         print \"SAMPLE {phase} ${{st}} ${{snow}} ${{ssnow}} ${{fm}} ${{lm}} ${{sv}}\"",
        d.sample
    );
}

/// One failure test `k` (1-based) at `fraction` of the pre-shear stress, from the restart.
fn failure(
    s: &mut String,
    p: &ParamSet,
    d: &CellDeck,
    law: &GranModel,
    k: usize,
    fraction: f64,
) -> Result<()> {
    let _ = writeln!(
        s,
        "\n# Failure point {k}: {fraction} of the pre-shear stress, from the pre-sheared state.\n\
         clear\natom_modify map array\nprocessors 1 * 1\nread_restart {RESTART}\nnewton off"
    );
    physics(s, p, d, law)?;
    cell_fixes(s);
    // mbgc's clone carries the lid's speed; the restart carries the atoms' velocities.
    let _ = writeln!(
        s,
        "variable pre string yes\nvariable target equal {}\nvariable snow equal ${{snowp}}\n\
         variable vxset equal 0\n\
         variable r{k} loop {}\nlabel relax{k}",
        num(fraction * d.sigma),
        d.relax_samples
    );
    sample(s, d, &format!("R{k}"));
    let _ = writeln!(
        s,
        "next r{k}\njump SELF relax{k}\n\
         variable vxset equal {vs}\nvariable f0 equal ${{st}}\n\
         variable t equal (step-${{f0}})*{dv}\n\
         print \"FAIL_START {k} ${{f0}}\"\n\
         variable an equal 0\nvariable as equal 0\nvariable ac equal 0\nvariable nb equal 0\n\
         variable s1 equal 0\nvariable s2 equal 0\nvariable s3 equal 0\n\
         variable hp equal 0\nvariable ps equal 0\n\
         variable f{k} loop {}\nlabel fail{k}",
        d.failure_samples,
        vs = num(d.v_shear),
        dv = num(d.dt * d.v_shear),
    );
    sample(s, d, &format!("F{k}"));
    // mbgc's peak rule on bins of 0.1 d50: a new bin's running mean over three bins is the
    // peak while it rises; past 0.5 d50 of travel a mean 5 % below the peak ends the test.
    // LIGGGHTS' `if` compares numbers but computes nothing, hence `edge` and `lim`.
    let _ = writeln!(
        s,
        "variable tt equal ${{t}}\n\
         variable an equal ${{an}}+${{snow}}\nvariable as equal ${{as}}+${{ssnow}}\n\
         variable ac equal ${{ac}}+1\n\
         variable edge equal {bin}*(${{nb}}+1)\n\
         if \"${{tt}} >= ${{edge}}\" then \"jump SELF bin{k}\"\n\
         jump SELF next{k}\nlabel bin{k}\n\
         variable nb equal ${{nb}}+1\n\
         variable s1 equal ${{s2}}\nvariable s2 equal ${{s3}}\nvariable s3 equal ${{as}}/${{ac}}\n\
         variable an equal 0\nvariable as equal 0\nvariable ac equal 0\n\
         if \"${{nb}} < 3\" then \"jump SELF next{k}\"\n\
         variable ms equal (${{s1}}+${{s2}}+${{s3}})/3\n\
         if \"${{hp}} == 0 || ${{ms}} > ${{ps}}\" then \"jump SELF peak{k}\"\n\
         variable lim equal 0.95*${{ps}}\n\
         if \"${{tt}} > {half} && ${{ms}} < ${{lim}}\" then \"jump SELF done{k}\"\n\
         jump SELF next{k}\nlabel peak{k}\nvariable ps equal ${{ms}}\nvariable hp equal 1\n\
         label next{k}\nnext f{k}\njump SELF fail{k}\nlabel done{k}\n\
         print \"FAIL_END {k} ${{st}}\"",
        bin = num(d.bin),
        half = num(0.5 * d.d50),
    );
    Ok(())
}

/// The bisection that glues the layer `name` (`floor`: the lowest grains, `lid`: the highest)
/// of mass `mlay`: the cut between `lo` and `hi` is halved [`BISECTIONS`] times, keeping the
/// side whose block holds at least the layer's mass.
fn glue_layer(s: &mut String, d: &CellDeck, name: &str) {
    let (lo, hi) = (d.domain.0[2], d.domain.1[2]);
    // Floor: the block below the cut; the cut that holds the layer is `hi`. Lid: the block
    // above it; the cut that holds it is `lo`.
    let (block, enough, short, keep) = if name == "floor" {
        ("INF ${zc}", "hi", "lo", "hi")
    } else {
        ("${zc} INF", "lo", "hi", "lo")
    };
    let tag = &name[..1];
    let _ = writeln!(
        s,
        "variable lo equal {lo}\nvariable hi equal {hi}\nvariable g{tag} loop {BISECTIONS}\n\
         label cut{name}\nvariable zc equal 0.5*(${{lo}}+${{hi}})\n\
         region {tag}c${{g{tag}}} block INF INF INF INF {block} units box\n\
         variable mc equal mass(all,{tag}c${{g{tag}}})\n\
         if \"${{mc}} >= ${{mlay}}\" then \"variable {enough} equal ${{zc}}\" \
         else \"variable {short} equal ${{zc}}\"\n\
         next g{tag}\njump SELF cut{name}\n\
         region {name}layer block INF INF INF INF {} units box\n\
         group {name} region {name}layer",
        block.replace("${zc}", &format!("${{{keep}}}")),
        lo = num(lo),
        hi = num(hi),
    );
}

/// Writes the input script into `dir`.
pub fn write_cell_deck(dir: &Path, p: &ParamSet, d: &CellDeck) -> Result<()> {
    let rho = p.require("rho_p", crate::experiments::RHO_RANGE.0, 1e5)?;
    if d.classes.is_empty() {
        return Err(Error::invalid("shear cell deck: no particle classes"));
    }
    let law = gran_model(&d.class)?;
    let [l, w, _] = d.size;
    let (lo, hi) = d.domain;
    let area = num(d.area());
    let mut s = String::from(
        "# mbgc shear cell (periodic in x and y, glued floor and lid layers of the grains), run \
         by LIGGGHTS itself.\n\
         # One atom type: the grains; the floor plane is of their material.\n\
         # Stages: pour, glue, consolidation, pre-shear until steady, restart, three failure \
         tests.\n",
    );
    let _ = writeln!(
        s,
        "echo none\nunits si\natom_style granular\natom_modify map array\nboundary p p f\n\
         newton off\nprocessors 1 * 1"
    );
    // The variables that `fix move` and `compute reduce` read by index come first and are
    // never redefined (module documentation); they read everything else by name. The lid's
    // vertical speed is mbgc's dead load: each step it changes by the lid's net force (the
    // bed's contact force of the last force computation minus the load) over its mass.
    let _ = writeln!(
        s,
        "variable vx equal v_vxset\nvariable zero equal 0\n\
         variable vz equal vcm(lid,z)+{dt}*(fcm(lid,z)-v_target*{area})/mass(lid)\n\
         variable v2a atom vx*vx+vy*vy+vz*vz\n\
         variable sa atom v_za-z+r\nvariable ca atom v_sa*(v_sa>0)-(v_sa-2*r)*(v_sa>2*r)\n\
         variable sb atom v_zb-z+r\nvariable cb atom v_sb*(v_sb>0)-(v_sb-2*r)*(v_sb>2*r)\n\
         variable slice atom PI*(v_cb*v_cb*(3*r-v_cb)-v_ca*v_ca*(3*r-v_ca))/3",
        dt = num(d.dt),
    );
    // mbgc's interior slab, stresses and load, read by name.
    let _ = writeln!(
        s,
        "variable za equal c_zfl+{gap}\nvariable zb equal c_zli-{gap}\n\
         variable sn equal fcm(lid,z)/{area}\nvariable ss equal -fcm(lid,x)/{area}\n\
         variable fm equal c_zfl\nvariable lm equal c_zli\nvariable sv equal c_slab\n\
         variable st equal step\nvariable na equal count(all)\nvariable mall equal mass(all)\n\
         variable vxset equal 0\nvariable target equal {sigma}\n\
         variable snow equal 0\nvariable pre string yes",
        gap = num(d.interior_gap()),
        sigma = num(d.sigma),
    );
    let _ = writeln!(
        s,
        "region domain block {} {} {} {} {} {} units box\ncreate_box 1 domain",
        num(lo[0]),
        num(hi[0]),
        num(lo[1]),
        num(hi[1]),
        num(lo[2]),
        num(hi[2])
    );
    physics(&mut s, p, d, &law)?;
    // Pour.
    let _ = writeln!(
        s,
        "\n# Pour.\nfix gravity all gravity {} vector 0.0 0.0 -1.0\nfix integrate all nve/sphere",
        num(G)
    );
    let mut dist = format!(
        "fix pdd all particledistribution/discrete {} {}",
        stream_seed(d.seed, 1),
        d.classes.len()
    );
    for (k, (diam, frac)) in d.classes.iter().enumerate() {
        let _ = writeln!(
            s,
            "fix pts{k} all particletemplate/sphere {} atom_type 1 density constant {} \
             radius constant {}",
            stream_seed(d.seed, 2 + k as u64),
            num(rho),
            num(0.5 * diam)
        );
        let _ = write!(dist, " pts{k} {}", num(*frac));
    }
    let _ = writeln!(s, "{dist}");
    let amount = if d.classes.len() == 1 {
        format!("particles_in_region {}", d.count)
    } else {
        format!("mass_in_region {}", num(d.mass))
    };
    let _ = writeln!(
        s,
        "region column block 0 {} 0 {} 0 {} units box\n\
         fix ins all insert/pack seed {} distributiontemplate pdd maxattempt 20000 \
         insert_every once overlapcheck yes all_in yes vel constant 0. 0. 0. region column {amount}\n\
         compute v2 all reduce sum v_v2a\nvariable vrms equal sqrt(c_v2/count(all))\n\
         thermo_style custom step atoms c_v2\nthermo {}\nthermo_modify lost ignore norm no",
        num(l),
        num(w),
        num(d.column_top),
        stream_seed(d.seed, 0),
        d.chunk,
    );
    let _ = writeln!(
        s,
        "label fill\nrun {}\n\
         if \"(${{vrms}} < {} && ${{st}} > {}) || ${{st}} >= {}\" then \"jump SELF filled\"\n\
         jump SELF fill\nlabel filled\n\
         variable settled equal ${{vrms}}<{}\n\
         print \"FILL_STEPS ${{st}} ${{settled}}\"\nprint \"INSERTED ${{na}} ${{mall}}\"\n\
         unfix ins\nuncompute v2\nunfix integrate\nunfix gravity",
        d.chunk,
        num(d.v_rest),
        d.fall_steps,
        d.max_fill_steps,
        num(d.v_rest),
    );
    // Glue the floor and the lid.
    let _ = writeln!(
        s,
        "\n# Glue the lowest and the highest layer.\nvariable mlay equal {}",
        num(d.layer_mass)
    );
    glue_layer(&mut s, d, "floor");
    glue_layer(&mut s, d, "lid");
    let _ = writeln!(
        s,
        "group glued union floor lid\ngroup free subtract all glued\n\
         variable nfl equal count(floor)\nvariable nli equal count(lid)\n\
         variable mfl equal mass(floor)\nvariable mli equal mass(lid)\n\
         print \"GLUED ${{nfl}} ${{nli}} ${{mfl}} ${{mli}}\"\n\
         velocity glued set 0.0 0.0 0.0\nset group glued omegax 0.0 omegay 0.0 omegaz 0.0"
    );
    cell_fixes(&mut s);
    // Consolidation at the pre-shear stress, the lid at rest horizontally.
    let _ = writeln!(
        s,
        "\n# Consolidation.\nvariable c loop {}\nlabel consolidate",
        d.consolidate_samples
    );
    sample(&mut s, d, "C");
    let _ = writeln!(s, "next c\njump SELF consolidate");
    // Pre-shear until steady: bins of 0.1 d50 of travel, the last ten bin means in n1..n10
    // (normal) and s1..s10 (shear), mbgc's test at every fifth bin.
    let _ = writeln!(
        s,
        "\n# Pre-shear until steady.\nvariable vxset equal {}\nvariable p0 equal ${{st}}\n\
         print \"PRESHEAR_START ${{p0}}\"\n\
         variable an equal 0\nvariable as equal 0\nvariable ac equal 0\nvariable nb equal 0",
        num(d.v_shear)
    );
    for i in 1..=10 {
        let _ = writeln!(s, "variable n{i} equal 0\nvariable s{i} equal 0");
    }
    let _ = writeln!(s, "variable p loop {}\nlabel preshear", d.preshear_samples);
    sample(&mut s, d, "P");
    let _ = writeln!(
        s,
        "variable tt equal (${{st}}-${{p0}})*{dv}\n\
         variable an equal ${{an}}+${{snow}}\nvariable as equal ${{as}}+${{ssnow}}\n\
         variable ac equal ${{ac}}+1\n\
         variable edge equal {bin}*(${{nb}}+1)\n\
         if \"${{tt}} >= ${{edge}}\" then \"jump SELF pbin\"\n\
         jump SELF pnext\nlabel pbin\nvariable nb equal ${{nb}}+1",
        dv = num(d.dt * d.v_shear),
        bin = num(d.bin),
    );
    for i in 1..10 {
        let _ = writeln!(
            s,
            "variable n{i} equal ${{n{j}}}\nvariable s{i} equal ${{s{j}}}",
            j = i + 1
        );
    }
    let sum = |v: &str, r: std::ops::RangeInclusive<usize>| {
        r.map(|i| format!("${{{v}{i}}}"))
            .collect::<Vec<_>>()
            .join("+")
    };
    let _ = writeln!(
        s,
        "variable n10 equal ${{an}}/${{ac}}\nvariable s10 equal ${{as}}/${{ac}}\n\
         variable an equal 0\nvariable as equal 0\nvariable ac equal 0\n\
         variable nm equal ${{nb}}%5\n\
         if \"${{nm}} != 0 || ${{tt}} < {first}\" then \"jump SELF pnext\"\n\
         if \"${{nb}} < 10\" then \"jump SELF plimit\"\n\
         variable rl equal ({sl})/({nl})\nvariable rb equal ({sb})/({nbf})\n\
         variable dev equal abs(${{rl}}-${{rb}})\nvariable tol equal {tol}*abs(${{rl}})\n\
         if \"${{dev}} < ${{tol}}\" then \"jump SELF pdone\"\n\
         label plimit\n\
         if \"${{tt}} >= {last}\" then \"jump SELF pdone\"\n\
         label pnext\nnext p\njump SELF preshear\nlabel pdone",
        first = num(d.preshear - 0.5 * d.bin),
        last = num(d.max_preshear - 0.5 * d.bin),
        tol = num(STEADY_TOLERANCE),
        sl = sum("s", 6..=10),
        nl = sum("n", 6..=10),
        sb = sum("s", 1..=5),
        nbf = sum("n", 1..=5),
    );
    // The pre-sheared state: its free grains, the restart.
    let _ = writeln!(
        s,
        "print \"PRESHEAR_END ${{st}} ${{na}}\"\n\
         write_dump free custom {PRESHEAR_DUMP} id radius x y z modify format \"%d %.17g %.17g %.17g %.17g\"\n\
         variable snowp equal ${{snow}}\nwrite_restart {RESTART}"
    );
    for (k, f) in FAILURE_FRACTIONS.iter().enumerate() {
        failure(&mut s, p, d, &law, k + 1, *f)?;
    }
    let _ = writeln!(
        s,
        "\n\
         write_dump all custom {FINAL_DUMP} id radius x y z modify format \"%d %.17g %.17g %.17g %.17g\"\n\
         print \"RUN_END\""
    );
    write_atomic(&dir.join(INPUT), s.as_bytes())
}

/// One stress sample the deck printed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Step at its end.
    pub step: u64,
    /// Normal stress (the lid's vertical contact force per area), Pa.
    pub normal: f64,
    /// Shear stress, Pa.
    pub shear: f64,
    /// Mean centre height of the floor's grains, m.
    pub floor: f64,
    /// Mean centre height of the lid's grains, m.
    pub lid: f64,
    /// Solid volume of the interior slab (every grain sliced), m^3.
    pub slab: f64,
}

/// One failure test as the deck ran it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FailureRun {
    /// Step at which the lid started to move.
    pub start: u64,
    /// Its samples while shearing.
    pub samples: Vec<Sample>,
}

/// Where the run in a directory stands.
pub use super::fill_run::RunState;

/// Where the run in `dir` stands, from its deck, log and final dump.
pub fn state(dir: &Path) -> RunState {
    super::fill_run::state(dir)
}

/// The glued layers as the deck chose them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Glued {
    /// Grains of the floor and of the lid.
    pub floor: usize,
    /// Grains of the lid.
    pub lid: usize,
    /// Mass of the floor, kg.
    pub floor_mass: f64,
    /// Mass of the lid, kg.
    pub lid_mass: f64,
}

/// A finished shear-cell run read back from its directory.
#[derive(Debug, Clone, PartialEq)]
pub struct CellRun {
    /// Step at which the fill stopped.
    pub fill_steps: u64,
    /// Whether the fill came to rest (rather than hitting the step limit).
    pub fill_settled: bool,
    /// Particles inserted.
    pub inserted: usize,
    /// Mass inserted, kg.
    pub inserted_mass: f64,
    /// The glued layers.
    pub glued: Glued,
    /// Step at which the pre-shear started.
    pub preshear_start: u64,
    /// Pre-shear samples.
    pub preshear: Vec<Sample>,
    /// Step at the end of the pre-shear (the main run's steps, as mbgc counts them).
    pub preshear_end: u64,
    /// Particles in the cell at the end of the pre-shear.
    pub atoms: usize,
    /// (radius, position) of each free grain at the end of the pre-shear.
    pub free: Vec<(f64, V3)>,
    /// The failure tests in [`FAILURE_FRACTIONS`] order.
    pub failures: Vec<FailureRun>,
    /// Steps of the whole run, summed over its `run` commands.
    pub steps: u64,
    /// LIGGGHTS' loop time summed over its `run` commands, s.
    pub loop_seconds: f64,
    /// MPI ranks the log reports.
    pub procs: usize,
}

fn read_log(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

impl CellRun {
    /// Reads a finished run; an unfinished or failed one is an error naming the directory.
    pub fn read(dir: &Path) -> Result<CellRun> {
        match state(dir) {
            RunState::Finished => {}
            RunState::Failed(e) => {
                return Err(Error::invalid(format!(
                    "LIGGGHTS failed in {}: {e}",
                    dir.display()
                )))
            }
            s => {
                return Err(Error::input(
                    dir.join(LOG).display(),
                    "end of run",
                    format!(
                        "a finished run (a 'RUN_END' line and {FINAL_DUMP}), found it {}",
                        if s == RunState::NotRun {
                            "not started"
                        } else {
                            "unfinished"
                        }
                    ),
                ))
            }
        }
        let log_path = dir.join(LOG);
        let free_path = dir.join(PRESHEAR_DUMP);
        let free = super::parse::parse_dump_rows(
            &free_path.display().to_string(),
            &read_to_string(&free_path)?,
        )?
        .into_iter()
        .map(|(_, r, x)| (r, x))
        .collect();
        Self::parse(&log_path.display().to_string(), &read_log(&log_path)?, free)
    }

    /// The run from the text of its log (`file` names it in errors) and its free grains at the
    /// end of the pre-shear.
    pub fn parse(file: &str, log: &str, free: Vec<(f64, V3)>) -> Result<CellRun> {
        let bad = |field: &str, what: &str| Error::input(file, field, what.to_owned());
        let words = |prefix: &str| -> Result<Vec<&str>> {
            log.lines()
                .find_map(|l| l.strip_prefix(prefix))
                .map(|r| r.split_whitespace().collect())
                .ok_or_else(|| bad(prefix.trim_end(), "the line the deck prints"))
        };
        let int = |w: Option<&&str>, field: &str| -> Result<u64> {
            w.and_then(|s| s.parse::<f64>().ok())
                .filter(|v| v.is_finite() && *v >= 0.0 && v.fract() == 0.0)
                .map(|v| v as u64)
                .ok_or_else(|| bad(field, "a whole number after it"))
        };
        let real = |w: Option<&&str>, field: &str| -> Result<f64> {
            w.and_then(|s| s.parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(field, "a finite number after it"))
        };
        let fill = words("FILL_STEPS ")?;
        let ins = words("INSERTED ")?;
        let glued = words("GLUED ")?;
        let pre = words("PRESHEAR_START ")?;
        let end = words("PRESHEAR_END ")?;
        let mut run = CellRun {
            fill_steps: int(fill.first(), "FILL_STEPS")?,
            fill_settled: real(fill.get(1), "FILL_STEPS")? > 0.5,
            inserted: int(ins.first(), "INSERTED")? as usize,
            inserted_mass: real(ins.get(1), "INSERTED")?,
            glued: Glued {
                floor: int(glued.first(), "GLUED")? as usize,
                lid: int(glued.get(1), "GLUED")? as usize,
                floor_mass: real(glued.get(2), "GLUED")?,
                lid_mass: real(glued.get(3), "GLUED")?,
            },
            preshear_start: int(pre.first(), "PRESHEAR_START")?,
            preshear: Vec::new(),
            preshear_end: int(end.first(), "PRESHEAR_END")?,
            atoms: int(end.get(1), "PRESHEAR_END")? as usize,
            free,
            failures: Vec::new(),
            steps: 0,
            loop_seconds: 0.0,
            procs: 1,
        };
        let mut current: Option<usize> = None;
        for line in log.lines() {
            if let Some(r) = line.strip_prefix("FAIL_START ") {
                let w: Vec<&str> = r.split_whitespace().collect();
                let k = int(w.first(), "FAIL_START")? as usize;
                if k != run.failures.len() + 1 {
                    return Err(bad("FAIL_START", "failure tests numbered 1, 2, 3 in order"));
                }
                run.failures.push(FailureRun {
                    start: int(w.get(1), "FAIL_START")?,
                    samples: Vec::new(),
                });
                current = Some(k - 1);
            } else if let Some(r) = line.strip_prefix("SAMPLE ") {
                let w: Vec<&str> = r.split_whitespace().collect();
                let s = Sample {
                    step: int(w.get(1), "SAMPLE")?,
                    normal: real(w.get(2), "SAMPLE")?,
                    shear: real(w.get(3), "SAMPLE")?,
                    floor: real(w.get(4), "SAMPLE")?,
                    lid: real(w.get(5), "SAMPLE")?,
                    slab: real(w.get(6), "SAMPLE")?,
                };
                match w.first().copied() {
                    Some("P") => run.preshear.push(s),
                    Some(ph) if ph.starts_with('F') => {
                        let k =
                            current
                                .filter(|k| ph == format!("F{}", k + 1))
                                .ok_or_else(|| {
                                    bad("SAMPLE", "failure samples after their FAIL_START")
                                })?;
                        run.failures[k].samples.push(s);
                    }
                    Some(_) => {}
                    None => return Err(bad("SAMPLE", "a phase, step and five numbers")),
                }
            } else if line.starts_with("Loop time of ") {
                // "Loop time of T on P procs for N steps with A atoms"
                let w: Vec<&str> = line.split_whitespace().collect();
                let what = format!("a readable line, found {line:?}");
                run.loop_seconds += w
                    .get(3)
                    .and_then(|s| s.parse::<f64>().ok())
                    .filter(|s| s.is_finite() && *s >= 0.0)
                    .ok_or_else(|| bad("Loop time", &what))?;
                run.procs = w
                    .get(5)
                    .and_then(|s| s.parse().ok())
                    .filter(|p| *p >= 1)
                    .ok_or_else(|| bad("Loop time", &what))?;
                run.steps += w
                    .get(8)
                    .and_then(|s| s.parse::<u64>().ok())
                    .ok_or_else(|| bad("Loop time", &what))?;
            }
        }
        if run.preshear.is_empty() {
            return Err(bad("SAMPLE P", "the pre-shear's samples"));
        }
        Ok(run)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::Experiment;

    /// The comparison's row: the cell's parameters only (no wall parameter exists).
    pub(crate) fn params() -> ParamSet {
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

    fn script(c: &ShearCell, p: &ParamSet) -> (CellDeck, String) {
        let d = cell_deck(c, p, 7).unwrap();
        let dir = tempfile::tempdir().unwrap();
        write_cell_deck(dir.path(), p, &d).unwrap();
        let files: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert_eq!(files, [INPUT], "the deck is one input script, no meshes");
        (d, std::fs::read_to_string(dir.path().join(INPUT)).unwrap())
    }

    #[test]
    fn the_deck_is_mbgcs_periodic_cell_with_its_schedule() {
        let c = cell(12.0);
        let p = params();
        c.check(&p).unwrap();
        let (d, s) = script(&c, &p);
        let lay = c.layout(&p, 7).unwrap();
        let sch = c.schedule(&lay, 2600.0, 5e7, 0.3, 6000.0);
        // k = 12 d_max of 10 mm: a period of 120 mm in x and y, mbgc's particles and column.
        assert_eq!(d.size, lay.size);
        assert_eq!((lay.size[0], lay.size[1]), (0.12, 0.12));
        assert_eq!(d.count, lay.diameters.len());
        assert_eq!(
            d.domain,
            ([0.0, 0.0, -0.04], [0.12, 0.12, sch.column_top + 0.05])
        );
        assert_eq!((d.dt, d.sample, d.chunk), (sch.dt, sch.sample, sch.chunk));
        assert_eq!((d.v_shear, d.bin), (sch.v_shear, sch.bin));
        assert_eq!((d.preshear, d.max_preshear), (0.02, 0.06));
        assert_eq!(
            d.consolidate_samples,
            sch.consolidate_steps.div_ceil(sch.sample)
        );
        assert_eq!(
            d.relax_samples,
            (sch.consolidate_steps / 2).div_ceil(sch.sample)
        );
        // The failure tests' samples reach 2 d50 of travel and no more; the pre-shear loop
        // reaches past 6 d50, so that only the steadiness rule ends it.
        let travel = |n: u64| d.travel(n * d.sample);
        assert!(travel(d.failure_samples) >= 0.02 && travel(d.failure_samples - 1) < 0.02);
        assert!(travel(d.preshear_samples) > 0.06 + 0.5 * d.bin);
        // Each glued layer: 0.55 x 1.5 d_max x the plan area of solid, as mbgc's.
        let layer = 2600.0 * 0.55 * 1.5 * 0.01 * 0.12 * 0.12;
        assert!((d.layer_mass - layer).abs() < 1e-12 * layer);
        assert!((d.interior_gap() - 0.0175).abs() < 1e-15);
        let (l, area) = (num(0.12), num(0.12 * 0.12));
        let law = "model hertz tangential history rolling_friction epsd2";
        for want in [
            "boundary p p f\n".to_string(),
            format!("region domain block 0e0 {l} 0e0 {l} -4e-2 {} units box\n", num(d.domain.1[2])),
            "create_box 1 domain\n".into(),
            format!("pair_style gran {law}\n"),
            format!("fix floorplane all wall/gran {law} primitive type 1 zplane 0e0\n"),
            "fix m1 all property/global youngsModulus peratomtype 5e7\n".into(),
            "fix m3 all property/global coefficientRestitution peratomtypepair 1 5e-1\n".into(),
            "fix m4 all property/global coefficientFriction peratomtypepair 1 5e-1\n".into(),
            "fix m5 all property/global coefficientRollingFriction peratomtypepair 1 1e-1\n".into(),
            format!("timestep {}\n", num(sch.dt)),
            format!("neighbor {} bin\n", num(lay.d_min)),
            format!("particles_in_region {}\n", lay.diameters.len()),
            format!("region column block 0 {l} 0 {l} 0 {} units box\n", num(sch.column_top)),
            // The layers: a cut halved 60 times, the floor below it, the lid above.
            format!("variable mlay equal {}\n", num(d.layer_mass)),
            "variable gf loop 60\n".into(),
            "region fc${gf} block INF INF INF INF INF ${zc} units box\n".into(),
            "if \"${mc} >= ${mlay}\" then \"variable hi equal ${zc}\" else \"variable lo equal ${zc}\"\n".into(),
            "region floorlayer block INF INF INF INF INF ${hi} units box\ngroup floor region floorlayer\n".into(),
            "region lc${gl} block INF INF INF INF ${zc} INF units box\n".into(),
            "if \"${mc} >= ${mlay}\" then \"variable lo equal ${zc}\" else \"variable hi equal ${zc}\"\n".into(),
            "region lidlayer block INF INF INF INF ${lo} INF units box\ngroup lid region lidlayer\n".into(),
            "group glued union floor lid\ngroup free subtract all glued\n".into(),
            "velocity glued set 0.0 0.0 0.0\nset group glued omegax 0.0 omegay 0.0 omegaz 0.0\n".into(),
            // Gravity off from the glue on (mbgc's shear); glued grains: no contacts among them,
            // not integrated; the lid rigid.
            "unfix integrate\nunfix gravity\n".into(),
            "neigh_modify exclude group glued glued\nfix integrate free nve/sphere\n".into(),
            "fix movelid lid move variable NULL NULL NULL v_vx v_zero v_vz\n".into(),
            // mbgc's stresses, slab and dead load.
            "compute zfl floor reduce ave z\ncompute zli lid reduce ave z\n".into(),
            "compute slab all reduce sum v_slice\n".into(),
            format!("variable sn equal fcm(lid,z)/{area}\n"),
            format!("variable ss equal -fcm(lid,x)/{area}\n"),
            "variable za equal c_zfl+1.75e-2\nvariable zb equal c_zli-1.75e-2\n".into(),
            format!(
                "variable vz equal vcm(lid,z)+{}*(fcm(lid,z)-v_target*{area})/mass(lid)\n",
                num(sch.dt)
            ),
            "thermo_style custom step atoms c_zfl c_zli c_slab\nthermo 0\n".into(),
            format!("run {} pre ${{pre}} post no\n", sch.sample),
            format!("variable c loop {}\n", d.consolidate_samples),
            // The pre-shear: shear speed, bins, mbgc's steadiness test and travel limits.
            format!("variable vxset equal {}\n", num(sch.v_shear)),
            format!("variable p loop {}\n", d.preshear_samples),
            format!("variable edge equal {}*(${{nb}}+1)\n", num(0.001)),
            format!("if \"${{nm}} != 0 || ${{tt}} < {}\" then \"jump SELF pnext\"\n", num(0.02 - 0.0005)),
            "variable rl equal (${s6}+${s7}+${s8}+${s9}+${s10})/(${n6}+${n7}+${n8}+${n9}+${n10})\n".into(),
            "variable rb equal (${s1}+${s2}+${s3}+${s4}+${s5})/(${n1}+${n2}+${n3}+${n4}+${n5})\n".into(),
            "variable tol equal 1.2e-1*abs(${rl})\n".into(),
            format!("if \"${{tt}} >= {}\" then \"jump SELF pdone\"\n", num(0.06 - 0.0005)),
            // Three failure tests from the restart, mbgc's peak rule.
            "write_restart preshear.restart\n".into(),
            "variable target equal 1.5e3\n".into(),
            "variable target equal 3e3\n".into(),
            "variable target equal 4.5e3\n".into(),
            format!("variable r2 loop {}\n", d.relax_samples),
            format!("variable f3 loop {}\n", d.failure_samples),
            "if \"${tt} > 5e-3 && ${ms} < ${lim}\" then \"jump SELF done3\"\n".into(),
            "print \"RUN_END\"\n".into(),
        ] {
            assert!(s.contains(&want), "missing {want:?} in\n{s}");
        }
        // No wall material, no second atom type, no mesh.
        assert_eq!(
            s.matches("\nfix gravity").count(),
            1,
            "gravity in the pour only"
        );
        for absent in ["type 2", "peratomtypepair 2", ".stl", "E_w", "mesh"] {
            assert!(!s.contains(absent), "{absent:?} in the deck");
        }
        assert_eq!(s.matches("read_restart preshear.restart").count(), 3);
        assert_eq!(s.matches("fix movelid lid move").count(), 4);
        // Every label jumped to exists once; every loop variable is used once.
        for j in s.split("jump SELF ").skip(1) {
            let to = j.split(['"', '\n']).next().unwrap();
            assert_eq!(s.matches(&format!("\nlabel {to}\n")).count(), 1, "{to}");
        }
        let loops: Vec<&str> = s
            .lines()
            .filter(|l| l.starts_with("variable ") && l.contains(" loop "))
            .map(|l| l.split_whitespace().nth(1).unwrap())
            .collect();
        let mut unique = loops.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), loops.len(), "{loops:?}");
        // The variables read by index come before any that is redefined or deleted.
        let first = |v: &str| s.find(&format!("variable {v} ")).unwrap();
        let defined_last = ["vx", "zero", "vz", "v2a", "slice"]
            .map(first)
            .into_iter()
            .max()
            .unwrap();
        assert!(defined_last < first("vxset") && defined_last < first("gf"));
    }

    #[test]
    fn the_experiment_has_the_cells_parameters_and_sjkr_its_grains_cohesion() {
        let c = ShearCell {
            class: ModelClass::parse("hertz,mindlin,epsd2,sjkr").unwrap(),
            ..cell(12.0)
        };
        let names = c.parameters();
        for wall in ["E_w", "e_pw", "mu_pw", "mu_r_pw", "ced_pw"] {
            assert!(!names.contains(&wall), "{wall} in {names:?}");
        }
        let mut p = params();
        p.set("ced_pp", 0.0);
        let (_, s) = script(&c, &p);
        let law = "model hertz tangential history cohesion sjkr rolling_friction epsd2";
        assert!(s.contains(&format!("pair_style gran {law}\n")), "{s}");
        assert!(s.contains(&format!(
            "fix floorplane all wall/gran {law} primitive type 1"
        )));
        assert!(
            s.contains("fix m6 all property/global cohesionEnergyDensity peratomtypepair 1 0e0\n"),
            "{s}"
        );
        // Without ced_pp the row is refused by name.
        let e = cell_deck(&c, &params(), 1)
            .and_then(|d| write_cell_deck(tempfile::tempdir().unwrap().path(), &params(), &d))
            .unwrap_err()
            .to_string();
        assert!(e.contains("ced_pp"), "{e}");
    }

    #[test]
    fn a_psd_is_poured_by_mass_as_equal_mass_templates() {
        let mut p = params();
        p.set("sigma_ln", 0.2);
        let (d, s) = script(&cell(5.0), &p);
        assert_eq!(d.classes.len(), CLASSES);
        assert!(
            s.contains(&format!("mass_in_region {}\n", num(d.mass))),
            "{s}"
        );
        assert_eq!(s.matches("particletemplate/sphere").count(), CLASSES);
    }

    #[test]
    fn bad_rows_and_classes_are_refused_by_name() {
        let mut p = params();
        p.set("normal_stress", -1.0);
        let e = cell_deck(&cell(5.0), &p, 1).unwrap_err().to_string();
        assert!(e.contains("normal_stress"), "{e}");
        let e = cell_deck(&cell(4.0), &params(), 1).unwrap_err().to_string();
        assert!(e.contains("--box-scale"), "{e}");
        let c = ShearCell {
            class: ModelClass::parse("tsuji,mindlin").unwrap(),
            ..cell(5.0)
        };
        let d = cell_deck(&c, &params(), 1).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let e = write_cell_deck(dir.path(), &params(), &d)
            .unwrap_err()
            .to_string();
        assert!(e.contains("tsuji") && e.contains("LIGGGHTS"), "{e}");
    }

    #[test]
    fn a_log_is_read_into_stages_and_samples() {
        let log = "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, x)\n\
            Loop time of 2 on 1 procs for 100 steps with 10 atoms\n\
            FILL_STEPS 100 1\nINSERTED 10 0.5\nGLUED 2 3 0.1 0.15\n\
            print \"SAMPLE P ${st} ${snow} ${ssnow} ${fm} ${lm} ${sv}\"\n\
            SAMPLE C 190 5000 0 0.01 0.1 1e-4\nPRESHEAR_START 200\n\
            SAMPLE P 230 5100 4000 0.01 0.1001 1.1e-4\n\
            Loop time of 1.5 on 1 procs for 30 steps with 10 atoms\n\
            PRESHEAR_END 230 10\nFAIL_START 1 300\n\
            SAMPLE R1 290 1 1 1 1 1\nSAMPLE F1 330 1500 1200 0.01 0.1002 1e-4\n\
            FAIL_START 2 400\nSAMPLE F2 430 3000 2500 0.01 0.1 1e-4\n";
        let r = CellRun::parse("log", log, vec![]).unwrap();
        assert_eq!((r.fill_steps, r.fill_settled, r.inserted), (100, true, 10));
        assert_eq!(
            r.glued,
            Glued {
                floor: 2,
                lid: 3,
                floor_mass: 0.1,
                lid_mass: 0.15
            }
        );
        assert_eq!((r.preshear_start, r.preshear_end, r.steps), (200, 230, 130));
        assert_eq!((r.atoms, r.loop_seconds), (10, 3.5));
        assert_eq!(r.preshear.len(), 1);
        assert_eq!((r.preshear[0].shear, r.preshear[0].lid), (4000.0, 0.1001));
        assert_eq!(r.preshear[0].slab, 1.1e-4);
        assert_eq!(r.failures.len(), 2);
        assert_eq!(r.failures[1].start, 400);
        assert_eq!(r.failures[0].samples[0].normal, 1500.0);
        let e = CellRun::parse(
            "log.x",
            &log.replace("SAMPLE P 230 5100", "SAMPLE P 230 x"),
            vec![],
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("log.x: SAMPLE"), "{e}");
        for line in ["PRESHEAR_END", "GLUED", "PRESHEAR_START"] {
            let e = CellRun::parse("log.x", &log.replace(line, "X"), vec![])
                .unwrap_err()
                .to_string();
            assert!(e.contains(line), "{e}");
        }
    }

    #[test]
    fn the_interior_slab_is_mbgcs() {
        let d = cell_deck(&cell(12.0), &params(), 1).unwrap();
        // Layers 0.1 m apart: a slab from 0.0175 above the floor to 0.0175 below the lid.
        let s = Sample {
            step: 0,
            normal: 0.0,
            shear: 0.0,
            floor: 0.01,
            lid: 0.11,
            slab: 0.6 * 0.12 * 0.12 * 0.065,
        };
        assert!((d.solid_fraction(&s) - 0.6).abs() < 1e-12);
        let close = Sample { lid: 0.04, ..s };
        assert!(d.solid_fraction(&close).is_nan());
    }
}
