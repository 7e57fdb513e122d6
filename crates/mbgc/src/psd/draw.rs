//! Drawing particle diameters by number so that the drawn set has a given mass distribution.
//!
//! A DEM inserts particles one by one, so sizes are drawn per particle (by number), while sieve
//! data and the fitted Q3 are by mass. The number density is q0(x) ∝ q3(x) / x^3: many fines
//! carry as much mass as a few coarse particles. The mass-weighted distribution of the drawn set
//! then follows Q3 truncated to [d_min, d_max]:
//! (Q3(x) - Q3(d_min)) / (Q3(d_max) - Q3(d_min)).

use rand::RngExt;

use super::distribution::{phi, phi_inv, Basis, Distribution, LogNormal, MassDistribution};
use crate::error::{Error, Result};
use crate::sampling::rng;

/// Default trim: the mass fraction left out at each end when no range is given.
///
/// The log-normal and RRSB tails are unbounded: untrimmed, one rare huge particle would set the
/// box size of the DEM domain, and the fine tail would add a vast number of tiny particles that
/// control the time step while carrying almost no mass. Trimming 1 % of the mass at each end
/// (the Q3 quantiles 0.01 and 0.99) keeps 98 % of the mass and both problems bounded.
pub const DEFAULT_TRIM: f64 = 0.01;

/// Least number of cells of the log-size grid used to invert the number cdf of GGS and RRSB.
/// The cdf error of the grid is O(h^2) in the cell width h; wide ranges get more cells so that
/// h stays below [`MAX_CELL_WIDTH`] (up to 2^20 cells).
pub const GRID_CELLS: usize = 8192;

/// Largest cell width in ln(x) of the inversion grid: a cdf error of order 1e-7, far below the
/// sampling noise of any practical N.
pub const MAX_CELL_WIDTH: f64 = 1e-3;

/// The default size range [Q3^-1(DEFAULT_TRIM), Q3^-1(1 - DEFAULT_TRIM)] in mm.
pub fn default_range(dist: &Distribution) -> (f64, f64) {
    (dist.q3_inv(DEFAULT_TRIM), dist.q3_inv(1.0 - DEFAULT_TRIM))
}

/// The sizes an experiment draws for a material of mass median `d50_mm` and log-normal width
/// `sigma_ln`: the distribution and its [`default_range`], or one size (`None`, d50, d50) when
/// `sigma_ln` is not positive. Refuses what [`LogNormal::new`] refuses.
pub fn sizes_drawn(d50_mm: f64, sigma_ln: f64) -> Result<(Option<Distribution>, f64, f64)> {
    if sigma_ln > 0.0 {
        let dist = Distribution::LogNormal(LogNormal::new(d50_mm, sigma_ln)?);
        let (a, b) = default_range(&dist);
        Ok((Some(dist), a, b))
    } else {
        Ok((None, d50_mm, d50_mm))
    }
}

/// Q3 truncated to [d_min, d_max] and renormalised: the target mass cdf of a drawn set.
pub fn truncated_q3(dist: &Distribution, (d_min, d_max): (f64, f64), x: f64) -> f64 {
    let lo = dist.q3(d_min);
    let f = (dist.q3(x.clamp(d_min, d_max)) - lo) / (dist.q3(d_max) - lo);
    f.clamp(0.0, 1.0)
}

/// A drawn particle set.
#[derive(Debug, Clone, PartialEq)]
pub struct ParticleSet {
    /// Particle diameters in drawing order, mm; their number density is q0 ∝ q3 / x^3 on [d_min,
    /// d_max].
    pub diameters_mm: Vec<f64>,
    /// Lower end of the size range used, mm; no drawn diameter is smaller.
    pub d_min: f64,
    /// Upper end of the size range used, mm; no drawn diameter is larger.
    pub d_max: f64,
    /// Mass fraction of the full distribution inside the range, Q3(d_max) - Q3(d_min).
    pub mass_fraction: f64,
}

impl ParticleSet {
    /// Number-weighted mean diameter, mm; well below the mass median for wide distributions.
    pub fn count_mean(&self) -> f64 {
        self.diameters_mm.iter().sum::<f64>() / self.diameters_mm.len() as f64
    }

    /// Diameter below which half of the drawn mass lies.
    pub fn mass_median(&self) -> f64 {
        let mut d = self.diameters_mm.clone();
        d.sort_by(f64::total_cmp);
        let total: f64 = d.iter().map(|x| x.powi(3)).sum();
        let mut acc = 0.0;
        for &x in &d {
            acc += x.powi(3);
            if acc >= 0.5 * total {
                return x;
            }
        }
        d.last().copied().unwrap_or(f64::NAN)
    }
}

