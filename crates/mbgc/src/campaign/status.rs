//! Progress of a table: runs done, failed and remaining.
//!
//! `mbgc simulate` writes a sidecar `<out>.meta.json` before it runs anything, holding the
//! experiment, the design (path as given and row count), the shard, the seed, the `--set`
//! constants and the settings. Status counts the remaining rows from it, or from `--design`
//! (needed for a merged table, which has no sidecar).

use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::plan::{Plan, Shard};
use super::table::{self, read_table, DONE, FAILED};
use crate::error::{read_to_string, write_atomic, Error, Result};
use crate::sampling::design::read_numeric_csv;

/// The sidecar of a table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Meta {
    /// Experiment name, as on the command line.
    pub experiment: String,
    /// The design path as given on the command line.
    pub design: String,
    /// Rows of the whole design (all shards).
    pub design_rows: usize,
    /// `K/N`, or null for the whole design.
    pub shard: Option<String>,
    /// Rows this table is meant to hold (the shard's rows).
    pub rows: usize,
    /// Campaign seed (`--seed`).
    pub seed: u64,
    /// `--set` constants (their column order is the table header's).
    pub set: BTreeMap<String, f64>,
    /// Shear-box scale k, when set.
    pub box_scale: Option<f64>,
    /// The model class (`+`-joined names; `-` without a contact law). Sidecars written before
    /// model classes existed lack it: their runs are all of the default class.
    #[serde(default = "default_class_label")]
    pub model_class: String,
    /// The backend when it is not the embedded engine (absent otherwise, as in every sidecar
    /// written before backends existed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub backend: Option<String>,
    /// MPI processes per run of an external backend, when given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mpi: Option<usize>,
    /// The shear box's rest rule when it is not the kinetic one (absent otherwise, as in every
    /// sidecar written before the rule could be chosen).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest_rule: Option<String>,
}

fn default_class_label() -> String {
    mbgc_dem::contact::ModelClass::default().label()
}

/// `<out>.meta.json`, beside the table.
pub fn meta_path(out: &Path) -> PathBuf {
    let mut name = out.file_name().unwrap_or_default().to_os_string();
    name.push(".meta.json");
    out.with_file_name(name)
}

impl Meta {
    /// The sidecar of a plan, written before any run starts.
    pub fn of(plan: &Plan) -> Meta {
        Meta {
            experiment: plan.experiment.clone(),
            design: plan.design.display().to_string(),
            design_rows: plan.rows.len(),
            shard: plan.shard.map(|s| s.to_string()),
            rows: plan.selected().count(),
            seed: plan.seed,
            set: plan.set.iter().cloned().collect(),
            box_scale: plan.settings.box_scale,
            model_class: plan.model_class_label(),
            backend: plan
                .settings
                .backend
                .is_recorded()
                .then(|| plan.settings.backend.label().to_string()),
            mpi: plan.settings.mpi,
            rest_rule: plan
                .settings
                .rest_rule
                .filter(|r| *r != crate::experiments::shear_box::RestRule::Kinetic)
                .map(|r| r.label()),
        }
    }

    /// Writes the sidecar to `<out>.meta.json` atomically.
    pub fn write(&self, out: &Path) -> Result<()> {
        let text = serde_json::to_string_pretty(self)
            .map_err(|e| Error::invalid(format!("sidecar of {}: {e}", out.display())))?;
        write_atomic(&meta_path(out), format!("{text}\n").as_bytes())
    }

    /// The sidecar of `out`, if there is one.
    pub fn read(out: &Path) -> Result<Option<Meta>> {
        let path = meta_path(out);
        if !path.exists() {
            return Ok(None);
        }
        let m: Meta = serde_json::from_str(&read_to_string(&path)?).map_err(|e| {
            Error::input(
                path.display(),
                "JSON",
                format!("{e}; not a campaign sidecar (remove it and pass --design)"),
            )
        })?;
        Ok(Some(m))
    }
}

/// Progress of a campaign table, as `mbgc campaign status` reports it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Status {
    /// The table's path.
    pub out: String,
    /// Experiment name from the sidecar, if there is one.
    pub experiment: Option<String>,
    /// Runs in the table with status done / failed.
    pub done: usize,
    /// Runs in the table with status failed.
    pub failed: usize,
    /// Rows of the design (this shard's rows) not in the table yet; None when neither a sidecar
    /// nor `--design` gives the design's size.
    pub remaining: Option<usize>,
    /// Rows the table is meant to hold (the shard's rows), when known.
    pub total: Option<usize>,
    /// An incomplete last line is present (its run counts as remaining).
    pub partial_line: bool,
    /// Of the done runs, those without a value of some response (NaN: a shear box whose material
    /// ran out flat has no flank); None when the table does not say which experiment made it.
    pub no_value: Option<usize>,
}

/// Refuses to count a table against a design it was not run on: every line's design columns must
/// hold that row's values.
fn same_design(
    file: &str,
    t: &table::Table,
    design: &Path,
    names: &[String],
    values: &[Vec<f64>],
) -> Result<()> {
    let mismatch = |line: u64, what: String| {
        Error::input(
            file,
            format!("line {line}"),
            format!(
                "{what}: the table is not a campaign of {}",
                design.display()
            ),
        )
    };
    let columns: Vec<Option<usize>> = names
        .iter()
        .map(|n| t.header.iter().position(|h| h == n))
        .collect();
    if let Some(k) = columns.iter().position(Option::is_none) {
        return Err(Error::input(
            file,
            "header",
            format!(
                "a column {} as in {}: the table is not a campaign of that design",
                names[k],
                design.display()
            ),
        ));
    }
    for (line, r) in &t.records {
        let Ok(row) = r[1].parse::<usize>() else {
            continue;
        };
        let Some(want) = values.get(row) else {
            return Err(mismatch(
                *line,
                format!("row {row} is beyond the design's {} rows", values.len()),
            ));
        };
        for ((name, col), v) in names.iter().zip(&columns).zip(want) {
            let field = &r[col.unwrap_or(0)];
            if !field.parse::<f64>().is_ok_and(|x| x == *v) {
                return Err(mismatch(
                    *line,
                    format!("row {row} has {name} = {field} but the design has {v:?}"),
                ));
            }
        }
    }
    Ok(())
}

