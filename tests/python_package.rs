//! The Python package (crates/mbgc-py) as a user installs it: a fresh virtual environment, the
//! package built by maturin and installed with pip, and its pytest suite run against the `mbgc`
//! binary of this build (MBGC_BIN), so that Python and the command line must give the same
//! numbers.
//!
//! Creating the environment and installing the pinned test tools needs Python's `venv` and
//! PyPI. Where either is missing the test says why and passes, unless MBGC_REQUIRE_PYTHON is
//! set (CI sets it), as tests/gp_cli.rs does with MBGC_REQUIRE_SYMPY. Building the package and
//! its tests are never skipped once the environment exists.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The versions the environment gets (the package itself asks only for numpy >= 1.21 and
/// pandas >= 1.3; these are a known good set for Python 3.11, the CI machine's).
const PINS: [&str; 5] = [
    "maturin==1.15.0",
    "pytest==9.0.3",
    "numpy==2.4.6",
    "pandas==3.0.6",
    "sympy==1.14.0",
];

/// Runs `c`; its standard output, or its whole output when it fails (or cannot start).
fn run(c: &mut Command) -> Result<String, String> {
    let shown = format!("{c:?}");
    let t0 = Instant::now();
    let out = c
        .output()
        .map_err(|e| format!("{shown}: cannot start: {e}"))?;
    eprintln!("{:6.1} s  {shown}", t0.elapsed().as_secs_f64());
    if out.status.success() {
        return Ok(String::from_utf8_lossy(&out.stdout).into_owned());
    }
    Err(format!(
        "{shown}: {}\n{}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    ))
}

/// Passes with the reason when the machine cannot make the environment, unless the environment
/// is required.
fn unavailable(why: &str) {
    assert!(
        std::env::var_os("MBGC_REQUIRE_PYTHON").is_none(),
        "MBGC_REQUIRE_PYTHON is set but the Python environment cannot be made: {why}"
    );
    eprintln!("Python package test skipped: {why}");
}

#[test]
fn the_python_package_builds_installs_and_passes_its_tests() {
    let interpreter = std::env::var("MBGC_PYTHON").unwrap_or_else(|_| "python3".into());
    let dir = tempfile::tempdir().unwrap();
    let venv = dir.path().join("venv");
    if let Err(why) = run(Command::new(&interpreter).arg("-m").arg("venv").arg(&venv)) {
        return unavailable(&why);
    }
    let bin = venv.join("bin");
    // As an activated environment: maturin's build hook runs `maturin` from PATH.
    let path = std::env::join_paths(std::iter::once(bin.clone()).chain(std::env::split_paths(
        &std::env::var_os("PATH").unwrap_or_default(),
    )))
    .unwrap();
    let python = |args: &[&str]| {
        let mut c = Command::new(bin.join("python"));
        c.args(args).env("PATH", &path).env("VIRTUAL_ENV", &venv);
        c
    };
    let pip = |args: &[&str]| {
        let mut c = python(&["-m", "pip", "--disable-pip-version-check", "--no-input"]);
        c.args(args).current_dir(ROOT);
        c
    };
    if let Err(why) = run(pip(&["install", "--quiet"]).args(PINS)) {
        return unavailable(&why);
    }
    // The README's install command, with the maturin pinned above instead of a fresh download,
    // and a target directory of its own: the outer `cargo test` holds target/'s lock.
    let target: PathBuf = Path::new(ROOT).join("target/python");
    run(
        pip(&["install", "--no-build-isolation", "./crates/mbgc-py"])
            .env("CARGO_TARGET_DIR", &target),
    )
    .unwrap_or_else(|e| panic!("the package does not build or install:\n{e}"));
    // Imported from the environment, not from the source tree.
    let scratch = dir.path();
    run(python(&[
        "-c",
        "import mbgc; assert 'site-packages' in mbgc.__file__, mbgc.__file__",
    ])
    .current_dir(scratch))
    .unwrap_or_else(|e| panic!("{e}"));
    let report = run(python(&["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(Path::new(ROOT).join("crates/mbgc-py/tests"))
        .env("MBGC_BIN", env!("CARGO_BIN_EXE_mbgc"))
        .current_dir(scratch))
    .unwrap_or_else(|e| panic!("the package's tests fail:\n{e}"));
    eprintln!("pytest: {}", report.lines().last().unwrap_or_default());
}
