//! Seed 000's time-dependent flow-rate model: FR(t) = FR0 / (1 + (t / K)^n), with FR0 the
//! initial (steady) flow rate, K the time at which the rate has fallen to half of it (the onset
//! of the decline) and n how steeply it falls. The paper's text as available here names the
//! three constants and their meaning but not the formula; this is the three-constant form with
//! exactly that meaning (a Hill decline), stated so that a reader can check it.
//!
//! Fitted by Levenberg-Marquardt in the logarithms of the constants, which keeps them positive;
//! the 95 % intervals are the log-scale intervals mapped back (so they are not symmetric).

use serde::Serialize;

use super::least_squares::{levenberg_marquardt, Residuals};
use crate::error::{Error, Result};

/// The model's value at time `t`.
pub fn flow_rate(fr0: f64, k: f64, n: f64, t: f64) -> f64 {
    fr0 / (1.0 + (t / k).powf(n))
}

/// A fitted constant of the flow-rate model with its 95 % interval.
#[derive(Debug, Clone, Serialize)]
pub struct Constant {
    /// The estimate, in the constant's unit (FR0 in the data's flow-rate unit, K in s, n
    /// dimensionless); always > 0.
    pub value: f64,
    /// The 95 % interval [low, high], mapped back from the log scale, so not symmetric about
    /// `value`.
    pub ci95: [f64; 2],
}

/// FR(t) = FR0 / (1 + (t / K)^n) fitted to a flow-rate history.
#[derive(Debug, Clone, Serialize)]
pub struct FlowCurveFit {
    /// Initial (steady) flow rate FR0, in the unit of the data (kg/s for the hopper).
    pub fr0: Constant,
    /// Time K at which the rate has fallen to FR0 / 2, s: the onset of the decline.
    pub k: Constant,
    /// Steepness n of the decline (dimensionless); large n means an abrupt end of the flow.
    pub n: Constant,
    /// Root-mean-square residual, in the unit of the flow rate.
    pub rmse: f64,
    /// Finite (time, rate) points the fit used.
    pub points: usize,
}

struct Curve<'a> {
    t: &'a [f64],
    y: &'a [f64],
}

impl Residuals for Curve<'_> {
    fn residuals(&self, p: &[f64]) -> Vec<f64> {
        let (fr0, k, n) = (p[0].exp(), p[1].exp(), p[2].exp());
        self.t
            .iter()
            .zip(self.y)
            .map(|(&t, &y)| flow_rate(fr0, k, n, t) - y)
            .collect()
    }

    fn jacobian(&self, p: &[f64]) -> Vec<Vec<f64>> {
        let (fr0, k, n) = (p[0].exp(), p[1].exp(), p[2].exp());
        self.t
            .iter()
            .map(|&t| {
                let q = (t / k).powf(n);
                let d = 1.0 + q;
                let f = fr0 / d;
                // d f / d ln q = -fr0 q / d^2; ln q = n (ln t - ln k).
                let dq = -fr0 * q / (d * d);
                let lnr = if t > 0.0 { (t / k).ln() } else { 0.0 };
                vec![f, dq * (-n), dq * n * lnr]
            })
            .collect()
    }
}

