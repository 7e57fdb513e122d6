//! A campaign as a Slurm job array: one array task per shard, each resuming its own shard table
//! (`mbgc simulate --shard K/N`), and a merge job that runs after the whole array, whatever its
//! tasks' exit codes (`afterany`), so that the merged table always holds every finished run.
//! A task that failed or was killed is rerun by submitting the same scripts again: the tasks
//! whose shard is complete find nothing to do, the others resume, and the merge runs again.
//!
//! Everything here writes text; [`submit`] is the only function that talks to Slurm.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::error::{write_atomic, Error, Result};

/// File name of the array job script: one task per shard.
pub const ARRAY_SCRIPT: &str = "array.sbatch";
/// File name of the merge job script, run after the whole array (`afterany`).
pub const MERGE_SCRIPT: &str = "merge.sbatch";
/// File name of the script that submits the array and then the merge job depending on it.
pub const SUBMIT_SCRIPT: &str = "submit.sh";

/// What the scripts run and how Slurm is asked for resources.
#[derive(Debug, Clone, PartialEq)]
pub struct JobArray {
    /// Absolute path of the `mbgc` executable the jobs run.
    pub mbgc: PathBuf,
    /// Directory the jobs start in (relative paths of the arguments are read from it).
    pub workdir: PathBuf,
    /// `mbgc simulate` arguments every task shares (without `--out`, `--shard`, `--threads`).
    pub simulate_args: Vec<String>,
    /// The merged table.
    pub out: PathBuf,
    /// Where the shard tables, logs and scripts go.
    pub dir: PathBuf,
    /// Number of shards N, one array task each (`--array=1-N`).
    pub shards: usize,
    /// Slurm job name of the array; the merge job gets `<name>-merge`.
    pub job_name: String,
    /// Slurm partition (`--partition`), or the cluster's default.
    pub partition: Option<String>,
    /// `--time` as Slurm reads it.
    pub time: Option<String>,
    /// CPUs Slurm allocates per array task (`--cpus-per-task`).
    pub cpus_per_task: usize,
    /// Threads per run's MPI processes: a task runs `cpus_per_task / mpi` runs at a time.
    pub mpi: usize,
}

/// A word for `sh`/`bash`: single-quoted unless it is plainly safe.
pub fn sh_quote(s: &str) -> String {
    let safe = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c));
    if safe {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// Refuses a `--time` Slurm would not read: minutes, MM:SS, HH:MM:SS, D-HH, D-HH:MM or
/// D-HH:MM:SS, whole numbers only.
pub fn check_time(t: &str) -> Result<()> {
    let bad = || {
        Error::invalid(format!(
            "--time {t}: expected a Slurm time limit: minutes, MM:SS, HH:MM:SS, D-HH, D-HH:MM or \
             D-HH:MM:SS (e.g. 2:00:00)"
        ))
    };
    let digits = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_ascii_digit());
    let (days, rest) = match t.split_once('-') {
        Some((d, r)) => (Some(d), r),
        None => (None, t),
    };
    let parts: Vec<&str> = rest.split(':').collect();
    let ok = parts.iter().all(|p| digits(p))
        && days.is_none_or(digits)
        && (1..=3).contains(&parts.len());
    if ok {
        Ok(())
    } else {
        Err(bad())
    }
}

impl JobArray {
    /// The table of shard `k` (1-based): `<dir>/shard_<k>.csv`.
    pub fn shard_table(&self, k: usize) -> PathBuf {
        self.dir.join(format!("shard_{k}.csv"))
    }

    fn header(&self, s: &mut String, name: &str, log: &str) {
        let _ = writeln!(s, "#!/bin/bash");
        let _ = writeln!(s, "#SBATCH --job-name={}", sh_quote(name));
        // `%` starts a Slurm filename pattern: a literal one in the path is written `%%`.
        let logs = self
            .dir
            .join("logs")
            .display()
            .to_string()
            .replace('%', "%%");
        let out = format!("{logs}/{log}");
        let _ = writeln!(s, "#SBATCH --output={}", sh_quote(&out));
        // A resubmission appends to the logs of the earlier attempt instead of erasing them.
        let _ = writeln!(s, "#SBATCH --open-mode=append");
        if let Some(p) = &self.partition {
            let _ = writeln!(s, "#SBATCH --partition={}", sh_quote(p));
        }
        if let Some(t) = &self.time {
            let _ = writeln!(s, "#SBATCH --time={t}");
        }
    }

