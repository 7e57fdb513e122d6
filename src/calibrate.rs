//! `mbgc calibrate`: the parameters of a material from its measurements, by inverting a saved
//! metamodel; every distinct solution, and what the data cannot decide.

use mbgc::outputs::refuse_overwriting_inputs;
use std::path::{Path, PathBuf};

use clap::Args;

use mbgc::calibrate::session::{self, Session, SessionOptions};
use mbgc::error::write_atomic;
use mbgc::material::PsdSpec;
use mbgc_output::outln;

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
}

pub fn run(a: &CalibrateArgs) -> anyhow::Result<()> {
    let mut material = crate::builtin::material(&a.material)?;
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
    if let Some(dir) = &a.plot {
        for label in model_labels(&a.model) {
            for f in figure_names(&label) {
                refuse_overwriting_inputs("--plot", &dir.join(f), &inputs)?;
            }
        }
    }
    for name in &a.free {
        let before = material.fixed.len();
        material.fixed.retain(|(n, _)| n != name);
        if material.fixed.len() == before {
            anyhow::bail!(
                "--free {name}: {} does not fix {name} (it fixes: {})",
                a.material.display(),
                material
                    .fixed
                    .iter()
                    .map(|(n, _)| n.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    let opts = SessionOptions {
        starts: a.starts,
        seed: a.seed,
        bayes: a.bayes,
        samples: a.samples,
        sigma_max: a.sigma_max,
    };
    opts.check()?;
    let mut sessions = Vec::new();
    let models = crate::builtin::models(&a.model)?;
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
        if let Some(dir) = &a.plot {
            written.extend(plot(dir, Path::new(label), &s)?);
        }
        if !a.json {
            print_text(&s)?;
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

/// The models' names as the session records them (the built-in one's when none is given).
fn model_labels(models: &[PathBuf]) -> Vec<PathBuf> {
    if models.is_empty() {
        vec![PathBuf::from(crate::builtin::SHEAR_BOX_MODEL)]
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

fn print_text(s: &Session) -> anyhow::Result<()> {
    let cal = &s.calibration;
    let names = &s.free;
    outln!("{} ({}) with {}", s.material, s.source, s.model)?;
    for n in &s.notes {
        outln!("  {n}")?;
    }
    for (n, v) in &s.fixed {
        outln!("  {n} = {v} fixed")?;
    }
    let meas: Vec<String> = s
        .measured
        .iter()
        .map(|t| format!("{} {} +- {}", t.name, t.value, t.sd))
        .collect();
    outln!("  measured: {}", meas.join(", "))?;
    let fitting = s.fitting().len();
    let others = cal.optima.len() - fitting;
    outln!(
        "{fitting} of {} distinct optima from {} starts in {:.3} s fit the measurements (chi2 <= \
         {:.2}, the 95 % level for {} measurement{}):",
        cal.optima.len(),
        cal.starts,
        cal.seconds,
        s.fit_threshold(),
        s.measured.len(),
        if s.measured.len() == 1 { "" } else { "s" }
    )?;
    for (i, o) in cal.optima.iter().enumerate().take(10) {
        if i == fitting && others > 0 {
            outln!("  local minima that do not fit:")?;
        }
        let params: Vec<String> = names
            .iter()
            .zip(&o.x)
            .map(|(n, v)| format!("{n} = {v:.4}"))
            .collect();
        let fits: Vec<String> = s
            .measured
            .iter()
            .zip(o.predictions.iter().zip(&o.residuals))
            .map(|(t, (p, r))| format!("{} {p:.4} ({r:+.2} sd)", t.name))
            .collect();
        outln!(
            "  #{} chi2 {:.3e} ({} starts): {}\n      predicted {}",
            i + 1,
            o.chi2,
            o.starts,
            params.join(", "),
            fits.join(", ")
        )?;
    }
    if cal.optima.len() > 10 {
        outln!("  ... {} more (see --json)", cal.optima.len() - 10)?;
    }
    if !s.unused.is_empty() {
        outln!(
            "Not in any equation of the measured responses (any value in range fits equally): {}",
            s.unused.join(", ")
        )?;
    }
    if cal.excess_parameters > 0 {
        let equal = s.equally_good().len();
        if equal > 1 {
            outln!(
                "{equal} of the optima are equally good points of one continuous solution set, \
                 not separate answers."
            )?;
        }
        outln!(
            "{} free parameters but {} measurements: the data fix at most {} combinations; the \
             solutions form a set of dimension >= {}.",
            names.len(),
            s.measured.len(),
            s.measured.len(),
            cal.excess_parameters
        )?;
    }
    if !cal.flat_directions.is_empty() {
        outln!("Directions at the best optimum along which the predictions do not change (unit-box steps):")?;
        for d in &cal.flat_directions {
            let comp: Vec<String> = names
                .iter()
                .zip(&d.components)
                .filter(|(_, c)| c.abs() >= 0.05)
                .map(|(n, c)| format!("{c:+.2} {n}"))
                .collect();
            outln!(
                "  {}  (singular value {:.1e})",
                comp.join(" "),
                d.singular_value
            )?;
        }
        outln!(
            "Range of each parameter over the equally good optima (chi2 within 1 of the best):"
        )?;
        for r in &cal.solution_ranges {
            outln!("  {} in [{:.4}, {:.4}]", r.name, r.min, r.max)?;
        }
    }
    if let Some(post) = &s.posterior {
        outln!(
            "Posterior (TMCMC, {} samples, {} stages): log evidence {:.3}",
            post.samples,
            post.stages,
            post.ln_evidence
        )?;
        for p in &post.parameters {
            outln!(
                "  {:>12}: mean {:.4}, COV {:.3}, 5 % {:.4}, 95 % {:.4}",
                p.name,
                p.mean,
                p.cov,
                p.q05,
                p.q95
            )?;
        }
        outln!("Posterior-robust predictions (mean +- sd over the posterior):")?;
        for r in &post.responses {
            outln!("  {:>12}: {:.4} +- {:.4}", r.name, r.mean, r.sd)?;
        }
    }
    Ok(())
}
