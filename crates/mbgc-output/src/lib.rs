//! Where a command's report goes. Without `--json`, text goes to standard output. With `--json`,
//! standard output holds exactly one JSON object and nothing else, so `mbgc ... --json | jq .`
//! always works; the human-readable text goes to standard error (as do progress bars, always).
//!
//! Nothing here panics when standard output cannot be written (a full disk, `> /dev/full`):
//! [`write_stdout`] returns the error, and keeps the first one for [`finish`], which the command
//! line calls before it exits, so a report line that could not be written (through [`say!`],
//! which has nowhere to return an error to) still makes the command fail with a message.

#![warn(missing_docs)]

use std::io::Write as _;
use std::sync::Mutex;

use serde::Serialize;

/// Standard output could not be written (other than a closed pipe, which ends the process
/// quietly once SIGPIPE has its default action).
#[derive(Debug)]
pub struct StdoutError(pub std::io::Error);

impl std::fmt::Display for StdoutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // "No space left on device", not "... (os error 28)".
        let e = self.0.to_string();
        let e = match e.find(" (os error ") {
            Some(k) if e.ends_with(')') => &e[..k],
            _ => &e,
        };
        write!(f, "writing to standard output: {e}")
    }
}

impl std::error::Error for StdoutError {}

/// The first write error on standard output (its kind and message), kept for [`finish`]: an
/// `io::Error` is not `Clone`.
static FAILED: Mutex<Option<(std::io::ErrorKind, String)>> = Mutex::new(None);

fn failed() -> std::sync::MutexGuard<'static, Option<(std::io::ErrorKind, String)>> {
    FAILED.lock().unwrap_or_else(|p| p.into_inner())
}

fn record(e: &std::io::Error) {
    failed().get_or_insert_with(|| (e.kind(), e.to_string()));
}

/// Writes `args` to standard output (no newline added). A failure is returned and remembered
/// for [`finish`]; after one, nothing more is written (the output would have a hole).
pub fn write_stdout(args: std::fmt::Arguments) -> Result<(), StdoutError> {
    if let Some((kind, text)) = failed().as_ref() {
        return Err(StdoutError(std::io::Error::new(*kind, text.clone())));
    }
    let mut out = std::io::stdout().lock();
    out.write_fmt(args).map_err(|e| {
        record(&e);
        StdoutError(e)
    })
}

/// Ends the command's output: flushes standard output and returns the first write error of the
/// run (from [`write_stdout`], [`Output::line`] or [`Output::object`]), if any.
pub fn finish() -> Result<(), StdoutError> {
    if let Err(e) = std::io::stdout().lock().flush() {
        record(&e);
    }
    match failed().as_ref() {
        Some((kind, text)) => Err(StdoutError(std::io::Error::new(*kind, text.clone()))),
        None => Ok(()),
    }
}

/// `outln!("format", args...)`: one line on standard output, whatever `--json` says (as
/// `println!`, but a write error is returned as a [`StdoutError`] instead of a panic).
#[macro_export]
macro_rules! outln {
    () => {
        $crate::write_stdout(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::write_stdout(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `out!("format", args...)`: text on standard output without a newline (as `print!`, but a
/// write error is returned as a [`StdoutError`]).
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::write_stdout(format_args!($($arg)*))
    };
}

/// The destination of one command's report, chosen once by `--json`.
#[derive(Debug, Clone, Copy)]
pub struct Output {
    json: bool,
}

impl Output {
    /// Text to standard output, or (with `json`) the JSON object there and the text to standard
    /// error.
    pub fn new(json: bool) -> Output {
        Output { json }
    }

    /// Whether `--json` was given: standard output is reserved for the one JSON object.
    pub fn json(&self) -> bool {
        self.json
    }

    /// One line of the human-readable report. A write error on standard output is not returned
    /// but kept: [`finish`] reports it when the command ends.
    pub fn line(&self, args: std::fmt::Arguments) {
        if self.json {
            eprintln!("{args}");
        } else {
            let _ = outln!("{args}");
        }
    }

    /// The machine-readable report: printed (as the only thing on standard output) with `--json`.
    pub fn object(&self, value: &impl Serialize) -> anyhow::Result<()> {
        if self.json {
            outln!("{}", serde_json::to_string(value)?)?;
        }
        Ok(())
    }
}

/// `say!(out, "format", args...)`: one line of the report through [`Output::line`].
#[macro_export]
macro_rules! say {
    ($out:expr, $($arg:tt)*) => {
        $out.line(format_args!($($arg)*))
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_message_names_standard_output_and_the_reason_without_the_os_code() {
        let e = StdoutError(std::io::Error::from_raw_os_error(28));
        let text = e.to_string();
        assert!(text.starts_with("writing to standard output: "), "{text}");
        assert!(!text.contains("os error"), "{text}");
    }
}
