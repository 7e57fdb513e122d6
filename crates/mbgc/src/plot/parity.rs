//! Figures for judging a fitted metamodel (cf. Figs. 14-15 of Richter & Will 2021): a parity plot
//! of the predicted against the observed (simulated) response, and a histogram of the residuals,
//! one colour per data split ("train", "test", ...).
//!
//! Pairs in which the observed or the predicted value is not finite are skipped (the legend says
//! how many); a split left without any finite pair is an error, as are an empty list of splits,
//! empty slices and slices of different lengths.

use crate::numeric::quantile_sorted;
use std::path::Path;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::labels::axis_label;
use super::{DESC_FONT, FONT, LEGEND_FONT, TICK_FONT};
use crate::draw_figure;
use crate::error::{Error, Result};

/// Points of one data split for the figures.
#[derive(Debug, Clone, Copy)]
pub struct Split<'a> {
    /// Name of the split in the legend (e.g. "train", "test").
    pub label: &'a str,
    /// Observed (simulated) values of the response.
    pub observed: &'a [f64],
    /// Metamodel predictions, one per observed value.
    pub predicted: &'a [f64],
}

/// Parity plot: predicted against observed, one colour/marker per split (e.g. "train", "test"),
/// the y = x line, axis labels `"{label}, observed"` / `"{label}, predicted"` (`label` is
/// [`axis_label`] of `response`, e.g. "shear angle (deg)" for "shear_angle"), and a legend
/// giving each split's R^2 and RMSE (computed inside from the slices). Axes span the union of all
/// values with a 5 % margin and equal ranges on both axes; the plotting area is square, so the
/// y = x line runs at 45 degrees.
pub fn parity(path: &Path, response: &str, splits: &[Split]) -> Result<()> {
    let data = prepare_splits(path, "parity plot", splits)?;
    let (lo, hi) = padded_range(
        path,
        data.iter()
            .flat_map(|s| s.observed.iter().chain(&s.predicted))
            .copied(),
    )?;
    let response = axis_label(response);
    draw_figure!(path, PARITY_SIZE, draw_parity(&response, &data, lo, hi))
}

/// Histogram of residuals (observed - predicted), bins shared by all splits (Freedman-Diaconis
/// rule on the pooled residuals, the square-root rule when the interquartile range is zero,
/// clamped to 10..=40 bins), the splits' bars side by side within each bin, x label
/// "residual of {label}" ([`axis_label`] of `response`), y label "count"; the legend gives each
/// split's 5/50/95 % residual quantiles.
pub fn residual_histogram(path: &Path, response: &str, splits: &[Split]) -> Result<()> {
    let data = prepare_splits(path, "residual histogram", splits)?;
    let residuals: Vec<Vec<f64>> = data.iter().map(SplitData::residuals).collect();
    let mut pooled: Vec<f64> = residuals.iter().flatten().copied().collect();
    pooled.sort_by(f64::total_cmp);
    let bins = Bins::new(path, &pooled)?;
    let hist = HistData {
        counts: residuals.iter().map(|r| bins.counts(r)).collect(),
        quantiles: residuals
            .iter()
            .map(|r| {
                let mut r = r.clone();
                r.sort_by(f64::total_cmp);
                [
                    quantile_sorted(&r, 0.05),
                    quantile_sorted(&r, 0.5),
                    quantile_sorted(&r, 0.95),
                ]
            })
            .collect(),
        bins,
    };
    let response = axis_label(response);
    draw_figure!(path, HIST_SIZE, draw_histogram(&response, &data, &hist))
}

const PARITY_SIZE: (u32, u32) = (820, 760);
const HIST_SIZE: (u32, u32) = (900, 600);
const MARGIN: u32 = 15;
const X_LABEL_AREA: u32 = 55;
const Y_LABEL_AREA: u32 = 80;

/// Matplotlib's "tab10" colours.
const PALETTE: [RGBColor; 8] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
    RGBColor(0x17, 0xbe, 0xcf),
];

fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// The finite pairs of one split.
struct SplitData {
    label: String,
    observed: Vec<f64>,
    predicted: Vec<f64>,
    skipped: usize,
}

impl SplitData {
    fn residuals(&self) -> Vec<f64> {
        self.observed
            .iter()
            .zip(&self.predicted)
            .map(|(o, p)| o - p)
            .filter(|r| r.is_finite())
            .collect()
    }

    /// "n = 80" plus the number of skipped pairs, if any.
    fn count_text(&self) -> String {
        let n = self.observed.len();
        match self.skipped {
            0 => format!("n = {n}"),
            s => format!("n = {n}, {s} non-finite skipped"),
        }
    }
}

fn prepare_splits(path: &Path, what: &str, splits: &[Split]) -> Result<Vec<SplitData>> {
    let fail = |msg: String| Error::invalid(format!("{}: {what}: {msg}", path.display()));
    if splits.is_empty() {
        return Err(fail("no data splits given".into()));
    }
    splits
        .iter()
        .map(|s| {
            let (no, np) = (s.observed.len(), s.predicted.len());
            if no != np {
                return Err(fail(format!(
                    "split \"{}\": {no} observed values but {np} predicted values",
                    s.label
                )));
            }
            if no == 0 {
                return Err(fail(format!("split \"{}\" has no values", s.label)));
            }
            let (observed, predicted): (Vec<f64>, Vec<f64>) = s
                .observed
                .iter()
                .zip(s.predicted)
                .filter(|(o, p)| o.is_finite() && p.is_finite())
                .map(|(&o, &p)| (o, p))
                .unzip();
            if observed.is_empty() {
                return Err(fail(format!(
                    "split \"{}\": none of its {no} observed/predicted pairs is finite",
                    s.label
                )));
            }
            Ok(SplitData {
                label: s.label.to_string(),
                skipped: no - observed.len(),
                observed,
                predicted,
            })
        })
        .collect()
}

/// The range of finite values, widened to a nonzero span when all values are equal.
fn span_of(path: &Path, values: impl Iterator<Item = f64>) -> Result<(f64, f64)> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(Error::invalid(format!(
            "{}: no finite values to plot",
            path.display()
        )));
    }
    let scale = lo.abs().max(hi.abs());
    if hi - lo <= scale * 1e-12 {
        let c = 0.5 * (lo + hi);
        let half = if c == 0.0 { 0.5 } else { 0.1 * c.abs() };
        return Ok((c - half, c + half));
    }
    if !(hi - lo).is_finite() {
        return Err(Error::invalid(format!(
            "{}: values from {lo:e} to {hi:e} are too far apart to plot",
            path.display()
        )));
    }
    Ok((lo, hi))
}

/// [`span_of`] with a 5 % margin on both sides.
fn padded_range(path: &Path, values: impl Iterator<Item = f64>) -> Result<(f64, f64)> {
    let (lo, hi) = span_of(path, values)?;
    let pad = 0.05 * (hi - lo);
    if !(lo - pad).is_finite() || !(hi + pad).is_finite() {
        return Err(Error::invalid(format!(
            "{}: values up to {:e} are too large to plot",
            path.display(),
            lo.abs().max(hi.abs())
        )));
    }
    Ok((lo - pad, hi + pad))
}

/// Coefficient of determination and root mean square error of `predicted` against `observed`.
/// R^2 is NaN when the observed values do not vary.
fn r2_rmse(observed: &[f64], predicted: &[f64]) -> (f64, f64) {
    let n = observed.len() as f64;
    let mean = observed.iter().sum::<f64>() / n;
    let ss_res: f64 = observed
        .iter()
        .zip(predicted)
        .map(|(o, p)| (o - p).powi(2))
        .sum();
    let ss_tot: f64 = observed.iter().map(|o| (o - mean).powi(2)).sum();
    let r2 = if ss_tot > 0.0 {
        1.0 - ss_res / ss_tot
    } else {
        f64::NAN
    };
    (r2, (ss_res / n).sqrt())
}
/// Four significant digits, switching to scientific notation outside 1e-3..1e5.
fn fmt_num(v: f64) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

