//! Genetic-programming symbolic regression: readable equations fitted to tables.
//!
//! Trees are flat postfix arrays ([`program`]) over an alphabet of variables, constants and a
//! configurable function set ([`node`]); [`eval`] evaluates them in batches and scores them,
//! [`constants`] tunes their constants by Levenberg-Marquardt, [`engine`] evolves them, [`select`]
//! picks the returned equation from the Pareto front, and [`expr`] simplifies and prints it.

pub mod constants;
pub mod engine;
pub mod eval;
pub mod expr;
pub mod front;
pub mod grad;
pub mod node;
pub mod program;
pub mod select;

pub use engine::{fit, Config, FitResult, FrontEntry, Progress};
pub use eval::Dataset;
pub use node::Node;
