//! Draws from a weighted sample by systematic resampling.
//!
//! Of the standard schemes (multinomial, stratified, systematic) systematic resampling has the
//! smallest resampling noise: each sample is drawn floor(n w_i) or ceil(n w_i) times, never
//! more or less, so the draws follow the weights as closely as n draws can. Multinomial draws
//! (seed 003's weighted resampling between TMCMC stages) would repeat some samples and drop
//! others by chance, an extra spread the DEM runs would then carry into the band. With the
//! equally weighted samples TMCMC ends with, systematic resampling takes every (N/n)-th sample
//! from a seeded random start: draws spread over all of the chains rather than clustered in a few.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};

/// The most draws a propagation takes: each is at least one DEM run.
pub const MAX_DRAWS: usize = 100_000;

/// `n` sample indices drawn from `weights` by systematic resampling with a start seeded by
/// `seed`, in increasing order. Refuses `n` of 0 or above [`MAX_DRAWS`], and weights that are
/// negative, not finite or all 0.
pub fn systematic(weights: &[f64], n: usize, seed: u64) -> Result<Vec<usize>> {
    if n == 0 || n > MAX_DRAWS {
        return Err(Error::invalid(format!(
            "--draws {n}: expected 1 to {MAX_DRAWS} draws (each is a DEM run)"
        )));
    }
    if let Some(w) = weights.iter().find(|w| !(w.is_finite() && **w >= 0.0)) {
        return Err(Error::invalid(format!(
            "posterior weight {w}: expected finite weights >= 0"
        )));
    }
    // Scaled by the largest weight first, so that a sum of huge weights cannot overflow.
    let largest = weights.iter().fold(0.0f64, |m, w| m.max(*w));
    if largest <= 0.0 {
        return Err(Error::invalid("posterior weights: all 0, nothing to draw"));
    }
    let cumulative: Vec<f64> = weights
        .iter()
        .scan(0.0, |c, w| {
            *c += w / largest;
            Some(*c)
        })
        .collect();
    let total = cumulative[cumulative.len() - 1];
    let last_drawable = weights.iter().rposition(|w| *w > 0.0).unwrap_or(0);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let start: f64 = rng.random::<f64>();
    Ok((0..n)
        .map(|k| {
            let u = total * (start + k as f64) / n as f64;
            // The first sample whose cumulative weight exceeds u: never one of weight 0 (its
            // cumulative equals its predecessor's), and the last drawable one where rounding
            // leaves u at the very top.
            cumulative.partition_point(|c| *c <= u).min(last_drawable)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_sample_is_drawn_within_one_of_its_expected_count() {
        let w = [0.1, 0.0, 0.45, 0.05, 0.4];
        for seed in 0..50 {
            let d = systematic(&w, 40, seed).unwrap();
            assert_eq!(d.len(), 40);
            assert!(d.windows(2).all(|p| p[0] <= p[1]));
            for (i, wi) in w.iter().enumerate() {
                let count = d.iter().filter(|&&j| j == i).count() as f64;
                assert!((count - 40.0 * wi).abs() < 1.0 + 1e-9, "{seed} {i} {count}");
            }
        }
        assert_eq!(
            systematic(&w, 40, 3).unwrap(),
            systematic(&w, 40, 3).unwrap()
        );
    }

    #[test]
    fn equal_weights_give_evenly_spaced_distinct_samples() {
        let d = systematic(&[1.0; 2000], 100, 7).unwrap();
        assert!(d.windows(2).all(|p| p[1] - p[0] == 20), "{d:?}");
    }

    #[test]
    fn huge_weights_do_not_overflow_and_zero_weights_are_never_drawn() {
        let d = systematic(&[1e308, 1e308, 0.0], 4, 1).unwrap();
        assert_eq!(d.iter().filter(|&&i| i == 0).count(), 2, "{d:?}");
        assert_eq!(d.iter().filter(|&&i| i == 1).count(), 2, "{d:?}");
        for seed in 0..200 {
            let d = systematic(&[0.3, 0.0, 0.7, 0.0, 0.0], 7, seed).unwrap();
            assert!(d.iter().all(|&i| i == 0 || i == 2), "{d:?}");
        }
    }

    #[test]
    fn bad_requests_are_refused() {
        for (w, n, want) in [
            (vec![1.0], 0, "--draws 0"),
            (vec![1.0], MAX_DRAWS + 1, "--draws"),
            (vec![1.0, f64::NAN], 3, "finite weights"),
            (vec![1.0, -1.0], 3, "finite weights"),
            (vec![0.0, 0.0], 3, "all 0"),
        ] {
            let e = systematic(&w, n, 1).unwrap_err().to_string();
            assert!(e.contains(want), "{want}: {e}");
        }
    }
}
