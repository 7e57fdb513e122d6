//! Running the `mbgc` binary from integration tests.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

pub fn mbgc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run mbgc")
}

/// Runs a command that must succeed and returns its standard output.
pub fn ok(args: &[&str]) -> String {
    let o = mbgc(args);
    assert!(
        o.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

/// Runs a command that must fail (without a panic) and returns its error message.
pub fn fails(args: &[&str]) -> String {
    let o = mbgc(args);
    assert!(!o.status.success(), "{args:?} should fail");
    let e = String::from_utf8(o.stderr).unwrap();
    assert!(!e.contains("panicked"), "{e}");
    e
}

pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The Python to check sympy exports with, or None when it cannot import sympy. CI installs sympy
/// and sets MBGC_REQUIRE_SYMPY=1, so there a missing sympy fails instead of skipping the check.
pub fn sympy_python() -> Option<String> {
    let python = std::env::var("MBGC_PYTHON").unwrap_or_else(|_| "python3".into());
    let has_sympy = Command::new(&python)
        .args(["-c", "import sympy"])
        .status()
        .is_ok_and(|s| s.success());
    if has_sympy {
        return Some(python);
    }
    assert!(
        std::env::var("MBGC_REQUIRE_SYMPY").is_err(),
        "MBGC_REQUIRE_SYMPY is set but {python} cannot import sympy"
    );
    eprintln!("sympy not installed: sympy export check skipped");
    None
}

/// Runs `args` (in the repository, as [`mbgc`]) with a deadline: a command that does not end is
/// a failure, not a stuck test suite.
pub fn within(seconds: u64, args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run mbgc");
    let t0 = std::time::Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if t0.elapsed() > std::time::Duration::from_secs(seconds) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{args:?} still running after {seconds} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}