    /// The array script: task K runs shard K of N into its own table.
    pub fn array_script(&self) -> String {
        let mut s = String::new();
        self.header(&mut s, &self.job_name, "shard_%a.out");
        let _ = writeln!(s, "#SBATCH --array=1-{}", self.shards);
        let _ = writeln!(s, "#SBATCH --ntasks=1");
        let _ = writeln!(s, "#SBATCH --cpus-per-task={}", self.cpus_per_task);
        let threads = (self.cpus_per_task / self.mpi.max(1)).max(1);
        let _ = writeln!(
            s,
            "# Shard K of {n} of the campaign into its own table; a rerun resumes it. Exit code: \
             mbgc's (1 when a run of the shard failed).\nset -euo pipefail\ncd {}\nK=\"$SLURM_ARRAY_TASK_ID\"",
            sh_quote(&self.workdir.display().to_string()),
            n = self.shards
        );
        let mut cmd = vec![
            sh_quote(&self.mbgc.display().to_string()),
            "simulate".into(),
        ];
        cmd.extend(self.simulate_args.iter().map(|a| sh_quote(a)));
        cmd.push("--out".into());
        cmd.push(format!(
            "{}/shard_\"$K\".csv",
            sh_quote(&self.dir.display().to_string())
        ));
        cmd.push("--shard".into());
        cmd.push(format!("\"$K\"/{}", self.shards));
        cmd.push("--threads".into());
        cmd.push(threads.to_string());
        let _ = writeln!(s, "exec {}", cmd.join(" \\\n  "));
        s
    }

    /// The merge script: every shard table there is, merged into the campaign table, then its
    /// status (runs still missing are those of failed or killed tasks).
    pub fn merge_script(&self) -> String {
        let mut s = String::new();
        self.header(&mut s, &format!("{}-merge", self.job_name), "merge.out");
        let _ = writeln!(s, "#SBATCH --ntasks=1\n#SBATCH --cpus-per-task=1");
        let mbgc = sh_quote(&self.mbgc.display().to_string());
        let _ = writeln!(
            s,
            "set -euo pipefail\ncd {}\nshopt -s nullglob\ntables=({}/shard_*.csv)\n\
             if [ ${{#tables[@]}} -eq 0 ]; then echo \"no shard table yet\" >&2; exit 1; fi\n\
             {mbgc} campaign merge \"${{tables[@]}}\" --out {}\n\
             {mbgc} campaign status {} --design {}",
            sh_quote(&self.workdir.display().to_string()),
            sh_quote(&self.dir.display().to_string()),
            sh_quote(&self.out.display().to_string()),
            sh_quote(&self.out.display().to_string()),
            sh_quote(&self.design_arg()),
        );
        s
    }

    fn design_arg(&self) -> String {
        self.simulate_args
            .iter()
            .position(|a| a == "--design")
            .and_then(|k| self.simulate_args.get(k + 1))
            .cloned()
            .unwrap_or_default()
    }

    /// Submits the array, then the merge after it (`afterany`); prints both job ids.
    pub fn submit_script(&self) -> String {
        format!(
            "#!/bin/bash\n\
             # Submits the array and its merge; run it again to rerun failed or killed tasks\n\
             # (finished shards have nothing left to do).\n\
             set -euo pipefail\n\
             cd \"$(dirname \"$0\")\"\n\
             array=$(sbatch --parsable {ARRAY_SCRIPT})\n\
             array=${{array%%;*}}\n\
             merge=$(sbatch --parsable --dependency=afterany:\"$array\" {MERGE_SCRIPT})\n\
             merge=${{merge%%;*}}\n\
             echo \"array $array merge $merge\"\n"
        )
    }

