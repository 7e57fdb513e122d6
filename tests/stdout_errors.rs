//! A command whose standard output cannot be written (a full disk, `> /dev/full`) fails with one
//! clean message and exit code 1, never a panic (exit 101, "failed printing to stdout"). A closed
//! pipe (`mbgc ... | head`) still ends the command quietly.

#![cfg(target_os = "linux")]

mod common;

use std::process::{Command, Stdio};

/// Runs `args` in the repository with standard output on /dev/full.
fn into_dev_full(args: &[&str]) -> std::process::Output {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .expect("open /dev/full");
    Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::from(full))
        .stderr(Stdio::piped())
        .output()
        .expect("run mbgc")
}

#[test]
fn a_full_standard_output_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let plot = dir.path().join("sieve.svg");
    let commands: Vec<Vec<&str>> = vec![
        vec!["effects"],
        vec!["effects", "--json"],
        vec![
            "calibrate",
            "--material",
            "examples/gravel.toml",
            "--starts",
            "4",
        ],
        vec![
            "calibrate",
            "--material",
            "examples/gravel.toml",
            "--starts",
            "4",
            "--json",
        ],
        vec![
            "export",
            "--model",
            "models/diagnose_local.json",
            "--format",
            "rust",
        ],
        vec!["psd", "fit", "examples/sieve_gravel_8_16.csv"],
        vec![
            "psd",
            "fit",
            "examples/sieve_gravel_8_16.csv",
            "--plot",
            plot.to_str().unwrap(),
        ],
        vec!["campaign", "status", "training_data/diagnose_local.csv"],
        vec![
            "campaign",
            "status",
            "training_data/diagnose_local.csv",
            "--json",
        ],
        vec![
            "sensitivity",
            "sobol",
            "--model",
            "models/diagnose_local.json",
            "--samples",
            "64",
            "--bootstrap",
            "100",
        ],
        vec![
            "sensitivity",
            "local",
            "--model",
            "models/diagnose_local.json",
            "--at",
            "E_p=5e6,E_w=5e6,rho_p=2600,mu_pp=0.4,d50=8",
        ],
    ];
    for args in &commands {
        let o = into_dev_full(args);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert!(!e.contains("panicked"), "{args:?}: {e}");
        assert!(
            e.contains("mbgc: writing to standard output: No space left on device"),
            "{args:?}: {e}"
        );
        // One message, without the OS's error number.
        assert_eq!(e.matches("writing to standard output").count(), 1, "{e}");
        assert!(!e.contains("os error"), "{args:?}: {e}");
    }
}

/// The same commands still succeed when standard output can be written, and a pipe closed early
/// still ends them quietly.
#[test]
fn a_writable_or_closed_standard_output_is_not_an_error() {
    let out = common::ok(&["effects"]);
    assert!(out.contains("| slot |"), "{out}");
    let mut child = Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .args(["effects"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Close the reading end at once: the first write meets a broken pipe.
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!e.contains("panicked"), "{e}");
    assert!(!e.contains("writing to standard output"), "{e}");
}
