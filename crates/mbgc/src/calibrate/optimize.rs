//! Deterministic inversion: L-BFGS (argmin) from many space-filling starts, distinct optima
//! clustered, and the solution set described when the data cannot pin every parameter.
//!
//! Bounds are handled by the transform `x = lo + (hi - lo) (1 + sin z) / 2` (as in MINUIT): the
//! search is unconstrained in `z`, every `z` is inside the box and a bound is reached at a finite
//! `z`. Constraints between parameters enter as a quadratic penalty (see [`Problem::objective`]).

use super::objective::Objective;
use super::problem::Problem;
use argmin::core::{CostFunction, Executor, Gradient, State};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use nalgebra::DMatrix;
use rayon::prelude::*;
use serde::Serialize;

type Best = std::sync::Arc<std::sync::Mutex<Option<(f64, Vec<f64>)>>>;

struct Transformed<'a, O: Objective + ?Sized> {
    p: &'a O,
    /// The lowest finite objective evaluated so far and where: argmin returns no state when a
    /// cost or gradient stops the run, and the start must then report where it got to, not where
    /// it began.
    best: Best,
}

impl<O: Objective + ?Sized> Transformed<'_, O> {
    fn x(&self, z: &[f64]) -> Vec<f64> {
        let (lo, hi) = (self.p.lower(), self.p.upper());
        z.iter()
            .enumerate()
            .map(|(j, z)| lo[j] + (hi[j] - lo[j]) * 0.5 * (1.0 + z.sin()))
            .collect()
    }
}

/// Large but finite, so the line search backs off instead of failing.
const OUTSIDE: f64 = 1e30;
/// Largest objective or gradient entry the optimiser works with: its products in L-BFGS must stay
/// finite.
const HUGE: f64 = 1e100;

impl<O: Objective + ?Sized> CostFunction for Transformed<'_, O> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, z: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        let f = self.p.objective(&self.x(z)).map_or(OUTSIDE, |(f, _)| f);
        if f.is_finite() && f <= HUGE {
            let mut best = self.best.lock().unwrap_or_else(|e| e.into_inner());
            if best.as_ref().is_none_or(|(b, _)| f < *b) {
                *best = Some((f, z.clone()));
            }
        }
        // argmin's line search has no iteration bound of its own: a NaN or an objective whose
        // squares overflow would keep it searching forever. Stop this start instead.
        if !(f.is_finite() && f.abs() <= HUGE) {
            return Err(argmin::core::Error::msg(format!(
                "objective {f:e} is beyond {HUGE:e}"
            )));
        }
        Ok(f)
    }
}

impl<O: Objective + ?Sized> Gradient for Transformed<'_, O> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, z: &Vec<f64>) -> Result<Vec<f64>, argmin::core::Error> {
        let Some((_, g)) = self.p.objective(&self.x(z)) else {
            return Ok(vec![0.0; z.len()]);
        };
        let g: Vec<f64> = g
            .iter()
            .enumerate()
            .map(|(j, g)| g * (self.p.upper()[j] - self.p.lower()[j]) * 0.5 * z[j].cos())
            .collect();
        if g.iter().any(|v| !(v.is_finite() && v.abs() <= HUGE)) {
            return Err(argmin::core::Error::msg(
                "gradient beyond the representable range",
            ));
        }
        Ok(g)
    }
}

/// A local minimum of the calibration objective, reached by one or more starts.
#[derive(Clone, Debug, Serialize)]
pub struct Optimum {
    /// Free parameters (physical units), in [`Problem::free`] order.
    pub x: Vec<f64>,
    /// chi^2 = sum of squared normalised residuals, the constraint penalty excluded: below about 1
    /// per measured response, the model matches the measurements within their sd.
    pub chi2: f64,
    /// 2 sum ln(sd / measured sd): what the rigid limit's scatter adds to -2 ln L beyond the
    /// model's data (0 inside). Optima are ranked by chi^2 plus this.
    pub sd_term: f64,
    /// Sum of squared constraint and group-domain violations (0: feasible).
    pub violation: f64,
    /// The model's predictions of the measured responses, in [`Problem::targets`] order.
    pub predictions: Vec<f64>,
    /// Normalised residuals `(prediction - measured) / sd`, same order.
    pub residuals: Vec<f64>,
    /// Starts that ended here.
    pub starts: usize,
}

