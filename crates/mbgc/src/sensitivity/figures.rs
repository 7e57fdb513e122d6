//! Figures of the sensitivity results: exponent bars with intervals, PCA loadings and the norm
//! shares of the sensitivity matrix, Sobol indices.

use std::path::Path;

use super::norms::NormSummary;
use super::pca::Pca;
use super::power_law;
use super::sobol::Index;
use crate::plot::sensitivity::{bars, Bar, BarSeries};

/// Bars of a power law's exponents with their intervals.
pub fn exponent_bars(
    path: &Path,
    name: &str,
    fit: &power_law::PowerLawFit,
) -> crate::error::Result<()> {
    let cats: Vec<String> = fit.exponents.iter().map(|(n, _)| n.clone()).collect();
    let s = BarSeries {
        label: name.to_string(),
        bars: fit
            .exponents
            .iter()
            .map(|(_, e)| Bar {
                value: e.value,
                ci95: Some(e.ci95),
            })
            .collect(),
    };
    bars(
        path,
        &format!("{name}: power-law exponents, 95 % intervals"),
        "exponent",
        &cats,
        &[s],
    )
}

/// Loadings of the components that explain at least 5 % (at most 3), one series each.
pub fn loading_bars(path: &Path, title: &str, p: &Pca) -> crate::error::Result<()> {
    let series: Vec<BarSeries> = p
        .components
        .iter()
        .enumerate()
        .filter(|(_, c)| c.explained >= 0.05)
        .take(3)
        .map(|(i, c)| BarSeries {
            label: format!("PC{} ({:.0} %)", i + 1, 100.0 * c.explained),
            bars: c
                .loadings
                .iter()
                .map(|(_, v)| Bar {
                    value: *v,
                    ci95: None,
                })
                .collect(),
        })
        .collect();
    bars(path, title, "loading", &p.columns, &series)
}

/// The norm shares of each labelled summary, one series each, over the parameters `names`.
pub fn share_bars(
    path: &Path,
    title: &str,
    y_label: &str,
    names: &[String],
    summaries: &[(String, &NormSummary)],
) -> crate::error::Result<()> {
    let series: Vec<BarSeries> = summaries
        .iter()
        .map(|(label, s)| BarSeries {
            label: label.clone(),
            bars: s
                .shares
                .iter()
                .map(|v| Bar {
                    value: *v,
                    ci95: None,
                })
                .collect(),
        })
        .collect();
    bars(path, title, y_label, names, &series)
}

/// First-order and total Sobol indices of one response, with their intervals, over `names`.
pub fn sobol_bars(
    path: &Path,
    title: &str,
    names: &[String],
    idx: &[Index],
) -> crate::error::Result<()> {
    let series = |label: &str, pick: fn(&Index) -> (f64, [f64; 2])| BarSeries {
        label: label.into(),
        bars: idx
            .iter()
            .map(|x| {
                let (value, ci) = pick(x);
                Bar {
                    value,
                    ci95: Some(ci),
                }
            })
            .collect(),
    };
    let s = [
        series("first order", |x| (x.first, x.first_ci95)),
        series("total", |x| (x.total, x.total_ci95)),
    ];
    bars(path, title, "index", names, &s)
}
