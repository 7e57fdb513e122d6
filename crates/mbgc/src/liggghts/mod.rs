//! Everything that speaks to LIGGGHTS-PUBLIC 3.8, the DEM code of seed 004 (Debian package
//! `liggghts`): decks written from mbgc scenes, the executable found and run, its logs and dumps
//! read back. The studies use it to compare mbgc's engine with LIGGGHTS on identical
//! configurations; it depends on the DEM engine's types, never the other way round.
//!
//! - [`binary`]: find and run the executable.
//! - [`closed_box`]: spheres settling in a closed box of six planes (the throughput scene).
//! - [`shear_box`]: the shear box replaying a recorded mbgc run.
//! - [`shear_box_fill`]: the shear box filling itself, mbgc's procedure in LIGGGHTS' own words;
//!   [`fill_run`] reads such a run back; [`shear_box_experiment`] makes it the shear-box
//!   experiment of `mbgc simulate --backend liggghts`.
//! - [`shear_cell`]: the shear cell (pour, loaded lid, pre-shear, three failure tests from a
//!   restart) as one deck; [`shear_cell_experiment`] makes it the shear-cell experiment of
//!   `mbgc simulate --backend liggghts`.
//! - [`session`]: a LIGGGHTS process driven command by command, its timed runs alternating
//!   with the caller's.
//! - [`mesh`]: STL walls; [`number`]: numbers as LIGGGHTS reads them; [`parse`]: logs, dumps.

pub mod binary;
pub mod closed_box;
pub mod fill_run;
pub mod mesh;
pub mod number;
pub mod parse;
pub mod session;
pub mod shear_box;
pub mod shear_box_experiment;
pub mod shear_box_fill;
pub mod shear_cell;
pub mod shear_cell_experiment;

pub use binary::{find_binary, require_binary, require_mpirun, run_deck, run_deck_on};
pub use closed_box::{LiggghtsCase, LiggghtsResult};
pub use parse::{parse_dump, parse_dump_rows, parse_log, LogSummary};
