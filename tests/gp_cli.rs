//! `mbgc fit`, `predict` and `export` end to end: the model file, predictions, the exported Rust
//! compiled by rustc and compared with `predict`, LaTeX well-formed, sympy readable by sympy, and
//! bad input refused naming the file and the field.

mod common;

use common::{fails, ok, s};
use std::path::{Path, PathBuf};
use std::process::Command;

use mbgc::metamodel::Metamodel;

/// A table with a log-scaled input: y1 = 3 mu / (1 + mu_r) + 0.2 ln(E), y2 = mu ln(E).
fn table(dir: &Path) -> (PathBuf, PathBuf) {
    let mut csv = String::from("run_id,mu,mu_r,E,y1,y2,status\n");
    let mut k = 0u64;
    for i in 0..240 {
        // A cheap deterministic scatter over the box.
        k = k
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let u = |s: u32| ((k >> s) & 0xffff) as f64 / 65535.0;
        let (mu, mu_r, e) = (0.1 + 0.8 * u(0), 0.6 * u(16), 1e6 * 100f64.powf(u(32)));
        let y1 = 3.0 * mu / (1.0 + mu_r) + 0.2 * e.ln();
        let y2 = e.ln() * mu;
        let status = if i % 40 == 7 { "failed" } else { "done" };
        csv.push_str(&format!("{i},{mu},{mu_r},{e},{y1},{y2},{status}\n"));
    }
    let data = dir.join("train.csv");
    std::fs::write(&data, csv).unwrap();
    let space = dir.join("space.toml");
    std::fs::write(
        &space,
        "[parameters]\nmu = { min = 0.1, max = 0.9 }\nmu_r = { min = 0.0, max = 0.6 }\n\
         E = { min = 1e6, max = 1e8, scale = \"log\" }\n",
    )
    .unwrap();
    (data, space)
}

fn fit(dir: &Path) -> PathBuf {
    let (data, space) = table(dir);
    let model = dir.join("model.json");
    let out = ok(&[
        "fit",
        "--data",
        s(&data),
        "--inputs",
        "mu,mu_r,E",
        "--targets",
        "y1,y2",
        "--out",
        s(&model),
        "--space",
        s(&space),
        "--population",
        "2000",
        "--generations",
        "20",
        "--seed",
        "3",
    ]);
    assert!(out.contains("y1 = ") && out.contains("y2 = "), "{out}");
    model
}

