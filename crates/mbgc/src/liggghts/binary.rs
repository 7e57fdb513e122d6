//! Finding and running the LIGGGHTS executable.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::{Error, Result};

/// Names LIGGGHTS is installed under: Debian's package, and the default of a source build.
const BINARY_NAMES: [&str; 2] = ["liggghts", "lmp_auto"];

/// The MPI launcher (Debian: Open MPI's, a dependency of the `liggghts` package).
pub const MPIRUN: &str = "mpirun";

/// The LIGGGHTS executable on `PATH`, or None when LIGGGHTS is not installed.
pub fn find_binary() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|dir| BINARY_NAMES.iter().map(move |name| dir.join(name)))
        .find(|p| is_executable(p))
}

fn is_executable(p: &Path) -> bool {
    let Ok(meta) = std::fs::metadata(p) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        meta.is_file() && meta.permissions().mode() & 0o111 != 0
    }
    #[cfg(not(unix))]
    {
        meta.is_file()
    }
}

/// Runs LIGGGHTS on the input script `input` in `dir` (one process, one thread), writing the log
/// to `log`; an error quotes the log's ERROR line.
pub fn run_deck(binary: &Path, dir: &Path, input: &str, log: &str) -> Result<()> {
    run_deck_on(binary, dir, input, log, 1)
}

/// [`run_deck`] on `ranks` MPI processes (`mpirun -np ranks`, Open MPI's launcher of Debian's
/// LIGGGHTS) when `ranks` > 1.
pub fn run_deck_on(binary: &Path, dir: &Path, input: &str, log: &str, ranks: usize) -> Result<()> {
    // `-screen none` makes LIGGGHTS 3.8 crash in some fixes, so the screen goes to /dev/null and
    // everything is read from the log.
    let args = ["-in", input, "-log", log, "-screen", "/dev/null"];
    let mut cmd = if ranks > 1 {
        let mut c = Command::new(MPIRUN);
        // Inside a Slurm task Open MPI counts its slots from the task count, and several runs at
        // once would each bind their ranks to the same first cores: the caller sizes the runs
        // to the cores it has, so neither limit applies.
        c.args([
            "-np",
            &ranks.to_string(),
            "--oversubscribe",
            "--bind-to",
            "none",
        ])
        .arg(binary)
        .args(args)
        // Open MPI refuses root unless told twice; containers and CI run as root.
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        // Its shared-memory transport copies large messages with process_vm_readv (CMA), which
        // a container without ptrace rights refuses ("Read -1 ... errno = 1", open-mpi/ompi
        // #4948) and the run aborts; copying through the shared segment works everywhere and
        // gives the same numbers.
        .env("OMPI_MCA_btl_vader_single_copy_mechanism", "none");
        c
    } else {
        let mut c = Command::new(binary);
        c.args(args);
        c
    };
    let out = cmd
        .current_dir(dir)
        .env("OMP_NUM_THREADS", "1")
        .output()
        .map_err(|e| {
            let what = if ranks > 1 { MPIRUN } else { "LIGGGHTS" };
            Error::invalid(format!(
                "cannot start {what} ({}): {e}",
                if ranks > 1 {
                    MPIRUN.to_string()
                } else {
                    binary.display().to_string()
                }
            ))
        })?;
    if out.status.success() {
        return Ok(());
    }
    let log_path = dir.join(log);
    // LIGGGHTS may print garbage bytes after an error message.
    let log_text =
        String::from_utf8_lossy(&std::fs::read(&log_path).unwrap_or_default()).into_owned();
    let error_line = log_text
        .lines()
        .find(|l| l.starts_with("ERROR"))
        .map(str::to_owned)
        .unwrap_or_else(|| {
            let stderr = String::from_utf8_lossy(&out.stderr);
            let tail: Vec<&str> = stderr.lines().rev().take(5).collect();
            tail.into_iter().rev().collect::<Vec<_>>().join(" | ")
        });
    Err(Error::invalid(format!(
        "LIGGGHTS ({}) failed with {} in {}: {}",
        binary.display(),
        out.status,
        dir.display(),
        if error_line.is_empty() {
            format!("no ERROR line in {}", log_path.display())
        } else {
            error_line
        }
    )))
}

/// The MPI launcher, or an error saying how to install it.
pub fn require_mpirun() -> Result<PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .map(|dir| dir.join(MPIRUN))
        .find(|p| is_executable(p))
        .ok_or_else(|| {
            Error::invalid(format!(
                "--mpi: {MPIRUN} not found on PATH (Debian: apt-get install openmpi-bin)"
            ))
        })
}

/// The LIGGGHTS executable, or an error saying how to install it.
pub fn require_binary() -> Result<PathBuf> {
    find_binary().ok_or_else(|| {
        Error::invalid(format!(
            "LIGGGHTS not found: expected one of {BINARY_NAMES:?} on PATH \
             (Debian: apt-get install liggghts)"
        ))
    })
}
