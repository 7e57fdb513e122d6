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
