//! The library's error type. Errors about user files always name the file, the field and what
//! was expected, so a user can fix the input without reading the source.

use std::fmt::Display;
use std::marker::PhantomData;
use std::path::Path;

use serde::de::{Deserialize, Deserializer, MapAccess, Visitor};

/// Every failure of the library, by what the caller can do about it: fix an input, fix the file
/// system, change the request, or try another model.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad content in a user-supplied file or argument.
    #[error("{file}: {field}: {}", Error::expectation(expected))]
    Input {
        /// The file (or label of in-memory data) holding the bad value.
        file: String,
        /// Where in it: a TOML key path, a CSV column and row, a JSON field.
        field: String,
        /// What was expected there, and usually what was found.
        expected: String,
    },
    /// The file could not be read or written. The OS error is part of the message and not a
    /// `source`, or `{:#}` (anyhow's chain) would print it twice.
    #[error("{file}: {cause}")]
    Io {
        /// The path that failed.
        file: String,
        /// The operating system's error.
        cause: std::io::Error,
    },
    /// A request that cannot be satisfied (bad combination of options, impossible size, ...).
    #[error("{0}")]
    Invalid(String),
    /// A material's value (a fixed parameter, a PSD parameter, a search range, a dimensionless
    /// group) lies outside the domain the metamodel was fitted on, where its equations would
    /// extrapolate. A caller may try another model (`mbgc diagnose` does).
    #[error("{file}: {field}: {expected}")]
    OutOfDomain {
        /// The material file (or label).
        file: String,
        /// The field holding the value.
        field: String,
        /// The domain it should lie in, and the value found.
        expected: String,
    },
    /// No start of the optimiser converged: the model's equations are not finite anywhere in
    /// the search box.
    #[error("{0}")]
    NoSolution(String),
    /// The material's constraints cannot be met inside the search box.
    #[error("{0}")]
    Infeasible(String),
}

/// `Result` with the library's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// The engine reads no files: its refusals are requests it cannot run, as the library's are.
impl From<mbgc_dem::Error> for Error {
    fn from(e: mbgc_dem::Error) -> Self {
        match e {
            mbgc_dem::Error::Invalid(msg) => Error::Invalid(msg),
        }
    }
}

impl Error {
    /// An [`Error::Input`] naming the file, the field and what was expected.
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

    /// An [`Error::Io`] for `file`.
    pub fn io(file: &Path, source: std::io::Error) -> Self {
        Error::Io {
            file: file.display().to_string(),
            cause: source,
        }
    }

    /// The `expected` text of an input error as printed: a bare description of what belongs there
    /// ("a standard deviation > 0, got -1") gets the word that says it is the expectation, so that
    /// the message cannot read as a statement of what was found. Texts that say "expected"
    /// themselves, or state what is wrong ("missing; ..."), are printed as written.
    fn expectation(text: &str) -> String {
        let bare = ["a ", "an ", "at least ", "at most ", "[", "\""]
            .iter()
            .any(|p| text.starts_with(p))
            || text.starts_with(|c: char| c.is_ascii_digit());
        if bare && !text.to_ascii_lowercase().contains("expected") {
            format!("expected {text}")
        } else {
            text.to_string()
        }
    }

    /// An [`Error::OutOfDomain`] naming the file, the field and the domain expected.
    pub fn out_of_domain(
        file: impl Display,
        field: impl Into<String>,
        expected: impl Into<String>,
    ) -> Self {
        Error::OutOfDomain {
            file: file.to_string(),
            field: field.into(),
            expected: expected.into(),
        }
    }

    /// An [`Error::Invalid`] with `msg`, which should name the option and the allowed values.
    pub fn invalid(msg: impl Into<String>) -> Self {
        Error::Invalid(msg.into())
    }
}

/// Reads a whole text file, mapping the failure to an error naming the file.
pub fn read_to_string(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::io(path, e))
}

