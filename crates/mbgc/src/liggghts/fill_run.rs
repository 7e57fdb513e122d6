//! A run of the self-filling shear-box deck ([`super::shear_box_fill`]) read back from its
//! directory: the particles at each stage from the dumps, and the step counts, the stop
//! criteria and the loop time from the log. Whether LIGGGHTS ran the deck here or a user ran it
//! on a cluster makes no difference to this reader.

use std::path::Path;

use super::parse::parse_dump_rows;
use super::shear_box_fill::{FILLED_DUMP, FINAL_DUMP, INPUT, INSERTED_DUMP, LOG, PRE_STRIKE_DUMP};
use crate::error::{read_to_string, Error, Result};
use mbgc_dem::vec3::V3;

/// (radius, position) of each particle of a dump.
pub type Spheres = Vec<(f64, V3)>;

/// Where the run in a directory stands.
#[derive(Debug, Clone, PartialEq)]
pub enum RunState {
    /// No deck, or a deck but no log: not started.
    NotRun,
    /// A log without an end and without an error: running, or killed.
    Unfinished,
    /// LIGGGHTS stopped with an error (its ERROR line).
    Failed(String),
    /// The final dump and the log's end marker are there.
    Finished,
}

/// The marker the deck prints after the outflow, before the final dump.
pub const FLOW_END: &str = "FLOW_END ";
/// The marker the deck prints last, after the final dump is written.
pub const RUN_END: &str = "RUN_END";
/// The marker the deck prints when the fill stops.
pub const FILL_STEPS: &str = "FILL_STEPS ";

/// Where the run in `dir` stands, from its deck, log and final dump; reading a log that cannot
/// be read counts as unfinished.
pub fn state(dir: &Path) -> RunState {
    let log = dir.join(LOG);
    if !dir.join(INPUT).exists() || !log.exists() {
        return RunState::NotRun;
    }
    let text = read_log(&log).unwrap_or_default();
    if let Some(e) = text.lines().find(|l| l.starts_with("ERROR")) {
        return RunState::Failed(e.trim().to_owned());
    }
    let ended = text.lines().any(|l| l.trim_end() == RUN_END);
    if ended && dir.join(FINAL_DUMP).exists() {
        RunState::Finished
    } else {
        RunState::Unfinished
    }
}