/// One L-BFGS run of any [`Objective`] from unit coordinates `u0`: where it ended (physical
/// units), or `None` when the solver could not be set up.
pub fn minimize<O: Objective + ?Sized>(p: &O, u0: &[f64], max_iters: u64) -> Option<Vec<f64>> {
    let best = Best::default();
    let op = Transformed {
        p,
        best: best.clone(),
    };
    let z0: Vec<f64> = u0
        .iter()
        .map(|u| (2.0 * u.clamp(0.0, 1.0) - 1.0).asin())
        .collect();
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 7)
        .with_tolerance_grad(1e-10)
        .ok()?
        .with_tolerance_cost(1e-15)
        .ok()?;
    let z = match Executor::new(op, solver)
        .configure(|s| s.param(z0.clone()).max_iters(max_iters))
        .run()
    {
        Ok(r) => r.state.get_best_param().cloned().unwrap_or(z0),
        Err(_) => best
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
            .map_or(z0, |(_, z)| z),
    };
    let op = Transformed {
        p,
        best: Best::default(),
    };
    Some(op.x(&z))
}

/// One L-BFGS run from unit coordinates `u0`.
pub fn local(p: &Problem, u0: &[f64], max_iters: u64) -> Option<Optimum> {
    let x = minimize(p, u0, max_iters)?;
    let (chi2_total, _) = p.objective(&x)?;
    let violation = p.violation(&x);
    let residuals = p.residuals(&x);
    let chi2 = residuals.iter().map(|r| r * r).sum();
    let sd_term = p.sd_term(&x);
    debug_assert!(chi2 + sd_term <= chi2_total + 1e-9);
    Some(Optimum {
        predictions: p.predictions(&x),
        x,
        chi2,
        sd_term,
        violation,
        residuals,
        starts: 1,
    })
}

/// Start points: Owen-scrambled Sobol points of the free unit cube.
pub fn starts(dim: usize, n: usize, seed: u64) -> Vec<Vec<f64>> {
    let s = (seed as u32) ^ ((seed >> 32) as u32);
    (0..n as u32)
        .map(|i| {
            (0..dim as u32)
                .map(|d| sobol_burley::sample(i, d, s) as f64)
                .collect()
        })
        .collect()
}

/// A direction in parameter space along which the measured responses barely change: a
/// combination of parameters the data cannot determine.
#[derive(Clone, Debug, Serialize)]
pub struct Direction {
    /// Singular value (change of the normalised residuals per unit step in unit coordinates).
    pub singular_value: f64,
    /// Unit-coordinate components, in [`Problem::free`] order.
    pub components: Vec<f64>,
}

/// The interval a free parameter spans over the equally good optima.
#[derive(Clone, Debug, Serialize)]
pub struct Range {
    /// The parameter's name.
    pub name: String,
    /// Smallest value among the equally good optima (physical units; +inf if there are none).
    pub min: f64,
    /// Largest value among them (-inf if there are none).
    pub max: f64,
}

/// The result of a multi-start calibration: every distinct optimum and, when the measurements
/// cannot fix every free parameter, a description of the solution set.
#[derive(Clone, Debug, Serialize)]
pub struct Calibration {
    /// Names of the free parameters, the order of every `x`.
    pub parameters: Vec<String>,
    /// Distinct optima, best first.
    pub optima: Vec<Optimum>,
    /// Free parameters minus measured responses (> 0: the data cannot fix all of them).
    pub excess_parameters: isize,
    /// Directions (at the best optimum) along which the predictions barely change: the
    /// right-singular vectors of the residual Jacobian with singular value below 1e-3 of the
    /// largest, plus the null space when there are more parameters than responses.
    pub flat_directions: Vec<Direction>,
    /// Range of each free parameter over the optima as good as the best (chi^2 within 1): the
    /// spread of the solution set found by the starts.
    pub solution_ranges: Vec<Range>,
    /// L-BFGS starts requested (Sobol points of the unit cube).
    pub starts: usize,
    /// Wall-clock time of the whole search, s.
    pub seconds: f64,
}

