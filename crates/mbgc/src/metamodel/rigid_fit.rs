//! Measuring a model's rigid limit ([`super::rigid_limit`]) from lines of DEM runs: each line
//! holds a point of the space and varies only the stiffness group, from the model's domain edge
//! outwards. The caller reads the runs; this takes them as data and returns the model with its
//! limit.

use super::model::Metamodel;
use super::rigid_limit::{
    Cohesion, CohesionCurve, CohesionKnot, Curve, LineShifts, RigidLimit, COHESION_POWER,
};
use crate::error::{Error, Result};

/// One line: the model's inputs at its point (any value of the input moved along the group)
/// and its runs as `(group value, one value per model response, NaN where missing)`.
#[derive(Clone, Debug)]
pub struct Line {
    /// The point's name.
    pub label: String,
    /// The model's inputs, in the model's order.
    pub inputs: Vec<f64>,
    /// The runs.
    pub runs: Vec<(f64, Vec<f64>)>,
}

/// How the limit is measured and where it applies.
#[derive(Clone, Debug)]
pub struct RigidFit<'a> {
    /// The group the lines vary (`K_p`).
    pub group: &'a str,
    /// The input that moves along it (`E_p`).
    pub along: &'a str,
    /// The wall's group and input, moved together with the particle's on the lines.
    pub wall: Option<(&'a str, &'a str)>,
    /// The largest value the inputs moved along may take (the space's top, e.g. seed 004's E
    /// of 5e8 Pa): their domains grow to it, the groups' reach bounds them.
    pub along_max: f64,
    /// What the tables were, for the record.
    pub source: String,
    /// A run this close to the domain's edge (in decades) stands for the edge
    /// ([`EDGE_DECADES`] unless the lines were run for another model's edge).
    pub edge_decades: f64,
}

/// A run this close to the domain's edge (in decades) stands for the edge: the lines run for a
/// model hit its edge to within rounding.
pub const EDGE_DECADES: f64 = 0.01;

/// The largest [`RigidFit::edge_decades`] taken: the edge's value is read from the run nearest
/// it, and a run farther than this would stand for a response that still moves.
pub const EDGE_DECADES_MAX: f64 = 0.05;

/// The model with the rigid limit measured on `lines`.
pub fn fit_rigid_limit(model: &Metamodel, fit: &RigidFit, lines: &[Line]) -> Result<Metamodel> {
    let bad = |what: String| Error::invalid(format!("rigid limit: {what}"));
    let gd = model
        .groups
        .iter()
        .find(|g| g.group.name == fit.group)
        .ok_or_else(|| bad(format!("the model has no group {}", fit.group)))?;
    let k_along = model.along_input(fit.group, fit.along).ok_or_else(|| {
        bad(format!(
            "{} does not enter {} alone with power 1",
            fit.along, fit.group
        ))
    })?;
    let wall_along = match fit.wall {
        Some((g, a)) => Some(
            model
                .along_input(g, a)
                .ok_or_else(|| bad(format!("{a} does not enter {g} alone with power 1")))?,
        ),
        None => None,
    };
    if !(fit.edge_decades > 0.0 && fit.edge_decades <= EDGE_DECADES_MAX) {
        return Err(bad(format!(
            "the edge tolerance must lie in (0, {EDGE_DECADES_MAX}] decades, got {}",
            fit.edge_decades
        )));
    }
    if !(fit.along_max.is_finite() && fit.along_max > 0.0) {
        return Err(bad(format!(
            "the largest {} must be positive, got {}",
            fit.along, fit.along_max
        )));
    }
    let n_in = model.inputs.len();
    if let Some(l) = lines.iter().find(|l| l.inputs.len() != n_in) {
        return Err(bad(format!(
            "line {}: {} inputs, the model has {n_in}",
            l.label,
            l.inputs.len()
        )));
    }
    let mut curves = Vec::new();
    let mut used: Vec<String> = Vec::new();
    let mut reach = gd.domain;
    for (r, resp) in model.responses.iter().enumerate() {
        for stiff in [false, true] {
            let edge = gd.domain[usize::from(stiff)];
            let shifts: Vec<LineShifts> = lines
                .iter()
                .filter_map(|l| {
                    line_shifts(
                        model,
                        l,
                        r,
                        (k_along, wall_along),
                        (edge, fit.edge_decades),
                        stiff,
                    )
                })
                .collect();
            for l in shifts.iter().filter(|l| !l.shifts.is_empty()) {
                if !used.contains(&l.label) {
                    used.push(l.label.clone());
                }
            }
            if let Some(c) = Curve::fit(&resp.name, stiff, &shifts) {
                let last = edge * 10f64.powf(c.knots.last().map_or(0.0, |k| k.decades));
                if stiff {
                    // Every response must answer up to the reach.
                    reach[1] = if reach[1] == gd.domain[1] {
                        last
                    } else {
                        reach[1].min(last)
                    };
                } else {
                    reach[0] = if reach[0] == gd.domain[0] {
                        last
                    } else {
                        reach[0].max(last)
                    };
                }
                curves.push(c);
            }
        }
    }
    // A side some response has no curve for is not reached.
    for stiff in [false, true] {
        let all = model.responses.iter().all(|resp| {
            curves
                .iter()
                .any(|c| c.response == resp.name && c.stiff == stiff)
        });
        if !all {
            reach[usize::from(stiff)] = gd.domain[usize::from(stiff)];
            curves.retain(|c| c.stiff != stiff);
        }
    }
    if curves.is_empty() {
        return Err(bad(format!(
            "no response has two lines with runs at the edge of {} ({:.4e} or {:.4e}, within \
             {} decades) and at a common value beyond it",
            fit.group, gd.domain[0], gd.domain[1], fit.edge_decades
        )));
    }
    let mut m = model.clone();
    for k in std::iter::once(k_along).chain(wall_along) {
        m.inputs[k].domain[1] = m.inputs[k].domain[1].max(fit.along_max);
    }
    m.rigid_limit = Some(RigidLimit {
        group: fit.group.to_string(),
        along: fit.along.to_string(),
        wall: fit.wall.map(|(g, a)| (g.to_string(), a.to_string())),
        reach,
        curves,
        // Only the lines with a run at an edge and beyond it: the others measured nothing.
        lines: used,
        source: fit.source.clone(),
        cohesion: Vec::new(),
    });
    Ok(m)
}

