//! `mbgc slurm` against a real Slurm: a single-node cluster of Debian's `slurm-wlm`, started by
//! `.ci/slurm-start` (CI runs it and sets MBGC_REQUIRE_SLURM=1, so that there a missing cluster
//! fails instead of skipping). The campaign is the `sleep-test` stand-in, so that the test
//! measures the job machinery, not a DEM.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use common::{fails, mbgc, ok, s};

fn slurm_up() -> bool {
    let up = Command::new("sinfo")
        .args(["-h", "-o", "%T"])
        .output()
        .is_ok_and(|o| {
            let state = String::from_utf8_lossy(&o.stdout);
            o.status.success() && (state.contains("idle") || state.contains("mix"))
        });
    if !up {
        assert!(
            std::env::var("MBGC_REQUIRE_SLURM").is_err(),
            "MBGC_REQUIRE_SLURM is set but no Slurm node answers (sinfo); start one with \
             .ci/slurm-start"
        );
        eprintln!(
            "no Slurm cluster (sinfo): the job-array test is skipped; .ci/slurm-start starts one"
        );
    }
    up
}

/// Eight rows; row 2 fails (shard 3 of 4 holds rows 2 and 6), every run sleeps `sleep_ms`.
fn design(dir: &Path, sleep_ms: u32) -> PathBuf {
    let mut t = String::from("x,y,fail,sleep_ms\n");
    for i in 0..8 {
        t += &format!("{i},{},{},{sleep_ms}\n", i as f64 / 2.0, u8::from(i == 2));
    }
    let p = dir.join("design.csv");
    std::fs::write(&p, t).unwrap();
    p
}

/// Table lines keyed by run id, without the wall time (the one column two executions of a run
/// may differ in).
fn lines(table: &Path) -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(table).unwrap();
    let mut rdr = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
    let wall = header.iter().position(|h| h == "wall_time_s").unwrap();
    let mut m = BTreeMap::new();
    for r in rdr.records() {
        let r = r.unwrap();
        let fields: Vec<&str> = r
            .iter()
            .enumerate()
            .filter(|(k, _)| *k != wall)
            .map(|(_, f)| f)
            .collect();
        assert!(
            m.insert(r[0].to_string(), fields.join(",")).is_none(),
            "{}: run {} twice",
            table.display(),
            &r[0]
        );
    }
    m
}

fn wait_for(jobs: &[&str], timeout: Duration) {
    let t0 = Instant::now();
    loop {
        let o = Command::new("squeue")
            .args(["-h", "-j", &jobs.join(",")])
            .output()
            .unwrap();
        if String::from_utf8_lossy(&o.stdout).trim().is_empty() {
            return;
        }
        assert!(
            t0.elapsed() < timeout,
            "jobs {jobs:?} still queued after {timeout:?}"
        );
        std::thread::sleep(Duration::from_millis(300));
    }
}

/// `scontrol show job -o` of one array task: its state and exit code.
fn task(array: &str, k: usize) -> (String, String) {
    let o = Command::new("scontrol")
        .args(["show", "job", "-o", &format!("{array}_{k}")])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    let field = |name: &str| {
        text.split_whitespace()
            .find_map(|w| w.strip_prefix(name))
            .unwrap_or("?")
            .to_string()
    };
    (field("JobState="), field("ExitCode="))
}

