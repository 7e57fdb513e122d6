//! `mbgc calibrate`: the parameters of a material from its measurements, by inverting a saved
//! metamodel; every distinct solution, and what the data cannot decide.

use mbgc::outputs::refuse_overwriting_inputs;
use std::path::{Path, PathBuf};

use clap::Args;

use mbgc::calibrate::report;
use mbgc::calibrate::session::{self, Session, SessionOptions};
use mbgc::error::write_atomic;
use mbgc::material::PsdSpec;
use mbgc::shipped;
use mbgc_output::{out, outln};

#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// Material file (measurements, PSD, fixed parameters, bounds, constraints).
    #[arg(long)]
    pub material: PathBuf,
    /// Metamodel written by `mbgc fit` [default: the shipped models/shear_box.json, built into
    /// mbgc]. Give several (e.g. with and without an effect) with `--bayes` to compare them as
    /// model classes by their evidence.
    #[arg(long)]
    pub model: Vec<PathBuf>,
    /// Parameters the material file fixes that this run searches instead, comma-separated (e.g.
    /// `mu_r_pp,mu_r_pw`): to see what the measurements alone can and cannot decide.
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    pub free: Vec<String>,
    /// L-BFGS starts (Sobol points of the search box).
    #[arg(long, default_value_t = 64)]
    pub starts: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Also sample the posterior by TMCMC (measurement sd plus a model-error term sigma |y|).
    #[arg(long)]
    pub bayes: bool,
    /// TMCMC samples per stage.
    #[arg(long, default_value_t = 2000)]
    pub samples: usize,
    /// Upper bound of the uniform prior of the relative model error sigma.
    #[arg(long, default_value_t = 0.1)]
    pub sigma_max: f64,
    /// Print the result as JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Directory for figures: the posterior (corner plot, with `--bayes`) and the set of equally
    /// good optima (when the data cannot fix every parameter).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Write the best parameter set (all model inputs, first model) as TOML, for `mbgc validate`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// With `--bayes` and one model: write the posterior samples as CSV, one row per equally
    /// weighted TMCMC sample. Columns: every model input in model order (the fixed ones at
    /// their value, the PSD's d50 and sigma_ln among them), `sigma` (the relative model error;
    /// 0 when `--sigma-max 0`), `weight` (1/n), `model` and `material` (the same in every row).
    #[arg(long, value_name = "FILE")]
    pub posterior_out: Option<PathBuf>,
}

