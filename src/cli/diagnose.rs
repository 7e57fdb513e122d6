//! `mbgc diagnose`: compare a measurement set with the model, show where it fails, rank the
//! candidate missing effects, and (with a model of the extended class) the error ladder.

use std::path::PathBuf;

use clap::Args;

use crate::cli::output::Output;
use crate::diagnose::{diagnose, Diagnosis, MeasurementSet, Options, Surrogate};
use crate::say;

#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    /// Measurement set: several samples of one material (see `docs/diagnose.md`).
    #[arg(long)]
    pub measurements: PathBuf,
    /// Metamodels: one of the set's class, and models of classes with a candidate effect (a
    /// model of a richer class also serves the poorer one, with the extra effect off).
    #[arg(long, default_values = ["models/shear_box.json"])]
    pub model: Vec<PathBuf>,
    /// L-BFGS starts of each joint fit.
    #[arg(long, default_value_t = 16)]
    pub starts: usize,
    /// TMCMC samples per stage (evidences and posterior intervals).
    #[arg(long, default_value_t = 2000)]
    pub samples: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Family-wise significance level of the chi^2 test and the residual-structure tests.
    #[arg(long, default_value_t = 0.01)]
    pub alpha: f64,
    /// Directory for the figures (parity, residual against d50, error ladder).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Standard output holds one JSON object; text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: &DiagnoseArgs) -> anyhow::Result<()> {
    if !(a.alpha > 0.0 && a.alpha < 1.0) {
        anyhow::bail!("--alpha: expected a level between 0 and 1, got {}", a.alpha);
    }
    if a.samples < 100 {
        anyhow::bail!(
            "--samples: expected at least 100 TMCMC samples per stage, got {}",
            a.samples
        );
    }
    if a.starts == 0 {
        anyhow::bail!("--starts: expected at least 1");
    }
    let out = Output::new(a.json);
    let set = MeasurementSet::from_file(&a.measurements)?;
    let models = a
        .model
        .iter()
        .map(|p| Surrogate::from_metamodel(p))
        .collect::<crate::error::Result<Vec<_>>>()?;
    let opts = Options {
        starts: a.starts,
        samples: a.samples,
        seed: a.seed,
        alpha: a.alpha,
    };
    let d = diagnose(&set, &models, &opts)?;
    report(&out, &d);
    if let Some(dir) = &a.plot {
        for f in figures(&d, dir)? {
            say!(out, "figure: {}", f.display());
        }
    }
    out.object(&json(&d))?;
    Ok(())
}

/// The JSON report: the keys first (`chi2_dof`, `residuals`, `ranking`), then the rest.
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

fn num(v: f64) -> String {
    if !v.is_finite() {
        "-".into()
    } else if v != 0.0 && !(1e-3..1e5).contains(&v.abs()) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

pub fn report(out: &Output, d: &Diagnosis) {
    let b = &d.base;
    say!(
        out,
        "{}: {} measurements, class {}",
        d.set,
        d.measurements,
        d.class
    );
    for m in &b.models {
        say!(out, "  {m}");
    }
    say!(
        out,
        "\nJoint calibration: chi^2 = {:.2} on {} degrees of freedom, chi^2/dof = {}, p = {}",
        b.chi2,
        b.dof,
        num(b.chi2_dof),
        num(b.p_value)
    );
    say!(
        out,
        "| parameter | best | posterior mean | 90 % interval |\n|---|---|---|---|"
    );
    for p in &b.parameters {
        say!(
            out,
            "| {} | {} | {} | [{}, {}] |",
            p.name,
            num(p.best),
            num(p.posterior_mean),
            num(p.q05),
            num(p.q95)
        );
    }
    say!(
        out,
        "\nResiduals (z = (measured - predicted) / sigma, sigma = sd and model error together):"
    );
    say!(
        out,
        "| sample | response | measured | predicted | sigma | z |\n|---|---|---|---|---|---|"
    );
    for r in &b.residuals {
        say!(
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
    say!(
        out,
        "\nStructure (two-sided z-tests; significant at family-wise {}: *):",
        d.settings.alpha
    );
    say!(
        out,
        "| test | of | against | estimate | se | p |\n|---|---|---|---|---|---|"
    );
    for t in &b.structure {
        let star = if b.structured.contains(t) { " *" } else { "" };
        say!(
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
    say!(out, "\nCandidate effects, best first:");
    say!(
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
        say!(
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
        say!(
            out,
            "| {} | not evaluated: {} | | | | | |",
            u.effect,
            u.reason
        );
    }
    say!(
        out,
        "\nError ladder (RMS of z per sample; RMSE per response):"
    );
    let mut head = String::from("| class | chi^2/dof |");
    for s in &b.samples {
        head += &format!(" {} |", s.sample);
    }
    for r in &b.rmse {
        head += &format!(" RMSE {} |", r.response);
    }
    say!(
        out,
        "{head}\n|{}",
        "---|".repeat(2 + b.samples.len() + b.rmse.len())
    );
    for c in std::iter::once(b).chain(&d.extended) {
        let mut row = format!("| {} | {} |", c.class, num(c.chi2_dof));
        for s in &c.samples {
            row += &format!(" {:.2} |", s.rms_z);
        }
        for r in &c.rmse {
            row += &format!(" {} |", num(r.rmse));
        }
        say!(out, "{row}");
    }
    say!(out, "\nVerdict: {}", d.verdict);
}

/// Parity per response, residuals against d50 per response, the ladder; base and the best
/// candidate.
pub fn figures(d: &Diagnosis, dir: &std::path::Path) -> anyhow::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)?;
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
    let all: Vec<&crate::diagnose::diagnosis::ClassFit> =
        std::iter::once(&d.base).chain(&d.extended).collect();
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
