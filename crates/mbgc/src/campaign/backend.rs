//! The simulation backend of a campaign: mbgc's embedded DEM, or LIGGGHTS 3.8 run on decks that
//! mbgc writes (`--backend liggghts`). The backend is part of a run's identity: the same row run
//! by two codes is two runs, and a table holds the runs of one backend.

use std::fmt;

use crate::error::{Error, Result};

/// The DEM code that runs a campaign's rows.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Backend {
    /// mbgc's own DEM engine.
    #[default]
    Embedded,
    /// LIGGGHTS-PUBLIC 3.8 (Debian's `liggghts`), one deck per run.
    Liggghts,
}

impl Backend {
    /// The names `--backend` accepts, in [`Backend::label`] spelling.
    pub const NAMES: [&'static str; 2] = ["embedded", "liggghts"];

    /// `--backend NAME`.
    pub fn parse(s: &str) -> Result<Backend> {
        match s.trim() {
            "embedded" => Ok(Backend::Embedded),
            "liggghts" => Ok(Backend::Liggghts),
            other => Err(Error::invalid(format!(
                "--backend {other}: unknown backend (known: {})",
                Self::NAMES.join(", ")
            ))),
        }
    }

    /// The name on the command line and in tables and run ids.
    pub fn label(self) -> &'static str {
        match self {
            Backend::Embedded => "embedded",
            Backend::Liggghts => "liggghts",
        }
    }

    /// Whether tables and run ids name the backend. The embedded backend is implied, so that
    /// tables and run ids written before backends existed stay valid.
    pub fn is_recorded(self) -> bool {
        self != Backend::Embedded
    }
}

/// The `backend` field of a table line: the backend, and the MPI processes when more than one
/// (`liggghts-np2`). LIGGGHTS repeats a run exactly on the same count only, so the table itself
/// says which count made each line, and a resume or merge with another count is refused even
/// without the sidecar.
pub fn table_field(backend: Backend, mpi: Option<usize>) -> String {
    match mpi {
        Some(n) if n > 1 => format!("{}-np{n}", backend.label()),
        _ => backend.label().to_string(),
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_ones_are_refused_with_the_list() {
        for n in Backend::NAMES {
            assert_eq!(Backend::parse(n).unwrap().label(), n);
        }
        let e = Backend::parse("lammps").unwrap_err().to_string();
        assert!(
            e.contains("--backend lammps") && e.contains("liggghts"),
            "{e}"
        );
        assert!(!Backend::Embedded.is_recorded() && Backend::Liggghts.is_recorded());
        assert_eq!(table_field(Backend::Liggghts, None), "liggghts");
        assert_eq!(table_field(Backend::Liggghts, Some(1)), "liggghts");
        assert_eq!(table_field(Backend::Liggghts, Some(2)), "liggghts-np2");
    }
}
