//! Level 1 of seed 000 (Yan et al. 2015, Eq. 19): a power law y = A x1^b1 x2^b2 ... fitted by
//! least squares on the logarithms, every replicate kept as its own observation, with the
//! exponents' 95 % intervals and the lack-of-fit test that weighs the model's error against the
//! replicates' scatter.
//!
//! Replicates are either several target columns of one row (seed 000's four orthoslice angles
//! of one run) or rows with identical inputs (repeated runs). The lack-of-fit F ratio is
//! (SS_lof / (G - p)) / (SS_pe / (N - G)) with G groups of identical inputs, N observations and
//! p fitted constants, on the log scale where the fit is made. A ratio above the F quantile
//! means the power law misses structure that the replicates show is real; below, its error is
//! what the replicates scatter anyway.

use serde::Serialize;
use statrs::distribution::{ContinuousCDF, FisherSnedecor};

use super::least_squares::{linear, t975};
use crate::error::{Error, Result};

/// Observations for a fit: per group of replicates, the inputs and the measured values.
#[derive(Debug, Clone)]
pub struct Groups {
    /// Names of the inputs x_k, in the order of each `x` row; all values must be > 0.
    pub inputs: Vec<String>,
    /// Name of the fitted response y; its values must be > 0.
    pub target: String,
    /// `x[group][input]`.
    pub x: Vec<Vec<f64>>,
    /// `y[group]`: the replicate values (NaN values already left out).
    pub y: Vec<Vec<f64>>,
    /// Non-finite target values left out.
    pub dropped: usize,
}

impl Groups {
    /// Groups from rows: `x[row]`, `y[row]` (the row's replicate columns). Rows with identical
    /// inputs are merged into one group. Refuses a non-positive input or target, naming it.
    pub fn from_rows(
        inputs: &[String],
        target: &str,
        x: &[Vec<f64>],
        y: &[Vec<f64>],
        source: &str,
    ) -> Result<Groups> {
        let mut g = Groups {
            inputs: inputs.to_vec(),
            target: target.to_string(),
            x: Vec::new(),
            y: Vec::new(),
            dropped: 0,
        };
        for (r, (xr, yr)) in x.iter().zip(y).enumerate() {
            for (name, &v) in inputs.iter().zip(xr) {
                if !(v.is_finite() && v > 0.0) {
                    return Err(Error::invalid(format!(
                        "{source}: row {}: input {name} = {v}; a power law needs positive \
                         inputs (it is fitted on their logarithms)",
                        r + 1
                    )));
                }
            }
            let mut vals = Vec::new();
            for &v in yr {
                if !v.is_finite() {
                    g.dropped += 1;
                    continue;
                }
                if v <= 0.0 {
                    return Err(Error::invalid(format!(
                        "{source}: row {}: target {target} = {v}; a power law needs positive \
                         values",
                        r + 1
                    )));
                }
                vals.push(v);
            }
            if vals.is_empty() {
                continue;
            }
            match g.x.iter().position(|gx| gx == xr) {
                Some(k) => g.y[k].extend(vals),
                None => {
                    g.x.push(xr.clone());
                    g.y.push(vals);
                }
            }
        }
        Ok(g)
    }

    /// Total number of replicate values over all groups (N).
    pub fn observations(&self) -> usize {
        self.y.iter().map(Vec::len).sum()
    }
}

/// One fitted exponent b_k of the power law.
#[derive(Debug, Clone, Serialize)]
pub struct Exponent {
    /// Estimate of b_k: the elasticity d ln y / d ln x_k (dimensionless).
    pub value: f64,
    /// Standard error of b_k from the log-scale least squares.
    pub std_error: f64,
    /// Two-sided 95 % Student-t interval of b_k.
    pub ci95: [f64; 2],
    /// The interval excludes 0.
    pub significant: bool,
}

/// Lack-of-fit F test of the power law against the replicates' pure error, on the log scale.
#[derive(Debug, Clone, Serialize)]
pub struct LackOfFit {
    /// Mean square of lack of fit over mean square of pure (replicate) error.
    pub ratio: f64,
    /// Degrees of freedom of lack of fit, G - p.
    pub dof_lack_of_fit: usize,
    /// Degrees of freedom of pure error, N - G.
    pub dof_pure_error: usize,
    /// The F distribution's 0.95 quantile at these degrees of freedom.
    pub f_critical_95: f64,
    /// Probability of a ratio at least this large if the power law were adequate.
    pub p_value: f64,
    /// Replicate standard deviation on the log scale, sqrt(SS_pe / dof).
    pub pure_error_sd_log: f64,
    /// The ratio exceeds the 0.95 quantile: the power law misses structure the replicates show is
    /// real.
    pub significant: bool,
}

