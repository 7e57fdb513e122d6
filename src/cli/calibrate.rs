//! `mbgc calibrate`: the parameters of a material from its measurements, by inverting a saved
//! metamodel; every distinct solution, and what the data cannot decide.

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;

use crate::calibrate::{bayes, calibrate, Problem};
use crate::error::write_atomic;
use crate::material::Material;
use crate::metamodel::Metamodel;

#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// Material file (measurements, PSD, fixed parameters, bounds, constraints).
    #[arg(long)]
    pub material: PathBuf,
    /// Metamodel written by `mbgc fit`. Give several (e.g. with and without an effect) with
    /// `--bayes` to compare them as model classes by their evidence.
    #[arg(long, default_values = ["models/shear_box.json"])]
    pub model: Vec<PathBuf>,
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
    let material = Material::from_file(&a.material)?;
    if a.starts == 0 {
        anyhow::bail!("--starts: expected at least 1");
    }
    let mut evidences = Vec::new();
    let mut jsons = Vec::new();
    for (i, path) in a.model.iter().enumerate() {
        if i > 0 && !a.json {
            println!();
        }
        let (ev, json) = run_one(a, &material, path, i == 0)?;
        evidences.push(ev);
        jsons.push(json);
    }
    if a.model.len() > 1 && a.bayes {
        let ln_z: Vec<f64> = evidences
            .iter()
            .map(|e| e.unwrap_or(f64::NEG_INFINITY))
            .collect();
        let prob = bayes::class_probabilities(&ln_z);
        if a.json {
            let v = serde_json::json!({
                "classes": jsons,
                "class_probabilities": prob,
            });
            println!("{}", serde_json::to_string_pretty(&v)?);
        } else {
            println!("\nModel classes (equal prior probabilities):");
            for ((m, z), p) in a.model.iter().zip(&ln_z).zip(&prob) {
                println!(
                    "  {:>40}: log evidence {z:.3}, P(M|D) = {p:.4}",
                    m.display()
                );
            }
        }
    } else if a.json {
        for j in jsons {
            println!("{}", serde_json::to_string_pretty(&j)?);
        }
    }
    Ok(())
}

