//! Which DEM inputs matter for which response: seed 000's three levels (Yan et al. 2015) and
//! variance-based indices on saved metamodels.
//!
//! - Level 1, [`power_law`]: y = A x1^b1 ... fitted on the logarithms with every replicate, the
//!   exponents' 95 % intervals and the lack-of-fit test; [`flow_curve`]: the time-dependent
//!   flow rate FR0 / (1 + (t/K)^n) of a hopper discharge.
//! - Level 2, [`pca`]: principal components of the autoscaled matrix of contact-law
//!   sensitivities ([`sensitivity_matrix`]) joined with a bulk response.
//! - Level 3, [`norms`]: norms and cross-correlations of the sensitivity matrix over a grid of
//!   contact states ([`contact_derivatives`] gives the analytic derivatives).
//! - Beyond seed 000: [`sobol`] first and total indices of a metamodel over its own domain, and
//!   [`local`] sensitivities at a calibrated point.

pub mod contact_derivatives;
pub mod design_pca;
pub mod figures;
pub mod flow_curve;
pub mod least_squares;
pub mod local;
pub mod norms;
pub mod pca;
pub mod power_law;
pub mod sensitivity_matrix;
pub mod sobol;
