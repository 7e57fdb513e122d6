//! The diagnosis as a Markdown report (tables of the fit, the residuals, their structure, the
//! ranked candidates and the error ladder), as JSON, and its figures.

use std::path::{Path, PathBuf};

use super::diagnosis::{ClassFit, Diagnosis};
use crate::error::Result;

/// Appends one formatted line.
macro_rules! line {
    ($out:expr, $($arg:tt)*) => {{
        $out.push_str(&format!($($arg)*));
        $out.push('\n');
    }};
}

fn num(v: f64) -> String {
    if !v.is_finite() {
        "-".into()
    } else if v != 0.0 && !(1e-3..1e5).contains(&v.abs()) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

/// The report as Markdown (what `mbgc diagnose` prints).
pub fn markdown(d: &Diagnosis) -> String {
    let mut out = String::new();
    let b = &d.base;
    line!(
        out,
        "{}: {} measurements, class {}",
        d.set,
        d.measurements,
        d.class
    );
    for m in &b.notes {
        line!(out, "  {m}");
    }
    line!(
        out,
        "\nJoint calibration: chi^2 = {:.2} on {} degrees of freedom, chi^2/dof = {}, p = {}",
        b.chi2,
        b.dof,
        num(b.chi2_dof),
        num(b.p_value)
    );
    line!(
        out,
        "| parameter | best | posterior mean | 90 % interval |\n|---|---|---|---|"
    );
    for p in &b.parameters {
        line!(
            out,
            "| {} | {} | {} | [{}, {}] |",
            p.name,
            num(p.best),
            num(p.posterior_mean),
            num(p.q05),
            num(p.q95)
        );
    }
    line!(
        out,
        "\nResiduals (z = (measured - predicted) / sigma, sigma = sd and model error together):"
    );
    line!(
        out,
        "| sample | response | measured | predicted | sigma | z |\n|---|---|---|---|---|---|"
    );
    for r in &b.residuals {
        line!(
            out,
            "| {} | {} | {} | {} | {} | {:+.2} |",
            r.sample,
            r.response,
            num(r.measured),
            num(r.predicted),
            num(r.sigma),
            r.z
        );
    }
    line!(
        out,
        "\nStructure (two-sided z-tests; significant at family-wise {}: *):",
        d.settings.alpha
    );
    line!(
        out,
        "| test | of | against | estimate | se | p |\n|---|---|---|---|---|---|"
    );
    for t in &b.structure {
        let star = if b.structured.contains(t) { " *" } else { "" };
        line!(
            out,
            "| {} | {} | {} | {:+.3} | {:.3} | {}{star} |",
            t.kind,
            t.of,
            t.against.as_deref().unwrap_or("-"),
            t.estimate,
            t.se,
            num(t.p)
        );
    }
    line!(out, "\nCandidate effects, best first:");
    line!(
        out,
        "| effect | chi^2/dof after | p after | ln Bayes factor | chi^2 ratio | structure left | strength (best, 90 % interval) |\n|---|---|---|---|---|---|---|"
    );
    for r in &d.ranking {
        let s: Vec<String> = r
            .strength
            .iter()
            .map(|p| {
                format!(
                    "{} = {} [{}, {}]",
                    p.name,
                    num(p.best),
                    num(p.q05),
                    num(p.q95)
                )
            })
            .collect();
        line!(
            out,
            "| {} | {} | {} | {:.2} | {:.2} | {} | {} |",
            r.effect,
            num(r.chi2_dof_after),
            num(r.p_value_after),
            r.log_bayes_factor,
            r.chi2_ratio,
            if r.structure_left { "yes" } else { "no" },
            s.join("; ")
        );
    }
    for u in &d.unavailable {
        line!(
            out,
            "| {} | not evaluated: {} | | | | | |",
            u.effect,
            u.reason
        );
    }
    line!(
        out,
        "\nError ladder (RMS of z per sample; RMSE per response):"
    );
    let mut head = String::from("| class | model | chi^2/dof |");
    for s in &b.samples {
        head += &format!(" {} |", s.sample);
    }
    for r in &b.rmse {
        head += &format!(" RMSE {} |", r.response);
    }
    line!(
        out,
        "{head}\n|{}",
        "---|".repeat(3 + b.samples.len() + b.rmse.len())
    );
    for c in std::iter::once(b).chain(&d.extended) {
        let mut row = format!(
            "| {} | {} | {} |",
            c.class,
            c.models.join(", "),
            num(c.chi2_dof)
        );
        for s in &c.samples {
            row += &format!(" {:.2} |", s.rms_z);
        }
        for r in &c.rmse {
            row += &format!(" {} |", num(r.rmse));
        }
        line!(out, "{row}");
    }
    limits(&mut out, std::iter::once(b).chain(d.extended.first()));
    line!(out, "\nVerdict: {}", d.verdict);
    out
}

/// The intervals beside those the measurements alone allow (every model exact), for the set's
/// class and the best candidate: whether a better model or more measurements would narrow them.
fn limits<'a>(out: &mut String, fits: impl Iterator<Item = &'a ClassFit>) {
    let mut rows = Vec::new();
    for c in fits {
        for p in &c.parameters {
            if let Some([lo, hi]) = p.exact_models {
                let ratio = (p.q95 - p.q05) / (hi - lo);
                rows.push(format!(
                    "| {} | {} | [{}, {}] | [{}, {}] | {} |",
                    c.class,
                    p.name,
                    num(p.q05),
                    num(p.q95),
                    num(lo),
                    num(hi),
                    if ratio.is_finite() {
                        format!("{ratio:.2}")
                    } else {
                        "-".into()
                    }
                ));
            }
        }
    }
    if rows.is_empty() {
        return;
    }
    line!(
        out,
        "\nWhat limits the intervals: the 90 % interval as fitted, and with every model's error \
         taken as zero (each value's sd alone). Only the widths compare: the second interval \
         still rests on the models' predictions, which miss. A width ratio well above 1: the \
         models limit the answer (more DEM runs would narrow it); near 1: the measurements do \
         (more or more precise measurements would), or nothing does where both intervals span \
         the searched range. An exact-model interval outside the fitted one is a sign of \
         misfit, not of precision."
    );
    line!(
        out,
        "| class | parameter | 90 % interval | with exact models | width ratio |\n|---|---|---|---|---|"
    );
    for r in rows {
        line!(out, "{r}");
    }
}

