//! Where the model fails and which physical effect is missing (`mbgc diagnose`).
//!
//! [`measurements`] reads a measurement set (several samples of one material); [`surrogate`]
//! wraps each model file; [`joint`] builds the joint problem of the set under a model class
//! (the set's own, or with one candidate effect switched on) and fits it, with [`covariance`]
//! sharing each model's error between the samples; [`structure`] tests the
//! residuals for offsets and trends; [`diagnosis`] runs it all and ranks the candidates;
//! [`build`] trains the local models it lacks around the material.

pub mod build;
pub mod covariance;
pub mod diagnosis;
pub mod joint;
pub mod measurements;
pub mod report;
pub mod structure;
pub mod surrogate;

pub use diagnosis::{diagnose, Diagnosis, Options, Parameter};
pub use measurements::MeasurementSet;
pub use surrogate::Surrogate;
