//! `mbgc sensitivity` through the command line: a power law with known exponents and noise is
//! recovered inside its intervals with a passing lack-of-fit test (and a wrong shape fails it);
//! Sobol indices of a saved model have the shape the JSON promises and the inputs its equations
//! do not read get zero; the Level 3 matrix and the Level 2 PCA run on small inputs; bad input
//! is refused naming the file and the field.

mod common;
use common::{fails, ok, s};

use rand::{RngExt, SeedableRng};

/// A table y = 3 a^0.6 b^-0.4 c^0 with three replicate columns (log-normal noise, sd 0.03),
/// optionally with a shape the power law cannot follow.
fn table(dir: &std::path::Path, wrong_shape: bool) -> std::path::PathBuf {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    let mut text = String::from("a,b,c,y1,y2,y3\n");
    for a in [0.1, 0.2, 0.4, 0.8] {
        for b in [0.5, 1.0, 2.0] {
            for c in [1.0, 3.0, 9.0] {
                let mut y = 3.0 * f64::powf(a, 0.6) * f64::powf(b, -0.4);
                if wrong_shape {
                    y *= 1.0 + 2.0 * (a - 0.3f64).powi(2);
                }
                let reps: Vec<String> = (0..3)
                    .map(|_| {
                        let (u, v): (f64, f64) = (rng.random(), rng.random());
                        let z =
                            (-2.0 * (1.0 - u).ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos();
                        format!("{}", y * (0.03 * z).exp())
                    })
                    .collect();
                text.push_str(&format!("{a},{b},{c},{}\n", reps.join(",")));
            }
        }
    }
    let p = dir.join(if wrong_shape { "wrong.csv" } else { "t.csv" });
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn power_law_recovers_known_exponents_and_tests_the_fit() {
    let dir = tempfile::tempdir().unwrap();
    let t = table(dir.path(), false);
    let plots = dir.path().join("fig");
    let out = ok(&[
        "sensitivity",
        "power-law",
        "--data",
        s(&t),
        "--inputs",
        "a,b,c",
        "--target",
        "y1,y2,y3",
        "--name",
        "y",
        "--plot",
        s(&plots),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for (name, truth) in [("a", 0.6), ("b", -0.4), ("c", 0.0)] {
        let e = &v["exponents"][name];
        let value = e["value"].as_f64().unwrap();
        let lo = e["ci95"][0].as_f64().unwrap();
        let hi = e["ci95"][1].as_f64().unwrap();
        // The 95 % interval misses the truth one time in 20 by design; at 1.5 times its
        // half-width (about 3 standard errors) one time in 300.
        let half = 0.5 * (hi - lo);
        assert!(
            (value - truth).abs() <= 1.5 * half,
            "{name}: {value} [{lo}, {hi}]"
        );
        assert!(lo < value && value < hi);
        assert!(hi - lo < 0.05, "{name}: interval [{lo}, {hi}] too wide");
    }
    assert_eq!(v["observations"], 108);
    assert_eq!(v["groups"], 36);
    let lof = &v["lack_of_fit"];
    assert_eq!(lof["significant"], false, "{lof}");
    assert_eq!(lof["dof_pure_error"], 72);
    assert!(plots.join("power_law_y_parity.svg").exists());
    assert!(plots.join("power_law_y_exponents.svg").exists());

    let w = table(dir.path(), true);
    let out = ok(&[
        "sensitivity",
        "power-law",
        "--data",
        s(&w),
        "--inputs",
        "a,b,c",
        "--target",
        "y1,y2,y3",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        v["lack_of_fit"]["significant"], true,
        "{}",
        v["lack_of_fit"]
    );
}

#[test]
fn power_law_refuses_bad_input_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let t = table(dir.path(), false);
    let e = fails(&[
        "sensitivity",
        "power-law",
        "--data",
        s(&t),
        "--inputs",
        "a,zz",
        "--target",
        "y1",
    ]);
    assert!(e.contains("t.csv") && e.contains("zz"), "{e}");
    let neg = dir.path().join("neg.csv");
    std::fs::write(&neg, "a,y\n1,2\n-1,3\n2,4\n3,5\n").unwrap();
    let e = fails(&[
        "sensitivity",
        "power-law",
        "--data",
        s(&neg),
        "--inputs",
        "a",
        "--target",
        "y",
    ]);
    assert!(
        e.contains("neg.csv") && e.contains("row 2") && e.contains("input a"),
        "{e}"
    );
}

#[test]
fn sobol_indices_of_a_saved_model() {
    let out = ok(&[
        "sensitivity",
        "sobol",
        "--model",
        "models/diagnose_local.json",
        "--samples",
        "1024",
        "--seed",
        "3",
        "--bootstrap",
        "100",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("models/diagnose_local.json").unwrap())
            .unwrap();
    for r in model["responses"].as_array().unwrap() {
        let name = r["name"].as_str().unwrap();
        let uses: Vec<&str> = r["uses"]
            .as_array()
            .unwrap()
            .iter()
            .map(|u| u.as_str().unwrap())
            .collect();
        let idx = &v["responses"][name]["inputs"];
        for inp in model["inputs"].as_array().unwrap() {
            let n = inp["name"].as_str().unwrap();
            let x = &idx[n];
            let (s1, st) = (x["first"].as_f64().unwrap(), x["total"].as_f64().unwrap());
            let ci = [
                x["total_ci95"][0].as_f64().unwrap(),
                x["total_ci95"][1].as_f64().unwrap(),
            ];
            if uses.contains(&n) {
                assert!(st > 0.0 && ci[0] <= st && st <= ci[1], "{name}/{n}: {x}");
            } else {
                // An input the equation does not read moves nothing.
                assert_eq!((s1, st), (0.0, 0.0), "{name}/{n}: {x}");
            }
        }
    }
    // Same seed, same answer.
    let again = ok(&[
        "sensitivity",
        "sobol",
        "--model",
        "models/diagnose_local.json",
        "--samples",
        "1024",
        "--seed",
        "3",
        "--bootstrap",
        "100",
        "--json",
    ]);
    assert_eq!(out, again);
    let e = fails(&[
        "sensitivity",
        "sobol",
        "--model",
        "models/diagnose_local.json",
        "--responses",
        "nope",
    ]);
    assert!(e.contains("nope"), "{e}");
}

#[test]
fn matrix_pca_and_local_run_and_refuse_unknown_names() {
    let out = ok(&[
        "sensitivity",
        "matrix",
        "--at",
        "E_p=2e7,e_pp=0.45,mu_pp=0.5,mu_r_pp=0.45",
        "--set",
        "nu_p=0.3,rho_p=2500,d50=2",
        "--scaling",
        "absolute",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let p = &v["points"][0];
    assert_eq!(p["states"], 81);
    let shares = p["translational"]["shares"].as_array().unwrap();
    let sum: f64 = shares.iter().map(|x| x.as_f64().unwrap()).sum();
    assert!((sum - 1.0).abs() < 1e-9);
    // mu_r does not enter the contact force.
    assert_eq!(shares[3].as_f64().unwrap(), 0.0);
    let e = fails(&[
        "sensitivity",
        "matrix",
        "--at",
        "E_p=2e7,zeta=1",
        "--set",
        "nu_p=0.3",
    ]);
    assert!(e.contains("zeta"), "{e}");

    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("d.csv");
    let mut text = String::from("e_pp,mu_pp,mu_r_pp,angle\n");
    for (i, mu) in [0.05, 0.15, 0.25, 0.5].iter().enumerate() {
        for mr in [0.05, 0.25, 0.45] {
            for e in [0.05, 0.45, 0.85] {
                text.push_str(&format!(
                    "{e},{mu},{mr},{}\n",
                    15.0 + 30.0 * mu + 10.0 * mr + i as f64 * 0.1
                ));
            }
        }
    }
    std::fs::write(&d, text).unwrap();
    let out = ok(&[
        "sensitivity",
        "pca",
        "--data",
        s(&d),
        "--response",
        "angle",
        "--set",
        "E_p=2e7,nu_p=0.3,rho_p=2500,d50=2",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let tr = &v["translational"];
    assert_eq!(tr["rows"], 36);
    // mu_r enters no contact force: left out of the translational matrix.
    let cols: Vec<&str> = tr["columns"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap())
        .collect();
    assert_eq!(cols, ["e_pp", "mu_pp", "angle"]);
    let e = fails(&["sensitivity", "pca", "--data", s(&d), "--response", "angle"]);
    assert!(e.contains("E_p"), "{e}");

    let e = fails(&[
        "sensitivity",
        "local",
        "--model",
        "models/diagnose_local.json",
        "--at",
        "mu_pp=0.4",
    ]);
    assert!(e.contains("no value of input E_p"), "{e}");
    let out = ok(&[
        "sensitivity",
        "local",
        "--model",
        "models/diagnose_local.json",
        "--at",
        "E_p=5e6,E_w=5e6,rho_p=2600,mu_pp=0.4,d50=8",
        "--fixed",
        "E_p,E_w,rho_p",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["parameters"].as_array().unwrap().len(), 2);
    let shares = v["information_share"][0].as_array().unwrap();
    let sum: f64 = shares.iter().map(|x| x.as_f64().unwrap()).sum();
    assert!((sum - 1.0).abs() < 1e-9, "{sum}");
}

/// Nothing silently wrong: a point where the contact law is undefined, a name given twice in a
/// list (counted twice, or the last value winning), a value given by both --at and --set, and a
/// flow record that determines no curve are refused, not answered with NaN or exit 0.
#[test]
fn invalid_points_duplicates_and_flat_records_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let set = "nu_p=0.3,rho_p=2500,d50=2";
    for (at, set) in [
        ("E_p=1e308,e_pp=0.45,mu_pp=0.5,mu_r_pp=0.45", set),
        // Finite norms but infinite correlations.
        (
            "E_p=1e-300,e_pp=0.45,mu_pp=0.25,mu_r_pp=0.25",
            "nu_p=0.3,rho_p=2600,d50=2",
        ),
        (
            "E_p=2e7,e_pp=0.45,mu_pp=0.5,mu_r_pp=0.45",
            "nu_p=-1,rho_p=2500,d50=2",
        ),
        ("E_p=2e7,e_pp=0.45,mu_pp=0.5,mu_pp=0.25,mu_r_pp=0.45", set),
        (
            "E_p=2e7,e_pp=0.45,mu_pp=0.5,mu_r_pp=0.45",
            "nu_p=0.3,rho_p=2500,d50=2,mu_pp=0.3",
        ),
    ] {
        let e = fails(&["sensitivity", "matrix", "--at", at, "--set", set]);
        assert!(e.contains("--at"), "{at} / {set}: {e}");
    }
    let table = dir.path().join("t.csv");
    std::fs::write(&table, "a,y,z\n1,2,3\n2,4,5\n3,5,6\n4,7,8\n5,9,9\n").unwrap();
    let e = fails(&[
        "sensitivity",
        "power-law",
        "--data",
        s(&table),
        "--inputs",
        "a",
        "--target",
        "y,y",
    ]);
    assert!(e.contains("--target: y is given twice"), "{e}");
    let e = fails(&[
        "sensitivity",
        "sobol",
        "--model",
        "models/diagnose_local.json",
        "--samples",
        "64",
        "--responses",
        "shear_angle,shear_angle",
    ]);
    assert!(e.contains("--responses: shear_angle is given twice"), "{e}");
    // A hopper record whose rate never changes, and one that is all zero.
    let flow = dir.path().join("flow.csv");
    let mut text = String::from("row,status,flow_bin_width");
    for k in 1..=8 {
        text.push_str(&format!(",flow_rate_t{k}"));
    }
    text.push_str("\n0,done,0.15,0.04,0.04,0.04,0.04,0.04,0.04,0.04,0.04\n");
    text.push_str("1,done,0.15,0,0,0,0,0,0,0,0\n");
    std::fs::write(&flow, text).unwrap();
    let e = fails(&["sensitivity", "flow-curve", "--data", s(&flow)]);
    assert!(
        e.contains("no row's flow-rate curve could be fitted"),
        "{e}"
    );
}

/// The bootstrap count has one range, checked before the model is evaluated and stated the same
/// way whichever end is crossed.
#[test]
fn sobol_bootstrap_has_one_range() {
    let run = |b: &str| {
        common::mbgc(&[
            "sensitivity",
            "sobol",
            "--model",
            "models/diagnose_local.json",
            "--samples",
            "64",
            "--bootstrap",
            b,
            "--json",
        ])
    };
    for b in ["0", "39", "100001", "1000000000000"] {
        let o = run(b);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "--bootstrap {b}: {e}");
        assert!(
            e.contains(&format!("--bootstrap {b}: expected 40 to 100000 resamples")),
            "--bootstrap {b}: {e}"
        );
    }
    for b in ["40", "100000"] {
        let o = run(b);
        assert!(
            o.status.success(),
            "--bootstrap {b}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

/// A hopper record with flow_bin_width 0 (or below) is refused by that name, not reported as a
/// fit that did not converge.
#[test]
fn flow_curve_names_a_bad_bin_width() {
    let dir = tempfile::tempdir().unwrap();
    for width in ["0", "-0.15"] {
        let flow = dir.path().join("flow.csv");
        let mut text = String::from("row,status,flow_bin_width");
        for k in 1..=8 {
            text.push_str(&format!(",flow_rate_t{k}"));
        }
        text.push_str("\n0,done,0.15,0.04,0.04,0.039,0.035,0.02,0.008,0.002,0\n");
        text.push_str(&format!(
            "3,done,{width},0.04,0.04,0.039,0.035,0.02,0.008,0.002,0\n"
        ));
        std::fs::write(&flow, text).unwrap();
        let e = fails(&["sensitivity", "flow-curve", "--data", s(&flow)]);
        assert!(
            e.contains("row 3, column flow_bin_width")
                && e.contains("expected a positive bin width"),
            "{width}: {e}"
        );
        assert!(!e.contains("converge"), "{width}: {e}");
    }
}
