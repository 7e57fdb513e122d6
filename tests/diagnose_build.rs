//! `mbgc diagnose --build` on the wall impact (milliseconds a run): a sphere's rebound measured at
//! five speeds, made by DEM with a wall cohesion the set's class lacks. No model describes the
//! wall impact, so the diagnosis builds a local model of the cohesive class around the material
//! (the runs of the class without it first, on its ced = 0 face), names the cohesion, recovers
//! its strength, and a second call reuses every run.

use std::path::Path;
use std::process::{Command, Output};

fn mbgc(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run mbgc")
}

fn ok(dir: &Path, args: &[&str]) -> (String, String) {
    let o = mbgc(dir, args);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{args:?} failed: {err}");
    (String::from_utf8(o.stdout).unwrap(), err)
}

const HIDDEN_CED: f64 = 3e4;

/// `diagnose --build sjkr` on the set at `budget` runs, one thread, JSON, a quick TMCMC.
fn build_args(budget: &str) -> Vec<&str> {
    vec![
        "diagnose",
        "--measurements",
        "set.toml",
        "--build",
        "sjkr",
        "--budget-runs",
        budget,
        "--threads",
        "1",
        "--json",
        "--samples",
        "500",
        "--starts",
        "4",
    ]
}
const SPEEDS: [f64; 5] = [0.05, 0.1, 0.2, 0.4, 0.6];

/// The measurement set, made by DEM runs with the hidden cohesion (sd 0.01 on both
/// coefficients of restitution, no noise added: the DEM is deterministic).
fn measurement_set(d: &Path) {
    let mut design =
        String::from("E_p,nu_p,rho_p,d50,E_w,impact_speed,impact_angle,e_pw,mu_pw,ced_pw\n");
    for v in SPEEDS {
        design.push_str(&format!("5e6,0.3,2600,4,5e6,{v},30,0.7,0.3,{HIDDEN_CED}\n"));
    }
    std::fs::write(d.join("truth.csv"), design).unwrap();
    ok(
        d,
        &[
            "simulate",
            "--design",
            "truth.csv",
            "--experiment",
            "wall-impact",
            "--model-class",
            "hertz,mindlin,sjkr",
            "--out",
            "truth_runs.csv",
            "--threads",
            "1",
        ],
    );
    let mut r = csv::Reader::from_path(d.join("truth_runs.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let mut set = String::from(
        "name = \"bead on a plate\"\n[model]\nclass = \"hertz,mindlin\"\n[fixed]\nE_p = 5e6\n\
         nu_p = 0.3\nrho_p = 2600\nd50 = 4\nE_w = 5e6\nimpact_angle = 30\nmu_pw = 0.3\n\
         [bounds]\ne_pw = [0.4, 0.9]\n[candidates.sjkr]\nbounds = { ced_pw = [0, 6e4] }\n",
    );
    for rec in r.records() {
        let rec = rec.unwrap();
        let v = &rec[col("impact_speed")];
        set.push_str(&format!(
            "[[sample]]\nname = \"{v} m/s\"\nexperiment = \"wall-impact\"\n\
             fixed = {{ impact_speed = {v} }}\nmeasured.cnr = {{ value = {}, sd = 0.01 }}\n\
             measured.ctr = {{ value = {}, sd = 0.01 }}\n",
            &rec[col("cnr")],
            &rec[col("ctr")]
        ));
    }
    std::fs::write(d.join("set.toml"), set).unwrap();
}

#[test]
fn a_diagnosis_builds_the_local_model_it_lacks_and_names_the_hidden_effect() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    measurement_set(d);
    if let Ok(keep) = std::env::var("KEEP_BUILD_TEST") {
        std::fs::copy(d.join("set.toml"), keep).unwrap();
    }
    let quick = ["--samples", "500", "--starts", "4"];
    // Without --build: no model describes the wall impact; the error offers the build.
    let o = mbgc(
        d,
        &[&["diagnose", "--measurements", "set.toml"][..], &quick].concat(),
    );
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("no model describes") && e.contains("--build"),
        "{e}"
    );
    // The build's settings need --build.
    let o = mbgc(
        d,
        &[
            "diagnose",
            "--measurements",
            "set.toml",
            "--budget-runs",
            "40",
        ],
    );
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("--budget-runs"), "{e}");
    let args = build_args("60");
    let (out, err) = ok(d, &args);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    // 60 runs, 30 a round: 6 validation, 2 replicates and 22 training runs, of which 5 (and 1
    // validation) without cohesion.
    assert!(err.contains("ran 5 (5 done"), "{err}");
    assert!(err.contains("copied 5 runs"), "{err}");
    assert!(err.contains("ran 2 (2 done"), "{err}");
    let built = &j["built"][0];
    assert_eq!(built["class"], "hertz,mindlin,sjkr", "{built}");
    let model = d.join(built["model"].as_str().unwrap());
    assert!(model.exists());
    // The verdict names the cohesion, the error falls, the strength brackets the truth.
    assert_eq!(j["ranking"][0]["effect"], "sjkr", "{}", j["verdict"]);
    let v = j["verdict"].as_str().unwrap();
    assert!(v.starts_with("sjkr explains it"), "{v}");
    let before = j["chi2_dof"].as_f64().unwrap();
    let after = j["ranking"][0]["chi2_dof_after"].as_f64().unwrap();
    assert!(
        before > 3.0 && after < 1.5 && before / after > 5.0,
        "{before} -> {after}"
    );
    let s = &j["ranking"][0]["strength"][0];
    assert_eq!(s["name"], "ced_pw");
    let (lo, hi) = (s["q05"].as_f64().unwrap(), s["q95"].as_f64().unwrap());
    assert!(
        lo < HIDDEN_CED && HIDDEN_CED < hi && hi / lo < 3.0,
        "[{lo}, {hi}]"
    );
    // A second call runs nothing: every run is in the tables.
    let (out2, err2) = ok(d, &args);
    assert!(!err2.contains("new)"), "{err2}");
    assert!(
        !err2
            .lines()
            .any(|l| l.contains(" ran ") && !l.contains(" ran 0 ")),
        "{err2}"
    );
    let j2: serde_json::Value = serde_json::from_str(&out2).unwrap();
    assert_eq!(j2["verdict"], j["verdict"]);
}

