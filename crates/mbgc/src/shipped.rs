//! What mbgc carries with it, so that a newcomer's first call works from any directory: the
//! shipped metamodels (the default models of a calibration and of a diagnosis) and seed 004's
//! Gravel 8/16 example with its sieve analysis. An explicit model always wins; the example is
//! used only when its path, [`GRAVEL`], does not exist where the call runs, and the caller is
//! given a note saying so.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::material::{Material, PsdSpec};
use crate::metamodel::Metamodel;
use crate::psd::SieveData;

/// The shipped shear-box model (class hertz,mindlin,epsd2).
pub const SHEAR_BOX: &str = "models/shear_box.json";
/// The shipped cohesive shear-box model (class hertz,mindlin,epsd2,sjkr).
pub const SHEAR_BOX_SJKR: &str = "models/shear_box_sjkr.json";
/// The shear-box model trained from K_p 6.5e3 to 9.8e6 (issue 40; docs/metamodel_wide.md).
pub const SHEAR_BOX_WIDE: &str = "models/shear_box_wide.json";
/// Its cohesive companion: the widened base plus a cohesion correction in the contact's pull
/// (class hertz,mindlin,epsd2,sjkr; docs/metamodel_wide.md).
pub const SHEAR_BOX_SJKR_WIDE: &str = "models/shear_box_sjkr_wide.json";
/// The shipped shear-cell model (class hertz,mindlin,epsd2).
pub const SHEAR_CELL: &str = "models/shear_cell.json";
/// The shipped cohesive shear-cell model (class hertz,mindlin,epsd2,sjkr).
pub const SHEAR_CELL_SJKR: &str = "models/shear_cell_sjkr.json";

/// A file of the repository built in: `(its path, its text)`. A macro because `include_str!`
/// takes only a literal, and one entry a line keeps adding a model one line.
macro_rules! built_in {
    ($path:literal) => {
        ($path, include_str!(concat!("../../../", $path)))
    };
}

/// Every shipped model: its path in the repository, which is also the name it is reported
/// under, and the file's text.
const MODELS: &[(&str, &str)] = &[
    built_in!("models/shear_box.json"),
    built_in!("models/shear_box_sjkr.json"),
    built_in!("models/shear_box_wide.json"),
    built_in!("models/shear_box_sjkr_wide.json"),
    built_in!("models/shear_cell.json"),
    built_in!("models/shear_cell_sjkr.json"),
];

/// The models a calibration uses when none is given.
pub const CALIBRATION_MODELS: &[&str] = &[SHEAR_BOX];
/// The models a diagnosis uses when none is given: each experiment's base class and its cohesive
/// extension (the candidate sjkr's model), the shear box's and the shear cell's (for a set with
/// shear-cell samples: each sample is served by its experiment's models).
pub const DIAGNOSIS_MODELS: &[&str] = &[SHEAR_BOX, SHEAR_BOX_SJKR, SHEAR_CELL, SHEAR_CELL_SJKR];

/// The example material's path in the repository.
pub const GRAVEL: &str = "examples/gravel.toml";
const GRAVEL_TOML: &str = include_str!("../../../examples/gravel.toml");
const GRAVEL_SIEVE: &str = "examples/sieve_gravel_8_16.csv";
const GRAVEL_SIEVE_CSV: &str = include_str!("../../../examples/sieve_gravel_8_16.csv");

/// A shipped model's short name: its file stem (`shear_box`).
fn stem(path: &str) -> &str {
    Path::new(path)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or(path)
}

/// The shipped models' short names (`shear_box`, ...), in the order they are listed.
pub fn names() -> Vec<&'static str> {
    MODELS.iter().map(|(path, _)| stem(path)).collect()
}

/// A shipped model by its path in the repository (`models/shear_box.json`) or its short name
/// (`shear_box`), with the name it is reported under (its path).
pub fn model(name: &str) -> Result<(Metamodel, String)> {
    let (path, text) = MODELS
        .iter()
        .find(|(path, _)| name == *path || name == stem(path))
        .ok_or_else(|| {
            Error::invalid(format!(
                "shipped model \"{name}\": expected one of {}",
                names().join(", ")
            ))
        })?;
    Ok((Metamodel::from_json_str(text, path)?, path.to_string()))
}

/// The shipped models of `names` (paths or short names), each with the name it is reported
/// under.
pub fn models(names: &[&str]) -> Result<Vec<(Metamodel, String)>> {
    names.iter().map(|name| model(name)).collect()
}

/// The model files of `paths`, each named by its path; the shipped models of `defaults` when
/// none is given.
pub fn files_or_models(paths: &[PathBuf], defaults: &[&str]) -> Result<Vec<(Metamodel, String)>> {
    if paths.is_empty() {
        return models(defaults);
    }
    paths
        .iter()
        .map(|p| Ok((Metamodel::load(p)?, p.display().to_string())))
        .collect()
}

