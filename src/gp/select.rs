//! Which equation of the Pareto front is returned.
//!
//! The rule is PySR's "best": among the front members whose error is within 1.5x of the most
//! accurate one, take the one whose error fell most steeply per added node relative to the next
//! smaller member, i.e. the largest `-d ln(error) / d size`. Errors are floored at 1e-24 (relative
//! RMSE 1e-12, round-off), so that exact fits of different sizes tie and the smallest one wins.

use super::front::FrontEntry;

pub const ERROR_FLOOR: f64 = 1e-24;
pub const ACCURACY_FACTOR: f64 = 1.5;

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
}
