//! mbgc: metamodel-first global calibration of DEM simulation parameters.
//!
//! A calibration experiment (a shear box, a hopper discharge, a wall impact) is simulated by the
//! discrete element method a few hundred times across a box of contact and particle parameters.
//! Genetic programming turns those runs into one readable equation per response, the
//! *metamodel*, valid over the box. A new bulk material is then calibrated in seconds by
//! inverting the equations for its measurements (multi-start L-BFGS, optionally a TMCMC
//! posterior) instead of running the DEM again; one campaign serves every material in its box.
//!
//! # The pipeline
//!
//! From a space to a calibrated material, each stage a module:
//!
//! 1. [`space`]: the parameters to vary, their units, bounds and scales (`space.toml`), and their
//!    map to the unit cube.
//! 2. [`sampling`]: a space-filling design of the cube (FSSF, MIPT, Sobol, Halton, LHS, random),
//!    extendable without moving existing rows.
//! 3. [`psd`]: particle size distributions: sieve data, fitted distributions (their `d50` and
//!    `sigma_ln` become metamodel inputs), and particle sets drawn for a scene.
//! 4. [`experiments`]: the calibration experiments as DEM scenes that return named responses.
//! 5. [`campaign`]: an experiment run for every design row into a table that survives crashes,
//!    resumes, shards over Slurm array jobs and can run on LIGGGHTS instead ([`liggghts`]).
//! 6. [`metamodel`]: one equation per response fitted to the table by genetic programming, in
//!    dimensionless groups where the experiment declares them ([`similarity`]); a JSON model file.
//! 7. [`calibrate`]: the metamodel inverted for a [`material`]'s measurements: every distinct
//!    optimum, the solution set when the data cannot fix every parameter, and the posterior,
//!    evidence and model-class probabilities.
//! 8. [`diagnose`]: where a model fails on a set of measurements and which physical effect is
//!    missing; [`sensitivity`]: which inputs matter for which response.
//!
//! [`train`] runs stages 2, 5 and 6 as one resumable command (`mbgc train`); [`export`] writes the
//! equations as Rust, LaTeX or sympy; [`plot`] draws the figures; [`shipped`] holds the models
//! and the example material that mbgc carries with it.
//!
//! Functions take and return data: a [`metamodel::TrainingTable`] built in memory fits like one
//! read from a campaign table, and a [`calibrate::session::Session`] is plain data. Files are read
//! or written only where a function says so (`from_file`, `read_csv`, `save`, `train`), and
//! figures only when asked for. Errors ([`Error`]) name the file, the field and what was expected.
//! The DEM engine and the symbolic regression are re-exported as [`dem`] (the `mbgc-dem` crate)
//! and [`gp`] (the `mbgc-sr` crate), so one dependency reaches every stage.
//!
//! `ARCHITECTURE.md` at the repository root maps the source (crates, where each concept lives,
//! how to add an effect, an experiment or a sampler); the user guide is in `docs/guide/`.
//!
//! # Example: fit a metamodel
//!
//! Thirty rows of a response `y = 2 a + 1` stand in for a campaign table; a small, seeded GP
//! search (100 trees, 5 generations) recovers the line.
//!
//! ```
//! use mbgc::metamodel::{self, FitSettings, TrainingTable};
//!
//! let a: Vec<f64> = (0..30).map(|i| i as f64 / 29.0).collect();
//! let y: Vec<f64> = a.iter().map(|a| 2.0 * a + 1.0).collect();
//! let table = TrainingTable::from_columns("doc", vec![("a".into(), a), ("y".into(), y)])?;
//! let settings = FitSettings::new(vec!["a".into()], vec!["y".into()]).config(mbgc::gp::Config {
//!     population: 100,
//!     generations: 5,
//!     seed: 7,
//!     ..mbgc::gp::Config::default()
//! });
//! let fit = metamodel::fit(&table, &settings, |_, _| {})?;
//! let y_model = fit.model.response("y").expect("a fitted response");
//! assert!(y_model.train.r2 > 0.99, "train R^2 {}", y_model.train.r2);
//! println!("y = {}", y_model.equation);
//! # Ok::<(), mbgc::Error>(())
//! ```
//!
//! # Example: calibrate a material against it
//!
//! A material whose `y` was measured as 2.0 with a standard deviation of 0.05: inverting the
//! model (64 L-BFGS starts, the defaults of `mbgc calibrate`) gives `a = 0.5`, searched over the
//! model's domain [0, 1] since the material neither fixes nor bounds it.
//!
//! ```
//! use mbgc::calibrate::session::{self, SessionOptions};
//! use mbgc::material::Material;
//! # use mbgc::metamodel::{self, FitSettings, TrainingTable};
//! # let a: Vec<f64> = (0..30).map(|i| i as f64 / 29.0).collect();
//! # let y: Vec<f64> = a.iter().map(|a| 2.0 * a + 1.0).collect();
//! # let table = TrainingTable::from_columns("doc", vec![("a".into(), a), ("y".into(), y)])?;
//! # let settings = FitSettings::new(vec!["a".into()], vec!["y".into()]).config(mbgc::gp::Config {
//! #     population: 100,
//! #     generations: 5,
//! #     seed: 7,
//! #     ..mbgc::gp::Config::default()
//! # });
//! # let model = metamodel::fit(&table, &settings, |_, _| {})?.model;
//! // `model`: the metamodel fitted in the example above.
//! let text = "[measured]\ny = { value = 2.0, sd = 0.05 }\n";
//! let material = Material::from_toml_str(text, "doc.toml")?;
//! let result = session::run(&material, &model, "doc", &SessionOptions::default())?;
//! assert_eq!(result.free, ["a"]);
//! let best = result.best().x[0];
//! assert!((best - 0.5).abs() < 1e-3, "a = {best}");
//! assert!(result.best().chi2 < 1e-6);
//! # Ok::<(), mbgc::Error>(())
//! ```

#![warn(missing_docs)]

pub mod calibrate;
pub mod campaign;
pub mod constraint;
pub mod diagnose;
pub mod error;
pub mod experiments;
pub mod export;
pub mod liggghts;
pub mod material;
pub mod metamodel;
pub mod model_table;
pub mod numeric;
pub mod outputs;
pub mod plot;
pub mod propagate;
pub mod psd;
pub mod sampling;
pub mod sensitivity;
pub mod shipped;
pub mod similarity;
pub mod space;
pub mod train;

pub use error::{Error, Result};

/// The DEM engine (the `mbgc-dem` crate), re-exported so one dependency reaches every stage.
pub use mbgc_dem as dem;
/// Genetic-programming symbolic regression (the `mbgc-sr` crate), re-exported likewise.
pub use mbgc_sr as gp;

// The test stand-ins under `tests/stand_ins/` name the library `mbgc::` as any user would; the
// unit tests and the `stand-ins` feature include them, so inside the crate that name must
// resolve too.
#[cfg(any(test, feature = "stand-ins"))]
extern crate self as mbgc;
