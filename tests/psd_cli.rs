//! `mbgc psd` end to end: the binary on the example sieve file and on bad input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn mbgc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .args(args)
        .output()
        .expect("the mbgc binary runs")
}

fn example() -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("examples/sieve_gravel_8_16.csv")
        .display()
        .to_string()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn fit_json_is_the_whole_stdout_with_best_models_and_metamodel_inputs() {
    let out = mbgc(&["psd", "fit", &example(), "--json"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    let last = stdout.lines().last().unwrap_or_default();
    let v: serde_json::Value = serde_json::from_str(last)
        .unwrap_or_else(|e| panic!("last line is not JSON ({e}): {last}"));

    let models = v["models"].as_array().expect("models is a list");
    let names: Vec<&str> = models.iter().filter_map(|m| m["model"].as_str()).collect();
    assert_eq!(names, ["ggs", "rrsb", "lognormal"]);
    for m in models {
        let params = m["params"].as_object().expect("params is an object");
        assert_eq!(params.len(), 2, "{m}");
        assert!(params.values().all(|p| p.as_f64().is_some_and(|x| x > 0.0)));
        let r2 = m["r2"].as_f64().expect("r2");
        let mse = m["mse"].as_f64().expect("mse");
        // The command's JSON carries the same fits as the guide's PSD table (docs/guide/src/psd.md, to its digits).
        let (want_r2, want_mse) = match m["model"].as_str() {
            Some("ggs") => (0.98449, 2.33e-3),
            Some("rrsb") => (0.99629, 5.57e-4),
            _ => (0.99985, 2.28e-5),
        };
        assert!((r2 - want_r2).abs() < 5e-6, "{m}");
        assert!((mse / want_mse - 1.0).abs() < 0.01, "{m}");
    }
    // `best` is the model with the highest R^2.
    let best = v["best"].as_str().expect("best");
    let top = models
        .iter()
        .max_by(|a, b| a["r2"].as_f64().partial_cmp(&b["r2"].as_f64()).unwrap())
        .and_then(|m| m["model"].as_str());
    assert_eq!(Some(best), top);
    // Standard output is the JSON object alone; the table went to standard error.
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    assert!(text(&out.stderr).contains("<- best"));

    let d50 = v["d50_mm"].as_f64().expect("d50_mm");
    let sigma = v["sigma_ln"].as_f64().expect("sigma_ln");
    assert!((d50 / 11.16 - 1.0).abs() < 0.03, "d50 {d50}");
    assert!((sigma / 0.26 - 1.0).abs() < 0.05, "sigma_ln {sigma}");
    let logn = &models[2]["params"];
    assert_eq!(logn["x50_3_mm"].as_f64(), Some(d50));
    assert_eq!(logn["sigma_ln"].as_f64(), Some(sigma));
}

#[test]
fn fit_plot_writes_svg_with_r2_legend() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("figs/fit.svg");
    let out = mbgc(&[
        "psd",
        "fit",
        &example(),
        "--plot",
        &svg.display().to_string(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let body = std::fs::read_to_string(&svg).expect("figure written");
    assert!(body.starts_with("<svg"), "not an SVG");
    for label in ["GGS (R²", "RRSB (R²", "log-normal (R²", "sieve data"] {
        assert!(body.contains(label), "legend lacks {label}");
    }
}

#[test]
fn fit_missing_passing_column_fails_naming_file_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("sieve_without_passing.csv");
    std::fs::write(&bad, "size_mm,mass_g\n4,0\n8,120\n16,300\n").unwrap();
    let out = mbgc(&["psd", "fit", &bad.display().to_string(), "--json"]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(out.stdout.is_empty(), "printed {}", text(&out.stdout));
    assert!(stderr.contains(&bad.display().to_string()), "{stderr}");
    assert!(stderr.contains("column passing"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

fn read_diameters(path: &Path) -> Vec<f64> {
    let body = std::fs::read_to_string(path).expect("particles written");
    let mut lines = body.lines();
    assert_eq!(lines.next(), Some("diameter_mm"));
    lines.map(|l| l.parse().expect("a number")).collect()
}

#[test]
fn draw_writes_reproducible_particles_in_range() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, seed: &str| {
        let path = dir.path().join(name);
        let out = mbgc(&[
            "psd",
            "draw",
            "--sieve",
            &example(),
            "--n",
            "2000",
            "--d-min",
            "6",
            "--d-max",
            "20",
            "--seed",
            seed,
            "--out",
            &path.display().to_string(),
        ]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        (read_diameters(&path), text(&out.stdout))
    };
    let (a, stdout) = run("a.csv", "5");
    let (b, _) = run("b.csv", "5");
    let (c, _) = run("c.csv", "6");
    assert_eq!(a.len(), 2000);
    assert!(a.iter().all(|&d| (6.0..=20.0).contains(&d)));
    assert_eq!(a, b);
    assert_ne!(a, c);
    assert!(stdout.contains("count-mean diameter") && stdout.contains("mass-median diameter"));
}

#[test]
fn draw_bad_range_fails_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.csv");
    let out = mbgc(&[
        "psd",
        "draw",
        "--d50",
        "11.16",
        "--sigma-ln",
        "0.26",
        "--n",
        "10",
        "--d-min",
        "20",
        "--d-max",
        "10",
        "--seed",
        "1",
        "--out",
        &path.display().to_string(),
    ]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("command line: d_min"), "{stderr}");
    assert!(!path.exists(), "wrote particles despite the error");
}
