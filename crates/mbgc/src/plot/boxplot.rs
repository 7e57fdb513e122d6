//! Box plots of a metric per method, several panels side by side (sampling benchmark figure).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::draw_figure;
use crate::error::Result;

/// One panel of box plots: a metric (e.g. MID or COV) compared across groups (e.g. methods).
pub struct BoxPanel {
    /// Panel title.
    pub title: String,
    /// Label of the value axis, with the metric's unit if it has one.
    pub y_label: String,
    /// One box per group: label and values.
    pub groups: Vec<(String, Vec<f64>)>,
}

/// Draws the panels in a grid with `cols` columns.
pub fn boxplots(path: &Path, panels: &[BoxPanel], cols: usize) -> Result<()> {
    let rows = panels.len().div_ceil(cols.max(1));
    let size = (560 * cols as u32, 400 * rows as u32);
    draw_figure!(path, size, draw_panels(panels, cols))
}

fn draw_panels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panels: &[BoxPanel],
    cols: usize,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let rows = panels.len().div_ceil(cols.max(1));
    let areas = root.split_evenly((rows, cols));
    for (panel, area) in panels.iter().zip(areas.iter()) {
        draw_panel(area, panel)?;
    }
    Ok(())
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &BoxPanel,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let labels: Vec<String> = panel.groups.iter().map(|(l, _)| l.clone()).collect();
    // Whiskers reach 1.5 IQR beyond the quartiles, possibly past every value: include them.
    let all = panel.groups.iter().flat_map(|(_, v)| {
        let q = Quartiles::new(v).values();
        v.iter().copied().chain([q[0] as f64, q[4] as f64])
    });
    let (lo, hi) = all.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let pad = ((hi - lo) * 0.08).max(1e-6);
    let y_range = (lo - pad).max(0.0) as f32..(hi + pad) as f32;
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (super::FONT, 20))
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d(labels[..].into_segmented(), y_range)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .y_desc(&panel.y_label)
        .x_label_formatter(&|v| match v {
            SegmentValue::CenterOf(s) | SegmentValue::Exact(s) => s.to_string(),
            SegmentValue::Last => String::new(),
        })
        .label_style((super::FONT, super::TICK_FONT))
        .axis_desc_style((super::FONT, super::DESC_FONT))
        .draw()?;
    let blue = RGBColor(31, 119, 180);
    chart.draw_series(panel.groups.iter().zip(&labels).map(|((_, v), l)| {
        Boxplot::new_vertical(SegmentValue::CenterOf(l), &Quartiles::new(v))
            .width(24)
            .whisker_width(0.6)
            .style(blue)
    }))?;
    // The individual designs on top of the boxes: with ten seeds, the points say as much.
    chart.draw_series(panel.groups.iter().zip(&labels).flat_map(|((_, v), l)| {
        v.iter().map(move |&y| {
            Circle::new(
                (SegmentValue::CenterOf(l), y as f32),
                2,
                BLACK.mix(0.5).filled(),
            )
        })
    }))?;
    Ok(())
}
