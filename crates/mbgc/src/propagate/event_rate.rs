//! How often an event that voids a run (a hopper's clogged orifice) happens over the posterior:
//! for a plant, whether the hopper flows at all comes before its flow rate.
//!
//! With the draws as equally weighted posterior samples, the share of runs with the event
//! estimates the posterior mean of its probability, P = E[P(event | theta)]. Its interval is
//! Jeffreys' (the Beta(k + 1/2, n - k + 1/2) quantiles): a plain binomial interval, which a
//! handful of events out of a hundred runs calls for (the normal approximation gives
//! intervals below 0 there).

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
    /// count / runs.
    pub share: f64,
    /// Jeffreys' 90 % interval of the probability: 5 % quantile.
    pub q05: f64,
    /// 95 % quantile.
    pub q95: f64,
}

impl EventRate {
    /// The rate of `event` from `per_draw[d]`: for each finished run of draw d, whether it had
    /// the event. `None` when no run finished.
    pub fn of(event: &str, per_draw: &[Vec<bool>]) -> Option<EventRate> {
        let runs: usize = per_draw.iter().map(Vec::len).sum();
        if runs == 0 {
            return None;
        }
        let count = per_draw.iter().flatten().filter(|&&e| e).count();
        let draws = per_draw.iter().filter(|v| v.iter().any(|&e| e)).count();
        let (k, n) = (count as f64, runs as f64);
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
            share: k / n,
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
}
