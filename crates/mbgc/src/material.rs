//! Material files: what was measured on a bulk material, what is fixed, and how the search may
//! be narrowed.
//!
//! ```toml
//! name = "Gravel 8/16"
//! [psd]                      # sieve data (fitted here) or the log-normal parameters
//! sieve = "sieve_gravel_8_16.csv"     # or: d50_mm = 11.16, sigma_ln = 0.26
//! [measured]                 # value and standard deviation of each response
//! shear_angle = { value = 35.53, sd = 0.5 }
//! [fixed]
//! mu_pw = 0.363
//! [bounds]
//! rho_p = [2000, 3000]
//! [constraints]
//! expr = ["e_pw <= e_pp"]
//! [model]                    # optional: the effects the material needs
//! class = "hertz,mindlin,epsd2,sjkr"
//! ```

use serde::Deserialize;
use std::path::{Path, PathBuf};

use crate::error::{from_toml, read_to_string, Entries, Error, Result};
use crate::model_table::{refuse_inactive_parameters, ModelTable};
use mbgc_dem::contact::ModelClass;

pub use crate::constraint::Constraint;

/// A bulk measurement of the material, an entry of `[measured]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    /// The response it measures, named as the metamodel names it (`shear_angle`).
    pub response: String,
    /// The measured value, in the response's unit (degrees, kg/m^3, ...).
    pub value: f64,
    /// Standard deviation of the measurement, same unit, > 0 (replicate scatter): it weighs the
    /// response in chi^2 and the likelihood.
    pub sd: f64,
}

/// The material's particle size distribution, which fixes the metamodel's `d50` and `sigma_ln`
/// inputs when it has them.
#[derive(Clone, Debug, PartialEq)]
pub enum PsdSpec {
    /// Sieve analysis (path resolved against the material file's folder).
    Sieve(PathBuf),
    /// Sieve analysis already in memory (a program's own data, or a built-in example's).
    SieveData(crate::psd::SieveData),
    /// The log-normal parameters given directly.
    LogNormal {
        /// Median particle diameter, mm (> 0).
        d50_mm: f64,
        /// Standard deviation of ln(diameter), dimensionless (> 0; 0.26 for the gravel 8/16 above).
        sigma_ln: f64,
    },
}

/// The smallest accepted standard deviation of a measurement, relative to its value.
pub const MIN_RELATIVE_SD: f64 = 1e-9;

/// A bulk material to calibrate: its measurements and what is known of it, read from a material
/// file (see the module example).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Display name: the file's `name`, else the file stem.
    pub name: String,
    /// The file path or label given when reading; errors name it.
    pub source: String,
    /// The size distribution, if the file has `[psd]`.
    pub psd: Option<PsdSpec>,
    /// The measured responses (at least one), in file order.
    pub measured: Vec<Measured>,
    /// Parameters known for the material (`[fixed]`), in physical units: not calibrated.
    pub fixed: Vec<(String, f64)>,
    /// `[min, max]` narrowing the search of a parameter inside the model's domain.
    pub bounds: Vec<(String, [f64; 2])>,
    /// Linear inequalities between parameters that every solution must satisfy.
    pub constraints: Vec<Constraint>,
    /// The `[model] class` the material declares it needs; `None`: whatever the metamodel's.
    pub model_class: Option<ModelClass>,
}

// The file as written. Required keys are `Option`s so that `validate` can say what a missing
// one means; serde only refuses unknown keys and values of the wrong type.

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a material file")]
struct MaterialFile {
    name: Option<String>,
    psd: Option<PsdFile>,
    #[serde(default)]
    measured: Entries<MeasuredFile>,
    #[serde(default)]
    fixed: Entries<f64>,
    #[serde(default)]
    bounds: Entries<Vec<f64>>,
    constraints: Option<ConstraintsFile>,
    model: Option<ModelTable>,
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `sieve = \"file.csv\"` or both `d50_mm` and `sigma_ln`"
)]
pub(crate) struct PsdFile {
    sieve: Option<String>,
    d50_mm: Option<f64>,
    sigma_ln: Option<f64>,
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table such as { value = 35.5, sd = 0.5 }"
)]
pub(crate) struct MeasuredFile {
    value: Option<f64>,
    sd: Option<f64>,
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `expr = [\"e_pw <= e_pp\", ...]`"
)]
struct ConstraintsFile {
    #[serde(default)]
    expr: Vec<String>,
}

