//! A metamodel's own error as a function of where it is evaluated.
//!
//! One validation RMSE describes the model everywhere, but a fitted equation is rarely equally
//! good over its whole space (the shear box's angle is worse where cohesion is strong and the
//! fill barely flows). The model's error at the point a calibration lands on is what its
//! intervals need. Here the validation residuals `r` are modelled as `N(0, s(x)^2)` with
//! `ln s^2 = a + b . (u(x) - 1/2)`, `u` the inputs scaled to [0, 1] over the model's space: a
//! log-linear variance, fitted by penalised maximum likelihood (a convex problem, solved by
//! Newton's method). The ridge weight on `b` is picked by five-fold cross-validated predictive
//! likelihood among a few values and the constant model (`b = 0`), so the error varies with `x`
//! only as far as held-out residuals support it.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// The fitted variance model of one response's residuals.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorModel {
    /// `ln s^2` at the centre of the scaled inputs.
    pub intercept: f64,
    /// Slope of `ln s^2` per scaled input (0 for an input not varied).
    pub slopes: Vec<f64>,
    /// The ridge weight cross-validation chose (`None`: the constant model).
    pub ridge: Option<f64>,
    /// Mean held-out negative log-likelihood per residual (five folds, up to a constant) of the
    /// chosen model, and of the constant one: how much the variation with `x` predicts.
    pub cv_nll: [f64; 2],
    /// The smallest and largest `s` the model may give: a quarter and four times the RMS
    /// residual, so that an extrapolated slope cannot make the model exact or useless.
    pub limits: [f64; 2],
}

/// Ridge weights tried (in units of the summed negative log-likelihood) before the constant model.
const RIDGES: [f64; 5] = [1.0, 4.0, 16.0, 64.0, 256.0];

/// Folds of the cross-validation that picks the ridge weight.
const FOLDS: usize = 5;

/// Fewest residuals an error model is fitted to; fewer give the constant model.
pub const MIN_POINTS: usize = 20;

fn centred(u: &[f64]) -> Vec<f64> {
    u.iter().map(|v| v.clamp(-0.5, 1.5) - 0.5).collect()
}

/// Penalised maximum likelihood of `(a, b)` on rows `(u, r)`; `None` ridge fits `a` alone.
fn fit_rows(u: &[Vec<f64>], r: &[f64], ridge: Option<f64>) -> (f64, Vec<f64>) {
    let n = r.len();
    let mean_sq = r.iter().map(|v| v * v).sum::<f64>() / n.max(1) as f64;
    let a0 = mean_sq.max(f64::MIN_POSITIVE).ln();
    let dim = u.first().map_or(0, Vec::len);
    let Some(lambda) = ridge else {
        return (a0, vec![0.0; dim]);
    };
    let p = dim + 1;
    let nll = |w: &DVector<f64>| -> f64 {
        let mut s = 0.0;
        for (ui, ri) in u.iter().zip(r) {
            let eta = w[0] + (0..dim).map(|j| w[j + 1] * ui[j]).sum::<f64>();
            s += 0.5 * (eta + ri * ri * (-eta).exp());
        }
        s + 0.5 * lambda * (1..p).map(|j| w[j] * w[j]).sum::<f64>()
    };
    let mut w = DVector::zeros(p);
    w[0] = a0;
    let mut f = nll(&w);
    for _ in 0..50 {
        let mut g = DVector::zeros(p);
        let mut h = DMatrix::zeros(p, p);
        for (ui, ri) in u.iter().zip(r) {
            let eta = w[0] + (0..dim).map(|j| w[j + 1] * ui[j]).sum::<f64>();
            let q = ri * ri * (-eta).exp();
            let z: Vec<f64> = std::iter::once(1.0).chain(ui.iter().copied()).collect();
            for j in 0..p {
                g[j] += 0.5 * (1.0 - q) * z[j];
                for k in 0..p {
                    h[(j, k)] += 0.5 * q * z[j] * z[k];
                }
            }
        }
        for j in 1..p {
            g[j] += lambda * w[j];
            h[(j, j)] += lambda;
        }
        // The intercept's curvature vanishes only if every residual is 0.
        h[(0, 0)] += 1e-9;
        let Some(step) = h.cholesky().map(|c| c.solve(&g)) else {
            break;
        };
        let mut t = 1.0;
        let mut improved = false;
        while t > 1e-6 {
            let trial = &w - &step * t;
            let ft = nll(&trial);
            if ft.is_finite() && ft <= f {
                improved = f - ft > 1e-10 * (1.0 + f.abs());
                w = trial;
                f = ft;
                break;
            }
            t *= 0.5;
        }
        if !improved {
            break;
        }
    }
    (w[0], w.iter().skip(1).copied().collect())
}

