//! The command line: one file per subcommand, each with its argument struct and a `run`.
//!
//! A program that embeds mbgc (to register its own experiment with
//! `mbgc::campaign::registry::register`) calls [`main`] after registering.

// The argument structs' doc comments are `mbgc --help`'s text, written for the terminal
// (`<dir>`, `[model]`), not as rustdoc markup.
#![allow(rustdoc::invalid_html_tags, rustdoc::broken_intra_doc_links)]

use clap::{Parser, Subcommand};

pub mod bench;
pub mod calibrate;
pub mod campaign;
pub mod campaign_progress;
pub mod choice;
pub mod diagnose;
pub mod effects;
pub mod export;
pub mod fit;
pub mod metrics;
pub mod noise;
pub mod predict;
pub mod propagate;
pub mod psd;
pub mod sample;
pub mod sensitivity;
pub mod simulate;
pub mod slurm;
pub mod train;
pub mod train_progress;
pub mod validate;

#[derive(Debug, Parser)]
#[command(
    name = "mbgc",
    version,
    about = "Metamodel-first global calibration of DEM simulation parameters"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Generate (or extend) a space-filling design.
    Sample(sample::SampleArgs),
    /// Space-filling metrics of a design: MID, COV, centered and wrap-around L2 discrepancy.
    Metrics(metrics::MetricsArgs),
    /// Particle size distributions: fit sieve data, draw particle sets.
    Psd(psd::PsdArgs),
    /// Run a calibration experiment for every row of a design (resumable, shardable).
    Simulate(simulate::SimulateArgs),
    /// Write (and with --submit, submit) a campaign as a Slurm job array and its merge job.
    Slurm(slurm::SlurmArgs),
    /// The physical effects a model class can switch on, with their parameters.
    Effects(effects::EffectsArgs),
    /// Campaign tables: merge shards, report progress, import runs made from written decks.
    Campaign(campaign::CampaignArgs),
    /// Fit one equation per response by genetic-programming symbolic regression.
    Fit(fit::FitArgs),
    /// Sample, simulate and fit in one resumable command (a design, its runs, the metamodel).
    Train(train::TrainArgs),
    /// Evaluate a saved metamodel on the rows of a table.
    Predict(predict::PredictArgs),
    /// Record a model's DEM noise, measured by replicate runs of its validation design.
    Noise(noise::NoiseArgs),
    /// Write a saved metamodel's equations as Rust, LaTeX or sympy.
    Export(export::ExportArgs),
    /// Calibrate a material: invert a saved metamodel for its measurements.
    Calibrate(calibrate::CalibrateArgs),
    /// Rerun the DEM experiment at calibrated parameters and compare with the measurements.
    Validate(validate::ValidateArgs),
    /// Compare a measurement set with the model: where it fails, which effect is missing.
    Diagnose(diagnose::DiagnoseArgs),
    /// Carry a calibrated posterior through DEM: draws, runs of a process experiment (a
    /// hopper's discharge), the robust band of each quantity beside the best-fit point's.
    Propagate(propagate::PropagateArgs),
    /// Which inputs matter for which response: power laws, PCA and norms of contact-law
    /// sensitivities (seed 000's three levels), Sobol indices and local sensitivities of a model.
    Sensitivity(sensitivity::SensitivityArgs),
    /// Benchmarks and reproduction reports.
    Bench(bench::BenchArgs),
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Sample(a) => sample::run(&a),
        Command::Metrics(a) => metrics::run(&a),
        Command::Psd(a) => psd::run(&a),
        Command::Simulate(a) => simulate::run(&a),
        Command::Slurm(a) => slurm::run(&a),
        Command::Effects(a) => effects::run(&a),
        Command::Campaign(a) => campaign::run(&a),
        Command::Fit(a) => fit::run(&a),
        Command::Train(a) => train::run(&a),
        Command::Predict(a) => predict::run(&a),
        Command::Noise(a) => noise::run(&a),
        Command::Export(a) => export::run(&a),
        Command::Calibrate(a) => calibrate::run(&a),
        Command::Validate(a) => validate::run(&a),
        Command::Diagnose(a) => diagnose::run(&a),
        Command::Propagate(a) => propagate::run(&a),
        Command::Sensitivity(a) => sensitivity::run(&a),
        Command::Bench(a) => bench::run(&a),
    }
}

/// Entry point of the binary: errors are printed as one readable message, never as a panic.
pub fn main() -> std::process::ExitCode {
    // `mbgc ... | head` closes the pipe early: end quietly as other Unix tools do (Rust ignores
    // SIGPIPE, so the next print would panic with "Broken pipe").
    #[cfg(unix)]
    // SAFETY: restoring the default action of one signal before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    quiet_stdout_panics();
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(cli)));
    let result = match result {
        Ok(r) => r,
        // A `println!` that could not write (only code not yet moved to mbgc_output's writers
        // has one): the same clean error as any other write failure on standard output.
        Err(payload) => match stdout_panic_reason(payload.as_ref()) {
            Some(reason) => {
                eprintln!("mbgc: writing to standard output: {reason}");
                return std::process::ExitCode::FAILURE;
            }
            None => std::panic::resume_unwind(payload),
        },
    };
    // A report line that could not be written (`say!` keeps the error) fails the command too.
    let flushed = mbgc_output::finish();
    match result {
        Err(e) => {
            match e.downcast_ref::<mbgc_output::StdoutError>() {
                Some(w) => eprintln!("mbgc: {w}"),
                None => eprintln!("error: {e:#}"),
            }
            std::process::ExitCode::FAILURE
        }
        Ok(()) => match flushed {
            Ok(()) => std::process::ExitCode::SUCCESS,
            Err(w) => {
                eprintln!("mbgc: {w}");
                std::process::ExitCode::FAILURE
            }
        },
    }
}

/// The prefix of the panic message of `print!` and `println!` when standard output fails.
const STDOUT_PANIC: &str = "failed printing to stdout: ";

/// The reason of a failed `println!` (its panic payload), without the OS error number.
fn stdout_panic_reason(payload: &(dyn std::any::Any + Send)) -> Option<String> {
    let text = payload
        .downcast_ref::<String>()
        .map(String::as_str)
        .or_else(|| payload.downcast_ref::<&str>().copied())?;
    let reason = text.strip_prefix(STDOUT_PANIC)?;
    Some(match reason.find(" (os error ") {
        Some(k) => reason[..k].to_string(),
        None => reason.to_string(),
    })
}

/// Keeps the panic of a failed `println!` off standard error: [`main`] reports it as an error.
/// Every other panic is reported as before.
fn quiet_stdout_panics() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if stdout_panic_reason(info.payload()).is_none() {
            default(info);
        }
    }));
}
