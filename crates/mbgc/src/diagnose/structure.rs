//! Structure in standardised residuals: an offset per response (the model misses by the same
//! amount everywhere) and a trend against what varies between samples (ln d50, sigma_ln), with
//! their significance, and an offset per experiment when there are several.
//!
//! Under a correct model the standardised residuals have unit variance and the correlation `R`
//! the model error shared between samples gives them (`covariance.rs`); an estimate `w^T z`
//! (a mean, or a least-squares slope against `u`) then has standard error `sqrt(w^T R w)`:
//! `1 / sqrt(n)` for a mean and `1 / sqrt(sum (u - mean u)^2)` for a slope when the residuals are
//! independent. A shared model error makes an offset cheap (the model may have made it) and
//! leaves a trend's standard error nearly as it was. The tests are z-tests on these
//! (two-sided); the searched parameters take up part of the scatter, so they are conservative.

use serde::Serialize;
use statrs::distribution::{ContinuousCDF, Normal};

/// One standardised residual and what describes its sample.
#[derive(Clone, Debug)]
pub struct Point {
    /// Response the residual belongs to.
    pub response: String,
    /// Experiment that measured it.
    pub experiment: String,
    /// Mass median size of the sample, mm, when known.
    pub d50: Option<f64>,
    /// Log-normal width of the sample's PSD, when known.
    pub sigma_ln: Option<f64>,
    /// Standardised residual (measured - predicted) / sigma.
    pub z: f64,
}

/// One z-test for structure in the standardised residuals: an offset or a trend.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Test {
    /// `offset` or `trend`.
    pub kind: String,
    /// The response (or `experiment <name>`) it is about.
    pub of: String,
    /// For a trend: `ln d50` or `sigma_ln`.
    pub against: Option<String>,
    /// Mean residual, or the slope per unit of `against`, in standardised units.
    pub estimate: f64,
    /// Standard error of the estimate under a correct model: `sqrt(w^T R w)`, 1 / sqrt(n) for
    /// an offset and 1 / sqrt(sum (u - mean u)^2) for a trend of independent residuals.
    pub se: f64,
    /// Two-sided p-value under the hypothesis of no structure.
    pub p: f64,
    /// Residuals the test used.
    pub points: usize,
}

/// Two-sided p-value of a standard normal statistic.
pub fn two_sided(z: f64) -> f64 {
    let n = Normal::new(0.0, 1.0).expect("the standard normal");
    2.0 * (1.0 - n.cdf(z.abs()))
}

/// `sqrt(w^T R w)` over the points `idx` with weights `w`.
fn standard_error(idx: &[usize], w: &[f64], corr: &[Vec<f64>]) -> f64 {
    let mut v = 0.0;
    for (a, &i) in idx.iter().enumerate() {
        for (b, &j) in idx.iter().enumerate() {
            v += w[a] * w[b] * corr[i][j];
        }
    }
    v.max(0.0).sqrt()
}

fn offset(of: String, idx: &[usize], points: &[Point], corr: &[Vec<f64>]) -> Test {
    let n = idx.len() as f64;
    let mean = idx.iter().map(|&i| points[i].z).sum::<f64>() / n;
    let se = standard_error(idx, &vec![1.0 / n; idx.len()], corr);
    Test {
        kind: "offset".into(),
        of,
        against: None,
        estimate: mean,
        se,
        p: two_sided(mean / se),
        points: idx.len(),
    }
}

/// Least-squares slope of `z` against `u` over the points `idx`; `None` when `u` takes fewer
/// than 3 distinct values.
fn trend(
    of: &str,
    against: &str,
    idx: &[usize],
    u: &[f64],
    points: &[Point],
    corr: &[Vec<f64>],
) -> Option<Test> {
    let mut distinct: Vec<f64> = u.to_vec();
    distinct.sort_by(f64::total_cmp);
    distinct.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * a.abs().max(b.abs()));
    if distinct.len() < 3 {
        return None;
    }
    let n = u.len() as f64;
    let mu = u.iter().sum::<f64>() / n;
    let sxx: f64 = u.iter().map(|v| (v - mu).powi(2)).sum();
    // The slope is w^T z with w = (u - mean u) / sxx (the weights sum to 0, so the mean of z
    // drops out).
    let w: Vec<f64> = u.iter().map(|v| (v - mu) / sxx).collect();
    let slope: f64 = w.iter().zip(idx).map(|(w, &i)| w * points[i].z).sum();
    let se = standard_error(idx, &w, corr);
    Some(Test {
        kind: "trend".into(),
        of: of.to_string(),
        against: Some(against.to_string()),
        estimate: slope,
        se,
        p: two_sided(slope / se),
        points: u.len(),
    })
}

