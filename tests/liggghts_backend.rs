//! `mbgc simulate --backend liggghts` and `mbgc campaign import` on a tiny shear box (k = 4,
//! about 300 particles, a few seconds per LIGGGHTS run). They need Debian's `liggghts`; CI
//! installs it and sets MBGC_REQUIRE_LIGGGHTS=1, so that there a missing LIGGGHTS fails instead
//! of skipping. The refusals need no LIGGGHTS.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::{fails, mbgc, ok, s};

fn liggghts_here() -> bool {
    let here = mbgc::liggghts::find_binary().is_some();
    if !here {
        assert!(
            std::env::var("MBGC_REQUIRE_LIGGGHTS").is_err(),
            "MBGC_REQUIRE_LIGGGHTS is set but LIGGGHTS is not on PATH (apt-get install liggghts)"
        );
        eprintln!("LIGGGHTS not installed: the LIGGGHTS backend test is skipped");
    }
    here
}

const SET: [&str; 20] = [
    "--set",
    "E_p=5e6",
    "--set",
    "E_w=5e6",
    "--set",
    "nu_p=0.3",
    "--set",
    "rho_p=2600",
    "--set",
    "d50=8",
    "--set",
    "sigma_ln=0.15",
    "--set",
    "e_pp=0.5",
    "--set",
    "e_pw=0.5",
    "--set",
    "mu_pw=0.3",
    "--set",
    "mu_r_pw=0.3",
];

fn design(dir: &Path, rows: &[(f64, f64)]) -> PathBuf {
    let mut t = String::from("mu_pp,mu_r_pp\n");
    for (a, b) in rows {
        t += &format!("{a},{b}\n");
    }
    let p = dir.join("design.csv");
    std::fs::write(&p, t).unwrap();
    p
}

fn simulate(design: &Path, out: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "simulate",
        "--design",
        s(design),
        "--experiment",
        "shear-box",
        "--box-scale",
        "4",
        "--out",
        s(out),
        "--threads",
        "2",
    ];
    args.extend(SET);
    args.extend(extra);
    ok(&args)
}

type Rows = Vec<BTreeMap<String, String>>;

fn read(table: &Path) -> (Vec<String>, Rows) {
    let mut rdr = csv::Reader::from_path(table).unwrap();
    let header: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
    let mut rows: Rows = rdr
        .records()
        .map(|r| {
            let r = r.unwrap();
            header
                .iter()
                .cloned()
                .zip(r.iter().map(String::from))
                .collect()
        })
        .collect();
    // Runs finish in any order on several threads.
    rows.sort_by_key(|r| r["row"].parse::<usize>().unwrap());
    (header, rows)
}

fn column(rows: &Rows, name: &str) -> Vec<f64> {
    rows.iter().map(|r| r[name].parse().unwrap()).collect()
}

fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

#[test]
fn liggghts_tables_agree_with_the_embedded_engine_within_the_seed_noise() {
    if !liggghts_here() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // Eight replicates (rows differ only in their seed) of one point.
    let d = design(dir.path(), &[(0.3, 0.2); 8]);
    let emb = dir.path().join("embedded.csv");
    let lig = dir.path().join("liggghts.csv");
    simulate(&d, &emb, &[]);
    let text = simulate(&d, &lig, &["--backend", "liggghts"]);
    assert!(text.is_empty() || text.contains("done"), "{text}");
    let (he, re) = read(&emb);
    let (hl, rl) = read(&lig);
    // Same columns, with the backend named after the model class.
    let mut expected = he.clone();
    expected.insert(5, "backend".into());
    assert_eq!(hl, expected);
    assert_eq!(rl.len(), 8);
    for (l, e) in rl.iter().zip(&re) {
        assert_eq!(l["status"], "done", "{l:?}");
        assert_eq!(l["settled"], "true", "{l:?}");
        assert_eq!(l["backend"], "liggghts");
        assert_eq!(l["seed"], e["seed"], "same row seeds");
        assert_ne!(
            l["run_id"], e["run_id"],
            "the backend is part of the run id"
        );
    }
    for name in ["shear_angle", "bulk_density"] {
        let (me, se) = mean_se(&column(&re, name));
        let (ml, sl) = mean_se(&column(&rl, name));
        let z = (ml - me) / (se * se + sl * sl).sqrt();
        eprintln!("{name}: embedded {me:.2} +- {se:.2}, LIGGGHTS {ml:.2} +- {sl:.2}, z = {z:.2}");
        assert!(z.abs() < 3.0, "{name}: z = {z:.2}");
    }
    // A second start finds every run in the table.
    let again = simulate(&d, &lig, &["--backend", "liggghts", "--json"]);
    let v: serde_json::Value = serde_json::from_str(again.trim()).unwrap();
    assert_eq!(
        (v["skipped"].as_u64(), v["done"].as_u64()),
        (Some(8), Some(0))
    );
    assert_eq!(v["backend"], "liggghts");
}

