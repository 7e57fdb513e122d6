//! Figure of a PSD fit: the sieve points and the fitted Q3 curves of GGS, RRSB and log-normal on
//! a log size axis, with R^2 in the legend.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::Result;
use crate::psd::{FitReport, MassDistribution, Model, SieveData};

fn colour(model: Model) -> RGBColor {
    match model {
        Model::Ggs => RGBColor(0x99, 0x99, 0x99),
        Model::Rrsb => RGBColor(0x1f, 0x77, 0xb4),
        Model::LogNormal => RGBColor(0xd6, 0x27, 0x28),
    }
}

fn label(model: Model) -> &'static str {
    match model {
        Model::Ggs => "GGS",
        Model::Rrsb => "RRSB",
        Model::LogNormal => "log-normal",
    }
}

/// Ticks at 1, 2, 3, 5 times powers of ten: plotters' own log axis labels only the decades, which
/// leaves a sieve range like 4..31.5 mm with a single label.
fn ticks_1235(lo: f64, hi: f64) -> Vec<f64> {
    let (e0, e1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (e0..=e1)
        .flat_map(|e| [1.0, 2.0, 3.0, 5.0].map(|m| m * 10f64.powi(e)))
        .filter(|&t| t >= lo && t <= hi)
        .collect()
}

/// Draws the fit figure on any backend.
pub fn draw_fit<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    data: &SieveData,
    report: &FitReport,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let (lo, hi) = match (data.size_mm.first(), data.size_mm.last()) {
        (Some(&a), Some(&b)) => (a / 1.5, b * 1.5),
        _ => (0.1, 10.0),
    };
    let title = Path::new(&data.source)
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| data.source.clone());
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("Particle size distribution: {title}"),
            ("sans-serif", 22),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(55)
        .build_cartesian_2d(
            (lo..hi).log_scale().with_key_points(ticks_1235(lo, hi)),
            0.0..100.0,
        )?;
    chart
        .configure_mesh()
        .x_label_formatter(&|x| format!("{}", (x * 1e4).round() / 1e4))
        .y_label_formatter(&|y| format!("{y:.0}"))
        .x_desc("particle size x / mm")
        .y_desc("cumulative mass passing Q3 / %")
        .draw()?;

    let n_curve = 400;
    for fit in &report.models {
        let c = colour(fit.model);
        let width = if fit.model == report.best { 3 } else { 2 };
        let best = if fit.model == report.best {
            ", best"
        } else {
            ""
        };
        let curve = (0..=n_curve).map(|i| {
            let x = lo * (hi / lo).powf(i as f64 / n_curve as f64);
            (x, 100.0 * fit.dist.q3(x))
        });
        chart
            .draw_series(LineSeries::new(curve, c.stroke_width(width)))?
            .label(format!("{} (R² = {:.4}{best})", label(fit.model), fit.r2))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3)));
    }
    chart
        .draw_series(
            data.size_mm
                .iter()
                .zip(&data.passing)
                .map(|(&x, &q)| Circle::new((x, 100.0 * q), 5, BLACK.filled())),
        )?
        .label("sieve data")
        .legend(|(x, y)| Circle::new((x + 10, y), 5, BLACK.filled()));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// Writes the fit figure as SVG or PNG according to the extension of `path`.
pub fn write_fit(path: &Path, data: &SieveData, report: &FitReport) -> Result<()> {
    crate::draw_figure!(path, (900, 600), draw_fit(data, report))
}
