//! Calibration against a metamodel fitted to synthetic data of known form: the true parameters are
//! recovered when the measurements can fix them, the solution set is described when they cannot,
//! and bad material files are refused naming the field.

use mbgc::calibrate::{calibrate, Problem};
use mbgc::gp::Config;
use mbgc::material::Material;
use mbgc::metamodel::{fit, FitSettings, Metamodel, TrainingTable};
use std::sync::OnceLock;

const INPUTS: [&str; 5] = ["mu_pp", "mu_r_pp", "rho_p", "sigma_ln", "d50"];

/// Made-up but shear-box-shaped responses (d50 has no effect, as in seed 004).
fn truth(x: &[f64]) -> [f64; 2] {
    let (mu, mur, rho, sig) = (x[0], x[1], x[2], x[3]);
    let angle = 18.0 + 22.0 * (2.0 * mu).tanh() + 9.0 * mur + 4.0 * sig;
    let density = rho * (0.62 - 0.1 * (2.0 * mu).tanh() - 0.05 * mur + 0.06 * sig);
    [angle, density]
}

fn model() -> &'static Metamodel {
    static MODEL: OnceLock<Metamodel> = OnceLock::new();
    MODEL.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let mut csv = String::from("mu_pp,mu_r_pp,rho_p,sigma_ln,d50,shear_angle,bulk_density\n");
        let lo = [0.0, 0.0, 2000.0, 0.1, 2.0];
        let hi = [1.0, 1.0, 3000.0, 0.5, 20.0];
        for i in 0..400u32 {
            let x: Vec<f64> = (0..5)
                .map(|d| lo[d] + (hi[d] - lo[d]) * sobol_burley::sample(i, d as u32, 7) as f64)
                .collect();
            let y = truth(&x);
            csv.push_str(&format!(
                "{},{},{},{},{},{},{}\n",
                x[0], x[1], x[2], x[3], x[4], y[0], y[1]
            ));
        }
        let data = dir.path().join("synthetic.csv");
        std::fs::write(&data, csv).unwrap();
        let inputs: Vec<String> = INPUTS.iter().map(|s| s.to_string()).collect();
        let targets: Vec<String> = vec!["shear_angle".into(), "bulk_density".into()];
        let settings = FitSettings::new(inputs.clone(), targets.clone())
            .test_fraction(0.1)
            .config(Config {
                population: 2000,
                generations: 20,
                seed: 2,
                ..Config::default()
            });
        let table = TrainingTable::read_csv(&data, &inputs, &targets).unwrap();
        let m = fit(&table, &settings, |_, _| {}).unwrap().model;
        for r in &m.responses {
            eprintln!(
                "{}: test R2 {:.5}: {}",
                r.name,
                r.test.unwrap().r2,
                r.equation
            );
            assert!(r.test.unwrap().r2 > 0.98, "{}: {}", r.name, r.equation);
        }
        m
    })
}

/// What the fitted model predicts at the true parameters: the inversion must return them exactly,
/// whatever the metamodel's own error against `truth`.
fn measured(x: &[f64]) -> [f64; 2] {
    let m = model();
    [
        m.predict_point(&m.responses[0], x),
        m.predict_point(&m.responses[1], x),
    ]
}

fn material(extra: &str, angle: f64, density: f64) -> Material {
    let text = format!(
        "name = \"test gravel\"\n[psd]\nd50_mm = 11.16\nsigma_ln = 0.26\n[measured]\n\
         shear_angle = {{ value = {angle}, sd = 0.5 }}\nbulk_density = {{ value = {density}, sd = 10 }}\n{extra}"
    );
    Material::from_toml_str(&text, "test.toml").unwrap()
}

#[test]
fn recovers_identifiable_parameters() {
    let m = model();
    // True material: mu_pp 0.3, rho_p 2600, mu_r_pp fixed at 0.4.
    let y = measured(&[0.3, 0.4, 2600.0, 0.26, 11.16]);
    let mat = material("[fixed]\nmu_r_pp = 0.4\n", y[0], y[1]);
    let p = Problem::new(m, &mat).unwrap();
    assert_eq!(p.free_names(), vec!["mu_pp", "rho_p"]);
    let cal = calibrate(&p, 32, 1);
    let best = &cal.optima[0];
    eprintln!(
        "best {:?} chi2 {:.2e}, {} optima, {:.3} s",
        best.x,
        best.chi2,
        cal.optima.len(),
        cal.seconds
    );
    assert!(best.chi2 < 1e-8, "chi2 {}", best.chi2);
    assert!((best.x[0] - 0.3).abs() < 1e-3, "mu_pp {}", best.x[0]);
    assert!((best.x[1] - 2600.0).abs() < 1.0, "rho_p {}", best.x[1]);
    // Against the function the model was fitted to, the error is the model's own.
    let t = truth(&[best.x[0], 0.4, best.x[1], 0.26, 11.16]);
    let y = truth(&[0.3, 0.4, 2600.0, 0.26, 11.16]);
    eprintln!("truth at the calibrated set vs truth at the true set: {t:?} vs {y:?}");
    assert_eq!(cal.excess_parameters, 0);
    assert!(cal.flat_directions.is_empty());
    assert!(
        best.starts >= 16,
        "most starts end at the one solution: {}",
        best.starts
    );
}

