//! How often an event that voids a run (a hopper's clogged orifice) happens over the posterior:
//! for a plant, whether the hopper flows at all comes before its flow rate.
//!
//! With the draws as equally weighted posterior samples, the mean over the draws of each draw's
//! share of runs with the event estimates the posterior mean of its probability,
//! P = E[P(event | theta)]. Its interval is Jeffreys' (the Beta(k + 1/2, n - k + 1/2)
//! quantiles): a binomial interval, which a handful of events out of a hundred runs calls for
//! (the normal approximation gives intervals below 0 there). With one run per draw the runs are
//! independent and n is their number. With several seeds per draw they are not: runs of one
//! draw share its parameters, and a draw that clogs tends to clog at every seed, so counting
//! them as independent would narrow the interval by up to sqrt(seeds). The interval then uses
//! the effective number of runs (Korn and Graubard 1998, Survey Methodology 24: 193-201):
//! n_eff = P (1 - P) / var(P), with var(P) the variance of the draws' shares over the number of
//! draws, at most the number of runs, and k = P n_eff.

use statrs::distribution::{Beta, ContinuousCDF};

/// An event's share of the runs that finished.
#[derive(Debug, Clone, PartialEq)]
pub struct EventRate {
    /// The event's name, as the experiment gives it.
    pub event: String,
    /// Runs that had it.
    pub count: usize,
    /// Runs that finished (with or without it).
    pub runs: usize,
    /// Draws with at least one run that had it.
    pub draws: usize,
    /// The mean over the draws with a finished run of their share of runs with the event
    /// (count / runs with one run per draw).
    pub share: f64,
    /// The number of independent runs the interval counts: `runs` with one run per draw, else
    /// the effective number of the module's notes.
    pub effective_runs: f64,
    /// Jeffreys' 90 % interval of the probability: 5 % quantile.
    pub q05: f64,
    /// 95 % quantile.
    pub q95: f64,
}

