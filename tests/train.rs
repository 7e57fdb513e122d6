//! `mbgc train` end to end on the stand-in experiment `sleep-test` (f = x + 2 y, instant runs):
//! the three stages, the files they leave, a resume that simulates nothing twice, an extension
//! that simulates only the new rows, shards, and a design that a smaller --n would cut.

use std::path::Path;
use std::process::{Command, Output};

fn mbgc(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run mbgc")
}

fn ok(dir: &Path, args: &[&str]) -> String {
    let o = mbgc(dir, args);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{args:?} failed: {err}");
    err
}

fn rows(path: &Path) -> usize {
    std::fs::read_to_string(path).unwrap().lines().count() - 1
}

const SPACE: &str = "name = \"t\"\n[parameters]\nx = { min = 0.0, max = 1.0 }\n\
                     y = { min = 0.0, max = 1.0 }\n";

#[test]
fn train_samples_simulates_fits_resumes_and_extends() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("space.toml"), SPACE).unwrap();
    let args = |n: &str| {
        vec![
            "train",
            "--space",
            "space.toml",
            "--experiment",
            "sleep-test",
            "--n",
            n,
            "--validation",
            "6",
            "--responses",
            "f",
            "--population",
            "200",
            "--generations",
            "3",
            "--threads",
            "1",
        ]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>()
    };
    let run = |n: &str| {
        let a = args(n);
        ok(d, &a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let err = run("12");
    assert!(
        err.contains("[1/3 sample]") && err.contains("[2/3 simulate]"),
        "{err}"
    );
    for f in [
        "sampling/sleep_test.csv",
        "sampling/sleep_test_validation.csv",
        "training_data/sleep_test.csv",
        "training_data/sleep_test_validation.csv",
        "training_data/sleep_test.train.json",
        "models/sleep_test.json",
        "models/sleep_test.rs",
        "models/sleep_test.tex",
        "models/sleep_test_figures/f_parity.svg",
    ] {
        assert!(d.join(f).exists(), "{f} missing");
    }
    assert_eq!(rows(&d.join("training_data/sleep_test.csv")), 12);
    assert_eq!(rows(&d.join("training_data/sleep_test_validation.csv")), 6);
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("models/sleep_test.json")).unwrap())
            .unwrap();
    let v = &model["responses"][0]["validation"];
    assert_eq!(v["rows"], 6, "{model}");
    assert!(v["r2"].as_f64().unwrap() > 0.99, "{v}");
    // Again: nothing is simulated twice.
    let err = run("12");
    assert!(err.contains("12 already done, ran 0"), "{err}");
    // Larger: the old rows stay, only the new ones run.
    let before = std::fs::read_to_string(d.join("sampling/sleep_test.csv")).unwrap();
    let err = run("16");
    assert!(err.contains("12 already done, ran 4"), "{err}");
    assert!(std::fs::read_to_string(d.join("sampling/sleep_test.csv"))
        .unwrap()
        .starts_with(&before));
    // Smaller: refused, naming the design.
    let o = mbgc(
        d,
        &args("10").iter().map(String::as_str).collect::<Vec<_>>(),
    );
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("sleep_test.csv") && e.contains("found 16"),
        "{e}"
    );
}

#[test]
fn a_shard_simulates_its_rows_and_does_not_fit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("space.toml"), SPACE).unwrap();
    let err = ok(
        d,
        &[
            "train",
            "--space",
            "space.toml",
            "--experiment",
            "sleep-test",
            "--n",
            "8",
            "--shard",
            "2/4",
            "--out-dir",
            "run",
            "--threads",
            "1",
        ],
    );
    assert!(err.contains("shard 2/4 done"), "{err}");
    assert_eq!(rows(&d.join("run/training_data/sleep_test.csv")), 2);
    assert!(!d.join("run/models/sleep_test.json").exists());
}

#[test]
fn partial_fits_on_the_rows_there_are_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("space.toml"), SPACE).unwrap();
    let base = [
        "train",
        "--space",
        "space.toml",
        "--experiment",
        "sleep-test",
        "--n",
        "16",
        "--responses",
        "f",
        "--population",
        "200",
        "--generations",
        "3",
        "--threads",
        "1",
    ];
    ok(d, &[&base[..], &["--shard", "1/2"]].concat());
    // Without --partial the fit waits for the missing rows.
    let o = mbgc(d, &base);
    assert!(o.status.success());
    assert_eq!(rows(&d.join("training_data/sleep_test.csv")), 16);
    std::fs::remove_file(d.join("models/sleep_test.json")).unwrap();
    // A fresh campaign half done: --partial simulates nothing and fits on the 8 rows there are.
    std::fs::remove_dir_all(d.join("training_data")).unwrap();
    ok(d, &[&base[..], &["--shard", "2/2"]].concat());
    // 8 rows are too few for 5-fold cross-validation: refused with the way out named.
    let o = mbgc(d, &[&base[..], &["--partial"]].concat());
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && text.contains("got 8") && text.contains("--select best"),
        "{text}"
    );
    let err = ok(d, &[&base[..], &["--partial", "--select", "best"]].concat());
    assert!(
        err.contains("skipped (--partial), 8 rows not yet simulated")
            && err.contains("provisional"),
        "{err}"
    );
    assert_eq!(rows(&d.join("training_data/sleep_test.csv")), 8);
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("models/sleep_test.json")).unwrap())
            .unwrap();
    assert_eq!(model["data"]["rows"], 8, "{model}");
    let o = mbgc(d, &[&base[..], &["--partial", "--no-fit"]].concat());
    assert!(!o.status.success());
}
