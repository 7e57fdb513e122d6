//! `mbgc calibrate` and `mbgc validate` end to end on small problems.

mod common;

use common::{fails, mbgc, ok, s};
use std::path::Path;

/// A model of y = 2 a + b^2 (a, b in [0, 1]) and z = a * c fitted by `mbgc fit` on `inputs`.
fn fit_model(dir: &Path) -> std::path::PathBuf {
    fit_on(dir, "a,b,c", "m.json")
}

fn fit_on(dir: &Path, inputs: &str, name: &str) -> std::path::PathBuf {
    let mut csv = String::from("a,b,c,y,z\n");
    for i in 0..200u32 {
        let a = sobol_burley::sample(i, 0, 3) as f64;
        let b = sobol_burley::sample(i, 1, 3) as f64;
        let c = 1.0 + sobol_burley::sample(i, 2, 3) as f64;
        csv.push_str(&format!("{a},{b},{c},{},{}\n", 2.0 * a + b * b, a * c));
    }
    let data = dir.join("t.csv");
    std::fs::write(&data, csv).unwrap();
    let model = dir.join(name);
    ok(&[
        "fit",
        "--data",
        s(&data),
        "--inputs",
        inputs,
        "--targets",
        "y,z",
        "--out",
        s(&model),
        "--population",
        "1000",
        "--generations",
        "10",
        "--no-figures",
    ]);
    model
}

