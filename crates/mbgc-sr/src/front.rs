//! A member of the Pareto front of complexity against error: what the engine returns and what
//! the selection rule picks from.

use super::program::Program;
use serde::{Deserialize, Serialize};

/// One member of the final Pareto front: the output scaling is folded into the tree and the tree
/// simplified, so `program` alone gives the prediction.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FrontEntry {
    /// The equation in postfix form, evaluated on the raw input columns.
    pub program: Program,
    /// Number of nodes of `program`: the complexity axis of the front.
    pub size: usize,
    /// Mean squared error over variance (1 - R^2) on the training rows.
    pub train_nmse: f64,
}
