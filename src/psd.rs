//! `mbgc psd`: fit sieve data, draw particle sets.

use mbgc::outputs::refuse_overwriting_inputs;
use mbgc_output::say;
use mbgc_output::Output;
use std::fmt::Write as _;
use std::path::PathBuf;

use clap::{ArgGroup, Args, Subcommand};

use mbgc::error::{write_atomic, Error};
use mbgc::psd::{
    default_range, draw_by_number, fit_all, fit_model, Distribution, LogNormal, MassDistribution,
    Model, SieveData, DEFAULT_TRIM,
};

#[derive(Debug, Args)]
pub struct PsdArgs {
    #[command(subcommand)]
    pub command: PsdCommand,
}

#[derive(Debug, Subcommand)]
pub enum PsdCommand {
    /// Fit GGS, RRSB and log-normal to a sieve analysis and report R^2 and MSE.
    Fit(FitArgs),
    /// Draw particle diameters by number whose mass distribution follows a PSD.
    Draw(DrawArgs),
}

#[derive(Debug, Args)]
pub struct FitArgs {
    /// Sieve CSV with columns size_mm and passing (fraction 0..1) or passing_pct (0..100).
    pub sieve: PathBuf,
    /// Standard output holds one JSON object; the text goes to standard error.
    #[arg(long)]
    pub json: bool,
    /// Write a figure of the data and the fitted curves (.svg or .png).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(group(ArgGroup::new("psd").required(true).args(["sieve", "d50"])))]
pub struct DrawArgs {
    /// Sieve CSV to fit the distribution to.
    #[arg(long, value_name = "CSV")]
    pub sieve: Option<PathBuf>,
    /// Model to fit to --sieve [default: lognormal, the family the metamodel is trained on].
    #[arg(long, conflicts_with = "d50", value_parser = crate::choice::choice::<Model>(Model::ALL.map(Model::name)))]
    pub model: Option<Model>,
    /// Log-normal mass median diameter d50 in mm (instead of --sieve).
    #[arg(
        long,
        value_name = "MM",
        requires = "sigma_ln",
        allow_negative_numbers = true
    )]
    pub d50: Option<f64>,
    /// Log-normal sigma_ln (standard deviation of ln d), with --d50.
    #[arg(
        long = "sigma-ln",
        value_name = "S",
        requires = "d50",
        conflicts_with = "sieve",
        allow_negative_numbers = true
    )]
    pub sigma_ln: Option<f64>,
    /// Number of particles.
    #[arg(long)]
    pub n: usize,
    /// Smallest diameter in mm [default: the size with 1 % of the mass below].
    #[arg(long = "d-min", value_name = "MM", allow_negative_numbers = true)]
    pub d_min: Option<f64>,
    /// Largest diameter in mm [default: the size with 1 % of the mass above].
    #[arg(long = "d-max", value_name = "MM", allow_negative_numbers = true)]
    pub d_max: Option<f64>,
    /// Random seed; the same seed gives the same particles.
    #[arg(long)]
    pub seed: u64,
    /// Output CSV with one column diameter_mm.
    #[arg(long, value_name = "CSV")]
    pub out: PathBuf,
    /// Standard output holds one JSON object (the summary); text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &PsdArgs) -> anyhow::Result<()> {
    match &args.command {
        PsdCommand::Fit(a) => run_fit(a),
        PsdCommand::Draw(a) => run_draw(a),
    }
}

fn run_fit(args: &FitArgs) -> anyhow::Result<()> {
    let out = Output::new(args.json);
    // Refuse a bad figure name before any output.
    if let Some(plot) = &args.plot {
        mbgc::plot::format_of(plot)?;
        refuse_overwriting_inputs("--plot", plot, &[("the sieve file", &args.sieve)])?;
    }
    let data = SieveData::read(&args.sieve)?;
    let report = fit_all(&data)?;
    say!(out, "{}: {} sieve points", data.source, data.len());
    say!(
        out,
        "{:<10} {:<38} {:>9} {:>11}",
        "model",
        "parameters",
        "R^2",
        "MSE"
    );
    for f in &report.models {
        say!(
            out,
            "{:<10} {:<38} {:>9.5} {:>11.3e}{}",
            f.model.name(),
            f.dist.describe(),
            f.r2,
            f.mse,
            if f.model == report.best {
                "  <- best"
            } else {
                ""
            }
        );
    }
    say!(
        out,
        "metamodel inputs (log-normal): d50 = {:.4} mm, sigma_ln = {:.4}",
        report.d50_mm,
        report.sigma_ln
    );
    if let Some(plot) = &args.plot {
        mbgc::plot::psd::write_fit(plot, &data, &report)?;
        say!(out, "figure: {}", plot.display());
    }
    out.object(&report)
}

