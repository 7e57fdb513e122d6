//! The shear cell ([`crate::experiments::shear_cell`]) as a LIGGGHTS 3.8 deck that runs the
//! whole procedure itself: pour, servo-lid consolidation, pre-shear over the fixed travel, and
//! three failure tests from copies of the pre-sheared state. [`cell_deck`] takes every number
//! from mbgc's own layout and schedule (cell in d_max units, time step, sample interval, shear
//! and servo speeds, step counts), so that the two codes do the same things at the same steps;
//! [`CellRun`] reads a finished run back for [`super::shear_cell_experiment`] to measure.
//!
//! What the deck does, in mbgc's order:
//!
//! - Walls as STL meshes (`fix mesh/surface`): the floor, the lower half's four sides up to the
//!   split, the upper half's four sides above it (one mesh), the lid and the shelf beyond the
//!   lower half's far end, with mbgc's extents. LIGGGHTS accepts one mesh `wall/gran` fix only,
//!   so all five meshes are in it from the start; the upper half, the lid and the shelf are
//!   `mesh/surface/stress` meshes, whose total force (`f_ID[1..3]`, the particles' force on the
//!   mesh, as mbgc's `wall_force`) the stresses are made of.
//! - Pour: LIGGGHTS' own `insert/pack` (the particle count of mbgc's layout when monosized,
//!   its mass as equal-mass templates of the PSD otherwise, as the shear-box backend) into
//!   mbgc's column, fill until the unweighted rms speed falls below mbgc's threshold after the
//!   free-fall time, in mbgc's chunks.
//! - The lid, which waits above the column during the pour as mbgc's does, is put on the bed
//!   (0.05 d_min above the highest particle top) by one step of `fix move/mesh` at the speed
//!   that covers the distance in that step; mbgc places it between two steps. This is the one
//!   step the LIGGGHTS run has that mbgc's has not.
//! - Consolidation, pre-shear, relaxation and failure as a loop of `run <sample>` commands: after
//!   each, the deck evaluates the stresses on the shear plane exactly as mbgc does (normal: lid
//!   z-force plus the weight of the particles above the split plus the shelf's z-force; shear:
//!   minus the x-forces on the upper walls and the lid, minus the shelf's x-force; both over
//!   (length - travel) x width) and sets the lid's vertical speed for the next sample by mbgc's
//!   servo (`fix move/mesh linear/variable`, with mbgc's gain and top speed). The upper walls
//!   and the lid move at mbgc's shear speed during pre-shear and failure. Particles that left
//!   the cell are deleted after each sample of the pre-shear and the failure, by mbgc's rule.
//! - The three failure points: mbgc clones its simulation; the deck writes a restart file after the
//!   pre-shear and starts each failure test with `clear` / `read_restart` (atoms, their contact
//!   histories, the meshes where they were). A k = 4 cell continued in the same process and from
//!   the restart gave stresses within 0.2 % of each other over the first 40 samples of the
//!   relaxation: the restart's setup (neighbour lists and forces computed afresh) is the only
//!   perturbation. The failure loop stops at mbgc's peak criterion (running mean of three 0.1 d50
//!   bins of the shear stress falling 5 % below its peak after 0.5 d50), computed in the deck; the
//!   responses are computed afterwards in Rust from every sample the deck printed, with mbgc's
//!   definitions. The overburden check runs in the deck too (it skips the failure tests), and
//!   again, authoritatively, in Rust on the pre-shear dump.
//!
//! Other differences from mbgc's cell: the walls are triangle meshes (LIGGGHTS' face, edge and
//! corner contacts) where mbgc's are analytic rectangles; the wall forces are those of the last
//! step's force computation (mbgc evaluates them again in the state after the step); the
//! numbers the deck computes with pass through its variables at 15 significant digits; regions
//! include their boundaries where mbgc's tests are strict.
//!
//! LIGGGHTS 3.8 traps the deck works around: an equal-style variable is redefined by deleting
//! and appending it, which moves every later variable's index, and `fix move/mesh
//! linear/variable` keeps the indices between runs without setup (`run N pre no`) - so the
//! three variables the meshes read are defined first and never redefined; computes of
//! atom-style variables in the thermo output crash such runs, so they exist only during the
//! pour; `if` compares numbers but computes nothing; `newton off` must be given again after
//! `read_restart`.
//!
//! The deck prints one `SAMPLE` line per sample (phase, step, normal and shear stress, lid
//! height), markers for each stage, and ends with `RUN_END` after its final dump. Its file
//! names are those of the campaign's deck tools (`in.shear_box_fill`, `log.shear_box_fill`,
//! `final.dump`, [`super::shear_box_fill`]), so `--write-decks`, their `run_all.sh` and
//! `mbgc campaign import` handle shear-cell decks as they handle shear-box ones.

