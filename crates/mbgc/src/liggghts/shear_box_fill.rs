//! The shear box (seed 004) as an independent LIGGGHTS 3.8 deck that fills itself: LIGGGHTS
//! creates the particles with its own insertion (`insert/pack` into the column mbgc pours from,
//! the PSD as `n` particle templates of equal mass combined by
//! `particledistribution/discrete`), so that a difference in how the box is filled shows up,
//! which the replay of [`super::shear_box`] cannot see. Everything else follows mbgc's procedure
//! and stop rules: the same box, walls, contact law, time step and total solid mass; fill until
//! the translational rms speed falls below the same threshold (after the free-fall time); strike
//! off every particle whose centre lies above the rim; relax one chunk; remove the flap; remove
//! what fell below the floor every chunk; stop after five quiet chunks once the minimum outflow
//! time has passed.
//!
//! LIGGGHTS 3.8 wants its random seeds prime and above 10 000, hence [`prime_seed`].

use std::fmt::Write as _;
use std::path::Path;

use super::number::num;
use super::shear_box::{
    gran_model, write_box_physics, write_box_walls, write_cohesion, write_contact_properties,
    GranModel,
};
use crate::error::{write_atomic, Error, Result};
use crate::experiments::shear_box::{psd_classes, ShearBox};
use crate::experiments::ParamSet;
use crate::psd::{default_range, Distribution, LogNormal};
use mbgc_dem::contact::ModelClass;
use mbgc_dem::vec3::V3;

const G: f64 = 9.81;

/// Particle templates of equal mass standing for the continuous PSD: the number the comparison
/// with mbgc's engine was made with (`docs/shear_box.md`), and the backend's.
pub const CLASSES: usize = 5;

/// Name of the input script written by [`write_fill_deck`].
pub const INPUT: &str = "in.shear_box_fill";
/// Name of the log LIGGGHTS writes for it.
pub const LOG: &str = "log.shear_box_fill";
/// Dumps: just after insertion, at the end of the fill, after strike-off and relaxation, final.
pub const INSERTED_DUMP: &str = "inserted.dump";
/// Dump at the end of the fill, before the strike-off.
pub const PRE_STRIKE_DUMP: &str = "prestrike.dump";
/// Dump after strike-off and relaxation: the bed whose bulk density is measured.
pub const FILLED_DUMP: &str = "filled.dump";
/// Dump at the end of the outflow: the flank whose angle is measured.
pub const FINAL_DUMP: &str = "final.dump";

/// What the deck needs, in SI units; the study derives it from mbgc's layout so that both codes
/// run the same procedure.
#[derive(Debug, Clone)]
pub struct FillDeck {
    /// The contact law, written effect by effect in LIGGGHTS' words.
    pub class: ModelClass,
    /// l, w, h of the box.
    pub size: V3,
    /// (diameter, mass fraction) of each particle template.
    pub classes: Vec<(f64, f64)>,
    /// Total particle mass inserted (kg).
    pub mass: f64,
    /// Insertion column: z range over the box's base.
    pub column: (f64, f64),
    /// Lower and upper corners of the simulation domain, m; particles leaving it are lost.
    pub domain: (V3, V3),
    /// Time step, s (the same fraction of the Rayleigh time as mbgc's run).
    pub dt: f64,
    /// Neighbour-list skin, m.
    pub skin: f64,
    /// Steps between rest checks and removals of fallen particles.
    pub chunk: u64,
    /// Fill ends at rest (rms speed below `v_rest`) after `fall_steps`, or at `max_fill_steps`.
    pub v_rest: f64,
    /// Steps before rest may be declared: the free fall of the inserted column.
    pub fall_steps: u64,
    /// Step limit of the fill; reaching it ends the fill unsettled.
    pub max_fill_steps: u64,
    /// Outflow: a particle in the box moving faster than this in x-z counts as motion.
    pub v_move: f64,
    /// Least and most steps with the flap open.
    pub min_flow_steps: u64,
    /// Step limit of the outflow.
    pub max_flow_steps: u64,
    /// Particles below this height have left over the floor's edge and are deleted, m.
    pub removal_height: f64,
    /// Any number; made prime for LIGGGHTS.
    pub seed: u64,
    /// The largest diameter of mbgc's layout: the box is k of them, and the flank is measured
    /// in columns this wide.
    pub d_max: f64,
}

/// A prime LIGGGHTS accepts for `seed`: above 10 000 and below its `INT_MAX`. Seeds below
/// 250 000 map to the smallest prime above 10 000 + 7919 `seed` (distinct primes for distinct
/// seeds); larger ones (campaign row seeds are 64-bit) are hashed into [10 000, 2e9) first.
pub fn prime_seed(seed: u64) -> u64 {
    let is_prime = |n: u64| {
        n > 1
            && (2..)
                .take_while(|d| d * d <= n)
                .all(|d| !n.is_multiple_of(d))
    };
    let start = if seed < 250_000 {
        10_001 + 7919 * seed
    } else {
        10_001 + crate::numeric::splitmix64(seed) % 1_999_000_000
    };
    (start..).find(|&n| is_prime(n)).unwrap_or(10_007)
}

