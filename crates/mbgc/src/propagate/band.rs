//! The robust prediction of a quantity: its statistics over the posterior draws (seed 003's
//! robust mean and variance, Eqs. 11-12, with the draws standing in for the posterior), and,
//! when each draw was run with several seeds, the parametric spread apart from the run-to-run
//! scatter.

use crate::numeric::{mean_sd, quantile};

/// A quantity's band over the draws.
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    /// Draws with at least one finite value.
    pub draws: usize,
    /// Finite values over all draws and seeds.
    pub runs: usize,
    /// Runs without a finite value (failed, or the experiment measured nothing).
    pub missing: usize,
    /// Robust mean: the mean of the draws' means (every draw weighs the same, seed 003's
    /// Eq. 11 with the draws as equally weighted posterior samples).
    pub mean: f64,
    /// Robust standard deviation of one run at a posterior draw: with one seed per draw the sd
    /// of the values; with replicates sqrt(parametric_sd^2 + scatter_sd^2), so it is never
    /// below either part.
    pub sd: f64,
    /// 5 %, 50 % and 95 % quantiles over every run.
    pub q05: f64,
    /// Median.
    pub q50: f64,
    /// 95 % quantile.
    pub q95: f64,
    /// Coefficient of variation sd / |mean|.
    pub cov: f64,
    /// With replicate seeds: the run-to-run scatter of one draw (pooled within-draw sd).
    pub scatter_sd: Option<f64>,
    /// With replicate seeds: the spread the posterior alone causes, sqrt(var of the draw means
    /// - scatter^2 / seeds), 0 when the scatter explains all of it.
    pub parametric_sd: Option<f64>,
}

impl Band {
    /// The band of `per_draw[d]`, the values of draw d's runs (NaN for a run without one).
    /// `None` when no run has a finite value.
    pub fn of(per_draw: &[Vec<f64>]) -> Option<Band> {
        let finite: Vec<Vec<f64>> = per_draw
            .iter()
            .map(|v| v.iter().copied().filter(|x| x.is_finite()).collect())
            .filter(|v: &Vec<f64>| !v.is_empty())
            .collect();
        let all: Vec<f64> = finite.iter().flatten().copied().collect();
        if all.is_empty() {
            return None;
        }
        let total: usize = per_draw.iter().map(Vec::len).sum();
        let means: Vec<f64> = finite.iter().map(|v| mean_sd(v).0).collect();
        let (mean, _) = mean_sd(&means);
        let replicated: Vec<&Vec<f64>> = finite.iter().filter(|v| v.len() > 1).collect();
        let (scatter_sd, parametric_sd) = if replicated.is_empty() || finite.len() < 2 {
            (None, None)
        } else {
            // Pooled within-draw variance: each draw's sum of squares over its degrees of
            // freedom.
            let (ss, dof) = replicated.iter().fold((0.0, 0usize), |(ss, dof), v| {
                let (m, _) = mean_sd(v);
                (
                    ss + v.iter().map(|x| (x - m).powi(2)).sum::<f64>(),
                    dof + v.len() - 1,
                )
            });
            let scatter = (ss / dof as f64).sqrt();
            // The variance of a draw's mean holds scatter^2 / n_d of run scatter: on average
            // over the draws, scatter^2 times the mean of 1 / n_d.
            let inverse_seeds =
                finite.iter().map(|v| 1.0 / v.len() as f64).sum::<f64>() / finite.len() as f64;
            let (_, sd_means) = mean_sd(&means);
            let parametric = (sd_means.powi(2) - scatter.powi(2) * inverse_seeds)
                .max(0.0)
                .sqrt();
            (Some(scatter), Some(parametric))
        };
        let sd = match (scatter_sd, parametric_sd) {
            (Some(s), Some(p)) => s.hypot(p),
            _ => mean_sd(&all).1,
        };
        Some(Band {
            draws: finite.len(),
            runs: all.len(),
            missing: total - all.len(),
            mean,
            sd,
            q05: quantile(&all, 0.05),
            q50: quantile(&all, 0.5),
            q95: quantile(&all, 0.95),
            cov: sd / mean.abs(),
            scatter_sd,
            parametric_sd,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::StandardNormal;

    #[test]
    fn statistics_over_every_run_and_nans_counted_as_missing() {
        let b = Band::of(&[vec![1.0], vec![2.0, f64::NAN], vec![3.0], vec![f64::NAN]]).unwrap();
        assert_eq!((b.draws, b.runs, b.missing), (3, 3, 2));
        assert_eq!((b.mean, b.sd, b.q50), (2.0, 1.0, 2.0));
        assert!((b.q05 - 1.1).abs() < 1e-12 && (b.q95 - 2.9).abs() < 1e-12);
        assert_eq!(b.cov, 0.5);
        assert_eq!(b.scatter_sd, None);
        assert!(Band::of(&[vec![f64::NAN]]).is_none());
    }

    /// Draw means of sd 2 and run scatter of sd 1, 4 seeds per draw: both are recovered.
    #[test]
    fn replicate_seeds_separate_the_parametric_spread_from_the_scatter() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut normal = || rng.sample::<f64, _>(StandardNormal);
        let per_draw: Vec<Vec<f64>> = (0..4000)
            .map(|_| {
                let m = 10.0 + 2.0 * normal();
                (0..4).map(|_| m + normal()).collect()
            })
            .collect();
        let b = Band::of(&per_draw).unwrap();
        let (scatter, parametric) = (b.scatter_sd.unwrap(), b.parametric_sd.unwrap());
        assert!((scatter - 1.0).abs() < 0.03, "{scatter}");
        assert!((parametric - 2.0).abs() < 0.1, "{parametric}");
        assert!((b.sd - 5f64.sqrt()).abs() < 0.1, "{}", b.sd);
    }
}
