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
use std::path::{Path, PathBuf};
use std::process::Command;

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
    pub positions: Vec<[f64; 3]>,
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
    pub box_lo: [f64; 3],
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
    /// The project's DEM benchmark scene ([`crate::dem::bench::BenchSpec`]'s defaults) with the
    /// given particles, 40000 + 20000 steps.
    pub fn benchmark(positions: Vec<[f64; 3]>, radii: Vec<f64>) -> Self {
        crate::dem::bench::liggghts_case(
            &crate::dem::bench::BenchSpec::default(),
            positions,
            radii,
            40_000,
            20_000,
        )
    }

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

/// The benchmark box, m (lower corner at the origin).
pub const BENCHMARK_BOX: [f64; 3] = [0.12, 0.12, 0.36];

/// Timing and settled state of one LIGGGHTS run.
#[derive(Debug, Clone, PartialEq)]
pub struct LiggghtsResult {
    /// "Loop time" of the timed run, s (wall clock, excludes setup and the dump).
    pub timed_wall_s: f64,
    /// particles x timed steps / timed_wall_s.
    pub particle_steps_per_s: f64,
    /// Positions after `settle_steps`, in the order of `LiggghtsCase::positions`.
    pub settled_positions: Vec<[f64; 3]>,
    pub settled_radii: Vec<f64>,
    /// From the log's first line, e.g. "LIGGGHTS-PUBLIC 3.8.0, compiled ... ".
    pub version: String,
    /// Distinct warnings of the log (first line of each message), e.g. a contact model missing
    /// from the build's whitelist, which makes LIGGGHTS run a slower generic code path.
    pub warnings: Vec<String>,
}

/// Names LIGGGHTS is installed under: Debian's package, and the default of a source build.
const BINARY_NAMES: [&str; 2] = ["liggghts", "lmp_auto"];

/// The LIGGGHTS executable on `PATH`, or None when LIGGGHTS is not installed.
pub fn find_binary() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|dir| BINARY_NAMES.iter().map(move |name| dir.join(name)))
        .find(|p| is_executable(p))
}

fn is_executable(p: &Path) -> bool {
    let Ok(meta) = std::fs::metadata(p) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        meta.is_file() && meta.permissions().mode() & 0o111 != 0
    }
    #[cfg(not(unix))]
    {
        meta.is_file()
    }
}

