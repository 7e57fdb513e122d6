//! Which equation of the Pareto front is returned.
//!
//! Two rules. [`Selection::Best`] is PySR's "best": among the front members whose error is within
//! 1.5x of the most accurate one, take the one whose error fell most steeply per added node
//! relative to the next smaller member, i.e. the largest `-d ln(error) / d size`. Errors are
//! floored at 1e-24 (relative RMSE 1e-12, round-off), so that exact fits of different sizes tie
//! and the smallest one wins. It favours the knee of the front, which suits discovering a law.
//!
//! [`Selection::CrossValidation`] estimates each member's error on rows it was not fitted to:
//! K-fold, the constants re-tuned on each fold's training part (the structure keeps what the
//! whole search saw), and returns the member with the smallest held-out error. A metamodel that
//! calibration inverts needs accuracy at new points, and on a front whose error still falls with
//! size the knee is too small for that; where the larger trees only fit noise, their held-out
//! error rises and they are not taken.

use super::constants::Tuner;
use super::eval::{Dataset, Evaluator};
use super::front::FrontEntry;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Normalised error (1 - R^2) below which fits count as exact: 1e-24, a relative RMSE of 1e-12,
/// the level of double-precision round-off. Exact fits of different sizes then tie, and the
/// smallest wins.
pub const ERROR_FLOOR: f64 = 1e-24;
/// [`Selection::Best`] considers only members whose error is within this factor of the most
/// accurate one's (PySR's 1.5).
pub const ACCURACY_FACTOR: f64 = 1.5;
/// Folds of the cross-validation.
pub const FOLDS: usize = 5;
/// Levenberg-Marquardt steps re-tuning a member's constants on one fold's training part (they
/// start from the whole-data constants, so few are needed).
pub const FOLD_TUNE_ITERATIONS: usize = 30;

/// The rule that picks the returned equation from the front.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Selection {
    /// PySR's "best" (the knee); what model files without the field were made with.
    #[default]
    Best,
    /// The smallest K-fold cross-validated error.
    CrossValidation,
}

impl Selection {
    /// The value of `--select` that asks for this rule.
    pub fn flag(self) -> &'static str {
        match self {
            Selection::Best => "best",
            Selection::CrossValidation => "cv",
        }
    }

    /// The rule `--select` names.
    pub fn from_flag(s: &str) -> Result<Selection, String> {
        [Selection::Best, Selection::CrossValidation]
            .into_iter()
            .find(|r| r.flag() == s)
            .ok_or_else(|| format!("expected `best` or `cv`, got `{s}`"))
    }

    /// How the model file describes the rule.
    pub fn describe(self) -> String {
        match self {
            Selection::Best => format!(
                "PySR 'best': among front members with error within {ACCURACY_FACTOR}x of the most \
                 accurate, the largest -d ln(1 - R^2)/d size (errors floored at {ERROR_FLOOR:e})"
            ),
            Selection::CrossValidation => format!(
                "cross-validation: the smallest {FOLDS}-fold held-out error (1 - R^2), constants \
                 re-tuned on each fold's training rows ({FOLD_TUNE_ITERATIONS} Levenberg-Marquardt \
                 steps), folds a seeded shuffle"
            ),
        }
    }
}

/// Held-out normalised error (mean squared error over the variance of `data`) of every member:
/// `FOLDS`-fold, rows shuffled with `seed`, each member's constants re-tuned on the other folds.
/// A member that is invalid on any held-out row (a log of a negative at a point it was not fitted
/// to) gets infinity. `data` must have at least `2 * FOLDS` rows (the engine refuses fewer).
pub fn cross_validation_errors(
    front: &[FrontEntry],
    data: &Dataset,
    linear_scaling: bool,
    seed: u64,
) -> Vec<f64> {
    let n = data.rows();
    assert!(n >= 2 * FOLDS, "cross-validation needs {} rows", 2 * FOLDS);
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    let folds: Vec<(Dataset, Dataset)> = (0..FOLDS)
        .map(|f| {
            // Fold f holds the rows ranked [f n / K, (f + 1) n / K) in the shuffle.
            let in_fold = |rank: usize| rank * FOLDS / n == f;
            let pick = |held: bool| -> Vec<usize> {
                (0..n)
                    .filter(|&rank| in_fold(rank) == held)
                    .map(|rank| order[rank])
                    .collect()
            };
            (data.subset(&pick(false)), data.subset(&pick(true)))
        })
        .collect();
    let var = data.y_var().max(f64::MIN_POSITIVE);
    let mut tuner = Tuner::new();
    let mut eval = Evaluator::new();
    front
        .iter()
        .map(|e| {
            let mut sse = 0.0;
            for (train, held) in &folds {
                let mut p = e.program.clone();
                let sc = tuner.tune(&mut p, train, linear_scaling, FOLD_TUNE_ITERATIONS);
                if !sc.is_valid() {
                    return f64::INFINITY;
                }
                // Without linear scaling the score's map is the identity.
                let (a, b) = (sc.intercept, sc.slope);
                let mut out = vec![0.0; held.rows()];
                if !eval.eval(&p, &held.x, &mut out) {
                    return f64::INFINITY;
                }
                sse += out
                    .iter()
                    .zip(&held.y)
                    .map(|(o, y)| (y - a - b * o).powi(2))
                    .sum::<f64>();
            }
            let cv = sse / (n as f64 * var);
            if cv.is_finite() {
                cv
            } else {
                f64::INFINITY
            }
        })
        .collect()
}

/// Index of the member with the smallest cross-validated error (the smaller member on a tie).
pub fn pick_cross_validated(cv: &[f64]) -> usize {
    let mut best = 0;
    for (i, &e) in cv.iter().enumerate() {
        if e < cv[best] {
            best = i;
        }
    }
    best
}