/// Fits FR(t) to (time, flow rate) points. Refuses fewer than 4 finite points, or a curve
/// without a positive rate.
pub fn fit(t: &[f64], y: &[f64]) -> Result<FlowCurveFit> {
    let (t, y): (Vec<f64>, Vec<f64>) = t
        .iter()
        .zip(y)
        .filter(|(t, y)| t.is_finite() && y.is_finite() && **t >= 0.0)
        .map(|(a, b)| (*a, *b))
        .unzip();
    if t.len() < 4 {
        return Err(Error::invalid(format!(
            "flow-rate curve: {} finite points; expected at least 4 for FR0, K and n",
            t.len()
        )));
    }
    let (t_lo, t_hi) = t
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if t_hi <= t_lo {
        return Err(Error::invalid(format!(
            "flow-rate curve: every point is at t = {t_lo} s; expected points at different times \
             (a bin width of 0?)"
        )));
    }
    let peak = y.iter().copied().fold(0.0, f64::max);
    if peak <= 0.0 {
        return Err(Error::invalid(
            "flow-rate curve: no positive flow rate to fit",
        ));
    }
    let low = y.iter().copied().fold(f64::INFINITY, f64::min);
    if peak - low <= 1e-9 * peak {
        return Err(Error::invalid(format!(
            "flow-rate curve: the rate is constant ({peak}) over the record: it does not decline, \
             so K and n are not determined"
        )));
    }
    // K: the first time after the peak at which the rate is below half of it.
    let ipeak = y.iter().position(|&v| v == peak).unwrap_or(0);
    let k0 = (ipeak..t.len())
        .find(|&i| y[i] < 0.5 * peak)
        .map_or(t[t.len() - 1], |i| t[i]);
    let curve = Curve { t: &t, y: &y };
    let mut best = None;
    for n0 in [2.0f64, 4.0, 8.0] {
        let Ok(e) = levenberg_marquardt(&curve, &[peak.ln(), k0.max(1e-9).ln(), n0.ln()], 300)
        else {
            continue;
        };
        if best
            .as_ref()
            .is_none_or(|b: &super::least_squares::Estimate| e.sse < b.sse)
        {
            best = Some(e);
        }
    }
    let e = best.ok_or_else(|| Error::invalid("flow-rate curve: the fit did not converge"))?;
    let c = |k: usize| Constant {
        value: e.values[k].exp(),
        ci95: [e.ci95[k][0].exp(), e.ci95[k][1].exp()],
    };
    let (fr0, k, n) = (c(0), c(1), c(2));
    for (name, p) in [("FR0", &fr0), ("K", &k), ("n", &n)] {
        let [lo, hi] = p.ci95;
        if !(lo.is_finite() && hi.is_finite() && hi > lo) {
            return Err(Error::invalid(format!(
                "flow-rate curve: {name} = {:.4e} has no finite 95 % interval ([{lo:.4e}, \
                 {hi:.4e}]): the points do not determine it",
                p.value
            )));
        }
    }
    Ok(FlowCurveFit {
        fr0,
        k,
        n,
        rmse: (e.sse / t.len() as f64).sqrt(),
        points: t.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat or empty record determines no curve: an error, never a fit with a zero-width
    /// interval.
    #[test]
    fn constant_or_zero_flow_is_refused() {
        let t: Vec<f64> = (0..8).map(|k| 0.1 + 0.2 * k as f64).collect();
        let e = fit(&t, &[0.04; 8]).unwrap_err().to_string();
        assert!(e.contains("constant"), "{e}");
        let e = fit(&t, &[0.0; 8]).unwrap_err().to_string();
        assert!(e.contains("no positive flow rate"), "{e}");
    }

    #[test]
    fn recovers_the_constants_of_a_noisy_curve() {
        let t: Vec<f64> = (0..16).map(|k| 0.075 + 0.15 * k as f64).collect();
        // Deterministic +-1.5 % "noise".
        let y: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                flow_rate(0.04, 1.1, 5.0, t) * (1.0 + 0.015 * ((i * 7 % 5) as f64 - 2.0) / 2.0)
            })
            .collect();
        let f = fit(&t, &y).unwrap();
        assert!((f.fr0.value - 0.04).abs() < 0.001, "{f:?}");
        assert!((f.k.value - 1.1).abs() < 0.03, "{f:?}");
        assert!((f.n.value - 5.0).abs() < 0.6, "{f:?}");
        for c in [&f.fr0, &f.k, &f.n] {
            assert!(c.ci95[0] < c.value && c.value < c.ci95[1]);
        }
        assert!(f.k.ci95[0] < 1.1 && 1.1 < f.k.ci95[1], "{f:?}");
    }

    /// Points all at one time (a bin width of 0) determine no K or n: said so, not "did not
    /// converge".
    #[test]
    fn points_at_one_time_are_refused_by_name() {
        let y = [0.04, 0.04, 0.03, 0.02, 0.01, 0.005, 0.002, 0.0];
        let e = fit(&[0.0; 8], &y).unwrap_err().to_string();
        assert!(e.contains("different times"), "{e}");
    }

    #[test]
    fn too_few_points_are_refused() {
        assert!(fit(&[0.1, 0.2, 0.3], &[1.0, 1.0, 0.5]).is_err());
        assert!(fit(&[0.1, 0.2, 0.3, 0.4], &[0.0; 4]).is_err());
    }
}