/// Draws `n` diameters (mm) by number from `dist` restricted to `range` (default:
/// [`default_range`]). Deterministic for a given seed. `source` names where the request came
/// from (e.g. the command line) in errors; the fields are `n`, `d_min` and `d_max`.
pub fn draw_by_number(
    dist: &Distribution,
    range: (Option<f64>, Option<f64>),
    n: usize,
    seed: u64,
    source: &str,
) -> Result<ParticleSet> {
    if n == 0 {
        return Err(Error::input(
            source,
            "n",
            "expected at least 1 particle, found 0",
        ));
    }
    let (dmin_default, dmax_default) = default_range(dist);
    let d_min = range.0.unwrap_or(dmin_default);
    let d_max = range.1.unwrap_or(dmax_default);
    for (name, v) in [("d_min", d_min), ("d_max", d_max)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::input(
                source,
                name,
                format!("expected a finite positive diameter in mm, found {v}"),
            ));
        }
    }
    if d_min >= d_max {
        // Name the bound the user gave; the other one is the distribution's default.
        let given = |v: Option<f64>| if v.is_some() { "given" } else { "default" };
        let field = if range.0.is_some() { "d_min" } else { "d_max" };
        return Err(Error::input(
            source,
            field,
            format!(
                "expected d_min < d_max, found d_min = {d_min} mm ({}) >= d_max = {d_max} mm ({})",
                given(range.0),
                given(range.1)
            ),
        ));
    }
    let mass_fraction = dist.q3(d_max) - dist.q3(d_min);
    // Below this there is no meaningful mass to distribute (and the cdf differences are noise).
    if mass_fraction.is_nan() || mass_fraction <= 1e-12 {
        return Err(Error::input(
            source,
            "d_min, d_max",
            format!(
                "the range [{d_min}, {d_max}] mm holds no mass of the distribution ({}); \
                 expected a range overlapping it, e.g. the default [{dmin_default:.4}, \
                 {dmax_default:.4}] mm",
                dist.describe()
            ),
        ));
    }
    let mut diameters_mm = Vec::new();
    diameters_mm
        .try_reserve_exact(n)
        .map_err(|_| Error::input(source, "n", format!("{n} particles do not fit in memory")))?;
    match dist {
        Distribution::LogNormal(l) => draw_lognormal(l, d_min, d_max, n, seed, &mut diameters_mm),
        _ => draw_numeric(dist, d_min, d_max, n, seed, &mut diameters_mm),
    }
    Ok(ParticleSet {
        diameters_mm,
        d_min,
        d_max,
        mass_fraction,
    })
}

/// Hatch-Choate: by number the log-normal keeps its sigma and has the median
/// x50_0 = x50_3 exp(-3 sigma^2); draw the truncated normal in ln x by inverse cdf.
fn draw_lognormal(l: &LogNormal, d_min: f64, d_max: f64, n: usize, seed: u64, out: &mut Vec<f64>) {
    let ln_med = l.median(Basis::Number).ln();
    let za = (d_min.ln() - ln_med) / l.sigma;
    let zb = (d_max.ln() - ln_med) / l.sigma;
    // In the upper tail Phi(z) is close to 1 and loses digits; reflecting works with the small
    // lower-tail values instead.
    let flip = za > 0.0;
    let (a, b) = if flip { (-zb, -za) } else { (za, zb) };
    let (pa, pb) = (phi(a), phi(b));
    if pb.is_nan() || pb <= pa {
        // Both bounds so far out (|z| > ~38) that Phi underflows: the grid method still works.
        draw_numeric(&Distribution::LogNormal(*l), d_min, d_max, n, seed, out);
        return;
    }
    let mut r = rng(seed);
    out.extend((0..n).map(|_| {
        let u: f64 = r.random();
        let z = phi_inv(pa + u * (pb - pa)).clamp(a, b);
        let z = if flip { -z } else { z };
        (ln_med + l.sigma * z).exp().clamp(d_min, d_max)
    }));
}

/// Tabulates the number cdf on a log grid and inverts it. The number in a cell is its exact
/// mass Q3(x_i+1) - Q3(x_i) divided by x^3 at the cell's geometric centre; inside a cell sizes are
/// uniform in ln x.
fn draw_numeric(
    dist: &Distribution,
    d_min: f64,
    d_max: f64,
    n: usize,
    seed: u64,
    out: &mut Vec<f64>,
) {
    let (grid, cdf) = number_cdf_table(dist, d_min, d_max);
    let total = cdf[cdf.len() - 1];
    let mut r = rng(seed);
    out.extend((0..n).map(|_| {
        let t = r.random::<f64>() * total;
        // First grid node whose cdf exceeds t; the cell is [i - 1, i].
        let i = cdf.partition_point(|&c| c <= t).clamp(1, cdf.len() - 1);
        let (c0, c1) = (cdf[i - 1], cdf[i]);
        let w = if c1 > c0 { (t - c0) / (c1 - c0) } else { 0.5 };
        (grid[i - 1] + w * (grid[i] - grid[i - 1]))
            .exp()
            .clamp(d_min, d_max)
    }));
}