#[test]
fn fit_predict_export_agree() {
    let dir = tempfile::tempdir().unwrap();
    let model_path = fit(dir.path());
    let model = Metamodel::load(&model_path).unwrap();
    assert_eq!(
        model.data.skipped_rows, 6,
        "failed campaign rows are left out"
    );
    assert_eq!(model.data.rows, 234);
    assert_eq!(model.data.test_rows, 23);
    assert!(matches!(
        model.inputs[2].transform,
        mbgc::metamodel::Transform::Log { .. }
    ));
    for r in &model.responses {
        assert!(r.train.r2 > 0.999, "{}: {}", r.name, r.train.r2);
        assert!(r.test.unwrap().r2 > 0.999, "{}", r.name);
        assert!(!r.pareto_front.is_empty() && r.pareto_front.len() < 65);
        assert_eq!(r.train_residual_quantiles.len(), 7);
    }
    assert!(dir.path().join("model_figures/y1_parity.svg").exists());
    assert!(dir.path().join("model_figures/y2_residuals.svg").exists());

    // Fresh points inside the domain: predict writes them back with the responses appended.
    let mut pts = String::from("E,mu,mu_r,note\n");
    let mut rows = Vec::new();
    for i in 0..25 {
        let (mu, mu_r, e) = (
            0.15 + 0.03 * i as f64,
            0.02 * i as f64,
            2e6 * 1.15f64.powi(i),
        );
        rows.push([mu, mu_r, e]);
        pts.push_str(&format!("{e:?},{mu:?},{mu_r:?},p{i}\n"));
    }
    let points = dir.path().join("points.csv");
    std::fs::write(&points, pts).unwrap();
    let pred_path = dir.path().join("pred.csv");
    ok(&[
        "predict",
        "--model",
        s(&model_path),
        "--data",
        s(&points),
        "--out",
        s(&pred_path),
    ]);
    let mut rdr = csv::Reader::from_path(&pred_path).unwrap();
    assert_eq!(
        rdr.headers().unwrap().iter().collect::<Vec<_>>(),
        ["E", "mu", "mu_r", "note", "y1", "y2"]
    );
    let predicted: Vec<[f64; 2]> = rdr
        .records()
        .map(|r| {
            let r = r.unwrap();
            [r[4].parse().unwrap(), r[5].parse().unwrap()]
        })
        .collect();
    // With --errors each prediction is followed by its error: here the test RMSE (the model
    // has no error model).
    let with_errors = dir.path().join("pred_errors.csv");
    ok(&[
        "predict",
        "--model",
        s(&model_path),
        "--data",
        s(&points),
        "--out",
        s(&with_errors),
        "--errors",
    ]);
    let mut rdr = csv::Reader::from_path(&with_errors).unwrap();
    assert_eq!(
        rdr.headers().unwrap().iter().collect::<Vec<_>>(),
        ["E", "mu", "mu_r", "note", "y1", "y1_error", "y2", "y2_error"]
    );
    let rmse = model.responses[0].test.unwrap().rmse;
    for r in rdr.records() {
        assert_eq!(r.unwrap()[5].parse::<f64>().unwrap(), rmse);
    }
    for (row, p) in rows.iter().zip(&predicted) {
        let truth = [
            3.0 * row[0] / (1.0 + row[1]) + 0.2 * row[2].ln(),
            row[2].ln() * row[0],
        ];
        for k in 0..2 {
            assert!(
                (p[k] - truth[k]).abs() < 0.02 * truth[k].abs(),
                "{p:?} vs {truth:?}"
            );
        }
    }

    // Rust export: compiled on its own, evaluated at the same points.
    let rs = ok(&["export", "--model", s(&model_path), "--format", "rust"]);
    let mut main = rs.clone();
    main.push_str("\nfn main() {\n");
    for r in &rows {
        main.push_str(&format!(
            "    println!(\"{{:?}},{{:?}}\", y1({:?}, {:?}, {:?}), y2({:?}, {:?}, {:?}));\n",
            r[0], r[1], r[2], r[0], r[1], r[2]
        ));
    }
    main.push_str("}\n");
    let src = dir.path().join("export_check.rs");
    std::fs::write(&src, main).unwrap();
    let exe = dir.path().join("export_check");
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let o = Command::new(rustc)
        .args(["--edition", "2021", "-o", s(&exe), s(&src)])
        .output()
        .expect("rustc");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = Command::new(&exe).output().unwrap();
    let lines = String::from_utf8(o.stdout).unwrap();
    for (line, p) in lines.lines().zip(&predicted) {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        for k in 0..2 {
            let rel = (v[k] - p[k]).abs() / p[k].abs().max(1e-300);
            assert!(rel <= 1e-12, "export {} vs predict {}", v[k], p[k]);
        }
    }
    assert_eq!(lines.lines().count(), rows.len());

    // LaTeX: balanced braces and \left/\right pairs.
    let tex = ok(&["export", "--model", s(&model_path), "--format", "latex"]);
    assert!(tex.starts_with("\\begin{align*}") && tex.trim_end().ends_with("\\end{align*}"));
    let mut depth = 0i32;
    for c in tex.chars() {
        depth += match c {
            '{' => 1,
            '}' => -1,
            _ => 0,
        };
        assert!(depth >= 0, "{tex}");
    }
    assert_eq!(depth, 0, "{tex}");
    assert_eq!(
        tex.matches("\\left").count(),
        tex.matches("\\right").count()
    );
    assert!(
        tex.contains("\\tilde{E}"),
        "log-scaled input defined: {tex}"
    );

    // sympy: sympify reads it and gives the same values (when sympy is installed; CI installs it
    // and sets MBGC_REQUIRE_SYMPY=1 so that the check cannot be skipped there).
    let sy = ok(&["export", "--model", s(&model_path), "--format", "sympy"]);
    let Some(python) = common::sympy_python() else {
        return;
    };
    let mut script = String::from("import sympy\nfrom sympy import Symbol\nexprs = {}\n");
    for line in sy.lines() {
        let (name, e) = line.split_once(" = ").unwrap();
        script.push_str(&format!("exprs['{name}'] = sympy.sympify({e:?})\n"));
    }
    script.push_str("mu, mu_r, E = sympy.symbols('mu mu_r E')\n");
    for r in &rows {
        script.push_str(&format!(
            "print(repr(float(exprs['y1'].subs({{mu: {:?}, mu_r: {:?}, E: {:?}}}).evalf(30))), repr(float(exprs['y2'].subs({{mu: {:?}, mu_r: {:?}, E: {:?}}}).evalf(30))))\n",
            r[0], r[1], r[2], r[0], r[1], r[2]
        ));
    }
    let o = Command::new(&python)
        .args(["-c", &script])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8(o.stdout).unwrap();
    for (line, p) in out.lines().zip(&predicted) {
        let v: Vec<f64> = line.split(' ').map(|x| x.parse().unwrap()).collect();
        for k in 0..2 {
            assert!(
                (v[k] - p[k]).abs() <= 1e-9 * p[k].abs(),
                "sympy {} vs predict {}",
                v[k],
                p[k]
            );
        }
    }
    assert_eq!(out.lines().count(), rows.len());
}

