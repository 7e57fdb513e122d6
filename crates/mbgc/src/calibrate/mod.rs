//! Calibration: invert the metamodel for a material.
//!
//! [`problem`] turns a model and a material file into the search (free parameters, box,
//! measurements, constraints); [`optimize`] finds every distinct optimum by L-BFGS from many
//! starts and describes the solution set when the data cannot fix every parameter; [`session`]
//! runs both (and the posterior) for `mbgc calibrate` and returns what it reports; [`report`]
//! words that as the command's text.

pub mod bayes;
pub mod objective;
pub mod optimize;
pub mod problem;
pub mod report;
pub mod session;
pub mod tmcmc;

pub use objective::Objective;
pub use optimize::{calibrate, minimize, starts, Calibration, Optimum};
pub use problem::Problem;