/// Writes `contents` to `path` so that readers see the old file or the new one, never a part:
/// a temporary file in the same directory (removed again on any error), synced, then renamed
/// over the target. A symlink is followed to the file it names, which is replaced; a target that
/// exists but is not a regular file (a directory, a FIFO, a device) is refused rather than
/// replaced by a regular file.
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<()> {
    let target = match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => {
            std::fs::canonicalize(path).map_err(|e| Error::io(path, e))?
        }
        Ok(_) => {
            return Err(Error::invalid(format!(
                "{}: exists and is not a regular file: expected a file path to write",
                path.display()
            )))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            if std::fs::symlink_metadata(path).is_ok() {
                return Err(Error::invalid(format!(
                    "{}: is a symlink to a missing file: expected a file path to write",
                    path.display()
                )));
            }
            path.to_path_buf()
        }
        Err(e) => return Err(Error::io(path, e)),
    };
    let dir = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let file_name = target
        .file_name()
        .ok_or_else(|| Error::invalid(format!("{}: not a file path", path.display())))?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    // Dropping the temporary file on an error path deletes it. A new file gets 0666 less the
    // umask, as `std::fs::write` would give it (tempfile's own default is 0600); a replaced file
    // keeps its mode (set below).
    let prefix = format!(".{}.", file_name.to_string_lossy());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder.tempfile_in(dir).map_err(|e| Error::io(dir, e))?;
    {
        use std::io::Write;
        let f = tmp.as_file_mut();
        f.write_all(contents)
            .and_then(|()| f.sync_all())
            .map_err(|e| Error::io(&target, e))?;
    }
    #[cfg(unix)]
    if let Ok(meta) = std::fs::metadata(&target) {
        let _ = tmp.as_file().set_permissions(meta.permissions());
    }
    tmp.persist(&target)
        .map_err(|e| Error::io(&target, e.error))?;
    Ok(())
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

/// A CSV reader over a file's bytes, held in memory.
pub type CsvReader = csv::Reader<std::io::Cursor<Vec<u8>>>;

/// Opens a CSV file (fields trimmed) and returns the reader with its header. A column name that
/// appears twice is refused: a reader looking it up would silently take the first.
pub fn csv_open(path: &Path) -> Result<(CsvReader, Vec<String>)> {
    let file = path.display().to_string();
    let mut bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    // CRLF line ends (Windows, git's autocrlf): the csv reader would number every line after
    // the first one short, so errors would point at the wrong line.
    if bytes.windows(2).any(|w| w == b"\r\n") {
        bytes = crlf_to_lf(&bytes);
    }
    let rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(std::io::Cursor::new(bytes));
    with_header(&file, rdr)
}

/// The bytes with every `\r\n` turned into `\n` (a lone `\r` is kept).
fn crlf_to_lf(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len());
    for (k, &b) in bytes.iter().enumerate() {
        if !(b == b'\r' && bytes.get(k + 1) == Some(&b'\n')) {
            out.push(b);
        }
    }
    out
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
    let header: Vec<String> = rdr
        .headers()
        .map_err(|e| csv_error(file, e))?
        .iter()
        .map(str::to_string)
        .collect();
    for (i, h) in header.iter().enumerate() {
        if !h.is_empty() && header[..i].contains(h) {
            return Err(Error::input(
                file,
                format!("column {h}"),
                format!(
                    "appears twice in the header (columns {} and {}): expected unique column names",
                    header.iter().position(|x| x == h).unwrap_or(0) + 1,
                    i + 1
                ),
            ));
        }
    }
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

