//! Figures of a diagnosis: the standardised residuals against the particle size, one series per
//! model class (a trend that a missing effect leaves shows as a slope), and the error ladder:
//! each sample's RMS standardised residual per class.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::labels::axis_label;
use super::{DESC_FONT, FONT, LEGEND_FONT, TICK_FONT};
use crate::draw_figure;
use crate::error::{Error, Result};

/// One model class's points.
pub struct Series<'a> {
    /// Name of the model class, shown in the legend.
    pub label: &'a str,
    /// (d50 in mm, standardised residual z) per sample for [`residuals_against_d50`]; for
    /// [`ladder`], one point per sample in sample order, of which only the RMS residual (second
    /// value) is drawn.
    pub points: Vec<(f64, f64)>,
}

const COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
];

/// `z` against d50 (log axis), with the +-2 band.
pub fn residuals_against_d50(path: &Path, response: &str, series: &[Series]) -> Result<()> {
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .collect();
    if all.is_empty()
        || all
            .iter()
            .any(|(d, z)| !(d.is_finite() && *d > 0.0 && z.is_finite()))
    {
        return Err(Error::invalid(format!(
            "{}: residual figure needs finite residuals at positive d50",
            path.display()
        )));
    }
    let (dlo, dhi) = all.iter().fold((f64::INFINITY, 0.0f64), |(a, b), (d, _)| {
        (a.min(*d), b.max(*d))
    });
    let zmax = all.iter().fold(2.5f64, |m, (_, z)| m.max(z.abs())) * 1.1;
    let response = axis_label(response);
    draw_figure!(
        path,
        (860, 600),
        draw_residuals(&response, series, dlo / 1.3, dhi * 1.3, zmax)
    )
}

fn draw_residuals<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    response: &str,
    series: &[Series],
    dlo: f64,
    dhi: f64,
    zmax: f64,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("{response}: standardised residual against d50"),
            (FONT, 20),
        )
        .margin(15)
        .x_label_area_size(60)
        .y_label_area_size(75)
        .build_cartesian_2d((dlo..dhi).log_scale(), -zmax..zmax)?;
    chart
        .configure_mesh()
        .x_desc("median particle size d50 (mm)")
        .y_desc("z = (measured - predicted) / σ")
        .label_style((FONT, TICK_FONT))
        .axis_desc_style((FONT, DESC_FONT))
        .draw()?;
    chart.draw_series(LineSeries::new(
        [(dlo, 0.0), (dhi, 0.0)],
        BLACK.stroke_width(1),
    ))?;
    let band = BLACK.mix(0.3).stroke_width(1);
    for z in [-2.0, 2.0] {
        let series = chart.draw_series(LineSeries::new([(dlo, z), (dhi, z)], band))?;
        if z > 0.0 {
            series
                .label("|z| = 2")
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], band));
        }
    }
    for (i, s) in series.iter().enumerate() {
        let c = COLOURS[i % COLOURS.len()];
        let mut pts = s.points.clone();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart.draw_series(LineSeries::new(pts.clone(), c.mix(0.5).stroke_width(1)))?;
        chart
            .draw_series(pts.iter().map(|&(d, z)| Circle::new((d, z), 5, c.filled())))?
            .label(s.label)
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.filled()));
    }
    chart
        .configure_series_labels()
        .label_font((FONT, LEGEND_FONT))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    Ok(())
}

/// Bars of each sample's RMS standardised residual, one colour per class.
pub fn ladder(path: &Path, samples: &[String], series: &[Series]) -> Result<()> {
    if samples.is_empty() || series.iter().any(|s| s.points.len() != samples.len()) {
        return Err(Error::invalid(format!(
            "{}: ladder figure needs one value per sample in every class",
            path.display()
        )));
    }
    let top = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .fold(1.0f64, f64::max)
        * 1.15;
    draw_figure!(path, (900, 560), draw_ladder(samples, series, top))
}

fn draw_ladder<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    samples: &[String],
    series: &[Series],
    top: f64,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let n = samples.len() as f64;
    let mut chart = ChartBuilder::on(root)
        .caption(
            "error ladder: RMS standardised residual per sample",
            (FONT, 20),
        )
        .margin(15)
        .x_label_area_size(60)
        .y_label_area_size(75)
        .build_cartesian_2d(-0.5..n - 0.5, 0.0..top)?;
    let names = samples.to_vec();
    chart
        .configure_mesh()
        .x_labels(samples.len())
        .x_label_formatter(&|v| {
            let k = v.round();
            if (v - k).abs() < 1e-6 && k >= 0.0 && (k as usize) < names.len() {
                names[k as usize].clone()
            } else {
                String::new()
            }
        })
        .y_desc("RMS of z = (measured - predicted) / σ")
        .label_style((FONT, TICK_FONT))
        .axis_desc_style((FONT, DESC_FONT))
        .draw()?;
    let unit = BLACK.mix(0.4).stroke_width(1);
    chart
        .draw_series(LineSeries::new([(-0.5, 1.0), (n - 0.5, 1.0)], unit))?
        .label("RMS z = 1 (within the measurement error)")
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], unit));
    let w = 0.8 / series.len().max(1) as f64;
    for (i, s) in series.iter().enumerate() {
        let c = COLOURS[i % COLOURS.len()];
        chart
            .draw_series(s.points.iter().enumerate().map(|(k, &(_, v))| {
                let x0 = k as f64 - 0.4 + i as f64 * w;
                Rectangle::new([(x0, 0.0), (x0 + w * 0.9, v)], c.filled())
            }))?
            .label(s.label)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.filled()));
    }
    chart
        .configure_series_labels()
        .label_font((FONT, LEGEND_FONT))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::test_util::assert_fonts_at_least;

    #[test]
    fn readable_labels_and_a_legend_for_every_line() {
        let dir = tempfile::tempdir().unwrap();
        let series = [
            Series {
                label: "base",
                points: vec![(0.5, 2.5), (4.0, 0.3), (16.0, -1.9)],
            },
            Series {
                label: "base+sjkr",
                points: vec![(0.5, 0.4), (4.0, -0.2), (16.0, 0.1)],
            },
        ];
        let p = dir.path().join("z.svg");
        residuals_against_d50(&p, "bulk_density", &series).unwrap();
        let svg = std::fs::read_to_string(&p).unwrap();
        for text in [
            "bulk density (kg/m³): standardised residual",
            "median particle size d50 (mm)",
            "|z| = 2",
            "base+sjkr",
        ] {
            assert!(svg.contains(text), "no \"{text}\"");
        }
        assert!(!svg.contains("bulk_density"));
        assert_fonts_at_least(&svg, 12.0);

        let p = dir.path().join("ladder.svg");
        let samples: Vec<String> = ["fine", "mid", "coarse"].map(String::from).to_vec();
        ladder(&p, &samples, &series).unwrap();
        let svg = std::fs::read_to_string(&p).unwrap();
        for text in ["RMS z = 1", "base", "base+sjkr", "fine", "coarse"] {
            assert!(svg.contains(text), "no \"{text}\"");
        }
        assert_fonts_at_least(&svg, 12.0);
    }
}
