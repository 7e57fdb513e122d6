//! Corner plot (pairs plot) of samples: the Bayesian posterior of a TMCMC run, or the set of
//! equally good calibration optima. The diagonal holds a histogram of each parameter, the lower
//! triangle a scatter plot of every pair; parameter names label the bottom row and the left
//! column. Optional marks (the best optimum, the true values, ...) are drawn as vertical lines on
//! the histograms and as crosses on the scatter plots.
//!
//! A sample with a non-finite coordinate is skipped as a whole (the title says how many); having
//! none left is an error, as are no samples, no parameter names, a sample or a list of marks or
//! ranges whose length differs from the number of names, and a range that is not finite or runs
//! backwards. A non-finite mark only leaves that parameter unmarked.

use crate::numeric::quantile_sorted;
use std::path::Path;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::labels::short_label;
use super::{FONT, TICK_FONT};
use crate::draw_figure;
use crate::error::{Error, Result};

/// Corner plot: a histogram of each parameter on the diagonal, a scatter of every pair below it,
/// axis labels with the parameter names; `marks` (e.g. the best optimum or the true values) drawn
/// as lines on the histograms and crosses on the scatters. Panel ranges from the samples (1 %-99 %
/// quantiles widened by 5 %, or `ranges` when given, e.g. the prior box).
///
/// `samples[i]` is one point with `names.len()` coordinates. Samples outside a panel's range are
/// left out of that panel (histogram and scatter); so is a mark outside it. The scatter plots show
/// at most [`MAX_SCATTER`] samples (every k-th one), the histograms all of them.
pub fn corner(
    path: &Path,
    names: &[String],
    samples: &[Vec<f64>],
    marks: Option<&[f64]>,
    ranges: Option<&[(f64, f64)]>,
) -> Result<()> {
    corner_keyed(
        path,
        names,
        samples,
        marks.map(|m| (m, "marked point")),
        ranges,
    )
}

/// [`corner`] with the marks named: `marks` is `(values, what they are)`, e.g. the best optimum,
/// and the title line gives the key ("red lines and crosses: best optimum").
pub fn corner_keyed(
    path: &Path,
    names: &[String],
    samples: &[Vec<f64>],
    marks: Option<(&[f64], &str)>,
    ranges: Option<&[(f64, f64)]>,
) -> Result<()> {
    let mut data = CornerData::new(path, names, samples, marks.map(|m| m.0), ranges)?;
    data.mark_label = marks
        .filter(|(m, _)| m.iter().any(|v| v.is_finite()))
        .map(|(_, l)| l.trim().to_string())
        .filter(|l| !l.is_empty());
    let size = data.layout.size();
    draw_figure!(path, size, draw_corner(&data))
}

/// The most samples drawn in each scatter plot; more are thinned by a fixed stride.
pub const MAX_SCATTER: usize = 3000;

/// The most parameters a corner plot shows (panels of `MIN_PANEL` px in a `MAX_SIDE` px
/// figure); up to about 12 stay comfortably legible.
pub const MAX_PARAMS: usize = 64;

/// Preferred side of one panel (including its gaps), pixels.
const PANEL: u32 = 220;
/// Smallest side of one panel when many parameters have to fit into [`MAX_SIDE`].
const MIN_PANEL: u32 = 60;
/// The figure is at least this wide...
const MIN_SIDE: u32 = 500;
/// ... and, unless that would make panels smaller than [`MIN_PANEL`], at most this wide.
const MAX_SIDE: u32 = 4000;
/// Room for the tick labels and the name left of the first column.
const LEFT: u32 = 85;
/// Room for the tick labels and the name below the last row.
const BOTTOM: u32 = 62;
/// Outer margins right and below the grid.
const RIGHT: u32 = 15;
const BELOW: u32 = 8;
/// Height of the title line.
const TITLE_H: u32 = 32;
/// Gap around each panel's plotting area.
const GAP: u32 = 5;

const DOT: RGBColor = RGBColor(0x1f, 0x77, 0xb4);
const MARK: RGBColor = RGBColor(0xd6, 0x27, 0x28);

/// Pixel geometry of the grid of panels.
#[derive(Debug, Clone, Copy)]
struct Layout {
    /// Number of parameters (panels per row and column).
    n: u32,
    /// Side of one grid cell, the plotting area plus `2 * GAP`.
    panel: u32,
}

impl Layout {
    fn new(n: usize) -> Self {
        let n = n.max(1) as u32;
        let fit = MAX_SIDE.saturating_sub(LEFT + RIGHT) / n;
        let panel = PANEL.min(fit).max(MIN_PANEL);
        // Small grids grow to the minimum figure width.
        let panel = panel.max(MIN_SIDE.saturating_sub(LEFT + RIGHT) / n);
        Layout { n, panel }
    }

    fn size(&self) -> (u32, u32) {
        let grid = self.n * self.panel;
        (LEFT + grid + RIGHT, TITLE_H + grid + BOTTOM + BELOW)
    }

    /// Side of a plotting area.
    fn inner(&self) -> u32 {
        self.panel - 2 * GAP
    }

    /// Number of tick labels a panel side holds.
    fn ticks(&self) -> usize {
        (self.inner() / 40).clamp(2, 10) as usize
    }

