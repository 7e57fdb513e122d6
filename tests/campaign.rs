//! Campaigns end to end through the binary: `simulate` with wall-impact, kill and resume, shards
//! merged against a full run, failures, status, and every bad input naming the file and field.
//! The stand-in experiment `sleep-test` (tests/stand_ins/, compiled only into test builds by the
//! `stand-ins` feature that the dev-dependency on the package itself switches on) makes runs
//! slow, failing or panicking on request; it reports a nominal wall time, so its tables are
//! reproducible to the byte.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn command(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_mbgc"));
    c.args(args);
    c
}

fn mbgc(args: &[&str]) -> Output {
    command(args).output().expect("run mbgc")
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

fn arg_refs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

/// Header and records of a table (an incomplete last line, if any, as a short record).
fn read(path: &Path) -> (Vec<String>, Vec<HashMap<String, String>>) {
    let mut rdr = csv::ReaderBuilder::new()
        .flexible(true)
        .from_path(path)
        .unwrap();
    let header: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
    let rows = rdr
        .records()
        .filter_map(|r| r.ok())
        .map(|r| {
            header
                .iter()
                .cloned()
                .zip(r.iter().map(String::from))
                .collect()
        })
        .collect();
    (header, rows)
}

/// Every field but the measured wall time, sorted by row.
fn without_wall_time(path: &Path) -> Vec<Vec<(String, String)>> {
    let (header, rows) = read(path);
    let mut out: Vec<Vec<(String, String)>> = rows
        .iter()
        .map(|r| {
            header
                .iter()
                .filter(|h| *h != "wall_time_s")
                .map(|h| (h.clone(), r[h].clone()))
                .collect()
        })
        .collect();
    out.sort_by_key(|r| r[1].1.parse::<usize>().unwrap());
    out
}

/// Wall-impact constants (the ones the designs below do not vary).
/// Hertz-Mindlin without rolling resistance (a sphere against a wall), and its constants.
const WALL_SET: [&str; 12] = [
    "--model-class",
    "hertz,mindlin",
    "--set",
    "E_p=380e9",
    "--set",
    "nu_p=0.23",
    "--set",
    "E_w=1e13",
    "--set",
    "e_pw=0.98",
    "--set",
    "impact_speed=3.9",
];

/// 12 rows varying impact_angle and mu_pw; rho_p and d50 as constant design columns.
fn wall_design(dir: &Path) -> PathBuf {
    let mut t = String::from("impact_angle,mu_pw,rho_p,d50\n");
    for i in 0..12 {
        t += &format!("{},{},4000,5\n", 10 + 6 * i, 0.05 + 0.03 * i as f64);
    }
    write(dir, "wall.csv", &t)
}

fn simulate_wall(design: &Path, out: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "simulate",
        "--design",
        s(design),
        "--experiment",
        "wall-impact",
        "--out",
        s(out),
    ];
    args.extend(WALL_SET);
    args.extend(extra);
    ok(&args)
}

/// `n` sleep-test rows: x = i, y = i / 2; row `fail_row` fails, x < 0 on row 2 (a warning).
fn sleep_design(dir: &Path, name: &str, n: usize, fail_row: Option<usize>) -> PathBuf {
    let mut t = String::from("x,y,fail\n");
    for i in 0..n {
        let x = if i == 2 { -1.0 } else { i as f64 };
        let fail = u8::from(Some(i) == fail_row);
        t += &format!("{x},{},{fail}\n", i as f64 / 2.0);
    }
    write(dir, name, &t)
}

/// Runs sleep-test rows and returns standard output. A campaign with failed runs must exit 1
/// and say so (a job array has to see it); the tests that care check the counts.
fn simulate_sleep(design: &Path, out: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "simulate",
        "--design",
        s(design),
        "--experiment",
        "sleep-test",
        "--out",
        s(out),
    ];
    args.extend(extra);
    let o = mbgc(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    if !o.status.success() {
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains("rerun with --retry-failed"), "{args:?}: {err}");
    }
    String::from_utf8(o.stdout).unwrap()
}

fn merge(inputs: &[&Path], out: &Path) -> Vec<u8> {
    let mut args = vec!["campaign", "merge"];
    args.extend(inputs.iter().map(|p| s(p)));
    args.extend(["--out", s(out)]);
    ok(&args);
    std::fs::read(out).unwrap()
}