/// The seed of the deck's `k`-th random stream (0: insertion, 1: the distribution, 2 + j:
/// template j) for run seed `seed`; k = 0 is `prime_seed(seed)`.
fn stream_seed(seed: u64, k: u64) -> u64 {
    if k == 0 {
        prime_seed(seed)
    } else {
        prime_seed(seed.wrapping_mul(31).wrapping_add(k))
    }
}

/// Writes the wall meshes and the input script into `dir`.
pub fn write_fill_deck(dir: &Path, p: &ParamSet, d: &FillDeck) -> Result<()> {
    let get = |k: &str| {
        p.get(k)
            .ok_or_else(|| Error::invalid(format!("parameter {k}: missing")))
    };
    if d.classes.is_empty() {
        return Err(Error::invalid("shear box fill deck: no particle classes"));
    }
    let GranModel { models, settings } = gran_model(&d.class)?;
    let [l, w, h] = d.size;
    let (lo, hi) = d.domain;
    let wall_h = hi[2] - 1e-9;
    write_box_walls(dir, l, w, wall_h)?;
    let rho = get("rho_p")?;
    let mut s = String::from(
        "# mbgc shear box, filled by LIGGGHTS itself. Type 1: particles, type 2: walls.\n",
    );
    let _ = writeln!(s, "units si\natom_style granular\natom_modify map array\nboundary f f f\nnewton off\ncommunicate single vel yes");
    // Under MPI the domain is cut into equal slabs. The box and the poured column sit in the
    // middle of the domain in y but fill only a part of it in x (room for the outflow) and z
    // (the fall), so only cuts in y give every process a share of the particles.
    let _ = writeln!(s, "processors 1 * 1");
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
    let _ = writeln!(s, "neighbor {} bin\nneigh_modify delay 0\n", num(d.skin));
    write_contact_properties(&mut s, p)?;
    write_cohesion(&mut s, p, &d.class)?;
    s.push('\n');
    write_box_physics(&mut s, &models, &settings, d.dt, l);
    // Each template and the distribution need their own prime seed.
    let mut dist = format!(
        "fix pdd all particledistribution/discrete {} {}",
        stream_seed(d.seed, 1),
        d.classes.len()
    );
    for (k, (diam, frac)) in d.classes.iter().enumerate() {
        let _ = writeln!(
            s,
            "fix pts{k} all particletemplate/sphere {} atom_type 1 density constant {} radius constant {}",
            stream_seed(d.seed, 2 + k as u64),
            num(rho),
            num(0.5 * diam)
        );
        let _ = write!(dist, " pts{k} {}", num(*frac));
    }
    let _ = writeln!(s, "{dist}");
    let _ = writeln!(
        s,
        "region column block 0 {} 0 {} {} {} units box",
        num(l),
        num(w),
        num(d.column.0),
        num(d.column.1)
    );
    let _ = writeln!(
        s,
        "fix ins all insert/pack seed {} distributiontemplate pdd maxattempt 20000 insert_every once \
         overlapcheck yes all_in yes vel constant 0. 0. 0. region column mass_in_region {}",
        stream_seed(d.seed, 0),
        num(d.mass)
    );
    let _ = writeln!(s, "fix integrate all nve/sphere");
    let dump = |name: &str| {
        format!("write_dump all custom {name} id radius x y z modify format \"%d %.17g %.17g %.17g %.17g\"\n")
    };
    // The rest checks read c_ke between runs; thermo at the end of each run keeps it current.
    let _ = writeln!(
        s,
        "compute ke all ke\nvariable vrms equal sqrt(2*c_ke/mass(all))\nvariable st equal step\n\
         variable na equal atoms\nthermo_style custom step atoms c_ke\nthermo {}\n\
         thermo_modify lost ignore norm no\n",
        d.chunk
    );
    let _ = writeln!(s, "run 1");
    s.push_str(&dump(INSERTED_DUMP));
    let _ = writeln!(
        s,
        "label fill\nrun {}\nif \"(${{vrms}} < {} && ${{st}} > {}) || ${{st}} >= {}\" then \"jump SELF filled\"\njump SELF fill\nlabel filled",
        d.chunk,
        num(d.v_rest),
        d.fall_steps,
        d.max_fill_steps
    );
    let _ = writeln!(s, "print \"FILL_STEPS ${{st}}\"");
    s.push_str(&dump(PRE_STRIKE_DUMP));
    let _ = writeln!(
        s,
        "region above block INF INF INF INF {} INF units box\ndelete_atoms region above compress no",
        num(h)
    );
    let _ = writeln!(s, "run {}", d.chunk);
    s.push_str(&dump(FILLED_DUMP));
    let _ = writeln!(s, "unfix flapwall");
    let _ = writeln!(
        s,
        "region below block INF INF INF INF INF {} units box",
        num(d.removal_height)
    );
    let _ = writeln!(
        s,
        "variable vxz atom sqrt(vx*vx+vz*vz)*(x<={})\ncompute vmax all reduce max v_vxz\n\
         thermo_style custom step atoms c_ke c_vmax\n\
         thermo_modify lost ignore norm no\nvariable vm equal c_vmax\nvariable q equal 0\n\
         variable open equal ${{st}}\n\
         variable tmin equal ${{open}}+{}\nvariable tmax equal ${{open}}+{}",
        num(l),
        d.min_flow_steps,
        d.max_flow_steps
    );
    let _ = writeln!(
        s,
        "label flow\nrun {}\nvariable n0 equal ${{na}}\ndelete_atoms region below compress no\n\
         variable n1 equal ${{na}}\n\
         variable qq equal (${{n1}}==${{n0}})*(${{vm}}<{})*(${{vrms}}<{})*(${{q}}+1)\n\
         variable q equal ${{qq}}\n\
         if \"(${{q}} >= 5 && ${{st}} > ${{tmin}}) || ${{st}} >= ${{tmax}}\" then \"jump SELF done\"\n\
         jump SELF flow\nlabel done",
        d.chunk,
        num(d.v_move),
        num(d.v_rest),
    );
    let _ = writeln!(s, "print \"FLOW_END ${{st}} ${{q}}\"");
    s.push_str(&dump(FINAL_DUMP));
    // After the last dump is complete: a run killed while writing it is not taken as finished.
    let _ = writeln!(s, "print \"RUN_END\"");
    write_atomic(&dir.join(INPUT), s.as_bytes())
}

