//! The campaign table: one CSV line per finished run.
//!
//! Columns: `run_id,row,status,seed,model_class`, the inputs (design columns in design order, then `--set`
//! names), the experiment's responses, then `settled,steps,particles,wall_time_s,warnings,error`.
//! Lines are appended whole, so the only damage an interruption can do is an incomplete last
//! line, which [`read_table`] detects.

use std::path::Path;

use csv::{ByteRecord, StringRecord};

use super::plan::PlannedRun;
use crate::error::{Error, Result};
use crate::experiments::Outcome;

pub use super::columns::{
    columns, identity_len, is_campaign_header, DIAGNOSTIC_COLUMNS, DONE, FAILED, FIXED_COLUMNS,
    WALL_TIME_COLUMN,
};

/// One CSV line, `\n`-terminated, quoted by the csv crate where needed (commas, quotes, newlines).
pub fn csv_line<I, T>(fields: I) -> Result<Vec<u8>>
where
    I: IntoIterator<Item = T>,
    T: AsRef<[u8]>,
{
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    w.write_record(fields)
        .map_err(|e| Error::invalid(format!("formatting a CSV line: {e}")))?;
    w.into_inner()
        .map_err(|e| Error::invalid(format!("formatting a CSV line: {e}")))
}

/// Shortest text that reads back to the same f64 (`NaN`, `inf` included).
pub fn number(v: f64) -> String {
    format!("{v:?}")
}

/// The table line of a finished run. A failed run has empty responses and diagnostics and its
/// reason in `error`.
pub fn run_line(
    run: &PlannedRun,
    model_class: &str,
    backend: Option<&str>,
    responses: &[String],
    result: &std::result::Result<Outcome, String>,
) -> Result<Vec<u8>> {
    let mut f: Vec<String> = vec![
        run.run_id.clone(),
        run.row.to_string(),
        match result {
            Ok(_) => DONE.into(),
            Err(_) => FAILED.into(),
        },
        run.seed.to_string(),
        model_class.to_string(),
    ];
    if let Some(b) = backend {
        f.push(b.to_string());
    }
    f.extend(run.params.iter().map(|(_, v)| number(v)));
    match result {
        Ok(o) => {
            f.extend(
                responses
                    .iter()
                    .map(|r| o.get(r).map(number).unwrap_or_default()),
            );
            let d = &o.diagnostics;
            f.extend([
                d.settled.to_string(),
                d.steps.to_string(),
                d.particles.to_string(),
                format!("{:.6}", d.wall_time_s),
                d.warnings.join("; "),
                String::new(),
            ]);
        }
        Err(reason) => {
            f.extend(std::iter::repeat_n(String::new(), responses.len() + 5));
            f.push(reason.clone());
        }
    }
    csv_line(&f)
}

/// A table as found on disk.
#[derive(Debug, Clone)]
pub struct Table {
    /// Empty when the file holds no complete header line.
    pub header: Vec<String>,
    /// Complete data records with their file line.
    pub records: Vec<(u64, StringRecord)>,
    /// Bytes of the complete part (header and complete records).
    pub complete_len: u64,
    /// Bytes of an incomplete last line after it (an interrupted append), 0 if none.
    pub partial_len: u64,
}

