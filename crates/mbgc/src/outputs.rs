//! Output paths checked before anything runs: no command writes over one of its own inputs
//! (a `fit --out` onto the campaign table would destroy the DEM results it was fitted on).

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// The path a file would have once written: symlinks and `..` resolved through the existing
/// part of the path, so two spellings of one file compare equal.
fn resolved(p: &Path) -> PathBuf {
    if let Ok(c) = std::fs::canonicalize(p) {
        return c;
    }
    let parent = match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    match (std::fs::canonicalize(parent), p.file_name()) {
        (Ok(dir), Some(name)) => dir.join(name),
        _ => p.to_path_buf(),
    }
}

/// Whether two paths name the same file once written (symlinks and `..` resolved).
pub fn same_path(a: &Path, b: &Path) -> bool {
    resolved(a) == resolved(b)
}

/// Refuses an output (`option`, e.g. `--out`) that is the same file as one of the named inputs.
pub fn refuse_overwriting_inputs(option: &str, out: &Path, inputs: &[(&str, &Path)]) -> Result<()> {
    let target = resolved(out);
    for (name, input) in inputs {
        if resolved(input) == target {
            return Err(Error::invalid(format!(
                "{option} {}: is the input {name} ({}); expected another path (mbgc never \
                 overwrites its own input)",
                out.display(),
                input.display()
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_output_that_is_an_input_under_another_spelling_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("run.csv");
        std::fs::write(&data, "x\n1\n").unwrap();
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        let other = dir.path().join("sub").join("..").join("run.csv");
        let e = refuse_overwriting_inputs("--out", &other, &[("--data", &data)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("--out") && e.contains("--data"), "{e}");
        #[cfg(unix)]
        {
            let link = dir.path().join("link.csv");
            std::os::unix::fs::symlink(&data, &link).unwrap();
            assert!(refuse_overwriting_inputs("--out", &link, &[("--data", &data)]).is_err());
        }
        let fresh = dir.path().join("model.json");
        refuse_overwriting_inputs("--out", &fresh, &[("--data", &data)]).unwrap();
        std::fs::write(&fresh, "{}").unwrap();
        refuse_overwriting_inputs("--out", &fresh, &[("--data", &data)]).unwrap();
    }
}
