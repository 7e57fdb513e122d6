//! `mbgc train`: sample -> simulate -> fit in one resumable command. Every stage keeps its state
//! in the files it writes (a design, a campaign table, a model), so a killed train resumes where
//! it stopped, a larger `n` extends the design sequentially and simulates only the new rows, and
//! the simulate stage can be sharded over machines and merged with `mbgc campaign merge`.
//!
//! Layout under the output directory, for a name `<name>`:
//! `sampling/<name>.csv` (training design), `sampling/<name>_validation.csv` (a separate random
//! design, never trained on), `training_data/<name>.csv` and `<name>_validation.csv` (campaign
//! tables), `training_data/<name>.train.json` (what produced them), `models/<name>.json` with
//! `.rs` and `.tex` exports and `models/<name>_figures/`.

pub mod extend;
mod pipeline;
mod stages;

pub use pipeline::{
    train, Silent, TrainObserver, TrainOutcome, TrainRequest, TrainStage, MAX_RUNS,
};
pub use stages::{
    ensure_design, fit_inputs, plan, samplers, seeds, space_parameters, ExtendsRecord, TrainPaths,
    TrainRecord,
};
