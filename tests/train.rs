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
    let saved = std::fs::read_to_string(d.join("models/sleep_test.json")).unwrap();
    let err = run("12");
    assert!(err.contains("12 already done, ran 0"), "{err}");
    // ... nor fitted twice: the same rows and settings keep the saved model as it is.
    assert!(err.contains("already; kept"), "{err}");
    assert_eq!(
        std::fs::read_to_string(d.join("models/sleep_test.json")).unwrap(),
        saved
    );
    // The space file is part of what was fitted (its constraints and scales): an edit fits
    // again, while another spelling of its path does not.
    let mut dotted = args("12");
    dotted[2] = "./space.toml".to_string();
    let err = ok(d, &dotted.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(err.contains("already; kept"), "{err}");
    std::fs::write(d.join("space.toml"), format!("{SPACE}# edited\n")).unwrap();
    let err = run("12");
    assert!(!err.contains("already; kept"), "{err}");
    // Another GP setting fits again.
    let mut other = args("12");
    other.extend(["--parsimony".to_string(), "0.01".to_string()]);
    let err = ok(d, &other.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(!err.contains("already; kept"), "{err}");
    // Larger: the old rows stay, only the new ones run.
    let before = std::fs::read_to_string(d.join("sampling/sleep_test.csv")).unwrap();
    let err = run("16");
    assert!(err.contains("12 already done, ran 4"), "{err}");
    assert!(!err.contains("already; kept"), "new rows are fitted: {err}");
    assert!(std::fs::read_to_string(d.join("sampling/sleep_test.csv"))
        .unwrap()
        .starts_with(&before));
    // A rest rule is the shear box's: refused here, naming the option and the experiment.
    let mut a = args("16");
    a.extend(["--rest-rule".to_string(), "response".to_string()]);
    let o = mbgc(d, &a.iter().map(String::as_str).collect::<Vec<_>>());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("--rest-rule response") && e.contains("sleep-test"),
        "{e}"
    );
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

/// `train` of the wall impact on one thread: the arguments every extension test starts from.
fn impact_train<'a>(space: &'a str, name: &'a str, n: &'a str, v: &'a str) -> Vec<&'a str> {
    vec![
        "train",
        "--space",
        space,
        "--experiment",
        "wall-impact",
        "--name",
        name,
        "--n",
        n,
        "--validation",
        v,
        "--threads",
        "1",
    ]
}

/// The wall impact (a few milliseconds a run) with sliding friction, then with EPSD2 rolling
/// friction added by `--extends`.
fn impact_space(class: &str, extra: &str) -> String {
    format!(
        "name = \"impact\"\n[model]\nclass = \"{class}\"\n[parameters]\n\
         E_p = {{ min = 1e6, max = 1e8, fixed = 5e6 }}\n\
         nu_p = {{ min = 0.1, max = 0.5, fixed = 0.3 }}\n\
         rho_p = {{ min = 1000, max = 3000, fixed = 2600 }}\n\
         d50 = {{ min = 1, max = 10, fixed = 4 }}\n\
         E_w = {{ min = 1e6, max = 1e8, fixed = 5e6 }}\n\
         impact_speed = {{ min = 0.5, max = 2, fixed = 1 }}\n\
         impact_angle = {{ min = 10, max = 60 }}\n\
         e_pw = {{ min = 0.3, max = 0.9, fixed = 0.5 }}\n\
         mu_pw = {{ min = 0.1, max = 0.5 }}\n{extra}"
    )
}

/// Issue 40: a model carried to a wider range (stiffer materials) keeps its runs: the old rows
/// come first in the new design, unchanged, are copied rather than run, and the new rows fill
/// the widened space around them. Narrowing or rescaling a range is refused by name.
#[test]
fn extends_widens_a_range_and_runs_only_new_rows() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("base.toml"), impact_space("hertz,mindlin", "")).unwrap();
    let wide = impact_space("hertz,mindlin", "")
        .replace(
            "impact_angle = { min = 10, max = 60 }",
            "impact_angle = { min = 10, max = 80 }",
        )
        .replace(
            "mu_pw = { min = 0.1, max = 0.5 }",
            "mu_pw = { min = 0.02, max = 0.5 }",
        );
    std::fs::write(d.join("wide.toml"), &wide).unwrap();
    std::fs::write(
        d.join("narrow.toml"),
        wide.replace("min = 0.02, max = 0.5", "min = 0.2, max = 0.5"),
    )
    .unwrap();
    std::fs::write(
        d.join("log.toml"),
        wide.replace(
            "min = 0.02, max = 0.5",
            "min = 0.02, max = 0.5, scale = \"log\"",
        ),
    )
    .unwrap();
    let train = |space: &'static str, name: &'static str, n: &'static str, v: &'static str| {
        let mut a = impact_train(space, name, n, v);
        a.push("--no-fit");
        if name != "base" {
            a.extend(["--extends", "base"]);
        }
        a
    };
    ok(d, &train("base.toml", "base", "10", "4"));
    for (args, want) in [
        (train("narrow.toml", "wide", "16", "4"), "parameters.mu_pw"),
        (train("log.toml", "wide", "16", "4"), "parameters.mu_pw"),
        (train("wide.toml", "wide", "16", "3"), "--validation 3"),
        (train("wide.toml", "wide", "10", "4"), "--n 10"),
    ] {
        let o = mbgc(d, &args);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && e.contains(want), "{args:?}: {e}");
        assert!(!d.join("training_data/wide.csv").exists(), "{args:?}");
    }
    let err = ok(d, &train("wide.toml", "wide", "16", "4"));
    assert!(
        err.contains("copied 10 runs") && err.contains("inside the old ranges"),
        "{err}"
    );
    assert!(err.contains("10 already done, ran 6"), "{err}");
    assert!(err.contains("4 already done, ran 0"), "{err}");
    let old = std::fs::read_to_string(d.join("sampling/base.csv")).unwrap();
    let new = std::fs::read_to_string(d.join("sampling/wide.csv")).unwrap();
    let new: Vec<&str> = new.lines().collect();
    assert_eq!(new.len(), 17);
    for (o, n) in old.lines().zip(&new) {
        assert_eq!(o, *n);
    }
    // The new rows go where the old ones left the widened space empty: outside the old box.
    let col = |line: &str, name: &str| -> f64 {
        let i = new[0].split(',').position(|h| h == name).unwrap();
        line.split(',').nth(i).unwrap().parse().unwrap()
    };
    let outside = new[11..]
        .iter()
        .filter(|l| col(l, "impact_angle") > 60.0 || col(l, "mu_pw") < 0.1)
        .count();
    assert!(outside >= 4, "{outside} of 6 new rows outside the old box");
    let rec: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(d.join("training_data/wide.train.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(rec["extends"]["added"].as_array().unwrap().len(), 0);
    assert_eq!(rec["extends"]["widened"][0][0], "impact_angle");
    assert_eq!(rec["extends"]["widened"][1][0], "mu_pw");
}

#[test]
fn extends_copies_the_old_runs_onto_the_effect_off_face_and_runs_only_new_rows() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("base.toml"), impact_space("hertz,mindlin", "")).unwrap();
    let with =
        |range: &str| impact_space("hertz,mindlin,epsd2", &format!("mu_r_pw = {{ {range} }}\n"));
    std::fs::write(d.join("rolling.toml"), with("min = 0, max = 0.3")).unwrap();
    std::fs::write(d.join("away.toml"), with("min = 0.05, max = 0.3")).unwrap();
    let base = [
        "train",
        "--space",
        "base.toml",
        "--experiment",
        "wall-impact",
        "--name",
        "base",
        "--n",
        "12",
        "--validation",
        "4",
        "--threads",
        "1",
        "--no-fit",
    ];
    ok(d, &base);
    let ext = |space: &'static str, n: &'static str, seed: &'static str| {
        vec![
            "train",
            "--space",
            space,
            "--experiment",
            "wall-impact",
            "--name",
            "rolling",
            "--extends",
            "base",
            "--n",
            n,
            "--validation",
            "6",
            "--seed",
            seed,
            "--threads",
            "1",
            "--no-fit",
        ]
    };
    // Refused: the added parameter's range misses the value that switches it off, a changed
    // seed, no new row.
    for (args, want) in [
        (ext("away.toml", "20", "1"), "parameters.mu_r_pw"),
        (ext("rolling.toml", "20", "2"), "--seed"),
        (ext("rolling.toml", "12", "1"), "--n 12"),
        (ext("base.toml", "20", "1"), "adds no effect"),
    ] {
        let o = mbgc(d, &args);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && e.contains(want), "{args:?}: {e}");
        assert!(!d.join("training_data/rolling.csv").exists(), "{args:?}");
    }
    let err = ok(d, &ext("rolling.toml", "20", "1"));
    assert!(
        err.contains("copied 12 runs") && err.contains("copied 4 runs"),
        "{err}"
    );
    assert!(err.contains("12 already done, ran 8"), "{err}");
    assert!(err.contains("4 already done, ran 2"), "{err}");
    // The old design rows come first, unchanged, at mu_r_pw = 0.
    let old = std::fs::read_to_string(d.join("sampling/base.csv")).unwrap();
    let new = std::fs::read_to_string(d.join("sampling/rolling.csv")).unwrap();
    let new: Vec<&str> = new.lines().collect();
    assert_eq!(new.len(), 21);
    assert!(new[0].ends_with(",mu_r_pw"), "{}", new[0]);
    for (o, n) in old.lines().skip(1).zip(&new[1..13]) {
        assert_eq!(format!("{o},0.0"), *n);
    }
    assert!(new[13..].iter().any(|l| !l.ends_with(",0.0")));
    // The copied lines say so; a fresh run of the same rows with rolling friction at 0 gives the
    // same responses (the wall impact has no cohesion, so bit for bit).
    ok(
        d,
        &[
            "simulate",
            "--design",
            "sampling/rolling.csv",
            "--experiment",
            "wall-impact",
            "--model-class",
            "hertz,mindlin,epsd2",
            "--out",
            "fresh.csv",
            "--seed",
            "1",
            "--threads",
            "1",
        ],
    );
    let table = |p: &str| {
        let mut r = csv::Reader::from_path(d.join(p)).unwrap();
        let h = r.headers().unwrap().clone();
        let mut rows: Vec<std::collections::HashMap<String, String>> = r
            .records()
            .map(|x| {
                let x = x.unwrap();
                h.iter()
                    .map(String::from)
                    .zip(x.iter().map(String::from))
                    .collect()
            })
            .collect();
        rows.sort_by_key(|m| m["row"].parse::<usize>().unwrap());
        rows
    };
    let (copied, fresh) = (table("training_data/rolling.csv"), table("fresh.csv"));
    assert_eq!(copied.len(), 20);
    for (c, f) in copied.iter().zip(&fresh) {
        assert_eq!(c["run_id"], f["run_id"]);
        assert_eq!(c["model_class"], "hertz+mindlin+epsd2");
        for r in ["cnr", "ctr"] {
            assert_eq!(c[r], f[r], "row {} {r}", c["row"]);
        }
        let row: usize = c["row"].parse().unwrap();
        assert_eq!(
            c["warnings"].contains("copied from training_data/base.csv"),
            row < 12,
            "{c:?}"
        );
    }
    // Again: nothing runs, nothing is copied twice.
    let err = ok(d, &ext("rolling.toml", "20", "1"));
    assert!(
        err.contains("20 already done, ran 0") && !err.contains("copied"),
        "{err}"
    );
    let rec: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(d.join("training_data/rolling.train.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(rec["extends"]["from"], "base");
    assert_eq!(rec["extends"]["added"][0], "epsd2");

    // A model file from wherever it lies (the shipped model's case): extended from another
    // directory into a third, its record's relative space path read under its own root. Issue 35:
    // `--extends shear_box --out-dir mine` looked for the old record under mine/.
    let elsewhere = tempfile::tempdir().unwrap();
    let (model, space) = (d.join("models/base.json"), d.join("rolling.toml"));
    let mine = elsewhere.path().join("mine");
    let args = |from: &str| {
        [
            "train",
            "--space",
            space.to_str().unwrap(),
            "--experiment",
            "wall-impact",
            "--name",
            "rolling",
            "--extends",
            from,
            "--out-dir",
            mine.to_str().unwrap(),
            "--n",
            "20",
            "--validation",
            "6",
            "--threads",
            "1",
            "--no-fit",
        ]
        .map(String::from)
    };
    let run = |a: &[String]| {
        mbgc(
            elsewhere.path(),
            &a.iter().map(String::as_str).collect::<Vec<_>>(),
        )
    };
    let o = run(&args("base.json"));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("<dir>/models/<name>.json"),
        "{e}"
    );
    // Into itself, however the directory is spelled: refused before anything is written.
    let o = mbgc(
        d,
        &[
            "train",
            "--space",
            "rolling.toml",
            "--experiment",
            "wall-impact",
            "--name",
            "base",
            "--extends",
            "./models/base.json",
            "--n",
            "20",
            "--no-fit",
        ],
    );
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("--name must differ"),
        "{e}"
    );
    let o = run(&args(model.to_str().unwrap()));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("copied 12 runs") && e.contains("12 already done, ran 8"),
        "{e}"
    );
    assert_eq!(rows(&mine.join("training_data/rolling.csv")), 20);
    assert_eq!(
        std::fs::read_to_string(mine.join("sampling/rolling.csv")).unwrap(),
        std::fs::read_to_string(d.join("sampling/rolling.csv")).unwrap()
    );
}