    /// Writes the three scripts (and the logs directory) into `dir`.
    pub fn write(&self) -> Result<()> {
        let logs = self.dir.join("logs");
        std::fs::create_dir_all(&logs).map_err(|e| Error::io(&logs, e))?;
        for (name, text) in [
            (ARRAY_SCRIPT, self.array_script()),
            (MERGE_SCRIPT, self.merge_script()),
            (SUBMIT_SCRIPT, self.submit_script()),
        ] {
            let path = self.dir.join(name);
            write_atomic(&path, text.as_bytes())?;
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755))
                    .map_err(|e| Error::io(&path, e))?;
            }
        }
        Ok(())
    }
}

/// Runs `dir/submit.sh`; returns (array job id, merge job id).
pub fn submit(dir: &Path) -> Result<(String, String)> {
    let script = dir.join(SUBMIT_SCRIPT);
    let out = Command::new("bash")
        .arg(&script)
        .output()
        .map_err(|e| Error::invalid(format!("cannot run {}: {e}", script.display())))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(Error::invalid(format!(
            "{} failed ({}): {}{}",
            script.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim(),
            if std::process::Command::new("sbatch")
                .arg("--version")
                .output()
                .is_err()
            {
                " (sbatch is not on PATH: is this a Slurm login node?)"
            } else {
                ""
            }
        )));
    }
    let w: Vec<&str> = stdout.split_whitespace().collect();
    match w.as_slice() {
        ["array", a, "merge", m] => Ok((a.to_string(), m.to_string())),
        _ => Err(Error::invalid(format!(
            "{}: expected 'array ID merge ID', found {stdout:?}",
            script.display()
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job() -> JobArray {
        JobArray {
            mbgc: "/opt/mbgc/bin/mbgc".into(),
            workdir: "/home/u/my runs".into(),
            simulate_args: vec![
                "--design".into(),
                "d.csv".into(),
                "--experiment".into(),
                "shear-box".into(),
                "--set".into(),
                "note=it's".into(),
            ],
            out: "/home/u/my runs/campaign.csv".into(),
            dir: "/home/u/my runs/campaign.csv.slurm".into(),
            shards: 4,
            job_name: "mbgc-campaign".into(),
            partition: Some("short".into()),
            time: Some("2:00:00".into()),
            cpus_per_task: 4,
            mpi: 2,
        }
    }

    #[test]
    fn the_array_runs_shard_k_of_n_into_its_own_table_with_quoted_paths() {
        let s = job().array_script();
        assert!(s.contains("#SBATCH --array=1-4\n"), "{s}");
        assert!(s.contains(
            "#SBATCH --output='/home/u/my runs/campaign.csv.slurm/logs/shard_%a.out'\n\
             #SBATCH --open-mode=append\n"
        ));
        let pct = JobArray {
            dir: "/scratch/100%/c.slurm".into(),
            ..job()
        };
        assert!(pct
            .array_script()
            .contains("--output=/scratch/100%%/c.slurm/logs/shard_%a.out"));
        assert!(s.contains("#SBATCH --partition=short\n#SBATCH --time=2:00:00\n"));
        assert!(s.contains("cd '/home/u/my runs'\n"), "{s}");
        assert!(s.contains("'/home/u/my runs/campaign.csv.slurm'/shard_\"$K\".csv"));
        assert!(s.contains("--shard \\\n  \"$K\"/4"), "{s}");
        assert!(s.contains("--threads \\\n  2"), "{s}");
        assert!(s.contains("'note=it'\\''s'"), "{s}");
        let m = job().merge_script();
        assert!(m.contains("campaign merge \"${tables[@]}\" --out '/home/u/my runs/campaign.csv'"));
        assert!(m.contains("--design d.csv"), "{m}");
        let sub = job().submit_script();
        assert!(sub.contains("--dependency=afterany:\"$array\" merge.sbatch"));
    }

    #[test]
    fn time_limits_are_checked_as_slurm_reads_them() {
        for ok in ["30", "30:00", "2:00:00", "1-12", "1-12:30", "1-12:30:00"] {
            assert!(check_time(ok).is_ok(), "{ok}");
        }
        for bad in ["", "2h", "1:2:3:4", "-5", "1-", "a-1", "1.5"] {
            let e = check_time(bad).unwrap_err().to_string();
            assert!(e.contains("--time"), "{bad}: {e}");
        }
    }
}