const ARGS: &str = "command line";

fn run_draw(args: &DrawArgs) -> anyhow::Result<()> {
    let out = Output::new(args.json);
    if let Some(sieve) = &args.sieve {
        refuse_overwriting_inputs("--out", &args.out, &[("--sieve", sieve)])?;
    }
    let dist = match (&args.sieve, args.d50, args.sigma_ln) {
        (Some(path), _, _) => {
            let data = SieveData::read(path)?;
            let model = args.model.unwrap_or(Model::LogNormal);
            let fit = fit_model(&data, model)?;
            say!(
                out,
                "{model} fitted to {}: {} (R^2 = {:.5})",
                data.source,
                fit.dist.describe(),
                fit.r2
            );
            fit.dist
        }
        (None, Some(d50), Some(sigma)) => {
            if !(d50.is_finite() && d50 > 0.0) {
                return Err(Error::input(
                    ARGS,
                    "--d50",
                    format!("expected a positive diameter in mm, found {d50}"),
                )
                .into());
            }
            if !(sigma.is_finite() && sigma > 0.0) {
                return Err(Error::input(
                    ARGS,
                    "--sigma-ln",
                    format!("expected a positive standard deviation of ln d, found {sigma}"),
                )
                .into());
            }
            Distribution::LogNormal(LogNormal::new(d50, sigma)?)
        }
        // clap enforces --sieve or --d50 with --sigma-ln.
        _ => anyhow::bail!("give either --sieve or --d50 with --sigma-ln"),
    };
    let set = draw_by_number(&dist, (args.d_min, args.d_max), args.n, args.seed, ARGS)?;

    let mut csv = String::with_capacity(24 * set.diameters_mm.len() + 16);
    csv.push_str("diameter_mm\n");
    for d in &set.diameters_mm {
        let _ = writeln!(csv, "{d}");
    }
    write_atomic(&args.out, csv.as_bytes())?;

    let (dmin_default, dmax_default) = default_range(&dist);
    let tag = |given: Option<f64>, q: f64| {
        if given.is_some() {
            String::new()
        } else {
            format!(" (default: Q3 = {q})")
        }
    };
    say!(
        out,
        "range: d_min = {:.4} mm{}, d_max = {:.4} mm{}; holds {:.2} % of the mass",
        set.d_min,
        tag(args.d_min, DEFAULT_TRIM),
        set.d_max,
        tag(args.d_max, 1.0 - DEFAULT_TRIM),
        100.0 * set.mass_fraction
    );
    if args.d_min.is_some() || args.d_max.is_some() {
        say!(
            out,
            "(default range would be [{dmin_default:.4}, {dmax_default:.4}] mm)"
        );
    }
    let target_median =
        dist.q3_inv(dist.q3(set.d_min) + 0.5 * (dist.q3(set.d_max) - dist.q3(set.d_min)));
    say!(
        out,
        "{} particles (seed {}) written to {}",
        set.diameters_mm.len(),
        args.seed,
        args.out.display()
    );
    say!(
        out,
        "count-mean diameter: {:.4} mm; mass-median diameter: {:.4} mm (truncated distribution: \
         {:.4} mm)",
        set.count_mean(),
        set.mass_median(),
        target_median
    );
    out.object(&serde_json::json!({
        "out": args.out,
        "n": set.diameters_mm.len(),
        "seed": args.seed,
        "d_min_mm": set.d_min,
        "d_max_mm": set.d_max,
        "mass_fraction": set.mass_fraction,
        "count_mean_mm": set.count_mean(),
        "mass_median_mm": set.mass_median(),
        "target_mass_median_mm": target_median,
    }))
}