/// A budget large enough for a second round near the material: the first model (over the
/// whole search range) is less precise than the measurements, so the rest of the budget is run
/// in a box around its fits, with the first round's runs inside the box fitted again, and the
/// diagnosis then searches that box.
#[test]
fn a_second_round_is_built_near_the_material_with_the_first_rounds_runs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    measurement_set(d);
    let args = build_args("150");
    let (out, err) = ok(d, &args);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let built = &j["built"][0];
    let first = &built["first_round"];
    assert!(first.is_object(), "{built}");
    // The first model misses by more than the sd, the second by less in cnr.
    let rmse = |p: &serde_json::Value, k: usize| p["precision"][k]["model_error"].as_f64().unwrap();
    assert!(rmse(first, 0) > 0.01 && rmse(built, 0) < 0.01, "{built}");
    // The box is narrower than the first range in e_pw and keeps ced_pw = 0.
    let focus = built["focus"].as_array().unwrap();
    let e = focus.iter().find(|f| f[0] == "e_pw").unwrap();
    let (lo, hi) = (e[1][0].as_f64().unwrap(), e[1][1].as_f64().unwrap());
    assert!(lo > 0.4 && hi < 0.9 && hi - lo < 0.4, "{focus:?}");
    let c = focus.iter().find(|f| f[0] == "ced_pw").unwrap();
    assert_eq!(c[1][0].as_f64().unwrap(), 0.0, "{focus:?}");
    assert!(
        err.contains("rows of"),
        "the first round's runs are fitted again: {err}"
    );
    assert!(
        err.contains("the search ranges are those the second round"),
        "{err}"
    );
    let v = j["verdict"].as_str().unwrap();
    assert!(v.starts_with("sjkr explains it"), "{v}");
    let s = &j["ranking"][0]["strength"][0];
    let (lo, hi) = (s["q05"].as_f64().unwrap(), s["q95"].as_f64().unwrap());
    assert!(lo < HIDDEN_CED && HIDDEN_CED < hi, "[{lo}, {hi}]");
    // A second call runs nothing new and keeps the box.
    let (out2, err2) = ok(d, &args);
    assert!(
        !err2
            .lines()
            .any(|l| l.contains(" ran ") && !l.contains(" ran 0 ")),
        "{err2}"
    );
    let j2: serde_json::Value = serde_json::from_str(&out2).unwrap();
    assert_eq!(j2["built"][0]["focus"], built["focus"]);
    assert_eq!(j2["verdict"], j["verdict"]);
}