#[test]
fn written_decks_run_elsewhere_import_to_the_table_simulate_writes() {
    if !liggghts_here() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = design(dir.path(), &[(0.3, 0.2), (0.6, 0.4), (0.4, 0.1)]);
    let direct = dir.path().join("direct.csv");
    simulate(
        &d,
        &direct,
        &[
            "--backend",
            "liggghts",
            "--decks",
            s(&dir.path().join("kept")),
        ],
    );
    let decks = dir.path().join("decks");
    let mut args = vec![
        "simulate",
        "--design",
        s(&d),
        "--experiment",
        "shear-box",
        "--box-scale",
        "4",
        "--backend",
        "liggghts",
        "--write-decks",
        s(&decks),
    ];
    args.extend(SET);
    ok(&args);
    let table = dir.path().join("imported.csv");
    let import = |extra: &[&str]| {
        let mut a = vec![
            "campaign",
            "import",
            "--decks",
            s(&decks),
            "--out",
            s(&table),
            "--json",
        ];
        a.extend(extra);
        let o = mbgc(&a);
        (
            o.status.code(),
            serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap_or_default(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, v, _) = import(&[]);
    assert_eq!(code, Some(0));
    assert_eq!(v["not_run"].as_array().unwrap().len(), 3);
    assert_eq!(v["imported"], 0);
    // A user runs one deck by hand, then the script runs the rest.
    let (_, rows_direct) = read(&direct);
    let first = decks.join(&rows_direct[0]["run_id"]);
    let st = Command::new("liggghts")
        .args([
            "-in",
            "in.shear_box_fill",
            "-log",
            "log.shear_box_fill",
            "-screen",
            "/dev/null",
        ])
        .current_dir(&first)
        .status()
        .unwrap();
    assert!(st.success());
    let (_, v, _) = import(&[]);
    assert_eq!(
        (
            v["imported"].as_u64(),
            v["not_run"].as_array().unwrap().len()
        ),
        (Some(1), 2)
    );
    let st = Command::new("sh")
        .arg(decks.join("run_all.sh"))
        .arg("2")
        .status()
        .unwrap();
    assert!(st.success());
    let (code, v, _) = import(&[]);
    assert_eq!(code, Some(0));
    assert_eq!(
        (v["imported"].as_u64(), v["skipped"].as_u64()),
        (Some(2), Some(1))
    );
    // LIGGGHTS on one process repeats itself: the imported runs are the direct ones.
    let strip = |rows: &Rows| -> Vec<BTreeMap<String, String>> {
        let mut v: Vec<_> = rows
            .iter()
            .map(|r| {
                let mut r = r.clone();
                r.remove("wall_time_s");
                r
            })
            .collect();
        v.sort_by(|a, b| a["row"].cmp(&b["row"]));
        v
    };
    let (_, rows_imported) = read(&table);
    assert_eq!(strip(&rows_imported), strip(&rows_direct));
    // A deck edited after it was written is not taken for the row's run.
    let other = dir.path().join("other.csv");
    let input = decks
        .join(&rows_direct[1]["run_id"])
        .join("in.shear_box_fill");
    let text = std::fs::read_to_string(&input).unwrap();
    std::fs::write(&input, text.replace("timestep", "timestep 1e-9 #")).unwrap();
    let o = mbgc(&[
        "campaign",
        "import",
        "--decks",
        s(&decks),
        "--out",
        s(&other),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let (_, rows_other) = read(&other);
    let bad = rows_other
        .iter()
        .find(|r| r["run_id"] == rows_direct[1]["run_id"])
        .unwrap();
    assert_eq!(bad["status"], "failed");
    assert!(
        bad["error"].contains("in.shear_box_fill") && bad["error"].contains("another run's deck")
    );
}

#[test]
fn options_the_chosen_backend_would_ignore_are_refused_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = design(dir.path(), &[(0.3, 0.2)]);
    let out = dir.path().join("t.csv");
    let base = |extra: &[&str]| {
        let mut a = vec![
            "simulate".to_string(),
            "--design".into(),
            s(&d).into(),
            "--out".into(),
            s(&out).into(),
        ];
        a.extend(SET.iter().map(|x| x.to_string()));
        a.extend(extra.iter().map(|x| x.to_string()));
        fails(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    for (extra, says) in [
        (
            &["--experiment", "shear-box", "--mpi", "2"][..],
            "--mpi 2: the embedded backend",
        ),
        (
            &["--experiment", "shear-box", "--decks", "x"][..],
            "--decks",
        ),
        (
            &["--experiment", "hopper", "--backend", "liggghts"][..],
            "the shear box and the shear cell only",
        ),
        (
            &["--experiment", "shear-box", "--backend", "lammps"][..],
            "--backend lammps",
        ),
        (
            &[
                "--experiment",
                "shear-box",
                "--backend",
                "liggghts",
                "--model-class",
                "tsuji,mindlin",
            ][..],
            "tsuji",
        ),
        (
            &[
                "--experiment",
                "shear-box",
                "--backend",
                "liggghts",
                "--mpi",
                "0",
            ][..],
            "--mpi 0",
        ),
        (
            &[
                "--experiment",
                "shear-box",
                "--backend",
                "liggghts",
                "--vtk",
                "v",
            ][..],
            "--vtk v",
        ),
    ] {
        let e = base(extra);
        assert!(e.contains(says), "{extra:?}: {e}");
    }
    assert!(!out.exists(), "nothing was written");
    // Someone else's files are not overwritten by decks.
    let theirs = dir.path().join("theirs");
    std::fs::create_dir(&theirs).unwrap();
    std::fs::write(theirs.join("design.csv"), "mine\n").unwrap();
    let mut a = vec![
        "simulate",
        "--design",
        s(&d),
        "--experiment",
        "shear-box",
        "--backend",
        "liggghts",
        "--write-decks",
        s(&theirs),
    ];
    a.extend(SET);
    let e = fails(&a);
    assert!(
        e.contains("--write-decks") && e.contains("no deck directory"),
        "{e}"
    );
    assert_eq!(
        std::fs::read_to_string(theirs.join("design.csv")).unwrap(),
        "mine\n"
    );
}

#[test]
fn liggghts_on_two_mpi_processes_repeats_itself_and_a_table_holds_one_process_count() {
    if !liggghts_here() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = design(dir.path(), &[(0.3, 0.2), (0.6, 0.4)]);
    let (a, b) = (dir.path().join("a.csv"), dir.path().join("b.csv"));
    for t in [&a, &b] {
        simulate(&d, t, &["--backend", "liggghts", "--mpi", "2"]);
    }
    let strip = |t: &Path| {
        let (h, rows) = read(t);
        let wall = h.iter().position(|c| c == "wall_time_s").unwrap();
        rows.iter()
            .map(|r| {
                let mut r = r.clone();
                r.remove(&h[wall]);
                r
            })
            .collect::<Vec<_>>()
    };
    let (ra, rb) = (strip(&a), strip(&b));
    assert_eq!(ra, rb, "the same runs on the same number of processes");
    assert!(ra
        .iter()
        .all(|r| r["status"] == "done" && r["backend"] == "liggghts-np2"));
    let meta = std::fs::read_to_string(dir.path().join("a.csv.meta.json")).unwrap();
    assert!(meta.contains("\"mpi\": 2"), "{meta}");
    // Resuming on one process would mix trajectories of two process counts in one table.
    let mut args = vec![
        "simulate",
        "--design",
        s(&d),
        "--experiment",
        "shear-box",
        "--box-scale",
        "4",
        "--out",
        s(&a),
        "--backend",
        "liggghts",
    ];
    args.extend(SET);
    let e = fails(&args);
    assert!(
        e.contains("MPI processes") && e.contains("liggghts-np2"),
        "{e}"
    );
}
