//! The reference codes a study can compare mbgc with.

/// `--vs`: run the identical case in this code too.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Reference {
    Liggghts,
}
