//! Least-squares fits of GGS, RRSB and log-normal to sieve data.
//!
//! The paper fits by linear least squares on the linearised forms (log/log for GGS,
//! ln(-ln(1 - Q)) vs ln x for RRSB, Phi^-1(Q) vs ln x for log-normal). Those weight the tails
//! heavily (a point at 0.4 % passing has the same say as one at 50 %), so here the linearised fit
//! is only the start: it is refined by Nelder-Mead on the sum of squared errors in Q3 itself,
//! which is also the quantity R^2 and MSE report.

use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use serde::{Serialize, Serializer};

use super::distribution::{phi_inv, Distribution, MassDistribution, Model};
use super::sieve::SieveData;
use crate::error::{Error, Result};

/// One model fitted to one sieve analysis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ModelFit {
    /// The fitted family.
    pub model: Model,
    /// The fitted distribution; serialised as a `params` map of its two named parameters.
    #[serde(rename = "params", serialize_with = "params_map")]
    pub dist: Distribution,
    /// 1 - SSE / SST on Q3 as fractions, over all points.
    pub r2: f64,
    /// SSE / n on Q3 as fractions.
    pub mse: f64,
    /// Sum of squared errors in Q3 (fractions) over all sieve points, the quantity minimised.
    pub sse: f64,
}

fn params_map<S: Serializer>(d: &Distribution, s: S) -> std::result::Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let params = d.params();
    let mut m = s.serialize_map(Some(params.len()))?;
    for (k, v) in params {
        m.serialize_entry(k, &v)?;
    }
    m.end()
}

/// All three models fitted to one sieve analysis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitReport {
    /// Where the sieve data came from (file path or caller's label).
    pub source: String,
    /// Number of sieve points fitted.
    pub n_points: usize,
    /// The model with the highest R^2.
    pub best: Model,
    /// In [`Model::ALL`] order.
    pub models: Vec<ModelFit>,
    /// Log-normal mass median (mm) and sigma_ln: the two PSD inputs of the metamodel.
    pub d50_mm: f64,
    /// Standard deviation of ln x of the log-normal fit (dimensionless, > 0), the metamodel's PSD
    /// width input.
    pub sigma_ln: f64,
}

impl FitReport {
    /// The fit of one family, if present.
    pub fn get(&self, model: Model) -> Option<&ModelFit> {
        self.models.iter().find(|f| f.model == model)
    }

    /// The fit with the highest R^2 (the one named by `best`).
    pub fn best_fit(&self) -> Option<&ModelFit> {
        self.get(self.best)
    }
}

/// Fits every model and picks the one with the highest R^2.
///
/// # Example
///
/// Five sieve points taken from a log-normal with mass median 11.16 mm and sigma_ln 0.26 (the
/// Gravel 8/16 of the MBGC paper): the fit recovers both metamodel inputs, and the log-normal
/// fits best.
///
/// ```
/// use mbgc::psd::{fit_all, phi, Model, SieveData};
///
/// let sizes = vec![8.0, 10.0, 11.2, 12.5, 16.0];
/// let passing = sizes.iter().map(|x: &f64| phi((x / 11.16).ln() / 0.26)).collect();
/// let data = SieveData::new("example", sizes, passing).unwrap();
/// let report = fit_all(&data).unwrap();
/// assert!((report.d50_mm - 11.16).abs() < 1e-3);
/// assert!((report.sigma_ln - 0.26).abs() < 1e-3);
/// assert_eq!(report.best, Model::LogNormal);
/// ```
pub fn fit_all(data: &SieveData) -> Result<FitReport> {
    let models = Model::ALL
        .iter()
        .map(|&m| fit_model(data, m))
        .collect::<Result<Vec<_>>>()?;
    let best = models
        .iter()
        .fold(None::<&ModelFit>, |b, f| match b {
            Some(b) if b.r2 >= f.r2 => Some(b),
            _ => Some(f),
        })
        .map(|f| f.model)
        .ok_or_else(|| Error::invalid("no model to fit"))?;
    let (d50_mm, sigma_ln) = match models.iter().find(|f| f.model == Model::LogNormal) {
        Some(ModelFit {
            dist: Distribution::LogNormal(l),
            ..
        }) => (l.x50_3, l.sigma),
        _ => return Err(Error::invalid("log-normal fit missing from the report")),
    };
    Ok(FitReport {
        source: data.source.clone(),
        n_points: data.len(),
        best,
        models,
        d50_mm,
        sigma_ln,
    })
}

/// Fits one model: linearised least squares as the start, then Nelder-Mead on the SSE in Q3.
pub fn fit_model(data: &SieveData, model: Model) -> Result<ModelFit> {
    let start = linearised_fit(data, model)?;
    let refined = refine(data, &start)?;
    let best = if sse(data, &refined) <= sse(data, &start) {
        refined
    } else {
        start
    };
    Ok(score(data, best))
}