#[test]
fn wall_impact_runs_every_row_of_a_design_and_resumes_to_a_no_op() {
    let dir = tempfile::tempdir().unwrap();
    let design = wall_design(dir.path());
    let out = dir.path().join("training_data/run.csv");
    let stdout = simulate_wall(&design, &out, &["--threads", "2"]);
    assert!(stdout.contains("ran 12 (12 done, 0 failed)"), "{stdout}");

    let (header, rows) = read(&out);
    assert_eq!(
        header.join(","),
        "run_id,row,status,seed,model_class,impact_angle,mu_pw,rho_p,d50,E_p,nu_p,E_w,e_pw,impact_speed,\
         cnr,ctr,settled,steps,particles,wall_time_s,warnings,error"
    );
    assert_eq!(rows.len(), 12);
    let mut seen: Vec<usize> = rows.iter().map(|r| r["row"].parse().unwrap()).collect();
    seen.sort();
    assert_eq!(seen, (0..12).collect::<Vec<_>>());
    for r in &rows {
        assert_eq!(r["status"], "done");
        assert_eq!(r["run_id"].len(), 16);
        let cnr: f64 = r["cnr"].parse().unwrap();
        let ctr: f64 = r["ctr"].parse().unwrap();
        assert!(cnr.is_finite() && ctr.is_finite(), "{r:?}");
        assert!((cnr - 0.98).abs() < 0.01, "{r:?}");
        assert!(ctr > 0.0 && ctr < 1.0, "{r:?}");
        assert_eq!(r["error"], "");
    }

    let status = last_json(&ok(&["campaign", "status", s(&out), "--json"]));
    assert_eq!(status["done"], 12);
    assert_eq!(status["failed"], 0);
    assert_eq!(status["remaining"], 0);
    assert_eq!(status["total"], 12);

    let before = std::fs::read(&out).unwrap();
    let stdout = simulate_wall(&design, &out, &["--threads", "2"]);
    assert!(
        stdout.contains("12 already in the table, ran 0"),
        "{stdout}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), before);
}

#[test]
fn same_design_and_seed_give_identical_results_whatever_the_threads() {
    let dir = tempfile::tempdir().unwrap();
    let design = wall_design(dir.path());
    let (a, b, c) = (
        dir.path().join("a.csv"),
        dir.path().join("b.csv"),
        dir.path().join("c.csv"),
    );
    simulate_wall(&design, &a, &["--threads", "1"]);
    simulate_wall(&design, &b, &["--threads", "2"]);
    assert_eq!(without_wall_time(&a), without_wall_time(&b));

    // Another campaign seed changes seeds and run ids (wall-impact itself ignores the seed).
    simulate_wall(&design, &c, &["--seed", "2"]);
    let (ra, rc) = (without_wall_time(&a), without_wall_time(&c));
    for (x, y) in ra.iter().zip(&rc) {
        assert_ne!(x[0], y[0], "run_id");
        assert_ne!(x[3], y[3], "seed");
        assert_eq!(x[4..], y[4..]);
    }

    // Seeds reach the experiment, and a row's seed does not depend on the others.
    let d = sleep_design(dir.path(), "s.csv", 6, None);
    let part = write(
        dir.path(),
        "s4.csv",
        "x,y,fail\n0,0,0\n1,0.5,0\n-1,1,0\n3,1.5,0\n",
    );
    let (x, y, z) = (
        dir.path().join("x.csv"),
        dir.path().join("y.csv"),
        dir.path().join("z.csv"),
    );
    simulate_sleep(&d, &x, &[]);
    simulate_sleep(&part, &y, &[]);
    simulate_sleep(&d, &z, &["--seed", "9"]);
    let (rx, ry, rz) = (read(&x).1, read(&y).1, read(&z).1);
    let noise = |rows: &[HashMap<String, String>], row: &str| {
        rows.iter().find(|r| r["row"] == row).unwrap()["noise"].clone()
    };
    for row in ["0", "1", "2", "3"] {
        assert_eq!(noise(&rx, row), noise(&ry, row));
        assert_ne!(noise(&rx, row), noise(&rz, row));
    }
}

#[test]
fn kill_and_resume_gives_the_uninterrupted_table() {
    let dir = tempfile::tempdir().unwrap();
    let design = sleep_design(dir.path(), "slow.csv", 60, Some(3));
    let (killed, reference) = (dir.path().join("killed.csv"), dir.path().join("ref.csv"));
    let args = |out: &Path| {
        vec![
            "simulate".to_string(),
            "--design".into(),
            s(&design).into(),
            "--experiment".into(),
            "sleep-test".into(),
            "--out".into(),
            s(out).into(),
            "--threads".into(),
            "2".into(),
            "--set".into(),
            "sleep_ms=30".into(),
        ]
    };
    let ref_args = args(&reference);
    let mut reference_run = command(&arg_refs(&ref_args))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();

    let kill_args = args(&killed);
    let mut child = command(&arg_refs(&kill_args))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    loop {
        // The table appears whole (atomic rename) and is never removed.
        let n = if killed.exists() {
            read(&killed).1.len()
        } else {
            0
        };
        if n >= 8 {
            break;
        }
        assert!(t0.elapsed() < Duration::from_secs(30), "no progress");
        std::thread::sleep(Duration::from_millis(5));
    }
    assert!(
        child.try_wait().unwrap().is_none(),
        "finished before the kill"
    );
    child.kill().unwrap(); // SIGKILL: no chance to clean up
    child.wait().unwrap();

    let at_kill = std::fs::read(&killed).unwrap();
    let status = last_json(&ok(&["campaign", "status", s(&killed), "--json"]));
    let present = status["done"].as_u64().unwrap() + status["failed"].as_u64().unwrap();
    assert!((8..60).contains(&present), "{status}");
    assert_eq!(status["total"], 60);
    assert_eq!(status["remaining"].as_u64().unwrap(), 60 - present);

    // Whatever the kill left, also simulate a write cut short: half of a line, no newline.
    let complete = if at_kill.ends_with(b"\n") {
        at_kill.clone()
    } else {
        at_kill[..=at_kill.iter().rposition(|&b| b == b'\n').unwrap()].to_vec()
    };
    let mut damaged = complete.clone();
    damaged.extend(b"ffffffffffffffff,59,do");
    std::fs::write(&killed, &damaged).unwrap();
    let status = last_json(&ok(&["campaign", "status", s(&killed), "--json"]));
    assert_eq!(status["partial_line"], true);

    let o = mbgc(&arg_refs(&kill_args));
    let stderr = String::from_utf8_lossy(&o.stderr);
    // Row 3 fails on request: the resumed campaign still reports it (exit 1).
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("1 of the 60 runs"), "{stderr}");
    assert!(
        stderr.contains("removed an incomplete last line"),
        "{stderr}"
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains(&format!("{present} already in the table")),
        "{stdout}"
    );
    let resumed = std::fs::read(&killed).unwrap();
    assert!(
        resumed.starts_with(&complete),
        "finished runs were rewritten"
    );

    // Every row exactly once, and the same table as the uninterrupted run.
    let (_, rows) = read(&killed);
    let mut seen: Vec<usize> = rows.iter().map(|r| r["row"].parse().unwrap()).collect();
    seen.sort();
    assert_eq!(seen, (0..60).collect::<Vec<_>>());
    // Row 3 fails on request, so the campaign exits 1.
    assert_eq!(reference_run.wait().unwrap().code(), Some(1));
    let a = merge(&[&killed], &dir.path().join("a.csv"));
    let b = merge(&[&reference], &dir.path().join("b.csv"));
    assert_eq!(a, b);
    let status = last_json(&ok(&["campaign", "status", s(&killed), "--json"]));
    assert_eq!(
        (&status["done"], &status["failed"], &status["remaining"]),
        (&59.into(), &1.into(), &0.into())
    );
}