#[test]
fn calibrate_writes_parameters_and_reports_the_posterior() {
    let dir = tempfile::tempdir().unwrap();
    let model = fit_model(dir.path());
    // Truth a = 0.3, b = 0.5, c = 1.5: y = 0.85, z = 0.45.
    let mat = dir.path().join("mat.toml");
    std::fs::write(
        &mat,
        "name = \"toy\"\n[measured]\ny = { value = 0.85, sd = 0.01 }\nz = { value = 0.45, sd = 0.01 }\n[fixed]\nc = 1.5\n",
    )
    .unwrap();
    let out = dir.path().join("cal.toml");
    let post = dir.path().join("posterior.csv");
    let text = ok(&[
        "calibrate",
        "--material",
        s(&mat),
        "--model",
        s(&model),
        "--out",
        s(&out),
        "--bayes",
        "--samples",
        "1000",
        "--sigma-max",
        "0.05",
        "--posterior-out",
        s(&post),
    ]);
    // The samples: every model input (the fixed one at its value), sigma, weight, model,
    // material; equally weighted, the free ones around the truth.
    let mut r = csv::Reader::from_path(&post).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(
        header,
        ["a", "b", "c", "sigma", "weight", "model", "material"],
        "{header:?}"
    );
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    assert!(rows.len() >= 1000, "{} samples", rows.len());
    let col = |k: usize| -> Vec<f64> { rows.iter().map(|x| x[k].parse().unwrap()).collect() };
    assert!(col(2).iter().all(|&c| c == 1.5), "c is fixed");
    let weights: f64 = col(4).iter().sum();
    assert!((weights - 1.0).abs() < 1e-9, "weights sum to {weights}");
    let mean_a = col(0).iter().sum::<f64>() / rows.len() as f64;
    assert!((mean_a - 0.3).abs() < 0.03, "posterior mean of a {mean_a}");
    assert!(
        col(3).iter().all(|&g| (0.0..=0.05).contains(&g)),
        "sigma within its prior"
    );
    assert!(rows.iter().all(|x| &x[6] == "toy"), "material named");
    // Without --bayes there is no posterior to write: refused, not silently skipped.
    let e = fails(&[
        "calibrate",
        "--material",
        s(&mat),
        "--model",
        s(&model),
        "--posterior-out",
        s(&dir.path().join("p2.csv")),
    ]);
    assert!(
        e.contains("--posterior-out") && e.contains("--bayes"),
        "{e}"
    );
    assert!(text.contains("distinct optim"), "{text}");
    assert!(text.contains("log evidence"), "{text}");
    let cal: toml::Table = std::fs::read_to_string(&out).unwrap().parse().unwrap();
    let p = cal["parameters"].as_table().unwrap();
    let a = p["a"].as_float().unwrap();
    let b = p["b"].as_float().unwrap();
    assert!((a - 0.3).abs() < 0.01 && (b - 0.5).abs() < 0.02, "{p:?}");
    assert_eq!(p["c"].as_float().unwrap(), 1.5);
    // JSON carries the same optimum and the posterior summaries.
    let json = ok(&[
        "calibrate",
        "--material",
        s(&mat),
        "--model",
        s(&model),
        "--json",
        "--bayes",
        "--samples",
        "500",
    ]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    // The interface scripts use: named parameters (fixed ones included), predictions by
    // response, the objective; posterior summaries by parameter name and the log-evidence.
    let best = &v["solutions"][0];
    assert!(
        (best["params"]["a"].as_f64().unwrap() - 0.3).abs() < 0.01,
        "{best}"
    );
    assert_eq!(best["params"]["c"].as_f64().unwrap(), 1.5);
    // Every model input is named, the fixed one included.
    let model_inputs = mbgc::metamodel::Metamodel::load(&model)
        .unwrap()
        .inputs
        .len();
    assert_eq!(best["params"].as_object().unwrap().len(), model_inputs);
    assert!(!best["predicted"].as_object().unwrap().is_empty(), "{best}");
    assert!(best["objective"].as_f64().unwrap() < 1.0);
    let mean_a = v["posterior"]["a"]["mean"].as_f64().unwrap();
    assert!((mean_a - 0.3).abs() < 0.03, "posterior mean of a {mean_a}");
    for k in ["cov", "q05", "q95"] {
        assert!(v["posterior"]["a"][k].as_f64().is_some(), "{k}");
    }
    assert!(v["log_evidence"].as_f64().unwrap().is_finite());
}

/// A model class that lacks an effect (y without b) loses against the full one by evidence when
/// the model error is bounded (a relative model error up to 10 % would absorb the 7 % misfit of the
/// reduced model, which then wins by having a parameter less: Occam).
#[test]
fn model_classes_are_ranked_by_evidence() {
    let dir = tempfile::tempdir().unwrap();
    let full = fit_model(dir.path());
    let reduced = fit_on(dir.path(), "a,c", "reduced.json");
    let mat = dir.path().join("mat.toml");
    std::fs::write(
        &mat,
        "[measured]\ny = { value = 0.85, sd = 0.01 }\nz = { value = 0.45, sd = 0.01 }\n[fixed]\nc = 1.5\n",
    )
    .unwrap();
    let json = ok(&[
        "calibrate",
        "--material",
        s(&mat),
        "--model",
        s(&full),
        "--model",
        s(&reduced),
        "--bayes",
        "--samples",
        "500",
        "--sigma-max",
        "0.02",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let p = v["class_probabilities"].as_array().unwrap();
    let p_full = p[0].as_f64().unwrap();
    assert!(
        p_full > 0.9,
        "P(full model) = {p_full}: {}",
        v["classes"][1]["posterior"]
    );
}

#[test]
fn validate_reruns_the_dem_experiment() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("steel.toml");
    std::fs::write(
        &mat,
        "name = \"steel ball\"\n[measured]\ncnr = { value = 0.8, sd = 0.05 }\n",
    )
    .unwrap();
    let params = dir.path().join("p.toml");
    std::fs::write(
        &params,
        "[parameters]\nE_p = 2e11\nnu_p = 0.3\nrho_p = 7800\nd50 = 10\nE_w = 2e11\ne_pw = 0.8\n\
         mu_pw = 0.1\nimpact_speed = 1.0\nimpact_angle = 0\n[predicted]\ncnr = 0.79\n\
         [model]\nclass = \"hertz,mindlin\"\n",
    )
    .unwrap();
    let text = ok(&[
        "validate",
        "--material",
        s(&mat),
        "--params",
        s(&params),
        "--experiment",
        "wall-impact",
    ]);
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("cnr"))
        .unwrap();
    let dem: f64 = line.split_whitespace().nth(3).unwrap().parse().unwrap();
    assert!((dem - 0.8).abs() < 0.01, "DEM restitution {dem}: {text}");
    // The class of the file is what runs: another on the command line is refused, and so is a
    // parameter of an effect the class lacks.
    let e = fails(&[
        "validate",
        "--material",
        s(&mat),
        "--params",
        s(&params),
        "--experiment",
        "wall-impact",
        "--model-class",
        "hertz,mindlin,epsd2",
    ]);
    assert!(e.contains("--model-class") && e.contains("p.toml"), "{e}");
    let text = std::fs::read_to_string(&params).unwrap();
    std::fs::write(
        &params,
        text.replace("mu_pw = 0.1", "mu_pw = 0.1\nced_pw = 1e4"),
    )
    .unwrap();
    let e = fails(&[
        "validate",
        "--material",
        s(&mat),
        "--params",
        s(&params),
        "--experiment",
        "wall-impact",
    ]);
    assert!(
        e.contains("parameters.ced_pw") && e.contains("sjkr") && e.contains("p.toml"),
        "{e}"
    );
    // A parameter the experiment needs but the file lacks is named.
    std::fs::write(&params, "[parameters]\nE_p = 2e11\n").unwrap();
    let o = mbgc(&[
        "validate",
        "--material",
        s(&mat),
        "--params",
        s(&params),
        "--experiment",
        "wall-impact",
    ]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("p.toml") && e.contains("missing"), "{e}");
}

#[test]
fn calibrate_refuses_bad_material_files_naming_the_key_path() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("gravel.toml");
    let cases = [
        (
            "[measured]\nshear_angle = { value = 35.5, sd = \"0.5\" }\n",
            "gravel.toml: measured.shear_angle.sd: expected a number, found string",
        ),
        (
            "[measured]\nshear_angle = { value = 35.5, sd = 0.5, unit = \"deg\" }\n",
            "gravel.toml: measured.shear_angle.unit: unknown key; expected one of: value, sd",
        ),
        (
            "[measured]\nshear_angle = { value = 35.5, sd = 0.5 }\n[constraints]\nexpr = [\"a <= b\", 2]\n",
            "gravel.toml: constraints.expr[1]: expected a string",
        ),
    ];
    for (text, want) in cases {
        std::fs::write(&mat, text).unwrap();
        let e = common::fails(&["calibrate", "--material", s(&mat), "--model", "none.json"]);
        assert!(e.contains(want), "{want}: {e}");
    }
}