/// Calibrates with one model; returns its log-evidence (with `--bayes`) and the JSON record.
fn run_one(
    a: &CalibrateArgs,
    material: &Material,
    model_path: &std::path::Path,
    first: bool,
) -> anyhow::Result<(Option<f64>, serde_json::Value)> {
    let model = Metamodel::load(model_path)?;
    let problem = Problem::new(&model, material)?;
    let cal = calibrate(&problem, a.starts, a.seed);
    let Some(best) = cal.optima.first() else {
        anyhow::bail!(
            "no start converged: the model's equations are not finite anywhere in the search box"
        );
    };
    if best.violation > 1e-8 {
        let list: Vec<&str> = problem
            .constraints
            .iter()
            .map(|(c, _)| c.text.as_str())
            .collect();
        anyhow::bail!(
            "{}: the constraints [{}] cannot be met inside the search box (smallest violation^2 {:.3e})",
            material.source,
            list.join(", "),
            best.violation
        );
    }
    let posterior = if a.bayes {
        Some(bayes::posterior(&problem, a.samples, a.sigma_max, a.seed)?)
    } else {
        None
    };
    if let Some(path) = a.out.as_ref().filter(|_| first) {
        let x = problem.full(&best.x);
        let mut t = format!(
            "# Calibrated by mbgc from {} with {}\nmaterial = {:?}\n\n[parameters]\n",
            material.source,
            model_path.display(),
            material.name
        );
        for (n, v) in problem.names.iter().zip(&x) {
            writeln!(t, "{n} = {v:?}")?;
        }
        t.push_str("\n[predicted]\n");
        for (tg, p) in problem.targets.iter().zip(&best.predictions) {
            writeln!(t, "{} = {p:?}", tg.name)?;
        }
        write_atomic(path, t.as_bytes())?;
    }
    let mut figures = Vec::new();
    if let Some(dir) = &a.plot {
        let stem = model_path
            .file_stem()
            .map_or("model".into(), |s| s.to_string_lossy().to_string());
        let names: Vec<String> = problem.free_names().iter().map(|s| s.to_string()).collect();
        let boxes: Vec<(f64, f64)> = problem
            .lower
            .iter()
            .copied()
            .zip(problem.upper.iter().copied())
            .collect();
        if let Some(post) = &posterior {
            let mut ranges = boxes.clone();
            let mut marks = best.x.clone();
            if post.names.len() > names.len() {
                ranges.push((0.0, a.sigma_max));
                marks.push(post.parameters.last().map_or(0.0, |s| s.mean));
            }
            let path = dir.join(format!("{stem}_posterior.svg"));
            crate::plot::corner::corner(
                &path,
                &post.names,
                &post.draws,
                Some(&marks),
                Some(&ranges),
            )?;
            figures.push(path);
        }
        let good: Vec<Vec<f64>> = cal
            .optima
            .iter()
            .filter(|o| o.chi2 <= best.chi2 + 1.0)
            .map(|o| o.x.clone())
            .collect();
        if cal.excess_parameters > 0 && good.len() > 1 && !names.is_empty() {
            let path = dir.join(format!("{stem}_solution_set.svg"));
            crate::plot::corner::corner(&path, &names, &good, Some(&best.x), Some(&boxes))?;
            figures.push(path);
        }
    }
    let json = serde_json::json!({
        "material": material.name,
        "model": model_path.display().to_string(),
        "notes": problem.notes,
        "calibration": cal,
        "posterior": posterior,
    });
    let ln_z = posterior.as_ref().map(|p| p.ln_evidence);
    if a.json {
        return Ok((ln_z, json));
    }
    let names = problem.free_names();
    println!(
        "{} ({}) with {}",
        material.name,
        material.source,
        model_path.display()
    );
    for n in &problem.notes {
        println!("  {n}");
    }
    for (n, v) in &material.fixed {
        println!("  {n} = {v} fixed");
    }
    let meas: Vec<String> = problem
        .targets
        .iter()
        .map(|t| format!("{} {} +- {}", t.name, t.value, t.sd))
        .collect();
    println!("  measured: {}", meas.join(", "));
    println!(
        "{} distinct optim{} from {} starts in {:.3} s:",
        cal.optima.len(),
        if cal.optima.len() == 1 { "um" } else { "a" },
        cal.starts,
        cal.seconds
    );
    for (i, o) in cal.optima.iter().enumerate().take(10) {
        let params: Vec<String> = names
            .iter()
            .zip(&o.x)
            .map(|(n, v)| format!("{n} = {v:.4}"))
            .collect();
        let fits: Vec<String> = problem
            .targets
            .iter()
            .zip(o.predictions.iter().zip(&o.residuals))
            .map(|(t, (p, r))| format!("{} {p:.4} ({r:+.2} sd)", t.name))
            .collect();
        println!(
            "  #{} chi2 {:.3e} ({} starts): {}\n      predicted {}",
            i + 1,
            o.chi2,
            o.starts,
            params.join(", "),
            fits.join(", ")
        );
    }
    if cal.optima.len() > 10 {
        println!("  ... {} more (see --json)", cal.optima.len() - 10);
    }
    let unused: Vec<&str> = names
        .iter()
        .copied()
        .filter(|n| {
            !problem
                .targets
                .iter()
                .any(|t| model.responses[t.response].uses.iter().any(|u| u == n))
        })
        .collect();
    if !unused.is_empty() {
        println!(
            "Not in any equation of the measured responses (any value in range fits equally): {}",
            unused.join(", ")
        );
    }
    if cal.excess_parameters > 0 {
        let equal = cal
            .optima
            .iter()
            .filter(|o| o.chi2 <= best.chi2 + 1.0)
            .count();
        if equal > 1 {
            println!(
                "{equal} of the optima are equally good points of one continuous solution set, \
                 not separate answers."
            );
        }
        println!(
            "{} free parameters but {} measurements: the data fix at most {} combinations; the \
             solutions form a set of dimension >= {}.",
            names.len(),
            problem.targets.len(),
            problem.targets.len(),
            cal.excess_parameters
        );
    }
    if !cal.flat_directions.is_empty() {
        println!("Directions at the best optimum along which the predictions do not change (unit-box steps):");
        for d in &cal.flat_directions {
            let comp: Vec<String> = names
                .iter()
                .zip(&d.components)
                .filter(|(_, c)| c.abs() >= 0.05)
                .map(|(n, c)| format!("{c:+.2} {n}"))
                .collect();
            println!(
                "  {}  (singular value {:.1e})",
                comp.join(" "),
                d.singular_value
            );
        }
        println!(
            "Range of each parameter over the equally good optima (chi2 within 1 of the best):"
        );
        for r in &cal.solution_ranges {
            println!("  {} in [{:.4}, {:.4}]", r.name, r.min, r.max);
        }
    }
    if let Some(post) = &posterior {
        println!(
            "Posterior (TMCMC, {} samples, {} stages): log evidence {:.3}",
            post.samples, post.stages, post.ln_evidence
        );
        for s in &post.parameters {
            println!(
                "  {:>12}: mean {:.4}, COV {:.3}, 5 % {:.4}, 95 % {:.4}",
                s.name, s.mean, s.cov, s.q05, s.q95
            );
        }
        println!("Posterior-robust predictions (mean +- sd over the posterior):");
        for s in &post.responses {
            println!("  {:>12}: {:.4} +- {:.4}", s.name, s.mean, s.sd);
        }
    }
    if let Some(p) = a.out.as_ref().filter(|_| first) {
        println!("wrote {}", p.display());
    }
    for f in &figures {
        println!("wrote {}", f.display());
    }
    Ok((ln_z, json))
}