/// R^2 and MSE of a given distribution against the sieve points.
pub fn score(data: &SieveData, dist: Distribution) -> ModelFit {
    let n = data.len() as f64;
    let mean = data.passing.iter().sum::<f64>() / n;
    let sst: f64 = data.passing.iter().map(|q| (q - mean).powi(2)).sum();
    let sse = sse(data, &dist);
    ModelFit {
        model: dist.model(),
        dist,
        r2: 1.0 - sse / sst,
        mse: sse / n,
        sse,
    }
}

fn sse(data: &SieveData, dist: &impl MassDistribution) -> f64 {
    data.size_mm
        .iter()
        .zip(&data.passing)
        .map(|(&x, &q)| (dist.q3(x) - q).powi(2))
        .sum()
}

/// The paper's fit: ordinary least squares of the linearised Q3 against ln x over the points
/// with 0 < Q3 < 1 (0 and 1 have no finite transform).
pub fn linearised_fit(data: &SieveData, model: Model) -> Result<Distribution> {
    let transform = |q: f64| match model {
        Model::Ggs => q.ln(),
        Model::Rrsb => (-(-q).ln_1p()).ln(),
        Model::LogNormal => phi_inv(q),
    };
    let interior = |q: f64| q > 0.0 && q < 1.0;
    let mut pts: Vec<(f64, f64)> = data
        .size_mm
        .iter()
        .zip(&data.passing)
        .filter(|(_, &q)| interior(q))
        .map(|(&x, &q)| (x.ln(), transform(q)))
        .collect();
    if pts.len() < 2 {
        // One interior point cannot fix a line; pulling the empty and full sieves slightly
        // inside (0, 1) gives a usable start, and the refinement then uses the true values.
        pts = data
            .size_mm
            .iter()
            .zip(&data.passing)
            .map(|(&x, &q)| (x.ln(), transform(q.clamp(0.01, 0.99))))
            .collect();
    }
    let (slope, intercept) = ols(&pts);
    // The shape parameter is the slope (1 / slope for the log-normal), and the scale is where
    // the line crosses zero: ln scale = -intercept / slope.
    let (scale, shape) = if slope.is_finite() && slope > 0.0 && intercept.is_finite() {
        let shape = match model {
            Model::LogNormal => 1.0 / slope,
            _ => slope,
        };
        ((-intercept / slope).exp(), shape)
    } else {
        // A flat start (all interior points equal): any positive guess will do for the
        // refinement; the geometric mean size is in the right region.
        let ln_mean = pts.iter().map(|p| p.0).sum::<f64>() / pts.len() as f64;
        let shape = if model == Model::LogNormal { 0.5 } else { 2.0 };
        (ln_mean.exp(), shape)
    };
    model.with_params(scale, shape).map_err(|e| {
        Error::input(
            &data.source,
            "passing",
            format!("the linearised {model} fit gives unusable parameters ({e})"),
        )
    })
}

fn ols(pts: &[(f64, f64)]) -> (f64, f64) {
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let slope = sxy / sxx;
    (slope, my - slope * mx)
}

/// SSE in Q3 over `[ln scale, ln shape]`: log parameters keep both positive without bounds.
struct LogSse<'a> {
    data: &'a SieveData,
    model: Model,
}

impl CostFunction for LogSse<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, p: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
        let c = match self.model.with_params(p[0].exp(), p[1].exp()) {
            Ok(d) => sse(self.data, &d),
            Err(_) => f64::INFINITY,
        };
        // Nelder-Mead compares costs; a NaN would break its ordering.
        Ok(if c.is_nan() { f64::INFINITY } else { c })
    }
}

/// Nelder-Mead from a simplex of `x0` and one step along each axis; returns (x, cost).
fn nelder_mead(
    cost: LogSse<'_>,
    x0: [f64; 2],
    step: [f64; 2],
) -> std::result::Result<([f64; 2], f64), argmin::core::Error> {
    let simplex = vec![
        x0.to_vec(),
        vec![x0[0] + step[0], x0[1]],
        vec![x0[0], x0[1] + step[1]],
    ];
    let res = Executor::new(cost, NelderMead::new(simplex))
        .configure(|s| s.max_iters(1000))
        .run()?;
    let state = res.state();
    let x = state.get_best_param().map_or(x0, |p| [p[0], p[1]]);
    Ok((x, state.get_best_cost()))
}

