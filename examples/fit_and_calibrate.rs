//! The library alone, from a campaign table to a calibrated material: read the shipped
//! shear-box campaign into memory, fit a small metamodel to it (one equation per response, in
//! the experiment's dimensionless groups), then invert it for Gravel 8/16. Nothing is written;
//! the fitted model could be saved with `Metamodel::save`.
//!
//!     cargo run --release --example fit_and_calibrate
//!
//! The GP settings are small so that this runs in seconds; `mbgc train` fits the shipped model
//! with 5000 individuals, 300 generations and 4 restarts.

use std::path::Path;

use mbgc::calibrate::session::{self, SessionOptions};
use mbgc::experiments::shear_box::ShearBox;
use mbgc::experiments::Experiment;
use mbgc::gp::Config;
use mbgc::material::Material;
use mbgc::metamodel::{fit, FitSettings, TrainingTable};
use mbgc::space::Space;

fn main() -> mbgc::Result<()> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // The inputs are the space's parameters; the responses the two the material measured.
    let space = Space::from_file(&root.join("examples/space_shear_box.toml"))?;
    let inputs: Vec<String> = space.parameters.iter().map(|p| p.name.clone()).collect();
    let responses = vec!["shear_angle".to_string(), "bulk_density".to_string()];
    let table = TrainingTable::read_csv(
        &root.join("training_data/shear_box.csv"),
        &inputs,
        &responses,
    )?;
    println!("{} runs of {}", table.rows(), table.source);

    // Checked before any generation runs; a bad setting is an error naming it.
    let mut settings = FitSettings::new(inputs, responses)
        .test_fraction(0.2)
        .space(space)
        .config(Config {
            population: 1000,
            generations: 30,
            seed: 7,
            ..Config::default()
        });
    settings.similarity = ShearBox::default().similarity();
    let fitted = fit(&table, &settings, |_, _| {})?;
    for r in &fitted.model.responses {
        let test = r.test.map_or(f64::NAN, |t| t.r2);
        println!("{} = {}\n    test R^2 {test:.3}", r.name, r.equation);
    }

    // The material: measured responses, the PSD from its sieve analysis, fixed parameters.
    let gravel = Material::from_file(&root.join("examples/gravel.toml"))?;
    let result = session::run(
        &gravel,
        &fitted.model,
        "the model fitted above",
        &SessionOptions::default().starts(32),
    )?;
    let best = result.best();
    println!(
        "{} distinct optima; the best:",
        result.calibration.optima.len()
    );
    for (name, value) in result.free.iter().zip(&best.x) {
        println!("    {name} = {value:.4}");
    }
    for (m, p) in result.measured.iter().zip(&best.predictions) {
        println!("    {}: measured {} predicted {p:.2}", m.name, m.value);
    }
    Ok(())
}