#[test]
fn more_parameters_than_measurements_gives_a_solution_set() {
    let m = model();
    let y = measured(&[0.3, 0.4, 2600.0, 0.26, 11.16]);
    let mat = material("", y[0], y[1]);
    let p = Problem::new(m, &mat).unwrap();
    assert_eq!(p.free_names(), vec!["mu_pp", "mu_r_pp", "rho_p"]);
    let cal = calibrate(&p, 64, 1);
    assert_eq!(cal.excess_parameters, 1);
    assert!(cal.optima[0].chi2 < 1e-6);
    assert_eq!(cal.flat_directions.len(), 1, "{:?}", cal.flat_directions);
    // Along the flat direction mu_pp and mu_r_pp trade against each other.
    let d = &cal.flat_directions[0].components;
    assert!(d[0] * d[1] < 0.0, "{d:?}");
    let range = &cal.solution_ranges[0];
    assert!(range.max - range.min > 0.1, "mu_pp spread {range:?}");
    // Every equally good optimum really reproduces the measurements.
    for o in cal.optima.iter().filter(|o| o.chi2 < 1e-6) {
        assert!(o.residuals.iter().all(|r| r.abs() < 1e-3));
    }
}

#[test]
fn constraints_are_respected_and_impossible_ones_reported() {
    let m = model();
    let y = measured(&[0.3, 0.4, 2600.0, 0.26, 11.16]);
    let mat = material(
        "[constraints]\nexpr = [\"mu_r_pp <= 0.5*mu_pp\"]\n",
        y[0],
        y[1],
    );
    let p = Problem::new(m, &mat).unwrap();
    let cal = calibrate(&p, 32, 1);
    let b = &cal.optima[0];
    assert!(b.x[1] <= 0.5 * b.x[0] + 1e-3, "{:?}", b.x);
    let mat = material("[constraints]\nexpr = [\"mu_pp >= 1.5\"]\n", y[0], y[1]);
    let p = Problem::new(m, &mat).unwrap();
    let cal = calibrate(&p, 8, 1);
    assert!(
        cal.optima[0].violation > 1e-3,
        "an impossible constraint shows as a violation"
    );
}

#[test]
fn bad_materials_are_refused_naming_the_field() {
    let m = model();
    let cases = [
        ("[fixed]\nmu_pp = 1.7\n", "fixed.mu_pp"),
        ("[fixed]\nfriction = 0.3\n", "fixed.friction"),
        ("[bounds]\nrho_p = [1000, 2500]\n", "bounds.rho_p"),
    ];
    for (extra, field) in cases {
        let mat = material(extra, 35.0, 1500.0);
        let e = Problem::new(m, &mat).unwrap_err().to_string();
        assert!(e.contains("test.toml") && e.contains(field), "{field}: {e}");
    }
    let text = "[measured]\nangle_of_repose = { value = 30, sd = 1 }\n";
    let mat = Material::from_toml_str(text, "test.toml").unwrap();
    let e = Problem::new(m, &mat).unwrap_err().to_string();
    assert!(
        e.contains("measured.angle_of_repose") && e.contains("shear_angle"),
        "{e}"
    );
    // A PSD outside the model's domain (sigma_ln 0.9 > 0.5) is refused, not extrapolated.
    let text =
        "[psd]\nd50_mm = 5\nsigma_ln = 0.9\n[measured]\nshear_angle = { value = 30, sd = 1 }\n";
    let mat = Material::from_toml_str(text, "test.toml").unwrap();
    let e = Problem::new(m, &mat).unwrap_err().to_string();
    assert!(e.contains("psd") && e.contains("sigma_ln"), "{e}");
}

/// Posterior and evidence of a problem with a known answer: model y = a on a in [0, 1] (uniform
/// prior), one measurement 0.4 +- 0.05, no model error: posterior N(0.4, 0.05^2) and
/// ln Z = ln(Phi(12) - Phi(-8)) = 0 (to 1e-15).
#[test]
fn bayesian_posterior_and_evidence_of_a_linear_model() {
    // In memory: the library fits columns, no file needed.
    let column: Vec<f64> = (0..=20).map(|i| i as f64 / 20.0).collect();
    let table = TrainingTable::from_columns(
        "lin",
        vec![("a".into(), column.clone()), ("y".into(), column)],
    )
    .unwrap();
    let settings = FitSettings::new(vec!["a".into()], vec!["y".into()])
        .test_fraction(0.0)
        .config(Config {
            population: 50,
            generations: 2,
            ..Config::default()
        });
    let m = fit(&table, &settings, |_, _| {}).unwrap().model;
    assert_eq!(m.responses[0].equation, "a");
    let mat = Material::from_toml_str("[measured]\ny = { value = 0.4, sd = 0.05 }\n", "lin.toml")
        .unwrap();
    let p = Problem::new(&m, &mat).unwrap();
    let post = mbgc::calibrate::bayes::posterior(&p, 2000, 0.0, 3).unwrap();
    let a = &post.parameters[0];
    eprintln!("mean {} sd {} ln Z {}", a.mean, a.sd, post.ln_evidence);
    assert!((a.mean - 0.4).abs() < 0.005, "{a:?}");
    assert!((a.sd - 0.05).abs() < 0.005, "{a:?}");
    assert!(post.ln_evidence.abs() < 0.1, "ln Z {}", post.ln_evidence);
    assert!(
        (a.q05 - (0.4 - 1.645 * 0.05)).abs() < 0.01 && (a.q95 - (0.4 + 1.645 * 0.05)).abs() < 0.01
    );
}
