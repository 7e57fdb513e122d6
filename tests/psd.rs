//! PSD: sieve reading, fitting the example file, drawing particles by number.

use std::path::PathBuf;

use mbgc::psd::{
    default_range, draw_by_number, fit_all, truncated_q3, Basis, Distribution, MassDistribution,
    Model, SieveData,
};

fn example() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/sieve_gravel_8_16.csv")
}

// ---------------------------------------------------------------------------------------------
// Sieve reader

fn write_csv(dir: &tempfile::TempDir, name: &str, text: &str) -> PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn sieve_reader_accepts_fraction_and_percent() {
    let dir = tempfile::tempdir().unwrap();
    let pct = write_csv(
        &dir,
        "pct.csv",
        "sieve,size_mm,passing_pct\nA, 4,0\nB,8,25.5\nC,16,100\n",
    );
    let frac = write_csv(&dir, "frac.csv", "size_mm,passing\n4,0\n8,0.255\n16,1\n");
    let a = SieveData::read(&pct).unwrap();
    let b = SieveData::read(&frac).unwrap();
    assert_eq!(a.size_mm, vec![4.0, 8.0, 16.0]);
    assert_eq!(a.size_mm, b.size_mm);
    for (x, y) in a.passing.iter().zip(&b.passing) {
        assert!((x - y).abs() < 1e-15, "{x} vs {y}");
    }
    assert!(a.source.ends_with("pct.csv"));
}

#[test]
fn sieve_reader_errors_name_file_and_column() {
    // (case, file content, what the message must name besides the file)
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "no_size_column",
            "size,passing\n4,0\n8,0.5\n16,1\n",
            &["size_mm"],
        ),
        (
            "no_passing_column",
            "size_mm,fraction\n4,0\n8,0.5\n16,1\n",
            &["passing"],
        ),
        (
            "both_passing_columns",
            "size_mm,passing,passing_pct\n4,0,0\n8,0.5,50\n16,1,100\n",
            &["passing", "passing_pct"],
        ),
        (
            "non_numeric_size",
            "size_mm,passing\n4,0\n8mm,0.5\n16,1\n",
            &["line 3", "size_mm", "8mm"],
        ),
        (
            "non_numeric_passing",
            "size_mm,passing_pct\n4,0\n8,\n16,100\n",
            &["line 3", "passing_pct"],
        ),
        (
            "nan_passing",
            "size_mm,passing\n4,0\n8,NaN\n16,1\n",
            &["line 3", "passing", "finite"],
        ),
        (
            "inf_size",
            "size_mm,passing\n4,0\ninf,0.5\n16,1\n",
            &["line 3", "size_mm", "finite"],
        ),
        (
            "zero_size",
            "size_mm,passing\n0,0\n8,0.5\n16,1\n",
            &["line 2", "size_mm", "positive"],
        ),
        (
            "negative_size",
            "size_mm,passing\n-4,0\n8,0.5\n16,1\n",
            &["line 2", "size_mm", "positive"],
        ),
        (
            "fraction_above_one",
            "size_mm,passing\n4,0\n8,0.5\n16,1.2\n",
            &["line 4", "passing", "[0, 1]"],
        ),
        (
            "percent_above_100",
            "size_mm,passing_pct\n4,0\n8,50\n16,100.5\n",
            &["line 4", "passing_pct", "[0, 100]"],
        ),
        (
            "negative_passing",
            "size_mm,passing\n4,-0.1\n8,0.5\n16,1\n",
            &["line 2", "passing"],
        ),
        (
            "sizes_not_increasing",
            "size_mm,passing\n4,0\n8,0.5\n8,0.7\n16,1\n",
            &["line 4", "size_mm", "increasing"],
        ),
        (
            "sizes_descending",
            "size_mm,passing\n16,1\n8,0.5\n4,0\n",
            &["line 3", "size_mm", "increasing"],
        ),
        (
            "passing_decreasing",
            "size_mm,passing_pct\n4,0\n8,60\n11.2,55\n16,100\n",
            &["line 4", "passing_pct", "decrease"],
        ),
        (
            "too_few_points",
            "size_mm,passing\n8,0.5\n16,1\n",
            &["size_mm", "at least 3"],
        ),
        (
            "header_only",
            "size_mm,passing\n",
            &["size_mm", "at least 3"],
        ),
        (
            "no_interior_point",
            "size_mm,passing\n4,0\n8,0\n16,1\n",
            &["passing", "strictly between"],
        ),
        (
            "constant_passing",
            "size_mm,passing\n4,0.5\n8,0.5\n16,0.5\n",
            &["passing", "equal"],
        ),
        (
            "ragged_row",
            "size_mm,passing\n4,0\n8,0.5,extra\n16,1\n",
            &["line 3", "fields"],
        ),
        ("empty_file", "", &["size_mm"]),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (case, text, needles) in cases {
        let path = write_csv(&dir, &format!("sieve_{case}.csv"), text);
        let err = match SieveData::read(&path) {
            Ok(d) => panic!("{case}: accepted {d:?}"),
            Err(e) => e.to_string(),
        };
        assert!(
            err.contains(&path.display().to_string()),
            "{case}: message does not name the file: {err}"
        );
        for n in *needles {
            assert!(err.contains(n), "{case}: message lacks \"{n}\": {err}");
        }
    }
}