    /// Tick labels at the default panel size are [`TICK_FONT`] (12.1 px in SVG); only the
    /// small panels of a figure with many parameters get smaller ones.
    fn tick_font(&self) -> u32 {
        (self.panel / 14).clamp(9, TICK_FONT)
    }

    /// Number of histogram bins for `count` values: the square-root rule, at least 10, and bars
    /// at least about 7 px wide.
    fn bins(&self, count: usize) -> usize {
        let max = (self.inner() / 7).max(10) as usize;
        ((count as f64).sqrt().round() as usize).clamp(10, max)
    }
}

/// The validated samples and everything derived from them.
struct CornerData {
    names: Vec<String>,
    /// Per parameter, its coordinate in each kept (all-finite) sample.
    columns: Vec<Vec<f64>>,
    /// Per parameter, the panel range.
    ranges: Vec<(f64, f64)>,
    /// Per parameter, the mark (NaN for none).
    marks: Vec<f64>,
    /// What the marks are, for the key in the title.
    mark_label: Option<String>,
    /// Samples given, and samples skipped for a non-finite coordinate.
    total: usize,
    skipped: usize,
    /// Indices into the kept samples that the scatter plots show: every `stride`-th one.
    shown: Vec<usize>,
    stride: usize,
    layout: Layout,
}

impl CornerData {
    fn new(
        path: &Path,
        names: &[String],
        samples: &[Vec<f64>],
        marks: Option<&[f64]>,
        ranges: Option<&[(f64, f64)]>,
    ) -> Result<Self> {
        let fail = |msg: String| Error::invalid(format!("{}: corner plot: {msg}", path.display()));
        let n = names.len();
        if n == 0 {
            return Err(fail("no parameter names given".into()));
        }
        if n > MAX_PARAMS {
            return Err(fail(format!(
                "{n} parameters are too many to show; at most {MAX_PARAMS} fit"
            )));
        }
        if samples.is_empty() {
            return Err(fail("no samples given".into()));
        }
        if let Some((i, s)) = samples.iter().enumerate().find(|(_, s)| s.len() != n) {
            return Err(fail(format!(
                "sample {i} has {} coordinates but {n} parameter names are given",
                s.len()
            )));
        }
        if let Some(m) = marks.filter(|m| m.len() != n) {
            return Err(fail(format!("{} marks given for {n} parameters", m.len())));
        }
        if let Some(r) = ranges.filter(|r| r.len() != n) {
            return Err(fail(format!("{} ranges given for {n} parameters", r.len())));
        }
        let names: Vec<String> = names
            .iter()
            .enumerate()
            .map(|(j, s)| match s.trim() {
                "" => format!("parameter {}", j + 1),
                t => short_label(t),
            })
            .collect();

        let kept: Vec<&Vec<f64>> = samples
            .iter()
            .filter(|s| s.iter().all(|v| v.is_finite()))
            .collect();
        if kept.is_empty() {
            return Err(fail(format!(
                "none of the {} samples has only finite coordinates",
                samples.len()
            )));
        }
        let columns: Vec<Vec<f64>> = (0..n)
            .map(|j| kept.iter().map(|s| s[j]).collect())
            .collect();

        let ranges = match ranges {
            Some(r) => r
                .iter()
                .zip(&names)
                .map(|(&(lo, hi), name)| {
                    if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                        return Err(fail(format!(
                            "range {lo}..{hi} of \"{name}\": expected finite bounds, lower <= upper"
                        )));
                    }
                    checked_span(lo, hi).ok_or_else(|| {
                        fail(format!(
                            "range {lo:e}..{hi:e} of \"{name}\" is too wide to plot"
                        ))
                    })
                })
                .collect::<Result<Vec<_>>>()?,
            None => columns
                .iter()
                .zip(&names)
                .map(|(c, name)| {
                    auto_range(c).ok_or_else(|| {
                        let (lo, hi) = c.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                            (a.min(v), b.max(v))
                        });
                        fail(format!(
                            "the values of \"{name}\" (from {lo:e} to {hi:e}) are too large or too far apart to plot"
                        ))
                    })
                })
                .collect::<Result<Vec<_>>>()?,
        };

        let stride = kept.len().div_ceil(MAX_SCATTER).max(1);
        Ok(CornerData {
            names,
            columns,
            ranges,
            marks: marks.map_or_else(|| vec![f64::NAN; n], <[f64]>::to_vec),
            mark_label: None,
            total: samples.len(),
            skipped: samples.len() - kept.len(),
            shown: (0..kept.len()).step_by(stride).collect(),
            stride,
            layout: Layout::new(n),
        })
    }

    fn kept(&self) -> usize {
        self.columns[0].len()
    }

    fn title(&self) -> String {
        let mut t = match self.total {
            1 => "1 sample".to_string(),
            n => format!("{n} samples"),
        };
        if self.skipped > 0 {
            t += &format!(", {} with non-finite coordinates skipped", self.skipped);
        }
        if self.names.len() > 1 && self.shown.len() < self.kept() {
            t += &format!(
                "; the scatter plots show {} of them (every {})",
                self.shown.len(),
                ordinal(self.stride)
            );
        }
        if let Some(label) = &self.mark_label {
            t += &format!("; red lines and crosses: {label}");
        }
        t
    }

    /// Histogram of parameter `j` over its panel range: bin edges' origin, width and counts.
    fn histogram(&self, j: usize) -> (f64, f64, Vec<u32>) {
        let (lo, hi) = self.ranges[j];
        let inside: Vec<f64> = self.columns[j]
            .iter()
            .copied()
            .filter(|v| (lo..=hi).contains(v))
            .collect();
        let bins = self.layout.bins(inside.len());
        let width = (hi - lo) / bins as f64;
        let mut counts = vec![0u32; bins];
        for v in inside {
            let i = ((v - lo) / width).floor().max(0.0) as usize;
            counts[i.min(bins - 1)] += 1;
        }
        (lo, width, counts)
    }

    /// The mark of parameter `j` if it is finite and inside the panel range.
    fn mark(&self, j: usize) -> Option<f64> {
        let (lo, hi) = self.ranges[j];
        Some(self.marks[j]).filter(|m| (lo..=hi).contains(m))
    }
}