#[test]
fn merged_shards_equal_the_merged_full_run_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let design = sleep_design(dir.path(), "d.csv", 20, Some(7));
    let full = dir.path().join("full.csv");
    simulate_sleep(&design, &full, &["--threads", "2"]);
    let shards: Vec<PathBuf> = (1..=3)
        .map(|k| {
            let out = dir.path().join(format!("part-{k}.csv"));
            let shard = format!("{k}/3");
            simulate_sleep(&design, &out, &["--shard", &shard, "--threads", "1"]);
            let (_, rows) = read(&out);
            assert!(rows
                .iter()
                .all(|r| r["row"].parse::<usize>().unwrap() % 3 == k - 1));
            out
        })
        .collect();
    let shard_refs: Vec<&Path> = shards.iter().map(|p| p.as_path()).collect();
    let from_shards = merge(&shard_refs, &dir.path().join("m1.csv"));
    let from_full = merge(&[&full], &dir.path().join("m2.csv"));
    assert_eq!(
        String::from_utf8(from_shards.clone()).unwrap(),
        String::from_utf8(from_full.clone()).unwrap()
    );
    // Input order and identical duplicates do not matter.
    let reversed: Vec<&Path> = shard_refs.iter().rev().copied().collect();
    assert_eq!(merge(&reversed, &dir.path().join("m3.csv")), from_full);
    let mut all = reversed.clone();
    all.push(&full);
    assert_eq!(merge(&all, &dir.path().join("m4.csv")), from_full);

    // Sorted by row, with the failed row and its escaped message intact.
    let (_, rows) = read(&dir.path().join("m1.csv"));
    let order: Vec<usize> = rows.iter().map(|r| r["row"].parse().unwrap()).collect();
    assert_eq!(order, (0..20).collect::<Vec<_>>());
    assert_eq!(rows[7]["status"], "failed");
    assert_eq!(
        rows[7]["error"],
        "sleep-test: \"fail\" requested, x = 7,\nsecond line"
    );

    // Shard sidecars count only their own rows.
    let status = last_json(&ok(&["campaign", "status", s(&shards[1]), "--json"]));
    assert_eq!(
        (&status["total"], &status["remaining"]),
        (&7.into(), &0.into())
    );
}

#[test]
fn wall_impact_shards_agree_with_a_full_run_except_for_measured_wall_time() {
    let dir = tempfile::tempdir().unwrap();
    let design = wall_design(dir.path());
    let full = dir.path().join("full.csv");
    simulate_wall(&design, &full, &[]);
    let parts: Vec<PathBuf> = (1..=3)
        .map(|k| {
            let out = dir.path().join(format!("p{k}.csv"));
            simulate_wall(&design, &out, &["--shard", &format!("{k}/3")]);
            out
        })
        .collect();
    let refs: Vec<&Path> = parts.iter().map(|p| p.as_path()).collect();
    let m = dir.path().join("m.csv");
    merge(&refs, &m);
    assert_eq!(without_wall_time(&m), without_wall_time(&full));
    // A duplicate differing only in wall_time_s is the same run, not a conflict.
    merge(&[&m, &full], &dir.path().join("m2.csv"));
}

#[test]
fn failed_and_panicking_runs_are_recorded_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    let design = write(
        dir.path(),
        "d.csv",
        "x,y,fail,panic\n1,1,0,0\n2,1,1,0\n3,1,0,1\n4,1,0,0\n5,1,0,0\n6,1,0,0\n",
    );
    let out = dir.path().join("out.csv");
    let args = [
        "simulate",
        "--design",
        s(&design),
        "--experiment",
        "sleep-test",
        "--out",
        s(&out),
    ];
    let o = mbgc(&args);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(
        o.status.code(),
        Some(1),
        "failed runs must fail the command"
    );
    assert!(stdout.contains("4 done, 2 failed"), "{stdout}");
    assert!(
        stderr.contains("2 of the 6 runs") && stderr.contains("(2 in this invocation, 0 earlier)"),
        "{stderr}"
    );
    let (_, rows) = read(&out);
    let row = |i: &str| rows.iter().find(|r| r["row"] == i).unwrap();
    assert_eq!(row("1")["status"], "failed");
    assert_eq!(
        row("1")["error"],
        "sleep-test: \"fail\" requested, x = 2,\nsecond line"
    );
    assert_eq!(
        (row("1")["f"].as_str(), row("1")["steps"].as_str()),
        ("", "")
    );
    assert_eq!(row("2")["status"], "failed");
    assert_eq!(
        row("2")["error"],
        "panic: sleep-test: panic on request at x = 3"
    );
    assert_eq!(row("3")["f"], "6.0");

    // A design grown by four rows: status counts them as remaining.
    let bigger = write(
        dir.path(),
        "d10.csv",
        "x,y,fail,panic\n1,1,0,0\n2,1,1,0\n3,1,0,1\n4,1,0,0\n5,1,0,0\n6,1,0,0\n7,1,0,0\n8,1,0,0\n\
         9,1,0,0\n10,1,0,0\n",
    );
    let text = ok(&[
        "campaign",
        "status",
        s(&out),
        "--design",
        s(&bigger),
        "--json",
    ]);
    let status = last_json(&text);
    // With --json the text goes to standard error; without it, to standard output.
    let human = ok(&["campaign", "status", s(&out), "--design", s(&bigger)]);
    assert!(human.contains("remaining  4"), "{human}");
    assert_eq!(status["done"], 4);
    assert_eq!(status["failed"], 2);
    assert_eq!(status["remaining"], 4);
    assert_eq!(status["total"], 10);

    // Resuming on it runs only the new rows; failed runs are not retried, but still counted.
    let o = mbgc(&[
        "simulate",
        "--design",
        s(&bigger),
        "--experiment",
        "sleep-test",
        "--out",
        s(&out),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("6 already in the table, ran 4"), "{stdout}");
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("(0 in this invocation, 2 earlier)"));
    let status = last_json(&ok(&["campaign", "status", s(&out), "--json"]));
    assert_eq!(
        (&status["remaining"], &status["total"]),
        (&0.into(), &10.into())
    );
}

