//! `mbgc diagnose`: compare a measurement set with the model, show where it fails, rank the
//! candidate missing effects, and (with a model of the extended class) the error ladder.

use std::path::PathBuf;

use clap::Args;

use mbgc::diagnose::report::{figures, markdown};
use mbgc::diagnose::{diagnose, Diagnosis, MeasurementSet, Options, Surrogate};
use mbgc_output::say;
use mbgc_output::Output;

#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    /// Measurement set: several samples of one material (see `docs/diagnose.md`).
    #[arg(long)]
    pub measurements: PathBuf,
    /// Metamodels: one of the set's class, and models of classes with a candidate effect (a
    /// model of a richer class also serves the poorer one, with the extra effect off)
    /// [default: the shipped models/shear_box.json, built into mbgc].
    #[arg(long)]
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
    let max = mbgc::calibrate::tmcmc::MAX_SAMPLES;
    if !(100..=max).contains(&a.samples) {
        anyhow::bail!(
            "--samples: expected 100 to {max} TMCMC samples per stage, got {}",
            a.samples
        );
    }
    let max_starts = mbgc::calibrate::session::MAX_STARTS;
    if a.starts == 0 || a.starts > max_starts {
        anyhow::bail!("--starts {}: expected 1 to {max_starts}", a.starts);
    }
    let out = Output::new(a.json);
    let set = MeasurementSet::from_file(&a.measurements)?;
    let models = crate::builtin::models(&a.model)?
        .into_iter()
        .map(|(m, label)| Surrogate::from_model(m, &label))
        .collect::<mbgc::error::Result<Vec<_>>>()?;
    let opts = Options {
        starts: a.starts,
        samples: a.samples,
        seed: a.seed,
        alpha: a.alpha,
    };
    let d = diagnose(&set, &models, &opts)?;
    say!(out, "{}", markdown(&d).trim_end());
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