#[test]
fn free_releases_a_fixed_parameter_and_refuses_one_that_is_not_fixed() {
    let dir = tempfile::tempdir().unwrap();
    let model = fit_model(dir.path());
    let mat = dir.path().join("mat.toml");
    std::fs::write(
        &mat,
        "name = \"toy\"\n[measured]\ny = { value = 0.85, sd = 0.01 }\nz = { value = 0.45, sd = 0.01 }\n[fixed]\nc = 1.5\n",
    )
    .unwrap();
    let json = ok(&[
        "calibrate",
        "--material",
        s(&mat),
        "--model",
        s(&model),
        "--free",
        "c",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    // Two measurements, three unknowns: c is searched, no longer held at 1.5, and every optimum
    // still reproduces z = a c = 0.45.
    let sols = v["solutions"].as_array().unwrap();
    assert!(
        sols.iter()
            .any(|b| (b["params"]["c"].as_f64().unwrap() - 1.5).abs() > 1e-3),
        "{v}"
    );
    let e = fails(&[
        "calibrate",
        "--material",
        s(&mat),
        "--model",
        s(&model),
        "--free",
        "b",
    ]);
    assert!(
        e.contains("--free b") && e.contains("mat.toml") && e.contains("fixes: c"),
        "{e}"
    );
}

/// Solutions that fit the measurements are told apart from local minima that do not, in the
/// text, the JSON and the written file; a file holding one point of a solution set says so.
#[test]
fn fitting_solutions_are_told_apart_from_local_minima_and_a_set_is_not_one_answer() {
    let text = ok(&["calibrate", "--material", "examples/gravel.toml"]);
    // One optimum fits; the other starts end in local minima (how many depends on the model).
    let head = text
        .lines()
        .find(|l| l.contains("distinct optima"))
        .unwrap_or_default();
    assert!(
        head.starts_with("1 of ") && head.contains("fit the measurements (chi2 <= 5.99"),
        "{text}"
    );
    assert!(text.contains("local minima that do not fit:"), "{text}");
    let v: serde_json::Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--material",
        "examples/gravel.toml",
        "--json",
    ]))
    .unwrap();
    assert_eq!(v["fitting"], 1);
    assert_eq!(v["solutions"][0]["fits"], true);
    assert_eq!(v["solutions"][1]["fits"], false);
    assert!((v["fit_threshold"].as_f64().unwrap() - 5.991).abs() < 1e-3);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.toml");
    ok(&[
        "calibrate",
        "--material",
        "examples/gravel.toml",
        "--free",
        "mu_r_pp,mu_r_pw",
        "--out",
        s(&out),
    ]);
    let written = std::fs::read_to_string(&out).unwrap();
    assert!(
        written.lines().nth(1).unwrap().starts_with("# NOT UNIQUE"),
        "{written}"
    );
    written.parse::<toml::Table>().unwrap();
}

