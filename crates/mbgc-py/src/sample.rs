//! `sample`: a space-filling design, new or extending an existing one, as `mbgc sample` makes
//! it (src/sample.rs): the same checks, samplers and summary.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyBytes;

use mbgc::sampling::{extend_design, fssf, lhs, metrics, mipt, Design, Method, Sampler};
use mbgc::space::Space;

use crate::convert::bytes_of;
use crate::documents::Document;
use crate::errors::{invalid, OrRaise};

/// The largest design `sample` makes (as the command line's): beyond this the design file alone
/// is gigabytes.
const MAX_VALUES: usize = 50_000_000;
/// Above this many points the summary skips the O(n^2) metrics.
const SUMMARY_MAX_POINTS: usize = 20_000;

/// A design: `n` new points (or `add` more after the design in `extend`) of the space (a file,
/// or a dict's JSON) or of a bare unit cube of `dim` dimensions. Returns the header, the values
/// row after row as float64 bytes, and the summary (as `--json` prints it, without `out`).
#[pyfunction]
#[pyo3(signature = (method, n, add, space_path, space_json, space_label, dim, seed, extend, mipt_alpha, fssf_candidates, out))]
#[allow(clippy::too_many_arguments)]
pub fn sample<'py>(
    py: Python<'py>,
    method: &str,
    n: Option<usize>,
    add: Option<usize>,
    space_path: Option<PathBuf>,
    space_json: Option<String>,
    space_label: &str,
    dim: Option<usize>,
    seed: u64,
    extend: Option<PathBuf>,
    mipt_alpha: f64,
    fssf_candidates: Option<usize>,
    out: Option<PathBuf>,
) -> PyResult<(Vec<String>, Bound<'py, PyBytes>, String)> {
    let method: Method = method.parse().or_raise(py)?;
    let space = match (space_path, space_json) {
        (None, None) => None,
        (p, j) => Some(
            match Document::new(py, p, j, space_label)? {
                Document::File(path) => Space::from_file(&path),
                Document::Text { toml, label } => Space::from_toml_str(&toml, &label),
            }
            .or_raise(py)?,
        ),
    };
    let dim = match (&space, dim) {
        (Some(_), Some(_)) => {
            return Err(invalid(
                py,
                "--dim: a space gives the dimension; pass a space or dim, not both",
            ))
        }
        (Some(s), None) => s.dim(),
        (None, Some(0)) => return Err(invalid(py, "--dim: expected at least 1")),
        (None, Some(d)) => d,
        (None, None) => {
            return Err(invalid(
                py,
                "--space or --dim: expected a parameter space or the dimension of a unit cube",
            ))
        }
    };
    let (flag, n) = match (n, add, &extend) {
        (Some(_), _, Some(path)) => {
            return Err(invalid(
                py,
                format!(
                    "--n with --extend: --n is the size of a new design; give the points to add \
                     to {} with --add",
                    path.display()
                ),
            ))
        }
        (Some(_), Some(_), None) | (None, Some(_), None) => {
            return Err(invalid(py, "--add: extends a design, so it needs --extend"))
        }
        (Some(n), None, None) => ("--n", n),
        (None, Some(m), Some(_)) => ("--add", m),
        (None, None, _) => {
            return Err(invalid(
                py,
                "--n: expected the size of a new design (or --add with --extend)",
            ))
        }
    };
    if n == 0 {
        return Err(invalid(
            py,
            format!("{flag}: expected at least one new point"),
        ));
    }
    if n.checked_mul(dim).is_none_or(|v| v > MAX_VALUES) {
        return Err(invalid(
            py,
            format!(
                "{flag} {n} in {dim} dimensions: expected at most {MAX_VALUES} values in all (n x dim)"
            ),
        ));
    }
    if let Some(c) = fssf_candidates {
        let most = MAX_VALUES / dim;
        if c < n || c > most {
            return Err(invalid(
                py,
                format!(
                    "--fssf-candidates {c} in {dim} dimensions: expected {n} to {most} candidates \
                     (at least one per new point, at most {MAX_VALUES} values in all, candidates x \
                     dim)"
                ),
            ));
        }
    }
    let (design, outside, m) = py
        .detach(|| -> mbgc::Result<_> {
            let mut design = match &extend {
                Some(path) => {
                    let d = Design::read(path, space.as_ref())?;
                    if d.unit.dim() != dim {
                        return Err(mbgc::Error::invalid(format!(
                            "{}: has {} columns but --dim asks for {dim}",
                            path.display(),
                            d.unit.dim()
                        )));
                    }
                    d
                }
                None => Design::empty(space.as_ref(), dim),
            };
            let sampler: Box<dyn Sampler> = match method {
                Method::Mipt => Box::new(mipt::Mipt {
                    alpha: mipt_alpha,
                    ..Default::default()
                }),
                Method::FssfF | Method::FssfFr => Box::new(fssf::Fssf {
                    candidates: fssf_candidates,
                    ..if method == Method::FssfF {
                        fssf::Fssf::forward()
                    } else {
                        fssf::Fssf::forward_reflected()
                    }
                }),
                Method::LhsMaximin => Box::new(lhs::Lhs::maximin()),
                m => m.sampler(),
            };
            let new = extend_design(sampler.as_ref(), &design.unit, n, seed).map_err(|e| {
                mbgc::Error::invalid(format!("sampling with {}: {e}", method.name()))
            })?;
            design.append_unit(space.as_ref(), &new);
            if let Some(out) = &out {
                design.write(out)?;
            }
            let m = (design.len() >= 2 && design.len() <= SUMMARY_MAX_POINTS)
                .then(|| metrics::metrics(&design.unit));
            let outside = space.as_ref().map_or(0, |s| {
                design
                    .values
                    .iter()
                    .filter(|x| s.violated(x).is_some())
                    .count()
            });
            Ok((design, outside, m))
        })
        .or_raise(py)?;
    let summary = serde_json::json!({
        "outside_constraints": outside,
        "method": method.name(),
        "seed": seed,
        "dim": dim,
        "existing": design.len() - n,
        "new": n,
        "n": design.len(),
        "metrics": m,
    });
    let values = bytes_of(design.values.iter().flatten().copied());
    Ok((
        design.header.clone(),
        PyBytes::new(py, &values),
        summary.to_string(),
    ))
}