/// "2nd", "7th", "11th", "23rd", ...
fn ordinal(k: usize) -> String {
    let suffix = match (k % 10, k % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{k}{suffix}")
}

/// `lo..hi` widened to a nonzero span around its centre when it is (nearly) empty: +-10 % of
/// the centre, or +-0.5 around (nearly) zero; `None` when the result is not finite.
fn checked_span(lo: f64, hi: f64) -> Option<(f64, f64)> {
    let scale = lo.abs().max(hi.abs());
    let (lo, hi) = if hi - lo <= scale * 1e-12 || hi - lo < 1e-200 {
        let c = 0.5 * lo + 0.5 * hi;
        let half = if c.abs() < 1e-200 { 0.5 } else { 0.1 * c.abs() };
        (c - half, c + half)
    } else {
        (lo, hi)
    };
    (lo.is_finite() && hi.is_finite() && (hi - lo).is_finite()).then_some((lo, hi))
}

/// The 1 %-99 % quantile range of finite values (their full range when the quantiles coincide),
/// given a nonzero span and widened by 5 % on both sides; `None` when that overflows.
fn auto_range(values: &[f64]) -> Option<(f64, f64)> {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let (mut lo, mut hi) = (
        quantile_sorted(&sorted, 0.01),
        quantile_sorted(&sorted, 0.99),
    );
    if hi - lo <= lo.abs().max(hi.abs()) * 1e-12 {
        (lo, hi) = (*sorted.first()?, *sorted.last()?);
    }
    let (lo, hi) = checked_span(lo, hi)?;
    let pad = 0.05 * (hi - lo);
    let (lo, hi) = (lo - pad, hi + pad);
    (lo.is_finite() && hi.is_finite() && (hi - lo).is_finite()).then_some((lo, hi))
}
/// Tick label for `v` on an axis spanning `lo..hi`: as many decimals as the tick spacing needs,
/// trailing zeros trimmed, "0" instead of rounding noise such as "-0.0", and scientific notation
/// (e.g. "2.5e7") for magnitudes outside 1e-3..1e5.
fn tick_label(v: f64, lo: f64, hi: f64) -> String {
    let span = hi - lo;
    if v.abs() <= span * 1e-9 {
        return "0".into();
    }
    // Ticks are at least about span / 20 apart.
    let step_exp = (span / 20.0).log10().floor() as i32;
    let max_abs = lo.abs().max(hi.abs());
    let trim = |s: &str| {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s.to_string()
        }
    };
    if (1e-3..1e5).contains(&max_abs) {
        let decimals = (-step_exp).clamp(0, 12) as usize;
        trim(&format!("{v:.decimals$}"))
    } else {
        let exp = v.abs().log10().floor() as i32;
        let decimals = exp.saturating_sub(step_exp).clamp(0, 6) as usize;
        let s = format!("{v:.decimals$e}");
        match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", trim(m)),
            None => s,
        }
    }
}

type DrawResult<DB> =
    std::result::Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;
type Chart2d<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

fn draw_corner<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    d: &CornerData,
) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let lay = d.layout;
    let (title, grid) = root.split_vertically(TITLE_H);
    let (w, _) = title.dim_in_pixel();
    title.draw(&Text::new(
        d.title(),
        ((LEFT + (w - LEFT) / 2) as i32, 8),
        (FONT, 18)
            .into_font()
            .color(&BLACK.mix(0.8))
            .pos(Pos::new(HPos::Center, VPos::Top)),
    ))?;
    // One count per column, so that the grid lines of a column line up.
    let x_ticks = d
        .ranges
        .iter()
        .enumerate()
        .map(|(col, &r)| x_tick_count(root, &lay, col, r))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    // One font size for all names, the largest at which the longest one fits.
    let fitted = d
        .names
        .iter()
        .map(|s| fit_text(root, s, lay.inner()))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let name_font = fitted.iter().map(|(_, f)| *f).min().unwrap_or(TICK_FONT);
    let names: Vec<String> = fitted.into_iter().map(|(s, _)| s).collect();
    let style = PanelStyle {
        x_ticks,
        names,
        name_font,
    };
    let n = lay.n as usize;
    let xs: Vec<i32> = (1..lay.n).map(|k| (LEFT + k * lay.panel) as i32).collect();
    let ys: Vec<i32> = (1..lay.n).map(|k| (k * lay.panel) as i32).collect();
    let cells = grid.split_by_breakpoints(xs, ys);
    for row in 0..n {
        for col in 0..=row {
            let cell = &cells[row * n + col];
            if row == col {
                draw_histogram(cell, d, &style, col)?;
            } else {
                draw_scatter(cell, d, &style, row, col)?;
            }
        }
    }
    Ok(())
}

