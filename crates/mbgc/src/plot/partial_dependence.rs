//! Partial dependence of a metamodel's response: each input its equation uses, swept over its
//! valid range with the others held at a centre point, one panel per input. It shows at a
//! glance what an equation says about the physics (monotone in the frictions? flat in the
//! stiffness?), which its printed form rarely does.

use std::path::Path;

use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::labels::{axis_label, short_label};
use super::{DESC_FONT, FONT, TICK_FONT};
use crate::draw_figure;
use crate::error::{Error, Result};
use crate::metamodel::{Metamodel, Transform};

/// Points along each sweep.
const STEPS: usize = 60;
/// Panels per row.
const COLS: usize = 4;

/// One panel: the input swept and the response along it (NaN where the point lies outside the
/// model's valid domain, e.g. a dimensionless group pushed out of its range).
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// The input's name.
    pub input: String,
    /// Its values, over its domain (log-spaced for a log-scaled or a group-absorbed input).
    pub x: Vec<f64>,
    /// The response at each value.
    pub y: Vec<f64>,
    /// Whether `x` is log-spaced (and drawn on a log axis).
    pub log: bool,
}

/// The sweeps of `response` through `centre` (physical inputs, in the model's input order): one
/// per input the equation uses, in the model's order.
pub fn sweeps(model: &Metamodel, response: usize, centre: &[f64]) -> Result<Vec<Sweep>> {
    let r = model.responses.get(response).ok_or_else(|| {
        Error::invalid(format!("partial dependence: no response number {response}"))
    })?;
    if centre.len() != model.inputs.len() {
        return Err(Error::invalid(format!(
            "partial dependence: a centre of {} values for {} inputs",
            centre.len(),
            model.inputs.len()
        )));
    }
    let mut out = Vec::new();
    for (k, input) in model.inputs.iter().enumerate() {
        if !r.uses.contains(&input.name) {
            continue;
        }
        let [lo, hi] = input.domain;
        let logarithmic = lo > 0.0
            && (matches!(input.transform, Transform::Log { .. })
                || model.groups.iter().any(|g| {
                    g.group
                        .monomial
                        .powers
                        .iter()
                        .any(|(n, _)| *n == input.name)
                }));
        let x: Vec<f64> = (0..STEPS)
            .map(|i| {
                let u = i as f64 / (STEPS - 1) as f64;
                if logarithmic {
                    lo * (hi / lo).powf(u)
                } else {
                    lo + u * (hi - lo)
                }
            })
            .collect();
        let y = x
            .iter()
            .map(|&v| {
                let mut p = centre.to_vec();
                p[k] = v;
                if model.outside_domain(&p).is_empty() {
                    model.predict_point(r, &p)
                } else {
                    f64::NAN
                }
            })
            .collect();
        out.push(Sweep {
            input: input.name.clone(),
            x,
            y,
            log: logarithmic,
        });
    }
    Ok(out)
}

/// Draws the sweeps of `response` (see [`sweeps`]) as a grid of panels, each with its own value
/// axis (a scale factor such as rho_p would flatten every other panel on a shared one);
/// `centre_text` says where the other inputs are held (e.g. "others at the training design's
/// median").
pub fn partial_dependence(
    path: &Path,
    model: &Metamodel,
    response: usize,
    centre: &[f64],
    centre_text: &str,
) -> Result<()> {
    let sweeps = sweeps(model, response, centre)?;
    if !sweeps.iter().flat_map(|s| &s.y).any(|v| v.is_finite()) {
        return Err(Error::invalid(format!(
            "{}: partial dependence: the response is not finite anywhere along the sweeps",
            path.display()
        )));
    }
    let name = model.responses[response].name.clone();
    let title = format!("{}: partial dependence ({centre_text})", axis_label(&name));
    let rows = sweeps.len().div_ceil(COLS).max(1);
    let cols = sweeps.len().clamp(1, COLS);
    let size = (320 * cols as u32 + 40, 280 * rows as u32 + 50);
    draw_figure!(path, size, draw(&title, &name, &sweeps, cols))
}

/// A tick label with as many decimals as the axis' span needs.
fn tick(v: f64, span: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        return format!("{v:.1e}");
    }
    let decimals = (1.0 - span.log10().floor()).clamp(0.0, 4.0) as usize;
    format!("{v:.decimals$}")
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    response: &str,
    sweeps: &[Sweep],
    cols: usize,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let area = root.titled(title, (FONT, 20))?;
    let rows = sweeps.len().div_ceil(cols).max(1);
    let panels = area.split_evenly((rows, cols));
    let y_desc = axis_label(response);
    for (s, panel) in sweeps.iter().zip(panels.iter()) {
        let (x0, x1) = (s.x[0], s.x[s.x.len() - 1]);
        let (lo, hi) =
            s.y.iter()
                .filter(|v| v.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
        if !lo.is_finite() {
            continue;
        }
        // A flat sweep still gets a readable span: 1 % of its value.
        let pad = ((hi - lo) * 0.08).max(0.005 * hi.abs().max(1e-9));
        let (lo, hi) = (lo - pad, hi + pad);
        let mut segments: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        for (&x, &y) in s.x.iter().zip(&s.y) {
            if y.is_finite() {
                segments.last_mut().expect("one segment").push((x, y));
            } else if !segments.last().expect("one segment").is_empty() {
                segments.push(Vec::new());
            }
        }
        segments.retain(|seg| !seg.is_empty());
        let mut b = ChartBuilder::on(panel);
        b.margin(8).x_label_area_size(48).y_label_area_size(78);
        let y_fmt = |v: &f64| tick(*v, hi - lo);
        let style = PanelStyle {
            x_desc: short_label(&s.input),
            y_desc: &y_desc,
            y_fmt: &y_fmt,
        };
        if s.log {
            let chart = b.build_cartesian_2d((x0..x1).log_scale(), lo..hi)?;
            draw_panel(chart, &segments, &style, &|v: &f64| tick(*v, *v))?;
        } else {
            let chart = b.build_cartesian_2d(x0..x1, lo..hi)?;
            draw_panel(chart, &segments, &style, &|v: &f64| tick(*v, x1 - x0))?;
        }
    }
    Ok(())
}