/// The log as text: LIGGGHTS may print garbage bytes after an error message.
fn read_log(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// A finished self-filling shear-box run read back from its directory.
#[derive(Debug, Clone)]
pub struct FillRun {
    /// Just after insertion, at the end of the fill, after strike-off and relaxation, at the end.
    pub inserted: Spheres,
    /// Particles at the end of the fill, before the strike-off.
    pub pre_strike: Spheres,
    /// Particles after strike-off and relaxation: the bed the bulk density is measured on.
    pub filled: Spheres,
    /// Particles at the end of the outflow: the flank the shear angle is measured on.
    pub last: Spheres,
    /// The step at which the fill stopped.
    pub fill_steps: u64,
    /// Quiet checks in a row when the outflow stopped (5 or more: it came to rest).
    pub quiet_checks: u64,
    /// Steps of the whole run, summed over its `run` commands.
    pub steps: u64,
    /// LIGGGHTS' loop time summed over its `run` commands, s.
    pub loop_seconds: f64,
    /// MPI ranks the log reports.
    pub procs: usize,
    /// "LIGGGHTS-PUBLIC 3.8.0, ..." from the log's first line.
    pub version: String,
}

impl FillRun {
    /// Reads a finished run; an unfinished or failed one is an error naming the directory.
    pub fn read(dir: &Path) -> Result<FillRun> {
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
                        "a finished run (a '{RUN_END}' line and {FINAL_DUMP}), found it {}",
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
        let file = log_path.display().to_string();
        let log = read_log(&log_path)?;
        let marker = |prefix: &str| -> Result<Vec<u64>> {
            let line = log
                .lines()
                .find_map(|l| l.strip_prefix(prefix))
                .ok_or_else(|| Error::input(&file, prefix.trim(), "the line the deck prints"))?;
            line.split_whitespace()
                .map(|w| w.parse::<u64>())
                .collect::<std::result::Result<_, _>>()
                .map_err(|_| Error::input(&file, prefix.trim(), "whole numbers after it"))
        };
        let fill_steps = *marker(FILL_STEPS)?
            .first()
            .ok_or_else(|| Error::input(&file, FILL_STEPS.trim(), "a step number"))?;
        let flow = marker(FLOW_END)?;
        let quiet_checks = *flow
            .get(1)
            .ok_or_else(|| Error::input(&file, FLOW_END.trim(), "the step and the quiet count"))?;
        let version = log
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("LIGGGHTS (Version "))
            .and_then(|v| v.strip_suffix(')'))
            .ok_or_else(|| Error::input(&file, "first line", "'LIGGGHTS (Version ...)'"))?
            .to_owned();
        // "Loop time of T on P procs for N steps with A atoms": one line per `run` command.
        let (mut steps, mut loop_seconds, mut procs, mut runs) = (0u64, 0.0, 1, 0);
        for l in log.lines().filter(|l| l.starts_with("Loop time of ")) {
            let w: Vec<&str> = l.split_whitespace().collect();
            let bad = || Error::input(&file, "Loop time", format!("a readable line, found {l:?}"));
            let seconds = w
                .get(3)
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|s| s.is_finite() && *s >= 0.0)
                .ok_or_else(bad)?;
            loop_seconds += seconds;
            procs = w
                .get(5)
                .and_then(|s| s.parse().ok())
                .filter(|p| *p >= 1)
                .ok_or_else(bad)?;
            let n = w
                .get(8)
                .and_then(|s| s.parse::<u64>().ok())
                .ok_or_else(bad)?;
            steps = steps.checked_add(n).ok_or_else(bad)?;
            runs += 1;
        }
        if runs == 0 {
            return Err(Error::input(
                &file,
                "Loop time",
                "a 'Loop time of ...' line per run command, found none",
            ));
        }
        let read = |name: &str| -> Result<Spheres> {
            let f = dir.join(name);
            Ok(
                parse_dump_rows(&f.display().to_string(), &read_to_string(&f)?)?
                    .into_iter()
                    .map(|(_, r, x)| (r, x))
                    .collect(),
            )
        };
        Ok(FillRun {
            inserted: read(INSERTED_DUMP)?,
            pre_strike: read(PRE_STRIKE_DUMP)?,
            filled: read(FILLED_DUMP)?,
            last: read(FINAL_DUMP)?,
            fill_steps,
            quiet_checks,
            steps,
            loop_seconds,
            procs,
            version,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DUMP: &str = "ITEM: TIMESTEP\n0\nITEM: ATOMS id radius x y z\n1 0.001 0 0 0.001\n";

    fn write(dir: &Path, log: &str, with_final: bool) {
        std::fs::write(dir.join(INPUT), "run 1\n").unwrap();
        std::fs::write(dir.join(LOG), log).unwrap();
        for d in [INSERTED_DUMP, PRE_STRIKE_DUMP, FILLED_DUMP] {
            std::fs::write(dir.join(d), DUMP).unwrap();
        }
        if with_final {
            std::fs::write(dir.join(FINAL_DUMP), DUMP).unwrap();
        }
    }

    #[test]
    fn states_and_a_finished_run_are_read_from_the_log_and_dumps() {
        let t = tempfile::tempdir().unwrap();
        let d = t.path();
        assert_eq!(state(d), RunState::NotRun);
        let head = "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, compiled x)\n\
            Loop time of 1.5 on 2 procs for 100 steps with 1 atoms\nFILL_STEPS 100\n";
        write(d, head, false);
        assert_eq!(state(d), RunState::Unfinished);
        assert!(FillRun::read(d)
            .unwrap_err()
            .to_string()
            .contains("unfinished"));
        let log = format!(
            "{head}Loop time of 0.5 on 2 procs for 50 steps with 1 atoms\nFLOW_END 150 5\n"
        );
        write(d, &log, true);
        assert_eq!(state(d), RunState::Unfinished, "no RUN_END yet");
        let log = format!("{log}RUN_END\n");
        write(d, &log, true);
        assert_eq!(state(d), RunState::Finished);
        let r = FillRun::read(d).unwrap();
        assert_eq!(
            (r.fill_steps, r.quiet_checks, r.steps, r.procs),
            (100, 5, 150, 2)
        );
        assert_eq!(r.loop_seconds, 2.0);
        assert_eq!(r.last, vec![(0.001, [0.0, 0.0, 0.001])]);
        assert!(r.version.starts_with("LIGGGHTS-PUBLIC 3.8.0"));
        write(
            d,
            &format!("{head}ERROR: Lost atoms: original 5 current 4\n"),
            false,
        );
        let s = state(d);
        assert_eq!(
            s,
            RunState::Failed("ERROR: Lost atoms: original 5 current 4".into())
        );
        assert!(FillRun::read(d)
            .unwrap_err()
            .to_string()
            .contains("Lost atoms"));
    }
}