/// Reads a TOML document into the serde type `T` (which should `deny_unknown_fields` and leave
/// required fields optional, so that a missing one is reported by the caller's validation with a
/// message of its own). A syntax error names the line and column; an unknown key or a value of
/// the wrong type names the dotted path of the field, found by locating the error's span in the
/// document, because toml's error keeps its key path private.
pub fn from_toml<T: serde::de::DeserializeOwned>(text: &str, file: &str) -> Result<T> {
    let doc = toml::de::DeTable::parse(text).map_err(|e| {
        let at = e
            .span()
            .map(|s| {
                let (line, column) = line_column(text, s.start);
                format!(" at line {line}, column {column}")
            })
            .unwrap_or_default();
        Error::input(
            file,
            "TOML syntax",
            format!("valid TOML{at} ({})", e.message().trim_end()),
        )
    })?;
    toml::from_str(text).map_err(|e: toml::de::Error| {
        let mut path = String::new();
        if let Some(s) = e.span() {
            path_at(doc.get_ref(), s.start, &mut String::new(), &mut path);
        }
        if path.is_empty() {
            path = match e.span() {
                Some(s) => {
                    let (line, column) = line_column(text, s.start);
                    format!("line {line}, column {column}")
                }
                None => "TOML".into(),
            };
        }
        Error::input(file, path, serde_message(e.message()))
    })
}

/// 1-based line and column (in characters) of a byte offset.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..text.floor_char_boundary(offset.min(text.len()))];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (
        before.matches('\n').count() + 1,
        before[line_start..].chars().count() + 1,
    )
}

/// Sets `best` to the path of the innermost key or value whose span holds `at`. Every entry is
/// visited, not only those whose parent's span holds `at`: a `[table]` header and its keys lie
/// apart in the text.
fn path_at(table: &toml::de::DeTable, at: usize, prefix: &mut String, best: &mut String) {
    for (k, v) in table {
        let len = prefix.len();
        if !prefix.is_empty() {
            prefix.push('.');
        }
        prefix.push_str(k.get_ref());
        if (k.span().contains(&at) || v.span().contains(&at)) && prefix.len() > best.len() {
            best.clone_from(prefix);
        }
        value_path_at(v, at, prefix, best);
        prefix.truncate(len);
    }
}

fn value_path_at(
    v: &toml::Spanned<toml::de::DeValue>,
    at: usize,
    prefix: &mut String,
    best: &mut String,
) {
    match v.get_ref() {
        toml::de::DeValue::Table(t) => path_at(t, at, prefix, best),
        toml::de::DeValue::Array(a) => {
            for (i, item) in a.iter().enumerate() {
                let len = prefix.len();
                prefix.push_str(&format!("[{i}]"));
                if item.span().contains(&at) && prefix.len() > best.len() {
                    best.clone_from(prefix);
                }
                value_path_at(item, at, prefix, best);
                prefix.truncate(len);
            }
        }
        _ => {}
    }
}

/// serde's wording recast as the crate's "expected ..., found ..." and "unknown key" messages.
fn serde_message(msg: &str) -> String {
    let msg = msg.trim_end();
    if let Some(rest) = msg.strip_prefix("unknown field `") {
        return match rest.split_once(", expected ") {
            Some((_, keys)) => format!(
                "unknown key; expected one of: {}",
                keys.trim_start_matches("one of ")
                    .replace('`', "")
                    .replace(" or ", ", ")
            ),
            None => "unknown key; this table takes none".into(),
        };
    }
    if let Some((found, expected)) = msg
        .strip_prefix("invalid type: ")
        .and_then(|r| r.split_once(", expected "))
    {
        let expected = match expected {
            "f64" => "a number",
            "a sequence" => "a list",
            e => e,
        };
        return format!("expected {expected}, found {found}");
    }
    msg.to_string()
}

/// The entries of a TOML table in file order, for tables whose keys are names the user chooses
/// (parameters, responses), where order matters and no struct can list the keys.
#[derive(Debug, Clone, PartialEq)]
pub struct Entries<T>(pub Vec<(String, T)>);

