//! The rows of a campaign table as the study reports read them (every numeric column by name,
//! whether the run finished, settled or was copied from an extended model), and the cost table
//! the metamodel reports print from them.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context as _;

/// One row of a campaign table.
#[derive(Clone, Debug)]
pub(crate) struct Run {
    /// Copied from the model it extends (`train --extends`), not run for this table.
    pub copied: bool,
    pub done: bool,
    pub settled: bool,
    pub wall_s: f64,
    /// Every numeric column by name (inputs and responses; `settled` as 1 or 0).
    values: Vec<(String, f64)>,
}

impl Run {
    /// The column `name`; NaN where the run has no number there.
    pub fn get(&self, name: &str) -> f64 {
        self.values
            .iter()
            .find(|(n, _)| n == name)
            .map_or(f64::NAN, |(_, v)| *v)
    }

    /// A finished, settled run with these columns (for tests of what reads runs).
    #[cfg(test)]
    pub fn with_values(values: Vec<(String, f64)>) -> Run {
        Run {
            copied: false,
            done: true,
            settled: true,
            wall_s: f64::NAN,
            values,
        }
    }
}

/// Every row of the campaign table at `path`.
pub(crate) fn read_runs(path: &Path) -> anyhow::Result<Vec<Run>> {
    let mut r = csv::Reader::from_path(path).with_context(|| path.display().to_string())?;
    let header = r.headers()?.clone();
    let col = |name: &str| {
        header
            .iter()
            .position(|c| c == name)
            .with_context(|| format!("{}: no column {name}", path.display()))
    };
    let (status, settled, wall, warnings) = (
        col("status")?,
        col("settled")?,
        col("wall_time_s")?,
        col("warnings")?,
    );
    let mut out = Vec::new();
    for rec in r.records() {
        let rec = rec.with_context(|| path.display().to_string())?;
        let values = header
            .iter()
            .zip(rec.iter())
            .filter_map(|(h, v)| {
                let x = match v {
                    "true" => Some(1.0),
                    "false" => Some(0.0),
                    _ => v.parse::<f64>().ok(),
                };
                x.map(|x| (h.to_string(), x))
            })
            .collect();
        out.push(Run {
            copied: rec[warnings].contains("copied from ") && rec[warnings].contains(", run by "),
            done: &rec[status] == "done",
            settled: &rec[settled] == "true",
            wall_s: rec[wall].parse().unwrap_or(f64::NAN),
            values,
        });
    }
    Ok(out)
}

/// The rows of the table at `path`, none when it does not exist (a table not made yet).
pub(crate) fn read_runs_if_any(path: &Path) -> anyhow::Result<Vec<Run>> {
    if path.exists() {
        read_runs(path)
    } else {
        Ok(Vec::new())
    }
}

/// Writes the cost table of `tables` (one line each: copied rows, new runs, failed, the new
/// runs `unusable` says gave no usable value, core-hours, median and max wall time) and the
/// total against `budget_core_h`.
pub(crate) fn cost_section(
    w: &mut String,
    tables: &[(&Path, &[Run])],
    unusable: (&str, &dyn Fn(&Run) -> bool),
    budget_core_h: f64,
) {
    let _ = writeln!(
        w,
        "\n## Cost\n\nWall time of each new run as the campaign table records it (one run per \
         core, two at a time on a 2-core machine, other work beside them: an upper bound of the \
         cost alone). Copied rows cost nothing here.\n\n\
         | table | copied | new runs | failed | {} | core-hours | median s | max s |\n\
         |---|---|---|---|---|---|---|---|",
        unusable.0
    );
    let mut total = 0.0;
    for (path, runs) in tables {
        if runs.is_empty() {
            continue;
        }
        let new: Vec<&Run> = runs.iter().filter(|r| !r.copied).collect();
        let wall: Vec<f64> = new
            .iter()
            .map(|r| r.wall_s)
            .filter(|v| v.is_finite())
            .collect();
        let hours = wall.iter().sum::<f64>() / 3600.0;
        total += hours;
        let _ = writeln!(
            w,
            "| `{}` | {} | {} | {} | {} | {hours:.2} | {:.0} | {:.0} |",
            path.display(),
            runs.len() - new.len(),
            new.len(),
            new.iter().filter(|r| !r.done).count(),
            new.iter().filter(|r| (unusable.1)(r)).count(),
            mbgc::numeric::quantile(&wall, 0.5),
            mbgc::numeric::quantile(&wall, 1.0),
        );
    }
    let _ = writeln!(
        w,
        "\nTogether {total:.2} core-hours of new runs, of the budget of {budget_core_h} ({:.0} \
         %).",
        100.0 * total / budget_core_h
    );
}
