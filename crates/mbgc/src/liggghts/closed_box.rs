//! LIGGGHTS-PUBLIC 3.8 as the reference DEM: writes a mbgc scene (spheres in a closed box,
//! Hertz-Mindlin with EPSD2 rolling friction, same material on walls or not) as a LIGGGHTS data
//! file and input script, runs it on one core, and reads back the timing and the settled state,
//! so mbgc's own engine can be compared with it on the identical configuration for speed and
//! physics.
//!
//! Atom type 1 is the particle material, type 2 the wall material (the six `wall/gran` planes
//! use `primitive type 2`), so particle-wall restitution, friction and rolling friction are the
//! off-diagonal entries of the LIGGGHTS property matrices and the wall stiffness enters through
//! type 2's Young's modulus. The walls share the particles' Poisson ratio.

use std::fmt::Write as _;
use std::path::Path;

use super::binary::{require_binary, run_deck};
use super::number::num;
use super::parse::{parse_dump, parse_log};
use crate::{Error, Result};

/// Name of the input script written by [`write_case`].
pub const INPUT_FILE: &str = "in.mbgc";
/// Name of the data file (particles) written by [`write_case`].
pub const DATA_FILE: &str = "data.mbgc";
/// Name of the log LIGGGHTS writes when started by [`run`].
pub const LOG_FILE: &str = "log.mbgc";
/// Name of the dump of the settled state (id radius x y z, full precision).
pub const DUMP_FILE: &str = "settled.dump";

/// A closed-box scene in SI units. Walls are the six faces of `[box_lo, box_hi]`.
#[derive(Debug, Clone, PartialEq)]
pub struct LiggghtsCase {
    /// Particle centres, m; each sphere must lie inside the box.
    pub positions: Vec<[f64; 3]>,
    /// Particle radii, m, in `positions` order.
    pub radii: Vec<f64>,
    /// Particle density, kg/m^3.
    pub density: f64,
    /// Particle Young's modulus, Pa.
    pub youngs_modulus: f64,
    /// Poisson ratio of particles and walls.
    pub poisson: f64,
    /// Particle-particle coefficient of restitution.
    pub restitution: f64,
    /// Particle-particle sliding friction coefficient.
    pub friction: f64,
    /// Particle-particle rolling friction coefficient (EPSD2).
    pub rolling_friction: f64,
    /// Wall Young's modulus, Pa.
    pub wall_youngs_modulus: f64,
    /// Particle-wall coefficient of restitution.
    pub wall_restitution: f64,
    /// Particle-wall sliding friction coefficient.
    pub wall_friction: f64,
    /// Particle-wall rolling friction coefficient (EPSD2).
    pub wall_rolling_friction: f64,
    /// Particle-particle cohesion energy density, J/m^3 (`cohesion sjkr`); 0 for none.
    pub cohesion_energy_density: f64,
    /// Particle-wall cohesion energy density, J/m^3 (`cohesion sjkr` on the walls); 0 for none.
    pub wall_cohesion_energy_density: f64,
    /// Lower corner of the box, m.
    pub box_lo: [f64; 3],
    /// Upper corner of the box, m.
    pub box_hi: [f64; 3],
    /// Magnitude of gravity, m/s^2, acting in -z.
    pub gravity: f64,
    /// Time step, s.
    pub dt: f64,
    /// Neighbour-list skin, m (`neighbor <skin> bin`, `neigh_modify delay 0`).
    pub skin: f64,
    /// Steps run before the settled state is dumped.
    pub settle_steps: u64,
    /// Steps run after the dump; their "Loop time" is the timing.
    pub timed_steps: u64,
}