#[test]
fn sieve_reader_missing_file_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no_such_sieve.csv");
    let err = SieveData::read(&path).unwrap_err().to_string();
    assert!(err.contains("no_such_sieve.csv"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Fitting the example file

#[test]
fn example_sieve_file_fits_lognormal_near_paper_values() {
    let data = SieveData::read(&example()).unwrap();
    let rep = fit_all(&data).unwrap();
    let logn = rep.get(Model::LogNormal).unwrap();
    let best = rep.best_fit().unwrap();
    // The example mimics Gravel 8/16 of Richter & Will (2021), Table 3: d50 = 11.16 mm,
    // sigma_ln = 0.26.
    assert!(
        best.model == Model::LogNormal || best.r2 - logn.r2 < 1e-3,
        "best {best:?}, log-normal {logn:?}"
    );
    assert!(
        (rep.d50_mm / 11.16 - 1.0).abs() < 0.03,
        "d50 = {}",
        rep.d50_mm
    );
    assert!(
        (rep.sigma_ln / 0.26 - 1.0).abs() < 0.05,
        "sigma_ln = {}",
        rep.sigma_ln
    );
    // As in the paper's Table 1, GGS is the worst of the three.
    let ggs = rep.get(Model::Ggs).unwrap();
    assert!(rep.models.iter().all(|f| f.r2 >= ggs.r2), "{rep:?}");
    // R^2 and MSE are those of the reported parameters, recomputed here from the data.
    let n = data.len() as f64;
    let mean = data.passing.iter().sum::<f64>() / n;
    let sst: f64 = data.passing.iter().map(|q| (q - mean).powi(2)).sum();
    for f in &rep.models {
        let sse: f64 = data
            .size_mm
            .iter()
            .zip(&data.passing)
            .map(|(&x, &q)| (f.dist.q3(x) - q).powi(2))
            .sum();
        assert!((f.sse / sse - 1.0).abs() < 1e-12, "{f:?}: SSE {sse}");
        assert!((f.mse / (sse / n) - 1.0).abs() < 1e-12, "{f:?}");
        assert!((f.r2 - (1.0 - sse / sst)).abs() < 1e-12, "{f:?}");
    }
}

/// The least-squares optimum of each model on the example file, as printed by
/// `mbgc psd fit examples/sieve_gravel_8_16.csv` and listed in the guide's PSD chapter (docs/guide/src/psd.md): the fit is a unique
/// minimum, so any solver that reaches it must reproduce these digits.
#[test]
fn example_sieve_fits_reproduce_the_published_table() {
    let data = SieveData::read(&example()).unwrap();
    let rep = fit_all(&data).unwrap();
    // (model, scale mm, shape, R^2), each to half a unit of the last printed digit.
    let table = [
        (Model::Ggs, 14.8097, 2.8589, 0.98449),
        (Model::Rrsb, 12.3596, 4.2872, 0.99629),
        (Model::LogNormal, 11.1577, 0.2633, 0.99985),
    ];
    for (model, scale, shape, r2) in table {
        let f = rep.get(model).unwrap();
        let [(_, a), (_, b)] = f.dist.params();
        assert!((a - scale).abs() <= 5e-5, "{model}: scale {a} vs {scale}");
        assert!((b - shape).abs() <= 5e-5, "{model}: shape {b} vs {shape}");
        assert!((f.r2 - r2).abs() <= 5e-6, "{model}: R^2 {} vs {r2}", f.r2);
    }
    // The order of the paper's Table 1: log-normal best, then RRSB, GGS worst.
    let r2 = |m| rep.get(m).unwrap().r2;
    assert!(r2(Model::LogNormal) > r2(Model::Rrsb) && r2(Model::Rrsb) > r2(Model::Ggs));
    assert_eq!(rep.best, Model::LogNormal);
    assert!((rep.get(Model::LogNormal).unwrap().mse / 2.280e-5 - 1.0).abs() < 5e-4);
}

/// Deterministic noise in [-1, 1], so that the tolerances below are checked on fixed data.
fn noise(i: usize) -> f64 {
    2.0 * ((i as f64 * 12.9898 + 4.1414).sin() * 43758.5453)
        .fract()
        .abs()
        - 1.0
}

/// Sieve data of a known distribution at the sizes of a usual sieve set, with an absolute error
/// of up to `amplitude` on each passing fraction (kept in [0, 1] and non-decreasing, as a real
/// sieve analysis is).
fn sieve_of(dist: &Distribution, amplitude: f64) -> SieveData {
    let sizes = vec![
        2.0, 2.8, 4.0, 5.6, 8.0, 10.0, 11.2, 12.5, 14.0, 16.0, 20.0, 22.4, 31.5,
    ];
    let mut passing: Vec<f64> = sizes
        .iter()
        .enumerate()
        .map(|(i, &x)| (dist.q3(x) + amplitude * noise(i)).clamp(0.0, 1.0))
        .collect();
    for i in 1..passing.len() {
        passing[i] = passing[i].max(passing[i - 1]);
    }
    SieveData::new("synthetic", sizes, passing).unwrap()
}

#[test]
fn fits_recover_known_distributions_exactly_and_under_noise() {
    let truths = [
        Model::Ggs.with_params(24.0, 1.6).unwrap(),
        Model::Ggs.with_params(33.0, 3.0).unwrap(),
        Model::Rrsb.with_params(12.0, 2.2).unwrap(),
        Model::Rrsb.with_params(6.0, 1.2).unwrap(),
        Model::LogNormal.with_params(11.16, 0.26).unwrap(),
        Model::LogNormal.with_params(7.0, 0.6).unwrap(),
    ];
    // (noise amplitude, relative tolerance on each parameter, least R^2). With +-0.5 % noise
    // the parameters move by up to about 1 % on these sieves.
    let levels = [(0.0, 1e-6, 1.0 - 1e-10), (0.005, 0.02, 0.9995)];
    for truth in truths {
        for (amplitude, tol, min_r2) in levels {
            let data = sieve_of(&truth, amplitude);
            let rep = fit_all(&data).unwrap();
            let fit = rep.get(truth.model()).unwrap();
            for ((k, want), (_, got)) in truth.params().iter().zip(fit.dist.params()) {
                assert!(
                    (got / want - 1.0).abs() < tol,
                    "{} noise {amplitude}: {k} = {got}, want {want} +- {tol}",
                    truth.describe()
                );
            }
            assert!(
                fit.r2 > min_r2,
                "{} noise {amplitude}: R^2 {}",
                truth.describe(),
                fit.r2
            );
            if amplitude == 0.0 {
                // Only the true family reproduces the curve exactly.
                assert_eq!(rep.best, truth.model(), "{}", truth.describe());
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Drawing by number

/// Kolmogorov distribution, 99.9 % quantile: sqrt(n) D_n stays below it with probability 0.999.
const K_999: f64 = 1.95;

/// Effective sample size of the mass-weighted ECDF of `n` particles drawn by number.
///
/// F_m(x) = sum w_i 1{d_i <= x} / sum w_i with w = d^3 is a ratio estimator; by the delta method
/// Var F_m(x) = V(x) / n with V(x) = E_n[w^2 (1{d <= x} - F(x))^2] / E_n[w]^2, which over the
/// truncated mass distribution mu reads V(x) = E_mu[X^-3] E_mu[X^3 (1{X <= x} - F(x))^2].
/// Unweighted, V = F (1 - F) <= 1/4, so an unweighted sample with the same worst-case variance
/// has n_eff = n / (4 max_x V). (Kish's n E[w]^2 / E[w^2] equals this at the median only; the
/// coarse end, carried by few heavy particles, is noisier.) Expectations are taken on a
/// quantile grid of mu.
fn mass_ecdf_neff(dist: &Distribution, range: (f64, f64), n: usize) -> f64 {
    let k = 100_000;
    let (qa, qb) = (dist.q3(range.0), dist.q3(range.1));
    let xs: Vec<f64> = (0..k)
        .map(|i| dist.q3_inv(qa + (i as f64 + 0.5) / k as f64 * (qb - qa)))
        .collect();
    let e_inv3 = xs.iter().map(|x| x.powi(-3)).sum::<f64>() / k as f64;
    let e3 = xs.iter().map(|x| x.powi(3)).sum::<f64>() / k as f64;
    let (mut below, mut v_max) = (0.0, 0.0f64);
    for (i, x) in xs.iter().enumerate() {
        below += x.powi(3) / k as f64;
        let f = (i + 1) as f64 / k as f64;
        let v = e_inv3 * ((1.0 - f).powi(2) * below + f * f * (e3 - below));
        v_max = v_max.max(v);
    }
    n as f64 / (4.0 * v_max)
}

/// Largest gap between the mass-weighted ECDF of `d` and the truncated Q3.
fn mass_ks(dist: &Distribution, range: (f64, f64), d: &[f64]) -> f64 {
    let mut d = d.to_vec();
    d.sort_by(f64::total_cmp);
    let total: f64 = d.iter().map(|x| x.powi(3)).sum();
    let (mut acc, mut ks) = (0.0, 0.0f64);
    for x in &d {
        let f = truncated_q3(dist, range, *x);
        ks = ks.max((acc / total - f).abs());
        acc += x.powi(3);
        ks = ks.max((acc / total - f).abs());
    }
    ks
}

fn check_mass_cdf(dist: &Distribution, range: (Option<f64>, Option<f64>), n: usize, seed: u64) {
    let set = draw_by_number(dist, range, n, seed, "test").unwrap();
    assert_eq!(set.diameters_mm.len(), n);
    assert!(set
        .diameters_mm
        .iter()
        .all(|&d| d >= set.d_min && d <= set.d_max));
    let r = (set.d_min, set.d_max);
    let ks = mass_ks(dist, r, &set.diameters_mm);
    let n_eff = mass_ecdf_neff(dist, r, n);
    let tol = K_999 / n_eff.sqrt();
    println!(
        "{} [{:.4}, {:.4}] mm, N = {n}: n_eff = {n_eff:.0}, KS = {ks:.5}, tol = {tol:.5}",
        dist.describe(),
        r.0,
        r.1
    );
    assert!(ks < tol, "{dist:?}: KS {ks} >= {tol} (n_eff {n_eff:.0})");
}

#[test]
fn draw_lognormal_mass_cdf_matches_truncated_q3() {
    for (sigma, n) in [(0.1, 50_000), (0.26, 50_000), (0.5, 50_000), (1.0, 500_000)] {
        // At sigma = 1 the top 5 % of the mass sits in about 1 particle in 10^5 (n_eff is
        // n / 1450), so it needs ten times the particles for a test with any power.
        let dist = Model::LogNormal.with_params(11.16, sigma).unwrap();
        check_mass_cdf(&dist, (None, None), n, 7);
    }
}

#[test]
fn draw_ggs_rrsb_mass_cdf_matches_truncated_q3() {
    let cases = [
        (Model::Ggs.with_params(16.0, 2.0).unwrap(), (None, None)),
        (
            Model::Ggs.with_params(16.0, 3.5).unwrap(),
            (Some(4.0), Some(20.0)),
        ),
        (Model::Rrsb.with_params(12.0, 3.0).unwrap(), (None, None)),
        (
            Model::Rrsb.with_params(0.5, 1.5).unwrap(),
            (Some(0.1), None),
        ),
    ];
    for (dist, range) in cases {
        check_mass_cdf(&dist, range, 50_000, 11);
    }
}

#[test]
fn draw_lognormal_number_cdf_is_hatch_choate() {
    // By number the drawn set must follow the log-normal with median x50_3 exp(-3 sigma^2),
    // truncated: a plain KS test with n = N.
    let n = 50_000;
    for sigma in [0.1, 0.26, 0.5, 1.0] {
        let dist = Model::LogNormal.with_params(11.16, sigma).unwrap();
        let Distribution::LogNormal(l) = dist else {
            unreachable!()
        };
        let set = draw_by_number(&dist, (None, None), n, 3, "test").unwrap();
        let (fa, fb) = (
            l.cdf(Basis::Number, set.d_min),
            l.cdf(Basis::Number, set.d_max),
        );
        let mut d = set.diameters_mm.clone();
        d.sort_by(f64::total_cmp);
        let ks = d
            .iter()
            .enumerate()
            .map(|(i, &x)| {
                let f = (l.cdf(Basis::Number, x) - fa) / (fb - fa);
                (f - i as f64 / n as f64)
                    .abs()
                    .max((f - (i + 1) as f64 / n as f64).abs())
            })
            .fold(0.0, f64::max);
        let tol = K_999 / (n as f64).sqrt();
        assert!(ks < tol, "sigma {sigma}: KS {ks} >= {tol}");
    }
}

#[test]
fn draw_default_range_trims_one_percent_of_mass_each_end() {
    let dist = Model::LogNormal.with_params(11.16, 0.26).unwrap();
    let (lo, hi) = default_range(&dist);
    assert!((dist.q3(lo) - 0.01).abs() < 1e-9 && (dist.q3(hi) - 0.99).abs() < 1e-9);
    let set = draw_by_number(&dist, (None, None), 10, 1, "test").unwrap();
    assert_eq!((set.d_min, set.d_max), (lo, hi));
    assert!((set.mass_fraction - 0.98).abs() < 1e-9);
    // One given end keeps the other default.
    let set = draw_by_number(&dist, (Some(8.0), None), 10, 1, "test").unwrap();
    assert_eq!((set.d_min, set.d_max), (8.0, hi));
}

#[test]
fn draw_is_deterministic_per_seed() {
    for dist in [
        Model::LogNormal.with_params(11.16, 0.26).unwrap(),
        Model::Rrsb.with_params(12.0, 3.0).unwrap(),
    ] {
        let a = draw_by_number(&dist, (None, None), 1000, 42, "test").unwrap();
        let b = draw_by_number(&dist, (None, None), 1000, 42, "test").unwrap();
        let c = draw_by_number(&dist, (None, None), 1000, 43, "test").unwrap();
        assert_eq!(a, b);
        assert_ne!(a.diameters_mm, c.diameters_mm);
    }
}

#[test]
fn draw_bad_inputs_name_source_and_field() {
    let logn = Model::LogNormal.with_params(11.16, 0.26).unwrap();
    let ggs = Model::Ggs.with_params(16.0, 2.0).unwrap();
    type Range = (Option<f64>, Option<f64>);
    let cases: &[(&str, Distribution, Range, usize, &str)] = &[
        ("n_zero", logn, (None, None), 0, "n"),
        ("min_above_max", logn, (Some(20.0), Some(10.0)), 10, "d_min"),
        (
            "min_equals_max",
            logn,
            (Some(10.0), Some(10.0)),
            10,
            "d_min",
        ),
        ("min_zero", logn, (Some(0.0), Some(10.0)), 10, "d_min"),
        ("min_negative", logn, (Some(-1.0), None), 10, "d_min"),
        ("max_nan", logn, (None, Some(f64::NAN)), 10, "d_max"),
        ("max_inf", logn, (None, Some(f64::INFINITY)), 10, "d_max"),
        ("min_nan", logn, (Some(f64::NAN), None), 10, "d_min"),
        // Above x_max a GGS holds no mass.
        (
            "range_without_mass",
            ggs,
            (Some(20.0), Some(30.0)),
            10,
            "d_min, d_max",
        ),
        ("far_tail", logn, (Some(1e4), Some(1e5)), 10, "d_min, d_max"),
    ];
    for (case, dist, range, n, field) in cases {
        let source = format!("request_{case}");
        let err = match draw_by_number(dist, *range, *n, 1, &source) {
            Ok(s) => panic!("{case}: accepted, drew {} particles", s.diameters_mm.len()),
            Err(e) => e.to_string(),
        };
        assert!(
            err.starts_with(&format!("{source}: {field}: ")),
            "{case}: {err}"
        );
    }
}
