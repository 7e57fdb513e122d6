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
    box_points("models/shear_box.json");
}

/// The same for the cohesive model, with the cohesion drawn over what the model covers at each
/// point: beyond its stiffness data a cohesion group is read at the edge as C (E*_edge /
/// E*)^(2/3) (docs/cohesion_stiffness.md), so its range there is the training runs' C range
/// carried back (and ced_pp <= 0.01 E_p, the space's constraint).
#[test]
fn every_point_of_seed_004s_box_is_answered_by_the_cohesive_model_with_its_error() {
    box_points("models/shear_box_sjkr.json");
}

/// The same for the model trained to K_p 9.8e6 (docs/metamodel_wide.md).
#[test]
fn every_point_of_seed_004s_box_is_answered_by_the_widened_model_with_its_error() {
    box_points("models/shear_box_wide.json");
}

/// And for its cohesive companion, whose cohesion is bounded by its contact pull's range.
#[test]
fn every_point_of_seed_004s_box_is_answered_by_the_widened_cohesive_model_with_its_error() {
    box_points("models/shear_box_sjkr_wide.json");
}

fn box_points(path: &str) {
    use mbgc::calibrate::session::{self, SessionOptions};
    use mbgc::material::Material;
    use rand::RngExt as _;
    let model = mbgc::metamodel::Metamodel::load(std::path::Path::new(path))
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
        let mut x = x;
        let k = |n: &str| names.iter().position(|m| m == n);
        for ced in ["ced_pp", "ced_pw"] {
            let (Some(kc), Some(_)) = (k(ced), model.group_of_input(ced)) else {
                continue;
            };
            // Each group of ced (the fitted one and a support group bounding it) is linear in
            // ced, carried or not: its read value per unit of ced bounds ced at this point.
            let u = x[kc] / model.inputs[kc].domain[1];
            x[kc] = 1.0;
            let mut top = model.inputs[kc].domain[1];
            for g in model
                .groups
                .iter()
                .filter(|g| g.group.monomial.contains(ced))
            {
                let per_unit = model.group_read_value(&g.group, &x);
                top = top.min(g.domain[1] / per_unit);
            }
            if ced == "ced_pp" {
                top = top.min(0.01 * x[k("E_p").unwrap()]);
            }
            x[kc] = u * top;
        }
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
    eprintln!("{path}: {answered} of 32 points answered, {refused} refused by name");
    assert!(answered > 0);
}

/// Beyond the data the rigid limit's scatter varies with the parameters, so L-BFGS minimises
/// -2 ln L = chi^2 + 2 sum ln(sd / measured sd), and its gradient must be that function's: a
/// central difference of the objective checks it, inside the data the term must vanish.
#[test]
fn beyond_the_data_the_objective_is_minus_two_ln_l_with_its_gradient() {
    use mbgc::calibrate::Problem;
    use mbgc::material::Material;
    let model = mbgc::metamodel::Metamodel::load(std::path::Path::new("models/shear_box.json"))
        .expect("the shipped model loads");
    let names = model.input_names();
    for (e, beyond) in [(2e7, false), (2e8, true)] {
        // rho_p 2600, d50 8 mm: K_p 9.8e4 at E 2e7 (inside), 9.8e5 at 2e8 (beyond the edge).
        let x: Vec<f64> = model
            .inputs
            .iter()
            .map(|i| match i.name.as_str() {
                "E_p" | "E_w" => e,
                "rho_p" => 2600.0,
                "d50" => 8.0,
                _ => 0.5 * (i.domain[0] + i.domain[1]),
            })
            .collect();
        let mut text = String::from("[measured]\n");
        for r in &model.responses {
            // Off the prediction, so that the residuals and their gradient are not zero.
            let y = model.predict_point(r, &x) * 1.01;
            text.push_str(&format!("{} = {{ value = {y:?}, sd = 0.5 }}\n", r.name));
        }
        let at = |n: &str| x[names.iter().position(|m| m == n).unwrap()];
        text.push_str(&format!(
            "[psd]\nd50_mm = 8.0\nsigma_ln = {:?}\n[fixed]\n",
            at("sigma_ln")
        ));
        for (n, v) in names.iter().zip(&x) {
            if !["mu_pp", "rho_p", "d50", "sigma_ln"].contains(&n.as_str()) {
                text.push_str(&format!("{n} = {v:?}\n"));
            }
        }
        let m = Material::from_toml_str(&text, "point.toml").unwrap();
        let p = Problem::new(&model, &m).unwrap();
        assert_eq!(p.free_names(), vec!["mu_pp", "rho_p"]);
        let free = [at("mu_pp") * 1.1, 2500.0];
        let (f, g) = p.objective(&free).expect("finite");
        let chi2: f64 = p.residuals(&free).iter().map(|r| r * r).sum();
        let sd_term = p.sd_term(&free);
        assert!(
            (f - chi2 - sd_term).abs() < 1e-9 * f,
            "{f} vs {chi2} + {sd_term}"
        );
        if beyond {
            assert!(sd_term > 0.1, "the limit's scatter counts: {sd_term}");
        } else {
            assert_eq!(sd_term, 0.0);
        }
        for j in 0..2 {
            let h = 1e-5 * free[j];
            let (mut lo, mut hi) = (free, free);
            lo[j] -= h;
            hi[j] += h;
            let fd = (p.objective(&hi).unwrap().0 - p.objective(&lo).unwrap().0) / (2.0 * h);
            assert!(
                (g[j] - fd).abs() <= 1e-3 * fd.abs().max(1e-6 * f / free[j]),
                "E {e}, parameter {j}: gradient {} against the difference {fd}",
                g[j]
            );
        }
    }
}

/// The limit's reach is stored in K_p's values; the wall's group is read at the same decades
/// beyond its own edges (its data's edges differ from the particles' by a fraction of a percent).
#[test]
fn the_wall_group_reaches_as_many_decades_beyond_its_edges_as_the_particle_group() {
    let model = mbgc::metamodel::Metamodel::load(std::path::Path::new("models/shear_box.json"))
        .expect("the shipped model loads");
    let lim = model
        .rigid_limit
        .as_ref()
        .expect("the shipped model has a rigid limit");
    let (wall, _) = lim.wall.as_ref().expect("and a wall group");
    let group = |n: &str| model.groups.iter().find(|g| g.group.name == n).unwrap();
    let (kp, kw) = (group(&lim.group), group(wall));
    assert_ne!(kp.domain, kw.domain, "the test needs edges that differ");
    let (rp, rw) = (model.group_range(kp), model.group_range(kw));
    assert_eq!(rp, lim.reach);
    for s in 0..2 {
        let (dp, dw) = (rp[s] / kp.domain[s], rw[s] / kw.domain[s]);
        assert!((dp / dw - 1.0).abs() < 1e-12, "side {s}: {dp} vs {dw}");
    }
}