/// `mbgc ... | head` ends quietly: a closed pipe is no panic.
#[test]
fn a_closed_pipe_ends_the_command_without_a_panic() {
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .args(["effects"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
}

/// validate runs what the model was trained on or refuses: the box scale the calibrated file
/// records, parameters the experiment reads, the material's own fixed values, a thread or more.
#[test]
fn validate_refuses_what_would_test_another_model_or_do_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let params = dir.path().join("p.toml");
    ok(&[
        "calibrate",
        "--material",
        "examples/gravel.toml",
        "--out",
        s(&params),
    ]);
    let text = std::fs::read_to_string(&params).unwrap();
    assert!(
        text.contains("[experiment]\nname = \"shear-box\"\nbox_scale = 10.0"),
        "{text}"
    );
    let validate = |p: &Path, extra: &[&str]| {
        let mut args = vec![
            "validate",
            "--material",
            "examples/gravel.toml",
            "--params",
            s(p),
        ];
        args.extend_from_slice(extra);
        fails(&args)
    };
    let e = validate(&params, &["--box-scale", "6"]);
    assert!(
        e.contains("--box-scale 6") && e.contains("trained at box scale 10"),
        "{e}"
    );
    let e = validate(&params, &["--threads", "0"]);
    assert!(e.contains("--threads 0"), "{e}");
    let typo = dir.path().join("typo.toml");
    std::fs::write(&typo, text.replace("mu_pp = ", "mu_ppp = 0.3\nmu_pp = ")).unwrap();
    let e = validate(&typo, &[]);
    assert!(
        e.contains("parameters.mu_ppp: not a parameter of shear-box"),
        "{e}"
    );
    let other = dir.path().join("other.toml");
    std::fs::write(&other, text.replace("mu_pw = 0.363", "mu_pw = 0.5")).unwrap();
    let e = validate(&other, &[]);
    assert!(e.contains("parameters.mu_pw") && e.contains("0.363"), "{e}");
}

/// Fixed values that alone put a dimensionless group outside the model's range: the message
/// says it is outside (not "inside"), with the value, the range and what to change.
#[test]
fn fixed_values_that_put_a_group_outside_are_named_as_outside() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::copy(
        root.join("examples/sieve_gravel_8_16.csv"),
        dir.path().join("sieve_gravel_8_16.csv"),
    )
    .unwrap();
    let text = std::fs::read_to_string(root.join("examples/gravel.toml"))
        .unwrap()
        .replace("nu_p = 0.25", "nu_p = 0.25\nrho_p = 1000");
    let material = dir.path().join("m.toml");
    std::fs::write(&material, text).unwrap();
    // The shipped model without its rigid limit, so that K_p 3.7e5 lies outside its range.
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(root.join("models/shear_box.json")).unwrap())
            .unwrap();
    json.as_object_mut().unwrap().remove("rigid_limit");
    let model = dir.path().join("no_limit.json");
    std::fs::write(&model, json.to_string()).unwrap();
    let e = fails(&[
        "calibrate",
        "--material",
        s(&material),
        "--model",
        s(&model),
    ]);
    assert!(
        e.contains("K_p")
            && e.contains("is not inside the model's range")
            && e.contains("expected"),
        "{e}"
    );
}
