//! Parameter spaces: the named, bounded inputs of a metamodel and their map to the unit cube.
//!
//! A `space.toml` lists parameters under `[parameters]`, each with a unit, bounds, a scale
//! (`linear` or `log`) and optionally a fixed value:
//!
//! ```toml
//! name = "seed 004, Table 2"
//! [parameters]
//! E_p  = { unit = "Pa", min = 5e6, max = 5e8, scale = "log", what = "Young's modulus" }
//! e_pp = { unit = "-",  min = 0.05, max = 0.95, fixed = 0.6 }
//! ```
//!
//! Free parameters span the unit cube in file order; fixed parameters keep their value and take
//! no dimension. A log-scaled parameter is uniform in `ln x`, which is what a sampler should
//! fill when the range spans decades (Young's modulus, particle size).

use std::path::Path;

use serde::de::IgnoredAny;
use serde::Deserialize;

pub use crate::constraint::is_identifier;
use crate::constraint::Constraint;
use crate::error::{from_toml, read_to_string, Entries, Error, Result};
use crate::model_table::{refuse_inactive_parameters, ModelTable};
use mbgc_dem::contact::{ModelClass, Pair};

/// How a parameter's range maps onto its unit-cube coordinate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Uniform in x: u = (x - min) / (max - min).
    Linear,
    /// Uniform in ln x: u = ln(x / min) / ln(max / min); needs min > 0. Use it for ranges that span
    /// decades (Young's modulus, particle size), which a linear design would crowd at the top.
    Log,
}

/// One named, bounded input of the metamodel, as checked from a `[parameters]` entry.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    /// Identifier used as CSV column and equation variable (letter first, then letters, digits,
    /// `_`).
    pub name: String,
    /// Physical unit as written in the file (SI, e.g. `Pa`, `kg/m^3`; `-` when dimensionless or
    /// omitted); informational only, never converted.
    pub unit: String,
    /// Lower bound, in `unit`; finite, below `max`, and > 0 for a log scale.
    pub min: f64,
    /// Upper bound, in `unit`; finite and above `min`.
    pub max: f64,
    /// Map between the bounds and the unit interval.
    pub scale: Scale,
    /// Value the parameter is held at instead of being sampled (within [min, max]); a fixed
    /// parameter takes no unit-cube dimension.
    pub fixed: Option<f64>,
    /// Free-text description for tables and plots (empty if omitted).
    pub what: String,
}

/// Relative slack accepted when mapping physical values back into the bounds, so that a value
/// printed and re-read (or computed with rounding) at a bound is not refused.
const BOUND_SLACK: f64 = 1e-9;

impl Parameter {
    /// Unit-cube coordinate of a physical value (0 at `min`, 1 at `max`).
    pub fn to_unit(&self, x: f64) -> f64 {
        match self.scale {
            Scale::Linear => (x - self.min) / (self.max - self.min),
            Scale::Log => (x / self.min).ln() / (self.max / self.min).ln(),
        }
    }

    /// Physical value of a unit-cube coordinate.
    pub fn from_unit(&self, u: f64) -> f64 {
        match self.scale {
            Scale::Linear => self.min + u * (self.max - self.min),
            Scale::Log => self.min * (self.max / self.min).powf(u),
        }
    }

    /// Whether `x` lies within the bounds (with a tiny relative slack for rounding).
    pub fn contains(&self, x: f64) -> bool {
        let slack = BOUND_SLACK * (self.max - self.min).abs().max(self.max.abs());
        x.is_finite() && x >= self.min - slack && x <= self.max + slack
    }

    /// Whether the parameter is held at a fixed value rather than sampled.
    pub fn is_fixed(&self) -> bool {
        self.fixed.is_some()
    }
}

/// A parameter space: the metamodel's inputs in file order, with the contact-model class they
/// belong to.
#[derive(Debug, Clone, PartialEq)]
pub struct Space {
    /// Optional human-readable title from the file's `name` key.
    pub name: Option<String>,
    /// All parameters, free and fixed, in file order; the free ones span the unit cube in this
    /// order.
    pub parameters: Vec<Parameter>,
    /// The `[model] class` of the file; `None`: seed 004's default class.
    pub model_class: Option<ModelClass>,
    /// Where the space came from (file path), used in error messages.
    pub source: String,
    /// `[constraints] expr`: linear limits between parameters that carve the valid region out of
    /// the box (`ced_pp <= 0.01*E_p`: where the experiment still measures). A train runs only
    /// the design rows inside them, and its model keeps them, so a calibration stays inside too.
    pub constraints: Vec<Constraint>,
}

