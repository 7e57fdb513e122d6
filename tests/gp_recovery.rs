//! Exact recovery: noise-free data from equations of known form must give back an equivalent
//! equation (checked on fresh points outside the training box: the difference or the ratio of
//! model and truth must be constant) with R^2 > 0.9999, for fixed seeds.

use mbgc::gp::{self, expr, Config, Dataset};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

struct Case {
    name: &'static str,
    vars: &'static [&'static str],
    range: (f64, f64),
    f: fn(&[f64]) -> f64,
}

fn sample(case: &Case, n: usize, range: (f64, f64), seed: u64) -> (Vec<Vec<f64>>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let rows: Vec<Vec<f64>> = (0..n)
        .map(|_| {
            case.vars
                .iter()
                .map(|_| rng.random_range(range.0..range.1))
                .collect()
        })
        .collect();
    let y = rows.iter().map(|r| (case.f)(r)).collect();
    let x = (0..case.vars.len())
        .map(|j| rows.iter().map(|r| r[j]).collect())
        .collect();
    (x, y)
}

fn predict(program: &[gp::Node], x: &[Vec<f64>]) -> Option<Vec<f64>> {
    let mut out = vec![0.0; x[0].len()];
    gp::eval::Evaluator::new()
        .eval(program, x, &mut out)
        .then_some(out)
}

/// Model and truth differ by a constant or by a constant factor, to 1e-6 relative.
fn equivalent(model: &[f64], truth: &[f64]) -> bool {
    let close = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        v.iter().all(|x| (x - m).abs() <= 1e-6 * m.abs().max(1e-9))
    };
    let diff: Vec<f64> = model.iter().zip(truth).map(|(a, b)| a - b).collect();
    let scale = truth.iter().map(|t| t.abs()).fold(0.0, f64::max);
    let diff_const = {
        let m = diff.iter().sum::<f64>() / diff.len() as f64;
        diff.iter().all(|d| (d - m).abs() <= 1e-6 * scale)
    };
    let ratio: Vec<f64> = model.iter().zip(truth).map(|(a, b)| a / b).collect();
    diff_const || close(&ratio)
}

fn run(case: &Case, seed: u64) {
    let (x, y) = sample(case, 300, case.range, 7);
    let train = Dataset::new(x, y);
    let cfg = Config {
        population: 4000,
        generations: 30,
        seed,
        ..Config::default()
    };
    let t = std::time::Instant::now();
    let res = gp::fit(&train, &cfg, |_| {}).unwrap();
    let names: Vec<String> = case.vars.iter().map(|s| s.to_string()).collect();
    let best = res.best();
    let text = expr::infix(
        &expr::Expr::from_postfix(&best.program),
        &names,
        &expr::exact_constant,
    );
    eprintln!(
        "{}: {} (size {}, 1-R2 {:.2e}, {} generations, {:.2} s)",
        case.name,
        text,
        best.size,
        best.train_nmse,
        res.generations,
        t.elapsed().as_secs_f64()
    );
    assert!(
        best.train_nmse < 1e-4,
        "{}: R^2 {}",
        case.name,
        1.0 - best.train_nmse
    );
    // Fresh points beyond the training box (extrapolation separates look-alikes).
    let (lo, hi) = case.range;
    let wide = (lo, hi + 0.5 * (hi - lo));
    let (xt, yt) = sample(case, 200, wide, 99);
    let pred = predict(&best.program, &xt).expect("finite on fresh points");
    assert!(
        equivalent(&pred, &yt),
        "{}: {text} is not equivalent to the truth",
        case.name
    );
}

#[test]
fn friction_force() {
    run(
        &Case {
            name: "F = mu N",
            vars: &["mu", "N"],
            range: (1.0, 5.0),
            f: |v| v[0] * v[1],
        },
        1,
    );
}

#[test]
fn potential_energy() {
    run(
        &Case {
            name: "U = m g z",
            vars: &["m", "g", "z"],
            range: (1.0, 5.0),
            f: |v| v[0] * v[1] * v[2],
        },
        1,
    );
}