#[test]
fn bad_input_is_refused_naming_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let (data, _) = table(dir.path());
    let model = dir.path().join("m.json");
    let base = |extra: &[&str]| {
        let mut v = vec![
            "fit",
            "--data",
            s(&data),
            "--out",
            s(&model),
            "--population",
            "40",
            "--generations",
            "2",
        ];
        v.extend_from_slice(extra);
        v.iter().map(|x| x.to_string()).collect::<Vec<String>>()
    };
    let run = |args: Vec<String>| fails(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let e = run(base(&["--inputs", "mu,nope", "--targets", "y1"]));
    assert!(e.contains("train.csv") && e.contains("nope"), "{e}");
    let e = run(base(&["--inputs", "mu", "--targets", "mu"]));
    assert!(e.contains("--targets"), "{e}");
    let e = run(base(&[
        "--inputs",
        "mu",
        "--targets",
        "y1",
        "--test-fraction",
        "1.5",
    ]));
    assert!(e.contains("--test-fraction"), "{e}");
    let e = run(base(&[
        "--inputs",
        "mu",
        "--targets",
        "y1",
        "--time-limit",
        "soon",
    ]));
    assert!(e.contains("duration"), "{e}");
    let e = run(base(&[
        "--inputs",
        "mu",
        "--targets",
        "y1",
        "--functions",
        "add,pow",
    ]));
    assert!(e.contains("pow"), "{e}");
    // A NaN in a used column.
    let text = std::fs::read_to_string(&data).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut f: Vec<String> = lines[3].split(',').map(String::from).collect();
    f[1] = "NaN".into();
    lines[3] = f.join(",");
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let e = fails(&[
        "fit",
        "--data",
        s(&bad),
        "--inputs",
        "mu",
        "--targets",
        "y1",
        "--out",
        s(&model),
    ]);
    assert!(
        e.contains("bad.csv") && e.contains("line 4") && e.contains("mu"),
        "{e}"
    );
    // A model file that is not one.
    let junk = dir.path().join("junk.json");
    std::fs::write(&junk, "{\"format\": 3}").unwrap();
    let e = fails(&["export", "--model", s(&junk), "--format", "rust"]);
    assert!(e.contains("junk.json"), "{e}");
}