/// Reads a table, setting aside an incomplete last line. The last line counts as complete only
/// if it ends with a newline and writing its fields back gives exactly its bytes, which catches a
/// cut inside a quoted multi-line field (there the cut can fall just after a newline).
pub fn read_table(path: &Path) -> Result<Table> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    // Lines ended by a lone CR (classic Mac OS): the reader would take the last completed run
    // for a cut line, and lines appended with LF would be glued to it. Refused rather than
    // rewritten: the table is the user's record of hours of runs.
    if bytes.contains(&b'\r') && !bytes.contains(&b'\n') {
        return Err(Error::input(
            &file,
            "line ends",
            "expected lines ended by LF or CR LF, found CR only (convert it, e.g. with `tr '\\r' \
             '\\n'`, then resume)",
        ));
    }
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(bytes.as_slice());
    let mut raw: Vec<ByteRecord> = Vec::new();
    for r in rdr.byte_records() {
        raw.push(r.map_err(|e| Error::input(&file, "CSV", e.to_string()))?);
    }
    let mut complete_len = bytes.len();
    if let Some(last) = raw.last() {
        let start = record_start(&bytes, last);
        let trim = |b: &[u8]| b.trim_ascii_end().to_vec();
        let whole = bytes.ends_with(b"\n")
            && (raw.len() == 1 || last.len() == raw[0].len())
            && trim(&bytes[start..]) == trim(&csv_line(last)?);
        if !whole {
            complete_len = start;
            raw.pop();
        }
    } else {
        complete_len = 0;
    }
    let mut records = raw.into_iter();
    let header: Vec<String> = match records.next() {
        None => Vec::new(),
        Some(h) => StringRecord::from_byte_record(h)
            .map_err(|_| Error::input(&file, "header", "expected UTF-8 text"))?
            .iter()
            .map(str::to_string)
            .collect(),
    };
    let mut out = Vec::new();
    for r in records {
        let line = record_line(&bytes, &r);
        if r.len() != header.len() {
            return Err(Error::input(
                &file,
                format!("line {line}"),
                format!(
                    "expected {} fields like the header, found {}",
                    header.len(),
                    r.len()
                ),
            ));
        }
        let r = StringRecord::from_byte_record(r)
            .map_err(|_| Error::input(&file, format!("line {line}"), "expected UTF-8 text"))?;
        out.push((line, r));
    }
    Ok(Table {
        header,
        records: out,
        complete_len: complete_len as u64,
        partial_len: (bytes.len() - complete_len) as u64,
    })
}

/// Where a record's text starts. The csv reader ends a record at the `\r` of a CRLF line end
/// (files from Windows, or git's autocrlf) and reports the next one as starting at the `\n`;
/// that byte still belongs to the line before.
fn record_start(bytes: &[u8], rec: &ByteRecord) -> usize {
    let start = rec.position().map_or(0, |p| p.byte() as usize);
    if start > 0 && bytes.get(start) == Some(&b'\n') && bytes[start - 1] == b'\r' {
        start + 1
    } else {
        start
    }
}

/// The file line a record starts on (1-based), counted as an editor counts it, CRLF or not.
fn record_line(bytes: &[u8], rec: &ByteRecord) -> u64 {
    let start = record_start(bytes, rec).min(bytes.len());
    1 + bytes[..start].iter().filter(|&&b| b == b'\n').count() as u64
}

