//! Paper reproductions and benchmarks behind `mbgc bench`: each study builds its cases from the
//! library, runs them and writes the report under `docs/` that names the command regenerating
//! it. The core modules never import a study; a study is one file named after what it compares.
//!
//! - [`sampling_quality`]: seed 004 Figs. 7-8, space-filling metrics of every design method.
//! - [`dem_scene`], [`dem_throughput`]: the settled polydisperse box, mbgc against LIGGGHTS.
//! - [`shear_box_vs_liggghts`]: the shear box replayed in LIGGGHTS; the cost of a run.
//! - [`shear_box_fill`], [`shear_box_check`]: the shear box against a LIGGGHTS deck that fills
//!   itself; seed 004's validation point, box scale, noise and whole-run cost (docs/shear_box.md).
//! - [`gp_vs_gplearn`]: symbolic regression against gplearn on Feynman equations.
//! - [`metamodel_report`]: the shipped metamodel, its cost and validation, the gravel calibrated
//!   on it (docs/metamodel.md).
//! - [`cohesive_metamodel_report`]: the shipped cohesive metamodel, its limit, cost and
//!   validation on both faces (docs/metamodel_sjkr.md).
//! - [`metamodel_benchmark`]: mbgc's GP against PyOperon, a Gaussian process and a quadratic
//!   surface on the shipped campaign (docs/metamodel_benchmark.md); [`noise_floor`]: the
//!   replicate noise both metamodel studies judge errors by.
//! - [`rest_detection`]: when a shear-box run is at rest: rest rules replayed on the traces of
//!   rerun campaign rows, and whole runs under two rules (docs/rest_detection.md);
//!   [`rest_validation`]: the shipped validation design rerun under the candidate rule, its cost
//!   and the shipped model's RMSE on it (docs/rest_validation.md).
//! - [`restitution`]: seed 003's Bayesian model classes on DEM impacts of steel.
//! - [`clogging_silo_report`]: the clogging silo's avalanches against the orifice, the published
//!   trend, their scatter and cost (docs/clogging_silo.md).
//! - [`sensitivity_report`]: seed 000's three-level sensitivity analysis on the hopper
//!   (docs/sensitivity.md).
//! - [`liggghts_backend`]: the shear box as a campaign on mbgc, LIGGGHTS and LIGGGHTS under MPI
//!   (docs/liggghts_backend.md).
//! - [`shear_cell_report`]: the shear cell's noise, cohesionless locus, cohesion and cost from
//!   its campaign tables (docs/shear_cell.md); [`cell_metamodel_report`]: the shear-cell
//!   metamodel's space, cost and validation against its replicate noise
//!   (docs/metamodel_shear_cell.md).
//! - [`stiffness_dependence`]: the shear box's responses along lines of the particle stiffness
//!   K_p, with and without cohesion, and where each stops changing (docs/stiffness.md).
//! - [`reference`](mod@reference): the reference codes (`--vs`).

// The options' doc comments are `mbgc bench --help`'s text, written for the terminal (`<dir>`).
#![allow(rustdoc::invalid_html_tags)]

mod campaign_runs;
pub mod cell_metamodel_report;
pub mod clogging_silo_report;
pub mod cohesive_metamodel_report;
pub mod dem_scene;
pub mod dem_throughput;
pub mod diagnose_report;
pub mod gp_vs_gplearn;
pub mod liggghts_backend;
pub mod metamodel_benchmark;
pub mod metamodel_report;
pub mod noise_floor;
pub mod reference;
pub mod rest_detection;
mod rest_tables;
pub mod rest_validation;
pub mod restitution;
pub mod rigid_limit_report;
pub mod sampling_quality;
pub mod sensitivity_report;
pub mod shear_box_check;
pub mod shear_box_fill;
pub mod shear_box_vs_liggghts;
pub mod shear_cell_report;
pub mod stiffness_dependence;
pub mod stiffness_validation;

/// Writes a study's report atomically (its directory made first), then says where it went
/// ([`report_written`]).
pub fn write_report(
    json: bool,
    report: &std::path::Path,
    text: &str,
    fields: serde_json::Value,
) -> anyhow::Result<()> {
    if let Some(parent) = report.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)?;
    }
    mbgc::error::write_atomic(report, text.as_bytes())?;
    report_written(json, report, fields);
    Ok(())
}

/// A study's report to `report` ([`write_report`]), or without one to standard output; with
/// `--json` and no file the text goes to standard error and standard output holds one JSON object
/// (`report: null`, then the study's own fields).
pub fn emit_report(
    json: bool,
    report: Option<&std::path::Path>,
    text: &str,
    fields: serde_json::Value,
) -> anyhow::Result<()> {
    match report {
        Some(path) => write_report(json, path, text, fields),
        None if json => {
            eprint!("{text}");
            let mut obj = serde_json::Map::new();
            obj.insert("report".into(), serde_json::Value::Null);
            if let serde_json::Value::Object(m) = fields {
                obj.extend(m);
            }
            println!("{}", serde_json::Value::Object(obj));
            Ok(())
        }
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

/// Tells where a study's report went: a line on standard error, and with `--json` one JSON
/// object on standard output (`report`, then the study's own fields), as every command does.
pub fn report_written(json: bool, report: &std::path::Path, fields: serde_json::Value) {
    eprintln!("wrote {}", report.display());
    if json {
        let mut obj = serde_json::Map::new();
        obj.insert("report".into(), report.display().to_string().into());
        if let serde_json::Value::Object(m) = fields {
            obj.extend(m);
        }
        println!("{}", serde_json::Value::Object(obj));
    }
}
