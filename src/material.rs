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

use crate::error::{read_to_string, Error, Result};
use std::path::{Path, PathBuf};

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

fn number(v: &toml::Value, file: &str, field: &str) -> Result<f64> {
    let x = match v {
        toml::Value::Float(f) => *f,
        toml::Value::Integer(i) => *i as f64,
        _ => return Err(Error::input(file, field, "a number")),
    };
    if !x.is_finite() {
        return Err(Error::input(
            file,
            field,
            format!("a finite number, got {x}"),
        ));
    }
    Ok(x)
}

fn table<'a>(v: &'a toml::Value, file: &str, field: &str) -> Result<&'a toml::Table> {
    v.as_table()
        .ok_or_else(|| Error::input(file, field, "a table"))
}

fn only_keys(t: &toml::Table, allowed: &[&str], file: &str, field: &str) -> Result<()> {
    for k in t.keys() {
        if !allowed.contains(&k.as_str()) {
            let name = if field.is_empty() {
                k.clone()
            } else {
                format!("{field}.{k}")
            };
            return Err(Error::input(
                file,
                name,
                format!("one of: {}", allowed.join(", ")),
            ));
        }
    }
    Ok(())
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
        let file = source;
        let doc: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            Error::input(file, "TOML syntax", format!("valid TOML ({})", e.message()))
        })?;
        only_keys(
            &doc,
            &["name", "psd", "measured", "fixed", "bounds", "constraints"],
            file,
            "",
        )?;
        let name = match doc.get("name") {
            Some(v) => v
                .as_str()
                .ok_or_else(|| Error::input(file, "name", "a string"))?
                .to_string(),
            None => Path::new(file)
                .file_stem()
                .map_or("material".into(), |s| s.to_string_lossy().to_string()),
        };
        let psd = match doc.get("psd") {
            None => None,
            Some(v) => {
                let t = table(v, file, "psd")?;
                only_keys(t, &["sieve", "d50_mm", "sigma_ln"], file, "psd")?;
                match (t.get("sieve"), t.get("d50_mm"), t.get("sigma_ln")) {
                    (Some(s), None, None) => Some(PsdSpec::Sieve(PathBuf::from(
                        s.as_str()
                            .ok_or_else(|| Error::input(file, "psd.sieve", "a file name"))?,
                    ))),
                    (None, Some(d), Some(s)) => {
                        let d50_mm = number(d, file, "psd.d50_mm")?;
                        let sigma_ln = number(s, file, "psd.sigma_ln")?;
                        if d50_mm <= 0.0 {
                            return Err(Error::input(file, "psd.d50_mm", "a positive size in mm"));
                        }
                        if sigma_ln <= 0.0 {
                            return Err(Error::input(file, "psd.sigma_ln", "a positive spread"));
                        }
                        Some(PsdSpec::LogNormal { d50_mm, sigma_ln })
                    }
                    _ => {
                        return Err(Error::input(
                            file,
                            "psd",
                            "either `sieve = \"file.csv\"` or both `d50_mm` and `sigma_ln`",
                        ))
                    }
                }
            }
        };
        let mut measured = Vec::new();
        if let Some(v) = doc.get("measured") {
            for (k, v) in table(v, file, "measured")? {
                let field = format!("measured.{k}");
                let t = table(v, file, &field)?;
                only_keys(t, &["value", "sd"], file, &field)?;
                let value = number(
                    t.get("value")
                        .ok_or_else(|| Error::input(file, &field, "a `value`"))?,
                    file,
                    &format!("{field}.value"),
                )?;
                let sd = number(
                    t.get("sd").ok_or_else(|| {
                        Error::input(
                            file,
                            &field,
                            "an `sd` (standard deviation of the measurement)",
                        )
                    })?,
                    file,
                    &format!("{field}.sd"),
                )?;
                if sd <= 0.0 {
                    return Err(Error::input(
                        file,
                        format!("{field}.sd"),
                        format!("a standard deviation > 0, got {sd}"),
                    ));
                }
                measured.push(Measured {
                    response: k.clone(),
                    value,
                    sd,
                });
            }
        }
        if measured.is_empty() {
            return Err(Error::input(
                file,
                "measured",
                "at least one measured response, e.g. shear_angle = { value = 35.5, sd = 0.5 }",
            ));
        }
        let mut fixed = Vec::new();
        if let Some(v) = doc.get("fixed") {
            for (k, v) in table(v, file, "fixed")? {
                fixed.push((k.clone(), number(v, file, &format!("fixed.{k}"))?));
            }
        }
        let mut bounds = Vec::new();
        if let Some(v) = doc.get("bounds") {
            for (k, v) in table(v, file, "bounds")? {
                let field = format!("bounds.{k}");
                let a = v
                    .as_array()
                    .filter(|a| a.len() == 2)
                    .ok_or_else(|| Error::input(file, &field, "[min, max]"))?;
                let (lo, hi) = (number(&a[0], file, &field)?, number(&a[1], file, &field)?);
                if lo >= hi {
                    return Err(Error::input(
                        file,
                        &field,
                        format!("min < max, got [{lo}, {hi}]"),
                    ));
                }
                if fixed.iter().any(|(n, _)| n == k) {
                    return Err(Error::input(
                        file,
                        &field,
                        format!("{k} is also in [fixed]: give it a value or a range, not both"),
                    ));
                }
                bounds.push((k.clone(), [lo, hi]));
            }
        }
        let mut constraints = Vec::new();
        if let Some(v) = doc.get("constraints") {
            let t = table(v, file, "constraints")?;
            only_keys(t, &["expr"], file, "constraints")?;
            if let Some(list) = t.get("expr") {
                let list = list.as_array().ok_or_else(|| {
                    Error::input(file, "constraints.expr", "a list of inequalities")
                })?;
                for (i, e) in list.iter().enumerate() {
                    let field = format!("constraints.expr[{i}]");
                    let s = e
                        .as_str()
                        .ok_or_else(|| Error::input(file, &field, "a string"))?;
                    constraints.push(constraint(s, file, &field)?);
                }
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
        })
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
}
