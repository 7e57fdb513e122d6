//! `campaign merge`: tables of one campaign (shards, restarts, reruns) into one, deduplicated by
//! run id and sorted by row. Rows are copied field by field and written by the same CSV writer,
//! so the merge of a design's shards is byte-identical to the merge of one full run.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use csv::StringRecord;

use super::columns::{backend_of, is_pre_class_header, MODEL_CLASS_COLUMN, PRE_CLASS_TABLE};
use super::lock::TableLock;
use super::status::Meta;
use super::table::{self, csv_line, read_table, DONE, FAILED, WALL_TIME_COLUMN};
use crate::error::{write_atomic, Error, Result};

/// What [`merge`] did.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MergeSummary {
    /// Distinct runs in the merged table.
    pub rows: usize,
    /// Records seen more than once (kept once).
    pub duplicates: usize,
    /// Failed runs left out because another table holds the same run done (a rerun that
    /// succeeded, e.g. with `--retry-failed` on another machine).
    pub superseded_failures: usize,
    /// Inputs whose incomplete last line was left out.
    pub partial_lines: Vec<PathBuf>,
}

/// Merges `inputs` into `out` (written atomically; `out` may be one of the inputs). Two records
/// with the same run id must agree in every column but `wall_time_s` (a measured time), or the
/// merge is refused, unless one of them failed: a done run supersedes a failed one (a rerun); two run ids for the same row mean tables of different campaigns and are
/// refused too.
pub fn merge(inputs: &[PathBuf], out: &Path) -> Result<MergeSummary> {
    // A simulate still appending to `out` would lose its later lines to the rename.
    let _lock = TableLock::acquire(out)?;
    let (header, records, summary) = merge_tables(inputs)?;
    let mut bytes = csv_line(&header)?;
    for r in &records {
        bytes.extend(csv_line(r)?);
    }
    write_atomic(out, &bytes)?;
    Ok(summary)
}

/// Refuses tables whose sidecars say they were run as different campaigns (another seed, `--set`,
/// box scale, model class, backend, MPI processes, rest rule, experiment or design size): their rows would not
/// collide by run id, so nothing else would notice. Tables without a sidecar (already merged) are
/// not compared.
fn same_campaign(inputs: &[PathBuf]) -> Result<()> {
    let mut first: Option<(&PathBuf, Meta)> = None;
    for path in inputs {
        let Some(m) = Meta::read(path)? else { continue };
        let Some((p0, m0)) = &first else {
            first = Some((path, m));
            continue;
        };
        let differs = [
            ("experiment", m0.experiment.clone(), m.experiment.clone()),
            ("--seed", m0.seed.to_string(), m.seed.to_string()),
            ("--set", format!("{:?}", m0.set), format!("{:?}", m.set)),
            (
                "--box-scale",
                format!("{:?}", m0.box_scale),
                format!("{:?}", m.box_scale),
            ),
            (
                "--model-class",
                m0.model_class.clone(),
                m.model_class.clone(),
            ),
            (
                "design rows",
                m0.design_rows.to_string(),
                m.design_rows.to_string(),
            ),
            (
                "--backend",
                m0.backend.clone().unwrap_or_else(|| "embedded".into()),
                m.backend.clone().unwrap_or_else(|| "embedded".into()),
            ),
            (
                "--mpi",
                m0.mpi.unwrap_or(1).to_string(),
                m.mpi.unwrap_or(1).to_string(),
            ),
            (
                "--rest-rule",
                m0.rest_rule.clone().unwrap_or_else(|| "kinetic".into()),
                m.rest_rule.clone().unwrap_or_else(|| "kinetic".into()),
            ),
        ];
        if let Some((what, a, b)) = differs.iter().find(|(_, a, b)| a != b) {
            return Err(Error::input(
                path.display(),
                *what,
                format!(
                    "the same as {} (one campaign in shards); the sidecars differ ({} has {a}, \
                     {} has {b})",
                    p0.display(),
                    p0.display(),
                    path.display(),
                ),
            ));
        }
    }
    Ok(())
}