/// A `[min, max]` range as written: two finite numbers, min < max.
pub(crate) fn min_max(v: Vec<f64>, file: &str, field: &str) -> Result<[f64; 2]> {
    let [lo, hi] = <[f64; 2]>::try_from(v).map_err(|v| {
        Error::input(
            file,
            field,
            format!("[min, max], got a list of {}", v.len()),
        )
    })?;
    let (lo, hi) = (finite(lo, file, field)?, finite(hi, file, field)?);
    if lo >= hi {
        return Err(Error::input(
            file,
            field,
            format!("min < max, got [{lo}, {hi}]"),
        ));
    }
    Ok([lo, hi])
}

pub(crate) fn finite(x: f64, file: &str, field: &str) -> Result<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::input(
            file,
            field,
            format!("a finite number, got {x}"),
        ))
    }
}

/// The `[psd]` table as written, checked; `prefix` goes before every field name in errors (a
/// measurement set's `sample[2].`).
pub(crate) fn psd_spec(psd: Option<PsdFile>, file: &str, prefix: &str) -> Result<Option<PsdSpec>> {
    Ok(match psd {
        None => None,
        Some(PsdFile {
            sieve: Some(s),
            d50_mm: None,
            sigma_ln: None,
        }) => Some(PsdSpec::Sieve(PathBuf::from(s))),
        Some(PsdFile {
            sieve: None,
            d50_mm: Some(d),
            sigma_ln: Some(s),
        }) => {
            let d50_mm = finite(d, file, &format!("{prefix}psd.d50_mm"))?;
            let sigma_ln = finite(s, file, &format!("{prefix}psd.sigma_ln"))?;
            if d50_mm <= 0.0 {
                return Err(Error::input(
                    file,
                    format!("{prefix}psd.d50_mm"),
                    "a positive size in mm",
                ));
            }
            if sigma_ln <= 0.0 {
                return Err(Error::input(
                    file,
                    format!("{prefix}psd.sigma_ln"),
                    "a positive spread",
                ));
            }
            Some(PsdSpec::LogNormal { d50_mm, sigma_ln })
        }
        Some(_) => {
            return Err(Error::input(
                file,
                format!("{prefix}psd"),
                "either `sieve = \"file.csv\"` or both `d50_mm` and `sigma_ln`",
            ))
        }
    })
}

/// The `[measured]` table as written, checked: at least one response, each with a finite value
/// and a realistic standard deviation.
pub(crate) fn measured_values(
    entries: Entries<MeasuredFile>,
    file: &str,
    prefix: &str,
) -> Result<Vec<Measured>> {
    let mut measured = Vec::new();
    for (response, m) in entries.0 {
        let field = format!("{prefix}measured.{response}");
        let value = m
            .value
            .ok_or_else(|| Error::input(file, &field, "a `value`"))?;
        let value = finite(value, file, &format!("{field}.value"))?;
        let sd = m.sd.ok_or_else(|| {
            Error::input(
                file,
                &field,
                "an `sd` (standard deviation of the measurement)",
            )
        })?;
        let sd = finite(sd, file, &format!("{field}.sd"))?;
        if sd <= 0.0 {
            return Err(Error::input(
                file,
                format!("{field}.sd"),
                format!("a standard deviation > 0, got {sd}"),
            ));
        }
        // No bulk-material measurement is known to 1e-9 of its value; such an sd only makes
        // chi^2 overflow the optimiser.
        if sd < MIN_RELATIVE_SD * value.abs() {
            return Err(Error::input(
                file,
                format!("{field}.sd"),
                format!(
                    "a realistic standard deviation, at least {MIN_RELATIVE_SD:e} of the value \
                     {value:e}; got {sd:e}"
                ),
            ));
        }
        measured.push(Measured {
            response,
            value,
            sd,
        });
    }
    if measured.is_empty() {
        return Err(Error::input(
            file,
            format!("{prefix}measured"),
            "at least one measured response, e.g. shear_angle = { value = 35.5, sd = 0.5 }",
        ));
    }
    Ok(measured)
}

