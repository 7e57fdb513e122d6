//! `mbgc noise`: measure a model's DEM noise from replicate runs of its validation design and
//! record it in a copy of the model, so that a diagnosis can tell the equations' miss (shared
//! between the samples of a material) from the noise its validation error holds.

use std::path::PathBuf;

use clap::Args;
use mbgc::metamodel::noise::record_replicate_noise;
use mbgc::metamodel::Metamodel;
use mbgc::outputs::refuse_overwriting_inputs;
use mbgc_output::{say, Output};

#[derive(Debug, Args)]
pub struct NoiseArgs {
    /// Model file.
    #[arg(long)]
    pub model: PathBuf,
    /// The model's validation table (a campaign table).
    #[arg(long)]
    pub validation: PathBuf,
    /// Runs at inputs of validation runs, with another seed (a campaign table).
    #[arg(long)]
    pub replicates: PathBuf,
    /// The model with each response's replicate sd recorded (JSON); never the model file itself.
    #[arg(long)]
    pub out: PathBuf,
    /// Standard output holds one JSON object; text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: &NoiseArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    refuse_overwriting_inputs(
        "--out",
        &a.out,
        &[
            ("--model", &a.model),
            ("--validation", &a.validation),
            ("--replicates", &a.replicates),
        ],
    )?;
    let mut model = Metamodel::load(&a.model)?;
    let (noise, notes) = record_replicate_noise(&mut model, &a.validation, &a.replicates)?;
    for n in &notes {
        eprintln!("warning: {}: {n}", a.model.display());
    }
    say!(
        out,
        "| response | replicate sd | pairs | validation RMSE | errors at |"
    );
    say!(out, "|---|---|---|---|---|");
    for (r, n) in model.responses.iter().zip(&noise) {
        say!(
            out,
            "| {} | {:.4} | {} | {} | {} |",
            n.response,
            n.sd,
            n.pairs,
            r.validation
                .map_or("-".to_string(), |v| format!("{:.4}", v.rmse)),
            r.error_reference
                .map_or("-".to_string(), |f| format!("factor {f}"))
        );
    }
    model.save(&a.out)?;
    say!(out, "wrote {}", a.out.display());
    out.object(&serde_json::json!({
        "out": a.out,
        "noise": noise.iter().zip(&model.responses).map(|(n, r)| serde_json::json!({
            "response": n.response, "sd": n.sd, "pairs": n.pairs,
            "error_reference": r.error_reference,
        })).collect::<Vec<_>>(),
        "notes": notes,
    }))
}
