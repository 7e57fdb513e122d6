//! The `sample` and `metrics` commands end to end, and every bad-input path naming the file and
//! the field.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn mbgc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run mbgc")
}

fn ok(args: &[&str]) -> String {
    let o = mbgc(args);
    assert!(
        o.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

/// Runs a command that must fail and returns its error message.
fn fails(args: &[&str]) -> String {
    let o = mbgc(args);
    assert!(!o.status.success(), "{args:?} should fail");
    let e = String::from_utf8(o.stderr).unwrap();
    assert!(!e.contains("panicked"), "{e}");
    e
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn last_json(stdout: &str) -> serde_json::Value {
    serde_json::from_str(stdout.lines().last().unwrap()).unwrap()
}

const SPACE: &str = "examples/space_seed004.toml";

#[test]
fn sample_with_space_writes_physical_values_and_metrics_reads_them_back() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d.csv");
    ok(&[
        "sample",
        "--method",
        "fssf-f",
        "--n",
        "30",
        "--space",
        SPACE,
        "--seed",
        "2",
        "--out",
        s(&out),
    ]);
    let text = std::fs::read_to_string(&out).unwrap();
    let header = text.lines().next().unwrap();
    assert_eq!(
        header,
        "E_p,E_w,nu_p,e_pp,e_pw,mu_pp,mu_pw,mu_r_pp,mu_r_pw,rho_p,d50,sigma_ln"
    );
    assert_eq!(text.lines().count(), 31);
    // Physical units: rho_p within its bounds and far outside [0, 1].
    let rho: Vec<f64> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(9).unwrap().parse().unwrap())
        .collect();
    assert!(rho.iter().all(|r| (250.0..=3000.0).contains(r)) && rho.iter().any(|r| *r > 1.0));
    let m = last_json(&ok(&["metrics", s(&out), "--space", SPACE, "--json"]));
    assert_eq!(m["n"], 30);
    assert_eq!(m["dim"], 12);
    for k in ["mid", "cov", "cd", "wd"] {
        assert!(m[k].as_f64().unwrap() > 0.0, "{k}");
    }
    // Without the space the physical values are refused, naming file, line and column.
    let e = fails(&["metrics", s(&out)]);
    assert!(
        e.contains("d.csv") && e.contains("column E_p") && e.contains("[0, 1]"),
        "{e}"
    );
}

#[test]
fn metrics_match_the_reference_constants_through_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let rows = [[1., 3.], [2., 6.], [3., 2.], [4., 5.], [5., 1.], [6., 4.]];
    let mut csv = String::from("x0,x1\n");
    for r in rows {
        csv += &format!(
            "{},{}\n",
            (r[0] * 2.0 - 1.0) / 12.0,
            (r[1] * 2.0 - 1.0) / 12.0
        );
    }
    let p = write(dir.path(), "space_1.csv", &csv);
    let m = last_json(&ok(&["metrics", s(&p), "--json"]));
    assert!((m["cd"].as_f64().unwrap() - 0.008142039609053464).abs() < 1e-12);
    assert!((m["wd"].as_f64().unwrap() - 0.01684670781892894).abs() < 1e-12);
    assert!((m["mid"].as_f64().unwrap() - 0.3726779962499649).abs() < 1e-12);
}

#[test]
fn extend_keeps_old_points_first_and_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let old = dir.path().join("old.csv");
    let new = dir.path().join("new.csv");
    ok(&[
        "sample",
        "--method",
        "lhs-maximin",
        "--n",
        "20",
        "--space",
        SPACE,
        "--seed",
        "5",
        "--out",
        s(&old),
    ]);
    ok(&[
        "sample",
        "--method",
        "fssf-f",
        "--add",
        "10",
        "--space",
        SPACE,
        "--seed",
        "1",
        "--extend",
        s(&old),
        "--out",
        s(&new),
    ]);
    let parse = |p: &Path| -> Vec<Vec<f64>> {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect()
    };
    let (a, b) = (parse(&old), parse(&new));
    assert_eq!(b.len(), 30);
    assert_eq!(&b[..20], &a[..], "old rows must stay first and unchanged");
    // Bare unit-cube designs extend too, and LHS refuses.
    let bare = dir.path().join("bare.csv");
    ok(&[
        "sample",
        "--method",
        "sobol",
        "--n",
        "8",
        "--dim",
        "3",
        "--out",
        s(&bare),
    ]);
    ok(&[
        "sample",
        "--method",
        "halton",
        "--add",
        "8",
        "--dim",
        "3",
        "--extend",
        s(&bare),
        "--out",
        s(&bare),
    ]);
    assert_eq!(std::fs::read_to_string(&bare).unwrap().lines().count(), 17);
    let e = fails(&[
        "sample",
        "--method",
        "lhs",
        "--add",
        "8",
        "--dim",
        "3",
        "--extend",
        s(&bare),
        "--out",
        s(&new),
    ]);
    assert!(e.contains("one-shot"), "{e}");
    let e = fails(&[
        "sample",
        "--method",
        "fssf-f",
        "--add",
        "8",
        "--dim",
        "4",
        "--extend",
        s(&bare),
        "--out",
        s(&new),
    ]);
    assert!(e.contains("bare.csv") && e.contains("--dim"), "{e}");
}

