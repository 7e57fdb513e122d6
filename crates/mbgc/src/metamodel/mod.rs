//! The saved global metamodel: one equation per response, the input scaling, the valid domain,
//! accuracy on training and test rows, the Pareto front, the settings, the seed and the data hash.
//!
//! A model file is JSON. Predictions evaluate the stored postfix program with the same evaluator
//! the fit used, so `mbgc predict`, the exported Rust and the fit agree to round-off.

mod build;
pub mod error_model;
mod fit_settings;
pub mod model;
pub mod noise;
mod rebase;
pub mod rigid_fit;
pub mod rigid_limit;
pub mod table;
mod training_table;

pub use build::{
    fit, regression_problems, Fit, ProblemRows, RegressionProblem, ResponseSplits, SplitValues,
};
pub use error_model::ErrorModel;
pub use fit_settings::FitSettings;
pub use model::*;
pub use rigid_limit::RigidLimit;
pub use training_table::TrainingTable;
