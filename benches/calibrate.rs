//! Calibration time: a metamodel with the 12 inputs of seed 004's space and two responses, two
//! measurements, 10 free parameters, 64 L-BFGS starts; and the TMCMC posterior on top. The
//! deterministic calibration must take well under a second (exits non-zero above 0.5 s).
//!
//!     cargo bench --bench calibrate

use mbgc::calibrate::{bayes, calibrate, Problem};
use mbgc::gp::Config;
use mbgc::material::Material;
use mbgc::metamodel::{fit, FitSettings, TrainingTable};

const NAMES: [&str; 12] = [
    "E_p", "E_w", "nu_p", "e_pp", "e_pw", "mu_pp", "mu_pw", "mu_r_pp", "mu_r_pw", "rho_p", "d50",
    "sigma_ln",
];

fn main() {
    // Synthetic responses shaped like the shear box's (the bench times the inversion, not
    // physics), fitted from memory: no table file.
    let lo = [
        5e6, 5e6, 0.1, 0.05, 0.05, 0.0, 0.0, 0.0, 0.0, 250.0, 0.4, 0.07,
    ];
    let hi = [
        5e8, 5e8, 0.5, 0.95, 0.95, 1.0, 1.0, 1.0, 1.0, 3000.0, 25.6, 1.17,
    ];
    let mut columns: Vec<(String, Vec<f64>)> = NAMES
        .iter()
        .chain(&["shear_angle", "bulk_density"])
        .map(|n| (n.to_string(), Vec::new()))
        .collect();
    for i in 0..600u32 {
        let x: Vec<f64> = (0..12)
            .map(|d| lo[d] + (hi[d] - lo[d]) * sobol_burley::sample(i, d as u32, 5) as f64)
            .collect();
        let angle = 18.0 + 22.0 * (2.0 * x[5]).tanh() + 9.0 * x[7] + 3.0 * x[11] + 2.0 * x[6];
        let density = x[9] * (0.6 - 0.1 * x[5] - 0.04 * x[7] + 0.05 * x[11]);
        for (c, v) in columns.iter_mut().zip(x.iter().chain(&[angle, density])) {
            c.1.push(*v);
        }
    }
    let table = TrainingTable::from_columns("synthetic", columns).expect("table");
    let settings = FitSettings::new(
        NAMES.iter().map(|s| s.to_string()).collect(),
        vec!["shear_angle".into(), "bulk_density".into()],
    )
    .test_fraction(0.1)
    .config(Config {
        population: 1000,
        generations: 10,
        ..Config::default()
    });
    let model = fit(&table, &settings, |_, _| {}).expect("fit").model;
    let material = Material::from_toml_str(
        "[psd]\nd50_mm = 11.16\nsigma_ln = 0.26\n[measured]\n\
         shear_angle = { value = 33.0, sd = 0.5 }\nbulk_density = { value = 1400.0, sd = 10 }\n",
        "bench.toml",
    )
    .expect("material");
    let problem = Problem::new(&model, &material).expect("problem");
    let budget = 0.5;
    let mut times = Vec::new();
    let mut optima = 0;
    for _ in 0..5 {
        let t = std::time::Instant::now();
        let cal = calibrate(&problem, 64, 1);
        times.push(t.elapsed().as_secs_f64());
        optima = cal.optima.len();
    }
    times.sort_by(f64::total_cmp);
    let t = std::time::Instant::now();
    let post = bayes::posterior(&problem, 2000, 0.1, 1).expect("posterior");
    let t_bayes = t.elapsed().as_secs_f64();
    println!(
        "calibration, {} free parameters, 2 measurements, 64 starts: best {:.4} s, median {:.4} s \
         ({} distinct optima), best/budget {:.3}",
        problem.dim(),
        times[0],
        times[2],
        optima,
        times[0] / budget
    );
    println!(
        "TMCMC posterior, 2000 samples, burn-in 10: {t_bayes:.2} s ({} stages)",
        post.stages
    );
    if times[0] > budget {
        eprintln!("calibration exceeded the budget of {budget} s");
        std::process::exit(1);
    }
}
