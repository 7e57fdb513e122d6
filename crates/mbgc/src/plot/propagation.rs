//! The figure of a propagation (`mbgc propagate`): the robust CDF of a quantity over the
//! posterior draws, each draw's spread over its seeds, the metamodel's CDF when there is one, and
//! the best-fit point's value.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::labels::axis_label;
use super::{DESC_FONT, FONT, LEGEND_FONT, TICK_FONT};
use crate::draw_figure;
use crate::error::{Error, Result};

/// What one quantity's figure shows.
pub struct PropagationFigure<'a> {
    /// The quantity (a response name: the axis gets its words and unit).
    pub response: &'a str,
    /// Each draw's DEM values (one per seed; NaN for a run without one).
    pub per_draw: &'a [Vec<f64>],
    /// The metamodel's prediction at each draw, if the draws went through one.
    pub metamodel: Option<&'a [f64]>,
    /// The best-fit point's value, if it ran.
    pub best_fit: Option<f64>,
}

/// Points of an empirical CDF: the sorted values at heights (i + 0.5) / n.
fn ecdf(values: &[f64]) -> Vec<(f64, f64)> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let n = v.len() as f64;
    v.into_iter()
        .enumerate()
        .map(|(i, x)| (x, (i as f64 + 0.5) / n))
        .collect()
}

/// Draws the figure into `path` (.svg or .png).
pub fn robust_cdf(path: &Path, f: &PropagationFigure) -> Result<()> {
    let means: Vec<f64> = f
        .per_draw
        .iter()
        .map(|v| {
            let x: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
            if x.is_empty() {
                f64::NAN
            } else {
                x.iter().sum::<f64>() / x.len() as f64
            }
        })
        .collect();
    let all: Vec<f64> = f
        .per_draw
        .iter()
        .flatten()
        .chain(f.metamodel.unwrap_or(&[]))
        .chain(f.best_fit.iter())
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    if all.is_empty() {
        return Err(Error::invalid(format!(
            "{}: no run of {} has a value to draw",
            path.display(),
            f.response
        )));
    }
    let (lo, hi) = all
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        0.05 * lo.abs().max(1e-12)
    };
    let label = axis_label(f.response);
    draw_figure!(
        path,
        (860, 600),
        draw(&label, f, &means, lo - pad, hi + pad)
    )
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    label: &str,
    f: &PropagationFigure,
    means: &[f64],
    lo: f64,
    hi: f64,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("{label}: robust CDF over the posterior draws"),
            (FONT, 20),
        )
        .margin(15)
        .x_label_area_size(60)
        .y_label_area_size(75)
        .build_cartesian_2d(lo..hi, 0.0..1.0)?;
    chart
        .configure_mesh()
        .x_desc(label)
        .y_desc("share of draws at or below")
        .label_style((FONT, TICK_FONT))
        .axis_desc_style((FONT, DESC_FONT))
        .draw()?;
    let blue = RGBColor(31, 119, 180);
    let orange = RGBColor(255, 127, 14);
    let cdf = ecdf(means);
    // Each draw's seeds as a bar at its mean's height: the run scatter beside the spread.
    let bars: Vec<(f64, f64, f64)> = f
        .per_draw
        .iter()
        .zip(means)
        .filter(|(v, m)| m.is_finite() && v.iter().filter(|x| x.is_finite()).count() > 1)
        .map(|(v, &m)| {
            let x: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
            let h = cdf.iter().find(|p| p.0 == m).map_or(0.5, |p| p.1);
            let (a, b) = x
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
                    (a.min(y), b.max(y))
                });
            (a, b, h)
        })
        .collect();
    if !bars.is_empty() {
        chart
            .draw_series(bars.iter().map(|&(a, b, h)| {
                PathElement::new([(a, h), (b, h)], blue.mix(0.35).stroke_width(2))
            }))?
            .label("one draw's seeds (min to max)")
            .legend(move |(x, y)| {
                PathElement::new([(x, y), (x + 20, y)], blue.mix(0.35).stroke_width(2))
            });
    }
    let steps = |pts: &[(f64, f64)]| {
        let mut s = Vec::with_capacity(2 * pts.len() + 2);
        let mut last = 0.0;
        s.push((lo, 0.0));
        for &(x, y) in pts {
            s.push((x, last));
            s.push((x, y));
            last = y;
        }
        s.push((hi, last));
        s
    };
    chart
        .draw_series(LineSeries::new(steps(&cdf), blue.stroke_width(2)))?
        .label(format!("DEM, {} draws", cdf.len()))
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], blue.stroke_width(2)));
    if let Some(m) = f.metamodel {
        let cdf = ecdf(m);
        chart
            .draw_series(LineSeries::new(steps(&cdf), orange.stroke_width(2)))?
            .label("metamodel, same draws")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], orange.stroke_width(2)));
    }
    if let Some(b) = f.best_fit.filter(|b| b.is_finite()) {
        chart
            .draw_series(LineSeries::new([(b, 0.0), (b, 1.0)], BLACK.stroke_width(2)))?
            .label("best-fit point")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .label_font((FONT, LEGEND_FONT))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cdf_is_drawn_as_svg_and_an_empty_one_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("flow_rate.svg");
        let per_draw = vec![vec![1.0, 1.2], vec![2.0, 2.1], vec![1.5, f64::NAN]];
        let fig = PropagationFigure {
            response: "flow_rate",
            per_draw: &per_draw,
            metamodel: Some(&[1.1, 2.0, 1.6]),
            best_fit: Some(1.4),
        };
        robust_cdf(&path, &fig).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(
            svg.contains("flow rate") && svg.contains("best-fit point"),
            "{svg}"
        );
        let empty = vec![vec![f64::NAN]];
        let fig = PropagationFigure {
            per_draw: &empty,
            metamodel: None,
            best_fit: None,
            ..fig
        };
        let e = robust_cdf(&path, &fig).unwrap_err().to_string();
        assert!(e.contains("no run of flow_rate"), "{e}");
        assert_eq!(ecdf(&[3.0, 1.0]), [(1.0, 0.25), (3.0, 0.75)]);
    }
}