/// Every test the points allow: per response an offset and trends against ln d50 and sigma_ln
/// (where they take 3 or more values); per experiment an offset when there are several.
/// `corr` is the correlation of the points' z (unit diagonal), in point order.
pub fn tests(points: &[Point], corr: &[Vec<f64>]) -> Vec<Test> {
    let mut responses: Vec<&str> = Vec::new();
    let mut experiments: Vec<&str> = Vec::new();
    for p in points {
        if !responses.contains(&p.response.as_str()) {
            responses.push(&p.response);
        }
        if !experiments.contains(&p.experiment.as_str()) {
            experiments.push(&p.experiment);
        }
    }
    let mut out = Vec::new();
    for r in responses {
        let mine: Vec<usize> = (0..points.len())
            .filter(|&i| points[i].response == r)
            .collect();
        out.push(offset(r.to_string(), &mine, points, corr));
        for (against, get) in [
            (
                "ln d50",
                (|p: &Point| p.d50.map(f64::ln)) as fn(&Point) -> Option<f64>,
            ),
            ("sigma_ln", |p: &Point| p.sigma_ln),
        ] {
            let pairs: Vec<(usize, f64)> = mine
                .iter()
                .filter_map(|&i| get(&points[i]).map(|u| (i, u)))
                .collect();
            let idx: Vec<usize> = pairs.iter().map(|p| p.0).collect();
            let u: Vec<f64> = pairs.iter().map(|p| p.1).collect();
            if let Some(t) = trend(r, against, &idx, &u, points, corr) {
                out.push(t);
            }
        }
    }
    if experiments.len() > 1 {
        for e in experiments {
            let idx: Vec<usize> = (0..points.len())
                .filter(|&i| points[i].experiment == e)
                .collect();
            out.push(offset(format!("experiment {e}"), &idx, points, corr));
        }
    }
    out
}

/// The identity: the correlation of independent residuals.
pub fn independent(n: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|i| (0..n).map(|j| f64::from(u8::from(i == j))).collect())
        .collect()
}