impl LiggghtsCase {
    /// Checks everything LIGGGHTS would reject or silently mis-handle, naming the field.
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &str, value: f64, expected: &str| {
            Err(Error::invalid(format!(
                "LiggghtsCase: {field} = {value}: expected {expected}"
            )))
        };
        let n = self.positions.len();
        if n == 0 {
            return Err(Error::invalid("LiggghtsCase: no particles"));
        }
        if self.radii.len() != n {
            return Err(Error::invalid(format!(
                "LiggghtsCase: {n} positions but {} radii: expected one radius per particle",
                self.radii.len()
            )));
        }
        let positive = [
            ("density", self.density),
            ("youngs_modulus", self.youngs_modulus),
            ("wall_youngs_modulus", self.wall_youngs_modulus),
            ("dt", self.dt),
            ("skin", self.skin),
        ];
        for (field, v) in positive {
            if !(v > 0.0 && v.is_finite()) {
                return bad(field, v, "a positive finite number");
            }
        }
        if !(0.0..=0.5).contains(&self.poisson) {
            return bad("poisson", self.poisson, "a value in [0, 0.5]");
        }
        // LIGGGHTS refuses restitution outside (0.05, 1] (its damping formula needs ln e).
        for (field, e) in [
            ("restitution", self.restitution),
            ("wall_restitution", self.wall_restitution),
        ] {
            if !(e > 0.05 && e <= 1.0) {
                return bad(field, e, "a value in (0.05, 1]");
            }
        }
        for (field, v) in [
            ("friction", self.friction),
            ("rolling_friction", self.rolling_friction),
            ("wall_friction", self.wall_friction),
            ("wall_rolling_friction", self.wall_rolling_friction),
            ("cohesion_energy_density", self.cohesion_energy_density),
            (
                "wall_cohesion_energy_density",
                self.wall_cohesion_energy_density,
            ),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return bad(field, v, "a finite number >= 0");
            }
        }
        if !(self.gravity >= 0.0 && self.gravity.is_finite()) {
            return bad(
                "gravity",
                self.gravity,
                "a finite magnitude >= 0 (acts in -z)",
            );
        }
        if self.timed_steps == 0 {
            return Err(Error::invalid(
                "LiggghtsCase: timed_steps = 0: expected at least 1 timed step",
            ));
        }
        for k in 0..3 {
            let (lo, hi) = (self.box_lo[k], self.box_hi[k]);
            if !(lo.is_finite() && hi.is_finite() && hi > lo) {
                return Err(Error::invalid(format!(
                    "LiggghtsCase: box axis {k}: [{lo}, {hi}]: expected finite bounds with lo < hi"
                )));
            }
        }
        for (i, (p, &r)) in self.positions.iter().zip(&self.radii).enumerate() {
            if !(r > 0.0 && r.is_finite()) {
                return bad(&format!("radii[{i}]"), r, "a positive finite radius");
            }
            // A wall may be overlapped a little (a state settled by another code), not crossed.
            for k in 0..3 {
                if !(p[k] - 0.5 * r >= self.box_lo[k] && p[k] + 0.5 * r <= self.box_hi[k]) {
                    return Err(Error::invalid(format!(
                        "LiggghtsCase: particle {i} at {p:?} with radius {r}: expected it inside \
                         the box {:?}..{:?} (overlapping a wall by at most half its radius)",
                        self.box_lo, self.box_hi
                    )));
                }
            }
        }
        Ok(())
    }
}

/// Timing and settled state of one LIGGGHTS run.
#[derive(Debug, Clone, PartialEq)]
pub struct LiggghtsResult {
    /// "Loop time" of the timed run, s (wall clock, excludes setup and the dump).
    pub timed_wall_s: f64,
    /// particles x timed steps / timed_wall_s.
    pub particle_steps_per_s: f64,
    /// Positions after `settle_steps`, in the order of `LiggghtsCase::positions`.
    pub settled_positions: Vec<[f64; 3]>,
    /// Radii read back from the dump, m, in the same order (a check that the order matches).
    pub settled_radii: Vec<f64>,
    /// From the log's first line, e.g. "LIGGGHTS-PUBLIC 3.8.0, compiled ... ".
    pub version: String,
    /// Distinct warnings of the log (first line of each message), e.g. a contact model missing
    /// from the build's whitelist, which makes LIGGGHTS run a slower generic code path.
    pub warnings: Vec<String>,
}

