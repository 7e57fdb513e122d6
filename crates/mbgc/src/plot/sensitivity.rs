//! Figures of a sensitivity analysis: grouped bars with 95 % intervals (power-law exponents,
//! PCA loadings, sensitivity-norm shares, Sobol indices) and a heat map of a correlation matrix.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::labels::{axis_label, short_label, title_label};
use super::{DESC_FONT, FONT, LEGEND_FONT, TICK_FONT};
use crate::draw_figure;
use crate::error::{Error, Result};

/// One bar: its value and, optionally, its 95 % interval.
#[derive(Debug, Clone)]
pub struct Bar {
    /// Height of the bar (an exponent, loading, share or index).
    pub value: f64,
    /// Its 95 % interval drawn as an error bar, if known.
    pub ci95: Option<[f64; 2]>,
}

/// Bars drawn side by side at each category, one series per colour.
#[derive(Debug, Clone)]
pub struct BarSeries {
    /// Series name in the legend.
    pub label: String,
    /// One bar per category.
    pub bars: Vec<Bar>,
}

const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Grouped bar chart: `categories` on the x axis, one bar per series at each, with interval
/// whiskers where given; a zero line. Category names, series labels and a title starting with
/// "name: " are made readable with [`short_label`], [`axis_label`] and [`title_label`]
/// ("mu_pp" -> "μ_pp").
pub fn bars(
    path: &Path,
    title: &str,
    y_label: &str,
    categories: &[String],
    series: &[BarSeries],
) -> Result<()> {
    if categories.is_empty()
        || series.is_empty()
        || series.iter().any(|s| s.bars.len() != categories.len())
    {
        return Err(Error::invalid(format!(
            "{}: a bar chart needs one bar per category in every series",
            path.display()
        )));
    }
    let vals = series.iter().flat_map(|s| {
        s.bars.iter().flat_map(|b| {
            let mut v = vec![b.value];
            if let Some(c) = b.ci95 {
                v.extend(c);
            }
            v
        })
    });
    let (mut lo, mut hi) = vals
        .filter(|v| v.is_finite())
        .fold((0.0f64, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if hi - lo <= 0.0 {
        hi = lo + 1.0;
    }
    let pad = 0.08 * (hi - lo);
    lo -= if lo < 0.0 { pad } else { 0.0 };
    hi += pad;
    let width = (160 + 90 * categories.len() * series.len().max(2) / 2).clamp(640, 1400) as u32;
    let title = title_label(title);
    let categories: Vec<String> = categories.iter().map(|c| short_label(c)).collect();
    let series: Vec<BarSeries> = series
        .iter()
        .map(|s| BarSeries {
            label: axis_label(&s.label),
            bars: s.bars.clone(),
        })
        .collect();
    draw_figure!(
        path,
        (width, 520),
        draw_bars(&title, y_label, &categories, &series, lo, hi)
    )
}

fn draw_bars<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    y_label: &str,
    categories: &[String],
    series: &[BarSeries],
    lo: f64,
    hi: f64,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let n = categories.len();
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 20))
        .margin(15)
        .x_label_area_size(60)
        .y_label_area_size(80)
        .build_cartesian_2d(-0.5f64..n as f64 - 0.5, lo..hi)?;
    let cats = categories.to_vec();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n)
        .x_label_formatter(&move |x: &f64| {
            let k = x.round();
            if (x - k).abs() < 1e-6 && k >= 0.0 && (k as usize) < cats.len() {
                cats[k as usize].clone()
            } else {
                String::new()
            }
        })
        .y_desc(y_label)
        .label_style((FONT, TICK_FONT))
        .axis_desc_style((FONT, DESC_FONT))
        .draw()?;
    chart.draw_series(LineSeries::new(
        [(-0.5, 0.0), (n as f64 - 0.5, 0.0)],
        BLACK.stroke_width(1),
    ))?;
    let m = series.len() as f64;
    let w = 0.8 / m;
    for (si, s) in series.iter().enumerate() {
        let colour = COLOURS[si % COLOURS.len()];
        let x0 = |c: usize| c as f64 - 0.4 + si as f64 * w;
        chart
            .draw_series(
                s.bars
                    .iter()
                    .enumerate()
                    .filter(|(_, b)| b.value.is_finite())
                    .map(|(c, b)| {
                        Rectangle::new(
                            [(x0(c) + 0.05 * w, 0.0), (x0(c) + 0.95 * w, b.value)],
                            colour.mix(0.8).filled(),
                        )
                    }),
            )?
            .label(s.label.clone())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], colour.filled()));
        for (c, b) in s.bars.iter().enumerate() {
            if let Some([a, z]) = b.ci95 {
                if a.is_finite() && z.is_finite() {
                    let xm = x0(c) + 0.5 * w;
                    chart
                        .draw_series(LineSeries::new([(xm, a), (xm, z)], BLACK.stroke_width(2)))?;
                    for y in [a, z] {
                        chart.draw_series(LineSeries::new(
                            [(xm - 0.2 * w, y), (xm + 0.2 * w, y)],
                            BLACK.stroke_width(2),
                        ))?;
                    }
                }
            }
        }
    }
    chart
        .configure_series_labels()
        .label_font((FONT, LEGEND_FONT))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// Heat map of a square matrix with values in [-1, 1] (blue negative, red positive), each cell