/// The tick labels plotters will put on an axis over `range` when asked for `count` labels:
/// each key point with its label, blank when the label would stick out more than `before` pixels
/// before the start (left or top) of the axis or `after` pixels past its end. The labels are
/// measured here because the backend is busy while plotters calls the label formatter.
fn tick_labels<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    lay: &Layout,
    (lo, hi): (f64, f64),
    count: usize,
    before: f64,
    after: f64,
    vertical: bool,
) -> std::result::Result<Vec<(f64, String)>, DrawingAreaErrorKind<DB::ErrorType>> {
    let font = (FONT, lay.tick_font()).into_text_style(area);
    let len = lay.inner() as f64;
    RangedCoordf64::from(lo..hi)
        .key_points(count)
        .into_iter()
        .map(|v| {
            let text = tick_label(v, lo, hi);
            let (w, h) = area.estimate_text_size(&text, &font)?;
            let half = 0.5 * if vertical { h } else { w } as f64;
            // Pixels from the start of the axis: left for x, top for y.
            let pos = len * if vertical { hi - v } else { v - lo } / (hi - lo);
            let fits = pos - half >= -before && pos + half <= len + after;
            Ok((v, if fits { text } else { String::new() }))
        })
        .collect()
}

/// What the panels share beyond the data.
struct PanelStyle {
    /// Per column, the number of x tick labels.
    x_ticks: Vec<usize>,
    /// The parameter names, shortened where they would not fit.
    names: Vec<String>,
    name_font: u32,
}

/// The largest number of x tick labels (up to [`Layout::ticks`], at least 2) for column `col`
/// over `range` whose visible labels (see [`tick_labels`]) keep at least 4 px apart.
fn x_tick_count<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    lay: &Layout,
    col: usize,
    range: (f64, f64),
) -> std::result::Result<usize, DrawingAreaErrorKind<DB::ErrorType>> {
    let font = (FONT, lay.tick_font()).into_text_style(area);
    let px = lay.inner() as f64 / (range.1 - range.0);
    let (before, after) = x_overhang(lay, col);
    for k in (3..=lay.ticks()).rev() {
        let mut right = f64::NEG_INFINITY;
        let mut fits = true;
        for (v, text) in tick_labels(area, lay, range, k, before, after, false)? {
            if text.is_empty() {
                continue;
            }
            let (w, _) = area.estimate_text_size(&text, &font)?;
            let centre = (v - range.0) * px;
            fits &= centre - w as f64 / 2.0 >= right + 4.0;
            right = centre + w as f64 / 2.0;
        }
        if fits {
            return Ok(k);
        }
    }
    Ok(2)
}

/// How far (pixels) the x tick labels of column `col` may stick out left and right of the
/// plotting area: 2 px where a neighbouring panel's labels sit, any amount at the figure's edges.
fn x_overhang(lay: &Layout, col: usize) -> (f64, f64) {
    let free = |shared: bool| if shared { 2.0 } else { f64::INFINITY };
    (free(col > 0), free(col + 1 < lay.n as usize))
}

/// The same for the y tick labels of row `row` above and below the plotting area (the first row
/// is a histogram without y labels).
fn y_overhang(lay: &Layout, row: usize) -> (f64, f64) {
    let free = |shared: bool| if shared { 2.0 } else { f64::INFINITY };
    (free(row > 1), free(row + 1 < lay.n as usize))
}

/// The chart of the panel in `row`, `col` over x range `x` and y range `y`, with its mesh: tick
/// labels and the parameter name below the last row and left of the first column only.
fn panel<'a, DB: DrawingBackend>(
    cell: &'a DrawingArea<DB, Shift>,
    d: &CornerData,
    style: &PanelStyle,
    (row, col): (usize, usize),
    x: (f64, f64),
    y: (f64, f64),
) -> std::result::Result<Chart2d<'a, DB>, DrawingAreaErrorKind<DB::ErrorType>> {
    let lay = d.layout;
    let last = lay.n as usize - 1;
    let hist = row == col;
    let mut b = ChartBuilder::on(cell);
    b.margin(GAP);
    if col == 0 {
        b.y_label_area_size(LEFT);
    }
    if row == last {
        b.x_label_area_size(BOTTOM).margin_bottom(GAP + BELOW);
    }
    if col == last {
        b.margin_right(GAP + RIGHT);
    }
    let mut chart = b.build_cartesian_2d(x.0..x.1, y.0..y.1)?;

    // Tick labels may not reach into a neighbouring panel's labels: those that would stick out
    // more than 2 px past a shared panel edge are left out.
    let (before, after) = x_overhang(&lay, col);
    let x_labels = tick_labels(cell, &lay, x, style.x_ticks[col], before, after, false)?;
    let (before, after) = y_overhang(&lay, row);
    let y_labels = tick_labels(cell, &lay, y, lay.ticks(), before, after, true)?;
    let find = |labels: &[(f64, String)], v: f64, (lo, hi): (f64, f64)| {
        labels
            .iter()
            .find(|(k, _)| *k == v)
            .map_or_else(|| tick_label(v, lo, hi), |(_, l)| l.clone())
    };
    let x_fmt = |v: &f64| find(&x_labels, *v, x);
    let y_fmt = |v: &f64| find(&y_labels, *v, y);
    let mut mesh = chart.configure_mesh();
    mesh.x_labels(style.x_ticks[col])
        .y_labels(lay.ticks())
        .max_light_lines(0)
        .bold_line_style(BLACK.mix(0.08))
        .axis_style(BLACK.mix(0.6))
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style((FONT, lay.tick_font()))
        .axis_desc_style((FONT, style.name_font));
    if row == last {
        mesh.x_desc(&style.names[col]);
    } else {
        mesh.disable_x_axis();
    }
    // The histograms' counts are labelled only when there is nothing else in the first column.
    if col == 0 && !hist {
        mesh.y_desc(&style.names[row]);
    } else if col == 0 && last == 0 {
        mesh.y_desc("count");
    } else {
        mesh.disable_y_axis();
    }
    if hist {
        mesh.disable_y_mesh();
    }
    mesh.draw()?;

    // A frame around every plotting area, the inner ones included.
    let area = chart.plotting_area().strip_coord_spec();
    let (w, h) = area.dim_in_pixel();
    area.draw(&Rectangle::new(
        [(0, 0), (w as i32 - 1, h as i32 - 1)],
        BLACK.mix(0.6).stroke_width(1),
    ))?;
    Ok(chart)
}