/// The LIGGGHTS data file (atom_style granular: id type diameter density x y z). The simulation
/// domain is the wall box widened by the largest radius, so a particle pressed into a wall is
/// never outside the domain (LIGGGHTS would drop it as lost).
pub fn data_file(case: &LiggghtsCase) -> String {
    let r_max = case.radii.iter().copied().fold(0.0, f64::max);
    let mut s = String::new();
    let _ = writeln!(s, "LIGGGHTS data file written by mbgc\n");
    let _ = writeln!(s, "{} atoms", case.positions.len());
    let _ = writeln!(s, "2 atom types\n");
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let _ = writeln!(
            s,
            "{} {} {axis}lo {axis}hi",
            num(case.box_lo[k] - r_max),
            num(case.box_hi[k] + r_max)
        );
    }
    let _ = writeln!(s, "\nAtoms\n");
    for (i, (p, r)) in case.positions.iter().zip(&case.radii).enumerate() {
        let _ = writeln!(
            s,
            "{} 1 {} {} {} {} {}",
            i + 1,
            num(2.0 * r),
            num(case.density),
            num(p[0]),
            num(p[1]),
            num(p[2])
        );
    }
    s
}

/// The contact model keywords of `pair_style gran` or `fix wall/gran`, with `cohesion sjkr` only
/// when that contact is cohesive, so that decks without cohesion stay as they were.
fn model_keywords(cohesive: bool) -> &'static str {
    if cohesive {
        "model hertz tangential history cohesion sjkr rolling_friction epsd2"
    } else {
        "model hertz tangential history rolling_friction epsd2"
    }
}

/// The LIGGGHTS input script: settle, dump the settled state, then the timed run.
pub fn input_script(case: &LiggghtsCase) -> String {
    format!(
        "{}\nrun             {}",
        settle_script(case),
        case.timed_steps
    )
}

/// The input script up to the timed run: the setup, the settling run and the dump of the
/// settled state.
pub fn settle_script(case: &LiggghtsCase) -> String {
    let pair_model = model_keywords(case.cohesion_energy_density > 0.0);
    let wall_model = model_keywords(case.wall_cohesion_energy_density > 0.0);
    let (lo, hi) = (case.box_lo, case.box_hi);
    // 2x2 matrices over (particle, wall); the wall-wall entry is never used.
    let pair = |pp: f64, pw: f64| format!("2 {} {} {} {}", num(pp), num(pw), num(pw), num(pw));
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# mbgc reference case (mbgc::liggghts::closed_box). Type 1: particles, type 2: walls.\n\
         units           si\n\
         atom_style      granular\n\
         atom_modify     map array\n\
         boundary        f f f\n\
         newton          off\n\
         communicate     single vel yes\n\
         read_data       {DATA_FILE}\n\
         neighbor        {skin} bin\n\
         neigh_modify    delay 0\n\
         \n\
         fix m1 all property/global youngsModulus peratomtype {e} {ew}\n\
         fix m2 all property/global poissonsRatio peratomtype {nu} {nu}\n\
         fix m3 all property/global coefficientRestitution peratomtypepair {rest}\n\
         fix m4 all property/global coefficientFriction peratomtypepair {fric}\n\
         fix m5 all property/global coefficientRollingFriction peratomtypepair {roll}\n\
         {cohesion}\
         \n\
         pair_style      gran {pair_model}\n\
         pair_coeff      * *\n\
         timestep        {dt}\n\
         fix gravity all gravity {g} vector 0.0 0.0 -1.0",
        skin = num(case.skin),
        e = num(case.youngs_modulus),
        ew = num(case.wall_youngs_modulus),
        nu = num(case.poisson),
        rest = pair(case.restitution, case.wall_restitution),
        fric = pair(case.friction, case.wall_friction),
        roll = pair(case.rolling_friction, case.wall_rolling_friction),
        // The wall-wall entry of the matrix must be given but is never used.
        cohesion = if case.cohesion_energy_density > 0.0 || case.wall_cohesion_energy_density > 0.0
        {
            format!(
                "fix m6 all property/global cohesionEnergyDensity peratomtypepair {}\n",
                pair(
                    case.cohesion_energy_density,
                    case.wall_cohesion_energy_density
                )
            )
        } else {
            String::new()
        },
        dt = num(case.dt),
        g = num(case.gravity),
    );
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        for (side, v) in [("lo", lo[k]), ("hi", hi[k])] {
            let _ = writeln!(
                s,
                "fix wall_{axis}{side} all wall/gran {wall_model} primitive type 2 {axis}plane {}",
                num(v)
            );
        }
    }
    let _ = writeln!(
        s,
        "fix integrate all nve/sphere\n\
         compute rke all erotate/sphere\n\
         thermo_style    custom step atoms ke c_rke\n\
         thermo_modify   norm no lost error\n\
         thermo          1000\n\
         \n\
         run             {settle}\n\
         write_dump      all custom {DUMP_FILE} id radius x y z modify format \
         \"%d %.17g %.17g %.17g %.17g\"",
        settle = case.settle_steps,
    );
    s
}