/// The material file at `path`; the shipped Gravel 8/16 when `path` is the example's and no
/// such file is here, with a note saying so for the caller to show.
pub fn material(path: &Path) -> Result<(Material, Option<String>)> {
    if path != Path::new(GRAVEL) || path.exists() {
        return Ok((Material::from_file(path)?, None));
    }
    let note = format!("{GRAVEL} is not here; using the copy built into mbgc");
    Ok((gravel()?, Some(note)))
}

/// The shipped Gravel 8/16 with its sieve analysis in memory, so that no file is read.
fn gravel() -> Result<Material> {
    let mut m = Material::from_toml_str(GRAVEL_TOML, GRAVEL)?;
    m.psd = Some(PsdSpec::SieveData(gravel_sieve()?));
    Ok(m)
}

/// The example's sieve analysis (sizes in mm, passing in percent).
fn gravel_sieve() -> Result<SieveData> {
    let (mut size, mut passing) = (Vec::new(), Vec::new());
    for (k, line) in GRAVEL_SIEVE_CSV.lines().enumerate().skip(1) {
        let bad = || Error::input(GRAVEL_SIEVE, format!("line {}", k + 1), "two numbers");
        let (x, p) = line.split_once(',').ok_or_else(bad)?;
        size.push(x.trim().parse::<f64>().map_err(|_| bad())?);
        passing.push(p.trim().parse::<f64>().map_err(|_| bad())? / 100.0);
    }
    SieveData::new(GRAVEL_SIEVE, size, passing)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The repository's root, where the shipped files' paths start.
    fn root() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
    }

    /// The built-in example is the file: the same material, and a sieve that fits alike.
    #[test]
    fn the_shipped_gravel_is_the_example_file() {
        let file = Material::from_file(&root().join(GRAVEL)).unwrap();
        let shipped = gravel().unwrap();
        assert_eq!(
            file.psd_parameters().unwrap(),
            shipped.psd_parameters().unwrap()
        );
        assert_eq!(file.fixed, shipped.fixed);
        assert_eq!(
            format!("{:?}", file.measured),
            format!("{:?}", shipped.measured)
        );
        let read = SieveData::read(&root().join(GRAVEL_SIEVE)).unwrap();
        let mine = gravel_sieve().unwrap();
        assert_eq!((read.size_mm, read.passing), (mine.size_mm, mine.passing));
    }

    #[test]
    fn the_shipped_models_are_the_files_and_found_by_path_or_short_name() {
        for (path, _) in MODELS {
            let file = Metamodel::load(&root().join(path)).unwrap();
            for name in [*path, stem(path)] {
                let (shipped, label) = model(name).unwrap();
                assert_eq!(label, *path);
                assert_eq!(
                    serde_json::to_value(shipped).unwrap(),
                    serde_json::to_value(&file).unwrap(),
                    "{name}"
                );
            }
        }
        assert_eq!(
            names(),
            [
                "shear_box",
                "shear_box_sjkr",
                "shear_box_wide",
                "shear_box_sjkr_wide",
                "shear_cell",
                "shear_cell_sjkr"
            ]
        );
        for defaults in [CALIBRATION_MODELS, DIAGNOSIS_MODELS] {
            let labels: Vec<String> = models(defaults).unwrap().into_iter().map(|m| m.1).collect();
            assert_eq!(labels, defaults);
        }
    }

    #[test]
    fn an_unknown_model_is_refused_naming_the_shipped_ones() {
        let e = model("shear_cube").unwrap_err().to_string();
        assert_eq!(
            e,
            "shipped model \"shear_cube\": expected one of shear_box, shear_box_sjkr, \
             shear_box_wide, shear_box_sjkr_wide, shear_cell, shear_cell_sjkr"
        );
    }

    /// An explicit model always wins over the defaults.
    #[test]
    fn files_win_over_the_shipped_defaults() {
        let path = root().join(SHEAR_BOX_SJKR);
        let given = files_or_models(std::slice::from_ref(&path), CALIBRATION_MODELS).unwrap();
        assert_eq!(given.len(), 1);
        assert_eq!(given[0].1, path.display().to_string());
        let default = files_or_models(&[], CALIBRATION_MODELS).unwrap();
        assert_eq!(default[0].1, SHEAR_BOX);
    }

    /// The example is used only where its path does not exist, and the caller is told.
    #[test]
    fn the_example_stands_in_only_for_its_own_missing_path() {
        let dir = tempfile::tempdir().unwrap();
        let (from_file, note) = material(&root().join(GRAVEL)).unwrap();
        assert!(note.is_none());
        assert_eq!(from_file.source, root().join(GRAVEL).display().to_string());
        let missing = dir.path().join("gravel.toml");
        assert!(
            material(&missing).is_err(),
            "another missing file is an error"
        );
        // Unit tests run in crates/mbgc, which has no examples/.
        assert!(!Path::new(GRAVEL).exists());
        let (shipped, note) = material(Path::new(GRAVEL)).unwrap();
        assert_eq!(shipped.source, GRAVEL);
        assert_eq!(
            note.as_deref(),
            Some("examples/gravel.toml is not here; using the copy built into mbgc")
        );
    }
}