/// A space's `[constraints]`: the rows outside are not run, rows run before the constraint was
/// set are not fitted, the model keeps the limit, and a calibration stays inside it.
#[test]
fn constraints_limit_the_runs_the_fit_and_the_calibration() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("space.toml"), SPACE).unwrap();
    std::fs::write(
        d.join("limited.toml"),
        format!("{SPACE}[constraints]\nexpr = [\"y <= x\"]\n"),
    )
    .unwrap();
    let args = |space: &'static str| {
        vec![
            "train",
            "--space",
            space,
            "--experiment",
            "sleep-test",
            "--n",
            "24",
            "--validation",
            "8",
            "--responses",
            "f",
            "--population",
            "300",
            "--generations",
            "10",
            "--threads",
            "1",
        ]
    };
    // A fresh train runs only the rows inside.
    let sub = tempfile::tempdir().unwrap();
    let s = sub.path();
    std::fs::copy(d.join("limited.toml"), s.join("limited.toml")).unwrap();
    let err = ok(s, &args("limited.toml"));
    let design = std::fs::read_to_string(s.join("sampling/sleep_test.csv")).unwrap();
    let inside = design
        .lines()
        .skip(1)
        .filter(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            v[1] <= v[0]
        })
        .count();
    assert!(inside > 4 && inside < 24, "{design}");
    assert!(
        err.contains(&format!(
            "{} of 24 design rows lie outside the space's constraints (y <= x): not run",
            24 - inside
        )),
        "{err}"
    );
    assert_eq!(rows(&s.join("training_data/sleep_test.csv")), inside);
    // Run without the limit first, then fitted with it: the rows outside are left out.
    ok(d, &[&args("space.toml")[..], &["--no-fit"]].concat());
    assert_eq!(rows(&d.join("training_data/sleep_test.csv")), 24);
    let err = ok(d, &args("limited.toml"));
    assert!(err.contains("lie outside the space's constraints"), "{err}");
    let path = d.join("models/sleep_test.json");
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(model["constraints"][0], "y <= x", "{model}");
    assert_eq!(model["data"]["rows"], inside, "{model}");
    assert_eq!(model["data"]["outside_rows"], 24 - inside, "{model}");
    // f = x + 2 y = 2.4: along the line, only x >= 0.8 keeps y <= x.
    std::fs::write(
        d.join("m.toml"),
        "name = \"m\"\n[measured]\nf = { value = 2.4, sd = 0.01 }\n",
    )
    .unwrap();
    let o = mbgc(
        d,
        &[
            "calibrate",
            "--material",
            "m.toml",
            "--model",
            "models/sleep_test.json",
            "--json",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json = String::from_utf8_lossy(&o.stdout);
    let v: serde_json::Value =
        serde_json::from_str(&json).unwrap_or_else(|e| panic!("{e}: {json}"));
    // Local optima that do not fit (beyond the limit, held at it by the penalty) are listed
    // as such; every one that fits lies inside.
    let solutions: Vec<&serde_json::Value> = v["solutions"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["fits"] == true)
        .collect();
    assert!(!solutions.is_empty(), "{v}");
    for sol in solutions {
        let (x, y) = (
            sol["params"]["x"].as_f64().unwrap(),
            sol["params"]["y"].as_f64().unwrap(),
        );
        assert!(y <= x + 1e-3 && x > 0.79, "{sol}");
    }
}

/// `--extends --correction`: the old equation is kept and a correction fitted on top.
#[test]
fn a_correction_keeps_the_extended_equation_and_adds_to_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("base.toml"), impact_space("hertz,mindlin", "")).unwrap();
    std::fs::write(
        d.join("rolling.toml"),
        impact_space("hertz,mindlin,epsd2", "mu_r_pw = { min = 0, max = 0.3 }\n"),
    )
    .unwrap();
    let train = |space: &str, name: &str, n: &str, v: &str, extra: &[&str]| {
        let mut a = impact_train(space, name, n, v);
        a.extend([
            "--population",
            "300",
            "--generations",
            "5",
            "--select",
            "best",
        ]);
        a.extend_from_slice(extra);
        ok(d, &a)
    };
    train("base.toml", "base", "12", "5", &[]);
    // Refused without --extends.
    let o = mbgc(
        d,
        &[
            "train",
            "--space",
            "rolling.toml",
            "--experiment",
            "wall-impact",
            "--n",
            "20",
            "--correction",
        ],
    );
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--extends"));
    train(
        "rolling.toml",
        "rolling",
        "20",
        "8",
        &["--extends", "base", "--correction"],
    );
    let read = |p: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.join(p)).unwrap()).unwrap()
    };
    let (old, new) = (read("models/base.json"), read("models/rolling.json"));
    for k in 0..2 {
        let (o, n) = (
            old["responses"][k]["equation"].as_str().unwrap(),
            new["responses"][k]["equation"].as_str().unwrap(),
        );
        assert!(n.contains(o), "{n} does not hold {o}");
    }
}