/// Tick label for `v` on an axis spanning `lo..hi`: as many decimals as the tick spacing needs,
/// trailing zeros trimmed, "0" instead of rounding noise such as "-0.0", and scientific notation
/// for very large or small magnitudes.
fn tick_label(v: f64, lo: f64, hi: f64) -> String {
    let span = hi - lo;
    if v.abs() <= span * 1e-9 {
        return "0".into();
    }
    // Ticks are at least about span / 20 apart.
    let step_exp = (span / 20.0).log10().floor() as i32;
    let max_abs = lo.abs().max(hi.abs());
    let trim = |s: String| {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    };
    if !(1e-4..1e6).contains(&max_abs) {
        let decimals = (max_abs.log10().floor() as i32 - step_exp).clamp(0, 6) as usize;
        let s = format!("{v:.decimals$e}");
        match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", trim(m.to_string())),
            None => s,
        }
    } else {
        let decimals = (-step_exp).clamp(0, 12) as usize;
        trim(format!("{v:.decimals$}"))
    }
}

/// A chart builder for `area` with the shared margins and label areas.
fn builder<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    extra_right: u32,
    extra_bottom: u32,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(area);
    b.margin(MARGIN)
        .margin_right(MARGIN + extra_right)
        .margin_bottom(MARGIN + extra_bottom)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA);
    b
}

type Chart2d<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