#[test]
fn coulomb_field() {
    run(
        &Case {
            name: "E = q / (4 pi eps r^2)",
            vars: &["q", "eps", "r"],
            range: (1.0, 5.0),
            f: |v| v[0] / (4.0 * std::f64::consts::PI * v[1] * v[2] * v[2]),
        },
        1,
    );
}

#[test]
fn saturating_tanh() {
    run(
        &Case {
            name: "y = 2.3 tanh(0.7 x) + 1.1",
            vars: &["x"],
            range: (-3.0, 3.0),
            f: |v| 2.3 * (0.7 * v[0]).tanh() + 1.1,
        },
        1,
    );
}

#[test]
fn power_law_times_exponential() {
    run(
        &Case {
            name: "y = 1.5 x^2 exp(-0.8 z)",
            vars: &["x", "z"],
            range: (0.5, 3.0),
            f: |v| 1.5 * v[0] * v[0] * (-0.8 * v[1]).exp(),
        },
        1,
    );
}

/// 1 % noise (sd = 0.01 RMS(y)) on every row: the test R^2 must come within 0.01 of the noise
/// ceiling, the R^2 of the true function on the same noisy test rows.
#[test]
fn noisy_data_reaches_the_noise_ceiling() {
    use rand_distr::{Distribution, Normal};
    let case = Case {
        name: "y = x0^2 / (1 + x1) + 0.5 log(x2)",
        vars: &["x0", "x1", "x2"],
        range: (1.0, 4.0),
        f: |v| v[0] * v[0] / (1.0 + v[1]) + 0.5 * v[2].ln(),
    };
    let (x, y) = sample(&case, 400, case.range, 3);
    let rms = (y.iter().map(|v| v * v).sum::<f64>() / y.len() as f64).sqrt();
    let noise = Normal::new(0.0, 0.01 * rms).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let noisy: Vec<f64> = y.iter().map(|v| v + noise.sample(&mut rng)).collect();
    let (xt, yt) = sample(&case, 400, case.range, 4);
    let yt_noisy: Vec<f64> = yt.iter().map(|v| v + noise.sample(&mut rng)).collect();
    let cfg = Config {
        population: 2000,
        generations: 20,
        seed: 1,
        ..Config::default()
    };
    let res = gp::fit(&Dataset::new(x, noisy), &cfg, |_| {}).unwrap();
    let pred = predict(&res.best().program, &xt).unwrap();
    let r2 = |p: &[f64]| {
        let m = yt_noisy.iter().sum::<f64>() / yt_noisy.len() as f64;
        let ss: f64 = yt_noisy.iter().map(|v| (v - m).powi(2)).sum();
        1.0 - p
            .iter()
            .zip(&yt_noisy)
            .map(|(p, y)| (y - p).powi(2))
            .sum::<f64>()
            / ss
    };
    let (model, ceiling) = (r2(&pred), r2(&yt));
    eprintln!(
        "noisy: test R2 {model:.5}, ceiling {ceiling:.5}, size {}",
        res.best().size
    );
    assert!(
        model > ceiling - 0.01,
        "test R2 {model} vs ceiling {ceiling}"
    );
    assert!(
        model <= ceiling + 0.002,
        "better than the truth by more than chance: {model}"
    );
}

