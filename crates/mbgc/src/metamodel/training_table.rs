//! The table a metamodel is fitted to, in memory: named numeric columns, where they came from
//! and, for a campaign table, what the campaign held fixed. A fit never reads a file itself;
//! [`TrainingTable::read_csv`] is the convenience that reads one the way `mbgc fit` does.

use std::path::Path;

use super::table::read_columns_skipping_nan;
use crate::campaign::status::Meta;
use crate::error::{Error, Result};
use crate::numeric::{fnv1a64, Fnv1a};

/// Named columns of numbers with the facts a saved model records about its data.
#[derive(Clone, Debug)]
pub struct TrainingTable {
    /// Where the rows came from (a file path or a label); errors and the saved model name it.
    pub source: String,
    /// 64-bit FNV-1a of the source, as 16 hex digits (of the file's bytes when read from one).
    pub fingerprint: String,
    /// `(name, values)` with one value per row, every column as long as the first.
    pub columns: Vec<(String, Vec<f64>)>,
    /// The `model_class` label of each row, when the table has that column (campaign tables).
    pub model_class: Option<Vec<String>>,
    /// Rows left out because a campaign table's `status` said the run did not finish.
    pub skipped_rows: usize,
    /// Finished campaign runs left out because a response was `NaN` (nothing was measured).
    pub no_value_rows: usize,
    /// Finished campaign runs left out because they did not come to rest (`settled` false).
    pub unsettled_rows: usize,
    /// The campaign's sidecar (experiment, constants set with `--set`), when there is one.
    pub campaign: Option<Meta>,
}

impl TrainingTable {
    /// A table from columns already in memory (a data frame, a computed sample). Every column
    /// must have as many values as the first and every value must be finite; names are unique.
    pub fn from_columns(source: &str, columns: Vec<(String, Vec<f64>)>) -> Result<TrainingTable> {
        let rows = columns.first().map_or(0, |c| c.1.len());
        let mut hash = Fnv1a::default();
        for (k, (name, values)) in columns.iter().enumerate() {
            if columns[..k].iter().any(|c| c.0 == *name) {
                return Err(Error::input(
                    source,
                    format!("column {name}"),
                    "appears twice: expected unique column names",
                ));
            }
            if values.len() != rows {
                return Err(Error::input(
                    source,
                    format!("column {name}"),
                    format!(
                        "{rows} values like column {}, found {}",
                        columns[0].0,
                        values.len()
                    ),
                ));
            }
            if let Some(row) = values.iter().position(|v| !v.is_finite()) {
                return Err(Error::input(
                    source,
                    format!("column {name}, row {}", row + 1),
                    format!("a finite number, found {}", values[row]),
                ));
            }
            hash.str(name);
            for v in values {
                hash.u64(v.to_bits());
            }
        }
        Ok(TrainingTable {
            source: source.to_string(),
            fingerprint: format!("{:016x}", hash.0),
            columns,
            model_class: None,
            skipped_rows: 0,
            no_value_rows: 0,
            unsettled_rows: 0,
            campaign: None,
        })
    }

    /// This table with the rows of `other` appended for which `keep` holds (given each row's
    /// values in this table's column order). `other` must have the same columns; the model class
    /// labels are kept where both tables have them. The source names both tables. A row equal to
    /// one this table holds in every column is the same run copied into both campaigns (an
    /// extension copies its base's runs): it is not added twice.
    pub fn with_rows_of(
        mut self,
        other: &TrainingTable,
        keep: impl Fn(&[(String, f64)]) -> bool,
    ) -> Result<TrainingTable> {
        let mut idx = Vec::with_capacity(self.columns.len());
        for (name, _) in &self.columns {
            let k = other
                .columns
                .iter()
                .position(|(n, _)| n == name)
                .ok_or_else(|| {
                    Error::input(
                        &other.source,
                        format!("column {name}"),
                        format!("no such column; {} has it", self.source),
                    )
                })?;
            idx.push(k);
        }
        let rows = other.columns.first().map_or(0, |c| c.1.len());
        let mine = self.columns.first().map_or(0, |c| c.1.len());
        let key = |vals: &mut dyn Iterator<Item = f64>| vals.map(f64::to_bits).collect::<Vec<_>>();
        let mut seen: std::collections::HashSet<Vec<u64>> = (0..mine)
            .map(|r| key(&mut self.columns.iter().map(|(_, c)| c[r])))
            .collect();
        let mut classes = match (&mut self.model_class, &other.model_class) {
            (Some(a), Some(b)) => Some((a, b)),
            _ => None,
        };
        let mut added = 0;
        for r in 0..rows {
            let row: Vec<(String, f64)> = self
                .columns
                .iter()
                .zip(&idx)
                .map(|((n, _), &k)| (n.clone(), other.columns[k].1[r]))
                .collect();
            if !keep(&row) || !seen.insert(key(&mut row.iter().map(|(_, v)| *v))) {
                continue;
            }
            for ((_, col), (_, v)) in self.columns.iter_mut().zip(&row) {
                col.push(*v);
            }
            if let Some((a, b)) = classes.as_mut() {
                a.push(b[r].clone());
            }
            added += 1;
        }
        if classes.is_none() && added > 0 {
            self.model_class = None;
        }
        if added > 0 {
            let mut hash = Fnv1a::default();
            hash.str(&self.fingerprint);
            hash.str(&other.fingerprint);
            hash.u64(added as u64);
            self.fingerprint = format!("{:016x}", hash.0);
            self.source = format!("{} + {added} rows of {}", self.source, other.source);
        }
        Ok(self)
    }

