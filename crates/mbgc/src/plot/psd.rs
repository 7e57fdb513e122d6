//! Figure of a PSD fit: the sieve points and the fitted Q3 curves of GGS, RRSB and log-normal on
//! a log size axis, with R^2 in the legend.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{DESC_FONT, FONT, LEGEND_FONT, TICK_FONT};
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
/// leaves a sieve range like 4..31.5 mm with a single label. Used when there are no sieve sizes.
fn ticks_1235(lo: f64, hi: f64) -> Vec<f64> {
    let (e0, e1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (e0..=e1)
        .flat_map(|e| [1.0, 2.0, 3.0, 5.0].map(|m| m * 10f64.powi(e)))
        .filter(|&t| t >= lo && t <= hi)
        .collect()
}

/// Tick label of a sieve size: up to four decimals, no trailing zeros ("0.063", "5.6", "16").
fn size_label(x: f64) -> String {
    format!("{}", (x * 1e4).round() / 1e4)
}

/// The ticks of the log size axis `lo..hi`, `width` pixels long: the sieve sizes of the data,
/// left to right, leaving out a size whose label (`label_width` gives its width in pixels)
/// would come closer than 6 px to the previous label's. The first and the last sieve are always
/// kept (the last replaces a kept neighbour it would collide with). Without sieves inside the
/// range, 1-2-3-5 ticks.
fn sieve_ticks(
    sizes: &[f64],
    (lo, hi): (f64, f64),
    width: f64,
    label_width: impl Fn(&str) -> f64,
) -> Vec<f64> {
    let px = |x: f64| width * (x / lo).ln() / (hi / lo).ln();
    let inside: Vec<f64> = sizes
        .iter()
        .copied()
        .filter(|&x| x.is_finite() && x >= lo && x <= hi)
        .collect();
    if inside.is_empty() {
        return ticks_1235(lo, hi);
    }
    let clear = |a: f64, b: f64| {
        let gap = (label_width(&size_label(a)) + label_width(&size_label(b))) / 2.0 + 6.0;
        (px(b) - px(a)).abs() >= gap
    };
    let mut kept: Vec<f64> = Vec::new();
    for &x in &inside {
        if kept.last().is_none_or(|&k| clear(k, x)) {
            kept.push(x);
        }
    }
    let last = inside[inside.len() - 1];
    if kept.last() != Some(&last) {
        while kept.len() > 1 && !clear(kept[kept.len() - 1], last) {
            kept.pop();
        }
        kept.push(last);
    }
    kept
}

const MARGIN: u32 = 12;
const X_LABEL_AREA: u32 = 60;
const Y_LABEL_AREA: u32 = 70;

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
    // Sieve sizes as the ticks of the size axis, thinned where their labels would overlap.
    let tick_style = (FONT, TICK_FONT).into_text_style(root);
    let mut widths = Vec::new();
    for x in &data.size_mm {
        widths.push((
            size_label(*x),
            root.estimate_text_size(&size_label(*x), &tick_style)?,
        ));
    }
    let label_width = |t: &str| {
        widths
            .iter()
            .find(|(l, _)| l == t)
            .map_or(8.0 * t.len() as f64, |(_, (w, _))| *w as f64)
    };
    let plot_w = root
        .dim_in_pixel()
        .0
        .saturating_sub(2 * MARGIN + Y_LABEL_AREA)
        .max(1) as f64;
    let ticks = sieve_ticks(&data.size_mm, (lo, hi), plot_w, label_width);
    let n_ticks = ticks.len();
    let mut chart = ChartBuilder::on(root)
        .caption(format!("Particle size distribution: {title}"), (FONT, 22))
        .margin(MARGIN)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d((lo..hi).log_scale().with_key_points(ticks), 0.0..100.0)?;
    chart
        .configure_mesh()
        .x_labels(n_ticks)
        .x_label_formatter(&|x| size_label(*x))
        .y_label_formatter(&|y| format!("{y:.0}"))
        .x_desc("sieve aperture x (mm)")
        .y_desc("cumulative mass passing Q3 (%)")
        .label_style((FONT, TICK_FONT))
        .axis_desc_style((FONT, DESC_FONT))
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
        .label_font((FONT, LEGEND_FONT))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// Writes the fit figure as SVG or PNG according to the extension of `path`.
pub fn write_fit(path: &Path, data: &SieveData, report: &FitReport) -> Result<()> {
    crate::draw_figure!(path, (900, 600), draw_fit(data, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::psd::fit_all;

    /// The sieve curve of examples/sieve_gravel_8_16.csv.
    fn gravel() -> SieveData {
        let size = vec![
            4.0, 5.6, 8.0, 10.0, 11.2, 12.5, 14.0, 16.0, 20.0, 22.4, 31.5,
        ];
        let pct = [
            0.0, 0.4, 9.4, 34.5, 51.1, 66.2, 79.9, 92.0, 98.7, 99.6, 100.0,
        ];
        SieveData::new("gravel.csv", size, pct.iter().map(|p| p / 100.0).collect()).unwrap()
    }

    #[test]
    fn ticks_at_the_sieve_sizes_with_readable_labels() {
        let data = gravel();
        let report = fit_all(&data).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("psd.svg");
        write_fit(&p, &data, &report).unwrap();
        let svg = std::fs::read_to_string(&p).unwrap();
        for tick in ["4", "5.6", "8", "11.2", "16", "22.4", "31.5"] {
            assert!(svg.contains(&format!("\n{tick}\n")), "no tick label {tick}");
        }
        // No 1-2-3-5 ticks between the sieves (the y axis has 0, 10, ..., 100).
        for tick in ["3", "5"] {
            assert!(!svg.contains(&format!("\n{tick}\n")), "tick label {tick}");
        }
        assert!(svg.contains("sieve aperture x (mm)"));
        assert!(svg.contains("cumulative mass passing Q3 (%)"));
        assert!(
            svg.contains("sieve data"),
            "no legend entry for the sieve points"
        );
        crate::plot::test_util::assert_fonts_at_least(&svg, 12.0);
        write_fit(&dir.path().join("psd.png"), &data, &report).unwrap();
    }

    #[test]
    fn crowded_sieve_ticks_are_thinned() {
        let w = |t: &str| 8.0 * t.len() as f64;
        let sizes = [1.0, 10.0, 100.0];
        assert_eq!(sieve_ticks(&sizes, (1.0, 100.0), 800.0, w), sizes.to_vec());
        // 10, 10.5, 11 are too close on 400 px spanning two decades: 10.5 goes, the last stays.
        let sizes = [1.0, 10.0, 10.5, 11.0, 100.0];
        assert_eq!(
            sieve_ticks(&sizes, (1.0, 100.0), 400.0, w),
            vec![1.0, 10.0, 100.0]
        );
        // A last sieve that collides with the previous kept one replaces it.
        let sizes = [1.0, 90.0, 100.0];
        assert_eq!(
            sieve_ticks(&sizes, (1.0, 100.0), 400.0, w),
            vec![1.0, 100.0]
        );
        // No sieve inside the range: 1-2-3-5 ticks.
        assert_eq!(sieve_ticks(&[], (1.5, 6.0), 400.0, w), vec![2.0, 3.0, 5.0]);
        assert_eq!(size_label(0.063), "0.063");
        assert_eq!(size_label(16.0), "16");
    }
}