fn draw_parity<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    response: &str,
    data: &[SplitData],
    lo: f64,
    hi: f64,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let area = root.titled(&format!("{response}: predicted vs. observed"), (FONT, 22))?;
    // Make the plotting area square so that equal axis ranges give a 45 degree y = x line.
    let (w, h) = area.dim_in_pixel();
    let pw = w.saturating_sub(2 * MARGIN + Y_LABEL_AREA);
    let ph = h.saturating_sub(2 * MARGIN + X_LABEL_AREA);
    let (extra_right, extra_bottom) = (pw.saturating_sub(ph), ph.saturating_sub(pw));
    let mut chart = builder(&area, extra_right, extra_bottom).build_cartesian_2d(lo..hi, lo..hi)?;
    chart
        .configure_mesh()
        .x_label_formatter(&|v| tick_label(*v, lo, hi))
        .y_label_formatter(&|v| tick_label(*v, lo, hi))
        .x_desc(format!("{response}, observed"))
        .y_desc(format!("{response}, predicted"))
        .axis_desc_style((FONT, DESC_FONT))
        .label_style((FONT, TICK_FONT))
        .draw()?;
    chart
        .draw_series(LineSeries::new([(lo, lo), (hi, hi)], BLACK.stroke_width(1)))?
        .label("y = x")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.stroke_width(1)));
    for (i, s) in data.iter().enumerate() {
        let (r2, rmse) = r2_rmse(&s.observed, &s.predicted);
        let r2 = if r2.is_finite() {
            format!("{r2:.4}")
        } else {
            "n/a".into()
        };
        let label = format!(
            "{} ({}): R² = {r2}, RMSE = {}",
            s.label,
            s.count_text(),
            fmt_num(rmse)
        );
        let points = s.observed.iter().copied().zip(s.predicted.iter().copied());
        draw_markers(&mut chart, i, points, label)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .label_font((FONT, LEGEND_FONT))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// Draws the points of split `i` with its colour and marker shape, and their legend entry.
fn draw_markers<DB: DrawingBackend>(
    chart: &mut Chart2d<'_, DB>,
    i: usize,
    points: impl Iterator<Item = (f64, f64)>,
    label: String,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let c = colour(i);
    let fill = c.mix(0.6).filled();
    let line = c.stroke_width(2);
    let s: i32 = 4;
    let anno = match i % 5 {
        0 => chart
            .draw_series(points.map(|p| Circle::new(p, s, fill)))?
            .legend(move |(x, y)| Circle::new((x + 10, y), s, fill)),
        1 => chart
            .draw_series(points.map(|p| TriangleMarker::new(p, s + 1, fill)))?
            .legend(move |(x, y)| TriangleMarker::new((x + 10, y), s + 1, fill)),
        2 => chart
            .draw_series(points.map(|p| Cross::new(p, s, line)))?
            .legend(move |(x, y)| Cross::new((x + 10, y), s, line)),
        3 => chart
            .draw_series(
                points.map(|p| EmptyElement::at(p) + Rectangle::new([(-s, -s), (s, s)], fill)),
            )?
            .legend(move |(x, y)| Rectangle::new([(x + 10 - s, y - s), (x + 10 + s, y + s)], fill)),
        _ => {
            let d = s + 1;
            let diamond = move || vec![(0, -d), (d, 0), (0, d), (-d, 0)];
            chart
                .draw_series(
                    points.map(move |p| EmptyElement::at(p) + Polygon::new(diamond(), fill)),
                )?
                .legend(move |(x, y)| {
                    Polygon::new(
                        diamond()
                            .into_iter()
                            .map(|(dx, dy)| (x + 10 + dx, y + dy))
                            .collect::<Vec<_>>(),
                        fill,
                    )
                })
        }
    };
    anno.label(label);
    Ok(())
}

/// Equal-width bins shared by all splits.
struct Bins {
    lo: f64,
    width: f64,
    n: usize,
}

impl Bins {
    /// Bins over the sorted, non-empty, finite pooled residuals.
    fn new(path: &Path, sorted: &[f64]) -> Result<Self> {
        let (lo, hi) = span_of(path, sorted.iter().copied())?;
        let span = hi - lo;
        let count = sorted.len() as f64;
        let iqr = quantile_sorted(sorted, 0.75) - quantile_sorted(sorted, 0.25);
        let fd_width = 2.0 * iqr / count.cbrt();
        let n = if lo < sorted[0] {
            // All residuals equal (span_of widened the range around them): an odd count puts
            // them in the middle of the centre bin.
            11.0
        } else if fd_width > 0.0 && (span / fd_width).is_finite() {
            (span / fd_width).ceil()
        } else {
            count.sqrt().ceil()
        };
        let n = n.clamp(10.0, 40.0) as usize;
        Ok(Bins {
            lo,
            width: span / n as f64,
            n,
        })
    }

    fn edge(&self, i: usize) -> f64 {
        self.lo + self.width * i as f64
    }

    fn counts(&self, values: &[f64]) -> Vec<u32> {
        let mut counts = vec![0u32; self.n];
        for v in values {
            let i = ((v - self.lo) / self.width).floor().max(0.0) as usize;
            counts[i.min(self.n - 1)] += 1;
        }
        counts
    }
}

struct HistData {
    bins: Bins,
    /// Per split, the count in each bin.
    counts: Vec<Vec<u32>>,
    /// Per split, the 5, 50 and 95 % quantiles of the residuals.
    quantiles: Vec<[f64; 3]>,
}

fn draw_histogram<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    response: &str,
    data: &[SplitData],
    hist: &HistData,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let area = root.titled(&format!("Residuals of {response}"), (FONT, 22))?;
    let bins = &hist.bins;
    let (lo, hi) = (bins.edge(0), bins.edge(bins.n));
    let pad = 0.05 * (hi - lo);
    // Leave room above the tallest bar for the legend (one row per split).
    let max_count = hist
        .counts
        .iter()
        .flatten()
        .copied()
        .max()
        .unwrap_or(0)
        .max(1);
    let (_, h) = area.dim_in_pixel();
    let plot_h = h.saturating_sub(2 * MARGIN + X_LABEL_AREA).max(1) as f64;
    let legend_h = (data.len() as f64 * (LEGEND_FONT as f64 + 8.0) + 30.0) / plot_h;
    let top = (max_count as f64 / (1.0 - legend_h.min(0.6) - 0.03)).ceil() as u32;
    let mut chart = builder(&area, 0, 0).build_cartesian_2d((lo - pad)..(hi + pad), 0u32..top)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_label_formatter(&|v| tick_label(*v, lo - pad, hi + pad))
        .x_desc(format!("residual of {response}"))
        .y_desc("count")
        .axis_desc_style((FONT, DESC_FONT))
        .label_style((FONT, TICK_FONT))
        .draw()?;
    if lo - pad < 0.0 && 0.0 < hi + pad {
        chart.draw_series(LineSeries::new(
            [(0.0, 0), (0.0, top)],
            BLACK.mix(0.5).stroke_width(1),
        ))?;
    }
    let k = data.len() as f64;
    for (j, (s, (counts, q))) in data
        .iter()
        .zip(hist.counts.iter().zip(&hist.quantiles))
        .enumerate()
    {
        let c = colour(j);
        let bars = counts
            .iter()
            .enumerate()
            .filter(|(_, &n)| n > 0)
            .map(|(i, &n)| {
                let x0 = bins.edge(i) + bins.width * (0.05 + 0.9 * j as f64 / k);
                let x1 = bins.edge(i) + bins.width * (0.05 + 0.9 * (j + 1) as f64 / k);
                Rectangle::new([(x0, 0), (x1, n)], c.mix(0.85).filled())
            });
        chart
            .draw_series(bars)?
            .label(format!(
                "{} ({}): 5 % = {}, median = {}, 95 % = {}",
                s.label,
                s.count_text(),
                fmt_num(q[0]),
                fmt_num(q[1]),
                fmt_num(q[2])
            ))
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 16, y + 6)], c.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .label_font((FONT, LEGEND_FONT))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic "train"/"test" data set with a slightly imperfect model.
    fn sample(n: usize, phase: f64) -> (Vec<f64>, Vec<f64>) {
        let observed: Vec<f64> = (0..n)
            .map(|i| 0.3 + 0.4 * ((i as f64 * 0.731 + phase).sin() * 0.5 + 0.5))
            .collect();
        let predicted = observed
            .iter()
            .enumerate()
            .map(|(i, o)| o + 0.02 * (i as f64 * 2.17 + phase).sin())
            .collect();
        (observed, predicted)
    }

    fn assert_written(path: &Path) {
        let len = std::fs::metadata(path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
            .len();
        assert!(len > 0, "{} is empty", path.display());
    }

    #[test]
    fn writes_svg_and_png() {
        let dir = tempfile::tempdir().unwrap();
        let (to, tp) = sample(120, 0.0);
        let (vo, vp) = sample(30, 1.0);
        let splits = [
            Split {
                label: "train",
                observed: &to,
                predicted: &tp,
            },
            Split {
                label: "test",
                observed: &vo,
                predicted: &vp,
            },
        ];
        for ext in ["svg", "png"] {
            let p = dir.path().join(format!("parity.{ext}"));
            parity(&p, "angle of repose / °", &splits).unwrap();
            assert_written(&p);
            let h = dir.path().join(format!("sub/residuals.{ext}"));
            residual_histogram(&h, "angle of repose / °", &splits).unwrap();
            assert_written(&h);
        }
        let svg = std::fs::read_to_string(dir.path().join("parity.svg")).unwrap();
        assert!(svg.contains("angle of repose / °, observed"));
        assert!(svg.contains("angle of repose / °, predicted"));
        assert!(svg.contains("R² = "));
        let svg = std::fs::read_to_string(dir.path().join("sub/residuals.svg")).unwrap();
        assert!(svg.contains("residual of angle of repose / °"));
        assert!(svg.contains("median = "));
    }

    #[test]
    fn readable_labels_fonts_and_a_legend_entry_per_split() {
        let dir = tempfile::tempdir().unwrap();
        let data: Vec<(Vec<f64>, Vec<f64>)> = (0..3).map(|k| sample(40, k as f64)).collect();
        let splits: Vec<Split> = ["train", "test", "validation"]
            .iter()
            .zip(&data)
            .map(|(label, (o, p))| Split {
                label,
                observed: o,
                predicted: p,
            })
            .collect();
        let p = dir.path().join("parity.svg");
        parity(&p, "shear_angle", &splits).unwrap();
        let svg = std::fs::read_to_string(&p).unwrap();
        assert!(svg.contains("shear angle (deg), observed"), "x axis label");
        assert!(svg.contains("shear angle (deg), predicted"), "y axis label");
        assert!(
            !svg.contains("shear_angle"),
            "snake_case name left in the figure"
        );
        for split in [
            "train (n = 40)",
            "test (n = 40)",
            "validation (n = 40)",
            "y = x",
        ] {
            assert!(svg.contains(split), "no legend entry for {split}");
        }
        crate::plot::test_util::assert_fonts_at_least(&svg, 12.0);
        let h = dir.path().join("residuals.svg");
        residual_histogram(&h, "bulk_density", &splits).unwrap();
        let svg = std::fs::read_to_string(&h).unwrap();
        assert!(svg.contains("residual of bulk density (kg/m³)"));
        assert!(svg.contains("validation (n = 40)"));
        crate::plot::test_util::assert_fonts_at_least(&svg, 12.0);
    }

    #[test]
    fn mismatched_lengths_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("p.svg");
        let splits = [Split {
            label: "test",
            observed: &[1.0, 2.0, 3.0],
            predicted: &[1.0, 2.0],
        }];
        let e = parity(&p, "y", &splits).unwrap_err().to_string();
        assert!(e.contains("\"test\"") && e.contains("3 observed") && e.contains("2 predicted"));
        assert!(residual_histogram(&p, "y", &splits).is_err());
        assert!(!p.exists());
    }

    #[test]
    fn empty_input_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("p.png");
        let e = parity(&p, "y", &[]).unwrap_err().to_string();
        assert!(e.contains("no data splits"), "{e}");
        assert!(residual_histogram(&p, "y", &[]).is_err());
        let empty = [Split {
            label: "train",
            observed: &[],
            predicted: &[],
        }];
        let e = parity(&p, "y", &empty).unwrap_err().to_string();
        assert!(e.contains("has no values"), "{e}");
        assert!(residual_histogram(&p, "y", &empty).is_err());
    }

    #[test]
    fn non_finite_values_are_skipped_or_rejected() {
        let dir = tempfile::tempdir().unwrap();
        let some = [Split {
            label: "train",
            observed: &[1.0, f64::NAN, 2.0, 3.0, f64::INFINITY],
            predicted: &[1.1, 2.0, f64::NEG_INFINITY, 2.9, 4.0],
        }];
        for name in ["p.svg", "p.png"] {
            let p = dir.path().join(name);
            parity(&p, "y", &some).unwrap();
            assert_written(&p);
            residual_histogram(&dir.path().join(format!("h{name}")), "y", &some).unwrap();
        }
        let svg = std::fs::read_to_string(dir.path().join("p.svg")).unwrap();
        assert!(svg.contains("3 non-finite skipped"));
        let none = [Split {
            label: "train",
            observed: &[f64::NAN, 1.0],
            predicted: &[1.0, f64::INFINITY],
        }];
        let p = dir.path().join("none.svg");
        let e = parity(&p, "y", &none).unwrap_err().to_string();
        assert!(e.contains("finite"), "{e}");
        assert!(residual_histogram(&p, "y", &none).is_err());
        // Finite but so far apart that the span overflows.
        let huge = [Split {
            label: "train",
            observed: &[f64::MAX, -f64::MAX],
            predicted: &[-f64::MAX, f64::MAX],
        }];
        assert!(parity(&p, "y", &huge).is_err());
        assert!(residual_histogram(&p, "y", &huge).is_err());
        // Residuals that overflow in one split only: that split's quantiles are n/a.
        let mixed = [
            huge[0],
            Split {
                label: "test",
                observed: &[1.0, 2.0],
                predicted: &[1.5, 2.5],
            },
        ];
        residual_histogram(&p, "y", &mixed).unwrap();
        assert_written(&p);
    }

    #[test]
    fn all_equal_values_get_a_span() {
        let dir = tempfile::tempdir().unwrap();
        for v in [0.0, 2.5, -1e9] {
            let obs = [v; 4];
            let splits = [Split {
                label: "train",
                observed: &obs,
                predicted: &obs,
            }];
            for ext in ["svg", "png"] {
                let p = dir.path().join(format!("p{v}.{ext}"));
                parity(&p, "y", &splits).unwrap();
                assert_written(&p);
                let h = dir.path().join(format!("h{v}.{ext}"));
                residual_histogram(&h, "y", &splits).unwrap();
                assert_written(&h);
            }
        }
        // A single point.
        let one = [Split {
            label: "train",
            observed: &[1.0],
            predicted: &[1.5],
        }];
        parity(&dir.path().join("one.svg"), "y", &one).unwrap();
        residual_histogram(&dir.path().join("one.svg"), "y", &one).unwrap();
    }

    #[test]
    fn bad_extension_errors() {
        let dir = tempfile::tempdir().unwrap();
        let (o, p) = sample(10, 0.0);
        let splits = [Split {
            label: "train",
            observed: &o,
            predicted: &p,
        }];
        assert!(parity(&dir.path().join("p.pdf"), "y", &splits).is_err());
        assert!(residual_histogram(&dir.path().join("h"), "y", &splits).is_err());
    }

    #[test]
    fn metrics_and_helpers() {
        let (r2, rmse) = r2_rmse(&[1.0, 2.0, 3.0], &[1.0, 2.0, 3.0]);
        assert_eq!((r2, rmse), (1.0, 0.0));
        let (r2, rmse) = r2_rmse(&[1.0, 2.0, 3.0], &[2.0, 2.0, 2.0]);
        assert!(r2.abs() < 1e-12);
        assert!((rmse - (2.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert!(r2_rmse(&[2.0, 2.0], &[2.0, 1.0]).0.is_nan());

        let v = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(quantile_sorted(&v, 0.0), 1.0);
        assert_eq!(quantile_sorted(&v, 0.5), 3.0);
        assert_eq!(quantile_sorted(&v, 1.0), 5.0);
        assert!((quantile_sorted(&v, 0.05) - 1.2).abs() < 1e-12);
        assert_eq!(quantile_sorted(&[7.0], 0.95), 7.0);
        assert!(quantile_sorted(&[], 0.5).is_nan());

        let p = Path::new("x.svg");
        for sorted in [vec![0.0; 3], (0..10_000).map(|i| i as f64).collect()] {
            let b = Bins::new(p, &sorted).unwrap();
            assert!((10..=40).contains(&b.n) && b.width > 0.0);
            let counts = b.counts(&sorted);
            assert_eq!(counts.iter().sum::<u32>() as usize, sorted.len());
        }
        // Equal residuals sit in the middle of the centre bin, not on an edge.
        let b = Bins::new(p, &[0.0; 3]).unwrap();
        assert_eq!(b.n, 11);
        assert_eq!(b.counts(&[0.0])[5], 1);

        assert_eq!(fmt_num(0.012345), "0.01235");
        assert_eq!(fmt_num(123.456), "123.5");
        assert_eq!(fmt_num(0.0), "0");
        assert_eq!(fmt_num(f64::NAN), "n/a");
        assert_eq!(fmt_num(1.5e-7), "1.500e-7");

        assert_eq!(tick_label(-1.4e-17, -0.55, 0.55), "0");
        assert_eq!(tick_label(-0.5, -0.55, 0.55), "-0.5");
        assert_eq!(tick_label(24.0, 23.0, 41.0), "24");
        assert_eq!(tick_label(0.0015, -0.002, 0.004), "0.0015");
        assert_eq!(tick_label(1.02e9, 0.9e9, 1.1e9), "1.02e9");
        assert_eq!(tick_label(3.0e-6, 0.0, 1.0e-5), "3e-6");
    }
}