/// What every panel's mesh shows, whatever its x axis.
struct PanelStyle<'a> {
    x_desc: String,
    y_desc: &'a str,
    y_fmt: &'a dyn Fn(&f64) -> String,
}

/// The mesh and the curve of one panel, on a linear or a logarithmic x axis.
fn draw_panel<DB: DrawingBackend, X>(
    mut chart: ChartContext<'_, DB, Cartesian2d<X, RangedCoordf64>>,
    segments: &[Vec<(f64, f64)>],
    style: &PanelStyle,
    x_fmt: &dyn Fn(&f64) -> String,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    chart
        .configure_mesh()
        .x_labels(4)
        .y_labels(5)
        .x_label_formatter(x_fmt)
        .y_label_formatter(style.y_fmt)
        .x_desc(&style.x_desc)
        .y_desc(style.y_desc)
        .label_style((FONT, TICK_FONT))
        .axis_desc_style((FONT, DESC_FONT))
        .draw()?;
    let blue = RGBColor(31, 119, 180);
    for seg in segments {
        chart.draw_series(LineSeries::new(seg.iter().copied(), blue.stroke_width(2)))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped() -> Metamodel {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        Metamodel::load(&root.join("models/shear_box.json")).unwrap()
    }

    /// The campaign's centre: inputs at the middle of their domains, rho_p and d50 where the
    /// campaign held them.
    fn centre(m: &Metamodel) -> Vec<f64> {
        m.inputs
            .iter()
            .map(|i| match i.name.as_str() {
                "rho_p" => 2600.0,
                "d50" => 10.0,
                "E_p" | "E_w" => 1e7,
                _ => 0.5 * (i.domain[0] + i.domain[1]),
            })
            .collect()
    }

    #[test]
    fn one_sweep_per_used_input_through_the_centre() {
        let m = shipped();
        let c = centre(&m);
        let k = m
            .responses
            .iter()
            .position(|r| r.name == "shear_angle")
            .unwrap();
        let s = sweeps(&m, k, &c).unwrap();
        let names: Vec<&str> = s.iter().map(|s| s.input.as_str()).collect();
        assert_eq!(names.len(), m.responses[k].uses.len());
        assert!(
            names.contains(&"mu_pp") && !names.contains(&"E_p"),
            "{names:?}"
        );
        // Each sweep passes through the centre's prediction where it crosses the centre value.
        let at_centre = m.predict_point(&m.responses[k], &c);
        for sw in &s {
            let j = m.inputs.iter().position(|i| i.name == sw.input).unwrap();
            let (lo, hi) = (sw.x[0], sw.x[sw.x.len() - 1]);
            assert!(lo <= c[j] && c[j] <= hi);
            assert!(sw.y.iter().all(|v| v.is_finite()), "{}", sw.input);
            assert!(at_centre.is_finite());
        }
        // The angle rises with the sliding friction over its range at the centre.
        let mu = s.iter().find(|s| s.input == "mu_pp").unwrap();
        assert!(mu.y[mu.y.len() - 1] > mu.y[0] + 5.0, "{:?}", mu.y);
    }

    #[test]
    fn an_input_pushed_outside_a_group_leaves_a_gap_and_the_figure_is_drawn() {
        // Without its rigid limit the model answers only in its groups' training range.
        let mut m = shipped();
        m.rigid_limit = None;
        let c = centre(&m);
        let k = m
            .responses
            .iter()
            .position(|r| r.name == "bulk_density")
            .unwrap();
        let s = sweeps(&m, k, &c).unwrap();
        // d50 from 0.4 to 25.6 mm at E_p 1e7 and rho_p 2600 leaves K_p's range at the fine end.
        let d = s.iter().find(|s| s.input == "d50").unwrap();
        assert!(d.y.iter().any(|v| v.is_nan()) && d.y.iter().any(|v| v.is_finite()));
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("pd.svg");
        partial_dependence(&p, &m, k, &c, "others at the centre").unwrap();
        let svg = std::fs::read_to_string(&p).unwrap();
        assert!(svg.contains("bulk density (kg/m³): partial dependence"));
        assert!(svg.contains("μ_pp") && !svg.contains("mu_pp"));
        crate::plot::test_util::assert_fonts_at_least(&svg, 12.0);
        assert!(sweeps(&m, k, &c[1..]).is_err());
    }
}
