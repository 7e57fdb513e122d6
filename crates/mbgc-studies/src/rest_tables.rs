//! The tables the rest-rule studies share: the rows of a shear-box campaign table to rerun, and
//! the tab-separated tables a study appends its runs to as they finish (so a killed study
//! resumes where it stopped).

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::Path;

use anyhow::Context as _;

use mbgc::experiments::shear_box::ShearBox;
use mbgc::experiments::{Experiment, ParamSet};

/// A design row: its seed, its parameters and the recorded (angle, density).
pub(crate) type DesignRow = (u64, ParamSet, (f64, f64));

/// The design rows by `row`.
pub(crate) fn design_rows(path: &Path, sb: &ShearBox) -> anyhow::Result<BTreeMap<u64, DesignRow>> {
    let mut r = csv::Reader::from_path(path).with_context(|| path.display().to_string())?;
    let header = r.headers()?.clone();
    let col = |n: &str| {
        header
            .iter()
            .position(|c| c == n)
            .with_context(|| format!("{}: no column {n}", path.display()))
    };
    let (c_row, c_seed, c_status) = (col("row")?, col("seed")?, col("status")?);
    let (c_a, c_b) = (col("shear_angle")?, col("bulk_density")?);
    let mut names: Vec<&str> = sb.parameters();
    names.push("sigma_ln");
    let mut out = BTreeMap::new();
    for (k, rec) in r.records().enumerate() {
        let rec = rec.with_context(|| format!("{}: record {}", path.display(), k + 1))?;
        if &rec[c_status] != "done" {
            continue;
        }
        let num = |c: usize, what: &str| -> anyhow::Result<f64> {
            rec[c].parse().with_context(|| {
                format!(
                    "{}: record {}, column {what}: expected a number, found {:?}",
                    path.display(),
                    k + 1,
                    &rec[c]
                )
            })
        };
        let row: u64 = rec[c_row]
            .parse()
            .with_context(|| format!("{}: record {}: row", path.display(), k + 1))?;
        let seed: u64 = rec[c_seed]
            .parse()
            .with_context(|| format!("{}: record {}: seed", path.display(), k + 1))?;
        let mut pairs = Vec::new();
        for n in &names {
            pairs.push((n.to_string(), num(col(n)?, n)?));
        }
        out.insert(
            row,
            (
                seed,
                ParamSet::from_pairs(&pairs),
                (num(c_a, "shear_angle")?, num(c_b, "bulk_density")?),
            ),
        );
    }
    Ok(out)
}

pub(crate) fn append(path: &Path, header: &str, lines: &[String]) -> anyhow::Result<()> {
    let new = !path.exists();
    if let Some(d) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).with_context(|| d.display().to_string())?;
    }
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .with_context(|| path.display().to_string())?;
    let mut s = String::new();
    if new {
        s.push_str(header);
        s.push('\n');
    }
    for l in lines {
        s.push_str(l);
        s.push('\n');
    }
    f.write_all(s.as_bytes())
        .with_context(|| path.display().to_string())
}

/// The rows of a table this study wrote, each with `columns` fields; a row of another width
/// (a hand edit, a file of another study) is an error naming the file and the line.
pub(crate) fn read_tsv(path: &Path, columns: usize) -> anyhow::Result<Vec<Vec<String>>> {
    if !path.exists() {
        return Ok(Vec::new());
    }
    let text = std::fs::read_to_string(path).with_context(|| path.display().to_string())?;
    let mut rows = Vec::new();
    for (k, l) in text.lines().enumerate().skip(1) {
        if l.trim().is_empty() {
            continue;
        }
        let c: Vec<String> = l.split('\t').map(String::from).collect();
        if c.len() != columns {
            anyhow::bail!(
                "{}: line {}: expected {columns} tab-separated fields, found {}",
                path.display(),
                k + 1,
                c.len()
            );
        }
        rows.push(c);
    }
    Ok(rows)
}
