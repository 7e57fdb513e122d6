//! Particle size distributions (PSD): sieve data, the three mass-based distribution families of
//! the MBGC paper, their least-squares fits, and drawing particle sets for a DEM by number.
//!
//! Sizes are in mm throughout; Q3 is the cumulative mass fraction passing (0..1).

pub mod distribution;
pub mod draw;
pub mod fit;
pub mod sieve;

pub use distribution::{
    phi, phi_inv, Basis, Distribution, Ggs, LogNormal, MassDistribution, Model, Rrsb,
};
pub use draw::{
    default_range, draw_by_number, sizes_drawn, truncated_q3, ParticleSet, DEFAULT_TRIM,
    GRID_CELLS, MAX_CELL_WIDTH,
};
pub use fit::{fit_all, fit_model, linearised_fit, score, FitReport, ModelFit};
pub use sieve::SieveData;