/// `--correct` and `--also-fit` (issue 40): an effect model's runs refitted, without a run, as a
/// correction of a base model widened since, beside that base's runs. The widened base's table
/// lacks the effect's parameter: its runs are taken at the value that switches the effect off,
/// and the runs both tables copied from the first base count once.
#[test]
fn an_effect_model_is_refitted_onto_a_widened_base_beside_its_runs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let widen = |s: String| {
        s.replace(
            "impact_angle = { min = 10, max = 60 }",
            "impact_angle = { min = 10, max = 80 }",
        )
    };
    let rolling = |s: String| format!("{s}mu_r_pw = {{ min = 0, max = 0.3 }}\n");
    std::fs::write(d.join("base.toml"), impact_space("hertz,mindlin", "")).unwrap();
    std::fs::write(
        d.join("wide.toml"),
        widen(impact_space("hertz,mindlin", "")),
    )
    .unwrap();
    std::fs::write(
        d.join("rolling.toml"),
        rolling(impact_space("hertz,mindlin,epsd2", "")),
    )
    .unwrap();
    std::fs::write(
        d.join("rolling_wide.toml"),
        rolling(widen(impact_space("hertz,mindlin,epsd2", ""))),
    )
    .unwrap();
    let fit = [
        "--population",
        "300",
        "--generations",
        "5",
        "--select",
        "best",
    ];
    let train = |space: &'static str,
                 name: &'static str,
                 n: &'static str,
                 extra: &[&'static str]|
     -> Vec<&'static str> {
        let mut a = impact_train(space, name, n, "4");
        a.extend(fit);
        a.extend_from_slice(extra);
        a
    };
    ok(d, &train("base.toml", "base", "10", &[]));
    ok(d, &train("wide.toml", "wide", "16", &["--extends", "base"]));
    ok(
        d,
        &train("rolling.toml", "rolling", "16", &["--extends", "base"]),
    );
    let also = "training_data/wide.csv,training_data/wide_validation.csv";
    let refit = |extra: &[&'static str]| {
        let mut a = train(
            "rolling_wide.toml",
            "rolling_wide",
            "16",
            &["--extends", "rolling"],
        );
        a.extend_from_slice(extra);
        mbgc(d, &a)
    };
    // No new run and nothing else new to fit: nothing is extended.
    let o = refit(&[]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("--n 16") && e.contains("--correct"),
        "{e}"
    );
    // A table missing an input that is no effect's parameter is refused by name.
    let bad = d.join("bad.csv");
    let wide_table = std::fs::read_to_string(d.join("training_data/wide.csv")).unwrap();
    std::fs::write(&bad, wide_table.replace("impact_angle", "angle")).unwrap();
    let o = refit(&["--also-fit", "bad.csv,training_data/wide_validation.csv"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("bad.csv") && e.contains("column impact_angle"),
        "{e}"
    );
    let o = refit(&["--correct", "models/wide.json", "--correction"]);
    assert!(!o.status.success());
    // Fit settings on a train that does not fit, a group both unread and unbounded, a model of
    // another experiment, a table of another class: refused by name.
    let other = std::fs::read_to_string(d.join("models/wide.json"))
        .unwrap()
        .replace(
            "\"experiment\": \"wall-impact\"",
            "\"experiment\": \"hopper\"",
        );
    assert!(other.contains("hopper"));
    std::fs::write(d.join("hopper.json"), other).unwrap();
    for (extra, want) in [
        (
            &["--correct", "models/wide.json", "--no-fit"][..],
            "--no-fit",
        ),
        (
            &["--unread-groups", "K_p", "--unbounded-groups", "K_p"][..],
            "--unbounded-groups K_p",
        ),
        (&["--correct", "hopper.json"][..], "experiment"),
        (
            &[
                "--correct",
                "models/wide.json",
                "--also-fit",
                "training_data/rolling.csv,training_data/rolling_validation.csv",
            ][..],
            "column model_class",
        ),
    ] {
        let mut a = train("wide.toml", "wide", "16", &["--extends", "base"]);
        if want == "--no-fit" || want == "experiment" || want.starts_with("--unbounded") {
            a = train(
                "rolling_wide.toml",
                "rolling_wide",
                "16",
                &["--extends", "rolling"],
            );
        }
        a.extend_from_slice(extra);
        let o = mbgc(d, &a);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && e.contains(want), "{extra:?}: {e}");
    }
    // Groups need a similarity; the wall impact has none.
    let o = refit(&["--correct", "models/wide.json", "--unread-groups", "K_p"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("--unread-groups"), "{e}");
    // Corrected onto the narrow base, the widened runs lie where it does not hold: left out.
    let err = String::from_utf8_lossy(
        &refit(&["--correct", "models/base.json", "--also-fit", also]).stderr,
    )
    .to_string();
    assert!(
        err.contains("lie outside where models/base.json holds (")
            && err.contains("impact_angle on"),
        "{err}"
    );
    let narrow: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("models/rolling_wide.json")).unwrap())
            .unwrap();
    let domain = |m: &serde_json::Value| {
        m["inputs"]
            .as_array()
            .unwrap()
            .iter()
            .find(|i| i["name"] == "impact_angle")
            .unwrap()["domain"][1]
            .as_f64()
            .unwrap()
    };
    assert!(domain(&narrow) <= 60.0, "{narrow}");
    let err = String::from_utf8_lossy(
        &refit(&["--correct", "models/wide.json", "--also-fit", also]).stderr,
    )
    .to_string();
    assert!(err.contains("ran 0"), "{err}");
    // A row just beyond the widened base's runs (its ranges are theirs) may be left out too.
    let left_out: usize = err
        .lines()
        .find(|l| l.contains("training rows (") && l.contains("lie outside"))
        .map_or(0, |l| {
            l.split("] ")
                .nth(1)
                .unwrap()
                .split(' ')
                .next()
                .unwrap()
                .parse()
                .unwrap()
        });
    assert!(left_out <= 2, "{err}");
    let read = |p: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.join(p)).unwrap()).unwrap()
    };
    let (wide, new) = (read("models/wide.json"), read("models/rolling_wide.json"));
    for k in 0..2 {
        let (w, n) = (
            wide["responses"][k]["equation"].as_str().unwrap(),
            new["responses"][k]["equation"].as_str().unwrap(),
        );
        assert!(n.contains(w), "{n} does not hold the widened base's {w}");
    }
    // The rolling model's 16 runs (10 copied from base) and the widened base's 6 new ones: its
    // 10 copies of base are the rolling table's at mu_r_pw = 0, counted once.
    let source = new["data"]["file"].as_str().unwrap();
    assert!(source.contains("wide.csv (at mu_r_pw = 0)"), "{source}");
    let settled = |p: &str| {
        std::fs::read_to_string(d.join(p))
            .unwrap()
            .lines()
            .skip(1)
            .filter(|l| l.contains(",done,"))
            .count()
    };
    let wide_new = settled("training_data/wide.csv") - 10;
    assert_eq!(
        new["data"]["rows"].as_u64().unwrap() as usize,
        settled("training_data/rolling_wide.csv") + wide_new - left_out,
        "{source}"
    );
    // The angle's range is the widened base's, from its runs.
    let angle = new["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|i| i["name"] == "impact_angle")
        .unwrap();
    assert!(angle["domain"][1].as_f64().unwrap() > 60.0, "{angle}");
    let rec = read("training_data/rolling_wide.train.json");
    assert_eq!(rec["correct"], "models/wide.json");
    assert_eq!(rec["also_fit"][0][0], "training_data/wide.csv");
}
