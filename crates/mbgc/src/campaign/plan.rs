//! What a campaign will run: the design read and checked row by row, `--set` constants added,
//! each row's run id and seed derived, and the rows of this shard selected. Nothing is written and
//! nothing runs until a whole plan has been built, so a bad row stops the campaign before it
//! starts.

use std::collections::HashSet;
use std::fmt;
use std::path::{Path, PathBuf};

use super::columns;
use super::identity::{row_seed, run_id};
use super::registry::ExperimentSettings;
use crate::error::{Error, Result};
use crate::experiments::{Experiment, ParamSet};
use crate::sampling::design::read_numeric_csv;
use mbgc_dem::contact::ModelClass;

/// `--shard K/N`: the rows with `row % N == K - 1` (K is 1-based, rows 0-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// K: which shard, 1-based, 1 <= K <= N.
    pub index: usize,
    /// N: the number of shards (>= 1).
    pub count: usize,
}

impl Shard {
    /// Parses `K/N`; refuses anything but whole numbers with 1 <= K <= N.
    pub fn parse(s: &str) -> Result<Shard> {
        let bad = || {
            Error::invalid(format!(
                "--shard {s}: expected K/N with whole numbers 1 <= K <= N, e.g. --shard 2/8"
            ))
        };
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = k.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// Whether this shard runs the 0-based design row `row`.
    pub fn contains(&self, row: usize) -> bool {
        row % self.count == self.index - 1
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// `--set name=value`.
pub fn parse_set(s: &str) -> Result<(String, f64)> {
    let bad = |why: &str| Error::invalid(format!("--set {s}: {why}"));
    let (name, value) = s
        .split_once('=')
        .ok_or_else(|| bad("expected NAME=VALUE, e.g. --set impact_speed=3.9"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(bad("empty parameter name"));
    }
    let v: f64 = value
        .trim()
        .parse()
        .map_err(|_| bad(&format!("expected a number after '=', found \"{value}\"")))?;
    if !v.is_finite() {
        return Err(bad("expected a finite number"));
    }
    Ok((name.to_string(), v))
}

/// One design row, ready to run.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedRun {
    /// 0-based index of the row in the design.
    pub row: usize,
    /// Line of the row in the design file: `row + 2` (header on line 1), the numbering of
    /// `read_numeric_csv`'s own messages (blank lines, which the CSV reader skips, are not
    /// counted).
    pub line: u64,
    /// Stable identity of the run, derived from its experiment, inputs and settings; resumed and
    /// merged tables match rows by it.
    pub run_id: String,
    /// Seed handed to [`Experiment::run`]: [`row_seed`] of the campaign seed and the row.
    pub seed: u64,
    /// Inputs in table order: design columns, then `--set` constants.
    pub params: ParamSet,
}

/// A checked campaign: every row of the design with its run id and seed, before anything runs.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Experiment name, as on the command line.
    pub experiment: String,
    /// The experiment's model class (`None` for one without a contact law).
    pub model_class: Option<ModelClass>,
    /// Path of the design file the rows were read from.
    pub design: PathBuf,
    /// Campaign seed (`--seed`).
    pub seed: u64,
    /// `--set` constants in the order given, added to every row.
    pub set: Vec<(String, f64)>,
    /// Experiment settings (box scale, model class, backend, MPI processes).
    pub settings: ExperimentSettings,
    /// The shard this process runs, or `None` for every row.
    pub shard: Option<Shard>,
    /// Input columns of the table: the design's columns in design order, then `--set` names.
    pub inputs: Vec<String>,
    /// Response columns of the table, in [`Experiment::responses`] order.
    pub responses: Vec<String>,
    /// Every row of the design (all shards), in design order, so that a resumed table can be
    /// checked against the row it claims to hold.
    pub rows: Vec<PlannedRun>,
}

impl Plan {
    /// Reads `design` and checks every row (all shards) with [`Experiment::check`]; the first bad
    /// row is refused naming the file, its line and the parameter.
    pub fn new(
        experiment: &dyn Experiment,
        design: &Path,
        set: &[(String, f64)],
        seed: u64,
        settings: &ExperimentSettings,
        shard: Option<Shard>,
    ) -> Result<Plan> {
        let file = design.display().to_string();
        let (header, values) = read_numeric_csv(design)?;
        if values.is_empty() {
            return Err(Error::input(
                &file,
                "rows",
                "expected at least one design row after the header",
            ));
        }
        let responses: Vec<String> = experiment
            .responses()
            .iter()
            .map(|s| s.to_string())
            .collect();
        let reserved = |name: &str| {
            columns::FIXED_COLUMNS.contains(&name)
                || name == columns::BACKEND_COLUMN
                || columns::DIAGNOSTIC_COLUMNS.contains(&name)
                || responses.iter().any(|r| r == name)
        };
        for h in &header {
            if reserved(h) {
                return Err(Error::input(
                    &file,
                    format!("column {h}"),
                    format!(
                        "clashes with the output column {h} of the campaign table; rename the \
                         design column"
                    ),
                ));
            }
        }
        let known: Vec<&str> = experiment
            .parameters()
            .into_iter()
            .chain(experiment.optional_parameters())
            .collect();
        // A parameter of an effect the class does not switch on would do nothing.
        if let Some(class) = experiment.class() {
            for h in &header {
                class
                    .refuse_inactive(h, experiment.pairs(), experiment.name())
                    .map_err(|e| Error::input(&file, format!("column {h}"), e.to_string()))?;
            }
            for (name, v) in set {
                class
                    .refuse_inactive(name, experiment.pairs(), experiment.name())
                    .map_err(|e| Error::invalid(format!("--set {name}={v}: {e}")))?;
            }
        }
        // A column the experiment does not read would look like an input and change nothing.
        for h in &header {
            if !known.contains(&h.as_str()) {
                let renamed = ["_pp", "_pw"]
                    .iter()
                    .map(|suffix| format!("{h}{suffix}"))
                    .filter(|n| {
                        mbgc_dem::contact::all_effects()
                            .iter()
                            .any(|e| e.params.iter().any(|p| p.names.contains(&n.as_str())))
                    })
                    .collect::<Vec<_>>();
                let hint = if renamed.is_empty() {
                    String::new()
                } else {
                    format!(
                        " (effect parameters are named per kind of contact: {})",
                        renamed.join(", ")
                    )
                };
                return Err(Error::input(
                    &file,
                    format!("column {h}"),
                    format!(
                        "{} does not read {h}, so it would do nothing{hint}; expected only its \
                         parameters ({}): remove the column",
                        experiment.name(),
                        known.join(", ")
                    ),
                ));
            }
        }
        for (i, (name, v)) in set.iter().enumerate() {
            // A typo would otherwise become an extra column that changes nothing.
            if !known.contains(&name.as_str()) {
                return Err(Error::invalid(format!(
                    "--set {name}={v}: {} has no parameter {name}; expected one of {}",
                    experiment.name(),
                    known.join(", ")
                )));
            }
            if set[..i].iter().any(|(n, _)| n == name) {
                return Err(Error::invalid(format!("--set {name}: given twice")));
            }
            if header.contains(name) {
                return Err(Error::input(
                    &file,
                    format!("column {name}"),
                    format!(
                        "also given as --set {name}={v}; a parameter comes either from the \
                         design or from --set: drop one"
                    ),
                ));
            }
            if reserved(name) {
                return Err(Error::invalid(format!(
                    "--set {name}: clashes with the output column {name} of the campaign table"
                )));
            }
        }
        let needed = experiment.parameters();
        for p in &needed {
            if !header.iter().any(|h| h == p) && !set.iter().any(|(n, _)| n == p) {
                // Name the effect that needs it: the user may rather switch the effect off.
                let owner = experiment.class().and_then(|c| {
                    let params = c.parameters(experiment.pairs());
                    let (_, spec, e) = params.into_iter().find(|(n, _, _)| n == p)?;
                    Some(format!(
                        " ({} '{}' of the model class {c}: {}, {})",
                        e.slot.label(),
                        e.name,
                        spec.what,
                        spec.unit
                    ))
                });
                return Err(Error::input(
                    &file,
                    format!("column {p}"),
                    format!(
                        "missing{}; {} needs {}: add a column {p} or pass --set {p}=VALUE",
                        owner.unwrap_or_default(),
                        experiment.name(),
                        needed.join(", ")
                    ),
                ));
            }
        }
        let mut rows = Vec::with_capacity(values.len());
        let mut ids = HashSet::with_capacity(values.len());
        for (row, v) in values.iter().enumerate() {
            let line = row as u64 + 2;
            let mut params = ParamSet::new();
            for (name, &x) in header.iter().zip(v) {
                params.set(name, x);
            }
            for (name, x) in set {
                params.set(name, *x);
            }
            experiment.check(&params).map_err(|e| {
                Error::input(
                    &file,
                    format!("line {line} (row {row})"),
                    format!("{e}; nothing was run"),
                )
            })?;
            let seed = row_seed(seed, row as u64);
            let run_id = run_id(
                experiment.name(),
                &params,
                seed,
                settings,
                experiment.class(),
            );
            // Different rows have different seeds, so equal ids would be a hash collision.
            if !ids.insert(run_id.clone()) {
                return Err(Error::invalid(format!(
                    "{file}: line {line} (row {row}): run id {run_id} collides with an earlier \
                     row; change --seed"
                )));
            }
            rows.push(PlannedRun {
                row,
                line,
                run_id,
                seed,
                params,
            });
        }
        Ok(Plan {
            experiment: experiment.name().to_string(),
            model_class: experiment.class().copied(),
            design: design.to_path_buf(),
            seed,
            set: set.to_vec(),
            settings: *settings,
            shard,
            inputs: header
                .into_iter()
                .chain(set.iter().map(|(n, _)| n.clone()))
                .collect(),
            responses,
            rows,
        })
    }

    /// The `model_class` field of every line: the class's names joined by `+`, or `-` for an
    /// experiment without a contact law.
    pub fn model_class_label(&self) -> String {
        self.model_class.map_or_else(|| "-".into(), |c| c.label())
    }

    /// The table header: fixed columns, inputs, responses, diagnostics.
    pub fn columns(&self) -> Vec<String> {
        columns::columns(&self.inputs, &self.responses, self.settings.backend)
    }

    /// The `backend` field of this plan's lines, when its table has that column.
    pub fn backend_field(&self) -> Option<String> {
        self.settings
            .backend
            .is_recorded()
            .then(|| super::backend::table_field(self.settings.backend, self.settings.mpi))
    }

    /// The identity columns of this plan's table (fixed ones, and `backend` when recorded).
    pub fn identity_len(&self) -> usize {
        columns::identity_len(&self.columns())
    }

    /// Rows of this shard (all rows without `--shard`).
    pub fn selected(&self) -> impl Iterator<Item = &PlannedRun> {
        self.rows
            .iter()
            .filter(|r| self.shard.is_none_or(|s| s.contains(r.row)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::registry::sleep_test::SleepTest;

    #[test]
    fn shard_parsing_accepts_k_of_n_and_refuses_the_rest_naming_the_option() {
        assert_eq!(Shard::parse("2/3").unwrap(), Shard { index: 2, count: 3 });
        assert_eq!(Shard::parse("1/1").unwrap().to_string(), "1/1");
        for bad in ["0/3", "4/3", "x/y", "3", "1/0", "-1/3", "1/3/4", ""] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.contains("--shard"), "{bad}: {e}");
        }
        let s = Shard { index: 2, count: 3 };
        assert_eq!(
            (0..9).filter(|&r| s.contains(r)).collect::<Vec<_>>(),
            [1, 4, 7]
        );
    }

    #[test]
    fn set_parsing() {
        assert_eq!(
            parse_set("impact_speed=3.9").unwrap(),
            ("impact_speed".into(), 3.9)
        );
        assert_eq!(parse_set("x=-1e3").unwrap(), ("x".into(), -1e3));
        for bad in ["x", "=3", "x=", "x=abc", "x=NaN", "x=inf"] {
            let e = parse_set(bad).unwrap_err().to_string();
            assert!(e.contains("--set"), "{bad}: {e}");
        }
    }

    fn design(text: &str) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("d.csv");
        std::fs::write(&p, text).unwrap();
        (dir, p)
    }

    fn plan(text: &str, set: &[(&str, f64)]) -> Result<Plan> {
        let (_dir, p) = design(text);
        let set: Vec<(String, f64)> = set.iter().map(|(n, v)| (n.to_string(), *v)).collect();
        Plan::new(
            &SleepTest,
            &p,
            &set,
            1,
            &ExperimentSettings::default(),
            None,
        )
    }

    #[test]
    fn columns_are_design_then_set_and_rows_are_checked() {
        let e = plan("y,extra,x\n1,5,2\n", &[]).unwrap_err().to_string();
        assert!(
            e.contains("column extra") && e.contains("does not read extra"),
            "{e}"
        );
        let p = plan("y,fail,x\n1,0,2\n\n3,0,4\n", &[("sleep_ms", 0.0)]).unwrap();
        assert_eq!(p.inputs, ["y", "fail", "x", "sleep_ms"]);
        assert_eq!(p.rows.len(), 2);
        assert_eq!(p.rows[1].line, 3, "numbered like read_numeric_csv");
        assert_eq!(
            p.rows[1].params.iter().collect::<Vec<_>>(),
            [("y", 3.0), ("fail", 0.0), ("x", 4.0), ("sleep_ms", 0.0)]
        );
        assert_eq!(
            p.columns()[..9],
            [
                "run_id",
                "row",
                "status",
                "seed",
                "model_class",
                "y",
                "fail",
                "x",
                "sleep_ms"
            ]
        );

        let e = plan("x,y\n1,2\n1,-2\n", &[]).unwrap_err().to_string();
        assert!(
            e.contains("d.csv") && e.contains("line 3 (row 1)") && e.contains("parameter y"),
            "{e}"
        );
        let e = plan("x\n1\n", &[]).unwrap_err().to_string();
        assert!(e.contains("column y") && e.contains("--set y="), "{e}");
        let e = plan("x,y\n1,2\n", &[("y", 1.0)]).unwrap_err().to_string();
        assert!(e.contains("column y") && e.contains("--set y=1"), "{e}");
        let e = plan("x,y,status\n1,2,0\n", &[]).unwrap_err().to_string();
        assert!(e.contains("column status"), "{e}");
        let e = plan("x,y\n", &[]).unwrap_err().to_string();
        assert!(e.contains("d.csv: rows"), "{e}");
        let e = plan("x,y\n1,2\n", &[("f", 1.0)]).unwrap_err().to_string();
        assert!(e.contains("--set f"), "{e}");
    }
}