    /// Reads the columns `inputs` and `responses` of a CSV table (any other columns may hold
    /// anything). In a campaign table, rows whose run did not finish are left out, as are done
    /// rows with a `NaN` response; the sidecar next to the table is read when present.
    pub fn read_csv(path: &Path, inputs: &[String], responses: &[String]) -> Result<TrainingTable> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        let names: Vec<String> = inputs.iter().chain(responses).cloned().collect();
        let cols = read_columns_skipping_nan(path, &names, inputs.len())?;
        let model_class = cols
            .header
            .iter()
            .position(|h| h == "model_class")
            .map(|k| {
                cols.records
                    .iter()
                    .map(|rec| rec.get(k).cloned().unwrap_or_default())
                    .collect()
            });
        Ok(TrainingTable {
            source: path.display().to_string(),
            fingerprint: format!("{:016x}", fnv1a64(&bytes)),
            columns: names.into_iter().zip(cols.values).collect(),
            model_class,
            skipped_rows: cols.skipped,
            no_value_rows: cols.no_value,
            unsettled_rows: cols.unsettled,
            campaign: Meta::read(path)?,
        })
    }

    /// The rows where `keep` is true, with the same source, fingerprint and sidecar.
    pub fn retain_rows(&self, keep: &[bool]) -> TrainingTable {
        assert_eq!(keep.len(), self.rows(), "one flag per row");
        let pick = |v: &Vec<f64>| -> Vec<f64> {
            v.iter()
                .zip(keep)
                .filter(|(_, k)| **k)
                .map(|(x, _)| *x)
                .collect()
        };
        TrainingTable {
            columns: self
                .columns
                .iter()
                .map(|(n, v)| (n.clone(), pick(v)))
                .collect(),
            model_class: self.model_class.as_ref().map(|m| {
                m.iter()
                    .zip(keep)
                    .filter(|(_, k)| **k)
                    .map(|(x, _)| x.clone())
                    .collect()
            }),
            ..self.clone()
        }
    }

    /// Rows in the table.
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, |c| c.1.len())
    }

    /// The column called `name`; the error names the source and the columns it has.
    pub fn column(&self, name: &str) -> Result<&[f64]> {
        self.columns
            .iter()
            .find(|c| c.0 == name)
            .map(|c| c.1.as_slice())
            .ok_or_else(|| {
                Error::input(
                    &self.source,
                    format!("column {name}"),
                    format!(
                        "no such column; expected one of: {}",
                        self.columns
                            .iter()
                            .map(|c| c.0.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_campaign_table_leaves_out_failed_unmeasured_and_unsettled_runs() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        std::fs::write(
            &path,
            "run_id,row,status,x,f,settled,error\n\
             a,0,done,0.1,1.0,true,\n\
             b,1,done,0.2,2.0,false,\n\
             c,2,failed,0.3,NaN,false,boom\n\
             d,3,done,0.4,NaN,true,\n\
             e,4,done,0.5,5.0,true,\n",
        )
        .unwrap();
        let t = TrainingTable::read_csv(&path, &["x".into()], &["f".into()]).unwrap();
        assert_eq!(t.column("x").unwrap(), [0.1, 0.5]);
        assert_eq!(
            (t.skipped_rows, t.no_value_rows, t.unsettled_rows),
            (1, 1, 1)
        );
        let kept = t.retain_rows(&[false, true]);
        assert_eq!(kept.column("f").unwrap(), [5.0]);
        assert_eq!(kept.source, t.source);
    }
}
