//! The DEM engine alone (the `mbgc-dem` crate, re-exported as `mbgc::dem`): pour 200 glass
//! beads into a box, let them settle under gravity and report the packing. No experiment, no
//! campaign, no files.
//!
//!     cargo run --release --example dem_alone

use mbgc::dem::insertion::random_pack;
use mbgc::dem::timestep::rayleigh_time;
use mbgc::dem::walls::box_planes;
use mbgc::dem::{Interaction, Materials, ModelClass, Particles, Scene, Simulation, Solid};
use rand::SeedableRng;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // One solid for beads and walls: glass, softened to E = 5e7 Pa for a usable time step.
    let mut materials = Materials::new();
    let glass = materials.add(Solid {
        name: "glass".into(),
        youngs_modulus: 5e7,
        poisson: 0.25,
    })?;
    materials.set_interaction(
        glass,
        glass,
        Interaction {
            restitution: 0.5,
            friction: 0.5,
            rolling_friction: 0.1,
            ..Interaction::default()
        },
    )?;

    // 200 beads of 4-6 mm, placed without overlap in the upper part of a 50 mm box.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let diameters: Vec<f64> = (0..200)
        .map(|i| 0.004 + 0.002 * (i % 5) as f64 / 4.0)
        .collect();
    let centres = random_pack(&diameters, [0.0, 0.0, 0.02], [0.05, 0.05, 0.12], &mut rng)?;
    let mut particles = Particles::new();
    for (x, d) in centres.iter().zip(&diameters) {
        particles.add(*x, d / 2.0, 2500.0, glass)?;
    }
    let dt = 0.2 * rayleigh_time(0.002, 2500.0, 5e7, 0.25);
    let scene = Scene {
        particles,
        walls: box_planes([0.0; 3], [0.05, 0.05, 0.12], glass),
        materials,
        gravity: [0.0, 0.0, -9.81],
        dt,
        class: ModelClass::default(),
        // Half the smallest radius: few rebuilds, few false neighbours.
        skin: 0.001,
        domain: ([-0.01, -0.01, -0.01], [0.06, 0.06, 0.13]),
        max_dt_fraction: 0.25,
        periodic: [false; 3],
    };
    let mut sim = Simulation::new(scene)?;
    let steps = (0.5 / dt) as u64;
    sim.run(steps).map_err(|b| b.to_string())?;
    let top = sim
        .particles
        .x
        .iter()
        .zip(&sim.particles.r)
        .map(|(x, r)| x[2] + r)
        .fold(0.0, f64::max);
    let solid: f64 = sim
        .particles
        .r
        .iter()
        .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3))
        .sum();
    println!(
        "{} beads after {:.2} s ({steps} steps of {dt:.2e} s): bed height {:.1} mm, solid \
         fraction {:.3}, kinetic energy {:.2e} J",
        sim.particles.len(),
        sim.time,
        1e3 * top,
        solid / (0.05 * 0.05 * top),
        sim.kinetic_energy().0 + sim.kinetic_energy().1
    );
    Ok(())
}