// The file as written. Required keys are `Option`s so that `validate` can say what a missing
// one means; serde only refuses unknown keys and values of the wrong type.

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a parameter-space file")]
struct SpaceFile {
    name: Option<String>,
    /// Free text for the reader; any TOML value is accepted and ignored.
    #[allow(dead_code)]
    description: Option<IgnoredAny>,
    parameters: Option<Entries<ParameterFile>>,
    model: Option<ModelTable>,
    constraints: Option<ConstraintsFile>,
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `expr = [\"ced_pp <= 0.01*E_p\", ...]`"
)]
struct ConstraintsFile {
    #[serde(default)]
    expr: Vec<String>,
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "an inline table such as { unit = \"-\", min = 0.0, max = 1.0 }"
)]
struct ParameterFile {
    unit: Option<String>,
    min: Option<f64>,
    max: Option<f64>,
    scale: Option<String>,
    fixed: Option<f64>,
    what: Option<String>,
}

impl Space {
    /// Reads and checks a `space.toml` (see the module docs for the format).
    pub fn from_file(path: &Path) -> Result<Space> {
        let text = read_to_string(path)?;
        Space::from_toml_str(&text, &path.display().to_string())
    }

    /// Parses a space from TOML text; `source` names the file in error messages.
    ///
    /// # Example
    ///
    /// A log-scaled Young's modulus and a fixed restitution coefficient: only the modulus is
    /// sampled, and the middle of its unit interval is the geometric mean of the bounds.
    ///
    /// ```
    /// use mbgc::space::{Scale, Space};
    ///
    /// let text = r#"
    /// [parameters]
    /// E_p  = { unit = "Pa", min = 5e6, max = 5e8, scale = "log" }
    /// e_pp = { min = 0.05, max = 0.95, fixed = 0.6 }
    /// "#;
    /// let space = Space::from_toml_str(text, "example").unwrap();
    /// assert_eq!(space.dim(), 1);
    /// assert_eq!(space.names(), ["E_p", "e_pp"]);
    /// assert_eq!(space.get("E_p").unwrap().scale, Scale::Log);
    /// let x = space.to_physical(&[0.5]);
    /// assert!((x[0] - 5e7).abs() < 1e-3 && x[1] == 0.6);
    /// assert!(Space::from_toml_str("[parameters]\nmu = { min = 1, max = 0 }", "bad").is_err());
    /// ```
    pub fn from_toml_str(text: &str, source: &str) -> Result<Space> {
        let file: SpaceFile = from_toml(text, source)?;
        let params = file.parameters.ok_or_else(|| {
            Error::input(
                source,
                "parameters",
                "missing; expected a [parameters] table with at least one parameter",
            )
        })?;
        if params.0.is_empty() {
            return Err(Error::input(
                source,
                "parameters",
                "empty; expected at least one parameter",
            ));
        }
        let parameters = params
            .0
            .into_iter()
            .map(|(name, p)| p.validate(source, name))
            .collect::<Result<Vec<_>>>()?;
        let model_class = file.model.map(|m| m.class(source)).transpose()?;
        let class = model_class.unwrap_or_default();
        refuse_inactive_parameters(
            &class,
            parameters.iter().map(|p| p.name.as_str()),
            source,
            "parameters",
            "this space",
        )?;
        // A structural constant of an effect (one that selects a model) is fixed, not sampled.
        for p in parameters.iter().filter(|p| !p.is_fixed()) {
            let structural = class
                .parameters(&Pair::BOTH)
                .into_iter()
                .any(|(n, spec, _)| n == p.name && !spec.variable);
            if structural {
                return Err(Error::input(
                    source,
                    format!("parameters.{}", p.name),
                    "a structural constant of its effect: a metamodel may not vary it; expected \
                     `fixed = VALUE`",
                ));
            }
        }
        let constraints = file
            .constraints
            .map(|c| c.expr)
            .unwrap_or_default()
            .iter()
            .enumerate()
            .map(|(i, text)| space_constraint(text, &parameters, source, i))
            .collect::<Result<Vec<_>>>()?;
        Ok(Space {
            name: file.name,
            parameters,
            model_class,
            source: source.to_string(),
            constraints,
        })
    }

    /// The first constraint that physical values of all parameters (file order) violate.
    pub fn violated(&self, x: &[f64]) -> Option<&Constraint> {
        assert_eq!(x.len(), self.parameters.len());
        let value = |n: &str| {
            self.parameters
                .iter()
                .position(|p| p.name == n)
                .map_or(f64::NAN, |i| x[i])
        };
        self.constraints
            .iter()
            .find(|c| c.violation(value) > CONSTRAINT_SLACK)
    }

