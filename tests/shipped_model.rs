//! The shipped metamodel on a fresh clone: the README's first command, `mbgc calibrate --material
//! examples/gravel.toml`, loads `models/shear_box.json` by default and calibrates seed 004's
//! Gravel 8/16 in a physical place.

mod common;

use common::ok;

#[test]
fn the_shipped_model_calibrates_the_gravel_example() {
    let model = mbgc::metamodel::Metamodel::load(std::path::Path::new("models/shear_box.json"))
        .expect("the shipped model loads");
    for r in ["shear_angle", "bulk_density"] {
        let m = model
            .response(r)
            .unwrap_or_else(|| panic!("no {r} equation"));
        assert!(m.validation.is_some(), "{r}: no validation metrics");
    }
    let json = ok(&["calibrate", "--material", "examples/gravel.toml", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let best = &v["solutions"][0];
    let p = |n: &str| best["params"][n].as_f64().unwrap_or(f64::NAN);
    let y = |n: &str| best["predicted"][n].as_f64().unwrap_or(f64::NAN);
    // Two free parameters for two measurements: met exactly.
    assert!((y("shear_angle") - 35.53).abs() < 0.05, "{best}");
    assert!((y("bulk_density") - 1478.8).abs() < 0.5, "{best}");
    // Gravel's particle density is about 2600-2700 kg/m3; a calibration far from it would say
    // that the model or the experiment is off.
    assert!((2300.0..3000.0).contains(&p("rho_p")), "{best}");
    assert!((0.05..1.0).contains(&p("mu_pp")), "{best}");
    // The material's fixed values are used as given.
    assert_eq!(p("E_p"), 4e7);
    assert_eq!(p("mu_r_pp"), 0.8);
}

/// `mbgc diagnose` on the shipped model and the shipped measurement set with a hidden rolling
/// resistance (DEM data): the JSON report has the documented keys, the class without rolling
/// resistance fails, and rolling resistance (EPSD2) is ranked first.
#[test]
fn diagnose_names_the_hidden_rolling_resistance_from_the_shipped_example() {
    let json = ok(&[
        "diagnose",
        "--measurements",
        "examples/measurements/hidden_rolling.toml",
        "--samples",
        "500",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert!(v["chi2_dof"].as_f64().unwrap() > 5.0, "{v}");
    assert_eq!(v["residuals"].as_array().unwrap().len(), 8);
    let best = &v["ranking"][0];
    assert_eq!(best["effect"], "epsd2", "{v}");
    assert!(best["chi2_dof_after"].as_f64().unwrap() < 0.2 * v["chi2_dof"].as_f64().unwrap());
    assert!(best["log_bayes_factor"].as_f64().unwrap() > 2.3);
}

/// The walk-through of docs/diagnose.md on the shipped local models: version 1 (no cohesion)
/// fails on DEM data with a strong hidden cohesion, version 2 (cohesion added by `train
/// --extends`) explains it, and the control made without cohesion needs nothing.
#[test]
fn diagnose_names_the_hidden_cohesion_and_the_extended_model_recovers_it() {
    let models = [
        "--model",
        "models/diagnose_local.json",
        "--model",
        "models/diagnose_local_sjkr.json",
        "--samples",
        "1000",
        "--json",
    ];
    let run = |file: &str| -> serde_json::Value {
        let mut args = vec!["diagnose", "--measurements", file];
        args.extend(models);
        serde_json::from_str(&ok(&args)).unwrap()
    };
    let v = run("examples/measurements/hidden_cohesion_strong.toml");
    let best = &v["ranking"][0];
    assert_eq!(best["effect"], "sjkr", "{v}");
    let (before, after) = (
        v["chi2_dof"].as_f64().unwrap(),
        best["chi2_dof_after"].as_f64().unwrap(),
    );
    assert!(before > 3.0 && after < before / 5.0, "{before} -> {after}");
    assert!(best["log_bayes_factor"].as_f64().unwrap() > 2.3, "{best}");
    let ced = best["strength"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "ced_pp")
        .unwrap();
    let (lo, hi) = (ced["q05"].as_f64().unwrap(), ced["q95"].as_f64().unwrap());
    assert!(
        lo <= 2.5e4 && 2.5e4 <= hi,
        "truth 2.5e4 outside [{lo}, {hi}]"
    );
    assert_eq!(
        v["extended"][0]["models"][0],
        "models/diagnose_local_sjkr.json"
    );
    let c = run("examples/measurements/control.toml");
    let verdict = c["verdict"].as_str().unwrap();
    assert!(
        verdict.starts_with("consistent, no effect needed"),
        "{verdict}"
    );
}

/// Seed 004's box of E_p, E_w (5e6-5e8 Pa), rho_p (250-3000 kg/m3) and d50 (0.4-25.6 mm), every
/// other parameter in the shipped model's ranges: at 32 seeded points, a point the model
/// answers gets finite predictions, each with its error stated, and a calibration of its own
/// predictions; a point it does not answer is refused by the group, its value and the range
/// (issue 40). The share answered is what the model's stiffness range and rigid limit cover.
#[test]
fn every_point_of_seed_004s_box_is_answered_with_its_error_or_refused_by_name() {
    use mbgc::calibrate::session::{self, SessionOptions};
    use mbgc::material::Material;
    use rand::RngExt as _;
    let model = mbgc::metamodel::Metamodel::load(std::path::Path::new("models/shear_box.json"))
        .expect("the shipped model loads");
    let names = model.input_names();
    let mut rng = mbgc::sampling::rng(40);
    let log_uniform = |u: f64, lo: f64, hi: f64| (lo.ln() + u * (hi / lo).ln()).exp();
    let (mut answered, mut refused) = (0, 0);
    for point in 0..32 {
        let x: Vec<f64> = model
            .inputs
            .iter()
            .map(|i| {
                let u: f64 = rng.random();
                match i.name.as_str() {
                    "E_p" | "E_w" => log_uniform(u, 5e6, 5e8),
                    "rho_p" => 250.0 + u * 2750.0,
                    "d50" => log_uniform(u, 0.4, 25.6),
                    _ => i.domain[0] + u * (i.domain[1] - i.domain[0]),
                }
            })
            .collect();
        let outside = model.outside_domain(&x);
        let mut fixed = String::from("[fixed]\n");
        for (n, v) in names.iter().zip(&x) {
            if !["mu_pp", "mu_r_pp", "d50", "sigma_ln"].contains(&n.as_str()) {
                fixed.push_str(&format!("{n} = {v:?}\n"));
            }
        }
        let at = |n: &str| x[names.iter().position(|m| m == n).unwrap()];
        let psd = format!(
            "[psd]\nd50_mm = {:?}\nsigma_ln = {:?}\n",
            at("d50"),
            at("sigma_ln")
        );
        if outside.is_empty() {
            answered += 1;
            let mut measured = String::from("[measured]\n");
            for r in &model.responses {
                let y = model.predict_point(r, &x);
                let e = model.prediction_error(r, &x);
                assert!(y.is_finite(), "point {point}: {} = {y} at {x:?}", r.name);
                assert!(
                    e.is_some_and(|e| e.is_finite() && e > 0.0),
                    "point {point}: {} states no error ({e:?}) at {x:?}",
                    r.name
                );
                measured.push_str(&format!("{} = {{ value = {y:?}, sd = 1.0 }}\n", r.name));
            }
            let text = format!("{measured}{psd}{fixed}");
            let m = Material::from_toml_str(&text, "point.toml").unwrap();
            let s = session::run(&m, &model, "shear_box", &SessionOptions::default())
                .unwrap_or_else(|e| panic!("point {point}: calibrate: {e}\n{text}"));
            assert!(!s.calibration.optima.is_empty());
        } else {
            refused += 1;
            let (name, v, range) = outside[0];
            assert!(
                ["K_p", "K_w"].contains(&name),
                "point {point}: only a stiffness group may be out of range, not {name} = {v}"
            );
            let text = format!("[measured]\nshear_angle = {{ value = 30, sd = 1 }}\n{psd}{fixed}");
            let m = Material::from_toml_str(&text, "point.toml").unwrap();
            let e = session::run(&m, &model, "shear_box", &SessionOptions::default())
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(name) && e.contains(&format!("{:.4e}", range[1])),
                "point {point}: {e}"
            );
        }
    }
    eprintln!("{answered} of 32 points answered, {refused} refused by name");
    assert!(answered > 0);
}
