//! Extending a design with a deterministic low-discrepancy sequence (Sobol, Halton).

use super::metrics;
use super::points::{self, Points};
use crate::error::{Error, Result};

/// Extends a design with points of a deterministic sequence (Sobol, Halton); `gen(start, count)`
/// returns points `start..start + count` of the sequence, which has `max_points` points at most.
///
/// If the existing points are the sequence's own first points, the sequence simply continues, so
/// extending equals generating the larger design at once. A sequence knows nothing of anyone
/// else's points, though, and continuing it beside a foreign design puts some new points right
/// next to old ones. Then we walk on along the sequence and skip every point closer to an
/// existing point than the minimum distance of the one-shot design of the final size (halving
/// that radius if the sequence runs out), which keeps the new points as spread as the sequence's
/// own design.
pub(crate) fn extend_sequence(
    existing: &Points,
    n_new: usize,
    max_points: usize,
    gen: impl Fn(usize, usize) -> Points,
) -> Result<Points> {
    let n_old = existing.len();
    let too_many = |n: usize| {
        Error::invalid(format!(
            "the sequence has at most {max_points} points; asked for {n}. Use fssf-f for larger designs"
        ))
    };
    if n_old + n_new > max_points {
        return Err(too_many(n_old + n_new));
    }
    if n_old == 0 {
        return Ok(gen(0, n_new));
    }
    let own = gen(0, n_old);
    let is_prefix = own
        .as_flat()
        .iter()
        .zip(existing.as_flat())
        .all(|(a, b)| (a - b).abs() <= 1e-9);
    if is_prefix {
        return Ok(gen(n_old, n_new));
    }
    let mut radius2 = if n_old + n_new >= 2 {
        metrics::mid(&gen(0, n_old + n_new)).powi(2)
    } else {
        0.0
    };
    loop {
        let mut out = Points::with_capacity(existing.dim(), n_new);
        let mut index = n_old;
        while out.len() < n_new && index < max_points {
            let chunk = (2 * n_new).min(max_points - index);
            let pts = gen(index, chunk);
            for p in pts.rows() {
                if existing.rows().all(|x| points::dist2(p, x) >= radius2) {
                    out.push(p);
                    if out.len() == n_new {
                        break;
                    }
                }
            }
            index += chunk;
        }
        if out.len() == n_new {
            return Ok(out);
        }
        if radius2 == 0.0 {
            return Err(too_many(index + n_new - out.len()));
        }
        radius2 = if radius2 < 1e-24 { 0.0 } else { radius2 / 4.0 };
    }
}
