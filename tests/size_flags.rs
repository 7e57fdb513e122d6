//! Every size a user gives is bounded with a message naming the flag and its range: nothing
//! aborts on an allocation or runs for days because a zero too many was typed.

mod common;

use common::{fails, s};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::path::Path;

/// A huge value and zero for each size flag: a clean refusal naming the flag, no panic, no
/// abort (exit code 1, not 134).
#[test]
fn huge_and_zero_sizes_are_refused_by_name() {
    let huge = "100000000000000";
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "calibrate",
                "--material",
                "examples/gravel.toml",
                "--bayes",
                "--samples",
                huge,
            ],
            "--samples",
        ),
        (
            vec![
                "calibrate",
                "--material",
                "examples/gravel.toml",
                "--starts",
                huge,
            ],
            "--starts",
        ),
        (
            vec![
                "calibrate",
                "--material",
                "examples/gravel.toml",
                "--starts",
                "0",
            ],
            "--starts",
        ),
        (
            vec![
                "diagnose",
                "--measurements",
                "examples/measurements/control.toml",
                "--samples",
                huge,
            ],
            "--samples",
        ),
        (
            vec![
                "diagnose",
                "--measurements",
                "examples/measurements/control.toml",
                "--starts",
                huge,
            ],
            "--starts",
        ),
        (
            vec![
                "sensitivity",
                "sobol",
                "--model",
                "models/diagnose_local.json",
                "--samples",
                "64",
                "--bootstrap",
                huge,
            ],
            "--bootstrap",
        ),
        (
            vec![
                "sensitivity",
                "sobol",
                "--model",
                "models/diagnose_local.json",
                "--samples",
                huge,
            ],
            "--samples",
        ),
        (
            vec![
                "sample", "--method", "sobol", "--dim", "3", "--n", huge, "--out", "x.csv",
            ],
            "--n",
        ),
    ];
    for (args, flag) in cases {
        let o = common::mbgc(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let e = fails(&args);
        assert!(e.contains(flag), "{args:?}: {e}");
    }
    let dir = tempfile::tempdir().unwrap();
    for flag in size_flags(dir.path()) {
        if flag.min == 0 {
            continue;
        }
        let value = (flag.min - 1).to_string();
        refused(&flag, &value, dir.path());
    }
}

/// A size flag of some command: the command line without it, and the range it allows (as its
/// refusal states it).
struct SizeFlag {
    args: Vec<String>,
    flag: &'static str,
    min: u64,
    max: u64,
}

/// Every size flag of the commands that sample, simulate or fit, with a command line that is
/// otherwise valid; outputs go to `dir`.
fn size_flags(dir: &Path) -> Vec<SizeFlag> {
    let out = dir.join("out");
    let fit: Vec<String> = [
        "fit",
        "--data",
        "training_data/shear_box.csv",
        "--inputs",
        "mu_pp,mu_r_pp",
        "--targets",
        "shear_angle",
        "--no-figures",
        "--out",
        s(&out.join("m.json")),
    ]
    .map(String::from)
    .to_vec();
    let train: Vec<String> = [
        "train",
        "--space",
        "examples/space_shear_box.toml",
        "--experiment",
        "shear-box",
        "--out-dir",
        s(&out),
    ]
    .map(String::from)
    .to_vec();
    let train_n: Vec<String> = train
        .iter()
        .cloned()
        .chain(["--n".to_string(), "20".to_string()])
        .collect();
    let sample: Vec<String> = [
        "sample",
        "--method",
        "fssf-f",
        "--dim",
        "3",
        "--n",
        "10",
        "--out",
        s(&out.join("d.csv")),
    ]
    .map(String::from)
    .to_vec();
    let flag = |args: &Vec<String>, flag, min, max| SizeFlag {
        args: args.clone(),
        flag,
        min,
        max,
    };
    vec![
        flag(&fit, "--population", 8, 1_000_000),
        flag(&fit, "--max-length", 1, 10_000),
        flag(&fit, "--generations", 1, 1_000_000),
        flag(&fit, "--restarts", 1, 1_000),
        // At most the population (default 5000).
        flag(&fit, "--tournament", 1, 5_000),
        flag(&fit, "--islands", 1, 1_000),
        flag(&train, "--n", 5, 100_000),
        flag(&train_n, "--validation", 0, 100_000),
        flag(&train_n, "--population", 8, 1_000_000),
        flag(&train_n, "--max-length", 1, 10_000),
        flag(&train_n, "--generations", 1, 1_000_000),
        flag(&train_n, "--restarts", 1, 1_000),
        // One per new point; 50 000 000 values in 3 dimensions.
        flag(&sample, "--fssf-candidates", 10, 16_666_666),
    ]
}

/// `flag value` must be refused at once, by exit code 1 (not an abort), naming the flag and its
/// range, before anything is written (a train must not sample or simulate first).
fn refused(flag: &SizeFlag, value: &str, dir: &Path) {
    let mut args: Vec<&str> = flag.args.iter().map(String::as_str).collect();
    args.extend([flag.flag, value]);
    let o = common::within(60, &args);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
    assert!(!e.contains("panicked"), "{args:?}: {e}");
    assert!(
        e.contains(&format!("{} {value}", flag.flag)),
        "{args:?} does not name the flag: {e}"
    );
    let range = format!("expected {} to {}", flag.min, flag.max);
    assert!(e.contains(&range), "{args:?} does not say {range}: {e}");
    assert!(
        !dir.join("out").exists(),
        "{args:?} wrote {} before refusing",
        dir.join("out").display()
    );
}

/// Any value above a size flag's range, from one past it to u64::MAX (1e11 among them), is
/// refused by name with the range: no abort on an allocation, no search that runs for days, no
/// train that simulates before it refuses.
#[test]
fn every_size_flag_refuses_every_value_above_its_range() {
    let dir = tempfile::tempdir().unwrap();
    let flags = size_flags(dir.path());
    for f in &flags {
        refused(f, "100000000000", dir.path());
    }
    let mut runner = TestRunner::new_with_rng(
        Config {
            cases: 6,
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::deterministic_rng(RngAlgorithm::ChaCha),
    );
    runner
        .run(&(0u32..64, any::<u64>()), |(bits, r)| {
            for f in &flags {
                // Above the range by a factor up to 2^64 (saturating at u64::MAX).
                let above = (f.max + 1).saturating_add(r >> bits.min(63));
                refused(f, &above.to_string(), dir.path());
                refused(f, &(f.max + 1).to_string(), dir.path());
            }
            Ok(())
        })
        .unwrap();
}
