//! Sieve analyses: CSV with a header, a column `size_mm` (sieve aperture, mm) and the cumulative
//! mass passing as `passing` (fraction 0..1) or `passing_pct` (percent 0..100). Other columns are
//! ignored, so lab sheets with notes or sieve names can be read as they are.

use std::path::Path;

use crate::error::{csv_error, Error, Result};

/// Column of sieve apertures in mm.
pub const SIZE_COLUMN: &str = "size_mm";
/// Column of cumulative mass passing as a fraction in [0, 1].
pub const PASSING_COLUMN: &str = "passing";
/// Column of cumulative mass passing in percent, [0, 100]; exclusive with [`PASSING_COLUMN`].
pub const PASSING_PCT_COLUMN: &str = "passing_pct";

/// A checked sieve analysis: at least 3 points, sizes strictly increasing, passing
/// non-decreasing, not constant, with at least one point strictly between 0 and 1.
#[derive(Debug, Clone, PartialEq)]
pub struct SieveData {
    /// Where the data came from (file path), named in every error.
    pub source: String,
    /// Sieve apertures, mm, strictly increasing and positive.
    pub size_mm: Vec<f64>,
    /// Cumulative mass passing as a fraction, whatever the file's unit.
    pub passing: Vec<f64>,
}

impl SieveData {
    /// Reads and checks a sieve CSV; errors name the file, the line and the column.
    pub fn read(path: &Path) -> Result<SieveData> {
        let file = path.display().to_string();
        let (mut rdr, header) = crate::error::csv_open(path)?;
        let find = |name: &str| header.iter().position(|h| h == name);
        let size_col = find(SIZE_COLUMN).ok_or_else(|| {
            Error::input(
                &file,
                format!("column {SIZE_COLUMN}"),
                format!(
                    "missing; expected a header with {SIZE_COLUMN} (sieve size in mm) and \
                     {PASSING_COLUMN} (fraction 0..1) or {PASSING_PCT_COLUMN} (percent 0..100), \
                     found [{}]",
                    header.join(", ")
                ),
            )
        })?;
        let (pass_col, pass_name, scale) = match (find(PASSING_COLUMN), find(PASSING_PCT_COLUMN)) {
            (Some(c), None) => (c, PASSING_COLUMN, 1.0),
            (None, Some(c)) => (c, PASSING_PCT_COLUMN, 100.0),
            (Some(_), Some(_)) => {
                return Err(Error::input(
                    &file,
                    format!("columns {PASSING_COLUMN}, {PASSING_PCT_COLUMN}"),
                    "both present; keep exactly one passing column so the unit is unambiguous",
                ))
            }
            (None, None) => {
                return Err(Error::input(
                    &file,
                    format!("column {PASSING_COLUMN}"),
                    format!(
                        "missing; expected a column {PASSING_COLUMN} (fraction 0..1) or \
                         {PASSING_PCT_COLUMN} (percent 0..100), found [{}]",
                        header.join(", ")
                    ),
                ))
            }
        };

        let mut size_mm = Vec::new();
        let mut passing = Vec::new();
        let (mut prev_line, mut prev_raw) = (0, 0.0);
        for rec in rdr.records() {
            let rec = rec.map_err(|e| csv_error(&file, e))?;
            let line = rec.position().map(|p| p.line()).unwrap_or(0);
            let number = |col: usize, name: &str| -> Result<f64> {
                let field = rec.get(col).unwrap_or("");
                let at = || format!("line {line}, column {name}");
                let v: f64 = field.parse().map_err(|_| {
                    Error::input(&file, at(), format!("expected a number, found \"{field}\""))
                })?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(Error::input(
                        &file,
                        at(),
                        format!("expected a finite number, found {field}"),
                    ))
                }
            };
            let x = number(size_col, SIZE_COLUMN)?;
            let p = number(pass_col, pass_name)?;
            if x <= 0.0 {
                return Err(Error::input(
                    &file,
                    format!("line {line}, column {SIZE_COLUMN}"),
                    format!("expected a positive sieve size in mm, found {x}"),
                ));
            }
            if !(0.0..=scale).contains(&p) {
                return Err(Error::input(
                    &file,
                    format!("line {line}, column {pass_name}"),
                    format!("expected a value in [0, {scale}], found {p}"),
                ));
            }
            if let (Some(&x0), Some(&p0)) = (size_mm.last(), passing.last()) {
                if x <= x0 {
                    return Err(Error::input(
                        &file,
                        format!("line {line}, column {SIZE_COLUMN}"),
                        format!(
                            "expected sizes in strictly increasing order, found {x} after {x0} \
                             on line {prev_line}"
                        ),
                    ));
                }
                if p / scale < p0 {
                    return Err(Error::input(
                        &file,
                        format!("line {line}, column {pass_name}"),
                        format!(
                            "cumulative passing must not decrease with size, found {p} after \
                             {prev_raw} on line {prev_line}"
                        ),
                    ));
                }
            }
            size_mm.push(x);
            passing.push(p / scale);
            (prev_line, prev_raw) = (line, p);
        }
        SieveData::check_shape(&file, pass_name, size_mm, passing)
    }

    /// Builds sieve data from values already in memory (passing as fractions), with the same
    /// checks as [`SieveData::read`]; `source` names the data in errors.
    pub fn new(source: &str, size_mm: Vec<f64>, passing: Vec<f64>) -> Result<SieveData> {
        if size_mm.len() != passing.len() {
            return Err(Error::input(
                source,
                PASSING_COLUMN,
                format!(
                    "expected one value per size, found {} sizes and {} values",
                    size_mm.len(),
                    passing.len()
                ),
            ));
        }
        for (i, (&x, &p)) in size_mm.iter().zip(&passing).enumerate() {
            if !(x.is_finite() && x > 0.0) || (i > 0 && x <= size_mm[i - 1]) {
                return Err(Error::input(
                    source,
                    format!("point {}, {SIZE_COLUMN}", i + 1),
                    format!("expected finite positive sizes in increasing order, found {x}"),
                ));
            }
            if !(0.0..=1.0).contains(&p) || (i > 0 && p < passing[i - 1]) {
                return Err(Error::input(
                    source,
                    format!("point {}, {PASSING_COLUMN}", i + 1),
                    format!("expected non-decreasing fractions in [0, 1], found {p}"),
                ));
            }
        }
        SieveData::check_shape(source, PASSING_COLUMN, size_mm, passing)
    }

    fn check_shape(
        file: &str,
        pass_name: &str,
        size_mm: Vec<f64>,
        passing: Vec<f64>,
    ) -> Result<SieveData> {
        if size_mm.len() < 3 {
            return Err(Error::input(
                file,
                format!("rows ({SIZE_COLUMN}, {pass_name})"),
                format!(
                    "expected at least 3 sieve points to fit a two-parameter distribution, \
                     found {}",
                    size_mm.len()
                ),
            ));
        }
        if !passing.iter().any(|&p| p > 0.0 && p < 1.0) {
            return Err(Error::input(
                file,
                format!("column {pass_name}"),
                "expected at least one point strictly between 0 and 100 % passing; with only \
                 empty and full sieves the distribution is not determined",
            ));
        }
        if passing.first() == passing.last() {
            return Err(Error::input(
                file,
                format!("column {pass_name}"),
                "all values are equal; expected a passing curve that rises with size",
            ));
        }
        Ok(SieveData {
            source: file.to_string(),
            size_mm,
            passing,
        })
    }

    /// Number of sieve points (at least 3 once checked).
    pub fn len(&self) -> usize {
        self.size_mm.len()
    }

    /// Whether there are no sieve points; never true for checked data.
    pub fn is_empty(&self) -> bool {
        self.size_mm.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn in_memory_data_is_checked_like_a_file() {
        let cases: [(&str, Vec<f64>, Vec<f64>, &str); 4] = [
            ("lengths", vec![4.0, 8.0, 16.0], vec![0.0, 0.5], "passing"),
            (
                "order",
                vec![4.0, 16.0, 8.0],
                vec![0.0, 0.5, 1.0],
                "size_mm",
            ),
            (
                "decrease",
                vec![4.0, 8.0, 16.0],
                vec![0.0, 0.6, 0.5],
                "passing",
            ),
            (
                "nan",
                vec![4.0, f64::NAN, 16.0],
                vec![0.0, 0.5, 1.0],
                "size_mm",
            ),
        ];
        for (case, x, q, field) in cases {
            let err = SieveData::new("lab_sheet", x, q).unwrap_err().to_string();
            assert!(
                err.starts_with("lab_sheet: ") && err.contains(field),
                "{case}: {err}"
            );
        }
        let ok = SieveData::new("lab_sheet", vec![4.0, 8.0, 16.0], vec![0.0, 0.5, 1.0]).unwrap();
        assert_eq!(ok.len(), 3);
    }
}