impl EventRate {
    /// The rate of `event` from `per_draw[d]`: for each finished run of draw d, whether it had
    /// the event. `None` when no run finished.
    pub fn of(event: &str, per_draw: &[Vec<bool>]) -> Option<EventRate> {
        let finished: Vec<&Vec<bool>> = per_draw.iter().filter(|v| !v.is_empty()).collect();
        let runs: usize = finished.iter().map(|v| v.len()).sum();
        if runs == 0 {
            return None;
        }
        let counts: Vec<usize> = finished
            .iter()
            .map(|v| v.iter().filter(|&&e| e).count())
            .collect();
        let count = counts.iter().sum();
        let draws = counts.iter().filter(|&&k| k > 0).count();
        let shares: Vec<f64> = counts
            .iter()
            .zip(&finished)
            .map(|(&k, v)| k as f64 / v.len() as f64)
            .collect();
        let d = shares.len() as f64;
        let share = shares.iter().sum::<f64>() / d;
        let one_each = finished.iter().all(|v| v.len() == 1);
        let effective_runs = if one_each || share == 0.0 || share == 1.0 {
            runs as f64
        } else if shares.len() < 2 {
            // One draw with several seeds: one posterior sample, however many runs.
            1.0
        } else {
            let var = shares.iter().map(|x| (x - share).powi(2)).sum::<f64>() / (d - 1.0) / d;
            if var > 0.0 {
                (share * (1.0 - share) / var).min(runs as f64)
            } else {
                runs as f64
            }
        };
        let (k, n) = (share * effective_runs, effective_runs);
        // Parameters >= 1/2, so the distribution always exists.
        let beta = Beta::new(k + 0.5, n - k + 0.5).expect("positive Beta parameters");
        // Jeffreys' interval is closed at 0 (1) when no (every) run had the event.
        let q05 = if count == 0 {
            0.0
        } else {
            beta.inverse_cdf(0.05)
        };
        let q95 = if count == runs {
            1.0
        } else {
            beta.inverse_cdf(0.95)
        };
        Some(EventRate {
            event: event.to_string(),
            count,
            runs,
            draws,
            share,
            effective_runs,
            q05,
            q95,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn share_and_jeffreys_interval() {
        // 2 of 18 runs: Jeffreys' 90 % interval, the 5 and 95 % quantiles of Beta(2.5, 16.5),
        // [0.03268, 0.27494] (bisection on a midpoint-rule integral of its density).
        let mut per_draw = vec![vec![false]; 16];
        per_draw.push(vec![true]);
        per_draw.push(vec![true, false]);
        let r = EventRate::of("clogged", &per_draw).unwrap();
        assert_eq!((r.count, r.runs, r.draws), (2, 19, 2));
        let r = EventRate::of("clogged", &per_draw[..17]).unwrap();
        assert_eq!((r.count, r.runs), (1, 17));
        let two: Vec<Vec<bool>> = (0..18).map(|i| vec![i < 2]).collect();
        let r = EventRate::of("clogged", &two).unwrap();
        assert!((r.share - 2.0 / 18.0).abs() < 1e-12);
        assert!((r.q05 - 0.03268).abs() < 1e-4, "{}", r.q05);
        assert!((r.q95 - 0.27494).abs() < 1e-4, "{}", r.q95);
    }

    #[test]
    fn no_event_and_every_run_close_the_interval_at_the_ends() {
        // 0 of 10: the 95 % quantile of Beta(0.5, 10.5) is 0.17077 (as above, with t = u^2
        // taking out the density's singularity at 0).
        let none = EventRate::of("clogged", &[vec![false; 10]]).unwrap();
        assert_eq!((none.share, none.q05), (0.0, 0.0));
        assert!((none.q95 - 0.17077).abs() < 1e-4, "{}", none.q95);
        let all = EventRate::of("clogged", &[vec![true; 10]]).unwrap();
        assert_eq!((all.share, all.q95), (1.0, 1.0));
        assert!(EventRate::of("clogged", &[vec![], vec![]]).is_none());
    }

    /// Three seeds per draw, and a draw that clogs clogs at every seed: 6 of 30 runs, but only
    /// 2 of 10 draws, so the interval is that of about 10 independent runs, much wider than the
    /// one 30 would give. Draws whose seeds disagree as often as independent runs would keep the
    /// plain interval of their runs.
    #[test]
    fn seeds_of_one_draw_do_not_count_as_independent_runs() {
        let clustered: Vec<Vec<bool>> = (0..10).map(|d| vec![d < 2; 3]).collect();
        let r = EventRate::of("clogged", &clustered).unwrap();
        assert_eq!((r.count, r.runs, r.draws), (6, 30, 2));
        assert!((r.share - 0.2).abs() < 1e-12);
        // var of the shares: 0.2 * 0.8 * 10 / 9 / 10, so n_eff = 9.
        assert!(
            (r.effective_runs - 9.0).abs() < 1e-9,
            "{}",
            r.effective_runs
        );
        let plain =
            EventRate::of("clogged", &(0..30).map(|i| vec![i < 6]).collect::<Vec<_>>()).unwrap();
        assert_eq!(plain.effective_runs, 30.0);
        assert!(
            r.q95 - r.q05 > 1.6 * (plain.q95 - plain.q05),
            "clustered [{}, {}] against independent [{}, {}]",
            r.q05,
            r.q95,
            plain.q05,
            plain.q95
        );
        // Every draw one clog in three: the draws agree exactly, the share is known as well
        // as 30 runs can tell, and n_eff stops at the number of runs.
        let spread: Vec<Vec<bool>> = (0..10).map(|_| vec![true, false, false]).collect();
        let r = EventRate::of("clogged", &spread).unwrap();
        assert_eq!(r.effective_runs, 30.0);
        let one = EventRate::of("clogged", &[vec![true, false, false]]).unwrap();
        assert_eq!(one.effective_runs, 1.0);
    }
}
