//! Campaigns: a calibration experiment run for every row of a design, into a table that survives
//! crashes, restarts and cluster job arrays.
//!
//! - [`registry`]: experiments by command-line name, built with [`ExperimentSettings`]
//!   (among them the [`backend`]: mbgc's engine or LIGGGHTS).
//! - [`plan`]: the design read and checked row by row, `--set` constants, `--shard`, run ids and
//!   seeds ([`identity`]).
//! - [`runner`]: worker threads, one appending writer, resume.
//! - [`columns`]: the table's column schema; [`table`]: its lines, and reading it back (incomplete last line).
//! - [`slurm`]: a campaign as a Slurm job array and its merge job.
//! - [`merge`](mod@merge) and [`status`](mod@status); [`decks`]: decks written for users who
//!   run the external code themselves, and their results imported.

pub mod backend;
pub mod columns;
pub mod decks;
pub mod identity;
pub mod lock;
pub mod merge;
pub mod observer;
pub mod plan;
pub mod registry;
pub mod runner;
pub mod slurm;
pub mod status;
pub mod table;

pub use backend::Backend;
pub use identity::{row_seed, run_id};
pub use merge::{merge, merge_tables, MergeSummary};
pub use observer::{Observer, ObserverHandle};
pub use plan::{parse_set, Plan, PlannedRun, Shard};
pub use registry::{experiment_by_name, experiment_names, ExperimentSettings};
pub use runner::{run_campaign, worker_threads, CampaignOptions, Summary};
pub use status::{meta_path, status, Meta, Status};
pub use table::{read_table, Table};
