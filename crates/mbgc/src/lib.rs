//! mbgc: metamodel-first global calibration of DEM simulation parameters.
//!
//! The pipeline, stage by stage (see `ARCHITECTURE.md` in the project's shared notes and the
//! README): a parameter [`space`] is filled by a [`sampling`] design; particle size distributions
//! ([`psd`]) turn sieve data into the two PSD inputs of the metamodel; later stages simulate,
//! fit, and calibrate.

pub mod calibrate;
pub mod campaign;
pub mod diagnose;
pub mod error;
pub mod experiments;
pub mod export;
pub mod liggghts;
pub mod material;
pub mod metamodel;
pub mod model_table;
pub mod numeric;
pub mod outputs;
pub mod plot;
pub mod psd;
pub mod sampling;
pub mod sensitivity;
pub mod similarity;
pub mod space;
pub mod train;

pub use error::{Error, Result};

/// The DEM engine (the `mbgc-dem` crate), re-exported so one dependency reaches every stage.
pub use mbgc_dem as dem;
/// Genetic-programming symbolic regression (the `mbgc-sr` crate), re-exported likewise.
pub use mbgc_sr as gp;

// The test stand-ins under `tests/stand_ins/` name the library `mbgc::` as any user would; the
// unit tests and the `stand-ins` feature include them, so inside the crate that name must
// resolve too.
#[cfg(any(test, feature = "stand-ins"))]
extern crate self as mbgc;
