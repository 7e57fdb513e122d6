//! `mbgc propagate` end to end on the wall impact (runs of milliseconds): a posterior file ->
//! draws -> DEM runs -> bands; a repeated call runs nothing again; bad input is refused by name.

use std::path::Path;
use std::process::{Command, Output};

fn mbgc(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run mbgc")
}

const HEADER: &str = "E_p,nu_p,rho_p,d50,E_w,e_pw,mu_pw,mu_r_pw,sigma,weight,model,material\n";

/// 200 samples with e_pw from 0.3 to 0.7, equally weighted.
fn posterior() -> String {
    let mut s = HEADER.to_string();
    for i in 0..200 {
        let e = 0.3 + 0.4 * i as f64 / 199.0;
        s.push_str(&format!(
            "1e9,0.3,2600,5,1e9,{e},0.35,0.1,0.05,0.005,m.json,Test\n"
        ));
    }
    s
}

const SET: [&str; 4] = ["--set", "impact_speed=3", "--set", "impact_angle=30"];

fn propagate(dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "propagate",
        "--posterior",
        "post.csv",
        "--experiment",
        "wall-impact",
        "--out-dir",
        "run",
        "--threads",
        "1",
    ];
    args.extend(SET);
    args.extend(extra);
    mbgc(dir, &args)
}

#[test]
fn draws_run_and_the_band_follows_the_posterior() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("post.csv"), posterior()).unwrap();
    std::fs::write(
        d.join("best.toml"),
        "[parameters]\nE_p = 1e9\nnu_p = 0.3\nrho_p = 2600\nd50 = 5\nE_w = 1e9\ne_pw = 0.5\n\
         mu_pw = 0.35\nmu_r_pw = 0.1\n",
    )
    .unwrap();
    let extra = [
        "--draws",
        "40",
        "--seeds",
        "2",
        "--params",
        "best.toml",
        "--json",
    ];
    let o = propagate(d, &extra);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (v["draws"].as_u64(), v["seeds"].as_u64()),
        (Some(40), Some(2))
    );
    let cnr = &v["bands"][0];
    assert_eq!(cnr["response"], "cnr");
    let band = &cnr["band"];
    assert_eq!(band["runs"], 80);
    // The normal restitution of a wall impact is e_pw: the band is the drawn e_pw's, whose
    // systematic draws from an even grid on [0.3, 0.7] have mean 0.5 and sd 0.4 / sqrt 12.
    let mean = band["mean"].as_f64().unwrap();
    let sd = band["sd"].as_f64().unwrap();
    assert!((mean - 0.5).abs() < 0.01, "{band}");
    assert!((sd - 0.4 / 12f64.sqrt()).abs() < 0.01, "{band}");
    assert!(band["q05"].as_f64().unwrap() < mean && mean < band["q95"].as_f64().unwrap());
    // One engine, one seed or another: a wall impact has no run scatter.
    assert!(band["scatter_sd"].as_f64().unwrap() < 1e-9, "{band}");
    assert!(
        (cnr["best_fit"].as_f64().unwrap() - 0.5).abs() < 0.01,
        "{cnr}"
    );
    // Again: nothing runs twice and the bands are the same.
    let table = std::fs::read_to_string(d.join("run/runs.csv")).unwrap();
    let o = propagate(d, &extra);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap(),
        v
    );
    assert_eq!(
        std::fs::read_to_string(d.join("run/runs.csv")).unwrap(),
        table
    );
    // The cheap path: a metamodel of cnr fitted to these runs gives the same band, and with its
    // own error a band at least as wide.
    let o = mbgc(
        d,
        &[
            "fit",
            "--data",
            "run/runs.csv",
            "--inputs",
            "e_pw",
            "--targets",
            "cnr",
            "--out",
            "cnr.json",
            "--population",
            "200",
            "--generations",
            "5",
            "--no-figures",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut with_model = extra.to_vec();
    with_model.extend(["--metamodel", "cnr.json", "--plot", "figs"]);
    let o = propagate(d, &with_model);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        m["bands"], v["bands"],
        "the DEM band is unchanged (nothing reran)"
    );
    let svg = std::fs::read_to_string(d.join("figs/cnr.svg")).unwrap();
    assert!(svg.contains("metamodel, same draws") && svg.contains("best-fit point"));
    let cheap = &m["metamodel"][0];
    assert_eq!(cheap["response"], "cnr");
    assert!(
        (cheap["mean"].as_f64().unwrap() - mean).abs() < 0.01,
        "{cheap}"
    );
    assert!((cheap["sd"].as_f64().unwrap() - sd).abs() < 0.01, "{cheap}");
    // (The error here is 1e-4; the band with it is over 200 error samples per draw, whose sd
    // divides by n - 1 of 8000 rather than of 40.)
    let with_error = cheap["with_error"]["sd"].as_f64().unwrap();
    assert!(
        with_error >= 0.98 * cheap["sd"].as_f64().unwrap(),
        "{cheap}"
    );
    // A model whose domain ends inside the draws (as a hopper model's does where its runs
    // clogged) refuses the band, or with --metamodel-outside skip leaves those draws out and
    // lists them.
    let mut narrow: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("cnr.json")).unwrap()).unwrap();
    let input = narrow["inputs"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|i| i["name"] == "e_pw")
        .unwrap();
    input["domain"][1] = serde_json::json!(0.6);
    std::fs::write(d.join("narrow.json"), narrow.to_string()).unwrap();
    let mut refused = extra.to_vec();
    refused.extend(["--metamodel", "narrow.json"]);
    let o = propagate(d, &refused);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("outside the model's domain") && e.contains("skip"),
        "{e}"
    );
    let mut skipped = refused.clone();
    skipped.extend(["--metamodel-outside", "skip", "--report", "skip.md"]);
    let o = propagate(d, &skipped);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let cheap = &m["metamodel"][0];
    let out = cheap["outside"].as_array().unwrap().len();
    // The draws spread e_pw evenly over [0.3, 0.7]: a quarter lie above 0.6.
    assert!((8..=12).contains(&out), "{cheap}");
    // The band is of the draws inside: their cnr (= e_pw) averages about 0.45.
    assert!(
        (cheap["mean"].as_f64().unwrap() - 0.45).abs() < 0.02,
        "{cheap}"
    );
    let report = std::fs::read_to_string(d.join("skip.md")).unwrap();
    assert!(
        report.contains(&format!(
            "{out} of 40 draws lie outside the metamodel's domain"
        )),
        "{report}"
    );
    // A model whose input the draws do not hold is refused before anything runs.
    std::fs::write(
        d.join("other.json"),
        std::fs::read_to_string(d.join("cnr.json"))
            .unwrap()
            .replace("\"e_pw\"", "\"e_pp\""),
    )
    .unwrap();
    let mut other = extra.to_vec();
    other.extend(["--metamodel", "other.json"]);
    let o = propagate(d, &other);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("its input e_pp"), "{e}");
    // Other draws into the same directory are refused: its runs belong to the first design.
    let o = propagate(d, &["--draws", "41"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("design of another propagation"),
        "{e}"
    );
}