/// Shortest round-trip form in exponent notation, which LIGGGHTS's number parser accepts.
fn num(v: f64) -> String {
    format!("{v:e}")
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

/// The LIGGGHTS input script: settle, dump the settled state, then the timed run.
pub fn input_script(case: &LiggghtsCase) -> String {
    const MODEL: &str = "model hertz tangential history rolling_friction epsd2";
    let (lo, hi) = (case.box_lo, case.box_hi);
    // 2x2 matrices over (particle, wall); the wall-wall entry is never used.
    let pair = |pp: f64, pw: f64| format!("2 {} {} {} {}", num(pp), num(pw), num(pw), num(pw));
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# mbgc reference case (mbgc::dem::liggghts). Type 1: particles, type 2: walls.\n\
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
         \n\
         pair_style      gran {MODEL}\n\
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
        dt = num(case.dt),
        g = num(case.gravity),
    );
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        for (side, v) in [("lo", lo[k]), ("hi", hi[k])] {
            let _ = writeln!(
                s,
                "fix wall_{axis}{side} all wall/gran {MODEL} primitive type 2 {axis}plane {}",
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
         \"%d %.17g %.17g %.17g %.17g\"\n\
         run             {timed}",
        settle = case.settle_steps,
        timed = case.timed_steps,
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

/// Writes the case into `dir`, runs LIGGGHTS from [`find_binary`] there and reads the results.
pub fn run(dir: &Path, case: &LiggghtsCase) -> Result<LiggghtsResult> {
    let binary = find_binary().ok_or_else(|| {
        Error::invalid(format!(
            "LIGGGHTS not found: expected one of {BINARY_NAMES:?} on PATH \
             (Debian: apt-get install liggghts)"
        ))
    })?;
    run_with_binary(&binary, dir, case)
}

/// As [`run`], with an explicit LIGGGHTS executable.
pub fn run_with_binary(binary: &Path, dir: &Path, case: &LiggghtsCase) -> Result<LiggghtsResult> {
    write_case(dir, case)?;
    let log = dir.join(LOG_FILE);
    let dump = dir.join(DUMP_FILE);
    // A stale log or dump from an earlier run must not be read as this run's.
    for stale in [&log, &dump] {
        if stale.exists() {
            std::fs::remove_file(stale).map_err(|e| Error::io(stale, e))?;
        }
    }
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

/// Runs LIGGGHTS on the input script `input` in `dir` (one process, one thread), writing the log
/// to `log`; an error quotes the log's ERROR line.
pub fn run_deck(binary: &Path, dir: &Path, input: &str, log: &str) -> Result<()> {
    // `-screen none` makes LIGGGHTS 3.8 crash in some fixes, so the screen goes to /dev/null and
    // everything is read from the log.
    let out = Command::new(binary)
        .args(["-in", input, "-log", log, "-screen", "/dev/null"])
        .current_dir(dir)
        .env("OMP_NUM_THREADS", "1")
        .output()
        .map_err(|e| {
            Error::invalid(format!("cannot start LIGGGHTS ({}): {e}", binary.display()))
        })?;
    if out.status.success() {
        return Ok(());
    }
    let log_path = dir.join(log);
    let log_text = std::fs::read_to_string(&log_path).unwrap_or_default();
    let error_line = log_text
        .lines()
        .find(|l| l.starts_with("ERROR"))
        .map(str::to_owned)
        .unwrap_or_else(|| {
            let stderr = String::from_utf8_lossy(&out.stderr);
            let tail: Vec<&str> = stderr.lines().rev().take(5).collect();
            tail.into_iter().rev().collect::<Vec<_>>().join(" | ")
        });
    Err(Error::invalid(format!(
        "LIGGGHTS ({}) failed with {} in {}: {}",
        binary.display(),
        out.status,
        dir.display(),
        if error_line.is_empty() {
            format!("no ERROR line in {}", log_path.display())
        } else {
            error_line
        }
    )))
}

/// Rows `(id, radius, position)` of a `write_dump ... custom ... id radius x y z` file, whatever
/// atoms it holds (atoms may have been deleted).
pub fn parse_dump_rows(file: &str, text: &str) -> Result<Vec<(usize, f64, [f64; 3])>> {
    let mut lines = text.lines();
    lines
        .by_ref()
        .find(|l| l.starts_with("ITEM: ATOMS"))
        .filter(|l| {
            l.split_whitespace()
                .skip(2)
                .eq(["id", "radius", "x", "y", "z"])
        })
        .ok_or_else(|| Error::input(file, "ITEM: ATOMS", "columns 'id radius x y z'"))?;
    let mut rows = Vec::new();
    for (k, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let v: Vec<f64> = line
            .split_whitespace()
            .map(|w| w.parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| {
                Error::input(
                    file,
                    format!("atom row {}", k + 1),
                    "5 numbers: id radius x y z",
                )
            })?;
        if v.len() != 5 || v.iter().any(|x| !x.is_finite()) || v[0] < 1.0 || v[0].fract() != 0.0 {
            return Err(Error::input(
                file,
                format!("atom row {}", k + 1),
                "5 finite numbers: id radius x y z",
            ));
        }
        rows.push((v[0] as usize, v[1], [v[2], v[3], v[4]]));
    }
    Ok(rows)
}

/// What [`run`] reads from a LIGGGHTS log.
#[derive(Debug, Clone, PartialEq)]
pub struct LogSummary {
    pub version: String,
    /// Loop time of the last run, s.
    pub loop_time_s: f64,
    pub warnings: Vec<String>,
}

/// Reads the version, the warnings and the last "Loop time" line of a log, checking that the
/// last run did `steps` steps with `atoms` atoms. `file` names the log in errors.
pub fn parse_log(file: &str, text: &str, atoms: usize, steps: u64) -> Result<LogSummary> {
    let first = text.lines().next().unwrap_or("");
    let version = first
        .strip_prefix("LIGGGHTS (Version ")
        .and_then(|v| v.strip_suffix(')'))
        .ok_or_else(|| {
            Error::input(
                file,
                "first line",
                format!("'LIGGGHTS (Version ...)' (is this LIGGGHTS?), found {first:?}"),
            )
        })?
        .to_owned();

    let mut warnings: Vec<String> = Vec::new();
    let lines: Vec<&str> = text.lines().collect();
    for (i, l) in lines.iter().enumerate() {
        if let Some(rest) = l.strip_prefix("WARNING:") {
            // Multi-line warnings put their text on the following lines.
            let msg = if rest.trim().is_empty() {
                lines[i + 1..]
                    .iter()
                    .map(|l| l.trim())
                    .find(|l| !l.is_empty())
                    .unwrap_or("")
            } else {
                rest.trim()
            };
            if !warnings.iter().any(|w| w == msg) {
                warnings.push(msg.to_owned());
            }
        }
    }

    let expected =
        format!("a line 'Loop time of T on 1 procs for {steps} steps with {atoms} atoms'");
    let loop_line = text
        .lines()
        .rev()
        .find(|l| l.starts_with("Loop time of "))
        .ok_or_else(|| Error::input(file, "Loop time", expected.clone()))?;
    let words: Vec<&str> = loop_line.split_whitespace().collect();
    // Loop time of <T> on <P> procs for <S> steps with <N> atoms[, finish time ...]
    let field = |k: usize| words.get(k).copied().unwrap_or("");
    let loop_time_s: f64 = field(3).parse().unwrap_or(f64::NAN);
    let got_steps: Option<u64> = field(8).parse().ok();
    let got_atoms: Option<usize> = field(11).parse().ok();
    if loop_time_s.is_nan()
        || loop_time_s <= 0.0
        || got_steps != Some(steps)
        || got_atoms != Some(atoms)
    {
        return Err(Error::input(
            file,
            "Loop time",
            format!("{expected} for the timed run, found {loop_line:?}"),
        ));
    }
    Ok(LogSummary {
        version,
        loop_time_s,
        warnings,
    })
}

/// Reads a `dump custom ... id radius x y z` snapshot with `atoms` atoms, returning positions and
/// radii ordered by atom id (id k is particle k - 1 of the case).
pub fn parse_dump(file: &str, text: &str, atoms: usize) -> Result<(Vec<[f64; 3]>, Vec<f64>)> {
    let mut positions = vec![[f64::NAN; 3]; atoms];
    let mut radii = vec![f64::NAN; atoms];
    let rows = parse_dump_rows(file, text)?;
    for (k, &(id, r, x)) in rows.iter().enumerate() {
        if id == 0 || id > atoms || !radii[id - 1].is_nan() {
            return Err(Error::input(
                file,
                format!("atom row {}", k + 1),
                format!("a unique atom id in 1..={atoms}, found {id}"),
            ));
        }
        radii[id - 1] = r;
        positions[id - 1] = x;
    }
    if rows.len() != atoms {
        return Err(Error::input(
            file,
            "atoms",
            format!("{atoms} atom rows, found {}", rows.len()),
        ));
    }
    Ok((positions, radii))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::bench::jittered_lattice;

    fn small_case() -> LiggghtsCase {
        let (p, r) = jittered_lattice(50, [0.0; 3], BENCHMARK_BOX, 0.0075, 0.01, 1).unwrap();
        LiggghtsCase::benchmark(p, r)
    }

    #[test]
    fn benchmark_lattice_is_10_by_10_by_33_without_overlaps() {
        let (p, r) = jittered_lattice(3300, [0.0; 3], BENCHMARK_BOX, 0.0075, 0.01, 7).unwrap();
        assert_eq!(p.len(), 3300);
        assert!(r.iter().all(|&r| (0.00375..=0.005).contains(&r)));
        assert_eq!(super::super::analysis::coordination_number(&p, &r), 0.0);
        // Lattice rows of 10 in x (spacing 12 mm) and 100 per layer.
        assert!((p[1][0] - p[0][0] - 0.012).abs() < 0.002);
        assert!(p[100][2] > p[99][2]);
        let case = LiggghtsCase::benchmark(p.clone(), r.clone());
        case.validate().unwrap();
        for (p, r) in p.iter().zip(&r) {
            for k in 0..3 {
                assert!(p[k] - r > 0.0 && p[k] + r < BENCHMARK_BOX[k], "{p:?} {r}");
            }
        }
        let again = jittered_lattice(3300, [0.0; 3], BENCHMARK_BOX, 0.0075, 0.01, 7).unwrap();
        assert_eq!(again, (p, r));
        assert!(jittered_lattice(4000, [0.0; 3], BENCHMARK_BOX, 0.0075, 0.011, 7).is_err());
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

    const LOG: &str = "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, compiled 2022-01-26 by buildd)\n\
        pair_style gran model hertz\nWARNING: \n\tThe contact model you specified is not located in any whitelist.\n\
        \tBecause of this ...\nWARNING: \n\tThe contact model you specified is not located in any whitelist.\n\
        Loop time of 12.5 on 1 procs for 40000 steps with 3 atoms, finish time Sat\n\
        Loop time of 2.5 on 1 procs for 20000 steps with 3 atoms, finish time Sat\n";

    #[test]
    fn log_gives_version_timing_and_warnings() {
        let s = parse_log("log", LOG, 3, 20000).unwrap();
        assert_eq!(
            s.version,
            "LIGGGHTS-PUBLIC 3.8.0, compiled 2022-01-26 by buildd"
        );
        assert_eq!(s.loop_time_s, 2.5);
        assert_eq!(
            s.warnings,
            ["The contact model you specified is not located in any whitelist."]
        );
        let e = parse_log("log.x", LOG, 4, 20000).unwrap_err().to_string();
        assert!(e.starts_with("log.x: Loop time:"), "{e}");
        let e = parse_log("log.x", "LIGGGHTS (Version X)\n", 3, 1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("Loop time"), "{e}");
        assert!(parse_log("log.x", "LAMMPS (29 Sep 2021)\n", 3, 1).is_err());
    }

    #[test]
    fn dump_is_read_in_id_order() {
        let text = "ITEM: TIMESTEP\n0\nITEM: ATOMS id radius x y z \n2 0.5 4 5 6\n1 0.25 1 2 3\n";
        let (p, r) = parse_dump("d", text, 2).unwrap();
        assert_eq!(p, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
        assert_eq!(r, [0.25, 0.5]);
        assert!(parse_dump("d", text, 3).is_err());
        assert!(parse_dump("d", &text.replace("2 0.5", "1 0.5"), 2).is_err());
        assert!(parse_dump("d", "ITEM: ATOMS id x y z\n", 0).is_err());
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
