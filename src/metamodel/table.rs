//! Reading the columns a fit or a prediction needs from a CSV table (a campaign table, a design,
//! any user table). Other columns may hold anything.

use crate::error::{csv_error, csv_number, csv_open, Error, Result};
use std::path::Path;

/// Named numeric columns of a table.
#[derive(Clone, Debug)]
pub struct Columns {
    pub header: Vec<String>,
    /// `values[k][row]` for the k-th requested name.
    pub values: Vec<Vec<f64>>,
    /// All fields of the kept rows, for writing them back with predictions.
    pub records: Vec<Vec<String>>,
    /// Rows left out because a `status` column said the run did not finish.
    pub skipped: usize,
}

/// Reads the columns `names` (every value must be a finite number). If the table has a `status`
/// column (campaign tables), rows whose status is not `done` are skipped and counted.
pub fn read_columns(path: &Path, names: &[String]) -> Result<Columns> {
    let file = path.display().to_string();
    let (mut rdr, header) = csv_open(path)?;
    let mut idx = Vec::with_capacity(names.len());
    for n in names {
        let i = header.iter().position(|h| h == n).ok_or_else(|| {
            Error::input(
                &file,
                format!("column {n}"),
                format!("a column named {n} (the header has: {})", header.join(", ")),
            )
        })?;
        idx.push(i);
    }
    let status = header.iter().position(|h| h == "status");
    let mut values = vec![Vec::new(); names.len()];
    let mut records = Vec::new();
    let mut skipped = 0;
    for (line, rec) in rdr.records().enumerate() {
        let rec = rec.map_err(|e| csv_error(&file, e))?;
        let line = line + 2;
        if let Some(s) = status {
            if rec.get(s) != Some("done") {
                skipped += 1;
                continue;
            }
        }
        for (k, &i) in idx.iter().enumerate() {
            let field = rec.get(i).unwrap_or("");
            values[k].push(csv_number(&file, line as u64, &names[k], field)?);
        }
        records.push(rec.iter().map(str::to_string).collect());
    }
    Ok(Columns {
        header,
        values,
        records,
        skipped,
    })
}
