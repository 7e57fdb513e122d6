//! The embedded DEM engine of mbgc: soft spheres with the Hertz-Mindlin contact law as
//! LIGGGHTS 3.8 implements it, integrated by velocity Verlet, for the bulk experiments (shear
//! box, hopper, wall impact) whose responses mbgc's metamodels learn.
//!
//! It is a library of physics only. It reads and writes no files (a VTK snapshot is returned as
//! text by [`vtk::to_vtk`]; the caller decides where it goes), parses no configuration, and knows
//! nothing of experiments, sampling designs or metamodels: those live in `mbgc`, which builds a
//! [`Scene`] and reads the particles back. It handles spheres only (no clumps or polyhedra) and
//! runs on one machine (threads, not MPI). Its errors ([`Error`]) name the offending parameter
//! and the range expected.
//!
//! The domain can be periodic along any of its axes ([`Scene::periodic`], [`periodic`]); walls
//! then bound it along the others only. Particles can be driven ([`Particles::drive`]): moved at
//! the velocity the caller sets, whatever the forces, with the contact forces on them still
//! summed, so that glued layers of them make rough floors and servo-controlled rough lids.
//!
//! Entry points: describe the solids and their pair interactions in [`Materials`], the effects of
//! the contact law in a [`ModelClass`] (e.g. `ModelClass::parse("hertz,mindlin,epsd2")`), place
//! [`Particles`] (by hand or with [`insertion::random_pack`]) and [`Wall`]s in a [`Scene`], then
//! [`Simulation::new`] checks it (time step against the Rayleigh time of [`timestep`]) and
//! [`Simulation::run`] advances it, returning a [`BlowUp`] instead of numbers when the
//! integration fails. [`impact::run_impact`] runs single-contact verification impacts and
//! [`analysis`] measures settled beds.
//!
//! - [`particles`]: spheres in structure-of-arrays form.
//! - [`material`]: materials, interactions and the per-pair constants of the contact law.
//! - [`contact`]: the contact law as a sum of effects (Hertz-Mindlin as LIGGGHTS 3.8, EPSD2,
//!   power-law damped normal models of seed 003, simplified JKR cohesion).
//! - [`insertion`]: random sequential insertion of a poured cloud.
//! - [`walls`]: analytic planes, rectangles, cylinders and orifice plates.
//! - [`neighbor`]: cell grid, sorting, half Verlet list with contact history (and the storage
//!   of the step's near list of the pairs that can touch soon, built by the private `near`).
//! - [`periodic`]: the period box, wrapping and nearest images.
//! - [`sim`]: a simulation, its run loop and blow-up checks ([`blowup`]); the velocity-Verlet
//!   step, serial or by a team of threads, is private to the crate; [`timestep`]: the Rayleigh
//!   time.
//!
//! # Example: a head-on collision of two beads
//!
//! Two glass-like beads (radius 2 mm) approach at 0.1 m/s each without gravity. The Hertz
//! contact pushes them apart, the pair's momentum is conserved to round-off (every contact force
//! acts equally and oppositely on both), and the rebound speed is the coefficient of restitution
//! times the impact speed.
//!
//! ```
//! use mbgc_dem::{Interaction, Materials, ModelClass, Particles, Scene, Simulation, Solid};
//!
//! let mut materials = Materials::new();
//! let glass = materials.add(Solid {
//!     name: "glass".into(),
//!     youngs_modulus: 5e7, // Pa: a softened modulus, as DEM calibrations use
//!     poisson: 0.25,
//! })?;
//! let e = 0.5;
//! materials.set_interaction(glass, glass, Interaction { restitution: e, ..Interaction::default() })?;
//!
//! let (r, rho) = (2e-3, 2500.0); // m, kg/m^3
//! let mut particles = Particles::new();
//! particles.add([-1.001 * r, 0.0, 0.0], r, rho, glass)?;
//! particles.add([1.001 * r, 0.0, 0.0], r, rho, glass)?;
//! particles.v[0] = [0.1, 0.0, 0.0];
//! particles.v[1] = [-0.1, 0.0, 0.0];
//!
//! let t_r = mbgc_dem::timestep::rayleigh_time(r, rho, 5e7, 0.25);
//! let mut sim = Simulation::new(Scene {
//!     particles,
//!     walls: Vec::new(),
//!     materials,
//!     class: ModelClass::parse("hertz,mindlin,epsd2")?,
//!     gravity: [0.0; 3],
//!     dt: 0.1 * t_r, // about 40 steps per contact
//!     skin: 0.5 * r,
//!     domain: ([-0.1; 3], [0.1; 3]),
//!     max_dt_fraction: 0.25,
//!     periodic: [false; 3],
//! })?;
//! sim.run(500).expect("no blow-up");
//!
//! // The engine sorts particles in memory; `id` keeps the insertion order.
//! let idx = sim.particles.index_of_ids();
//! let (v0, v1) = (sim.particles.v[idx[0]][0], sim.particles.v[idx[1]][0]);
//! assert!(v0 < 0.0 && v1 > 0.0, "the beads repel: {v0} {v1}");
//! let m = &sim.particles.m;
//! let momentum = m[idx[0]] * v0 + m[idx[1]] * v1;
//! assert!(momentum.abs() < 1e-12 * m[0] * 0.1, "momentum conserved: {momentum}");
//! // Restitution: separation speed over approach speed (within the time discretisation).
//! assert!(((v1 - v0) / 0.2 - e).abs() < 0.01, "rebound at the restitution");
//! # Ok::<(), mbgc_dem::Error>(())
//! ```

#![warn(missing_docs)]

pub mod analysis;
pub mod blowup;
pub mod contact;
pub mod error;
pub mod impact;
pub mod insertion;
mod kick;
pub mod material;
mod near;
pub mod neighbor;
pub mod param_set;
pub mod particles;
pub mod periodic;
pub mod sim;
mod step;
mod team;
pub mod timestep;
pub mod vec3;
pub mod vtk;
pub mod walls;

pub use blowup::BlowUp;
pub use contact::ModelClass;
pub use material::{Interaction, Materials, Solid};
pub use particles::Particles;
pub use periodic::PeriodicBox;
pub use sim::{Scene, Simulation};
pub use walls::{Shape, Wall};

pub use error::{Error, Result};

/// The seeded generator of the engine's tests: ChaCha8 from a 64-bit seed, the generator the
/// rest of mbgc uses, so that a test's packing is the one the library would draw.
#[cfg(test)]
pub(crate) fn test_rng(seed: u64) -> rand_chacha::ChaCha8Rng {
    use rand::SeedableRng;
    rand_chacha::ChaCha8Rng::seed_from_u64(seed)
}