use std::fmt::Write as _;
use std::path::Path;

use super::mesh::rect_stl;
use super::number::num;
use super::shear_box::{gran_model, write_cohesion, write_contact_properties, GranModel};
use super::shear_box_fill::prime_seed;
use crate::error::{read_to_string, write_atomic, Error, Result};
use crate::experiments::shear_box::psd_classes;
use crate::experiments::shear_cell::{ShearCell, FAILURE_FRACTIONS};
use crate::experiments::shear_test::SERVO_GAIN;
use crate::experiments::ParamSet;
use crate::psd::{default_range, Distribution, LogNormal};
use mbgc_dem::contact::ModelClass;
use mbgc_dem::vec3::V3;

pub use super::shear_box_fill::{FINAL_DUMP, INPUT, LOG};

/// Gravity, m/s^2 (mbgc's).
pub const G: f64 = 9.81;

/// Dump at the end of the pre-shear: the bed whose bulk density and overburden are measured.
pub const PRESHEAR_DUMP: &str = "preshear.dump";

/// The restart file the failure tests start from.
pub const RESTART: &str = "preshear.restart";

/// Particle templates of equal mass standing for a continuous PSD (as the shear-box backend).
pub const CLASSES: usize = 5;

/// What the deck needs, in SI units, all from mbgc's layout and schedule for the row.
#[derive(Debug, Clone, PartialEq)]
pub struct CellDeck {
    /// The contact law, written effect by effect in LIGGGHTS' words.
    pub class: ModelClass,
    /// Length (shear direction), width and nominal bed height of the cell, m.
    pub size: V3,
    /// Height of the split plane, m.
    pub split: f64,
    /// Height of the upper walls' top and of the lid during the pour, m.
    pub top: f64,
    /// Length of the shelf beyond the lower half's far end, m.
    pub shelf: f64,
    /// (diameter m, mass fraction) of each particle template.
    pub classes: Vec<(f64, f64)>,
    /// Particles of mbgc's layout (inserted by number when monosized).
    pub count: usize,
    /// Their total mass, kg (inserted by mass when there are several templates).
    pub mass: f64,
    /// Top of the poured column, m.
    pub column_top: f64,
    /// Lower and upper corners of the simulation domain, m.
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
    /// d50, smallest and largest diameter of mbgc's layout, m.
    pub d50: f64,
    /// Smallest diameter, m.
    pub d_min: f64,
    /// Largest diameter, m.
    pub d_max: f64,
    /// Pre-shear normal stress, Pa.
    pub sigma: f64,
    /// Speed of the upper half, m/s.
    pub v_shear: f64,
    /// Top speed of the lid, m/s.
    pub v_servo: f64,
    /// Steps per sample (and servo update).
    pub sample: u64,
    /// Travel per averaging bin, m.
    pub bin: f64,
    /// Samples of the consolidation.
    pub consolidate_samples: u64,
    /// Samples of the pre-shear (its travel reaches mbgc's fixed pre-shear travel).
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
    /// Travel after `n` samples at the shear speed, m (mbgc's `(time - start) * v_shear`).
    pub fn travel(&self, steps: u64) -> f64 {
        steps as f64 * self.dt * self.v_shear
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
    Ok(CellDeck {
        class: cell.class,
        size: lay.size,
        split: lay.split,
        top,
        shelf: sch.preshear + sch.max_failure + lay.d_max,
        classes,
        count: lay.diameters.len(),
        mass,
        column_top: sch.column_top,
        domain: (
            [-margin - l, -margin, -margin],
            [2.0 * l + margin, w + margin, top + margin],
        ),
        dt: sch.dt,
        skin: lay.d_min,
        chunk: sch.chunk,
        v_rest: sch.v_rest,
        fall_steps: (sch.fall / sch.dt) as u64,
        max_fill_steps: sch.max_fill_steps,
        d50: lay.d50,
        d_min: lay.d_min,
        d_max: lay.d_max,
        sigma,
        v_shear: sch.v_shear,
        v_servo: sch.v_servo,
        sample: sch.sample,
        bin: sch.bin,
        consolidate_samples: sch.consolidate_steps.div_ceil(sch.sample),
        preshear_samples: samples_for(sch.preshear, sch.sample, sch.dt, sch.v_shear),
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

/// An STL solid of several rectangles (corner, edge a, edge b).
fn rects_stl(name: &str, rects: &[(V3, V3, V3)]) -> String {
    let mut s = format!("solid {name}\n");
    for &(c, a, b) in rects {
        let one = rect_stl(name, c, a, b);
        for line in one.lines().filter(|l| l.starts_with(' ')) {
            s.push_str(line);
            s.push('\n');
        }
    }
    s + &format!("endsolid {name}\n")
}

/// The meshes of the cell, in the order of the wall fix: (name, stress mesh?, rectangles).
type MeshSpec = (&'static str, bool, Vec<(V3, V3, V3)>);

fn meshes(d: &CellDeck) -> Vec<MeshSpec> {
    let [l, w, _] = d.size;
    let (zs, top, dm) = (d.split, d.top, d.d_max);
    let sides = |z0: f64, h: f64| {
        vec![
            ([0.0, 0.0, z0], [0.0, w, 0.0], [0.0, 0.0, h]),
            ([l, 0.0, z0], [0.0, w, 0.0], [0.0, 0.0, h]),
            ([0.0, 0.0, z0], [l, 0.0, 0.0], [0.0, 0.0, h]),
            ([0.0, w, z0], [l, 0.0, 0.0], [0.0, 0.0, h]),
        ]
    };
    vec![
        (
            "floor",
            false,
            vec![(
                [-0.5 * l, -dm, 0.0],
                [2.0 * l, 0.0, 0.0],
                [0.0, w + 2.0 * dm, 0.0],
            )],
        ),
        ("lower", false, sides(0.0, zs)),
        ("upper", true, sides(zs, top - zs)),
        (
            "lid",
            true,
            vec![([0.0, 0.0, top], [l, 0.0, 0.0], [0.0, w, 0.0])],
        ),
        (
            "shelf",
            true,
            vec![([l, 0.0, zs], [d.shelf, 0.0, 0.0], [0.0, w, 0.0])],
        ),
    ]
}

/// The part of the deck that a restart does not restore: neighbour lists, contact law, walls,
/// their motion, integration, regions, the stress variables and the output.
fn physics(s: &mut String, p: &ParamSet, d: &CellDeck, law: &GranModel) -> Result<()> {
    let [l, w, _] = d.size;
    let _ = writeln!(
        s,
        "neighbor {} bin\nneigh_modify delay 0\ncommunicate single vel yes\n",
        num(d.skin)
    );
    write_contact_properties(s, p)?;
    write_cohesion(s, p, &d.class)?;
    let GranModel { models, settings } = law;
    let _ = writeln!(
        s,
        "\npair_style gran {models}{settings}\npair_coeff * *\ntimestep {}\n\
         fix gravity all gravity {} vector 0.0 0.0 -1.0",
        num(d.dt),
        num(G)
    );
    let all = meshes(d);
    for (name, stress, _) in &all {
        let style = if *stress {
            "mesh/surface/stress"
        } else {
            "mesh/surface"
        };
        let _ = writeln!(s, "fix {name} all {style} file {name}.stl type 2");
    }
    let names: Vec<&str> = all.iter().map(|m| m.0).collect();
    let _ = writeln!(
        s,
        "fix walls all wall/gran {models} mesh n_meshes {} meshes {}{settings}",
        names.len(),
        names.join(" ")
    );
    // The upper half and the lid move at v_vx (0 or the shear speed), the lid vertically at
    // v_vz (the servo's speed); the variables are numbers, set between runs.
    let _ = writeln!(
        s,
        "fix move_upper all move/mesh mesh upper linear/variable v_vx v_zero v_zero\n\
         fix move_lid all move/mesh mesh lid linear/variable v_vx v_zero v_vz\n\
         fix integrate all nve/sphere"
    );
    let dm = num(d.d_max);
    let _ = writeln!(
        s,
        "region above block INF INF INF INF {zs} INF units box\n\
         region sp1 block INF -{dm} INF INF INF INF units box\n\
         region sp2 block INF INF INF -{dm} INF INF units box\n\
         region sp3 block INF INF {wd} INF INF INF units box\n\
         region sp4 block {l} INF INF INF INF {zd} units box\n\
         region spill union 4 sp1 sp2 sp3 sp4",
        zs = num(d.split),
        wd = num(w + d.d_max),
        l = num(l),
        zd = num(d.split - d.d_max),
    );
    // mbgc's stress on the shear plane, its servo, the rest criterion and the bed's top.
    let _ = writeln!(
        s,
        "variable area equal ({l}-v_tr)*{w}\n\
         variable sn equal (f_lid[3]+{g}*mass(all,above)+f_shelf[3])/v_area\n\
         variable ss equal (-(f_upper[1]+f_lid[1])-f_shelf[1])/v_area\n\
         variable err equal {gain}*(v_target-v_snow)/v_target\n\
         variable vzs equal -{vs}*(v_err*(abs(v_err)<=1)+(v_err>1)-(v_err<-1))\n\
         variable st equal step\n\
         variable na equal count(all)\n\
         variable mall equal mass(all)\n\
         variable nsp equal count(all,spill)\n\
         variable msp equal mass(all,spill)\n\
         variable ob equal {g}*mass(all,above)/v_area\n\
         thermo_style custom step atoms\nthermo {}\nthermo_modify lost ignore norm no\n",
        d.chunk,
        l = num(l),
        w = num(w),
        g = num(G),
        gain = num(SERVO_GAIN),
        vs = num(d.v_servo),
    );
    Ok(())
}

/// One sample: run, move the lid's height on, delete what left the cell (pre-shear and
/// failure), measure, print, set the servo's speed.
fn sample(s: &mut String, d: &CellDeck, phase: &str, spill: bool) {
    let _ = writeln!(
        s,
        "run {} pre ${{pre}} post no\nvariable pre string no\n\
         variable lz equal ${{lz}}+(${{vzset}})*{}",
        d.sample,
        num(d.sample as f64 * d.dt)
    );
    if spill {
        let _ = writeln!(
            s,
            "if \"${{nsp}} > 0\" then \"variable spm equal ${{spm}}+${{msp}}\" \
             \"delete_atoms region spill compress no\" \"variable pre string yes\""
        );
    }
    let _ = writeln!(
        s,
        "variable snow equal ${{sn}}\nvariable ssnow equal ${{ss}}\n\
         print \"SAMPLE {phase} ${{st}} ${{snow}} ${{ssnow}} ${{lz}}\"\n\
         variable vzset equal ${{vzs}}"
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
    let _ = writeln!(
        s,
        "variable pre string yes\nvariable vxset equal 0\nvariable vzset equal ${{vzp}}\n\
         variable lz equal ${{lzp}}\nvariable tr equal ${{trp}}\nvariable target equal {}\n\
         variable r{k} loop {}\nlabel relax{k}",
        num(fraction * d.sigma),
        d.relax_samples
    );
    sample(s, d, &format!("R{k}"), false);
    let _ = writeln!(
        s,
        "next r{k}\njump SELF relax{k}\n\
         variable vxset equal {vs}\nvariable f0 equal ${{st}}\n\
         variable tr equal ${{trp}}+(step-${{f0}})*{dv}\n\
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
    sample(s, d, &format!("F{k}"), true);
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

/// Writes the wall meshes and the input script into `dir`.
pub fn write_cell_deck(dir: &Path, p: &ParamSet, d: &CellDeck) -> Result<()> {
    let rho = p.require("rho_p", crate::experiments::RHO_RANGE.0, 1e5)?;
    if d.classes.is_empty() {
        return Err(Error::invalid("shear cell deck: no particle classes"));
    }
    let law = gran_model(&d.class)?;
    for (name, _, rects) in meshes(d) {
        write_atomic(
            &dir.join(format!("{name}.stl")),
            rects_stl(name, &rects).as_bytes(),
        )?;
    }
    let [l, w, _] = d.size;
    let (lo, hi) = d.domain;
    let mut s = String::from(
        "# mbgc shear cell (Jenike split cell), run by LIGGGHTS itself. Type 1: particles, \
         type 2: walls.\n\
         # Stages: pour, lid, consolidation, pre-shear, restart, three failure tests.\n",
    );
    let _ = writeln!(
        s,
        "echo none\nunits si\natom_style granular\natom_modify map array\nboundary f f f\n\
         newton off\nprocessors 1 * 1"
    );
    let _ = writeln!(
        s,
        "region domain block {} {} {} {} {} {} units box\ncreate_box 2 domain",
        num(lo[0]),
        num(hi[0]),
        num(lo[1]),
        num(hi[1]),
        num(lo[2]),
        num(hi[2])
    );
    // `fix move/mesh linear/variable` keeps the index of its variables between runs without
    // setup (`pre no`), and LIGGGHTS 3.8 redefines an equal-style variable by deleting it and
    // appending it, which moves every later one down: the mesh then reads another variable
    // (the lid stood still, or the run stopped on an atom-style formula). So the three it reads
    // come first and are never redefined; they read the speeds by name from vxset and vzset.
    let _ = writeln!(
        s,
        "variable vx equal v_vxset\nvariable zero equal 0\nvariable vz equal v_vzset\n\
         variable vxset equal 0\nvariable vzset equal 0\nvariable tr equal 0\n\
         variable target equal {}\nvariable pre string yes",
        num(d.sigma)
    );
    physics(&mut s, p, d, &law)?;
    // Pour.
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
         insert_every once overlapcheck yes all_in yes vel constant 0. 0. 0. region column {amount}",
        num(l),
        num(w),
        num(d.column_top),
        stream_seed(d.seed, 0),
    );
    // The fill's rest test (mbgc's unweighted rms speed) and the bed's top: computes of
    // atom-style variables, which LIGGGHTS 3.8 cannot evaluate in the thermo output of a run
    // without setup (`pre no`, it crashes), so they are dropped before the samples start.
    let _ = writeln!(
        s,
        "\nvariable v2a atom vx*vx+vy*vy+vz*vz\ncompute v2 all reduce sum v_v2a\n\
         variable vrms equal sqrt(c_v2/count(all))\ncompute rad all property/atom radius\n\
         variable zt atom z+c_rad\ncompute ztop all reduce max v_zt\n\
         variable bedtop equal c_ztop\n\
         thermo_style custom step atoms c_v2 c_ztop\nthermo_modify lost ignore norm no"
    );
    let _ = writeln!(
        s,
        "\nlabel fill\nrun {}\n\
         if \"(${{vrms}} < {} && ${{st}} > {}) || ${{st}} >= {}\" then \"jump SELF filled\"\n\
         jump SELF fill\nlabel filled\n\
         variable settled equal ${{vrms}}<{}\n\
         print \"FILL_STEPS ${{st}} ${{settled}}\"\nprint \"INSERTED ${{na}} ${{mall}}\"\nunfix ins",
        d.chunk,
        num(d.v_rest),
        d.fall_steps,
        d.max_fill_steps,
        num(d.v_rest),
    );
    // Lid onto the bed in one step.
    let _ = writeln!(
        s,
        "\nvariable lid0 equal ${{bedtop}}+{}\nvariable vzset equal (${{lid0}}-{})/{}\nrun 1\n\
         variable vzset equal 0\nvariable lz equal ${{lid0}}\nprint \"LID ${{st}} ${{lz}}\"\n\
         thermo_style custom step atoms\nthermo_modify lost ignore norm no\n\
         uncompute ztop\nuncompute rad\nuncompute v2",
        num(0.05 * d.d_min),
        num(d.top),
        num(d.dt),
    );
    // Consolidation at the pre-shear stress, upper half at rest.
    let _ = writeln!(
        s,
        "\nvariable c loop {}\nlabel consolidate",
        d.consolidate_samples
    );
    sample(&mut s, d, "C", false);
    let _ = writeln!(s, "next c\njump SELF consolidate");
    // Pre-shear over the fixed travel.
    let _ = writeln!(
        s,
        "\nvariable vxset equal {}\nvariable p0 equal ${{st}}\nvariable tr equal (step-${{p0}})*{}\n\
         variable spm equal 0\nprint \"PRESHEAR_START ${{p0}}\"\n\
         variable p loop {}\nlabel preshear",
        num(d.v_shear),
        num(d.dt * d.v_shear),
        d.preshear_samples
    );
    sample(&mut s, d, "P", true);
    let _ = writeln!(
        s,
        "next p\njump SELF preshear\n\
         print \"PRESHEAR_END ${{st}} ${{spm}}\"\n\
         write_dump all custom {PRESHEAR_DUMP} id radius x y z modify format \"%d %.17g %.17g %.17g %.17g\"\n\
         variable trp equal ${{tr}}\nvariable vzp equal ${{vzset}}\nvariable lzp equal ${{lz}}\n\
         print \"OVERBURDEN ${{ob}}\"\n\
         if \"${{ob}} > {}\" then \"jump SELF finish\"\n\
         write_restart {RESTART}",
        num(FAILURE_FRACTIONS[0] * d.sigma),
    );
    for (k, f) in FAILURE_FRACTIONS.iter().enumerate() {
        failure(&mut s, p, d, &law, k + 1, *f)?;
    }
    let _ = writeln!(
        s,
        "\nlabel finish\n\
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
    /// Normal stress on the shear plane, Pa.
    pub normal: f64,
    /// Shear stress on it, Pa.
    pub shear: f64,
    /// Height of the lid, m.
    pub lid: f64,
}

/// One failure test as the deck ran it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FailureRun {
    /// Step at which the upper half started to move.
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

/// A finished shear-cell run read back from its directory.
#[derive(Debug, Clone, PartialEq)]
pub struct CellRun {
    /// Step at which the fill stopped, and whether it was at rest.
    pub fill_steps: u64,
    /// Whether the fill came to rest (rather than hitting the step limit).
    pub fill_settled: bool,
    /// Particles inserted and their mass, kg.
    pub inserted: usize,
    /// Mass inserted, kg.
    pub inserted_mass: f64,
    /// Step at which the pre-shear started.
    pub preshear_start: u64,
    /// Pre-shear samples.
    pub preshear: Vec<Sample>,
    /// Step at the end of the pre-shear (the main run's steps, as mbgc counts them).
    pub preshear_end: u64,
    /// Mass deleted during the pre-shear, kg.
    pub spilled: f64,
    /// (radius, position) of each particle at the end of the pre-shear.
    pub bed: Vec<(f64, V3)>,
    /// The failure tests in [`FAILURE_FRACTIONS`] order (none when the deck stopped at the
    /// overburden check).
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
        let bed_path = dir.join(PRESHEAR_DUMP);
        let bed = super::parse::parse_dump_rows(
            &bed_path.display().to_string(),
            &read_to_string(&bed_path)?,
        )?
        .into_iter()
        .map(|(_, r, x)| (r, x))
        .collect();
        Self::parse(&log_path.display().to_string(), &read_log(&log_path)?, bed)
    }

    /// The run from the text of its log (`file` names it in errors) and its pre-shear bed.
    pub fn parse(file: &str, log: &str, bed: Vec<(f64, V3)>) -> Result<CellRun> {
        let bad = |field: &str, what: &str| Error::input(file, field, what.to_owned());
        let words = |prefix: &str| -> Option<Vec<&str>> {
            log.lines()
                .find_map(|l| l.strip_prefix(prefix))
                .map(|r| r.split_whitespace().collect())
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
        let fill =
            words("FILL_STEPS ").ok_or_else(|| bad("FILL_STEPS", "the line the deck prints"))?;
        let ins = words("INSERTED ").ok_or_else(|| bad("INSERTED", "the line the deck prints"))?;
        let pre = words("PRESHEAR_START ")
            .ok_or_else(|| bad("PRESHEAR_START", "the line the deck prints"))?;
        let end = words("PRESHEAR_END ")
            .ok_or_else(|| bad("PRESHEAR_END", "the line the deck prints"))?;
        let mut run = CellRun {
            fill_steps: int(fill.first(), "FILL_STEPS")?,
            fill_settled: real(fill.get(1), "FILL_STEPS")? > 0.5,
            inserted: int(ins.first(), "INSERTED")? as usize,
            inserted_mass: real(ins.get(1), "INSERTED")?,
            preshear_start: int(pre.first(), "PRESHEAR_START")?,
            preshear: Vec::new(),
            preshear_end: int(end.first(), "PRESHEAR_END")?,
            spilled: real(end.get(1), "PRESHEAR_END")?,
            bed,
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
                    lid: real(w.get(4), "SAMPLE")?,
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
                    None => return Err(bad("SAMPLE", "a phase, step and three numbers")),
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

    pub(crate) fn params() -> ParamSet {
        ParamSet::from_pairs(&[
            ("E_p", 5e7),
            ("E_w", 5e7),
            ("nu_p", 0.3),
            ("rho_p", 2600.0),
            ("d50", 10.0),
            ("normal_stress", 6000.0),
            ("e_pp", 0.5),
            ("e_pw", 0.5),
            ("mu_pp", 0.5),
            ("mu_pw", 0.3),
            ("mu_r_pp", 0.1),
            ("mu_r_pw", 0.1),
        ])
    }

    fn cell(k: f64) -> ShearCell {
        ShearCell {
            cell_scale: k,
            class: ModelClass::parse("hertz,mindlin,epsd2").unwrap(),
            ..ShearCell::default()
        }
    }

    #[test]
    fn the_deck_has_mbgcs_cell_schedule_and_stresses() {
        let c = cell(4.0);
        let p = params();
        let d = cell_deck(&c, &p, 7).unwrap();
        let lay = c.layout(&p, 7).unwrap();
        let sch = c.schedule(&lay, 2600.0, 5e7, 0.3, 6000.0);
        // k = 4 d_max of 10 mm: mbgc's length, 40 mm wide and tall, split at 20 mm, the shelf
        // 2 + 2 d50 + d_max long.
        assert_eq!(d.size, lay.size);
        assert_eq!((lay.size[1], lay.size[2], d.split), (0.04, 0.04, 0.02));
        assert!((d.shelf - 0.05).abs() < 1e-15);
        let (l, w) = (num(lay.size[0]), num(lay.size[1]));
        assert_eq!(d.count, lay.diameters.len());
        assert_eq!((d.dt, d.sample), (sch.dt, sch.sample));
        assert_eq!(
            d.consolidate_samples,
            sch.consolidate_steps.div_ceil(sch.sample)
        );
        // The pre-shear's samples reach 2 d50 of travel and no more.
        let travel = |n: u64| d.travel(n * d.sample);
        assert!(travel(d.preshear_samples) >= 0.02);
        assert!(travel(d.preshear_samples - 1) < 0.02);
        let dir = tempfile::tempdir().unwrap();
        write_cell_deck(dir.path(), &p, &d).unwrap();
        let s = std::fs::read_to_string(dir.path().join(INPUT)).unwrap();
        let law = "model hertz tangential history rolling_friction epsd2";
        for want in [
            format!("pair_style gran {law}\n"),
            format!("fix walls all wall/gran {law} mesh n_meshes 5 meshes floor lower upper lid shelf\n"),
            "fix lid all mesh/surface/stress file lid.stl type 2\n".into(),
            "fix move_lid all move/mesh mesh lid linear/variable v_vx v_zero v_vz\n".into(),
            format!("timestep {}\n", num(sch.dt)),
            format!("neighbor {} bin\n", num(lay.d_min)),
            format!("particles_in_region {}\n", lay.diameters.len()),
            format!("region column block 0 {l} 0 {w} 0 {} units box\n", num(sch.column_top)),
            "variable sn equal (f_lid[3]+9.81e0*mass(all,above)+f_shelf[3])/v_area\n".into(),
            "variable ss equal (-(f_upper[1]+f_lid[1])-f_shelf[1])/v_area\n".into(),
            format!("variable area equal ({l}-v_tr)*{w}\n"),
            format!("variable vzs equal -{}*(", num(sch.v_servo)),
            "variable err equal 5e0*(v_target-v_snow)/v_target\n".into(),
            format!("run {} pre ${{pre}} post no\n", sch.sample),
            format!("variable p loop {}\n", d.preshear_samples),
            format!("variable c loop {}\n", d.consolidate_samples),
            format!("variable vxset equal {}\n", num(sch.v_shear)),
            format!("region sp4 block {l} INF INF INF INF 1e-2 units box\n"),
            "variable target equal 1.5e3\n".into(),
            "variable target equal 3e3\n".into(),
            "variable target equal 4.5e3\n".into(),
            "if \"${ob} > 1.5e3\" then \"jump SELF finish\"\n".into(),
            "if \"${tt} > 5e-3 && ${ms} < ${lim}\" then \"jump SELF done3\"\n".into(),
            "variable lim equal 0.95*${ps}\n".into(),
            format!("variable edge equal {}*(${{nb}}+1)\n", num(0.001)),
            "if \"${tt} >= ${edge}\" then \"jump SELF bin2\"\n".into(),
            "write_restart preshear.restart\n".into(),
            "print \"RUN_END\"\n".into(),
        ] {
            assert!(s.contains(&want), "missing {want:?} in\n{s}");
        }
        assert_eq!(s.matches("read_restart preshear.restart").count(), 3);
        assert_eq!(s.matches("fix walls all wall/gran").count(), 4);
        // Every label jumped to exists once.
        for j in s.split("jump SELF ").skip(1) {
            let to = j.split(['"', '\n']).next().unwrap();
            assert_eq!(s.matches(&format!("\nlabel {to}\n")).count(), 1, "{to}");
        }
        let lid = std::fs::read_to_string(dir.path().join("lid.stl")).unwrap();
        assert_eq!(lid.matches("facet normal").count(), 2);
        assert!(
            lid.contains(&format!("vertex {l} {w} {}", num(d.top))),
            "{lid}"
        );
        let upper = std::fs::read_to_string(dir.path().join("upper.stl")).unwrap();
        assert_eq!(upper.matches("facet normal").count(), 8);
        assert!(upper.starts_with("solid upper\n") && upper.ends_with("endsolid upper\n"));
    }

    #[test]
    fn a_psd_is_poured_by_mass_as_equal_mass_templates() {
        let mut p = params();
        p.set("sigma_ln", 0.2);
        let d = cell_deck(&cell(4.0), &p, 1).unwrap();
        assert_eq!(d.classes.len(), CLASSES);
        let dir = tempfile::tempdir().unwrap();
        write_cell_deck(dir.path(), &p, &d).unwrap();
        let s = std::fs::read_to_string(dir.path().join(INPUT)).unwrap();
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
        let e = cell_deck(&cell(4.0), &p, 1).unwrap_err().to_string();
        assert!(e.contains("normal_stress"), "{e}");
        let e = cell_deck(&cell(2.0), &params(), 1).unwrap_err().to_string();
        assert!(e.contains("--box-scale"), "{e}");
        let c = ShearCell {
            class: ModelClass::parse("tsuji,mindlin").unwrap(),
            ..cell(4.0)
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
            FILL_STEPS 100 1\nINSERTED 10 0.5\nPRESHEAR_START 200\n\
            print \"SAMPLE P ${st} ${snow} ${ssnow} ${lz}\"\n\
            SAMPLE C 190 5000 0 0.1\nSAMPLE P 230 5100 4000 0.1001\n\
            Loop time of 1.5 on 1 procs for 30 steps with 10 atoms\n\
            PRESHEAR_END 230 0.01\nFAIL_START 1 300\nSAMPLE R1 290 1 1 1\n\
            SAMPLE F1 330 1500 1200 0.1002\nFAIL_START 2 400\nSAMPLE F2 430 3000 2500 0.1\n";
        let r = CellRun::parse("log", log, vec![]).unwrap();
        assert_eq!((r.fill_steps, r.fill_settled, r.inserted), (100, true, 10));
        assert_eq!((r.preshear_start, r.preshear_end, r.steps), (200, 230, 130));
        assert_eq!(r.loop_seconds, 3.5);
        assert_eq!(r.preshear.len(), 1);
        assert_eq!(r.preshear[0].shear, 4000.0);
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
        let e = CellRun::parse("log.x", &log.replace("PRESHEAR_END", "X"), vec![])
            .unwrap_err()
            .to_string();
        assert!(e.contains("PRESHEAR_END"), "{e}");
    }
}
