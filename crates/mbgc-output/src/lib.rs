//! Where a command's report goes. Without `--json`, text goes to standard output. With `--json`,
//! standard output holds exactly one JSON object and nothing else, so `mbgc ... --json | jq .`
//! always works; the human-readable text goes to standard error (as do progress bars, always).

#![warn(missing_docs)]

use serde::Serialize;

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

    /// One line of the human-readable report.
    pub fn line(&self, args: std::fmt::Arguments) {
        if self.json {
            eprintln!("{args}");
        } else {
            println!("{args}");
        }
    }

    /// The machine-readable report: printed (as the only thing on standard output) with `--json`.
    pub fn object(&self, value: &impl Serialize) -> anyhow::Result<()> {
        if self.json {
            println!("{}", serde_json::to_string(value)?);
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
