//! What the `mbgc` binary carries with it, so that a newcomer's first command works from any
//! directory: the shipped shear-box metamodels (the default of `--model`: the base one for a
//! calibration, with the cohesive one for a diagnosis) and seed 004's Gravel 8/16 example with
//! its sieve analysis. An explicit `--model` always wins; the example is used
//! only when its path, `examples/gravel.toml`, does not exist where the command runs, and the
//! command says so.

use std::path::Path;

use mbgc::material::{Material, PsdSpec};
use mbgc::metamodel::Metamodel;
use mbgc::psd::SieveData;

/// Where the shipped model lives in the repository; the name it is reported under.
pub const SHEAR_BOX_MODEL: &str = "models/shear_box.json";
const SHEAR_BOX_JSON: &str = include_str!("../models/shear_box.json");
/// The shipped cohesive shear-box model (class hertz,mindlin,epsd2,sjkr).
pub const SHEAR_BOX_SJKR_MODEL: &str = "models/shear_box_sjkr.json";
const SHEAR_BOX_SJKR_JSON: &str = include_str!("../models/shear_box_sjkr.json");

/// The example material's path in the repository.
pub const GRAVEL: &str = "examples/gravel.toml";
const GRAVEL_TOML: &str = include_str!("../examples/gravel.toml");
const GRAVEL_SIEVE: &str = "examples/sieve_gravel_8_16.csv";
const GRAVEL_SIEVE_CSV: &str = include_str!("../examples/sieve_gravel_8_16.csv");

/// The shipped shear-box metamodel, as built into this binary.
pub fn shear_box_model() -> mbgc::Result<Metamodel> {
    Metamodel::from_json_str(SHEAR_BOX_JSON, SHEAR_BOX_MODEL)
}

/// The shipped cohesive shear-box metamodel, as built into this binary.
pub fn shear_box_sjkr_model() -> mbgc::Result<Metamodel> {
    Metamodel::from_json_str(SHEAR_BOX_SJKR_JSON, SHEAR_BOX_SJKR_MODEL)
}

/// The models of `--model`: the files given, or the built-in shear-box model when none is.
pub fn models(paths: &[std::path::PathBuf]) -> mbgc::Result<Vec<(Metamodel, String)>> {
    if paths.is_empty() {
        return Ok(vec![(shear_box_model()?, SHEAR_BOX_MODEL.to_string())]);
    }
    load(paths)
}

/// The models of a diagnosis: the files given, or both built-in shear-box models (the base
/// class and its cohesive extension, the candidate sjkr's model) when none is.
pub fn diagnosis_models(paths: &[std::path::PathBuf]) -> mbgc::Result<Vec<(Metamodel, String)>> {
    if paths.is_empty() {
        return Ok(vec![
            (shear_box_model()?, SHEAR_BOX_MODEL.to_string()),
            (shear_box_sjkr_model()?, SHEAR_BOX_SJKR_MODEL.to_string()),
        ]);
    }
    load(paths)
}

fn load(paths: &[std::path::PathBuf]) -> mbgc::Result<Vec<(Metamodel, String)>> {
    paths
        .iter()
        .map(|p| Ok((Metamodel::load(p)?, p.display().to_string())))
        .collect()
}

/// The material file at `path`; the built-in Gravel 8/16 when `path` is the example's and no
/// such file is here (with a note on standard error).
pub fn material(path: &Path) -> mbgc::Result<Material> {
    if path != Path::new(GRAVEL) || path.exists() {
        return Material::from_file(path);
    }
    eprintln!("note: {GRAVEL} is not here; using the copy built into mbgc");
    let mut m = Material::from_toml_str(GRAVEL_TOML, GRAVEL)?;
    m.psd = Some(PsdSpec::SieveData(gravel_sieve()?));
    Ok(m)
}

/// The example's sieve analysis (sizes in mm, passing in percent).
fn gravel_sieve() -> mbgc::Result<SieveData> {
    let (mut size, mut passing) = (Vec::new(), Vec::new());
    for (k, line) in GRAVEL_SIEVE_CSV.lines().enumerate().skip(1) {
        let bad = || mbgc::Error::input(GRAVEL_SIEVE, format!("line {}", k + 1), "two numbers");
        let (x, p) = line.split_once(',').ok_or_else(bad)?;
        size.push(x.trim().parse::<f64>().map_err(|_| bad())?);
        passing.push(p.trim().parse::<f64>().map_err(|_| bad())? / 100.0);
    }
    SieveData::new(GRAVEL_SIEVE, size, passing)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The built-in example is the file: the same material, and a sieve that fits alike.
    #[test]
    fn the_built_in_gravel_is_the_example_file() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let file = Material::from_file(&root.join(GRAVEL)).unwrap();
        let mut built_in = Material::from_toml_str(GRAVEL_TOML, GRAVEL).unwrap();
        built_in.psd = Some(PsdSpec::SieveData(gravel_sieve().unwrap()));
        assert_eq!(
            file.psd_parameters().unwrap(),
            built_in.psd_parameters().unwrap()
        );
        assert_eq!(file.fixed, built_in.fixed);
        assert_eq!(
            format!("{:?}", file.measured),
            format!("{:?}", built_in.measured)
        );
        let read = SieveData::read(&root.join(GRAVEL_SIEVE)).unwrap();
        let mine = gravel_sieve().unwrap();
        assert_eq!((read.size_mm, read.passing), (mine.size_mm, mine.passing));
    }

    #[test]
    fn the_built_in_models_are_the_shipped_files() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        for (path, built_in) in [
            (SHEAR_BOX_MODEL, shear_box_model().unwrap()),
            (SHEAR_BOX_SJKR_MODEL, shear_box_sjkr_model().unwrap()),
        ] {
            let file = Metamodel::load(&root.join(path)).unwrap();
            assert_eq!(
                serde_json::to_value(built_in).unwrap(),
                serde_json::to_value(file).unwrap(),
                "{path}"
            );
        }
    }
}