pub fn run(a: &CalibrateArgs) -> anyhow::Result<()> {
    let (mut material, note) = shipped::material(&a.material)?;
    if let Some(note) = note {
        eprintln!("note: {note}");
    }
    // Files reached through the material are inputs too (its sieve analysis).
    let sieve = format!("the sieve analysis of {}", a.material.display());
    let mut inputs: Vec<(&str, &Path)> = vec![("--material", &a.material)];
    inputs.extend(a.model.iter().map(|m| ("--model", m.as_path())));
    if let Some(PsdSpec::Sieve(p)) = &material.psd {
        inputs.push((&sieve, p));
    }
    if let Some(out) = &a.out {
        refuse_overwriting_inputs("--out", out, &inputs)?;
    }
    if let Some(out) = &a.posterior_out {
        if !a.bayes {
            anyhow::bail!(
                "--posterior-out {}: there is no posterior without --bayes, so it would write \
                 nothing; add --bayes",
                out.display()
            );
        }
        if a.model.len() > 1 {
            anyhow::bail!(
                "--posterior-out {}: {} models were given and their posteriors have different \
                 parameters; calibrate with one --model to write its samples",
                out.display(),
                a.model.len()
            );
        }
        refuse_overwriting_inputs("--posterior-out", out, &inputs)?;
        if let Some(o) = &a.out {
            refuse_overwriting_inputs("--posterior-out", out, &[("--out", o.as_path())])?;
        }
    }
    if let Some(dir) = &a.plot {
        for label in model_labels(&a.model) {
            for f in figure_names(&label) {
                refuse_overwriting_inputs("--plot", &dir.join(f), &inputs)?;
            }
        }
    }
    material.free(&a.free)?;
    let opts = SessionOptions {
        starts: a.starts,
        seed: a.seed,
        bayes: a.bayes,
        samples: a.samples,
        sigma_max: a.sigma_max,
    };
    opts.check()?;
    let mut sessions = Vec::new();
    let models = shipped::files_or_models(&a.model, shipped::CALIBRATION_MODELS)?;
    for (i, (model, label)) in models.iter().enumerate() {
        if i > 0 && !a.json {
            outln!()?;
        }
        let s = session::run(&material, model, label, &opts)?;
        let mut written = Vec::new();
        if let Some(out) = a.out.as_ref().filter(|_| i == 0) {
            write_atomic(out, s.calibrated_toml().as_bytes())?;
            written.push(out.clone());
        }
        if let Some(out) = a.posterior_out.as_ref().filter(|_| i == 0) {
            let samples = s.posterior_samples()?.ok_or_else(|| {
                anyhow::anyhow!(
                    "--posterior-out {}: the calibration with {label} has no posterior",
                    out.display()
                )
            })?;
            write_atomic(out, posterior_csv(&samples)?.as_bytes())?;
            written.push(out.clone());
        }
        if let Some(dir) = &a.plot {
            written.extend(plot(dir, Path::new(label), &s)?);
        }
        if !a.json {
            out!("{}", report::text(&s, "--json"))?;
            for f in &written {
                outln!("wrote {}", f.display())?;
            }
        }
        sessions.push(s);
    }
    if models.len() > 1 && a.bayes {
        let (ln_z, prob) = session::class_probabilities(&sessions);
        if a.json {
            let v = serde_json::json!({
                "classes": sessions.iter().map(Session::json).collect::<Vec<_>>(),
                "class_probabilities": prob,
            });
            outln!("{}", serde_json::to_string_pretty(&v)?)?;
        } else {
            outln!("\nModel classes (equal prior probabilities):")?;
            for (((_, m), z), p) in models.iter().zip(&ln_z).zip(&prob) {
                outln!("  {m:>40}: log evidence {z:.3}, P(M|D) = {p:.4}")?;
            }
        }
    } else if a.json {
        // Exactly one object on standard output, however many models.
        let v = if sessions.len() == 1 {
            sessions[0].json()
        } else {
            serde_json::json!({ "classes": sessions.iter().map(Session::json).collect::<Vec<_>>() })
        };
        outln!("{}", serde_json::to_string_pretty(&v)?)?;
    }
    Ok(())
}

/// The posterior samples as CSV text (the columns of `--posterior-out`).
fn posterior_csv(p: &mbgc::calibrate::session::PosteriorSamples) -> anyhow::Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header = p.columns();
    header.push("model".into());
    header.push("material".into());
    w.write_record(&header)?;
    for row in &p.rows {
        let mut rec: Vec<String> = row.iter().map(|v| format!("{v:?}")).collect();
        rec.push(p.model.clone());
        rec.push(p.material.clone());
        w.write_record(&rec)?;
    }
    Ok(String::from_utf8(w.into_inner()?)?)
}

/// The models' names as the session records them (the shipped ones' when none is given).
fn model_labels(models: &[PathBuf]) -> Vec<PathBuf> {
    if models.is_empty() {
        shipped::CALIBRATION_MODELS
            .iter()
            .map(PathBuf::from)
            .collect()
    } else {
        models.to_vec()
    }
}

/// The figure files of a model: its posterior and its solution set.
fn figure_names(model: &Path) -> [String; 2] {
    let stem = model
        .file_stem()
        .map_or("model".into(), |s| s.to_string_lossy().to_string());
    [
        format!("{stem}_posterior.svg"),
        format!("{stem}_solution_set.svg"),
    ]
}

/// The posterior corner plot (with `--bayes`) and the solution set (when the data leave one);
/// returns the files written.
fn plot(dir: &Path, model: &Path, s: &Session) -> anyhow::Result<Vec<PathBuf>> {
    let [posterior, solution_set] = figure_names(model);
    let mut figures = Vec::new();
    if let (Some(post), Some(frame)) = (&s.posterior, s.posterior_frame()) {
        let path = dir.join(posterior);
        let key = if frame.marks.len() > s.free.len() {
            "best optimum (σ: posterior mean)"
        } else {
            "best optimum"
        };
        let (marks, ranges) = (Some((&frame.marks[..], key)), Some(&frame.ranges[..]));
        mbgc::plot::corner::corner_keyed(&path, &post.names, &post.draws, marks, ranges)?;
        figures.push(path);
    }
    if let Some(good) = s.solution_set() {
        let path = dir.join(solution_set);
        let marks = Some((&s.best().x[..], "best optimum"));
        mbgc::plot::corner::corner_keyed(&path, &s.free, &good, marks, Some(&s.bounds))?;
        figures.push(path);
    }
    Ok(figures)
}