/// Index of the returned equation in `front` (non-dominated, sorted by size, non-empty).
pub fn pick(front: &[FrontEntry]) -> usize {
    let err = |e: &FrontEntry| e.train_nmse.max(ERROR_FLOOR);
    let min = front.iter().map(err).fold(f64::INFINITY, f64::min);
    let mut best = (front.len() - 1, f64::NEG_INFINITY);
    for i in 0..front.len() {
        if err(&front[i]) > ACCURACY_FACTOR * min {
            continue;
        }
        let steep = if i == 0 {
            // Against a constant model (error 1 at size 1).
            -(err(&front[0]).ln() - 0.0) / (front[0].size as f64).max(1.0)
        } else {
            -(err(&front[i]).ln() - err(&front[i - 1]).ln())
                / (front[i].size as f64 - front[i - 1].size as f64).max(1.0)
        };
        if steep > best.1 {
            best = (i, steep);
        }
    }
    best.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::node::Node;
    use rand::RngExt;

    fn e(size: usize, nmse: f64) -> FrontEntry {
        FrontEntry {
            program: vec![],
            size,
            train_nmse: nmse,
        }
    }

    #[test]
    fn exact_fits_pick_the_smallest_exact_tree() {
        let f = [e(3, 0.2), e(5, 0.01), e(7, 1e-31), e(11, 1e-33)];
        assert_eq!(pick(&f), 2);
    }

    #[test]
    fn noisy_fits_pick_the_knee() {
        let f = [e(3, 0.05), e(5, 0.02), e(9, 0.0199), e(15, 0.0195)];
        assert_eq!(pick(&f), 1);
    }

    #[test]
    fn a_much_better_large_tree_wins_over_a_poor_knee() {
        let f = [e(3, 0.5), e(5, 0.1), e(21, 0.001)];
        assert_eq!(pick(&f), 2);
    }

    /// `c[d] x^d + ... + c[0]` in Horner form.
    fn polynomial(c: &[f64]) -> Vec<Node> {
        let mut p = vec![Node::Const(c[c.len() - 1])];
        for &ci in c[..c.len() - 1].iter().rev() {
            p.extend([Node::Var(0), Node::Mul, Node::Const(ci), Node::Add]);
        }
        p
    }

    /// Least-squares polynomial of degree `d` (the best its tree can do on `data`) as a front
    /// member.
    fn least_squares(data: &Dataset, d: usize) -> FrontEntry {
        let x = &data.x[0];
        let a = nalgebra::DMatrix::from_fn(x.len(), d + 1, |r, k| x[r].powi(k as i32));
        let y = nalgebra::DVector::from_column_slice(&data.y);
        let c = a.clone().svd(true, true).solve(&y, 1e-14).unwrap();
        let sse = (&a * &c - &y).norm_squared();
        let program = polynomial(c.as_slice());
        FrontEntry {
            size: program.len(),
            program,
            train_nmse: sse / (data.rows() as f64 * data.y_var()),
        }
    }

    #[test]
    fn cross_validation_passes_over_a_tree_that_fits_noise() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let n = 40;
        let x: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let y: Vec<f64> = x
            .iter()
            .map(|&x| 1.0 + 2.0 * x + 3.0 * x * x + 0.5 * (rng.random::<f64>() - 0.5) * 3.46)
            .collect();
        let data = Dataset::new(vec![x], y);
        let front: Vec<FrontEntry> = [1, 2, 12]
            .iter()
            .map(|&d| least_squares(&data, d))
            .collect();
        // The degree-12 tree is the most accurate on the training rows...
        assert!(front[2].train_nmse < front[1].train_nmse);
        assert!(front[1].train_nmse < front[0].train_nmse);
        // ...but on held-out rows the true degree wins, and the underfit line loses too.
        let cv = cross_validation_errors(&front, &data, true, 3);
        assert_eq!(pick_cross_validated(&cv), 1, "cv errors {cv:?}");
        assert!(
            cv.iter().zip(&front).all(|(c, e)| *c > e.train_nmse),
            "{cv:?}"
        );
        assert_eq!(cv, cross_validation_errors(&front, &data, true, 3));
    }

    #[test]
    fn cross_validation_prefers_the_larger_tree_while_the_error_still_falls() {
        // No noise: every added term is real, so held-out error keeps falling with size.
        let x: Vec<f64> = (0..60).map(|i| -1.0 + 2.0 * i as f64 / 59.0).collect();
        let y: Vec<f64> = x.iter().map(|&x| (1.5 * x).exp()).collect();
        let data = Dataset::new(vec![x], y);
        let front: Vec<FrontEntry> = [1, 2, 3, 4]
            .iter()
            .map(|&d| least_squares(&data, d))
            .collect();
        let cv = cross_validation_errors(&front, &data, true, 1);
        assert_eq!(pick_cross_validated(&cv), 3, "cv errors {cv:?}");
    }

    #[test]
    fn a_tree_invalid_on_held_out_rows_is_never_picked() {
        // log(x) is undefined at the held-out x <= 0 rows that are not all in one fold.
        let x: Vec<f64> = (0..30).map(|i| -0.5 + i as f64 / 10.0).collect();
        let y: Vec<f64> = x.iter().map(|&x| 2.0 * x).collect();
        let data = Dataset::new(vec![x], y);
        let line = least_squares(&data, 1);
        let log = FrontEntry {
            program: vec![Node::Var(0), Node::Log],
            size: 2,
            train_nmse: 0.5,
        };
        let cv = cross_validation_errors(&[log, line], &data, true, 1);
        assert!(cv[0].is_infinite());
        assert_eq!(pick_cross_validated(&cv), 1);
    }
}