/// The largest font size from 20 down to 15 (12.1 px in SVG) at which `text` fits into `max` pixels, with the
/// text itself, shortened with an ellipsis when it does not fit even at 12 px.
fn fit_text<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    max: u32,
) -> std::result::Result<(String, u32), DrawingAreaErrorKind<DB::ErrorType>> {
    const SIZES: std::ops::RangeInclusive<u32> = TICK_FONT..=20;
    let fits = |t: &str, size: u32| {
        let style = (FONT, size).into_text_style(area);
        area.estimate_text_size(t, &style).map(|(w, _)| w <= max)
    };
    for size in SIZES.rev() {
        if fits(text, size)? {
            return Ok((text.to_string(), size));
        }
    }
    let chars: Vec<char> = text.chars().collect();
    for keep in (1..chars.len()).rev() {
        let short = format!("{}…", chars[..keep].iter().collect::<String>().trim_end());
        if fits(&short, *SIZES.start())? {
            return Ok((short, *SIZES.start()));
        }
    }
    Ok(("…".into(), *SIZES.start()))
}

fn draw_histogram<DB: DrawingBackend>(
    cell: &DrawingArea<DB, Shift>,
    d: &CornerData,
    style: &PanelStyle,
    j: usize,
) -> DrawResult<DB> {
    let (lo, width, counts) = d.histogram(j);
    let max = counts.iter().copied().max().unwrap_or(0).max(1) as f64;
    let chart = panel(cell, d, style, (j, j), d.ranges[j], (0.0, max * 1.08))?;
    let area = chart.plotting_area();
    let edge = |i: usize| lo + width * i as f64;
    for (i, &c) in counts.iter().enumerate().filter(|(_, &c)| c > 0) {
        area.draw(&Rectangle::new(
            [(edge(i), 0.0), (edge(i + 1), c as f64)],
            DOT.mix(0.55).filled(),
        ))?;
        area.draw(&Rectangle::new(
            [(edge(i), 0.0), (edge(i + 1), c as f64)],
            DOT.stroke_width(1),
        ))?;
    }
    if let Some(m) = d.mark(j) {
        area.draw(&PathElement::new(
            [(m, 0.0), (m, max * 1.08)],
            MARK.stroke_width(2),
        ))?;
    }
    Ok(())
}

