//! The tables the rest-rule studies share: the rows of a shear-box campaign table to rerun, and
//! the tab-separated tables a study appends its runs to as they finish (so a killed study
//! resumes where it stopped).

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;

use mbgc::dem::contact::ModelClass;
use mbgc::experiments::shear_box::{RestRule, ShearBox};
use mbgc::experiments::{Experiment, ParamSet};

/// The shear box a campaign table's runs were made with, from its sidecar
/// (`<table>.meta.json`: the experiment, the model class and the box scale), under `rest`: the
/// box a rerun of its rows needs. A table of another experiment, or without its sidecar, is
/// refused by name.
pub(crate) fn design_box(table: &Path, rest: RestRule) -> anyhow::Result<ShearBox> {
    let meta = PathBuf::from(format!("{}.meta.json", table.display()));
    let text = std::fs::read_to_string(&meta).with_context(|| {
        format!(
            "{}: the campaign table's sidecar, which names its experiment, model class and box \
             scale",
            meta.display()
        )
    })?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| meta.display().to_string())?;
    let experiment = v["experiment"].as_str().unwrap_or("");
    if experiment != "shear-box" {
        anyhow::bail!(
            "{}: experiment: expected shear-box (the rest rules are the shear box's), found {:?}",
            meta.display(),
            v["experiment"]
        );
    }
    let class = match v["model_class"].as_str() {
        Some(c) => {
            ModelClass::parse(c).with_context(|| format!("{}: model_class", meta.display()))?
        }
        None => ModelClass::default(),
    };
    let default = ShearBox::default();
    let box_scale = match &v["box_scale"] {
        serde_json::Value::Null => default.box_scale,
        x => x.as_f64().with_context(|| {
            format!(
                "{}: box_scale: expected a number or null, found {x}",
                meta.display()
            )
        })?,
    };
    Ok(ShearBox {
        class,
        box_scale,
        rest,
        ..default
    })
}

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

/// Appends `lines` to a study's table, with `header` first if the file is new or empty. A last
/// line cut short by a killed write (no final newline) is cut off first: its run is done again,
/// and a truncated number is never read as a whole one ([`read_tsv`] ignores it too).
pub(crate) fn append(path: &Path, header: &str, lines: &[String]) -> anyhow::Result<()> {
    if let Some(d) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).with_context(|| d.display().to_string())?;
    }
    let existing = std::fs::read(path).unwrap_or_default();
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .with_context(|| path.display().to_string())?;
    let whole = existing
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    if whole < existing.len() {
        f.set_len(whole as u64)
            .with_context(|| format!("{}: cutting off a partial last line", path.display()))?;
    }
    let mut s = String::new();
    if whole == 0 {
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

/// The rows of a table a study wrote, each with `columns` fields, under the header `header`. A
/// row of another width (a hand edit, a file of another study) or another header is an error
/// naming the file and the line; a last line without its newline (a write killed midway) is
/// dropped with a warning, and its run is done again.
pub(crate) fn read_tsv(path: &Path, header: &str) -> anyhow::Result<Vec<Vec<String>>> {
    if !path.exists() {
        return Ok(Vec::new());
    }
    let columns = header.split('\t').count();
    let text = std::fs::read_to_string(path).with_context(|| path.display().to_string())?;
    let complete = match text.rfind('\n') {
        Some(end) if end + 1 < text.len() => {
            eprintln!(
                "warning: {}: the last line has no newline (a write cut short); ignored",
                path.display()
            );
            &text[..=end]
        }
        Some(_) => text.as_str(),
        None if text.is_empty() => return Ok(Vec::new()),
        None => anyhow::bail!(
            "{}: no complete line (expected the header {header:?})",
            path.display()
        ),
    };
    let mut lines = complete.lines();
    let first = lines.next().unwrap_or_default();
    if first != header {
        anyhow::bail!(
            "{}: line 1: expected the header {header:?}, found {first:?}",
            path.display()
        );
    }
    let mut rows = Vec::new();
    for (k, l) in lines.enumerate() {
        if l.trim().is_empty() {
            continue;
        }
        let c: Vec<String> = l.split('\t').map(String::from).collect();
        if c.len() != columns {
            anyhow::bail!(
                "{}: line {}: expected {columns} tab-separated fields, found {}",
                path.display(),
                k + 2,
                c.len()
            );
        }
        rows.push(c);
    }
    Ok(rows)
}

/// Runs `f` on every item of `todo`, in order, `jobs` at a time (one thread each), and returns
/// the failures as text (each prefixed by `label` of its item); `f` gets a lock to hold while it
/// appends its line to a shared table.
pub(crate) fn run_queue<T: Send>(
    jobs: usize,
    todo: Vec<T>,
    label: impl Fn(&T) -> String + Sync,
    f: impl Fn(&T, &std::sync::Mutex<()>) -> anyhow::Result<()> + Sync,
) -> Vec<String> {
    use std::sync::Mutex;
    let queue = Mutex::new(todo.into_iter().rev().collect::<Vec<_>>());
    let write = Mutex::new(());
    let failures = Mutex::new(Vec::<String>::new());
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| {
                while let Some(item) = queue.lock().ok().and_then(|mut q| q.pop()) {
                    if let Err(e) = f(&item, &write) {
                        if let Ok(mut v) = failures.lock() {
                            v.push(format!("{}{e:#}", label(&item)));
                        }
                    }
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap_or_default();
    for f in &failures {
        eprintln!("failed: {f}");
    }
    failures
}

/// The outcome columns that end a shear-box row of the stiffness tables: shear angle, bulk
/// density, settled (0/1), steps, particles and wall seconds, tab-separated.
pub(crate) fn outcome_columns(o: &mbgc::experiments::Outcome) -> String {
    format!(
        "{:.6}\t{:.4}\t{}\t{}\t{}\t{:.3}",
        o.get("shear_angle").unwrap_or(f64::NAN),
        o.get("bulk_density").unwrap_or(f64::NAN),
        u8::from(o.diagnostics.settled),
        o.diagnostics.steps,
        o.diagnostics.particles,
        o.diagnostics.wall_time_s
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_cut_short_is_dropped_and_the_next_append_stays_whole() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.tsv");
        append(&p, "a\tb", &["1\t2".into()]).unwrap();
        // A write killed midway.
        let mut f = std::fs::OpenOptions::new().append(true).open(&p).unwrap();
        f.write_all(b"3\t").unwrap();
        assert_eq!(read_tsv(&p, "a\tb").unwrap(), vec![vec!["1", "2"]]);
        append(&p, "a\tb", &["5\t6".into()]).unwrap();
        // The fragment is gone, the rows whole.
        assert_eq!(
            read_tsv(&p, "a\tb").unwrap(),
            vec![vec!["1", "2"], vec!["5", "6"]]
        );
        std::fs::write(&p, "a\tb\n1\t2\t3\n").unwrap();
        let e = read_tsv(&p, "a\tb").unwrap_err().to_string();
        assert!(e.contains("line 2"), "{e}");
        // An empty file gets its header.
        let q = dir.path().join("e.tsv");
        std::fs::write(&q, "").unwrap();
        append(&q, "a\tb", &["1\t2".into()]).unwrap();
        assert_eq!(read_tsv(&q, "a\tb").unwrap().len(), 1);
        let e = read_tsv(&q, "x\ty").unwrap_err().to_string();
        assert!(e.contains("header"), "{e}");
    }
}
