//! Design files: CSV with a header of parameter names, one point per row.
//!
//! With a space file the values are physical (all parameters, fixed ones included, in the space's
//! order); without one they are unit-cube coordinates named `x0`, `x1`, ...

use std::path::Path;

use super::points::Points;
use crate::error::{csv_error, csv_number, csv_open, write_atomic, Error, Result};
use crate::space::Space;

/// A design as stored on disk: its column names, one row of values per point, and the matching
/// unit-cube coordinates of the free parameters that the samplers and metrics work on.
#[derive(Debug, Clone, PartialEq)]
pub struct Design {
    /// Column names, in the order written.
    pub header: Vec<String>,
    /// Rows in `header` order: physical values with a space, unit-cube values without.
    pub values: Vec<Vec<f64>>,
    /// Unit-cube coordinates of the free parameters, one row per design point.
    pub unit: Points,
}

/// Reads a CSV of numbers: header plus rows, every value finite. Errors name the file, the line
/// and the column.
pub fn read_numeric_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>)> {
    let file = path.display().to_string();
    let (mut rdr, header) = csv_open(path)?;
    if header.is_empty() || header.iter().all(|h| h.is_empty()) {
        return Err(Error::input(
            &file,
            "header",
            "expected a header line of column names",
        ));
    }
    for (i, h) in header.iter().enumerate() {
        if h.is_empty() {
            return Err(Error::input(
                &file,
                format!("header column {}", i + 1),
                "empty column name",
            ));
        }
    }
    let mut rows = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| csv_error(&file, e))?;
        let line = rec.position().map(|p| p.line()).unwrap_or(0);
        let mut row = Vec::with_capacity(header.len());
        for (j, field) in rec.iter().enumerate() {
            row.push(csv_number(&file, line, &header[j], field)?);
        }
        rows.push(row);
    }
    Ok((header, rows))
}

impl Design {
    /// Reads a design. With a space, every free parameter must have a column with values inside
    /// its bounds; fixed parameters may be absent (the fixed value is used) or must equal the
    /// fixed value; other columns are ignored. Without a space, every column is a unit-cube
    /// coordinate and must lie in [0, 1].
    pub fn read(path: &Path, space: Option<&Space>) -> Result<Design> {
        let file = path.display().to_string();
        let (header, rows) = read_numeric_csv(path)?;
        match space {
            None => {
                for (i, row) in rows.iter().enumerate() {
                    for (j, &v) in row.iter().enumerate() {
                        if !(0.0..=1.0).contains(&v) {
                            return Err(Error::input(
                                &file,
                                format!("line {}, column {}", i + 2, header[j]),
                                format!(
                                    "value {v} lies outside [0, 1]; a design without --space \
                                     must hold unit-cube coordinates (pass --space to read \
                                     physical values)"
                                ),
                            ));
                        }
                    }
                }
                let unit = Points::from_rows(header.len(), &rows);
                Ok(Design {
                    header,
                    values: rows,
                    unit,
                })
            }
            Some(space) => {
                let mut cols = Vec::with_capacity(space.parameters.len());
                for p in &space.parameters {
                    let c = header.iter().position(|h| h == &p.name);
                    if c.is_none() && !p.is_fixed() {
                        return Err(Error::input(
                            &file,
                            format!("column {}", p.name),
                            format!(
                                "missing; the space {} needs a column for every free \
                                 parameter ({})",
                                space.source,
                                space
                                    .free()
                                    .map(|p| p.name.as_str())
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ),
                        ));
                    }
                    cols.push(c);
                }
                let mut values = Vec::with_capacity(rows.len());
                let mut unit = Points::with_capacity(space.dim(), rows.len());
                for (i, row) in rows.iter().enumerate() {
                    let mut phys = Vec::with_capacity(cols.len());
                    for (p, c) in space.parameters.iter().zip(&cols) {
                        let field = || format!("line {}, column {}", i + 2, p.name);
                        let v = match (c, p.fixed) {
                            (Some(c), Some(f)) => {
                                let v = row[*c];
                                if (v - f).abs() > 1e-9 * f.abs().max(1e-300) {
                                    return Err(Error::input(
                                        &file,
                                        field(),
                                        format!(
                                            "value {v} differs from the value {f} that {} \
                                             fixes",
                                            space.source
                                        ),
                                    ));
                                }
                                v
                            }
                            (Some(c), None) => row[*c],
                            (None, Some(f)) => f,
                            (None, None) => unreachable!("checked above"),
                        };
                        if !p.contains(v) {
                            return Err(Error::input(
                                &file,
                                field(),
                                format!(
                                    "value {v} lies outside the bounds [{}, {}] of {}",
                                    p.min, p.max, space.source
                                ),
                            ));
                        }
                        phys.push(v);
                    }
                    unit.push(&space.to_unit(&phys));
                    values.push(phys);
                }
                Ok(Design {
                    header: space.names().iter().map(|s| s.to_string()).collect(),
                    values,
                    unit,
                })
            }
        }
    }

    /// An empty design with the right header for a space (or `x0..` for a bare cube).
    pub fn empty(space: Option<&Space>, dim: usize) -> Design {
        let header = match space {
            Some(s) => s.names().iter().map(|s| s.to_string()).collect(),
            None => (0..dim).map(|i| format!("x{i}")).collect(),
        };
        Design {
            header,
            values: Vec::new(),
            unit: Points::new(space.map(|s| s.dim()).unwrap_or(dim)),
        }
    }

    /// Appends unit-cube points, converting to physical values when there is a space.
    pub fn append_unit(&mut self, space: Option<&Space>, new: &Points) {
        for row in new.rows() {
            let values = match space {
                Some(s) => s.to_physical(row),
                None => row.to_vec(),
            };
            self.values.push(values);
        }
        self.unit.append(new);
    }

    /// Number of design points (rows).
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether the design has no points yet; a sampler then starts from scratch.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// CSV text; numbers in Rust's shortest round-trip form, so re-reading gives the same values.
    pub fn to_csv(&self) -> String {
        let mut s = self.header.join(",");
        s.push('\n');
        for row in &self.values {
            let line: Vec<String> = row.iter().map(|v| format!("{v:?}")).collect();
            s.push_str(&line.join(","));
            s.push('\n');
        }
        s
    }

    /// Writes [`Self::to_csv`] to `path` atomically (temporary file and rename), so an interrupted
    /// run never leaves a half-written design.
    pub fn write(&self, path: &Path) -> Result<()> {
        write_atomic(path, self.to_csv().as_bytes())
    }
}
