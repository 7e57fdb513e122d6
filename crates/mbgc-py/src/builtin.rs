//! What the package carries with it, as the `mbgc` binary does (src/builtin.rs): the shipped
//! shear-box metamodels, the default model of a calibration (the base one) and of a diagnosis
//! (with its cohesive extension), and the Gravel 8/16 example for when `examples/gravel.toml`
//! is not where the call runs.

use std::path::Path;

use mbgc::material::{Material, PsdSpec};
use mbgc::metamodel::Metamodel;
use mbgc::psd::SieveData;

/// The shipped shear-box model's path in the repository, the name it is reported under.
pub const SHEAR_BOX_MODEL: &str = "models/shear_box.json";
const SHEAR_BOX_JSON: &str = include_str!("../../../models/shear_box.json");
/// The shipped cohesive shear-box model (class hertz,mindlin,epsd2,sjkr).
pub const SHEAR_BOX_SJKR_MODEL: &str = "models/shear_box_sjkr.json";
const SHEAR_BOX_SJKR_JSON: &str = include_str!("../../../models/shear_box_sjkr.json");

/// The example material's path in the repository.
pub const GRAVEL: &str = "examples/gravel.toml";
const GRAVEL_TOML: &str = include_str!("../../../examples/gravel.toml");
const GRAVEL_SIEVE: &str = "examples/sieve_gravel_8_16.csv";
const GRAVEL_SIEVE_CSV: &str = include_str!("../../../examples/sieve_gravel_8_16.csv");

/// A shipped model by its path in the repository (`models/shear_box.json`) or its stem.
pub fn model(name: &str) -> mbgc::Result<(Metamodel, String)> {
    let (text, label) = match name {
        "shear_box" | SHEAR_BOX_MODEL => (SHEAR_BOX_JSON, SHEAR_BOX_MODEL),
        "shear_box_sjkr" | SHEAR_BOX_SJKR_MODEL => (SHEAR_BOX_SJKR_JSON, SHEAR_BOX_SJKR_MODEL),
        _ => {
            return Err(mbgc::Error::invalid(format!(
                "shipped model \"{name}\": expected one of shear_box, shear_box_sjkr"
            )))
        }
    };
    Ok((Metamodel::from_json_str(text, label)?, label.to_string()))
}

/// The material file at `path`; the built-in Gravel 8/16 when `path` is the example's and no
/// such file is here (the second value then says so).
pub fn material(path: &Path) -> mbgc::Result<(Material, Option<String>)> {
    if path != Path::new(GRAVEL) || path.exists() {
        return Ok((Material::from_file(path)?, None));
    }
    let mut m = Material::from_toml_str(GRAVEL_TOML, GRAVEL)?;
    m.psd = Some(PsdSpec::SieveData(gravel_sieve()?));
    Ok((
        m,
        Some(format!(
            "{GRAVEL} is not here; using the copy built into mbgc"
        )),
    ))
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