    /// The model class of the space (seed 004's when the file names none).
    pub fn class(&self) -> ModelClass {
        self.model_class.unwrap_or_default()
    }

    /// Number of free (sampled) parameters: the dimension of the unit cube.
    pub fn dim(&self) -> usize {
        self.parameters.iter().filter(|p| !p.is_fixed()).count()
    }

    /// The free (sampled) parameters in file order, one per unit-cube dimension.
    pub fn free(&self) -> impl Iterator<Item = &Parameter> {
        self.parameters.iter().filter(|p| !p.is_fixed())
    }

    /// Names of all parameters, fixed ones included, in file order: the columns of a physical
    /// design.
    pub fn names(&self) -> Vec<&str> {
        self.parameters.iter().map(|p| p.name.as_str()).collect()
    }

    /// The parameter called `name`, if the space has one.
    pub fn get(&self, name: &str) -> Option<&Parameter> {
        self.parameters.iter().find(|p| p.name == name)
    }

    /// Physical values of all parameters (fixed ones included, file order) for a unit-cube point
    /// over the free parameters.
    pub fn to_physical(&self, u: &[f64]) -> Vec<f64> {
        assert_eq!(u.len(), self.dim(), "unit point has the wrong dimension");
        let mut free = u.iter();
        self.parameters
            .iter()
            .map(|p| match p.fixed {
                Some(v) => v,
                None => p.from_unit(*free.next().expect("dimension checked above")),
            })
            .collect()
    }

    /// Unit-cube coordinates of the free parameters from physical values of all parameters.
    /// Values must already be checked to lie in their bounds; results are clamped to [0, 1] to
    /// absorb rounding at the bounds.
    pub fn to_unit(&self, x: &[f64]) -> Vec<f64> {
        assert_eq!(x.len(), self.parameters.len());
        self.parameters
            .iter()
            .zip(x)
            .filter(|(p, _)| !p.is_fixed())
            .map(|(p, &v)| p.to_unit(v).clamp(0.0, 1.0))
            .collect()
    }
}

/// Violation tolerated by [`Space::violated`] (constraints are scaled so that the largest
/// coefficient is 1): a point written at the limit and read back is inside.
const CONSTRAINT_SLACK: f64 = 1e-9;

/// A space's constraint: its names are parameters of the space, and it can bind somewhere in the
/// box and hold somewhere (else it would refuse every design row or do nothing).
fn space_constraint(
    text: &str,
    parameters: &[Parameter],
    source: &str,
    i: usize,
) -> Result<Constraint> {
    let field = format!("constraints.expr[{i}]");
    let c = Constraint::parse(text, source, &field)?;
    for (n, _) in &c.terms {
        if !parameters.iter().any(|p| &p.name == n) {
            return Err(Error::input(
                source,
                &field,
                format!("\"{n}\" is not a parameter of this space"),
            ));
        }
    }
    // Over the box (fixed parameters at their value), the linear form's range.
    let (mut lo, mut hi) = (c.constant, c.constant);
    for (n, coef) in &c.terms {
        let p = parameters
            .iter()
            .find(|p| &p.name == n)
            .expect("checked above");
        let (a, b) = match p.fixed {
            Some(v) => (v, v),
            None => (p.min, p.max),
        };
        lo += (coef * a).min(coef * b);
        hi += (coef * a).max(coef * b);
    }
    if lo > CONSTRAINT_SLACK {
        return Err(Error::input(
            source,
            &field,
            format!(
                "\"{}\" holds nowhere in the parameters' ranges: no point could be sampled",
                c.text
            ),
        ));
    }
    if hi <= CONSTRAINT_SLACK {
        return Err(Error::input(
            source,
            &field,
            format!(
                "\"{}\" holds everywhere in the parameters' ranges, so it limits nothing; remove it",
                c.text
            ),
        ));
    }
    Ok(c)
}

