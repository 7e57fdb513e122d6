//! Reading what LIGGGHTS writes: logs (version, warnings, loop time) and custom dumps.

use crate::{Error, Result};

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
        if v.len() != 5
            || v.iter().any(|x| !x.is_finite())
            || v[0] < 1.0
            || v[0].fract() != 0.0
            || v[1] <= 0.0
        {
            return Err(Error::input(
                file,
                format!("atom row {}", k + 1),
                "5 finite numbers: id radius x y z, with a whole id >= 1 and a radius > 0",
            ));
        }
        rows.push((v[0] as usize, v[1], [v[2], v[3], v[4]]));
    }
    Ok(rows)
}

/// What [`run`](super::closed_box::run) reads from a LIGGGHTS log.
#[derive(Debug, Clone, PartialEq)]
pub struct LogSummary {
    /// The log's first line, e.g. "LIGGGHTS-PUBLIC 3.8.0, compiled ...".
    pub version: String,
    /// Loop time of the last run, s.
    pub loop_time_s: f64,
    /// Distinct warnings of the log (first line of each message).
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
}