/// Counts the runs of a table. `design` overrides the sidecar's row count; the sidecar's shard,
/// if any, still applies.
pub fn status(out: &Path, design: Option<&Path>) -> Result<Status> {
    let file = out.display().to_string();
    let t = read_table(out)?;
    if super::columns::is_pre_class_header(&t.header) {
        return Err(Error::input(
            out.display(),
            "header",
            super::columns::PRE_CLASS_TABLE,
        ));
    }
    if !table::is_campaign_header(&t.header) {
        return Err(Error::input(
            &file,
            "header",
            "expected a campaign table (run_id,row,status,seed,model_class,...,error)",
        ));
    }
    let meta = Meta::read(out)?;
    let (mut done, mut failed) = (0, 0);
    let mut rows = HashSet::new();
    for (line, r) in &t.records {
        match &r[2] {
            s if s == DONE => done += 1,
            s if s == FAILED => failed += 1,
            s => {
                return Err(Error::input(
                    &file,
                    format!("line {line}"),
                    format!("status: expected done or failed, found \"{s}\""),
                ))
            }
        }
        let row: usize = r[1].parse().map_err(|_| {
            Error::input(
                &file,
                format!("line {line}"),
                format!("row: expected a row number, found \"{}\"", &r[1]),
            )
        })?;
        rows.insert(row);
    }
    let shard = match meta.as_ref().and_then(|m| m.shard.as_deref()) {
        Some(s) => Some(
            Shard::parse(s)
                .map_err(|e| Error::input(meta_path(out).display(), "shard", e.to_string()))?,
        ),
        None => None,
    };
    let design_rows = match (design, &meta) {
        (Some(d), _) => {
            let (names, values) = read_numeric_csv(d)?;
            same_design(&file, &t, d, &names, &values)?;
            Some(values.len())
        }
        (None, Some(m)) => Some(m.design_rows),
        (None, None) => None,
    };
    let (total, remaining) = match design_rows {
        Some(n) => {
            let planned: Vec<usize> = (0..n)
                .filter(|&r| shard.is_none_or(|s| s.contains(r)))
                .collect();
            let remaining = planned.iter().filter(|r| !rows.contains(r)).count();
            (Some(planned.len()), Some(remaining))
        }
        None => (None, None),
    };
    // The experiment's responses, when the sidecar names a known experiment: a done run with a
    // NaN in one of them measured nothing there.
    let responses: Option<Vec<usize>> = meta.as_ref().and_then(|m| {
        super::registry::experiment_by_name(&m.experiment, &Default::default())
            .ok()
            .map(|e| {
                e.responses()
                    .iter()
                    .filter_map(|r| t.header.iter().position(|h| h == r))
                    .collect()
            })
    });
    let no_value = responses.map(|cols| {
        t.records
            .iter()
            .filter(|(_, r)| &r[2] == DONE)
            .filter(|(_, r)| {
                cols.iter()
                    .any(|&k| r[k].parse::<f64>().is_ok_and(f64::is_nan))
            })
            .count()
    });
    Ok(Status {
        no_value,
        out: file,
        experiment: meta.map(|m| m.experiment),
        done,
        failed,
        remaining,
        total,
        partial_line: t.partial_len > 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::{experiment_by_name, ExperimentSettings};
    use crate::experiments::shear_box::RestRule;

    /// A non-kinetic rest rule is written into the sidecar and changes every run id; the
    /// kinetic one, given or not, leaves both as tables before the rule existed had them.
    #[test]
    fn the_rest_rule_is_in_the_sidecar_and_the_run_ids_only_when_not_kinetic() {
        let dir = tempfile::tempdir().unwrap();
        let design = dir.path().join("design.csv");
        std::fs::write(
            &design,
            "E_p,E_w,nu_p,e_pp,e_pw,mu_pp,mu_pw,mu_r_pp,mu_r_pw,rho_p,d50,sigma_ln\n\
             3.5e7,1.3e7,0.4,0.85,0.44,0.69,0.93,0.016,0.17,2600,10,0.118\n",
        )
        .unwrap();
        let plan = |rule: Option<RestRule>| {
            let s = ExperimentSettings {
                rest_rule: rule,
                ..Default::default()
            };
            let e = experiment_by_name("shear-box", &s).unwrap();
            Plan::new(e.as_ref(), &design, &[], 1, &s, None).unwrap()
        };
        let (none, kinetic, response) = (
            plan(None),
            plan(Some(RestRule::Kinetic)),
            plan(Some(RestRule::CANDIDATE)),
        );
        assert_eq!(Meta::of(&none).rest_rule, None);
        assert_eq!(Meta::of(&kinetic).rest_rule, None);
        assert_eq!(Meta::of(&response).rest_rule.as_deref(), Some("response"));
        assert_eq!(none.rows[0].run_id, kinetic.rows[0].run_id);
        assert_ne!(none.rows[0].run_id, response.rows[0].run_id);
    }
}