/// The LIGGGHTS deck of the same procedure as `sb` runs it for `p` and `seed`, with the PSD as
/// `classes` templates of equal mass; `column` overrides the insertion column's z range.
pub fn fill_deck(
    sb: &ShearBox,
    p: &ParamSet,
    seed: u64,
    classes: usize,
    column: Option<(f64, f64)>,
) -> Result<FillDeck> {
    let lay = sb.layout(p, seed)?;
    let get = |k: &str| {
        p.get(k)
            .ok_or_else(|| Error::invalid(format!("parameter {k}: missing")))
    };
    let rho = get("rho_p")?;
    let d50 = get("d50")?;
    let sigma = p.get("sigma_ln").unwrap_or(0.0);
    let reps: Vec<(f64, f64)> = if sigma < 1e-6 || classes == 0 {
        vec![(d50 * 1e-3, 1.0)]
    } else {
        let dist = Distribution::LogNormal(LogNormal::new(d50, sigma)?);
        psd_classes(&dist, default_range(&dist), classes)
            .into_iter()
            .map(|d| (d * 1e-3, 1.0 / classes as f64))
            .collect()
    };
    // Everything but the particle creation is the run's own schedule.
    let sc = sb.schedule(&lay, rho, get("E_p")?, get("nu_p")?);
    let column = column.unwrap_or((0.0, sc.column_top));
    // A column placed elsewhere than mbgc's needs the walls, domain and fall time to follow it.
    let col_top = sc.column_top.max(column.1);
    let fall = (2.0 * col_top / G).sqrt();
    let (mut domain, dt) = (sc.domain, sc.dt);
    domain.1[2] += col_top - sc.column_top;
    let mass: f64 = lay
        .diameters
        .iter()
        .map(|d| rho * std::f64::consts::PI / 6.0 * d.powi(3))
        .sum();
    Ok(FillDeck {
        class: sb.class,
        size: lay.size,
        classes: reps,
        mass,
        column,
        domain,
        dt,
        skin: sc.skin,
        chunk: sc.chunk,
        v_rest: sc.v_rest,
        fall_steps: (fall / dt) as u64,
        max_fill_steps: sc.max_fill_steps + ((fall - sc.fall) / dt) as u64,
        v_move: sc.v_move,
        min_flow_steps: (sc.min_flow_time / dt) as u64,
        max_flow_steps: sc.max_flow_steps,
        removal_height: sc.removal_height,
        seed,
        d_max: lay.d_max,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_are_distinct_primes_above_ten_thousand() {
        let big = [u64::MAX, 1 << 63, 8_780_794_297_754_785_331, 250_000];
        let s: Vec<u64> = (0..20)
            .map(prime_seed)
            .chain(big.iter().map(|&b| prime_seed(b)))
            .chain((0..5).map(|k| stream_seed(12_345_678_901_234, k)))
            .collect();
        assert!(s.iter().all(|&p| p < i32::MAX as u64), "{s:?}");
        for (i, a) in s.iter().enumerate() {
            assert!(
                *a > 10_000
                    && (2..*a)
                        .take_while(|d| d * d <= *a)
                        .all(|d| !a.is_multiple_of(d))
            );
            assert!(!s[..i].contains(a));
        }
    }
}