/// The same seed gives the same equation, whatever the number of threads.
#[test]
fn same_seed_same_equation_on_any_thread_count() {
    let case = Case {
        name: "y = x0 exp(-x1)",
        vars: &["x0", "x1"],
        range: (0.5, 2.0),
        f: |v| v[0] * (-v[1]).exp() + 0.1 * v[0] * v[0],
    };
    let (x, y) = sample(&case, 200, case.range, 5);
    let data = Dataset::new(x, y);
    let cfg = Config {
        population: 400,
        generations: 5,
        stop_nmse: 0.0,
        seed: 9,
        ..Config::default()
    };
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| gp::fit(&data, &cfg, |_| {}).unwrap())
    };
    let (a, b) = (on(1), on(2));
    assert_eq!(a.front.len(), b.front.len());
    for (ea, eb) in a.front.iter().zip(&b.front) {
        assert_eq!(ea.program, eb.program);
        assert_eq!(ea.train_nmse.to_bits(), eb.train_nmse.to_bits());
    }
    let c = gp::fit(
        &data,
        &Config {
            seed: 10,
            ..cfg.clone()
        },
        |_| {},
    )
    .unwrap();
    assert_ne!(
        a.best().program,
        c.best().program,
        "another seed should search differently"
    );
}

/// Restarts merge their fronts: at every size, the merged front is at least as accurate as the
/// front of each restart alone (same seeds), and a second call gives the same equation.
/// 120 rows of a two-input function with uniform noise of +-0.05.
fn noisy_data() -> Dataset {
    let case = Case {
        name: "noisy",
        vars: &["a", "b"],
        range: (0.1, 2.0),
        f: |v| (v[0] * 1.7).tanh() * v[1].sqrt() + 0.3 * v[0] * v[1],
    };
    let (x, mut y) = sample(&case, 120, case.range, 11);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for v in &mut y {
        *v += rng.random_range(-0.05..0.05);
    }
    Dataset::new(x, y)
}

#[test]
fn restarts_merge_fronts_that_dominate_each_single_search() {
    let train = noisy_data();
    let cfg = |seed: u64, restarts: usize| Config {
        population: 400,
        generations: 8,
        seed,
        restarts,
        ..Config::default()
    };
    let merged = gp::fit(&train, &cfg(3, 3), |_| {}).unwrap();
    // Each front member beats every smaller one.
    for w in merged.front.windows(2) {
        assert!(w[0].size < w[1].size && w[1].train_nmse < w[0].train_nmse);
    }
    for seed in 3..6 {
        let single = gp::fit(&train, &cfg(seed, 1), |_| {}).unwrap();
        for e in &single.front {
            let covered = merged
                .front
                .iter()
                .any(|m| m.size <= e.size && m.train_nmse <= e.train_nmse);
            assert!(
                covered,
                "seed {seed}: size {} nmse {:.3e} lost",
                e.size, e.train_nmse
            );
        }
    }
    let again = gp::fit(&train, &cfg(3, 3), |_| {}).unwrap();
    assert_eq!(again.best().program, merged.best().program);
    let bad = gp::fit(&train, &cfg(3, 0), |_| {});
    assert!(bad.unwrap_err().contains("restarts"));
}

#[test]
fn cross_validated_selection_picks_the_member_with_the_smallest_held_out_error() {
    let train = noisy_data();
    let cfg = |selection| Config {
        population: 400,
        generations: 8,
        seed: 3,
        restarts: 2,
        selection,
        ..Config::default()
    };
    let knee = gp::fit(&train, &cfg(gp::select::Selection::Best), |_| {}).unwrap();
    assert!(knee.cv_nmse.is_none());
    let cv = gp::fit(&train, &cfg(gp::select::Selection::CrossValidation), |_| {}).unwrap();
    // Same search, same front; only the pick differs.
    assert_eq!(knee.front.len(), cv.front.len());
    let errors = cv.cv_nmse.as_ref().unwrap();
    assert_eq!(errors.len(), cv.front.len());
    let min = errors.iter().cloned().fold(f64::INFINITY, f64::min);
    assert_eq!(errors[cv.chosen], min);
    assert!(errors.iter().take(cv.chosen).all(|&e| e > min));
    // Held-out rows are harder than the rows a member was fitted to.
    assert!(min > cv.front[cv.chosen].train_nmse);
    let few = train.subset(&(0..9).collect::<Vec<_>>());
    let err = gp::fit(&few, &cfg(gp::select::Selection::CrossValidation), |_| {}).unwrap_err();
    assert!(err.contains("selection") && err.contains("got 9"), "{err}");
}
