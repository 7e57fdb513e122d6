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
//! ```

use serde::Deserialize;
use std::path::{Path, PathBuf};

use crate::error::{from_toml, read_to_string, Entries, Error, Result};

#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    pub response: String,
    pub value: f64,
    pub sd: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub enum PsdSpec {
    /// Sieve analysis (path resolved against the material file's folder).
    Sieve(PathBuf),
    LogNormal {
        d50_mm: f64,
        sigma_ln: f64,
    },
}

/// `sum coef * x[name] + constant <= 0`, from a text such as `e_pw <= e_pp` or
/// `mu_pp + 0.5*mu_r_pp <= 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct Constraint {
    pub text: String,
    pub terms: Vec<(String, f64)>,
    pub constant: f64,
}

impl Constraint {
    /// Positive by how much the constraint is violated at `value(name)`.
    pub fn violation(&self, value: impl Fn(&str) -> f64) -> f64 {
        let g: f64 = self.terms.iter().map(|(n, c)| c * value(n)).sum::<f64>() + self.constant;
        g.max(0.0)
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub source: String,
    pub psd: Option<PsdSpec>,
    pub measured: Vec<Measured>,
    pub fixed: Vec<(String, f64)>,
    pub bounds: Vec<(String, [f64; 2])>,
    pub constraints: Vec<Constraint>,
}

/// Parses `a*x + b - y` into terms and a constant.
fn linear(side: &str, file: &str, field: &str) -> Result<(Vec<(String, f64)>, f64)> {
    let mut terms = Vec::new();
    let mut constant = 0.0;
    let text = side.replace('-', "+-");
    for raw in text.split('+').map(str::trim).filter(|s| !s.is_empty()) {
        let (sign, body) = match raw.strip_prefix('-') {
            Some(b) => (-1.0, b.trim()),
            None => (1.0, raw),
        };
        let bad = || {
            Error::input(
                file,
                field,
                format!(
                    "a linear inequality such as \"e_pw <= e_pp\" or \"mu_pp + 0.5*mu_r_pp <= 1\", \
                     could not read \"{raw}\""
                ),
            )
        };
        let (coef, name) = match body.split_once('*') {
            Some((c, n)) => (c.trim().parse::<f64>().map_err(|_| bad())?, Some(n.trim())),
            None => match body.parse::<f64>() {
                Ok(c) => (c, None),
                Err(_) => (1.0, Some(body)),
            },
        };
        match name {
            Some(n) if crate::space::is_identifier(n) => terms.push((n.to_string(), sign * coef)),
            Some(_) => return Err(bad()),
            None => constant += sign * coef,
        }
    }
    Ok((terms, constant))
}

fn constraint(text: &str, file: &str, field: &str) -> Result<Constraint> {
    let (lhs, rhs, flip) = if let Some((l, r)) = text.split_once("<=") {
        (l, r, false)
    } else if let Some((l, r)) = text.split_once(">=") {
        (l, r, true)
    } else {
        return Err(Error::input(
            file,
            field,
            format!("an inequality with <= or >=, got \"{text}\""),
        ));
    };
    let (lt, lc) = linear(lhs, file, field)?;
    let (rt, rc) = linear(rhs, file, field)?;
    // lhs - rhs <= 0 (or rhs - lhs <= 0 for >=).
    let s = if flip { -1.0 } else { 1.0 };
    let mut terms: Vec<(String, f64)> = Vec::new();
    for (n, c) in lt
        .into_iter()
        .map(|(n, c)| (n, s * c))
        .chain(rt.into_iter().map(|(n, c)| (n, -s * c)))
    {
        match terms.iter_mut().find(|(m, _)| *m == n) {
            Some((_, k)) => *k += c,
            None => terms.push((n, c)),
        }
    }
    terms.retain(|(_, c)| *c != 0.0);
    if terms.is_empty() {
        return Err(Error::input(
            file,
            field,
            format!("an inequality between parameters, \"{text}\" names none"),
        ));
    }
    Ok(Constraint {
        text: text.trim().to_string(),
        terms,
        constant: s * (lc - rc),
    })
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
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `sieve = \"file.csv\"` or both `d50_mm` and `sigma_ln`"
)]
struct PsdFile {
    sieve: Option<String>,
    d50_mm: Option<f64>,
    sigma_ln: Option<f64>,
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table such as { value = 35.5, sd = 0.5 }"
)]
struct MeasuredFile {
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

fn finite(x: f64, file: &str, field: &str) -> Result<f64> {
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

impl MaterialFile {
    /// Everything serde cannot say: what is missing, out of range or inconsistent.
    fn validate(self, file: &str) -> Result<Material> {
        let name = self.name.unwrap_or_else(|| {
            Path::new(file)
                .file_stem()
                .map_or("material".into(), |s| s.to_string_lossy().to_string())
        });
        let psd = match self.psd {
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
                let d50_mm = finite(d, file, "psd.d50_mm")?;
                let sigma_ln = finite(s, file, "psd.sigma_ln")?;
                if d50_mm <= 0.0 {
                    return Err(Error::input(file, "psd.d50_mm", "a positive size in mm"));
                }
                if sigma_ln <= 0.0 {
                    return Err(Error::input(file, "psd.sigma_ln", "a positive spread"));
                }
                Some(PsdSpec::LogNormal { d50_mm, sigma_ln })
            }
            Some(_) => {
                return Err(Error::input(
                    file,
                    "psd",
                    "either `sieve = \"file.csv\"` or both `d50_mm` and `sigma_ln`",
                ))
            }
        };
        let mut measured = Vec::new();
        for (response, m) in self.measured.0 {
            let field = format!("measured.{response}");
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
            measured.push(Measured {
                response,
                value,
                sd,
            });
        }
        if measured.is_empty() {
            return Err(Error::input(
                file,
                "measured",
                "at least one measured response, e.g. shear_angle = { value = 35.5, sd = 0.5 }",
            ));
        }
        let mut fixed = Vec::new();
        for (k, v) in self.fixed.0 {
            let v = finite(v, file, &format!("fixed.{k}"))?;
            fixed.push((k, v));
        }
        let mut bounds = Vec::new();
        for (k, v) in self.bounds.0 {
            let field = format!("bounds.{k}");
            let [lo, hi] = <[f64; 2]>::try_from(v).map_err(|v| {
                Error::input(
                    file,
                    &field,
                    format!("[min, max], got a list of {}", v.len()),
                )
            })?;
            let (lo, hi) = (finite(lo, file, &field)?, finite(hi, file, &field)?);
            if lo >= hi {
                return Err(Error::input(
                    file,
                    &field,
                    format!("min < max, got [{lo}, {hi}]"),
                ));
            }
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
            .map(|(i, text)| constraint(text, file, &format!("constraints.expr[{i}]")))
            .collect::<Result<Vec<_>>>()?;
        Ok(Material {
            name,
            source: file.to_string(),
            psd,
            measured,
            fixed,
            bounds,
            constraints,
        })
    }
}

impl Material {
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

    pub fn from_toml_str(text: &str, source: &str) -> Result<Material> {
        from_toml::<MaterialFile>(text, source)?.validate(source)
    }

    /// `(d50_mm, sigma_ln)` of the log-normal PSD, fitting sieve data if that is what was given.
    pub fn psd_parameters(&self) -> Result<Option<(f64, f64)>> {
        Ok(match &self.psd {
            None => None,
            Some(PsdSpec::LogNormal { d50_mm, sigma_ln }) => Some((*d50_mm, *sigma_ln)),
            Some(PsdSpec::Sieve(p)) => {
                let data = crate::psd::SieveData::read(p)?;
                let fit = crate::psd::fit_all(&data)?;
                Some((fit.d50_mm, fit.sigma_ln))
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
}