#[test]
fn same_seed_same_model_file() {
    let dir = tempfile::tempdir().unwrap();
    let (data, _) = table(dir.path());
    let run = |name: &str| {
        let out = dir.path().join(name);
        ok(&[
            "fit",
            "--data",
            s(&data),
            "--inputs",
            "mu,mu_r,E",
            "--targets",
            "y2",
            "--out",
            s(&out),
            "--population",
            "300",
            "--generations",
            "5",
            "--seed",
            "4",
            "--no-figures",
        ]);
        let mut m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap();
        m["responses"][0]["seconds"] = serde_json::Value::Null;
        m
    };
    assert_eq!(run("a.json"), run("b.json"));
}

/// A column holding a parameter the model's campaign held fixed is read: a row at another value
/// lies outside what the model describes and is counted and named as such.
#[test]
fn predict_names_rows_at_another_value_of_a_held_parameter() {
    let dir = tempfile::tempdir().unwrap();
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/diagnose_local_sjkr.json");
    let data = dir.path().join("pts.csv");
    std::fs::write(
        &data,
        "mu_pp,d50,ced_pp,E_p\n0.4,4,10000,5e6\n0.4,4,10000,5e7\n",
    )
    .unwrap();
    let out = dir.path().join("pred.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .args(["predict", "--model", s(&model), "--data", s(&data)])
        .args(["--out", s(&out), "--json"])
        .output()
        .unwrap();
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["outside_domain"], 1, "{v}");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("line 3: E_p = 50000000, but the model holds only at E_p = 5000000"),
        "{err}"
    );
}

/// A validation table's scores are printed and in the JSON, not only in the model file; a
/// folder of figures that holds an input with a figure's name is refused.
#[test]
fn fit_reports_its_validation_and_keeps_figures_off_its_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let (data, _) = table(dir.path());
    let model = dir.path().join("m.json");
    let args = |extra: &[&str]| -> Vec<String> {
        let mut v = vec![
            "fit",
            "--inputs",
            "mu,mu_r,E",
            "--targets",
            "y1",
            "--out",
            s(&model),
            "--population",
            "200",
            "--generations",
            "3",
        ];
        v.extend_from_slice(extra);
        v.iter().map(|x| x.to_string()).collect()
    };
    let run = |a: Vec<String>| ok(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let text = run(args(&[
        "--data",
        s(&data),
        "--validation",
        s(&data),
        "--no-figures",
    ]));
    assert!(
        text.contains("validation R2 ") && text.contains("rows)"),
        "{text}"
    );
    let json = run(args(&[
        "--data",
        s(&data),
        "--validation",
        s(&data),
        "--no-figures",
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert!(v["responses"][0]["validation"]["r2"].is_number(), "{json}");
    // Data whose name is that of a figure the fit draws, in the folder of figures.
    let figs = dir.path().join("figs");
    std::fs::create_dir(&figs).unwrap();
    let named = figs.join("y1_parity.svg");
    std::fs::copy(&data, &named).unwrap();
    let before = std::fs::read(&named).unwrap();
    let a = args(&["--data", s(&named), "--figures", s(&figs)]);
    let e = fails(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(e.contains("--figures") && e.contains("--data"), "{e}");
    assert_eq!(std::fs::read(&named).unwrap(), before);
}

/// A DEM table fitted without its campaign record: the model cannot know its experiment, and
/// the fit says so instead of writing a model that validate cannot check.
#[test]
fn fit_warns_when_a_dem_table_has_no_campaign_record() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("dl.csv");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("training_data/diagnose_local.csv"),
        &data,
    )
    .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .args([
            "fit",
            "--data",
            s(&data),
            "--inputs",
            "mu_pp,d50",
            "--targets",
        ])
        .args([
            "shear_angle",
            "--population",
            "100",
            "--generations",
            "2",
            "--no-figures",
        ])
        .args(["--out", s(&dir.path().join("m.json"))])
        .output()
        .unwrap();
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("has no campaign record"), "{err}");
}