/// The report as JSON (what `mbgc diagnose --json` prints, less what the command adds about the
/// models it built): the keys an issue asks about first (`chi2_dof`, `residuals`, `ranking`),
/// then the rest.
pub fn json(d: &Diagnosis) -> serde_json::Value {
    serde_json::json!({
        "set": d.set,
        "class": d.class,
        "chi2_dof": d.chi2_dof,
        "p_value": d.p_value,
        "residuals": d.base.residuals,
        "structure": d.base.structure,
        "ranking": d.ranking,
        "unavailable": d.unavailable,
        "verdict": d.verdict,
        "base": d.base,
        "extended": d.extended,
        "settings": d.settings,
    })
}

/// Parity per response, residuals against d50 per response, the ladder; base and the best
/// candidate.
pub fn figures(d: &Diagnosis, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| crate::error::Error::io(dir, e))?;
    let mut classes = vec![&d.base];
    classes.extend(d.extended.first());
    let mut files = Vec::new();
    let mut responses: Vec<&str> = Vec::new();
    for r in &d.base.residuals {
        if !responses.contains(&r.response.as_str()) {
            responses.push(&r.response);
        }
    }
    let labels: Vec<String> = classes.iter().map(|c| c.class.replace(',', "+")).collect();
    for resp in &responses {
        let data: Vec<(Vec<f64>, Vec<f64>)> = classes
            .iter()
            .map(|c| {
                let rs: Vec<_> = c.residuals.iter().filter(|r| r.response == *resp).collect();
                (
                    rs.iter().map(|r| r.measured).collect(),
                    rs.iter().map(|r| r.predicted).collect(),
                )
            })
            .collect();
        let splits: Vec<crate::plot::parity::Split> = data
            .iter()
            .zip(&labels)
            .map(|((o, p), l)| crate::plot::parity::Split {
                label: l,
                observed: o,
                predicted: p,
            })
            .collect();
        let f = dir.join(format!("{resp}_parity.svg"));
        crate::plot::parity::parity(&f, resp, &splits)?;
        files.push(f);
        let series: Vec<crate::plot::diagnosis::Series> = classes
            .iter()
            .zip(&labels)
            .map(|(c, l)| crate::plot::diagnosis::Series {
                label: l,
                points: c
                    .residuals
                    .iter()
                    .zip(std::iter::repeat(()))
                    .filter(|(r, _)| r.response == *resp)
                    .filter_map(|(r, _)| {
                        c.samples
                            .iter()
                            .find(|s| s.sample == r.sample)
                            .and_then(|s| s.d50)
                            .map(|d| (d, r.z))
                    })
                    .collect(),
            })
            .collect();
        if series.iter().all(|s| !s.points.is_empty()) {
            let f = dir.join(format!("{resp}_residual_d50.svg"));
            crate::plot::diagnosis::residuals_against_d50(&f, resp, &series)?;
            files.push(f);
        }
    }
    let samples: Vec<String> = d.base.samples.iter().map(|s| s.sample.clone()).collect();
    let all: Vec<&ClassFit> = std::iter::once(&d.base).chain(&d.extended).collect();
    let labels: Vec<String> = all.iter().map(|c| c.class.replace(',', "+")).collect();
    let series: Vec<crate::plot::diagnosis::Series> = all
        .iter()
        .zip(&labels)
        .map(|(c, l)| crate::plot::diagnosis::Series {
            label: l,
            points: c
                .samples
                .iter()
                .enumerate()
                .map(|(k, s)| (k as f64, s.rms_z))
                .collect(),
        })
        .collect();
    let f = dir.join("ladder.svg");
    crate::plot::diagnosis::ladder(&f, &samples, &series)?;
    files.push(f);
    Ok(files)
}