/// The tests significant at family-wise level `alpha` (Bonferroni over all tests).
pub fn significant(tests: &[Test], alpha: f64) -> Vec<&Test> {
    let m = tests.len().max(1) as f64;
    tests.iter().filter(|t| t.p < alpha / m).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    fn points(z: impl Fn(f64, usize) -> f64) -> Vec<Point> {
        let d50 = [2.0, 4.0, 8.0, 16.0, 2.0, 4.0, 8.0, 16.0];
        d50.iter()
            .enumerate()
            .map(|(i, &d)| Point {
                response: if i < 4 { "shear_angle" } else { "bulk_density" }.into(),
                experiment: "shear-box".into(),
                d50: Some(d),
                sigma_ln: Some(0.12),
                z: z(d, i),
            })
            .collect()
    }

    #[test]
    fn a_residual_that_grows_as_particles_get_smaller_is_a_trend_not_an_offset() {
        // z = 4 at 2 mm falling to -2 at 16 mm: 2 per halving of d50 around mean 1, on the angle.
        let pts = points(|d, i| {
            if i < 4 {
                1.0 - 2.0 * (d / 5.657).log2()
            } else {
                0.1
            }
        });
        let t = tests(&pts, &independent(pts.len()));
        let trend = t
            .iter()
            .find(|t| t.kind == "trend" && t.of == "shear_angle")
            .unwrap();
        assert!(
            (trend.estimate - (-2.0 / 2f64.ln())).abs() < 1e-9,
            "{trend:?}"
        );
        assert!(trend.p < 1e-3, "{trend:?}");
        let density = t
            .iter()
            .find(|t| t.kind == "trend" && t.of == "bulk_density")
            .unwrap();
        assert!(density.estimate.abs() < 1e-12 && density.p > 0.99);
        // sigma_ln takes one value: no trend against it is claimed.
        assert!(t.iter().all(|t| t.against.as_deref() != Some("sigma_ln")));
        let sig = significant(&t, 0.01);
        assert_eq!(sig.len(), 1, "{sig:?}");
    }

    #[test]
    fn the_same_miss_everywhere_is_an_offset_with_the_textbook_standard_error() {
        let pts = points(|_, i| if i < 4 { 3.0 } else { 0.0 });
        let t = tests(&pts, &independent(pts.len()));
        let off = t
            .iter()
            .find(|t| t.kind == "offset" && t.of == "shear_angle")
            .unwrap();
        assert_eq!(off.estimate, 3.0);
        assert_eq!(off.se, 0.5);
        // z = 6: p = 2 (1 - Phi(6)) ~ 2e-9.
        assert!(off.p < 1e-8 && off.p > 1e-10, "{off:?}");
        let trend = t
            .iter()
            .find(|t| t.kind == "trend" && t.of == "shear_angle")
            .unwrap();
        assert!(trend.estimate.abs() < 1e-12);
    }

    #[test]
    fn pure_noise_is_flagged_at_about_the_nominal_rate() {
        // 2000 sets of 8 standard normal residuals: each test's false-alarm rate at 5 % must be
        // near 5 % if its standard error is right.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut hits = [0usize; 2];
        let n = 2000;
        for _ in 0..n {
            let zs: Vec<f64> = (0..8).map(|_| StandardNormal.sample(&mut rng)).collect();
            let t = tests(&points(|_, i| zs[i]), &independent(8));
            let off = t
                .iter()
                .find(|t| t.kind == "offset" && t.of == "shear_angle")
                .unwrap();
            let tr = t
                .iter()
                .find(|t| t.kind == "trend" && t.of == "shear_angle")
                .unwrap();
            hits[0] += usize::from(off.p < 0.05);
            hits[1] += usize::from(tr.p < 0.05);
        }
        for h in hits {
            let rate = h as f64 / n as f64;
            assert!((0.035..0.065).contains(&rate), "false-alarm rate {rate}");
        }
    }

    /// Residuals sharing a model error (correlation 0.8 within a response): the offset test
    /// keeps its nominal 5 % false-alarm rate only with the shared part in its standard error;
    /// treated as independent it cries wolf six times as often.
    #[test]
    fn a_shared_model_error_is_not_taken_for_an_offset() {
        let rho: f64 = 0.8;
        let corr: Vec<Vec<f64>> = (0..8)
            .map(|i| {
                (0..8)
                    .map(|j| {
                        if i == j {
                            1.0
                        } else if (i < 4) == (j < 4) {
                            rho
                        } else {
                            0.0
                        }
                    })
                    .collect()
            })
            .collect();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let (mut with, mut without, mut trends) = (0usize, 0usize, 0usize);
        let n = 2000;
        for _ in 0..n {
            let shared: [f64; 2] = [
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
            ];
            let zs: Vec<f64> = (0..8)
                .map(|i| {
                    let e: f64 = StandardNormal.sample(&mut rng);
                    rho.sqrt() * shared[i / 4] + (1.0 - rho).sqrt() * e
                })
                .collect();
            let pts = points(|_, i| zs[i]);
            let find = |t: &[Test], kind: &str| {
                t.iter()
                    .find(|t| t.kind == kind && t.of == "shear_angle")
                    .unwrap()
                    .p
            };
            let t = tests(&pts, &corr);
            with += usize::from(find(&t, "offset") < 0.05);
            trends += usize::from(find(&t, "trend") < 0.05);
            let t = tests(&pts, &independent(8));
            without += usize::from(find(&t, "offset") < 0.05);
        }
        let rate = |h: usize| h as f64 / n as f64;
        assert!((0.035..0.065).contains(&rate(with)), "{}", rate(with));
        assert!((0.035..0.065).contains(&rate(trends)), "{}", rate(trends));
        // var(mean z) is (1 + 3 rho) / 4 = 0.85, not 1/4: |z| > 1.96 / sqrt(3.4) about 29 % of
        // the time.
        assert!((0.22..0.36).contains(&rate(without)), "{}", rate(without));
    }
}