/// The index of `name` in a header.
pub fn column(header: &[String], name: &str) -> Option<usize> {
    header.iter().position(|h| h == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table whose line ends were turned into CRLF (git's autocrlf) reads as the same table:
    /// every run complete, nothing to truncate, the lines numbered as an editor shows them.
    #[test]
    fn a_table_with_cr_only_line_ends_is_refused_not_cut() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cr.csv");
        std::fs::write(&path, "a,b\r1,2\r3,4\r").unwrap();
        let e = read_table(&path).unwrap_err().to_string();
        assert!(e.contains("line ends") && e.contains("CR only"), "{e}");
        assert_eq!(std::fs::read(&path).unwrap(), b"a,b\r1,2\r3,4\r");
    }

    #[test]
    fn a_crlf_table_is_read_whole_with_its_editor_line_numbers() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        let lf = "a,b\n1,2\n3,4\n5,\n";
        std::fs::write(&path, lf.replace('\n', "\r\n")).unwrap();
        let t = read_table(&path).unwrap();
        assert_eq!(t.partial_len, 0, "{t:?}");
        assert_eq!(t.records.len(), 3);
        let lines: Vec<u64> = t.records.iter().map(|r| r.0).collect();
        assert_eq!(lines, [2, 3, 4]);
        // An interrupted CRLF append: only its bytes are set aside, the line before keeps its
        // whole line end.
        std::fs::write(&path, lf.replace('\n', "\r\n") + "7").unwrap();
        let t = read_table(&path).unwrap();
        assert_eq!(t.records.len(), 3);
        assert_eq!(t.partial_len, 1);
        // The same lines in LF: the same numbers.
        std::fs::write(&path, lf).unwrap();
        let lines: Vec<u64> = read_table(&path)
            .unwrap()
            .records
            .iter()
            .map(|r| r.0)
            .collect();
        assert_eq!(lines, [2, 3, 4]);
    }
    use crate::campaign::Backend;
    use crate::experiments::{Diagnostics, ParamSet};

    fn run() -> PlannedRun {
        PlannedRun {
            row: 3,
            line: 5,
            run_id: "00000000000000ab".into(),
            seed: 42,
            params: ParamSet::from_pairs(&[("a", 0.1), ("b", -2.0)]),
        }
    }

    fn responses() -> Vec<String> {
        vec!["r1".into(), "r2".into()]
    }

    fn lines() -> (Vec<u8>, Vec<u8>, Vec<u8>) {
        let header = csv_line(columns(
            &["a".into(), "b".into()],
            &responses(),
            Backend::Embedded,
        ))
        .unwrap();
        let ok = Outcome {
            responses: vec![("r1".into(), 1.5), ("r2".into(), f64::NAN)],
            diagnostics: Diagnostics {
                settled: true,
                steps: 10,
                particles: 1,
                wall_time_s: 0.25,
                warnings: vec!["w1".into(), "w, 2".into()],
            },
        };
        let done = run_line(&run(), "hertz+mindlin+epsd2", None, &responses(), &Ok(ok)).unwrap();
        let failed = run_line(
            &run(),
            "hertz+mindlin+epsd2",
            None,
            &responses(),
            &Err("bad, \"very\"\nbad".to_string()),
        )
        .unwrap();
        (header, done, failed)
    }

    #[test]
    fn lines_have_the_documented_layout_and_escape_messages() {
        let (header, done, failed) = lines();
        assert_eq!(
            String::from_utf8(header).unwrap(),
            "run_id,row,status,seed,model_class,a,b,r1,r2,settled,steps,particles,wall_time_s,warnings,error\n"
        );
        assert_eq!(
            String::from_utf8(done).unwrap(),
            "00000000000000ab,3,done,42,hertz+mindlin+epsd2,0.1,-2.0,1.5,NaN,true,10,1,0.250000,\"w1; w, 2\",\n"
        );
        assert_eq!(
            String::from_utf8(failed).unwrap(),
            "00000000000000ab,3,failed,42,hertz+mindlin+epsd2,0.1,-2.0,,,,,,,,\"bad, \"\"very\"\"\nbad\"\n"
        );
    }

    fn table_of(bytes: &[u8]) -> Table {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        std::fs::write(&p, bytes).unwrap();
        read_table(&p).unwrap()
    }

    #[test]
    fn every_cut_of_the_last_line_is_detected_and_earlier_lines_survive() {
        let (header, done, failed) = lines();
        let mut file = header.clone();
        file.extend(&done);
        let whole = file.len();
        file.extend(&failed);
        let t = table_of(&file);
        assert_eq!((t.records.len(), t.partial_len), (2, 0));
        assert_eq!(&t.records[1].1[14], "bad, \"very\"\nbad");
        // Cut the failed line (whose quoted field holds a newline) at every byte.
        for cut in whole..file.len() {
            let t = table_of(&file[..cut]);
            assert_eq!(t.header.len(), 15);
            assert_eq!(t.records.len(), 1, "cut at {cut}");
            assert_eq!(t.complete_len as usize, whole, "cut at {cut}");
            assert_eq!(t.partial_len as usize, cut - whole);
        }
        // A cut header leaves nothing complete.
        let t = table_of(&header[..10]);
        assert!(t.header.is_empty() && t.partial_len == 10);
        assert!(table_of(b"").header.is_empty());
    }

    #[test]
    fn a_short_line_in_the_middle_is_an_error_naming_the_line() {
        let (header, done, _) = lines();
        let mut file = header;
        file.extend(b"x,y\n");
        file.extend(&done);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        std::fs::write(&p, &file).unwrap();
        let e = read_table(&p).unwrap_err().to_string();
        assert!(e.contains("t.csv: line 2"), "{e}");
    }
}