/// ln-size grid and unnormalised number cdf at its nodes.
fn number_cdf_table(dist: &Distribution, d_min: f64, d_max: f64) -> (Vec<f64>, Vec<f64>) {
    let (u0, u1) = (d_min.ln(), d_max.ln());
    let cells = ((u1 - u0) / MAX_CELL_WIDTH)
        .ceil()
        .clamp(GRID_CELLS as f64, (1 << 20) as f64) as usize;
    let h = (u1 - u0) / cells as f64;
    let grid: Vec<f64> = (0..=cells).map(|i| u0 + h * i as f64).collect();
    // ln(number in cell) = ln(mass in cell) - 3 ln(x_mid); shifted by its maximum before exp so
    // that neither x^-3 nor tiny masses under- or overflow, whatever the range.
    let mut q_prev = dist.q3(d_min);
    let ln_count: Vec<f64> = grid[1..]
        .iter()
        .map(|&u| {
            let q = dist.q3(u.exp());
            let dm = q - q_prev;
            q_prev = q;
            if dm > 0.0 {
                dm.ln() - 3.0 * (u - 0.5 * h)
            } else {
                f64::NEG_INFINITY
            }
        })
        .collect();
    let top = ln_count.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut cdf = Vec::with_capacity(grid.len());
    cdf.push(0.0);
    let mut acc = 0.0;
    for l in ln_count {
        acc += (l - top).exp();
        cdf.push(acc);
    }
    (grid, cdf)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::psd::distribution::Model;

    #[test]
    fn numeric_table_matches_hatch_choate() {
        // The grid method applied to a log-normal must reproduce the analytic number cdf.
        let l = LogNormal::new(11.16, 0.5).unwrap();
        let dist = Distribution::LogNormal(l);
        let (d_min, d_max) = default_range(&dist);
        let (grid, cdf) = number_cdf_table(&dist, d_min, d_max);
        let total = cdf[cdf.len() - 1];
        let (f_lo, f_hi) = (l.cdf(Basis::Number, d_min), l.cdf(Basis::Number, d_max));
        let max_err = grid
            .iter()
            .zip(&cdf)
            .map(|(u, c)| {
                let exact = (l.cdf(Basis::Number, u.exp()) - f_lo) / (f_hi - f_lo);
                (c / total - exact).abs()
            })
            .fold(0.0, f64::max);
        assert!(max_err < 1e-6, "max cdf error {max_err}");
    }

    #[test]
    fn extreme_ranges_still_draw_inside_the_mass() {
        // Steep GGS over 110 decades: x^-3 alone would underflow to 0 near the top, where all
        // the mass is. Particles must land where Q3 rises (x > 0.95 holds 1 - 0.95^1000 of it).
        let ggs = Model::Ggs.with_params(1.0, 1000.0).unwrap();
        let set = draw_by_number(&ggs, (Some(1e-110), Some(1.0)), 200, 5, "t").unwrap();
        assert!(set.diameters_mm.iter().all(|&d| d > 0.95 && d <= 1.0));
        // sigma_ln = 15, range from 46 sigma above the number median: Phi underflows, so the
        // log-normal falls back to the grid. There the number density in t = ln(x / lo) is
        // ~ exp(-46 t / 15): median t = ln 2 * 15 / 46 = 0.226 (SE 0.007 for n = 2000).
        let logn = Model::LogNormal.with_params(1.0, 15.0).unwrap();
        let (lo, hi) = (15f64.exp(), 30f64.exp());
        let set = draw_by_number(&logn, (Some(lo), Some(hi)), 2000, 5, "t").unwrap();
        assert!((set.mass_fraction - (phi(2.0) - phi(1.0))).abs() < 1e-9);
        let mut t: Vec<f64> = set.diameters_mm.iter().map(|d| (d / lo).ln()).collect();
        t.sort_by(f64::total_cmp);
        let median = t[t.len() / 2];
        assert!(
            (median - 2f64.ln() * 15.0 / 46.0).abs() < 0.03,
            "median {median}"
        );
    }

    #[test]
    fn ggs_number_cdf_is_a_power_law() {
        // For GGS q0 ∝ x^(m-4), so the number cdf on [a, b] is (x^(m-3) - a^(m-3)) / (...).
        let dist = Model::Ggs.with_params(16.0, 2.0).unwrap();
        let (a, b) = (2.0, 16.0);
        let (grid, cdf) = number_cdf_table(&dist, a, b);
        let total = cdf[cdf.len() - 1];
        let f = |x: f64| (x.powf(-1.0) - a.powf(-1.0)) / (b.powf(-1.0) - a.powf(-1.0));
        let max_err = grid
            .iter()
            .zip(&cdf)
            .map(|(u, c)| (c / total - f(u.exp())).abs())
            .fold(0.0, f64::max);
        assert!(max_err < 1e-6, "max cdf error {max_err}");
    }
}