/// A global model that covers the material but is less precise than the measurements: the
/// diagnosis with it cannot decide, says the models limit it, and `--build sjkr` builds a local
/// cohesive model that replaces it (for both classes), which names the hidden cohesion.
#[test]
fn a_diagnosis_sharpens_a_covering_model_less_precise_than_its_measurements() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    measurement_set(d);
    // The coarse model: 24 runs over a wide box, a two-generation GP.
    std::fs::write(
        d.join("space.toml"),
        "name = \"coarse impact\"\n[model]\nclass = \"hertz,mindlin,sjkr\"\n[parameters]\n\
         E_p = { min = 1e6, max = 1e8, fixed = 5e6 }\n\
         nu_p = { min = 0.1, max = 0.5, fixed = 0.3 }\n\
         rho_p = { min = 1000, max = 3000, fixed = 2600 }\n\
         d50 = { min = 1, max = 10, fixed = 4 }\n\
         E_w = { min = 1e6, max = 1e8, fixed = 5e6 }\n\
         impact_speed = { min = 0.04, max = 0.7 }\n\
         impact_angle = { min = 10, max = 60, fixed = 30 }\n\
         e_pw = { min = 0.35, max = 0.95 }\n\
         mu_pw = { min = 0.1, max = 0.5, fixed = 0.3 }\n\
         ced_pw = { min = 0, max = 6e4 }\n",
    )
    .unwrap();
    ok(
        d,
        &[
            "train",
            "--space",
            "space.toml",
            "--experiment",
            "wall-impact",
            "--name",
            "coarse",
            "--n",
            "24",
            "--validation",
            "8",
            "--threads",
            "1",
            "--population",
            "40",
            "--generations",
            "2",
            "--restarts",
            "1",
        ],
    );
    let coarse = "models/coarse.json";
    assert!(d.join(coarse).exists());
    let quick = ["--samples", "500", "--starts", "4", "--json"];
    let (out, _) = ok(
        d,
        &[
            &["diagnose", "--measurements", "set.toml", "--model", coarse][..],
            &quick,
        ]
        .concat(),
    );
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let v = j["verdict"].as_str().unwrap();
    assert!(
        v.contains("limit this verdict") && v.contains("--build sjkr"),
        "the premise: the coarse model limits the diagnosis: {v}"
    );
    let mut args = build_args("60");
    args.extend(["--model", coarse]);
    let (out, err) = ok(d, &args);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(
        err.contains("their own error exceeds the measurements' sd")
            && err.contains("replaces the 1 given model(s) of wall-impact"),
        "{err}"
    );
    let built = &j["built"][0];
    assert_eq!(built["class"], "hertz,mindlin,sjkr", "{built}");
    assert!(
        built["reason"]
            .as_str()
            .unwrap()
            .starts_with("the given models cover it"),
        "{built}"
    );
    let v = j["verdict"].as_str().unwrap();
    assert!(v.starts_with("sjkr explains it"), "{v}");
    let s = &j["ranking"][0]["strength"][0];
    let (lo, hi) = (s["q05"].as_f64().unwrap(), s["q95"].as_f64().unwrap());
    assert!(lo < HIDDEN_CED && HIDDEN_CED < hi, "[{lo}, {hi}]");
}
