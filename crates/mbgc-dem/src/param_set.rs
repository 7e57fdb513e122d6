//! Named parameter values: what a design row, a material or a command line gives a run.

use crate::error::{Error, Result};

/// Named parameter values, in insertion order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParamSet {
    values: Vec<(String, f64)>,
}

impl ParamSet {
    /// No values.
    pub fn new() -> Self {
        Self::default()
    }

    /// The values of `(name, value)` pairs; a repeated name keeps its last value, at its first
    /// position.
    pub fn from_pairs<S: AsRef<str>>(pairs: &[(S, f64)]) -> Self {
        let mut p = ParamSet::new();
        for (k, v) in pairs {
            p.set(k.as_ref(), *v);
        }
        p
    }

    /// Sets (or replaces) a value.
    pub fn set(&mut self, name: &str, value: f64) -> &mut Self {
        match self.values.iter_mut().find(|(k, _)| k == name) {
            Some(e) => e.1 = value,
            None => self.values.push((name.to_string(), value)),
        }
        self
    }

    /// The value of `name`, if set (unchecked; see [`ParamSet::require`]).
    pub fn get(&self, name: &str) -> Option<f64> {
        self.values.iter().find(|(k, _)| k == name).map(|(_, v)| *v)
    }

    /// Every `(name, value)`, in insertion order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, f64)> {
        self.values.iter().map(|(k, v)| (k.as_str(), *v))
    }

    /// The value of a parameter that must lie in `[lo, hi]`; the error names the parameter.
    pub fn require(&self, name: &str, lo: f64, hi: f64) -> Result<f64> {
        let v = self.get(name).ok_or_else(|| {
            Error::invalid(format!(
                "parameter {name}: missing (expected a value in [{lo}, {hi}])"
            ))
        })?;
        if !(v.is_finite() && v >= lo && v <= hi) {
            return Err(Error::invalid(format!(
                "parameter {name} = {v}: expected a finite value in [{lo}, {hi}]"
            )));
        }
        Ok(v)
    }

    /// An optional value with a default, checked like [`ParamSet::require`].
    pub fn optional(&self, name: &str, default: f64, lo: f64, hi: f64) -> Result<f64> {
        match self.get(name) {
            None => Ok(default),
            Some(_) => self.require(name, lo, hi),
        }
    }
}
