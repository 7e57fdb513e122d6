//! Reading the columns a fit or a prediction needs from a CSV table (a campaign table, a design,
//! any user table). Other columns may hold anything.

use crate::error::{csv_error, csv_number, csv_open, Error, Result};
use std::collections::HashMap;
use std::path::Path;

/// Named numeric columns of a table.
#[derive(Clone, Debug)]
pub struct Columns {
    /// Every column name of the table, in file order.
    pub header: Vec<String>,
    /// `values[k][row]` for the k-th requested name.
    pub values: Vec<Vec<f64>>,
    /// All fields of the kept rows, for writing them back with predictions.
    pub records: Vec<Vec<String>>,
    /// Rows left out because a `status` column said the run did not finish.
    pub skipped: usize,
    /// Finished campaign runs left out because a requested column is `NaN`: the experiment
    /// measured nothing there (a shear box whose material ran out flat has no flank).
    pub no_value: usize,
    /// Finished campaign runs left out because they did not meet the experiment's rest or
    /// steady-state criterion (`settled` false): what they hold was not measured at rest.
    pub unsettled: usize,
}

/// Reads the columns `names` (every value must be a finite number). If the table has a `status`
/// column (campaign tables), rows whose status is not `done` are skipped and counted.
pub fn read_columns(path: &Path, names: &[String]) -> Result<Columns> {
    read_columns_skipping_nan(path, names, names.len())
}

/// As [`read_columns`], but in a campaign table a done row whose value in one of the columns
/// `names[first_response..]` is `NaN` is left out and counted in `no_value` (the experiment
/// measured nothing there); a NaN input is still an error.
pub fn read_columns_skipping_nan(
    path: &Path,
    names: &[String],
    first_response: usize,
) -> Result<Columns> {
    read(path, names, first_response, false)
}

/// As [`read_columns_skipping_nan`], but a done row keeps a `NaN` in the columns
/// `names[first_response..]` as NaN (for replicate columns, where one missing measurement
/// should not drop its row's others).
pub fn read_columns_keeping_nan(
    path: &Path,
    names: &[String],
    first_response: usize,
) -> Result<Columns> {
    read(path, names, first_response, true)
}

fn read(path: &Path, names: &[String], first_response: usize, keep_nan: bool) -> Result<Columns> {
    let file = path.display().to_string();
    let (mut rdr, header) = csv_open(path)?;
    let mut idx = Vec::with_capacity(names.len());
    for n in names {
        let i = header.iter().position(|h| h == n).ok_or_else(|| {
            Error::input(
                &file,
                format!("column {n}"),
                format!("no such column; expected one of: {}", header.join(", ")),
            )
        })?;
        idx.push(i);
    }
    let status = header.iter().position(|h| h == "status");
    // A campaign table holds each run once; two writers on one table (or a bad merge) would
    // otherwise weigh those runs twice in a fit.
    let run_id = header.iter().position(|h| h == "run_id");
    let mut seen: HashMap<String, u64> = HashMap::new();
    let mut values = vec![Vec::new(); names.len()];
    let mut records = Vec::new();
    let mut skipped = 0;
    let mut no_value = 0;
    let mut unsettled = 0;
    let settled = header.iter().position(|h| h == "settled");
    for rec in rdr.records() {
        let rec = rec.map_err(|e| csv_error(&file, e))?;
        let line = rec.position().map_or(0, |p| p.line());
        if let Some(id) = run_id.and_then(|k| rec.get(k)) {
            if let Some(first) = seen.insert(id.to_string(), line) {
                return Err(Error::input(
                    &file,
                    format!("line {line}, column run_id"),
                    format!(
                        "run {id} is also on line {first}: expected each run once (deduplicate \
                         with `mbgc campaign merge {file} --out <new table>`)"
                    ),
                ));
            }
        }
        if let Some(s) = status {
            if rec.get(s) != Some("done") {
                skipped += 1;
                continue;
            }
        }
        if status.is_some()
            && !keep_nan
            && matches!(settled.and_then(|k| rec.get(k)), Some("false" | "0"))
        {
            unsettled += 1;
            continue;
        }
        if status.is_some()
            && !keep_nan
            && idx[first_response.min(idx.len())..]
                .iter()
                .any(|&i| rec.get(i) == Some("NaN"))
        {
            no_value += 1;
            continue;
        }
        for (k, &i) in idx.iter().enumerate() {
            let field = rec.get(i).unwrap_or("");
            if keep_nan && status.is_some() && k >= first_response && field == "NaN" {
                values[k].push(f64::NAN);
                continue;
            }
            values[k].push(csv_number(&file, line, &names[k], field)?);
        }
        records.push(rec.iter().map(str::to_string).collect());
    }
    Ok(Columns {
        header,
        values,
        records,
        skipped,
        no_value,
        unsettled,
    })
}