#[test]
fn bad_inputs_are_refused_naming_the_file_and_field_before_anything_runs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("out.csv");
    let wall = |design: &Path, extra: &[&str]| {
        let mut args = vec![
            "simulate",
            "--design",
            s(design),
            "--experiment",
            "wall-impact",
            "--out",
            s(&out),
        ];
        args.extend(WALL_SET);
        args.extend(extra);
        let e = fails(&args);
        assert!(!out.exists(), "output created for {extra:?}: {e}");
        assert!(!d.join("out.csv.meta.json").exists());
        e
    };

    let no_mu = write(d, "no_mu.csv", "impact_angle,rho_p,d50\n30,4000,5\n");
    let e = wall(&no_mu, &[]);
    assert!(
        e.contains("no_mu.csv: column mu_pw: missing") && e.contains("--set mu_pw="),
        "{e}"
    );

    let nan = write(
        d,
        "nan.csv",
        "impact_angle,mu_pw,rho_p,d50\n30,0.1,4000,5\n40,NaN,4000,5\n",
    );
    let e = wall(&nan, &[]);
    assert!(e.contains("nan.csv: line 3, column mu_pw"), "{e}");

    let negative = write(
        d,
        "neg.csv",
        "impact_angle,mu_pw,rho_p,d50\n30,0.1,4000,5\n40,0.1,4000,5\n50,0.1,4000,5\n\
         60,0.1,-2500,5\n",
    );
    let e = wall(&negative, &[]);
    assert!(
        e.contains("neg.csv: line 5 (row 3)")
            && e.contains("rho_p")
            && e.contains("nothing was run"),
        "{e}"
    );

    let good = wall_design(d);
    for bad in ["0/3", "4/3", "x/y", "3"] {
        let e = wall(&good, &["--shard", bad]);
        assert!(e.contains(&format!("--shard {bad}")), "{e}");
    }
    let e = wall(&good, &["--set", "mu_pw=0.2"]);
    assert!(
        e.contains("wall.csv: column mu_pw") && e.contains("--set"),
        "{e}"
    );
    let e = wall(&good, &["--set", "impact_speed"]);
    assert!(e.contains("--set impact_speed"), "{e}");
    let e = wall(&good, &["--threads", "0"]);
    assert!(e.contains("--threads"), "{e}");
    let e = wall(&good, &["--box-scale", "-1"]);
    assert!(e.contains("--box-scale"), "{e}");
    // --set values are checked like design values.
    let e = wall(&good, &["--set", "spin=1e9"]);
    assert!(
        e.contains("wall.csv: line 2 (row 0)") && e.contains("parameter spin"),
        "{e}"
    );

    let e = fails(&[
        "simulate",
        "--design",
        s(&good),
        "--experiment",
        "shear-bx",
        "--out",
        s(&out),
    ]);
    assert!(
        e.contains("--experiment shear-bx: unknown experiment (known: wall-impact"),
        "{e}"
    );
    // Resume onto a table of another campaign: refused, table untouched.
    let sd = sleep_design(d, "s.csv", 4, None);
    simulate_sleep(&sd, &out, &[]);
    let before = std::fs::read(&out).unwrap();
    let sleep = |extra: &[&str]| {
        let mut args = vec![
            "simulate",
            "--design",
            s(&sd),
            "--experiment",
            "sleep-test",
            "--out",
            s(&out),
        ];
        args.extend(extra);
        let e = fails(&args);
        assert_eq!(std::fs::read(&out).unwrap(), before, "{extra:?}");
        e
    };
    let e = sleep(&["--set", "sleep_ms=1"]);
    assert!(
        e.contains("out.csv: header:") && e.contains("sleep_ms"),
        "{e}"
    );
    let e = sleep(&["--seed", "2"]);
    assert!(
        e.contains("out.csv: line 2: row") && e.contains("another campaign"),
        "{e}"
    );
    let e = fails(&[
        "simulate",
        "--design",
        s(&good),
        "--experiment",
        "wall-impact",
        "--out",
        s(&out),
        "--set",
        "E_p=380e9",
        "--set",
        "nu_p=0.23",
        "--set",
        "E_w=1e13",
        "--set",
        "e_pw=0.98",
        "--set",
        "impact_speed=3.9",
        "--model-class",
        "hertz,mindlin",
    ]);
    assert!(e.contains("out.csv: header:"), "{e}");
    assert_eq!(std::fs::read(&out).unwrap(), before);

    // Merge refuses mixed headers and conflicting results for one run.
    let other = d.join("other.csv");
    simulate_sleep(&sd, &other, &["--set", "sleep_ms=0"]);
    let e = fails(&[
        "campaign",
        "merge",
        s(&out),
        s(&other),
        "--out",
        s(&d.join("m.csv")),
    ]);
    assert!(
        e.contains("other.csv: header: differs from the header of"),
        "{e}"
    );
    let text = String::from_utf8(before.clone()).unwrap();
    let (_, rows) = read(&out);
    let f0 = &rows[0]["f"];
    let tampered = write(
        d,
        "tampered.csv",
        &text.replacen(&format!(",{f0},"), ",123.0,", 1),
    );
    let e = fails(&[
        "campaign",
        "merge",
        s(&out),
        s(&tampered),
        "--out",
        s(&d.join("m.csv")),
    ]);
    assert!(
        e.contains("tampered.csv: line 2") && e.contains("conflicting results"),
        "{e}"
    );
    let reseeded = d.join("reseeded.csv");
    simulate_sleep(&sd, &reseeded, &["--seed", "5"]);
    let e = fails(&[
        "campaign",
        "merge",
        s(&out),
        s(&reseeded),
        "--out",
        s(&d.join("m.csv")),
    ]);
    assert!(e.contains("different campaigns"), "{e}");
    assert!(!d.join("m.csv").exists());

    let e = fails(&["campaign", "status", s(&good)]);
    assert!(
        e.contains("wall.csv: header: expected a campaign table"),
        "{e}"
    );
}