/// The merged header and records, sorted by row.
pub fn merge_tables(inputs: &[PathBuf]) -> Result<(Vec<String>, Vec<StringRecord>, MergeSummary)> {
    if inputs.is_empty() {
        return Err(Error::invalid(
            "campaign merge: expected at least one table",
        ));
    }
    let mut header: Option<(String, Vec<String>)> = None;
    // run id -> (row, file, line, record)
    let mut by_id: HashMap<String, (u64, String, u64, StringRecord)> = HashMap::new();
    let mut by_row: HashMap<u64, (String, String, u64)> = HashMap::new();
    // The first model class seen, with where: a table holds one class.
    let mut class: Option<(String, String, u64)> = None;
    // Likewise the backend (with its MPI process count), in tables that name it.
    let mut backend: Option<(String, String, u64)> = None;
    let mut summary = MergeSummary {
        rows: 0,
        duplicates: 0,
        superseded_failures: 0,
        partial_lines: Vec::new(),
    };
    for path in inputs {
        let file = path.display().to_string();
        let t = read_table(path)?;
        if is_pre_class_header(&t.header) {
            return Err(Error::input(&file, "header", PRE_CLASS_TABLE));
        }
        if !table::is_campaign_header(&t.header) {
            return Err(Error::input(
                &file,
                "header",
                "expected a campaign table (run_id,row,status,seed,model_class,...,error)",
            ));
        }
        match &header {
            None => header = Some((file.clone(), t.header.clone())),
            Some((first, h)) if *h != t.header => {
                let k = h
                    .iter()
                    .zip(&t.header)
                    .position(|(a, b)| a != b)
                    .unwrap_or(h.len().min(t.header.len()));
                return Err(Error::input(
                    &file,
                    "header",
                    format!(
                        "differs from the header of {first} at column {} ({} vs {}): merge tables \
                         of one campaign only{}",
                        k + 1,
                        t.header.get(k).map(String::as_str).unwrap_or("(none)"),
                        h.get(k).map(String::as_str).unwrap_or("(none)"),
                        // One table holds every column of the other: a shard written before the
                        // experiment gained a response.
                        if h.iter().all(|c| t.header.contains(c))
                            || t.header.iter().all(|c| h.contains(c))
                        {
                            "; if one was written before the experiment recorded more \
                             responses, resume it with its simulate command first (that adds \
                             the columns)"
                        } else {
                            ""
                        }
                    ),
                ));
            }
            Some(_) => {}
        }
        if t.partial_len > 0 {
            summary.partial_lines.push(path.clone());
        }
        let wall = table::column(&t.header, WALL_TIME_COLUMN);
        for (line, r) in t.records {
            let row: u64 = r[1].parse().map_err(|_| {
                Error::input(
                    &file,
                    format!("line {line}"),
                    format!("row: expected a row number, found \"{}\"", &r[1]),
                )
            })?;
            // As `campaign status` and a resumed `simulate` read it: a line whose status is
            // neither is not a run, and copying it would hand the damage on.
            if r[2] != *DONE && r[2] != *FAILED {
                return Err(Error::input(
                    &file,
                    format!("line {line}"),
                    format!("status: expected done or failed, found \"{}\"", &r[2]),
                ));
            }
            let id = r[0].to_string();
            if let Some(b) = backend_of(&t.header, &r) {
                match &backend {
                    None => backend = Some((b, file.clone(), line)),
                    Some((b0, f0, l0)) if *b0 != b => {
                        return Err(Error::input(
                            &file,
                            format!("line {line}, column backend"),
                            format!(
                                "{b} here but {b0} in {f0} line {l0}: runs of different codes \
                                 or MPI process counts are different campaigns"
                            ),
                        ));
                    }
                    Some(_) => {}
                }
            }
            let c = &r[MODEL_CLASS_COLUMN];
            match &class {
                None => class = Some((c.to_string(), file.clone(), line)),
                Some((c0, f0, l0)) if c0 != c => {
                    return Err(Error::input(
                        &file,
                        format!("line {line}, column model_class"),
                        format!(
                            "{c} here but {c0} in {f0} line {l0}: runs of different model \
                             classes are different campaigns; merge each class on its own"
                        ),
                    ));
                }
                Some(_) => {}
            }
            if let Some((other, f0, l0)) = by_row.get(&row) {
                if *other != id {
                    return Err(Error::input(
                        &file,
                        format!("line {line}"),
                        format!(
                            "row {row} has run_id {id} here but {other} in {f0} line {l0}: \
                             tables of different campaigns (design, seed, --set or \
                             experiment differ)"
                        ),
                    ));
                }
            }
            // Status is the third column of every campaign table.
            let status = |r: &StringRecord| r.get(2).map(str::to_string).unwrap_or_default();
            if let Some((_, _, _, r0)) = by_id.get(&id) {
                let (before, now) = (status(r0), status(&r));
                // A rerun: the done run supersedes the failed one; two failures are one failure.
                if before == FAILED || now == FAILED {
                    if before == FAILED && now == DONE {
                        by_id.insert(id.clone(), (row, file.clone(), line, r));
                        summary.superseded_failures += 1;
                    } else if before == DONE {
                        summary.superseded_failures += 1;
                    } else {
                        summary.duplicates += 1;
                    }
                    continue;
                }
            }
            match by_id.get(&id) {
                Some((_, f0, l0, r0)) => {
                    let differs = r0
                        .iter()
                        .zip(r.iter())
                        .enumerate()
                        .find(|(k, (a, b))| Some(*k) != wall && a != b);
                    if let Some((k, (a, b))) = differs {
                        let h = &t.header[k];
                        return Err(Error::input(
                            &file,
                            format!("line {line}"),
                            format!(
                                "run {id} (row {row}) has {h} = \"{b}\" here but \"{a}\" in \
                                 {f0} line {l0}: conflicting results for one run"
                            ),
                        ));
                    }
                    summary.duplicates += 1;
                }
                None => {
                    by_row.insert(row, (id.clone(), file.clone(), line));
                    by_id.insert(id, (row, file.clone(), line, r));
                }
            }
        }
    }
    // After the line-by-line checks, which name the offending line when tables collide.
    same_campaign(inputs)?;
    let mut records: Vec<(u64, StringRecord)> =
        by_id.into_values().map(|(row, _, _, r)| (row, r)).collect();
    records.sort_by_key(|(row, _)| *row);
    summary.rows = records.len();
    let header = header.map(|h| h.1).unwrap_or_default();
    Ok((
        header,
        records.into_iter().map(|(_, r)| r).collect(),
        summary,
    ))
}
