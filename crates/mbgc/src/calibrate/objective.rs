//! What the optimiser searches: a box of parameters and an objective with its gradient. The
//! calibration problem of one material and the joint problem of a measurement set
//! (`mbgc diagnose`) both implement it, so one L-BFGS driver serves both.

/// A smooth objective over a box of physical parameters, minimised by [`super::minimize`] from
/// starts in the unit cube. `Sync` because the starts run in parallel.
pub trait Objective: Sync {
    /// Lower bounds of the searched parameters (physical units).
    fn lower(&self) -> &[f64];
    /// Upper bounds of the searched parameters (physical units), each above its lower bound.
    fn upper(&self) -> &[f64];
    /// Value and gradient at `x`; `None` where the model is not finite.
    fn objective(&self, x: &[f64]) -> Option<(f64, Vec<f64>)>;
}
