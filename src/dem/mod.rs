//! The embedded DEM engine.
//!
//! - [`particles`]: spheres in structure-of-arrays form.
//! - [`material`]: materials, interactions and the per-pair constants of the contact law.
//! - [`contact`]: the contact law as a sum of effects (Hertz-Mindlin as LIGGGHTS 3.8, EPSD2,
//!   power-law damped normal models of seed 003, simplified JKR cohesion).
//! - [`insertion`]: random sequential insertion of a poured cloud.
//! - [`walls`]: analytic planes, rectangles, cylinders and orifice plates.
//! - [`neighbor`]: cell grid, sorting, half Verlet list with contact history.
//! - [`sim`]: a simulation, its run loop and blow-up checks ([`blowup`]); [`step`]: the
//!   velocity-Verlet step, serial or by a thread team ([`team`]); [`timestep`]: the Rayleigh time.

pub mod analysis;
pub mod blowup;
pub mod contact;
pub mod experiments;
pub mod impact;
pub mod insertion;
pub mod material;
pub mod neighbor;
pub mod param_set;
pub mod particles;
pub mod sim;
mod step;
mod team;
pub mod timestep;
pub mod vec3;
pub mod vtk;
pub mod walls;

pub use blowup::BlowUp;
pub use contact::ModelClass;
pub use material::{Interaction, Material, Materials};
pub use particles::Particles;
pub use sim::{Scene, Simulation};
pub use walls::{Shape, Wall};