/// labelled with its value; `names` are made readable with [`short_label`] and a title starting
/// with "name: " with [`title_label`].
pub fn heat_map(path: &Path, title: &str, names: &[String], m: &[Vec<f64>]) -> Result<()> {
    if names.is_empty() || m.len() != names.len() || m.iter().any(|r| r.len() != names.len()) {
        return Err(Error::invalid(format!(
            "{}: a heat map needs a square matrix with one name per row",
            path.display()
        )));
    }
    let title = title_label(title);
    let names: Vec<String> = names.iter().map(|n| short_label(n)).collect();
    draw_figure!(path, (680, 620), draw_heat(&title, &names, m))
}

fn draw_heat<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    names: &[String],
    m: &[Vec<f64>],
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let n = names.len();
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 20))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(120)
        .build_cartesian_2d(0f64..n as f64, 0f64..n as f64)?;
    let xs = names.to_vec();
    let ys = names.to_vec();
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(2 * n + 1)
        .y_labels(2 * n + 1)
        .x_label_formatter(&move |x: &f64| label_at(&xs, *x, false))
        .y_label_formatter(&move |y: &f64| label_at(&ys, *y, true))
        .label_style((FONT, TICK_FONT))
        .draw()?;
    for (i, row) in m.iter().enumerate() {
        for (j, &v) in row.iter().enumerate() {
            let y = (n - 1 - i) as f64;
            let x = j as f64;
            let c = if v.is_finite() {
                let a = v.clamp(-1.0, 1.0);
                if a >= 0.0 {
                    RGBColor(255, (255.0 * (1.0 - a)) as u8, (255.0 * (1.0 - a)) as u8)
                } else {
                    RGBColor((255.0 * (1.0 + a)) as u8, (255.0 * (1.0 + a)) as u8, 255)
                }
            } else {
                RGBColor(200, 200, 200)
            };
            chart.draw_series([Rectangle::new([(x, y), (x + 1.0, y + 1.0)], c.filled())])?;
            chart.draw_series([Text::new(
                format!("{v:.2}"),
                (x + 0.35, y + 0.55),
                (FONT, 16).into_font(),
            )])?;
        }
    }
    Ok(())
}

/// The name at a half-integer position (cell centre); rows count from the top.
fn label_at(names: &[String], x: f64, rows: bool) -> String {
    let k = x - 0.5;
    let r = k.round();
    if (k - r).abs() > 1e-6 || r < 0.0 || r as usize >= names.len() {
        return String::new();
    }
    let idx = if rows {
        names.len() - 1 - r as usize
    } else {
        r as usize
    };
    names[idx].clone()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::test_util::assert_fonts_at_least;

    #[test]
    fn bars_and_heat_map_show_readable_names() {
        let dir = tempfile::tempdir().unwrap();
        let cats: Vec<String> = ["e_pp", "mu_pp", "mu_r_pp"].map(String::from).to_vec();
        let bar = |v: f64| Bar {
            value: v,
            ci95: Some([v - 0.1, v + 0.1]),
        };
        let series = [
            BarSeries {
                label: "shear_angle".into(),
                bars: vec![bar(0.1), bar(0.8), bar(0.3)],
            },
            BarSeries {
                label: "bulk_density".into(),
                bars: vec![bar(-0.2), bar(0.1), bar(0.05)],
            },
        ];
        let p = dir.path().join("bars.svg");
        bars(&p, "shear_angle: Sobol indices", "index", &cats, &series).unwrap();
        let svg = std::fs::read_to_string(&p).unwrap();
        for text in [
            "shear angle (deg): Sobol indices",
            "μ_pp",
            "μ_r,pp",
            "shear angle (deg)",
            "bulk density (kg/m³)",
        ] {
            assert!(svg.contains(text), "no \"{text}\"");
        }
        assert!(!svg.contains("mu_pp") && !svg.contains("bulk_density"));
        assert_fonts_at_least(&svg, 12.0);

        let m = vec![
            vec![1.0, -0.3, 0.2],
            vec![-0.3, 1.0, 0.5],
            vec![0.2, 0.5, 1.0],
        ];
        let h = dir.path().join("heat.svg");
        heat_map(&h, "correlation", &cats, &m).unwrap();
        let svg = std::fs::read_to_string(&h).unwrap();
        assert!(svg.contains("μ_r,pp") && !svg.contains("mu_r_pp"));
        assert_fonts_at_least(&svg, 12.0);
    }
}
