//! The library's error type. Errors about user files always name the file, the field and what
//! was expected, so a user can fix the input without reading the source.

use std::fmt::Display;
use std::marker::PhantomData;
use std::path::Path;

use serde::de::{Deserialize, Deserializer, MapAccess, Visitor};

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

/// Opens a CSV file (fields trimmed) and returns the reader with its header. A column name that
/// appears twice is refused: a reader looking it up would silently take the first.
pub fn csv_open(path: &Path) -> Result<(csv::Reader<std::fs::File>, Vec<String>)> {
    let file = path.display().to_string();
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| csv_error(&file, e))?;
    let header: Vec<String> = rdr
        .headers()
        .map_err(|e| csv_error(&file, e))?
        .iter()
        .map(str::to_string)
        .collect();
    for (i, h) in header.iter().enumerate() {
        if !h.is_empty() && header[..i].contains(h) {
            return Err(Error::input(
                &file,
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