/// Starts `first` writing `out`, waits for its first run, then runs `second` (which may first
/// make `link` a hard link to the table) and asserts that it is refused while the first ends
/// well.
fn second_writer_is_refused(first: &[String], second: &[String], out: &Path, link: Option<&Path>) {
    let mut child = command(&arg_refs(first))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Wait until the first process has started writing (header plus one run).
    let t0 = Instant::now();
    while !out.exists() || read(out).1.is_empty() {
        assert!(
            t0.elapsed() < Duration::from_secs(30),
            "first writer made no progress"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    if let Some(link) = link {
        std::fs::hard_link(out, link).unwrap();
    }
    let o = mbgc(&arg_refs(second));
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(!o.status.success(), "second writer was allowed");
    assert!(err.contains("another mbgc process is writing"), "{err}");
    assert!(child.wait().unwrap().success());
}

#[test]
fn a_second_writer_on_the_same_table_is_refused_and_nothing_is_written_twice() {
    let dir = tempfile::tempdir().unwrap();
    let design = sleep_design(dir.path(), "d.csv", 20, None);
    let out = dir.path().join("t.csv");
    let args: Vec<String> = [
        "simulate",
        "--design",
        s(&design),
        "--experiment",
        "sleep-test",
        "--out",
        s(&out),
        "--threads",
        "1",
        "--set",
        "sleep_ms=40",
    ]
    .iter()
    .map(|a| a.to_string())
    .collect();
    second_writer_is_refused(&args, &args, &out, None);
    let rows = read(&out).1;
    assert_eq!(rows.len(), 20);
    let mut ids: Vec<&String> = rows.iter().map(|r| &r["run_id"]).collect();
    ids.sort();
    ids.dedup();
    assert_eq!(ids.len(), 20);
    // Once the first has finished, the table is free again (resume finds nothing to do).
    mbgc(&arg_refs(&args))
        .status
        .success()
        .then_some(())
        .unwrap();
}

/// The same through a hard link made once the first writer has created the table: another
/// name, hence another lock file, but the same file, which the first writer holds.
#[test]
fn a_second_writer_through_a_hard_link_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let design = sleep_design(dir.path(), "d.csv", 12, None);
    let out = dir.path().join("t.csv");
    let hard = dir.path().join("h.csv");
    let args = |table: &Path| -> Vec<String> {
        [
            "simulate",
            "--design",
            s(&design),
            "--experiment",
            "sleep-test",
            "--out",
            s(table),
            "--threads",
            "1",
            "--set",
            "sleep_ms=40",
        ]
        .iter()
        .map(|a| a.to_string())
        .collect()
    };
    second_writer_is_refused(&args(&out), &args(&hard), &out, Some(&hard));
    let rows = read(&out).1;
    assert_eq!(rows.len(), 12, "lines written twice");
}

#[test]
fn fit_refuses_a_table_holding_a_run_twice() {
    let dir = tempfile::tempdir().unwrap();
    let design = sleep_design(dir.path(), "d.csv", 12, None);
    let out = dir.path().join("t.csv");
    simulate_sleep(&design, &out, &[]);
    // A table written twice over (as two unlocked writers once did).
    let text = std::fs::read_to_string(&out).unwrap();
    let dup_line = text.lines().nth(3).unwrap().to_string();
    std::fs::write(&out, format!("{text}{dup_line}\n")).unwrap();
    let o = mbgc(&[
        "fit",
        "--data",
        s(&out),
        "--inputs",
        "x,y",
        "--targets",
        "f",
        "--out",
        s(&dir.path().join("m.json")),
        "--generations",
        "2",
        "--population",
        "50",
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "fit accepted a duplicated run");
    assert!(
        e.contains("column run_id") && e.contains("also on line 4"),
        "{e}"
    );
}

#[test]
fn retry_failed_reruns_only_the_failed_rows_and_replaces_their_lines() {
    let dir = tempfile::tempdir().unwrap();
    let design = sleep_design(dir.path(), "d.csv", 8, None);
    let out = dir.path().join("t.csv");
    let args = [
        "simulate",
        "--design",
        s(&design),
        "--experiment",
        "sleep-test",
        "--out",
        s(&out),
    ];
    // x = 5 fails once (a transient fault), then the fault is gone.
    let first = command(&args)
        .env("SLEEP_TEST_FAIL_X", "5")
        .output()
        .unwrap();
    assert_eq!(first.status.code(), Some(1));
    let (_, rows) = read(&out);
    let failed: Vec<&str> = rows
        .iter()
        .filter(|r| r["status"] == "failed")
        .map(|r| r["row"].as_str())
        .collect();
    assert_eq!(failed, ["5"]);
    // A plain resume does not retry (and still exits 1); --retry-failed does.
    assert_eq!(mbgc(&args).status.code(), Some(1));
    let mut retry = args.to_vec();
    retry.push("--retry-failed");
    let o = mbgc(&retry);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("1 failed run(s) of earlier attempts"));
    let (_, rows) = read(&out);
    assert_eq!(rows.len(), 8);
    assert!(rows.iter().all(|r| r["status"] == "done"));
    let mut ids: Vec<&String> = rows.iter().map(|r| &r["run_id"]).collect();
    ids.dedup();
    assert_eq!(ids.len(), 8);
    // The table equals an uninterrupted run of the same campaign.
    let clean = dir.path().join("clean.csv");
    ok(&[
        "simulate",
        "--design",
        s(&design),
        "--experiment",
        "sleep-test",
        "--out",
        s(&clean),
    ]);
    let sorted = |p: &Path| {
        let mut l: Vec<String> = std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .map(String::from)
            .collect();
        l.sort();
        l
    };
    assert_eq!(sorted(&out), sorted(&clean));
}

#[test]
fn an_unwritable_vtk_directory_is_refused_before_anything_runs() {
    let dir = tempfile::tempdir().unwrap();
    let design = sleep_design(dir.path(), "d.csv", 3, None);
    let out = dir.path().join("t.csv");
    // A file where the directory should be.
    let blocker = dir.path().join("vtk");
    std::fs::write(&blocker, "x").unwrap();
    let e = fails(&[
        "simulate",
        "--design",
        s(&design),
        "--experiment",
        "sleep-test",
        "--out",
        s(&out),
        "--vtk",
        s(&blocker.join("sub")),
    ]);
    assert!(
        e.contains("--vtk") && e.contains("expected a writable directory"),
        "{e}"
    );
    assert!(
        !out.exists(),
        "a table was started although nothing could run"
    );
}

#[test]
fn tables_that_do_not_belong_are_refused_by_resume_status_and_merge() {
    let dir = tempfile::tempdir().unwrap();
    let design = sleep_design(dir.path(), "d.csv", 6, None);
    let out = dir.path().join("t.csv");
    simulate_sleep(&design, &out, &[]);

    // An input edited by hand: resume refuses instead of counting the line as this run.
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let x_col = lines[0].split(',').position(|c| c == "x").unwrap();
    let mut fields: Vec<String> = lines[2].split(',').map(String::from).collect();
    fields[x_col] = "99.0".into();
    lines[2] = fields.join(",");
    let edited = dir.path().join("edited.csv");
    std::fs::write(&edited, lines.join("\n") + "\n").unwrap();
    std::fs::copy(
        dir.path().join("t.csv.meta.json"),
        dir.path().join("edited.csv.meta.json"),
    )
    .unwrap();
    let e = fails(&[
        "simulate",
        "--design",
        s(&design),
        "--experiment",
        "sleep-test",
        "--out",
        s(&edited),
    ]);
    assert!(
        e.contains("line 3, column x") && e.contains("edited"),
        "{e}"
    );

    // Status against an unrelated design (same size, other values).
    let other = write(
        dir.path(),
        "other.csv",
        "x,y,fail\n9,9,0\n9,9,0\n9,9,0\n9,9,0\n9,9,0\n9,9,0\n",
    );
    let e = fails(&["campaign", "status", s(&out), "--design", s(&other)]);
    assert!(
        e.contains("not a campaign of") && e.contains("other.csv"),
        "{e}"
    );

    // Shards run with different seeds do not merge.
    let (a, b) = (dir.path().join("a.csv"), dir.path().join("b.csv"));
    simulate_sleep(&design, &a, &["--shard", "1/2"]);
    simulate_sleep(&design, &b, &["--shard", "2/2", "--seed", "9"]);
    let e = fails(&[
        "campaign",
        "merge",
        s(&a),
        s(&b),
        "--out",
        s(&dir.path().join("m.csv")),
    ]);
    assert!(e.contains("--seed") && e.contains("b.csv"), "{e}");
}

#[test]
fn a_set_constant_the_experiment_does_not_read_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let design = sleep_design(dir.path(), "d.csv", 3, None);
    let out = dir.path().join("t.csv");
    let e = fails(&[
        "simulate",
        "--design",
        s(&design),
        "--experiment",
        "sleep-test",
        "--out",
        s(&out),
        "--set",
        "sleep_mss=3",
    ]);
    assert!(
        e.contains("--set sleep_mss=3")
            && e.contains("no parameter sleep_mss")
            && e.contains("sleep_ms"),
        "{e}"
    );
    assert!(!out.exists());
    // Optional parameters are accepted.
    simulate_sleep(&design, &out, &["--set", "sleep_ms=1"]);
}