/// Writes `data.mbgc` and `in.mbgc` into `dir` (created if missing).
pub fn write_case(dir: &Path, case: &LiggghtsCase) -> Result<()> {
    case.validate()?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    crate::error::write_atomic(&dir.join(DATA_FILE), data_file(case).as_bytes())?;
    crate::error::write_atomic(&dir.join(INPUT_FILE), input_script(case).as_bytes())
}

/// Writes the case into `dir` and removes the log and dump of an earlier run, which must not be
/// read as this run's: their paths.
fn prepare(dir: &Path, case: &LiggghtsCase) -> Result<(std::path::PathBuf, std::path::PathBuf)> {
    write_case(dir, case)?;
    let (log, dump) = (dir.join(LOG_FILE), dir.join(DUMP_FILE));
    for stale in [&log, &dump] {
        if stale.exists() {
            std::fs::remove_file(stale).map_err(|e| Error::io(stale, e))?;
        }
    }
    Ok((log, dump))
}

/// Writes the case into `dir`, runs LIGGGHTS from [`super::find_binary`] there and reads the
/// results.
pub fn run(dir: &Path, case: &LiggghtsCase) -> Result<LiggghtsResult> {
    run_with_binary(&require_binary()?, dir, case)
}

/// As [`run`], with an explicit LIGGGHTS executable.
pub fn run_with_binary(binary: &Path, dir: &Path, case: &LiggghtsCase) -> Result<LiggghtsResult> {
    let (log, dump) = prepare(dir, case)?;
    run_deck(binary, dir, INPUT_FILE, LOG_FILE)?;
    let log_text = crate::error::read_to_string(&log)?;
    let n = case.positions.len();
    let parsed = parse_log(&log.display().to_string(), &log_text, n, case.timed_steps)?;
    let (settled_positions, settled_radii) = parse_dump(
        &dump.display().to_string(),
        &crate::error::read_to_string(&dump)?,
        n,
    )?;
    Ok(LiggghtsResult {
        timed_wall_s: parsed.loop_time_s,
        particle_steps_per_s: n as f64 * case.timed_steps as f64 / parsed.loop_time_s,
        settled_positions,
        settled_radii,
        version: parsed.version,
        warnings: parsed.warnings,
    })
}

/// What [`run_interleaved`] measured.
#[derive(Debug, Clone)]
pub struct Interleaved {
    /// The run's result; its rate is the median of the segments' rates.
    pub result: LiggghtsResult,
    /// Loop time of each timed segment, s, in order.
    pub segment_s: Vec<f64>,
    /// Each segment's particle-steps per second, in order.
    pub segment_rates: Vec<f64>,
}