/// Jacobian of the normalised residuals with respect to unit coordinates, by central differences
/// of the exact predictions (cheap: one equation evaluation per entry).
fn jacobian(p: &Problem, x: &[f64]) -> DMatrix<f64> {
    let (m, n) = (p.targets.len(), p.dim());
    let mut j = DMatrix::zeros(m, n);
    for c in 0..n {
        let h = 1e-6 * (p.upper[c] - p.lower[c]);
        let (mut a, mut b) = (x.to_vec(), x.to_vec());
        a[c] = (x[c] + h).min(p.upper[c]);
        b[c] = (x[c] - h).max(p.lower[c]);
        let (ra, rb) = (p.residuals(&a), p.residuals(&b));
        let du = (a[c] - b[c]) / (p.upper[c] - p.lower[c]);
        for r in 0..m {
            j[(r, c)] = (ra[r] - rb[r]) / du;
        }
    }
    j
}

fn flat_directions(p: &Problem, x: &[f64]) -> Vec<Direction> {
    let j = jacobian(p, x);
    let n = p.dim();
    // Eigen-decomposition of J^T J (n x n) gives every right-singular vector, null space included.
    let jtj = j.transpose() * &j;
    let eig = jtj.symmetric_eigen();
    let smax = eig
        .eigenvalues
        .iter()
        .fold(0.0f64, |m, v| m.max(v.max(0.0).sqrt()));
    let mut out: Vec<Direction> = (0..n)
        .filter_map(|i| {
            let s = eig.eigenvalues[i].max(0.0).sqrt();
            (s <= 1e-3 * smax.max(1e-300)).then(|| Direction {
                singular_value: s,
                components: eig.eigenvectors.column(i).iter().copied().collect(),
            })
        })
        .collect();
    out.sort_by(|a, b| a.singular_value.total_cmp(&b.singular_value));
    out
}

/// Multi-start calibration: L-BFGS from `n_starts` scrambled Sobol points (seeded by `seed`) in
/// parallel, at most 500 iterations each. Optima within 0.02 of each other in unit coordinates
/// and with chi^2 equal to 1e-3 (relative) are one solution; the result lists them best first.
pub fn calibrate(p: &Problem, n_starts: usize, seed: u64) -> Calibration {
    let t = std::time::Instant::now();
    let n = p.dim();
    let mut found: Vec<Optimum> = if n == 0 {
        local(p, &[], 1).into_iter().collect()
    } else {
        starts(n, n_starts, seed)
            .par_iter()
            .filter_map(|u| local(p, u, 500))
            .collect()
    };
    let rank = |o: &Optimum| o.chi2 + o.sd_term + o.violation * 1e6;
    found.sort_by(|a, b| rank(a).total_cmp(&rank(b)));
    // Cluster: an optimum within 2 % of the box (unit distance) of a kept one, with a chi^2
    // within 1e-3 of it, is the same solution.
    let unit = |x: &[f64]| -> Vec<f64> {
        x.iter()
            .enumerate()
            .map(|(j, v)| (v - p.lower[j]) / (p.upper[j] - p.lower[j]))
            .collect()
    };
    let best = found.first().map_or(f64::INFINITY, |o| o.chi2 + o.sd_term);
    let good: Vec<&Optimum> = found
        .iter()
        .filter(|o| o.chi2 + o.sd_term <= best + 1.0 && o.violation < 1e-8)
        .collect();
    let solution_ranges = (0..n)
        .map(|j| Range {
            name: p.names[p.free[j]].clone(),
            min: good.iter().map(|o| o.x[j]).fold(f64::INFINITY, f64::min),
            max: good
                .iter()
                .map(|o| o.x[j])
                .fold(f64::NEG_INFINITY, f64::max),
        })
        .collect();
    let mut optima: Vec<Optimum> = Vec::new();
    for o in found {
        let uo = unit(&o.x);
        let same = optima.iter_mut().find(|k| {
            let uk = unit(&k.x);
            let d = uo
                .iter()
                .zip(&uk)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt();
            d < 0.02 && (o.chi2 - k.chi2).abs() <= 1e-3 * (1.0 + k.chi2)
        });
        match same {
            Some(k) => k.starts += 1,
            None => optima.push(o),
        }
    }
    // With every parameter fixed there is nothing to vary (and no Jacobian to decompose).
    let flat = optima
        .first()
        .filter(|_| n > 0)
        .map(|o| flat_directions(p, &o.x))
        .unwrap_or_default();
    Calibration {
        parameters: p.free_names().iter().map(|s| s.to_string()).collect(),
        optima,
        excess_parameters: n as isize - p.targets.len() as isize,
        flat_directions: flat,
        solution_ranges,
        starts: n_starts,
        seconds: t.elapsed().as_secs_f64(),
    }
}
