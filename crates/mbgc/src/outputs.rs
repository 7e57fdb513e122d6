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

/// Whether two existing paths are one file under two names (hard links, bind mounts): the same
/// device and inode.
#[cfg(unix)]
fn same_inode(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_inode(_: &Path, _: &Path) -> bool {
    false
}

/// Whether two paths name the same file once written (symlinks and `..` resolved, hard links
/// recognised).
pub fn same_path(a: &Path, b: &Path) -> bool {
    resolved(a) == resolved(b) || same_inode(a, b)
}

/// Refuses an output (`option`, e.g. `--out`) that is the same file as one of the named inputs.
pub fn refuse_overwriting_inputs(option: &str, out: &Path, inputs: &[(&str, &Path)]) -> Result<()> {
    for (name, input) in inputs {
        if same_path(out, input) {
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

/// Refuses a folder of figures (`option`, e.g. `--figures`) that holds one of the named inputs
/// as an image file (`.svg`, `.png`): a figure of that name would replace it. Inputs of other
/// kinds cannot collide with a figure's name and are allowed there.
pub fn refuse_figures_over_inputs(
    option: &str,
    dir: &Path,
    inputs: &[(&str, &Path)],
) -> Result<()> {
    let dir = resolved(dir);
    for (name, input) in inputs {
        let image = input
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("svg") || e.eq_ignore_ascii_case("png"));
        let inside = resolved(input).parent() == Some(dir.as_path());
        if image && inside {
            return Err(Error::invalid(format!(
                "{option} {}: holds the input {name} ({}), which a figure of that name would \
                 replace; expected another folder (mbgc never overwrites its own input)",
                dir.display(),
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
            let hard = dir.path().join("sub").join("hard.svg");
            std::fs::hard_link(&data, &hard).unwrap();
            assert!(refuse_overwriting_inputs("--plot", &hard, &[("--data", &data)]).is_err());
            assert!(same_path(&hard, &data));
        }
        // A folder of figures that holds an input with an image's name.
        let svg = dir.path().join("exponents.svg");
        std::fs::write(&svg, "x\n1\n").unwrap();
        let e = refuse_figures_over_inputs("--figures", dir.path(), &[("--data", &svg)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("--figures") && e.contains("--data"), "{e}");
        refuse_figures_over_inputs("--figures", dir.path(), &[("--data", &data)]).unwrap();
        refuse_figures_over_inputs("--figures", &dir.path().join("sub"), &[("--data", &svg)])
            .unwrap();
        let fresh = dir.path().join("model.json");
        refuse_overwriting_inputs("--out", &fresh, &[("--data", &data)]).unwrap();
        std::fs::write(&fresh, "{}").unwrap();
        refuse_overwriting_inputs("--out", &fresh, &[("--data", &data)]).unwrap();
    }
}