/// One line's shifts of response `r` beyond the edge `edge` (on the stiff or soft side), in the
/// fitted response's unit, with the variance the runs' noise gives each (from the model's
/// replicate sd); `None` without a run at the edge.
fn line_shifts(
    model: &Metamodel,
    line: &Line,
    r: usize,
    (k_along, wall_along): (usize, Option<usize>),
    (edge, tolerance): (f64, f64),
    stiff: bool,
) -> Option<LineShifts> {
    // The seed means at each group value (runs at the same value are replicates).
    let mut means: Vec<(f64, f64, usize)> = Vec::new();
    for (k, v) in &line.runs {
        let v = v[r];
        if !v.is_finite() || !k.is_finite() || *k <= 0.0 {
            continue;
        }
        match means.iter_mut().find(|m| ((m.0 / k) - 1.0).abs() < 1e-9) {
            Some(m) => {
                m.1 += v;
                m.2 += 1;
            }
            None => means.push((*k, v, 1)),
        }
    }
    let means: Vec<(f64, f64, usize)> =
        means.iter().map(|m| (m.0, m.1 / m.2 as f64, m.2)).collect();
    let &(_, at_edge, n_edge) = means
        .iter()
        .filter(|m| (m.0 / edge).log10().abs() < tolerance)
        .min_by(|a, b| {
            (a.0 / edge)
                .log10()
                .abs()
                .total_cmp(&(b.0 / edge).log10().abs())
        })?;
    // The model's inputs on the edge: the point's, the particle (and wall) moved along.
    let gd = model
        .groups
        .iter()
        .find(|g| model.along_input(&g.group.name, &model.inputs[k_along].name) == Some(k_along))?;
    let mut x = line.inputs.clone();
    let scale = edge / model.group_value(&gd.group, &x);
    x[k_along] *= scale;
    if let Some(w) = wall_along {
        x[w] *= scale;
    }
    let resp = &model.responses[r];
    let factor = model.factor_at(resp, &x);
    let along: Vec<usize> = std::iter::once(k_along).chain(wall_along).collect();
    let slope = model.slope_per_decade(resp, &x, &along)?;
    // One run's noise variance in the fitted unit, at its 95 % lower bound (only what surely
    // is noise is taken off); unknown noise is taken as none (the scatter then keeps it, which
    // errs on the safe side).
    // The sd was measured at the response's error reference (rho_p of its runs), not here.
    let var = resp.replicate_sd.map_or(0.0, |sd| {
        (super::noise::lower_bound(sd, resp.replicate_pairs)
            / resp.error_reference.unwrap_or(factor))
        .powi(2)
    });
    let beyond: Vec<&(f64, f64, usize)> = means
        .iter()
        .filter(|m| {
            let d = (m.0 / edge).log10();
            d.abs() >= tolerance && (d > 0.0) == stiff
        })
        .collect();
    Some(LineShifts {
        label: line.label.clone(),
        slope: slope / factor,
        shifts: beyond
            .iter()
            .map(|&&(k, v, _)| ((k / edge).log10(), (v - at_edge) / factor))
            .collect(),
        noise: beyond
            .iter()
            .map(|&&(_, _, n)| var * (1.0 / n_edge as f64 + 1.0 / n as f64))
            .collect(),
    })
}