/// Mean predictive negative log-likelihood of held-out residuals, by five folds.
fn cv_score(u: &[Vec<f64>], r: &[f64], ridge: Option<f64>) -> f64 {
    let n = r.len();
    let mut total = 0.0;
    for fold in 0..FOLDS {
        let (mut tu, mut tr, mut hu, mut hr) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 0..n {
            if i % FOLDS == fold {
                hu.push(u[i].clone());
                hr.push(r[i]);
            } else {
                tu.push(u[i].clone());
                tr.push(r[i]);
            }
        }
        let (a, b) = fit_rows(&tu, &tr, ridge);
        for (ui, ri) in hu.iter().zip(&hr) {
            let eta = a + b.iter().zip(ui).map(|(b, u)| b * u).sum::<f64>();
            total += 0.5 * (eta + ri * ri * (-eta).exp());
        }
    }
    total / n as f64
}

impl ErrorModel {
    /// Fits the error model to residuals `r` at scaled inputs `u` (one row per residual, values
    /// in [0, 1] over the model's space). `None` with fewer than [`MIN_POINTS`] finite rows.
    pub fn fit(u: &[Vec<f64>], r: &[f64]) -> Option<ErrorModel> {
        let rows: Vec<(Vec<f64>, f64)> = u
            .iter()
            .zip(r)
            .filter(|(ui, ri)| ri.is_finite() && ui.iter().all(|v| v.is_finite()))
            .map(|(ui, ri)| (centred(ui), *ri))
            .collect();
        if rows.len() < MIN_POINTS {
            return None;
        }
        let (u, r): (Vec<Vec<f64>>, Vec<f64>) = rows.into_iter().unzip();
        let constant = cv_score(&u, &r, None);
        let (ridge, best) = RIDGES
            .iter()
            .map(|&l| (Some(l), cv_score(&u, &r, Some(l))))
            .fold((None, constant), |a, b| if b.1 < a.1 { b } else { a });
        let (intercept, slopes) = fit_rows(&u, &r, ridge);
        let rms = (r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt();
        Some(ErrorModel {
            intercept,
            slopes,
            ridge,
            cv_nll: [best, constant],
            limits: [0.25 * rms, 4.0 * rms],
        })
    }

    /// The model's standard error at scaled inputs `u`.
    pub fn sd(&self, u: &[f64]) -> f64 {
        let eta = self.intercept
            + self
                .slopes
                .iter()
                .zip(centred(u))
                .map(|(b, u)| b * u)
                .sum::<f64>();
        (0.5 * eta).exp().clamp(self.limits[0], self.limits[1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal, Uniform};

    fn rows(n: usize, sd: impl Fn(&[f64]) -> f64, seed: u64) -> (Vec<Vec<f64>>, Vec<f64>) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let unit = Uniform::new(0.0, 1.0).unwrap();
        let z = Normal::new(0.0, 1.0).unwrap();
        let u: Vec<Vec<f64>> = (0..n)
            .map(|_| (0..3).map(|_| unit.sample(&mut rng)).collect())
            .collect();
        let r = u.iter().map(|x| sd(x) * z.sample(&mut rng)).collect();
        (u, r)
    }

    #[test]
    fn an_error_that_grows_along_one_input_is_found_there_and_only_there() {
        let (u, r) = rows(200, |x| 0.2 * (3.0 * x[0]).exp(), 1);
        let m = ErrorModel::fit(&u, &r).unwrap();
        let lo = m.sd(&[0.05, 0.5, 0.5]);
        let hi = m.sd(&[0.95, 0.5, 0.5]);
        // Truth: 0.23 and 3.5.
        assert!(lo < 0.5 && hi > 2.0, "{lo} {hi}");
        let flat = m.sd(&[0.5, 0.05, 0.5]) / m.sd(&[0.5, 0.95, 0.5]);
        assert!((flat.ln()).abs() < 0.5, "{flat} {m:?}");
    }

    #[test]
    fn a_constant_error_stays_nearly_constant() {
        let (u, r) = rows(128, |_| 1.5, 2);
        let m = ErrorModel::fit(&u, &r).unwrap();
        for x in [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [0.0, 1.0, 0.5]] {
            let s = m.sd(&x);
            assert!((s / 1.5 - 1.0).abs() < 0.35, "{s} at {x:?}: {m:?}");
        }
        assert!(ErrorModel::fit(&u[..10], &r[..10]).is_none());
    }
}