impl ParameterFile {
    /// Everything serde cannot say: what is missing, out of range or inconsistent.
    fn validate(self, source: &str, pname: String) -> Result<Parameter> {
        let field = |k: &str| format!("parameters.{pname}.{k}");
        if !is_identifier(&pname) {
            return Err(Error::input(
                source,
                format!("parameters.{pname}"),
                "parameter names must start with a letter and contain only letters, digits and _",
            ));
        }
        let min = self
            .min
            .ok_or_else(|| Error::input(source, field("min"), "missing lower bound"))?;
        let max = self
            .max
            .ok_or_else(|| Error::input(source, field("max"), "missing upper bound"))?;
        for (k, v) in [("min", min), ("max", max)] {
            if !v.is_finite() {
                return Err(Error::input(source, field(k), "expected a finite number"));
            }
        }
        if min >= max {
            return Err(Error::input(
                source,
                field("min"),
                format!("min ({min}) must be smaller than max ({max})"),
            ));
        }
        let scale = match self.scale.as_deref() {
            None | Some("linear") => Scale::Linear,
            Some("log") => Scale::Log,
            Some(other) => {
                return Err(Error::input(
                    source,
                    field("scale"),
                    format!("expected \"linear\" or \"log\", found \"{other}\""),
                ))
            }
        };
        if scale == Scale::Log && min <= 0.0 {
            return Err(Error::input(
                source,
                field("min"),
                format!("log scale needs min > 0, found {min}"),
            ));
        }
        // The unit-cube mapping computes max - min (or max / min); a span that overflows would
        // put inf into every design.
        let span = match scale {
            Scale::Linear => max - min,
            Scale::Log => max / min,
        };
        if !span.is_finite() {
            return Err(Error::input(
                source,
                field("max"),
                match scale {
                    Scale::Linear => format!(
                        "a range [{min:e}, {max:e}] whose width max - min is a finite number (it \
                         overflows); expected narrower bounds or scale = \"log\""
                    ),
                    Scale::Log => format!(
                        "a log range [{min:e}, {max:e}] whose ratio max / min is a finite number \
                         (it overflows); expected narrower bounds"
                    ),
                },
            ));
        }
        if let Some(v) = self.fixed {
            if !v.is_finite() || v < min || v > max {
                return Err(Error::input(
                    source,
                    field("fixed"),
                    format!("fixed value {v} must lie within [min, max] = [{min}, {max}]"),
                ));
            }
        }
        Ok(Parameter {
            name: pname,
            unit: self.unit.unwrap_or_else(|| "-".to_string()),
            min,
            max,
            scale,
            fixed: self.fixed,
            what: self.what.unwrap_or_default(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
name = "test"
[parameters]
E_p = { unit = "Pa", min = 5e6, max = 5e8, scale = "log" }
mu_pp = { min = 0, max = 1 }
e_pp = { min = 0.05, max = 0.95, fixed = 0.6 }
"#;

    #[test]
    fn the_model_class_decides_which_effect_parameters_a_space_may_hold() {
        let s = Space::from_toml_str(GOOD, "good.toml").unwrap();
        assert_eq!(s.class(), ModelClass::default());
        let cohesive = format!("{GOOD}ced_pp = {{ unit = \"J/m3\", min = 0, max = 3e4 }}\n");
        let e = Space::from_toml_str(&cohesive, "s.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("s.toml") && e.contains("parameters.ced_pp") && e.contains("sjkr"),
            "{e}"
        );
        let with_model = format!("{cohesive}[model]\nclass = \"hertz,mindlin,epsd2,sjkr\"\n");
        let s = Space::from_toml_str(&with_model, "s.toml").unwrap();
        assert_eq!(s.class().to_string(), "hertz,mindlin,epsd2,sjkr");
        let e = Space::from_toml_str(&format!("{GOOD}[model]\nclass = \"hertz\"\n"), "s.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("model.class") && e.contains("tangential"), "{e}");
    }

    #[test]
    fn constraints_carve_the_box_and_refuse_what_limits_nothing_or_everything() {
        let s = Space::from_toml_str(
            &format!("{GOOD}[constraints]\nexpr = [\"mu_pp <= 2e-9*E_p\"]\n"),
            "c.toml",
        )
        .unwrap();
        assert_eq!(s.constraints.len(), 1);
        // mu_pp 0.5 is allowed from E_p 2.5e8 up.
        assert!(s.violated(&[1e8, 0.5, 0.6]).is_some());
        assert!(s.violated(&[3e8, 0.5, 0.6]).is_none());
        let bad = |expr: &str| err(&format!("{GOOD}[constraints]\nexpr = [\"{expr}\"]\n"));
        let e = bad("mu_r_pp <= mu_pp");
        assert!(
            e.contains("constraints.expr[0]")
                && e.contains("mu_r_pp")
                && e.contains("not a parameter"),
            "{e}"
        );
        let e = bad("mu_pp <= 2");
        assert!(
            e.contains("holds everywhere") && e.contains("remove it"),
            "{e}"
        );
        let e = bad("mu_pp >= 1e-6*E_p + 1");
        assert!(e.contains("holds nowhere"), "{e}");
        // The fixed e_pp = 0.6 counts at its value: mu_pp <= e_pp binds (mu_pp reaches 1).
        assert!(Space::from_toml_str(
            &format!("{GOOD}[constraints]\nexpr = [\"mu_pp <= e_pp\"]\n"),
            "c.toml"
        )
        .is_ok());
        let e = bad("mu_pp <=");
        assert!(e.contains("constraints.expr[0]"), "{e}");
    }

    #[test]
    fn parses_and_maps_round_trip() {
        let s = Space::from_toml_str(GOOD, "good.toml").unwrap();
        assert_eq!(s.dim(), 2);
        assert_eq!(s.names(), vec!["E_p", "mu_pp", "e_pp"]);
        let x = s.to_physical(&[0.5, 0.25]);
        assert!(
            (x[0] - 5e7).abs() < 1e-6,
            "log midpoint is the geometric mean"
        );
        assert_eq!(x[1], 0.25);
        assert_eq!(x[2], 0.6);
        let u = s.to_unit(&x);
        assert!((u[0] - 0.5).abs() < 1e-14 && (u[1] - 0.25).abs() < 1e-14);
    }

    fn err(text: &str) -> String {
        Space::from_toml_str(text, "bad.toml")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn rejects_bad_files_naming_file_and_field() {
        let e = err("[parameters]\na = { max = 1 }");
        assert!(
            e.contains("bad.toml") && e.contains("parameters.a.min"),
            "{e}"
        );
        let e = err("[parameters]\na = { min = 2, max = 1 }");
        assert!(
            e.contains("parameters.a.min") && e.contains("smaller"),
            "{e}"
        );
        let e = err("[parameters]\na = { min = 0, max = 1, scale = \"log\" }");
        assert!(e.contains("parameters.a.min") && e.contains("log"), "{e}");
        let e = err("[parameters]\na = { min = 0, max = 1, unt = \"m\" }");
        assert!(
            e.contains("parameters.a.unt") && e.contains("unknown"),
            "{e}"
        );
        let e = err("[parameters]\na = { min = 0, max = 1, fixed = 3 }");
        assert!(e.contains("parameters.a.fixed"), "{e}");
        let e = err("[parameters]\na = { min = 0, max = nan }");
        assert!(
            e.contains("parameters.a.max") && e.contains("finite"),
            "{e}"
        );
        let e = err("[parameters]\na = { min = 0, max = 1, scale = \"cubic\" }");
        assert!(e.contains("parameters.a.scale"), "{e}");
        let e = err("[params]\na = { min = 0, max = 1 }");
        assert!(e.contains("params") && e.contains("unknown key"), "{e}");
        let e = err("[parameters]\na = { min = 0, max = 1");
        assert!(e.contains("bad.toml") && e.contains("TOML"), "{e}");
    }

    #[test]
    fn wrong_types_name_the_path_found_and_expected() {
        let e = err("[parameters]\na = { min = \"x\", max = 1 }");
        assert!(
            e.starts_with("bad.toml: parameters.a.min: ")
                && e.contains("a number")
                && e.contains("string"),
            "{e}"
        );
        let e = err("[parameters]\na = 3");
        assert!(
            e.starts_with("bad.toml: parameters.a: ") && e.contains("inline table"),
            "{e}"
        );
        let e = err("[parameters]\na = { min = 0, max = 1 }\n[parameters.b]\nmin = 0\nunits = 1");
        assert!(
            e.starts_with("bad.toml: parameters.b.units: unknown key"),
            "{e}"
        );
        let e = err("[parameters]\n");
        assert!(e.contains("parameters") && e.contains("empty"), "{e}");
        let e = err("name = \"x\"");
        assert!(e.contains("parameters") && e.contains("missing"), "{e}");
        // A description is free text for the reader: any value is accepted.
        let s = Space::from_toml_str(
            "description = [1, \"two\"]\n[parameters]\nb = { min = 0, max = 1 }\na = { min = 0, max = 1 }",
            "ok.toml",
        )
        .unwrap();
        assert_eq!(s.names(), ["b", "a"]);
    }

    #[test]
    fn ranges_whose_width_overflows_are_refused() {
        for text in [
            "[parameters]\na = { min = -1e308, max = 1e308 }",
            "[parameters]\na = { min = 1e-300, max = 1e300, scale = \"log\" }",
        ] {
            let e = Space::from_toml_str(text, "s.toml")
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("parameters.a.max") && e.contains("overflows"),
                "{e}"
            );
        }
        // Wide but representable: every mapped value finite.
        let s = Space::from_toml_str(
            "[parameters]\na = { min = 1e-150, max = 1e150, scale = \"log\" }",
            "s.toml",
        )
        .unwrap();
        for u in [0.0, 0.3, 1.0] {
            assert!(s.parameters[0].from_unit(u).is_finite());
        }
    }
}
