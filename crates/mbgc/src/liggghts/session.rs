//! A LIGGGHTS process driven command by command through its standard input, so that its timed
//! runs can alternate with the caller's work. On a shared machine whose speed drifts by tens of
//! percent within minutes, a benchmark that runs one code after the other measures the drift as
//! much as the codes (`docs/dem_benchmark.md`: three invocations of the settled box gave ratios
//! from 2.27 to 3.37); alternating segments lets a slow spell hit both codes alike.
//!
//! LIGGGHTS reads its input from standard input when given no `-in`, and writes its screen to
//! standard output. When that is a pipe the C library buffers it fully, so the process runs
//! under `stdbuf -oL` (GNU coreutils) to flush each line, and every command is followed by a
//! `print` of a numbered mark: the screen lines up to the mark are that command's output.

use std::io::{BufRead, BufReader, Lines, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

use crate::{Error, Result};

/// The line-buffering wrapper (GNU coreutils).
const STDBUF: &str = "stdbuf";

/// A running LIGGGHTS process awaiting commands.
pub struct Session {
    child: Child,
    stdin: Option<ChildStdin>,
    lines: Lines<BufReader<ChildStdout>>,
    marks: u64,
    dir: PathBuf,
    log: String,
}

impl Session {
    /// Starts `binary` in `dir` (one process, one thread), its log in `dir/log`.
    pub fn start(binary: &Path, dir: &Path, log: &str) -> Result<Session> {
        let mut child = Command::new(STDBUF)
            .args(["-oL", "-eL"])
            .arg(binary)
            .args(["-echo", "none", "-log", log])
            .current_dir(dir)
            .env("OMP_NUM_THREADS", "1")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| {
                Error::invalid(format!(
                    "cannot start LIGGGHTS ({}) under {STDBUF} (GNU coreutils, needed to read \
                     its screen line by line): {e}",
                    binary.display()
                ))
            })?;
        let stdin = child.stdin.take();
        let stdout = child
            .stdout
            .take()
            .ok_or_else(|| Error::invalid("LIGGGHTS: no standard output to read"))?;
        Ok(Session {
            child,
            stdin,
            lines: BufReader::new(stdout).lines(),
            marks: 0,
            dir: dir.to_path_buf(),
            log: log.to_string(),
        })
    }

    /// Sends `commands` (one or more input lines) and returns the screen output they printed,
    /// once all of them have run. An error names the log and quotes its ERROR line.
    pub fn command(&mut self, commands: &str) -> Result<String> {
        self.marks += 1;
        let mark = format!("mbgc-session-mark-{}", self.marks);
        let stdin = self
            .stdin
            .as_mut()
            .ok_or_else(|| Error::invalid("LIGGGHTS session: already finished"))?;
        let sent = writeln!(stdin, "{}\nprint \"{mark}\"", commands.trim_end())
            .and_then(|()| stdin.flush());
        if sent.is_err() {
            return Err(self.died(commands));
        }
        let mut out = String::new();
        loop {
            match self.lines.next() {
                Some(Ok(line)) if line.trim() == mark => return Ok(out),
                Some(Ok(line)) => {
                    out.push_str(&line);
                    out.push('\n');
                }
                Some(Err(_)) | None => return Err(self.died(commands)),
            }
        }
    }

    /// Closes the input and waits for LIGGGHTS to exit.
    pub fn finish(mut self) -> Result<()> {
        drop(self.stdin.take());
        let status = self
            .child
            .wait()
            .map_err(|e| Error::invalid(format!("LIGGGHTS session: waiting for it: {e}")))?;
        if status.success() {
            Ok(())
        } else {
            Err(self.died("the end of its input"))
        }
    }

    /// The error of a process that stopped answering: its log's ERROR line when there is one.
    fn died(&mut self, commands: &str) -> Error {
        drop(self.stdin.take());
        let _ = self.child.wait();
        let log = self.dir.join(&self.log);
        let text = String::from_utf8_lossy(&std::fs::read(&log).unwrap_or_default()).into_owned();
        let error = text
            .lines()
            .find(|l| l.starts_with("ERROR"))
            .map(str::to_owned)
            .unwrap_or_else(|| format!("no ERROR line in {}", log.display()));
        let first = commands.lines().next().unwrap_or("");
        Error::invalid(format!(
            "LIGGGHTS in {} stopped at \"{first}\": {error}",
            self.dir.display()
        ))
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        // A session left early (an error on the caller's side) must not leave LIGGGHTS running.
        if self.stdin.is_some() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// The seconds of the line "Loop time of T on 1 procs for `steps` steps with `atoms` atoms" in
/// `output` (one run's screen output), checked against the run it should belong to.
pub fn loop_time(output: &str, steps: u64, atoms: usize) -> Result<f64> {
    let line = output
        .lines()
        .rev()
        .find(|l| l.starts_with("Loop time of "))
        .ok_or_else(|| {
            Error::invalid(format!(
                "LIGGGHTS printed no \"Loop time\" line for a run of {steps} steps"
            ))
        })?;
    let w: Vec<&str> = line.split_whitespace().collect();
    let t: f64 = w.get(3).and_then(|s| s.parse().ok()).unwrap_or(f64::NAN);
    let ok = t > 0.0
        && w.get(8).and_then(|s| s.parse::<u64>().ok()) == Some(steps)
        && w.get(11).and_then(|s| s.parse::<usize>().ok()) == Some(atoms);
    if ok {
        Ok(t)
    } else {
        Err(Error::invalid(format!(
            "LIGGGHTS: expected \"Loop time of T on 1 procs for {steps} steps with {atoms} atoms\", \
             found {line:?}"
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stand-in for LIGGGHTS that speaks its screen protocol: `run N` prints a loop time,
    /// `print "x"` prints x, `fail` exits with an ERROR line in the log.
    fn fake(dir: &Path) -> PathBuf {
        let p = dir.join("fake-liggghts");
        std::fs::write(
            &p,
            "#!/bin/sh\n\
             echo 'LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, fake)' > log.fake\n\
             while read -r cmd rest; do\n\
             case \"$cmd\" in\n\
             run) echo \"Loop time of 0.25 on 1 procs for $rest steps with 10 atoms\" ;;\n\
             print) echo \"$rest\" | tr -d '\"' ;;\n\
             fail) echo 'ERROR: fake failure (fake.cpp:1)' >> log.fake; exit 1 ;;\n\
             esac\n\
             done\n",
        )
        .unwrap();
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
        }
        p
    }

    #[test]
    fn commands_alternate_with_the_caller_and_a_failure_names_the_error() {
        let dir = tempfile::tempdir().unwrap();
        let bin = fake(dir.path());
        let mut s = Session::start(&bin, dir.path(), "log.fake").unwrap();
        for steps in [100u64, 200, 300] {
            let out = s.command(&format!("run {steps}")).unwrap();
            assert_eq!(loop_time(&out, steps, 10).unwrap(), 0.25, "{out}");
            // The output of one command is not the next one's.
            assert!(loop_time(&out, steps + 1, 10).is_err());
        }
        assert_eq!(s.command("units si").unwrap(), "");
        let e = s.command("fail").unwrap_err().to_string();
        assert!(
            e.contains("stopped at \"fail\"") && e.contains("ERROR: fake failure"),
            "{e}"
        );
        let s = Session::start(&bin, dir.path(), "log.fake").unwrap();
        s.finish().unwrap();
    }
}