fn draw_scatter<DB: DrawingBackend>(
    cell: &DrawingArea<DB, Shift>,
    d: &CornerData,
    style: &PanelStyle,
    row: usize,
    col: usize,
) -> DrawResult<DB> {
    let (x, y) = (d.ranges[col], d.ranges[row]);
    let chart = panel(cell, d, style, (row, col), x, y)?;
    let (xs, ys) = (&d.columns[col], &d.columns[row]);
    let points: Vec<(f64, f64)> = d
        .shown
        .iter()
        .map(|&k| (xs[k], ys[k]))
        .filter(|(a, b)| (x.0..=x.1).contains(a) && (y.0..=y.1).contains(b))
        .collect();
    // Fewer points are drawn bigger and more opaque.
    let m = points.len().max(1) as f64;
    let alpha = (15.0 / m.sqrt()).clamp(0.25, 0.8);
    let radius = if m > 1000.0 { 1 } else { 2 };
    let style = DOT.mix(alpha).filled();
    let mut chart = chart;
    chart.draw_series(points.into_iter().map(|p| Circle::new(p, radius, style)))?;
    let area = chart.plotting_area();
    if let (Some(mx), Some(my)) = (d.mark(col), d.mark(row)) {
        area.draw(&Cross::new((mx, my), 6, WHITE.stroke_width(5)))?;
        area.draw(&Cross::new((mx, my), 6, MARK.stroke_width(2)))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::StandardNormal;

    /// Mean and standard deviation of each test parameter: magnitudes from 1e-4 to 1e7, so that
    /// some axes need scientific notation.
    const PARAMS: [(&str, f64, f64); 6] = [
        ("sliding friction", 0.5, 0.08),
        ("Young's modulus / Pa", 2.5e7, 4e6),
        ("restitution", 0.3, 0.05),
        ("rolling friction / m", 1e-4, 2e-5),
        ("density / kg m⁻³", 2600.0, 150.0),
        ("cohesion energy / J m⁻³", 40.0, 12.0),
    ];

    fn names(n: usize) -> Vec<String> {
        (0..n)
            .map(|j| PARAMS[j % PARAMS.len()].0.to_string())
            .collect()
    }

    /// `count` correlated Gaussian points: each coordinate is 0.7 times the previous one plus
    /// independent noise (in standard units), then scaled to the parameter's mean and spread.
    fn gaussian(n: usize, count: usize, seed: u64) -> Vec<Vec<f64>> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..count)
            .map(|_| {
                let mut prev = 0.0;
                (0..n)
                    .map(|j| {
                        let z: f64 = rng.sample(StandardNormal);
                        prev = if j == 0 {
                            z
                        } else {
                            0.7 * prev + 0.51f64.sqrt() * z
                        };
                        let (_, mean, sd) = PARAMS[j % PARAMS.len()];
                        mean + sd * prev
                    })
                    .collect()
            })
            .collect()
    }

    fn means(n: usize) -> Vec<f64> {
        (0..n).map(|j| PARAMS[j % PARAMS.len()].1).collect()
    }

    fn assert_written(path: &Path) {
        let len = std::fs::metadata(path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
            .len();
        assert!(len > 0, "{} is empty", path.display());
    }

    fn err(
        names: &[String],
        samples: &[Vec<f64>],
        marks: Option<&[f64]>,
        ranges: Option<&[(f64, f64)]>,
    ) -> String {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("c.svg");
        let e = corner(&p, names, samples, marks, ranges)
            .unwrap_err()
            .to_string();
        assert!(!p.exists(), "{e}");
        assert!(e.contains("c.svg: corner plot: "), "{e}");
        e
    }

    #[test]
    fn parameter_symbols_readable_ticks_and_a_key_for_the_marks() {
        let dir = tempfile::tempdir().unwrap();
        let names: Vec<String> = ["mu_pp", "mu_r_pp", "sigma"].map(String::from).to_vec();
        let samples: Vec<Vec<f64>> = gaussian(3, 500, 7)
            .into_iter()
            .map(|s| vec![s[0], s[2], s[2].abs()])
            .collect();
        let best = [0.5, 0.3, 0.1];
        let p = dir.path().join("post.svg");
        corner_keyed(&p, &names, &samples, Some((&best, "best optimum")), None).unwrap();
        let svg = std::fs::read_to_string(&p).unwrap();
        for text in [
            "μ_pp",
            "μ_r,pp",
            "σ (model error)",
            "red lines and crosses: best optimum",
        ] {
            assert!(svg.contains(text), "no \"{text}\"");
        }
        assert!(!svg.contains("mu_pp") && !svg.contains("mu_r_pp"));
        crate::plot::test_util::assert_fonts_at_least(&svg, 12.0);
        // Without marks there is nothing to explain.
        corner_keyed(&p, &names, &samples, None, None).unwrap();
        assert!(!std::fs::read_to_string(&p).unwrap().contains("red lines"));
    }

    #[test]
    fn writes_svg_and_png_for_1_2_and_5_parameters() {
        let dir = tempfile::tempdir().unwrap();
        for n in [1, 2, 5] {
            let names = names(n);
            let samples = gaussian(n, 4000, n as u64);
            let marks = means(n);
            for ext in ["svg", "png"] {
                let p = dir.path().join(format!("sub/corner{n}.{ext}"));
                corner(&p, &names, &samples, Some(&marks), None).unwrap();
                assert_written(&p);
                let p = dir.path().join(format!("plain{n}.{ext}"));
                corner(&p, &names, &samples, None, None).unwrap();
                assert_written(&p);
            }
            let svg =
                std::fs::read_to_string(dir.path().join(format!("sub/corner{n}.svg"))).unwrap();
            for name in &names {
                assert!(
                    svg.contains(&name.replace('\'', "&apos;")) || svg.contains(name),
                    "{name}"
                );
            }
            assert!(svg.contains("4000 samples"));
            if n == 1 {
                assert!(svg.contains("count"));
            } else {
                assert!(!svg.contains(">count<"));
            }
        }
        // Large magnitudes get scientific tick labels.
        let svg = std::fs::read_to_string(dir.path().join("sub/corner5.svg")).unwrap();
        assert!(svg.contains("\n2.5e7\n"), "no scientific tick label");
    }

    #[test]
    fn twelve_parameters_with_prior_ranges() {
        let dir = tempfile::tempdir().unwrap();
        let n = 12;
        let samples = gaussian(n, 1500, 12);
        let ranges: Vec<(f64, f64)> = (0..n)
            .map(|j| {
                let (_, m, sd) = PARAMS[j % PARAMS.len()];
                (m - 4.0 * sd, m + 4.0 * sd)
            })
            .collect();
        for ext in ["svg", "png"] {
            let p = dir.path().join(format!("c12.{ext}"));
            corner(&p, &names(n), &samples, Some(&means(n)), Some(&ranges)).unwrap();
            assert_written(&p);
        }
        let (w, h) = Layout::new(n).size();
        assert!(w >= n as u32 * 200 && h >= n as u32 * 200, "{w} x {h}");
    }

    #[test]
    fn long_names_are_shortened() {
        let dir = tempfile::tempdir().unwrap();
        let long = "a very long parameter name with its unit that cannot fit / kg m s⁻²";
        let names = vec![long.to_string(), "b".to_string(), "c".to_string()];
        // Awkward magnitudes: negative, tiny spans around large and small values.
        let samples: Vec<Vec<f64>> = gaussian(3, 500, 5)
            .into_iter()
            .map(|s| {
                vec![
                    -1.234e-5 + 1e-6 * s[0],
                    12345.6 + 1e-9 * s[1],
                    -0.0123 + 0.01 * s[2],
                ]
            })
            .collect();
        for ext in ["svg", "png"] {
            let p = dir.path().join(format!("long.{ext}"));
            corner(&p, &names, &samples, None, None).unwrap();
            assert_written(&p);
        }
        let svg = std::fs::read_to_string(dir.path().join("long.svg")).unwrap();
        assert!(
            svg.contains("a very long parameter"),
            "shortened name kept its start"
        );
        assert!(svg.contains('…'), "no ellipsis");
        assert!(!svg.contains("cannot fit / kg"), "name not shortened");
    }

    #[test]
    fn most_parameters() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("max.png");
        corner(
            &p,
            &names(MAX_PARAMS),
            &gaussian(MAX_PARAMS, 40, 2),
            None,
            None,
        )
        .unwrap();
        assert_written(&p);
    }

    #[test]
    fn scatter_is_thinned() {
        let dir = tempfile::tempdir().unwrap();
        let samples = gaussian(2, 20_000, 7);
        let p = dir.path().join("thin.svg");
        corner(&p, &names(2), &samples, None, None).unwrap();
        let svg = std::fs::read_to_string(&p).unwrap();
        let circles = svg.matches("<circle").count();
        assert!((2000..=MAX_SCATTER).contains(&circles), "{circles} circles");
        assert!(svg.contains("show 2858 of them (every 7th)"), "title");
    }

    #[test]
    fn figure_size_follows_the_parameter_count() {
        assert_eq!(Layout::new(1).size().0, MIN_SIDE);
        assert_eq!(Layout::new(2).size().0, LEFT + 2 * PANEL + RIGHT);
        let (w5, h5) = Layout::new(5).size();
        assert_eq!(w5, LEFT + 5 * PANEL + RIGHT);
        assert!(h5 > 5 * PANEL);
        assert!(Layout::new(12).size().0 <= MAX_SIDE);
        // Many parameters shrink the panels down to a floor.
        assert_eq!(Layout::new(40).panel, 97);
        assert_eq!(Layout::new(200).panel, MIN_PANEL);
    }

    #[test]
    fn input_errors() {
        let names2 = names(2);
        let good = gaussian(2, 50, 1);
        let e = err(&[], &good, None, None);
        assert!(e.contains("no parameter names"), "{e}");
        let e = err(&names2, &[], None, None);
        assert!(e.contains("no samples"), "{e}");
        let mut bad = good.clone();
        bad[3].push(1.0);
        let e = err(&names2, &bad, None, None);
        assert!(
            e.contains("sample 3 has 3 coordinates but 2 parameter names"),
            "{e}"
        );
        let e = err(&names2, &good, Some(&[1.0]), None);
        assert!(e.contains("1 marks given for 2 parameters"), "{e}");
        let e = err(&names2, &good, None, Some(&[(0.0, 1.0); 3]));
        assert!(e.contains("3 ranges given for 2 parameters"), "{e}");
        let e = err(&names2, &good, None, Some(&[(0.0, 1.0), (2.0, 1.0)]));
        assert!(e.contains("range 2..1 of \"Young's modulus / Pa\""), "{e}");
        let e = err(&names2, &good, None, Some(&[(0.0, f64::NAN), (0.0, 1.0)]));
        assert!(e.contains("expected finite bounds"), "{e}");
        let e = err(
            &names2,
            &good,
            None,
            Some(&[(-f64::MAX, f64::MAX), (0.0, 1.0)]),
        );
        assert!(e.contains("too wide"), "{e}");
        let nan = vec![vec![f64::NAN, 1.0], vec![2.0, f64::INFINITY]];
        let e = err(&names2, &nan, None, None);
        assert!(
            e.contains("none of the 2 samples has only finite coordinates"),
            "{e}"
        );
        let huge = vec![vec![f64::MAX, 1.0], vec![-f64::MAX, 2.0]];
        let e = err(&names2, &huge, None, None);
        assert!(e.contains("\"sliding friction\" (from"), "{e}");
        assert!(e.contains("too large or too far apart"), "{e}");
        let e = err(
            &names2,
            &good,
            None,
            Some(&[(f64::MAX, f64::MAX), (0.0, 1.0)]),
        );
        assert!(e.contains("too wide"), "{e}");
        let many = names(MAX_PARAMS + 1);
        let e = err(&many, &gaussian(MAX_PARAMS + 1, 3, 1), None, None);
        assert!(e.contains("65 parameters are too many"), "{e}");
        // A bad extension is the figure helpers' error.
        let dir = tempfile::tempdir().unwrap();
        assert!(corner(&dir.path().join("c.pdf"), &names2, &good, None, None).is_err());
    }

    #[test]
    fn non_finite_samples_are_skipped() {
        let dir = tempfile::tempdir().unwrap();
        let mut samples = gaussian(3, 200, 3);
        samples[5][1] = f64::NAN;
        samples[9][0] = f64::NEG_INFINITY;
        // A non-finite mark leaves its parameter unmarked.
        let marks = [0.5, f64::NAN, 0.3];
        for ext in ["svg", "png"] {
            let p = dir.path().join(format!("skip.{ext}"));
            corner(&p, &names(3), &samples, Some(&marks), None).unwrap();
            assert_written(&p);
        }
        let svg = std::fs::read_to_string(dir.path().join("skip.svg")).unwrap();
        assert!(svg.contains("200 samples, 2 with non-finite coordinates skipped"));
    }

    #[test]
    fn constant_parameters_and_single_samples() {
        let dir = tempfile::tempdir().unwrap();
        let mut samples = gaussian(3, 300, 4);
        for s in &mut samples {
            s[1] = 7.0e6;
            s[2] = 0.0;
        }
        let mut names = names(3);
        names[2] = " ".into();
        for ext in ["svg", "png"] {
            let p = dir.path().join(format!("const.{ext}"));
            corner(&p, &names, &samples, Some(&[0.5, 7.0e6, 0.0]), None).unwrap();
            assert_written(&p);
            let p = dir.path().join(format!("one.{ext}"));
            corner(&p, &names, &samples[..1], None, None).unwrap();
            assert_written(&p);
            let p = dir.path().join(format!("one1.{ext}"));
            corner(&p, &names[..1], &[vec![3.0]], Some(&[3.0]), None).unwrap();
            assert_written(&p);
            // A degenerate prior box is widened like a constant parameter.
            let p = dir.path().join(format!("box.{ext}"));
            let ranges = [(0.0, 1.0), (7.0e6, 7.0e6), (-1.0, 1.0)];
            corner(&p, &names, &samples, None, Some(&ranges)).unwrap();
            assert_written(&p);
        }
        let svg = std::fs::read_to_string(dir.path().join("const.svg")).unwrap();
        assert!(svg.contains("parameter 3"), "blank name replaced");
    }

    #[test]
    fn ranges_and_helpers() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(quantile_sorted(&v, 0.0), 1.0);
        assert_eq!(quantile_sorted(&v, 0.5), 3.0);
        assert!((quantile_sorted(&v, 0.01) - 1.04).abs() < 1e-12);
        assert!(quantile_sorted(&[], 0.5).is_nan());

        // 1 %-99 % quantiles widened by 5 %: one outlier does not stretch the panel.
        let mut values: Vec<f64> = (0..=100).map(f64::from).collect();
        values.push(1e6);
        let (lo, hi) = auto_range(&values).unwrap();
        assert!(
            lo < 1.02 && lo > -5.0 && hi > 99.0 && hi < 110.0,
            "{lo}..{hi}"
        );
        // Coinciding quantiles fall back to the full range; constant values get a span.
        let mut mostly: Vec<f64> = vec![1.0; 200];
        mostly.push(2.0);
        let (lo, hi) = auto_range(&mostly).unwrap();
        assert!(lo < 1.0 && hi > 2.0, "{lo}..{hi}");
        for c in [0.0, 3.0, -2e9] {
            let (lo, hi) = auto_range(&[c; 5]).unwrap();
            assert!(lo < c && c < hi && hi - lo > 0.0, "{c}: {lo}..{hi}");
        }
        assert!(auto_range(&[f64::MAX, -f64::MAX]).is_none());
        assert_eq!(ordinal(2), "2nd");
        assert_eq!(ordinal(12), "12th");
        assert_eq!(ordinal(23), "23rd");
        assert_eq!(checked_span(1.0, 2.0), Some((1.0, 2.0)));
        assert_eq!(checked_span(0.0, 0.0), Some((-0.5, 0.5)));
        assert_eq!(checked_span(2.0, 2.0), Some((1.8, 2.2)));
        assert_eq!(checked_span(0.0, 5e-324), Some((-0.5, 0.5)));
        assert!(checked_span(f64::MAX, f64::MAX).is_none());
        assert!(checked_span(-f64::MAX, f64::MAX).is_none());
        assert_eq!(quantile_sorted(&[-f64::MAX, f64::MAX], 0.5), 0.0);

        assert_eq!(tick_label(-1.4e-17, -0.55, 0.55), "0");
        assert_eq!(tick_label(-0.5, -0.55, 0.55), "-0.5");
        assert_eq!(tick_label(24.0, 23.0, 41.0), "24");
        assert_eq!(tick_label(0.0015, -0.002, 0.004), "0.0015");
        assert_eq!(tick_label(2.5e7, 1.0e7, 4.0e7), "2.5e7");
        assert_eq!(tick_label(1.02e9, 0.9e9, 1.1e9), "1.02e9");
        assert_eq!(tick_label(5e-5, 0.0, 2.0e-4), "5e-5");
        assert_eq!(tick_label(1.5e-4, 0.0, 2.0e-4), "1.5e-4");
    }
}