#[test]
fn bad_space_files_are_refused_naming_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("[parameters]\nmu = { min = 0.0 }\n", "parameters.mu.max"),
        (
            "[parameters]\nmu = { min = 1.0, max = 0.5 }\n",
            "parameters.mu.min",
        ),
        (
            "[parameters]\nE = { min = 0.0, max = 5e8, scale = \"log\" }\n",
            "parameters.E.min",
        ),
        (
            "[parameters]\nmu = { min = 0.0, max = 1.0, maxi = 2 }\n",
            "parameters.mu.maxi",
        ),
        (
            "[parameters]\nmu = { min = 0.0, max = 1.0, fixed = 1.5 }\n",
            "parameters.mu.fixed",
        ),
        (
            "[parameters]\nmu = { min = 0.0, max = \"one\" }\n",
            "parameters.mu.max",
        ),
        (
            "[parameters]\nmu = { min = 0.0, max = nan }\n",
            "parameters.mu.max",
        ),
        ("[parameters]\n", "parameters"),
        ("[parameters\nmu = 1\n", "TOML"),
    ];
    for (i, (text, field)) in cases.iter().enumerate() {
        let name = format!("space{i}.toml");
        let p = write(dir.path(), &name, text);
        let e = fails(&[
            "sample",
            "--method",
            "random",
            "--n",
            "3",
            "--space",
            s(&p),
            "--out",
            s(&dir.path().join("o.csv")),
        ]);
        assert!(e.contains(&name) && e.contains(field), "case {i}: {e}");
    }
    let e = fails(&[
        "sample",
        "--method",
        "random",
        "--n",
        "3",
        "--space",
        "nope.toml",
        "--out",
        "o.csv",
    ]);
    assert!(e.contains("nope.toml"), "{e}");
}

#[test]
fn bad_design_files_are_refused_naming_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let space = write(dir.path(), "sp.toml", "[parameters]\na = { min = 0, max = 10 }\nb = { min = 1, max = 100, scale = \"log\" }\nc = { min = 0, max = 1, fixed = 0.5 }\n");
    let sp = s(&space);
    let cases = [
        ("a\n1\n", "column b", "missing"),
        ("a,b\n1,2\n3,NaN\n", "column b", "finite"),
        ("a,b\n1,2\n3,abc\n", "column b", "number"),
        ("a,b\n1,2\n11,2\n", "column a", "bounds"),
        ("a,b,c\n1,2,0.7\n", "column c", "fixes"),
        ("a,b\n1,2\n3\n", "line 3", "fields"),
        ("a,a\n1,2\n", "column a", "twice"),
    ];
    for (i, (text, field, what)) in cases.iter().enumerate() {
        let name = format!("design{i}.csv");
        let p = write(dir.path(), &name, text);
        let e = fails(&["metrics", s(&p), "--space", sp]);
        assert!(
            e.contains(&name) && e.contains(field) && e.contains(what),
            "case {i}: {e}"
        );
    }
    // A fixed column may be absent; values in bounds are accepted.
    let good = write(dir.path(), "good.csv", "b,a\n2,1\n50,9\n");
    ok(&["metrics", s(&good), "--space", sp]);
    // A bare design must hold unit-cube values.
    let bare = write(dir.path(), "bare.csv", "x0,x1\n0.1,0.2\n0.3,1.2\n");
    let e = fails(&["metrics", s(&bare)]);
    assert!(
        e.contains("bare.csv") && e.contains("line 3, column x1"),
        "{e}"
    );
    let one = write(dir.path(), "one.csv", "x0\n0.5\n");
    let e = fails(&["metrics", s(&one)]);
    assert!(e.contains("one.csv") && e.contains("at least 2"), "{e}");
}

#[test]
fn dem_bench_prints_the_json_fields() {
    let out = ok(&[
        "bench",
        "dem",
        "--particles",
        "300",
        "--settle",
        "200",
        "--steps",
        "100",
        "--threads",
        "2",
        "--json",
    ]);
    let j = last_json(&out);
    for k in [
        "mbgc_particle_steps_per_s",
        "liggghts_particle_steps_per_s",
        "ratio",
        "threads",
        "packing_fraction_mbgc",
        "packing_fraction_liggghts",
        "coordination_mbgc",
        "coordination_liggghts",
        "thread_speedup",
    ] {
        assert!(j.get(k).is_some(), "missing {k}");
    }
    assert!(j["mbgc_particle_steps_per_s"].as_f64().unwrap() > 0.0);
    assert_eq!(j["threads"], 2);
    let e = fails(&["bench", "dem", "--particles", "0"]);
    assert!(e.contains("--particles"), "{e}");
}

/// `--n` means a design's size everywhere (as in `train`); the points an extension adds are
/// `--add`, and `--n` beside `--extend` is refused instead of being read as new points.
#[test]
fn n_is_a_size_and_add_extends() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("d.csv");
    let ds = d.to_str().unwrap();
    ok(&[
        "sample", "--method", "sobol", "--dim", "2", "--n", "8", "--out", ds,
    ]);
    let e = fails(&[
        "sample", "--method", "sobol", "--dim", "2", "--n", "12", "--extend", ds, "--out", ds,
    ]);
    assert!(e.contains("--add"), "{e}");
    ok(&[
        "sample", "--method", "sobol", "--dim", "2", "--add", "4", "--extend", ds, "--out", ds,
    ]);
    assert_eq!(std::fs::read_to_string(&d).unwrap().lines().count(), 1 + 12);
}
