//! Linear inequalities between parameters, `e_pw <= e_pp` or `ced_pp <= 0.01*E_p`: a material's
//! constraints on its solutions, and a space's limits on where its model is valid.

use crate::error::{Error, Result};

/// `sum coef * x[name] + constant <= 0`, from a text such as `e_pw <= e_pp` or
/// `mu_pp + 0.5*mu_r_pp <= 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct Constraint {
    /// The inequality as written (trimmed), for messages.
    pub text: String,
    /// `(parameter, coefficient)` pairs, scaled so the largest |coefficient| is 1.
    pub terms: Vec<(String, f64)>,
    /// The constant term, on the same scale.
    pub constant: f64,
}

impl Constraint {
    /// Positive by how much the constraint is violated at `value(name)` (infinite where a value
    /// is NaN).
    pub fn violation(&self, value: impl Fn(&str) -> f64) -> f64 {
        let g: f64 = self.terms.iter().map(|(n, c)| c * value(n)).sum::<f64>() + self.constant;
        // A missing value (NaN) cannot be shown to satisfy it.
        if g.is_nan() {
            f64::INFINITY
        } else {
            g.max(0.0)
        }
    }
}

/// Parses a linear expression such as `0.5*mu_r_pp + mu_pp - 3e-1` into terms and a constant.
/// Grammar: `expr = ["+"|"-"] term {("+"|"-") term}`, `term = number | name | number "*" name |
/// name "*" number`; numbers as in Rust and TOML (`3e-1`, `1.5E+2`, `.5`), finite only.
fn linear(side: &str, file: &str, field: &str) -> Result<(Vec<(String, f64)>, f64)> {
    #[derive(Debug, PartialEq)]
    enum Tok {
        Num(f64),
        Name(String),
        Plus,
        Minus,
        Times,
    }
    let expected = "a linear inequality such as \"e_pw <= e_pp\" or \"mu_pp + 0.5*mu_r_pp <= 1\"";
    let bad = |what: String| Error::input(file, field, format!("{expected}; {what}"));
    let c: Vec<char> = side.chars().collect();
    let mut toks = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch.is_whitespace() {
            i += 1;
        } else if ch.is_ascii_digit() || ch == '.' {
            let start = i;
            while i < c.len() && (c[i].is_ascii_digit() || c[i] == '.') {
                i += 1;
            }
            if i < c.len() && (c[i] == 'e' || c[i] == 'E') {
                i += 1;
                if i < c.len() && (c[i] == '+' || c[i] == '-') {
                    i += 1;
                }
                while i < c.len() && c[i].is_ascii_digit() {
                    i += 1;
                }
            }
            let text: String = c[start..i].iter().collect();
            match text.parse::<f64>() {
                Ok(v) if v.is_finite() => toks.push(Tok::Num(v)),
                _ => return Err(bad(format!("\"{text}\" is not a finite number"))),
            }
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            let name: String = c[start..i].iter().collect();
            // f64's parser would read these as numbers; a bound of infinity or NaN means nothing.
            if ["inf", "infinity", "nan"].contains(&name.to_ascii_lowercase().as_str()) {
                return Err(bad(format!("\"{name}\": expected a finite number")));
            }
            toks.push(Tok::Name(name));
        } else {
            toks.push(match ch {
                '+' => Tok::Plus,
                '-' => Tok::Minus,
                '*' => Tok::Times,
                other => return Err(bad(format!("unexpected \"{other}\""))),
            });
            i += 1;
        }
    }
    let mut terms: Vec<(String, f64)> = Vec::new();
    let mut constant = 0.0;
    let mut k = 0;
    let mut first = true;
    while k < toks.len() || first {
        let mut sign = 1.0;
        match toks.get(k) {
            Some(Tok::Plus) => k += 1,
            Some(Tok::Minus) => {
                sign = -1.0;
                k += 1;
            }
            _ if first => {}
            _ => return Err(bad("expected + or - between terms".into())),
        }
        first = false;
        let term = match (toks.get(k), toks.get(k + 1), toks.get(k + 2)) {
            (Some(Tok::Num(a)), Some(Tok::Times), Some(Tok::Name(n))) => {
                k += 3;
                (Some(n.clone()), *a)
            }
            (Some(Tok::Name(n)), Some(Tok::Times), Some(Tok::Num(a))) => {
                k += 3;
                (Some(n.clone()), *a)
            }
            (Some(Tok::Num(a)), _, _) => {
                k += 1;
                (None, *a)
            }
            (Some(Tok::Name(n)), _, _) => {
                k += 1;
                (Some(n.clone()), 1.0)
            }
            _ => return Err(bad("expected a number or a parameter name".into())),
        };
        match term {
            (Some(n), coef) if is_identifier(&n) => terms.push((n, sign * coef)),
            (Some(n), _) => return Err(bad(format!("\"{n}\" is not a parameter name"))),
            (None, v) => constant += sign * v,
        }
    }
    Ok((terms, constant))
}

impl Constraint {
    /// Reads `lhs <= rhs` (or `>=`), both sides linear in the parameters; errors name `file`
    /// and `field`.
    pub fn parse(text: &str, file: &str, field: &str) -> Result<Constraint> {
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
        // Scaled so that the largest coefficient is 1: the penalty then means the same for
        // `1e300*x >= 1e300` as for `x >= 1` and cannot overflow.
        let scale = terms.iter().map(|(_, c)| c.abs()).fold(0.0, f64::max);
        let constant = s * (lc - rc) / scale;
        let terms: Vec<(String, f64)> = terms.into_iter().map(|(n, c)| (n, c / scale)).collect();
        if !constant.is_finite() || terms.iter().any(|(_, c)| !c.is_finite()) {
            return Err(Error::input(
                file,
                field,
                format!("\"{text}\": coefficients and bounds must be finite once scaled"),
            ));
        }
        Ok(Constraint {
            text: text.trim().to_string(),
            terms,
            constant,
        })
    }
}

/// Parameter and response names become CSV headers and equation variables.
pub fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}