/// The model class is part of a campaign: recorded on every line, in the run ids when it is not
/// the default, and a resume with another class is refused; a parameter of an effect the class
/// lacks is refused naming the effect, a missing one naming the parameter.
#[test]
fn the_model_class_is_recorded_and_a_resume_with_another_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let design = wall_design(d);
    let out = d.join("table.csv");
    simulate_wall(&design, &out, &[]);
    let (header, rows) = read(&out);
    assert_eq!(header[4], "model_class");
    assert!(rows.iter().all(|r| r["model_class"] == "hertz+mindlin"));
    let before = std::fs::read(&out).unwrap();
    // WALL_SET without its class: each command below names its own.
    let mut base: Vec<&str> = vec![
        "simulate",
        "--design",
        s(&design),
        "--experiment",
        "wall-impact",
        "--out",
        s(&out),
    ];
    base.extend(&WALL_SET[2..]);
    let mut args = base.clone();
    args.extend([
        "--model-class",
        "hertz,mindlin,epsd2",
        "--set",
        "mu_r_pw=0.1",
    ]);
    let e = fails(&args);
    assert!(
        e.contains("column model_class") && e.contains("--model-class hertz,mindlin"),
        "{e}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), before, "nothing written");
    // The default class needs mu_r_pw (EPSD2), and names it.
    let fresh = d.join("fresh.csv");
    let mut args = base.clone();
    args[6] = s(&fresh);
    let e = fails(&args);
    assert!(e.contains("mu_r_pw") && e.contains("epsd2"), "{e}");
    // A cohesion parameter without cohesion does nothing: refused, naming the effect.
    let mut args = base.clone();
    args[6] = s(&fresh);
    args.extend(["--model-class", "hertz,mindlin", "--set", "ced_pw=1e4"]);
    let e = fails(&args);
    assert!(
        e.contains("ced_pw") && e.contains("sjkr") && e.contains("hertz,mindlin,sjkr"),
        "{e}"
    );
    // A particle-particle parameter in an experiment without particle-particle contacts.
    let mut args = base.clone();
    args[6] = s(&fresh);
    args.extend(["--model-class", "hertz,mindlin", "--set", "mu_pp=0.4"]);
    let e = fails(&args);
    assert!(
        e.contains("mu_pp") && e.contains("particle-particle"),
        "{e}"
    );
    assert!(!fresh.exists());
    // With cohesion switched on, the same value runs, under other run ids.
    let mut args = base.clone();
    args[6] = s(&fresh);
    args.extend(["--model-class", "hertz,mindlin,sjkr", "--set", "ced_pw=1e4"]);
    ok(&args);
    let (_, cohesive) = read(&fresh);
    assert!(cohesive
        .iter()
        .all(|r| r["model_class"] == "hertz+mindlin+sjkr"));
    assert_ne!(cohesive[0]["run_id"], rows[0]["run_id"]);
    // Tables of different classes with the same columns do not merge.
    let strict = d.join("strict.csv");
    let mut args = base.clone();
    args[6] = s(&strict);
    args.extend(["--model-class", "hertz,strict-coulomb"]);
    ok(&args);
    let e = fails(&[
        "campaign",
        "merge",
        s(&out),
        s(&strict),
        "--out",
        s(&d.join("m.csv")),
    ]);
    assert!(
        e.contains("column model_class") && e.contains("hertz+strict-coulomb"),
        "{e}"
    );

    // The metamodel records the class of its data; calibrate refuses a material needing more.
    let model = d.join("m.json");
    let fit = |extra: &[&str]| {
        let mut args = vec![
            "fit",
            "--data",
            s(&out),
            "--inputs",
            "impact_angle,mu_pw",
            "--targets",
            "ctr",
            "--out",
            s(&model),
            "--population",
            "200",
            "--generations",
            "3",
            "--no-figures",
        ];
        args.extend(extra);
        args.iter().map(|a| a.to_string()).collect::<Vec<_>>()
    };
    ok(&arg_refs(&fit(&[])));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(m["model_class"], "hertz,mindlin");
    let e = fails(&arg_refs(&fit(&["--model-class", "hertz,mindlin,epsd2"])));
    assert!(
        e.contains("--model-class") && e.contains("hertz,mindlin"),
        "{e}"
    );
    let material = |extra: &str| {
        write(
            d,
            "steel.toml",
            &format!("[measured]\nctr = {{ value = 0.7, sd = 0.05 }}\n{extra}"),
        )
    };
    let calibrate = |mat: &Path| {
        vec![
            "calibrate".to_string(),
            "--material".into(),
            s(mat).into(),
            "--model".into(),
            s(&model).into(),
            "--starts".into(),
            "4".into(),
        ]
    };
    ok(&arg_refs(&calibrate(&material(""))));
    let e = fails(&arg_refs(&calibrate(&material(
        "[model]\nclass = \"hertz,mindlin,epsd2\"\n",
    ))));
    assert!(
        e.contains("model.class") && e.contains("needs epsd2"),
        "{e}"
    );
    let e = fails(&arg_refs(&calibrate(&material("[fixed]\nced_pw = 1e4\n"))));
    assert!(e.contains("fixed.ced_pw") && e.contains("sjkr"), "{e}");

    // A model whose inputs belong to an effect its class lacks is refused when loaded.
    let text = std::fs::read_to_string(&model).unwrap();
    let edited = d.join("edited.json");
    std::fs::write(
        &edited,
        text.replace("\"name\": \"mu_pw\"", "\"name\": \"ced_pw\""),
    )
    .unwrap();
    let mut args = calibrate(&material(""));
    args[4] = s(&edited).into();
    let e = fails(&arg_refs(&args));
    assert!(e.contains("inputs.ced_pw") && e.contains("sjkr"), "{e}");

    // A table whose class is not recorded gives a model with none, never a guessed one; a
    // material that names a class is then refused.
    let table_text = std::fs::read_to_string(&out).unwrap();
    let bare = d.join("bare.csv");
    let strip = |line: &str| {
        let mut f: Vec<&str> = line.split(',').collect();
        f.remove(4);
        f.join(",")
    };
    std::fs::write(
        &bare,
        table_text.lines().map(strip).collect::<Vec<_>>().join("\n") + "\n",
    )
    .unwrap();
    let mut args = fit(&[]);
    args[2] = s(&bare).into();
    ok(&arg_refs(&args));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert!(m["model_class"].is_null(), "{}", m["model_class"]);
    let e = fails(&arg_refs(&calibrate(&material(
        "[model]\nclass = \"hertz,mindlin\"\n",
    ))));
    assert!(e.contains("records no model class"), "{e}");
    // ... and resuming it is refused with the column to add.
    let e = fails(&["campaign", "status", s(&bare)]);
    assert!(e.contains("before model classes"), "{e}");
    // One class per fit, whatever the row that differs ("-": no contact law).
    let mixed = d.join("mixed.csv");
    std::fs::write(&mixed, table_text.replacen("hertz+mindlin", "-", 1)).unwrap();
    let mut args = fit(&[]);
    args[2] = s(&mixed).into();
    let e = fails(&arg_refs(&args));
    assert!(
        e.contains("column model_class") && e.contains("one model class"),
        "{e}"
    );

    // A design column the experiment does not read is refused; a retired name gets a hint.
    let old = write(
        d,
        "old.csv",
        "impact_angle,mu_pw,rho_p,d50,k_t\n30,0.1,4000,5,1e3\n",
    );
    let mut args = base.clone();
    args[2] = s(&old);
    args[6] = s(&fresh);
    args.extend(["--model-class", "hertz,linear-spring"]);
    let e = fails(&args);
    assert!(e.contains("column k_t") && e.contains("k_t_pw"), "{e}");
}