impl MaterialFile {
    /// Everything serde cannot say: what is missing, out of range or inconsistent.
    fn validate(self, file: &str) -> Result<Material> {
        let name = self.name.unwrap_or_else(|| {
            Path::new(file)
                .file_stem()
                .map_or("material".into(), |s| s.to_string_lossy().to_string())
        });
        let psd = psd_spec(self.psd, file, "")?;
        let measured = measured_values(self.measured, file, "")?;
        let mut fixed = Vec::new();
        for (k, v) in self.fixed.0 {
            let v = finite(v, file, &format!("fixed.{k}"))?;
            fixed.push((k, v));
        }
        let mut bounds = Vec::new();
        for (k, v) in self.bounds.0 {
            let field = format!("bounds.{k}");
            let [lo, hi] = min_max(v, file, &field)?;
            if fixed.iter().any(|(n, _)| *n == k) {
                return Err(Error::input(
                    file,
                    &field,
                    format!("{k} is also in [fixed]: give it a value or a range, not both"),
                ));
            }
            bounds.push((k, [lo, hi]));
        }
        let constraints = self
            .constraints
            .map_or(Vec::new(), |c| c.expr)
            .iter()
            .enumerate()
            .map(|(i, text)| Constraint::parse(text, file, &format!("constraints.expr[{i}]")))
            .collect::<Result<Vec<_>>>()?;
        let model_class = self.model.map(|m| m.class(file)).transpose()?;
        if let Some(c) = &model_class {
            refuse_inactive_parameters(
                c,
                fixed.iter().map(|(n, _)| n.as_str()),
                file,
                "fixed",
                "this material",
            )?;
            refuse_inactive_parameters(
                c,
                bounds.iter().map(|(n, _)| n.as_str()),
                file,
                "bounds",
                "this material",
            )?;
            for (k, con) in constraints.iter().enumerate() {
                refuse_inactive_parameters(
                    c,
                    con.terms.iter().map(|(n, _)| n.as_str()),
                    file,
                    &format!("constraints.expr[{k}]"),
                    "this material",
                )?;
            }
        }
        Ok(Material {
            name,
            source: file.to_string(),
            psd,
            measured,
            fixed,
            bounds,
            constraints,
            model_class,
        })
    }
}

impl Material {
    /// Reads a material file; a relative sieve path is taken relative to the file's folder.
    pub fn from_file(path: &Path) -> Result<Material> {
        let text = read_to_string(path)?;
        let mut m = Material::from_toml_str(&text, &path.display().to_string())?;
        if let Some(PsdSpec::Sieve(p)) = &mut m.psd {
            if p.is_relative() {
                *p = path.parent().unwrap_or(Path::new(".")).join(&*p);
            }
        }
        Ok(m)
    }

    /// A material from the text of a material file; `source` names it in errors and gives the
    /// default name. A sieve path stays as written.
    pub fn from_toml_str(text: &str, source: &str) -> Result<Material> {
        // A measurement set's samples may come from several experiments, each with its own
        // model: one material's single prediction per response cannot hold them, so point to
        // the command whose first step is their joint calibration instead of "unknown key".
        if let Ok(t) = text.parse::<toml::Table>() {
            if t.contains_key("sample") {
                return Err(Error::input(
                    source,
                    "sample",
                    "a material file (one [psd] and one [measured] table); this is a \
                     measurement set of [[sample]]s: calibrate all its samples jointly, on \
                     each sample's experiment's model, with `mbgc diagnose --measurements \
                     FILE --model MODEL ...` (its first step is that joint calibration)",
                ));
            }
        }
        from_toml::<MaterialFile>(text, source)?.validate(source)
    }

    /// `(d50_mm, sigma_ln)` of the log-normal PSD, fitting sieve data if that is what was given.
    pub fn psd_parameters(&self) -> Result<Option<(f64, f64)>> {
        self.psd.as_ref().map(PsdSpec::parameters).transpose()
    }

