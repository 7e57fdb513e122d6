//! What the optimiser searches: a box of parameters and an objective with its gradient. The
//! calibration problem of one material and the joint problem of a measurement set
//! (`mbgc diagnose`) both implement it, so one L-BFGS driver serves both.

pub trait Objective: Sync {
    /// Lower bounds of the searched parameters (physical units).
    fn lower(&self) -> &[f64];
    fn upper(&self) -> &[f64];
    /// Value and gradient at `x`; `None` where the model is not finite.
    fn objective(&self, x: &[f64]) -> Option<(f64, Vec<f64>)>;
}