/// Done runs that measured no value of a response (NaN) are counted apart: the summary, the
/// JSON and a warning say how many; they stay done rows (exit 0), and a fit leaves them out.
#[test]
fn runs_without_a_value_are_counted_apart() {
    let dir = tempfile::tempdir().unwrap();
    let design = write(
        dir.path(),
        "d.csv",
        "x,y,no_value\n0.1,0.2,0\n0.3,0.4,1\n0.5,0.6,0\n0.7,0.8,1\n",
    );
    let out = dir.path().join("t.csv");
    let o = mbgc(&[
        "simulate",
        "--design",
        design.to_str().unwrap(),
        "--experiment",
        "sleep-test",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (v["done"].as_u64(), v["no_value"].as_u64()),
        (Some(4), Some(2)),
        "{v}"
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("2 of the 4 runs done measured no value"),
        "{err}"
    );
    // The table's status counts them too, from the table alone.
    let o = mbgc(&["campaign", "status", out.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (v["done"].as_u64(), v["no_value"].as_u64()),
        (Some(4), Some(2)),
        "{v}"
    );
    let o = mbgc(&["campaign", "status", out.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("without a value of some response: 2"),
        "{text}"
    );
}

/// A failed run in one table and the same run done in another (a rerun that succeeded
/// elsewhere) merge to the done run, in either order; the summary counts it.
#[test]
fn merge_keeps_the_rerun_that_succeeded() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let design = write(d, "d.csv", "x,y\n0.1,0.2\n0.3,0.4\n0.5,0.6\n");
    let done = d.join("done.csv");
    simulate_sleep(&design, &done, &[]);
    let text = std::fs::read_to_string(&done).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let first = lines.next().unwrap();
    let fields: Vec<&str> = first.split(',').collect();
    let failed_line = format!(
        "{},{},failed,{}{}",
        fields[0],
        fields[1],
        fields[3..fields.len() - 1].join(","),
        ",sleep-test: transient"
    );
    let failed = write(d, "failed.csv", &format!("{header}\n{failed_line}\n"));
    for order in [[&failed, &done], [&done, &failed]] {
        let out = d.join("merged.csv");
        let merged = merge(&[order[0].as_path(), order[1].as_path()], &out);
        let merged = String::from_utf8(merged).unwrap();
        assert!(!merged.contains(",failed,"), "{merged}");
        assert_eq!(merged.lines().count(), text.lines().count());
    }
    let v: serde_json::Value = serde_json::from_str(&ok(&[
        "campaign",
        "merge",
        s(&failed),
        s(&done),
        "--out",
        s(&d.join("m2.csv")),
        "--json",
    ]))
    .unwrap();
    assert_eq!(v["summary"]["superseded_failures"], 1, "{v}");
}

/// Decks whose campaign.json or design.csv was edited after --write-decks name other runs:
/// import refuses instead of reporting "0 imported" and exiting 0.
#[test]
fn import_refuses_decks_of_an_edited_campaign() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let design = write(d, "d.csv", "mu_pp,rho_p\n0.3,2500\n0.5,2600\n");
    let decks = d.join("decks");
    let mut args = vec![
        "simulate",
        "--design",
        s(&design),
        "--experiment",
        "shear-box",
        "--backend",
        "liggghts",
        "--write-decks",
        s(&decks),
        "--box-scale",
        "4",
    ];
    for kv in [
        "E_p=4e7",
        "E_w=4e7",
        "nu_p=0.25",
        "e_pp=0.5",
        "e_pw=0.5",
        "mu_pw=0.3",
        "mu_r_pp=0.3",
        "mu_r_pw=0.3",
        "d50=8",
        "sigma_ln=0.2",
    ] {
        args.extend(["--set", kv]);
    }
    ok(&args);
    let text = std::fs::read_to_string(decks.join("design.csv")).unwrap();
    std::fs::write(decks.join("design.csv"), text.replace("\n0.3,", "\n0.35,")).unwrap();
    let e = fails(&[
        "campaign",
        "import",
        "--decks",
        s(&decks),
        "--out",
        s(&d.join("t.csv")),
    ]);
    assert!(e.contains("edited after --write-decks"), "{e}");
}

/// A line whose status is neither done nor failed is refused by merge as by status and a resumed
/// simulate, naming the file, the line and the field; merge does not copy it on.
#[test]
fn merge_refuses_a_line_with_an_invalid_status() {
    let dir = tempfile::tempdir().unwrap();
    let full = Path::new(env!("CARGO_MANIFEST_DIR")).join("training_data/diagnose_local.csv");
    let text = std::fs::read_to_string(full).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    assert!(lines[3].contains(",done,"), "{}", lines[3]);
    lines[3] = lines[3].replacen(",done,", ",dne,", 1);
    let bad = write(dir.path(), "lf.csv", &(lines.join("\n") + "\n"));
    let out = dir.path().join("m.csv");
    for args in [
        vec!["campaign", "merge", s(&bad), "--out", s(&out)],
        vec!["campaign", "status", s(&bad)],
    ] {
        let e = fails(&args);
        assert!(
            e.contains(s(&bad))
                && e.contains("line 4")
                && e.contains("status")
                && e.contains("dne"),
            "{args:?}: {e}"
        );
    }
    assert!(!out.exists(), "merge wrote {}", out.display());
}