/// One line's runs with and without cohesion, as the cohesion fit takes them.
#[derive(Clone, Debug)]
pub struct CohesionLine {
    /// The point's name.
    pub label: String,
    /// The model's inputs at the point, in the model's order (any stiffness, no cohesion).
    pub inputs: Vec<f64>,
    /// The runs as `(stiffness group K, the cohesion input (ced), one value per model response,
    /// NaN where missing)`; ced = 0 for the runs without cohesion. A line holds its density and
    /// size, so the carry C_e (K / K_e)^(2/3) of its C = ced / (rho_p g d50) is ced's.
    pub runs: Vec<(f64, f64, Vec<f64>)>,
}

/// Relative tolerance on a run's cohesion matching the edge's carried by
/// [`COHESION_POWER`]: the tables write it to four or five significant digits.
const SAME_COHESION: f64 = 1e-3;

/// Measures how well a cohesion group carried to the stiffness edge
/// ([`super::rigid_limit::Cohesion`]) stands for the material beyond it. Each line has runs
/// on the edge with cohesion C_e and without, and beyond it at K with C_e (K / K_e)^(2/3) and
/// without; the cohesion effect there minus the edge's is what the similarity misses. Runs at
/// other cohesions are left out. `model` must carry its rigid limit.
///
/// `runs_edge`: where the effect's own runs stop in the stiffness group, when below the model's
/// edge (a correction fitted beyond its runs through the contact pull); the lines' edge runs
/// are then those at it, and the scatter counts from it
/// ([`super::rigid_limit::Cohesion::runs_edge`]).
pub fn fit_cohesion(
    model: &Metamodel,
    group: &str,
    along: &str,
    contact: [&str; 2],
    lines: &[CohesionLine],
    measured: String,
    runs_edge: Option<f64>,
) -> Result<Cohesion> {
    let bad = |what: String| Error::invalid(format!("rigid limit, cohesion: {what}"));
    let lim = model
        .rigid_limit
        .as_ref()
        .ok_or_else(|| bad("the model has no rigid limit to carry its cohesion".into()))?;
    let along_k = model
        .along_input(group, along)
        .ok_or_else(|| bad(format!("{along} does not enter {group} alone with power 1")))?;
    let gd = model
        .groups
        .iter()
        .find(|g| g.group.name == lim.group)
        .ok_or_else(|| bad(format!("the model has no group {}", lim.group)))?;
    if let Some(e) = runs_edge {
        if !(e > gd.domain[0] && e < gd.domain[1]) {
            return Err(bad(format!(
                "the effect's runs' edge {e:.4e} must lie inside the model's range of {} \
                 ([{:.4e}, {:.4e}]); at its top, leave it out",
                lim.group, gd.domain[0], gd.domain[1]
            )));
        }
    }
    let edge = runs_edge.unwrap_or(gd.domain[1]);
    let mut reference: Option<f64> = None;
    // A line's inputs on the edge, where the reference is read in the model's group.
    let mut edge_point: Option<Vec<f64>> = None;
    // Per response: (decades, difference, noise variance) of every line.
    let mut diffs: Vec<Vec<(f64, f64, f64)>> = vec![Vec::new(); model.responses.len()];
    for line in lines {
        // Seed means at each (K, C).
        let mut means: Vec<(f64, f64, Vec<f64>, Vec<usize>)> = Vec::new();
        for (k, c, v) in &line.runs {
            let at = means.iter().position(|m| {
                (m.0 / k - 1.0).abs() < 1e-9 && (m.1 - c).abs() <= SAME_COHESION * c.abs()
            });
            let i = at.unwrap_or_else(|| {
                means.push((*k, *c, vec![0.0; v.len()], vec![0; v.len()]));
                means.len() - 1
            });
            for (r, y) in v.iter().enumerate() {
                if y.is_finite() {
                    means[i].2[r] += y;
                    means[i].3[r] += 1;
                }
            }
        }
        let mean = |k: f64, c: f64, r: usize| {
            means
                .iter()
                .find(|m| {
                    (m.0 / k - 1.0).abs() < 1e-9
                        && (m.1 - c).abs() <= SAME_COHESION * c.abs().max(1e-300)
                })
                .filter(|m| m.3[r] > 0)
                .map(|m| (m.2[r] / m.3[r] as f64, m.3[r]))
        };
        let on_edge = |k: f64| (k / edge).log10().abs() < EDGE_DECADES;
        let edge_runs: Vec<&(f64, f64, Vec<f64>, Vec<usize>)> =
            means.iter().filter(|m| on_edge(m.0) && m.1 > 0.0).collect();
        let Some(first) = edge_runs.first() else {
            continue;
        };
        let (k_e, c_e) = (first.0, first.1);
        if edge_runs
            .iter()
            .any(|m| (m.1 / c_e - 1.0).abs() > SAME_COHESION)
        {
            return Err(bad(format!(
                "line {}: runs at two cohesions on the edge; expected one",
                line.label
            )));
        }
        match reference {
            Some(r) if (r / c_e - 1.0).abs() > SAME_COHESION => {
                return Err(bad(format!(
                    "line {}: edge cohesion {c_e}, another line's is {r}; expected one for all",
                    line.label
                )))
            }
            _ => reference = Some(c_e),
        }
        let mut x = line.inputs.clone();
        let scale = edge / model.group_value(&gd.group, &x);
        if let Some(k) = model.along_input(&lim.group, &lim.along) {
            x[k] *= scale;
        }
        edge_point.get_or_insert_with(|| x.clone());
        for (r, resp) in model.responses.iter().enumerate() {
            let factor = model.factor_at(resp, &x);
            let var = resp.replicate_sd.map_or(0.0, |sd| {
                (super::noise::lower_bound(sd, resp.replicate_pairs)
                    / resp.error_reference.unwrap_or(factor))
                .powi(2)
            });
            let (Some((ye_c, ne_c)), Some((ye_0, ne_0))) = (mean(k_e, c_e, r), mean(k_e, 0.0, r))
            else {
                continue;
            };
            for m in means.iter().filter(|m| !on_edge(m.0) && m.0 > edge) {
                let carried = c_e * (m.0 / k_e).powf(COHESION_POWER);
                if (m.1 / carried - 1.0).abs() > SAME_COHESION {
                    continue;
                }
                let (Some((y_c, n_c)), Some((y_0, n_0))) = (mean(m.0, m.1, r), mean(m.0, 0.0, r))
                else {
                    continue;
                };
                let d = ((y_c - y_0) - (ye_c - ye_0)) / factor;
                let noise = var
                    * (1.0 / n_c as f64 + 1.0 / n_0 as f64 + 1.0 / ne_c as f64 + 1.0 / ne_0 as f64);
                diffs[r].push(((m.0 / edge).log10(), d, noise));
            }
        }
    }
    let reference = reference.ok_or_else(|| {
        bad(format!(
            "no line has runs with cohesion on the edge of {} ({edge:.4e}, within \
             {EDGE_DECADES} decades)",
            lim.group
        ))
    })?;
    // The reference in the model's cohesion group: the lines' ced on the edge, read there.
    let reference = {
        let mut x = edge_point.expect("set with the reference");
        let cg = model
            .groups
            .iter()
            .find(|g| g.group.name == group)
            .ok_or_else(|| bad(format!("the model has no group {group}")))?;
        x[along_k] = reference;
        model.group_value(&cg.group, &x)
    };
    let mut curves = Vec::new();
    for (r, resp) in model.responses.iter().enumerate() {
        let mut ds: Vec<f64> = diffs[r].iter().map(|d| d.0).collect();
        ds.sort_by(f64::total_cmp);
        ds.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
        let mut knots = Vec::new();
        for d in ds {
            let here: Vec<&(f64, f64, f64)> =
                diffs[r].iter().filter(|p| (p.0 - d).abs() < 1e-6).collect();
            if here.len() < 2 {
                continue;
            }
            let n = here.len() as f64;
            let ms = here.iter().map(|p| p.1 * p.1).sum::<f64>() / n;
            let noise = here.iter().map(|p| p.2).sum::<f64>() / n;
            let mean = here.iter().map(|p| p.1).sum::<f64>() / n;
            let var = here.iter().map(|p| (p.1 - mean).powi(2)).sum::<f64>() / (n - 1.0);
            knots.push(CohesionKnot {
                decades: d,
                sd: ((ms - noise).max(0.0) + ms / n).sqrt(),
                mean,
                se: (var / n).sqrt(),
                lines: here.len(),
            });
        }
        if knots.is_empty() {
            return Err(bad(format!(
                "{}: no stiffness beyond the edge where two lines ran with the carried \
                 cohesion C_e (K / K_e)^(2/3) and without",
                resp.name
            )));
        }
        curves.push(CohesionCurve {
            response: resp.name.clone(),
            knots,
        });
    }
    Ok(Cohesion {
        group: group.to_string(),
        along: along.to_string(),
        contact: [contact[0].to_string(), contact[1].to_string()],
        reference,
        curves,
        measured,
        runs_edge,
    })
}