#[test]
fn bad_input_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let nan = posterior().replacen(",0.005,m.json", ",NaN,m.json", 1);
    let pp = posterior().replace("mu_r_pw,sigma", "mu_pp,sigma");
    let cases: [(&str, String, Vec<&str>, &str); 6] = [
        ("NaN weight", nan, vec![], "line 2, column weight"),
        ("no draws", posterior(), vec!["--draws", "0"], "--draws 0"),
        (
            "too many draws",
            posterior(),
            vec!["--draws", "1000000"],
            "--draws 1000000",
        ),
        (
            "a parameter the experiment lacks",
            pp,
            vec![],
            "posterior column mu_pp",
        ),
        (
            "missing columns",
            "mu_pw,weight\n0.3,1\n".into(),
            vec![],
            "then sigma,weight,model,material",
        ),
        (
            "an unknown quantity",
            posterior(),
            vec!["--responses", "flow_rate"],
            "--responses flow_rate",
        ),
    ];
    for (what, text, extra, want) in cases {
        std::fs::write(d.join("post.csv"), text).unwrap();
        let o = propagate(d, &extra);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && e.contains(want), "{what}: {e}");
    }
    // Without the constants the experiment needs.
    std::fs::write(d.join("post.csv"), posterior()).unwrap();
    let o = mbgc(
        d,
        &[
            "propagate",
            "--posterior",
            "post.csv",
            "--experiment",
            "wall-impact",
            "--out-dir",
            "run",
        ],
    );
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("impact_speed, impact_angle"),
        "{e}"
    );
    assert!(
        !d.join("run").exists(),
        "nothing is written before the input is checked"
    );
    // A constant no experiment reads fails the plan; the design it left is no lock on the
    // directory, since nothing ran.
    let o = propagate(d, &["--draws", "3", "--set", "foo=1"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("foo"), "{e}");
    let o = propagate(d, &["--draws", "4"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The report never replaces the propagation's own table.
    let o = propagate(d, &["--draws", "4", "--report", "run/runs.csv"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("--report"), "{e}");
    assert!(std::fs::read_to_string(d.join("run/runs.csv"))
        .unwrap()
        .starts_with("run_id,"));
    // A best-fit file with a value the propagation would not use.
    std::fs::write(
        d.join("best.toml"),
        "[parameters]\nE_p = 1e9\nnu_p = 0.3\nrho_p = 2600\nd50 = 5\nE_w = 1e9\ne_pw = 0.5\n\
         mu_pw = 0.35\nmu_r_pw = 0.1\nimpact_speed = 9\n",
    )
    .unwrap();
    let o = propagate(d, &["--draws", "4", "--params", "best.toml"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && e.contains("[parameters] impact_speed = 9")
            && e.contains("--set gives 3"),
        "{e}"
    );
}
