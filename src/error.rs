//! The library's error type. Errors about user files always name the file, the field and what
//! was expected, so a user can fix the input without reading the source.

use std::fmt::Display;
use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad content in a user-supplied file or argument.
    #[error("{file}: {field}: {expected}")]
    Input {
        file: String,
        field: String,
        expected: String,
    },
    /// The file could not be read or written.
    #[error("{file}: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// A request that cannot be satisfied (bad combination of options, impossible size, ...).
    #[error("{0}")]
    Invalid(String),
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn input(
        file: impl Display,
        field: impl Into<String>,
        expected: impl Into<String>,
    ) -> Self {
        Error::Input {
            file: file.to_string(),
            field: field.into(),
            expected: expected.into(),
        }
    }

    pub fn io(file: &Path, source: std::io::Error) -> Self {
        Error::Io {
            file: file.display().to_string(),
            source,
        }
    }

    pub fn invalid(msg: impl Into<String>) -> Self {
        Error::Invalid(msg.into())
    }
}

/// Reads a whole text file, mapping the failure to an error naming the file.
pub fn read_to_string(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::io(path, e))
}

/// Writes a file atomically (temporary file in the same directory, then rename), so an
/// interrupted run never leaves a half-written result behind.
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let file_name = path
        .file_name()
        .ok_or_else(|| Error::invalid(format!("{}: not a file path", path.display())))?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        file_name.to_string_lossy(),
        std::process::id()
    ));
    std::fs::write(&tmp, contents).map_err(|e| Error::io(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
}

/// Maps a csv crate error to an error naming the file and, for ragged rows, the line.
pub fn csv_error(file: &str, e: csv::Error) -> Error {
    let msg = e.to_string();
    match e.into_kind() {
        // Not Error::Io: its message already embeds the source, which `{:#}` would repeat.
        csv::ErrorKind::Io(_) => Error::invalid(format!("{file}: {msg}")),
        csv::ErrorKind::UnequalLengths {
            pos,
            expected_len,
            len,
        } => Error::input(
            file,
            format!("line {}", pos.map(|p| p.line()).unwrap_or(0)),
            format!("expected {expected_len} fields like the header, found {len}"),
        ),
        _ => Error::input(file, "CSV", msg),
    }
}

/// Opens a CSV file (fields trimmed) and returns the reader with its header.
pub fn csv_open(path: &Path) -> Result<(csv::Reader<std::fs::File>, Vec<String>)> {
    let file = path.display().to_string();
    let rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| csv_error(&file, e))?;
    with_header(&file, rdr)
}

/// CSV text already in memory, read like [`csv_open`] but with `#` comment lines skipped
/// (annotated data tables); `file` names the source in errors.
pub fn csv_open_str<'a>(text: &'a str, file: &str) -> Result<(csv::Reader<&'a [u8]>, Vec<String>)> {
    let rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(text.as_bytes());
    with_header(file, rdr)
}

fn with_header<R: std::io::Read>(
    file: &str,
    mut rdr: csv::Reader<R>,
) -> Result<(csv::Reader<R>, Vec<String>)> {
    let header = rdr
        .headers()
        .map_err(|e| csv_error(file, e))?
        .iter()
        .map(str::to_string)
        .collect();
    Ok((rdr, header))
}

/// One CSV field as a finite number; the error names the file, the line and the column.
pub fn csv_number(file: &str, line: u64, column: &str, field: &str) -> Result<f64> {
    let at = || format!("line {line}, column {column}");
    let v: f64 = field
        .parse()
        .map_err(|_| Error::input(file, at(), format!("expected a number, found \"{field}\"")))?;
    if !v.is_finite() {
        return Err(Error::input(
            file,
            at(),
            format!("expected a finite number, found {field}"),
        ));
    }
    Ok(v)
}