impl<T> Default for Entries<T> {
    fn default() -> Self {
        Entries(Vec::new())
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Entries<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct EntriesVisitor<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for EntriesVisitor<T> {
            type Value = Entries<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a table")
            }
            fn visit_map<A: MapAccess<'de>>(
                self,
                mut map: A,
            ) -> std::result::Result<Entries<T>, A::Error> {
                let mut entries = Vec::with_capacity(map.size_hint().unwrap_or(0));
                while let Some(entry) = map.next_entry::<String, T>()? {
                    entries.push(entry);
                }
                Ok(Entries(entries))
            }
        }
        d.deserialize_map(EntriesVisitor(PhantomData))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bare_expectation_says_it_is_one() {
        let e = Error::input(
            "m.toml",
            "measured.x.sd",
            "a standard deviation > 0, got -1",
        );
        assert_eq!(
            e.to_string(),
            "m.toml: measured.x.sd: expected a standard deviation > 0, got -1"
        );
        let e = Error::input("m.json", "version", "1, got 99");
        assert_eq!(e.to_string(), "m.json: version: expected 1, got 99");
        let e = Error::input("m.json", "format", "\"mbgc-metamodel\", got \"x\"");
        assert!(e
            .to_string()
            .contains("format: expected \"mbgc-metamodel\""));
        for kept in [
            "missing; add a column",
            "not a response of the model; expected one of: a, b",
            "an x; expected y",
        ] {
            assert!(Error::input("f", "k", kept).to_string().ends_with(kept));
        }
    }

    /// Errors in a CRLF file name the line an editor shows, as in an LF file.
    #[test]
    fn crlf_files_report_the_lines_an_editor_shows() {
        let dir = tempfile::tempdir().unwrap();
        for (name, end) in [("lf.csv", "\n"), ("crlf.csv", "\r\n")] {
            let path = dir.path().join(name);
            std::fs::write(&path, ["x,y", "1,2", "3,4", "5,6"].join(end) + end).unwrap();
            let (mut rdr, header) = csv_open(&path).unwrap();
            assert_eq!(header, ["x", "y"]);
            let lines: Vec<u64> = rdr
                .records()
                .map(|r| r.unwrap().position().unwrap().line())
                .collect();
            assert_eq!(lines, [2, 3, 4], "{name}");
        }
    }

    fn leftovers(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp"))
            .collect()
    }

    #[test]
    fn atomic_write_replaces_a_file_and_leaves_no_temporary_behind() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.csv");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        // A replaced file keeps its mode (a private result stays private).
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o600)).unwrap();
            write_atomic(&p, b"three").unwrap();
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, 0o600);
        }
        assert!(leftovers(dir.path()).is_empty());
    }

    #[cfg(unix)]
    #[test]
    fn atomic_write_refuses_devices_fifos_and_directories_and_follows_symlinks() {
        use std::os::unix::fs::FileTypeExt;
        // A device node stays a device node.
        let e = write_atomic(Path::new("/dev/null"), b"x")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a regular file"), "{e}");
        assert!(std::fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device());

        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            let e = write_atomic(&fifo, b"x").unwrap_err().to_string();
            assert!(e.contains("not a regular file"), "{e}");
            assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
        }
        let e = write_atomic(dir.path(), b"x").unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");

        // A symlink to a file: the file gets the new contents, the link stays a link.
        let real = dir.path().join("real.txt");
        std::fs::write(&real, "old").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        // A dangling symlink is refused, not replaced.
        let dangling = dir.path().join("dangling.txt");
        std::os::unix::fs::symlink(dir.path().join("missing"), &dangling).unwrap();
        assert!(write_atomic(&dangling, b"x").is_err());
        assert!(leftovers(dir.path()).is_empty());
    }

    #[test]
    fn a_failed_atomic_write_leaves_nothing_behind() {
        let dir = tempfile::tempdir().unwrap();
        // The parent "directory" is a file: nothing can be created below it.
        let blocker = dir.path().join("blocker");
        std::fs::write(&blocker, "x").unwrap();
        assert!(write_atomic(&blocker.join("out.csv"), b"x").is_err());
        assert!(leftovers(dir.path()).is_empty());
        assert_eq!(std::fs::read(&blocker).unwrap(), b"x");
    }

    #[test]
    fn csv_with_a_duplicated_column_is_refused_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        std::fs::write(&p, "a,b,a\n1,2,3\n").unwrap();
        let e = csv_open(&p).err().unwrap().to_string();
        assert!(e.contains("t.csv") && e.contains("column a"), "{e}");
        assert!(e.contains("columns 1 and 3"), "{e}");
    }
}