fn submit(dir: &Path) -> (String, String) {
    let o = Command::new("bash")
        .arg(dir.join("submit.sh"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    let w: Vec<&str> = text.split_whitespace().collect();
    (w[1].to_string(), w[3].to_string())
}

#[test]
fn the_scripts_and_refusals_need_no_cluster() {
    let dir = tempfile::tempdir().unwrap();
    let d = design(dir.path(), 0);
    let out = dir.path().join("campaign.csv");
    let args = |extra: &[&str]| {
        let mut v = vec![
            "slurm",
            "--design",
            s(&d),
            "--experiment",
            "sleep-test",
            "--out",
            s(&out),
        ];
        v.extend(extra);
        v.iter().map(|a| a.to_string()).collect::<Vec<String>>()
    };
    let run = |extra: &[&str]| {
        let v = args(extra);
        ok(&v.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let refused = |extra: &[&str]| {
        let v = args(extra);
        fails(&v.iter().map(String::as_str).collect::<Vec<_>>())
    };
    run(&["--shards", "4", "--partition", "debug", "--time", "10:00"]);
    let sd = dir.path().join("campaign.csv.slurm");
    let array = std::fs::read_to_string(sd.join("array.sbatch")).unwrap();
    assert!(array.contains("#SBATCH --array=1-4") && array.contains("--time=10:00"));
    assert!(array.contains("--shard \\\n  \"$K\"/4"), "{array}");
    assert!(sd.join("merge.sbatch").exists() && sd.join("submit.sh").exists());
    for (extra, says) in [
        (&["--shards", "0"][..], "--shards 0"),
        (&["--shards", "9"][..], "--shards 9"),
        (&["--shards", "2", "--time", "2h"][..], "--time 2h"),
        (
            &["--shards", "2", "--mpi", "2", "--cpus-per-task", "2"][..],
            "--mpi 2: the embedded",
        ),
        (&["--shards", "2", "--mpi", "2"][..], "--cpus-per-task 1"),
        (
            &["--shards", "2", "--cpus-per-task", "0"][..],
            "--cpus-per-task",
        ),
    ] {
        let e = refused(extra);
        assert!(e.contains(says), "{extra:?}: {e}");
    }
    let e = fails(&[
        "slurm",
        "--design",
        s(&d),
        "--experiment",
        "sleep-test",
        "--out",
        s(&d),
        "--shards",
        "2",
    ]);
    assert!(e.contains("--out") && e.contains("--design"), "{e}");
}

#[test]
fn a_job_array_merges_to_the_local_table_and_a_killed_task_resumes_on_resubmission() {
    if !slurm_up() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = design(dir.path(), 1500);
    let out = dir.path().join("campaign.csv");
    let local = dir.path().join("local.csv");
    // The reference: the same campaign in one local process (row 2 fails: exit 1).
    let o = mbgc(&[
        "simulate",
        "--design",
        s(&d),
        "--experiment",
        "sleep-test",
        "--out",
        s(&local),
        "--threads",
        "2",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let want = lines(&local);
    assert_eq!(want.len(), 8);

    let text = ok(&[
        "slurm",
        "--design",
        s(&d),
        "--experiment",
        "sleep-test",
        "--out",
        s(&out),
        "--shards",
        "4",
        "--time",
        "5:00",
        "--submit",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(text.trim()).unwrap();
    let array = v["array_job"].as_str().unwrap().to_string();
    let merge = v["merge_job"].as_str().unwrap().to_string();
    let sd = PathBuf::from(v["dir"].as_str().unwrap());
    // Kill task 1 once its first run is in its table and the second is running.
    let shard1 = sd.join("shard_1.csv");
    let t0 = Instant::now();
    while std::fs::read_to_string(&shard1).map_or(0, |t| t.lines().count()) < 2 {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "task 1 never wrote a run"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let st = Command::new("scancel")
        .arg(format!("{array}_1"))
        .status()
        .unwrap();
    assert!(st.success());
    wait_for(&[&array, &merge], Duration::from_secs(120));
    let (state1, _) = task(&array, 1);
    assert_eq!(state1, "CANCELLED", "task 1");
    let (state3, code3) = task(&array, 3);
    assert_eq!(
        (state3.as_str(), code3.as_str()),
        ("FAILED", "1:0"),
        "task 3 holds the failing row"
    );
    assert_eq!(task(&array, 2), ("COMPLETED".into(), "0:0".into()));
    // The merge ran anyway (afterany) and holds every run but the killed task's second.
    let first = lines(&out);
    assert_eq!(first.len(), 7, "{first:?}");
    for (id, line) in &first {
        assert_eq!(want.get(id), Some(line), "run {id}");
    }

    // Resubmitting the same scripts reruns what is missing; nothing is lost or duplicated.
    let (array2, merge2) = submit(&sd);
    wait_for(&[&array2, &merge2], Duration::from_secs(120));
    assert_eq!(task(&array2, 1).0, "COMPLETED");
    assert_eq!(lines(&out), want, "merged table against the local run");
    assert_eq!(lines(&shard1).len(), 2, "shard 1: its two runs, once each");
}