/// A power law y = A x1^b1 x2^b2 ... fitted on the logarithms (seed 000, Level 1).
#[derive(Debug, Clone, Serialize)]
pub struct PowerLawFit {
    /// Name of the fitted response.
    pub target: String,
    /// Prefactor A, in the target's unit divided by the product of input units to their powers.
    pub a: f64,
    /// 95 % interval of A, mapped back from the log scale (not symmetric about A).
    pub a_ci95: [f64; 2],
    /// Input name -> exponent, in the inputs' order.
    pub exponents: Vec<(String, Exponent)>,
    /// Observations fitted (N, replicates counted individually).
    pub observations: usize,
    /// Distinct input points (G).
    pub groups: usize,
    /// Non-finite target values left out.
    pub dropped: usize,
    /// R^2 of the fit on the logarithms.
    pub r2_log: f64,
    /// RMS of (observed - predicted), in the target's unit.
    pub rmse: f64,
    /// None without replicates (no pure error to compare with), with the reason.
    pub lack_of_fit: std::result::Result<LackOfFit, String>,
    /// Per observation: (observed, predicted).
    #[serde(skip)]
    pub parity: Vec<(f64, f64)>,
}

/// Fits the power law to the groups.
pub fn fit(g: &Groups) -> Result<PowerLawFit> {
    let p = g.inputs.len() + 1;
    let mut rows = Vec::new();
    let mut ys = Vec::new();
    for (xg, yg) in g.x.iter().zip(&g.y) {
        let mut row = vec![1.0];
        row.extend(xg.iter().map(|v| v.ln()));
        for &y in yg {
            rows.push(row.clone());
            ys.push(y.ln());
        }
    }
    let n = ys.len();
    if n <= p {
        return Err(Error::invalid(format!(
            "power law for {}: {n} finite observations for {p} constants (A and one exponent \
             per input); expected more",
            g.target
        )));
    }
    let e = linear(&rows, &ys)
        .map_err(|e| Error::invalid(format!("power law for {}: {e}", g.target)))?;
    let t = t975(e.dof);
    let exponents = g
        .inputs
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let ci = e.ci95[k + 1];
            (
                name.clone(),
                Exponent {
                    value: e.values[k + 1],
                    std_error: e.std_errors[k + 1],
                    ci95: ci,
                    significant: ci[0] > 0.0 || ci[1] < 0.0,
                },
            )
        })
        .collect();
    let mean = ys.iter().sum::<f64>() / n as f64;
    let sst: f64 = ys.iter().map(|y| (y - mean).powi(2)).sum();
    let parity: Vec<(f64, f64)> = rows
        .iter()
        .zip(&ys)
        .map(|(row, y)| {
            let pred: f64 = row.iter().zip(&e.values).map(|(a, b)| a * b).sum();
            (y.exp(), pred.exp())
        })
        .collect();
    let rmse = (parity.iter().map(|(o, p)| (o - p).powi(2)).sum::<f64>() / n as f64).sqrt();
    let groups = g.y.len();
    let ss_pe: f64 =
        g.y.iter()
            .map(|yg| {
                let l: Vec<f64> = yg.iter().map(|v| v.ln()).collect();
                let m = l.iter().sum::<f64>() / l.len() as f64;
                l.iter().map(|v| (v - m).powi(2)).sum::<f64>()
            })
            .sum();
    let dof_pe = n - groups;
    let lack_of_fit = if dof_pe == 0 {
        Err("no replicates: every group of identical inputs holds one observation".to_string())
    } else if groups <= p {
        Err(format!(
            "{groups} distinct input points for {p} constants: nothing left to test the fit's \
             shape"
        ))
    } else if ss_pe <= 0.0 {
        Err("the replicates are identical: no pure error to compare with".to_string())
    } else {
        let dof_lof = groups - p;
        let ss_lof = (e.sse - ss_pe).max(0.0);
        let ratio = (ss_lof / dof_lof as f64) / (ss_pe / dof_pe as f64);
        let f = FisherSnedecor::new(dof_lof as f64, dof_pe as f64)
            .map_err(|e| Error::invalid(format!("lack of fit: {e}")))?;
        let f_crit = f.inverse_cdf(0.95);
        Ok(LackOfFit {
            ratio,
            dof_lack_of_fit: dof_lof,
            dof_pure_error: dof_pe,
            f_critical_95: f_crit,
            p_value: 1.0 - f.cdf(ratio),
            pure_error_sd_log: (ss_pe / dof_pe as f64).sqrt(),
            significant: ratio > f_crit,
        })
    };
    let a_se = e.std_errors[0];
    Ok(PowerLawFit {
        target: g.target.clone(),
        a: e.values[0].exp(),
        a_ci95: [
            (e.values[0] - t * a_se).exp(),
            (e.values[0] + t * a_se).exp(),
        ],
        exponents,
        observations: n,
        groups,
        dropped: g.dropped,
        r2_log: 1.0 - e.sse / sst,
        rmse,
        lack_of_fit,
        parity,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    fn names(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    /// y = 2 a^0.5 b^-1.2 c^0 with 4 log-normal replicates (sd 0.05) on a 4 x 3 x 3 grid.
    fn noisy(seed: u64, shape_error: bool) -> Groups {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let mut x = Vec::new();
        let mut y = Vec::new();
        for a in [0.05, 0.15, 0.25, 0.5] {
            for b in [0.05, 0.25, 0.45] {
                for c in [0.05, 0.45, 0.85] {
                    let mut base = 2.0 * f64::powf(a, 0.5) * f64::powf(b, -1.2);
                    if shape_error {
                        base *= 1.0 + 3.0 * (a - 0.25f64).powi(2);
                    }
                    let reps = (0..4)
                        .map(|_| {
                            // Box-Muller normal.
                            let (u, v): (f64, f64) = (rng.random(), rng.random());
                            let z =
                                (-2.0 * (1.0 - u).ln()).sqrt() * (std::f64::consts::TAU * v).cos();
                            base * (0.05 * z).exp()
                        })
                        .collect();
                    x.push(vec![a, b, c]);
                    y.push(reps);
                }
            }
        }
        Groups::from_rows(&names(&["a", "b", "c"]), "y", &x, &y, "test").unwrap()
    }

    #[test]
    fn recovers_known_exponents_inside_their_intervals() {
        let mut covered = 0;
        let trials = 40;
        for seed in 0..trials {
            let f = fit(&noisy(seed, false)).unwrap();
            let want = [0.5, -1.2, 0.0];
            for ((_, e), w) in f.exponents.iter().zip(want) {
                assert!((e.value - w).abs() < 0.06, "{} vs {w}", e.value);
                if e.ci95[0] <= w && w <= e.ci95[1] {
                    covered += 1;
                }
            }
            assert!(f.exponents[0].1.significant && f.exponents[1].1.significant);
        }
        // 95 % intervals: of 120, about 114 cover; far fewer would mean the intervals are wrong.
        assert!((105..=120).contains(&covered), "{covered} of 120 covered");
    }

    #[test]
    fn lack_of_fit_flags_a_wrong_shape_and_passes_the_right_one() {
        let mut flagged_true = 0;
        let mut flagged_wrong = 0;
        for seed in 0..20 {
            let ok = fit(&noisy(seed, false)).unwrap().lack_of_fit.unwrap();
            let bad = fit(&noisy(seed, true)).unwrap().lack_of_fit.unwrap();
            assert_eq!(ok.dof_lack_of_fit, 36 - 4);
            assert_eq!(ok.dof_pure_error, 144 - 36);
            flagged_true += ok.significant as usize;
            flagged_wrong += bad.significant as usize;
        }
        assert!(
            flagged_true <= 4,
            "{flagged_true} of 20 true models flagged"
        );
        assert!(
            flagged_wrong >= 18,
            "{flagged_wrong} of 20 wrong models flagged"
        );
    }

    #[test]
    fn rows_with_equal_inputs_are_replicates_and_bad_values_are_named() {
        let x = vec![vec![1.0], vec![2.0], vec![1.0], vec![3.0]];
        let y = vec![vec![1.0], vec![2.1], vec![1.1], vec![f64::NAN]];
        let g = Groups::from_rows(&names(&["a"]), "y", &x, &y, "t.csv").unwrap();
        assert_eq!((g.y.len(), g.observations(), g.dropped), (2, 3, 1));
        let e = Groups::from_rows(&names(&["a"]), "y", &[vec![0.0]], &[vec![1.0]], "t.csv");
        let msg = e.unwrap_err().to_string();
        assert!(msg.contains("t.csv") && msg.contains("input a"), "{msg}");
    }
}