    /// Searches the fixed parameters `names` instead of fixing them (`--free`): to see what the
    /// measurements alone can and cannot decide. A name the material does not fix is refused.
    pub fn free(&mut self, names: &[String]) -> Result<()> {
        for name in names {
            let before = self.fixed.len();
            self.fixed.retain(|(n, _)| n != name);
            if self.fixed.len() == before {
                return Err(Error::invalid(format!(
                    "--free {name}: {} does not fix {name} (it fixes: {})",
                    self.source,
                    self.fixed
                        .iter()
                        .map(|(n, _)| n.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
        }
        Ok(())
    }
}

impl PsdSpec {
    /// `(d50 in mm, sigma_ln)`: as given, or fitted to the sieve data.
    pub fn parameters(&self) -> Result<(f64, f64)> {
        Ok(match self {
            PsdSpec::LogNormal { d50_mm, sigma_ln } => (*d50_mm, *sigma_ln),
            PsdSpec::Sieve(p) => {
                let fit = crate::psd::fit_all(&crate::psd::SieveData::read(p)?)?;
                (fit.d50_mm, fit.sigma_ln)
            }
            PsdSpec::SieveData(data) => {
                let fit = crate::psd::fit_all(data)?;
                (fit.d50_mm, fit.sigma_ln)
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
name = "Gravel 8/16"
[psd]
d50_mm = 11.16
sigma_ln = 0.26
[measured]
shear_angle = { value = 35.53, sd = 0.5 }
bulk_density = { value = 1478.8, sd = 10 }
[fixed]
mu_pw = 0.363
[bounds]
rho_p = [2000, 3000]
[constraints]
expr = ["e_pw <= e_pp", "mu_pp + 0.5*mu_r_pp >= 0.2"]
"#;

    #[test]
    fn a_measurement_set_is_pointed_to_diagnose() {
        let set = r#"
name = "two experiments"
[[sample]]
name = "box"
experiment = "shear-box"
psd = { d50_mm = 8, sigma_ln = 0.1 }
measured.shear_angle = { value = 36.8, sd = 0.6 }
"#;
        let e = Material::from_toml_str(set, "set.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("set.toml") && e.contains("sample"), "{e}");
        assert!(e.contains("mbgc diagnose --measurements"), "{e}");
    }

    #[test]
    fn the_model_table_names_a_class_and_refuses_parameters_of_other_effects() {
        let m = Material::from_toml_str(GOOD, "g.toml").unwrap();
        assert_eq!(m.model_class, None, "no [model]: whatever the metamodel's");
        let sticky = format!("{GOOD}[model]\nclass = \"hertz,mindlin,epsd2,sjkr\"\n");
        let m = Material::from_toml_str(&sticky, "g.toml").unwrap();
        assert_eq!(
            m.model_class,
            Some(ModelClass::parse("hertz,mindlin,epsd2,sjkr").unwrap())
        );
        let fixed = sticky.replace("mu_pw = 0.363", "mu_pw = 0.363\nced_pw = 1e4");
        assert!(Material::from_toml_str(&fixed, "g.toml").is_ok());
        let rolling_free = GOOD.replace("rho_p = [2000, 3000]", "mu_r_pp = [0, 1]")
            + "[model]\nclass = \"hertz,mindlin\"\n";
        let e = Material::from_toml_str(&rolling_free, "g.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("g.toml") && e.contains("bounds.mu_r_pp") && e.contains("epsd2"),
            "{e}"
        );
        for (bad, field) in [
            ("class = \"hertz,jkr\"", "model.class"),
            ("klass = \"hertz\"", "klass"),
            ("", "model.class"),
        ] {
            let text = format!("{GOOD}[model]\n{bad}\n");
            let e = Material::from_toml_str(&text, "g.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains("g.toml") && e.contains(field), "{bad}: {e}");
        }
    }

    #[test]
    fn reads_a_material() {
        let m = Material::from_toml_str(GOOD, "g.toml").unwrap();
        assert_eq!(m.name, "Gravel 8/16");
        assert_eq!(m.measured.len(), 2);
        assert_eq!(m.bounds, vec![("rho_p".to_string(), [2000.0, 3000.0])]);
        let c = &m.constraints[0];
        let at = |e_pw: f64, e_pp: f64| c.violation(|n| if n == "e_pw" { e_pw } else { e_pp });
        assert_eq!(at(0.3, 0.5), 0.0);
        assert!((at(0.6, 0.5) - 0.1).abs() < 1e-12);
        let c = &m.constraints[1];
        let v = c.violation(|_| 0.1);
        assert!((v - 0.05).abs() < 1e-12, "{v}");
    }

    #[test]
    fn bad_fields_are_named() {
        let cases = [
            (
                GOOD.replace("sd = 0.5", "sd = 0"),
                "measured.shear_angle.sd",
            ),
            (
                GOOD.replace("sd = 0.5", "sd = -1"),
                "measured.shear_angle.sd",
            ),
            (GOOD.replace("[2000, 3000]", "[3000, 2000]"), "bounds.rho_p"),
            (GOOD.replace("rho_p = [", "mu_pw = ["), "bounds.mu_pw"),
            (
                GOOD.replace("e_pw <= e_pp", "e_pw < e_pp"),
                "constraints.expr[0]",
            ),
            (
                GOOD.replace("e_pw <= e_pp", "1 <= 2"),
                "constraints.expr[0]",
            ),
            (GOOD.replace("[fixed]", "[fixd]"), "fixd"),
            (
                GOOD.replace("value = 35.53", "value = nan"),
                "measured.shear_angle.value",
            ),
            (GOOD.replace("sigma_ln = 0.26", ""), "psd"),
            (GOOD.replace("name =", "name = = "), "TOML syntax"),
        ];
        for (text, field) in cases {
            let e = Material::from_toml_str(&text, "g.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains("g.toml") && e.contains(field), "{field}: {e}");
        }
    }

    #[test]
    fn unknown_keys_and_wrong_types_name_the_path_found_and_expected() {
        // (replace, by, field, words the message must hold)
        let cases: [(&str, &str, &str, &[&str]); 7] = [
            (
                "sd = 0.5",
                "sdd = 0.5",
                "measured.shear_angle.sdd",
                &["unknown key", "sd"],
            ),
            (
                "mu_pw = 0.363",
                "mu_pw = \"x\"",
                "fixed.mu_pw",
                &["a number", "string"],
            ),
            (
                "\"mu_pp + 0.5*mu_r_pp >= 0.2\"",
                "3",
                "constraints.expr[1]",
                &["string"],
            ),
            (
                "[2000, 3000]",
                "[2000, \"a\"]",
                "bounds.rho_p[1]",
                &["a number"],
            ),
            ("[2000, 3000]", "[2000]", "bounds.rho_p", &["[min, max]"]),
            (
                "sigma_ln = 0.26",
                "sigma_ln = 0.26\nd90_mm = 1",
                "psd.d90_mm",
                &["unknown key"],
            ),
            (
                "{ value = 35.53, sd = 0.5 }",
                "35.53",
                "measured.shear_angle",
                &["value = 35.5"],
            ),
        ];
        for (a, b, field, words) in cases {
            let e = Material::from_toml_str(&GOOD.replace(a, b), "g.toml")
                .unwrap_err()
                .to_string();
            assert!(e.starts_with(&format!("g.toml: {field}: ")), "{field}: {e}");
            for w in words {
                assert!(e.contains(w), "{field}: no \"{w}\" in {e}");
            }
        }
        let e = Material::from_toml_str(&GOOD.replace("name =", "name = = "), "g.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2, column 8"), "{e}");
    }

    #[test]
    fn keeps_file_order_and_defaults() {
        let text = "[measured]\nz = { value = 1, sd = 1 }\na = { value = 2, sd = 1 }\n\
                    [fixed]\nz9 = 1\nb = 2\n";
        let m = Material::from_toml_str(text, "dir/sand.toml").unwrap();
        assert_eq!(m.name, "sand");
        let names: Vec<&str> = m.measured.iter().map(|r| r.response.as_str()).collect();
        assert_eq!(names, ["z", "a"]);
        assert_eq!(m.fixed, [("z9".to_string(), 1.0), ("b".to_string(), 2.0)]);
        assert!(m.psd.is_none() && m.bounds.is_empty() && m.constraints.is_empty());
    }

    #[test]
    fn constraints_read_rust_numbers_and_refuse_non_finite_bounds() {
        let c = |t: &str| Constraint::parse(t, "m.toml", "constraints.expr[0]");
        // `3e-1` used to be split at its minus sign.
        let k = c("mu_pw <= 3e-1").unwrap();
        assert_eq!(k.terms, [("mu_pw".to_string(), 1.0)]);
        assert!((k.constant + 0.3).abs() < 1e-15);
        let k = c("0.5*mu_r_pp + mu_pp - 1.5E+0 >= -.5").unwrap();
        assert_eq!(k.terms.len(), 2);
        assert!((k.constant - 1.0).abs() < 1e-15, "{k:?}");
        // x*2 and 2*x read alike.
        assert_eq!(c("x*2 <= y").unwrap().terms, c("2*x <= y").unwrap().terms);
        for bad in [
            "mu_pw <= nan",
            "x >= inf",
            "x <= -inf",
            "x <= 1e999",
            "x <= 2*3",
            "x <= y z",
        ] {
            let e = c(bad).unwrap_err().to_string();
            assert!(e.contains("constraints.expr[0]"), "{bad}: {e}");
        }
        // Scaled to a largest coefficient of 1: the same constraint however it is written.
        assert_eq!(
            c("1e300*x >= 1e300").unwrap().terms,
            c("x >= 1").unwrap().terms
        );
        assert_eq!(
            c("1e300*x >= 1e300").unwrap().constant,
            c("x >= 1").unwrap().constant
        );
    }
}