/// As [`run`], but LIGGGHTS runs its timed steps as `segments` runs of `timed_steps / segments`
/// steps, and `between(k)` runs after its k-th segment while LIGGGHTS waits: the caller's timed
/// work alternates with LIGGGHTS', so that a slow spell of the machine hits both alike.
pub fn run_interleaved(
    dir: &Path,
    case: &LiggghtsCase,
    segments: u64,
    mut between: impl FnMut(usize) -> Result<()>,
) -> Result<Interleaved> {
    let binary = require_binary()?;
    let seg_steps = case.timed_steps / segments.max(1);
    if segments == 0 || seg_steps == 0 {
        return Err(Error::invalid(format!(
            "LiggghtsCase: {} timed steps in {segments} segments: expected at least one step \
             per segment",
            case.timed_steps
        )));
    }
    let (log, dump) = prepare(dir, case)?;
    let mut s = super::session::Session::start(&binary, dir, LOG_FILE)?;
    s.command(&settle_script(case))?;
    let n = case.positions.len();
    let mut segment_s = Vec::new();
    for k in 0..segments as usize {
        let out = s.command(&format!("run {seg_steps}"))?;
        segment_s.push(super::session::loop_time(&out, seg_steps, n)?);
        between(k)?;
    }
    s.finish()?;
    let log_text = crate::error::read_to_string(&log)?;
    let parsed = parse_log(&log.display().to_string(), &log_text, n, seg_steps)?;
    let (settled_positions, settled_radii) = parse_dump(
        &dump.display().to_string(),
        &crate::error::read_to_string(&dump)?,
        n,
    )?;
    let segment_rates: Vec<f64> = segment_s
        .iter()
        .map(|t| n as f64 * seg_steps as f64 / t)
        .collect();
    let mut rates = segment_rates.clone();
    rates.sort_by(f64::total_cmp);
    Ok(Interleaved {
        result: LiggghtsResult {
            timed_wall_s: segment_s.iter().sum(),
            particle_steps_per_s: rates[rates.len() / 2],
            settled_positions,
            settled_radii,
            version: parsed.version,
            warnings: parsed.warnings,
        },
        segment_s,
        segment_rates,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 50 spheres on a loose cubic lattice in a 0.12 x 0.12 x 0.36 m box, the benchmark's
    /// material, 40000 settle + 20000 timed steps.
    fn small_case() -> LiggghtsCase {
        let (mut positions, mut radii) = (Vec::new(), Vec::new());
        for i in 0..50 {
            let (ix, iy, iz) = (i % 5, (i / 5) % 5, i / 25);
            positions.push([
                0.012 + 0.02 * ix as f64,
                0.012 + 0.02 * iy as f64,
                0.012 + 0.02 * iz as f64,
            ]);
            radii.push(0.004 + 0.00002 * i as f64);
        }
        LiggghtsCase {
            positions,
            radii,
            density: 2600.0,
            youngs_modulus: 5e7,
            poisson: 0.3,
            restitution: 0.5,
            friction: 0.5,
            rolling_friction: 0.3,
            wall_youngs_modulus: 5e7,
            wall_restitution: 0.5,
            wall_friction: 0.5,
            wall_rolling_friction: 0.3,
            cohesion_energy_density: 0.0,
            wall_cohesion_energy_density: 0.0,
            box_lo: [0.0; 3],
            box_hi: [0.12, 0.12, 0.36],
            gravity: 9.81,
            dt: 2e-5,
            skin: 2e-3,
            settle_steps: 40_000,
            timed_steps: 20_000,
        }
    }

    #[test]
    fn case_files_hold_every_particle_and_the_model() {
        let case = small_case();
        let dir = tempfile::tempdir().unwrap();
        write_case(dir.path(), &case).unwrap();
        let data = std::fs::read_to_string(dir.path().join(DATA_FILE)).unwrap();
        assert!(data.contains("50 atoms\n2 atom types\n"));
        let atoms: Vec<&str> = data.lines().skip_while(|l| *l != "Atoms").skip(2).collect();
        assert_eq!(atoms.len(), 50);
        let first: Vec<f64> = atoms[0].split(' ').map(|w| w.parse().unwrap()).collect();
        assert_eq!(first[0], 1.0);
        assert_eq!(first[2], 2.0 * case.radii[0]);
        assert_eq!(&first[4..], &case.positions[0]);
        let script = std::fs::read_to_string(dir.path().join(INPUT_FILE)).unwrap();
        assert_eq!(
            script
                .matches("wall/gran model hertz tangential history rolling_friction epsd2")
                .count(),
            6
        );
        assert!(script.contains("coefficientRestitution peratomtypepair 2 5e-1 5e-1 5e-1 5e-1"));
        assert!(script.contains("run             40000\nwrite_dump"));
        assert!(script.trim_end().ends_with("run             20000"));
    }

    #[test]
    fn cohesion_is_written_only_when_asked_for() {
        let plain = input_script(&small_case());
        assert!(!plain.contains("cohesion"));
        assert!(plain.contains("peratomtypepair 2 3e-1 3e-1 3e-1 3e-1\n\npair_style"));
        let mut case = small_case();
        case.cohesion_energy_density = 3e5;
        let script = input_script(&case);
        assert!(script.contains(
            "fix m6 all property/global cohesionEnergyDensity peratomtypepair 2 3e5 0e0 0e0 0e0\n\n\
             pair_style      gran model hertz tangential history cohesion sjkr rolling_friction \
             epsd2\n"
        ));
        assert_eq!(
            script.matches("cohesion sjkr").count(),
            1,
            "walls not cohesive"
        );
        case.wall_cohesion_energy_density = 1e5;
        let script = input_script(&case);
        assert!(script.contains("cohesionEnergyDensity peratomtypepair 2 3e5 1e5 1e5 1e5\n"));
        assert_eq!(script.matches("cohesion sjkr").count(), 7);
        case.wall_cohesion_energy_density = -1.0;
        let msg = case.validate().unwrap_err().to_string();
        assert!(msg.contains("wall_cohesion_energy_density"), "{msg}");
    }

    #[test]
    fn bad_cases_are_refused_with_the_field() {
        let mut case = small_case();
        case.restitution = 0.01;
        let msg = case.validate().unwrap_err().to_string();
        assert!(msg.contains("restitution"), "{msg}");
        let mut case = small_case();
        case.radii.pop();
        assert!(case.validate().unwrap_err().to_string().contains("radii"));
        let mut case = small_case();
        case.positions[3][2] = 0.5;
        assert!(case
            .validate()
            .unwrap_err()
            .to_string()
            .contains("particle 3"));
        let mut case = small_case();
        case.timed_steps = 0;
        assert!(case.validate().is_err());
    }

    #[test]
    fn missing_or_failing_binary_is_a_clear_error() {
        let dir = tempfile::tempdir().unwrap();
        let case = small_case();
        let missing = dir.path().join("no-such-liggghts");
        let e = run_with_binary(&missing, dir.path(), &case)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no-such-liggghts"), "{e}");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let fake = dir.path().join("fake-liggghts");
            std::fs::write(
                &fake,
                "#!/bin/sh\necho 'LIGGGHTS (Version fake)' > log.mbgc\necho 'ERROR: boom' >> log.mbgc\nexit 3\n",
            )
            .unwrap();
            std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
            let e = run_with_binary(&fake, dir.path(), &case)
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("ERROR: boom") && e.contains("exit status: 3"),
                "{e}"
            );
            // Exit 0 without a timed run: the log lacks the expected line.
            std::fs::write(
                &fake,
                "#!/bin/sh\necho 'LIGGGHTS (Version fake)' > log.mbgc\n",
            )
            .unwrap();
            let e = run_with_binary(&fake, dir.path(), &case)
                .unwrap_err()
                .to_string();
            assert!(e.contains("log.mbgc: Loop time"), "{e}");
        }
    }
}