fn refine(data: &SieveData, start: &Distribution) -> Result<Distribution> {
    let model = start.model();
    let [(_, scale), (_, shape)] = start.params();
    let failed = |e: argmin::core::Error| {
        Error::invalid(format!("{}: {model} fit failed: {e}", data.source))
    };
    let mut x = [scale.ln(), shape.ln()];
    let mut best = f64::INFINITY;
    // A simplex can collapse onto a line short of the optimum (the SSE valley is long and bent
    // in the two log parameters); restarting with a fresh, smaller simplex at the last best
    // point costs little and stops only once a restart no longer improves the SSE.
    let mut step = [0.05, 0.1];
    for _ in 0..5 {
        let (next, cost) = nelder_mead(LogSse { data, model }, x, step).map_err(failed)?;
        if cost >= best {
            break;
        }
        let gain = best - cost;
        x = next;
        best = cost;
        if gain <= 1e-12 * best {
            break;
        }
        step = [step[0] * 0.5, step[1] * 0.5];
    }
    model.with_params(x[0].exp(), x[1].exp())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::psd::distribution::MassDistribution;

    fn synthetic(dist: &Distribution, sizes: &[f64]) -> SieveData {
        let passing = sizes.iter().map(|&x| dist.q3(x)).collect();
        SieveData::new("synthetic", sizes.to_vec(), passing).unwrap()
    }

    const SIZES: [f64; 10] = [2.0, 4.0, 5.6, 8.0, 10.0, 11.2, 12.5, 14.0, 16.0, 20.0];

    #[test]
    fn recovers_exact_parameters_and_picks_the_model() {
        let truths = [
            Model::Ggs.with_params(18.0, 1.7).unwrap(),
            Model::Rrsb.with_params(11.0, 2.4).unwrap(),
            Model::LogNormal.with_params(9.5, 0.45).unwrap(),
        ];
        for truth in truths {
            let data = synthetic(&truth, &SIZES);
            let rep = fit_all(&data).unwrap();
            assert_eq!(rep.best, truth.model(), "{rep:?}");
            let fit = rep.get(truth.model()).unwrap();
            for ((k, want), (_, got)) in truth.params().iter().zip(fit.dist.params()) {
                assert!(
                    (got / want - 1.0).abs() < 1e-4,
                    "{}: {k} = {got}, want {want}",
                    truth.model()
                );
            }
            assert!(fit.r2 > 1.0 - 1e-8 && fit.mse < 1e-10, "{fit:?}");
            // The other models cannot reproduce the curve exactly.
            for other in rep.models.iter().filter(|f| f.model != truth.model()) {
                assert!(other.r2 < fit.r2, "{other:?} vs {fit:?}");
            }
        }
    }

    #[test]
    fn refinement_lowers_sse_below_linearised_fit() {
        // Perturb the data so the linearised start is off; the refinement must then lower the
        // SSE in Q3 below the paper's linearised fit for every model.
        let truth = Model::LogNormal.with_params(11.0, 0.3).unwrap();
        let mut data = synthetic(&truth, &SIZES);
        for (i, q) in data.passing.iter_mut().enumerate() {
            *q = (*q + if i % 2 == 0 { 0.004 } else { -0.004 }).clamp(0.0, 1.0);
        }
        for i in 1..data.passing.len() {
            data.passing[i] = data.passing[i].max(data.passing[i - 1]);
        }
        for model in Model::ALL {
            let lin = score(&data, linearised_fit(&data, model).unwrap());
            let fit = fit_model(&data, model).unwrap();
            assert!(fit.sse < lin.sse, "{model}: {} !< {}", fit.sse, lin.sse);
        }
    }

    #[test]
    fn refinement_reaches_the_least_squares_optimum() {
        // A brute-force grid over +-20 % in both parameters around the fit must not find a
        // lower SSE (the grid is coarse, so allow for its resolution but not more).
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/sieve_gravel_8_16.csv"
        );
        let data = SieveData::read(std::path::Path::new(path)).unwrap();
        for model in Model::ALL {
            let fit = fit_model(&data, model).unwrap();
            let [(_, a), (_, b)] = fit.dist.params();
            let k = 200;
            let mut grid_min = f64::INFINITY;
            for i in 0..=k {
                for j in 0..=k {
                    let fa = 0.8 + 0.4 * i as f64 / k as f64;
                    let fb = 0.8 + 0.4 * j as f64 / k as f64;
                    let d = model.with_params(a * fa, b * fb).unwrap();
                    grid_min = grid_min.min(sse(&data, &d));
                }
            }
            assert!(
                fit.sse <= grid_min * (1.0 + 1e-9),
                "{model}: fit SSE {} > grid SSE {grid_min}",
                fit.sse
            );
        }
    }

    #[test]
    fn one_interior_point_still_fits() {
        let data = SieveData::new("one", vec![4.0, 8.0, 16.0], vec![0.0, 0.5, 1.0]).unwrap();
        let rep = fit_all(&data).unwrap();
        for f in &rep.models {
            assert!(f.r2.is_finite() && f.r2 > 0.9, "{f:?}");
        }
    }

    #[test]
    fn json_has_model_params_r2_mse() {
        let truth = Model::LogNormal.with_params(11.16, 0.26).unwrap();
        let rep = fit_all(&synthetic(&truth, &SIZES)).unwrap();
        let v = serde_json::to_value(&rep).unwrap();
        assert_eq!(v["best"], "lognormal");
        let m = &v["models"][2];
        assert_eq!(m["model"], "lognormal");
        assert!(m["params"]["x50_3_mm"].as_f64().is_some());
        assert!(m["params"]["sigma_ln"].as_f64().is_some());
        assert!(m["r2"].as_f64().is_some() && m["mse"].as_f64().is_some());
        assert!((v["d50_mm"].as_f64().unwrap() / 11.16 - 1.0).abs() < 1e-4);
    }
}
