//! The thread team against the serial path on a scene that exercises everything the team splits
//! or republishes: polydisperse spheres with EPSD2 rolling and cohesion, a moving lid (wall
//! motion and skin used up by a wall), neighbour-list rebuilds (particles reordered), a wall
//! removed and particles removed mid-run.

use mbgc::dem::contact::ModelClass;
use mbgc::dem::walls::box_planes;
use mbgc::dem::{Interaction, Materials, Particles, Scene, Simulation, Solid};
use rand::RngExt;

const LID: usize = 5;

fn scene() -> Scene {
    let mut m = Materials::new();
    let a = m
        .add(Solid {
            name: "grain".into(),
            youngs_modulus: 5e6,
            poisson: 0.3,
        })
        .unwrap();
    m.set_interaction(
        a,
        a,
        Interaction {
            restitution: 0.5,
            friction: 0.4,
            rolling_friction: 0.1,
            cohesion_energy_density: 2e3,
            ..Default::default()
        },
    )
    .unwrap();
    let mut rng = mbgc::sampling::rng(5);
    let mut p = Particles::new();
    for i in 0..7 {
        for j in 0..7 {
            for k in 0..8 {
                let x = [i, j, k].map(|c| 0.0025 + 0.005 * c as f64);
                let r = 0.0015 + 0.0008 * rng.random::<f64>();
                let id = p.add(x, r, 2500.0, 0).unwrap();
                p.v[id as usize] = std::array::from_fn(|_| rng.random::<f64>() - 0.5);
            }
        }
    }
    let mut walls = box_planes([0.0; 3], [0.035, 0.035, 0.045], 0);
    walls[LID].velocity = [0.0, 0.0, -0.2];
    Scene {
        particles: p,
        walls,
        materials: m,
        class: ModelClass::parse("hertz,mindlin,epsd2,sjkr").unwrap(),
        gravity: [0.0, 0.0, -9.81],
        dt: 2e-5,
        skin: 5e-4,
        domain: ([-0.01; 3], [0.05, 0.05, 0.1]),
        max_dt_fraction: 0.3,
        periodic: [false; 3],
    }
}

/// Largest coordinate difference between the two runs' particles (same order: the rebuilds sort
/// identically as long as the positions agree to far below a cell).
fn worst(a: &Simulation, b: &Simulation) -> f64 {
    a.particles
        .x
        .iter()
        .zip(&b.particles.x)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max)
}

fn same_counts(a: &Simulation, b: &Simulation) {
    assert_eq!(a.particles.len(), b.particles.len());
    assert_eq!(
        a.particles.id, b.particles.id,
        "same order after the rebuilds"
    );
    assert_eq!(a.contact_count(), b.contact_count());
    assert_eq!(a.neighbors.pairs(), b.neighbors.pairs());
    assert_eq!(a.neighbors.builds, b.neighbors.builds);
    assert_eq!((a.step, a.time), (b.step, b.time));
}

/// Three threads (more than the cores of a small machine, which also exercises the barriers'
/// yielding) follow the serial run to round-off. The team sums a particle's contact forces in
/// another order (the leader's contacts, then each buffer), so forces differ in the last bits,
/// about 1e-16 relative; over these 450 colliding steps that grows to a few units in the last
/// place of the positions (3e-17 m measured, on coordinates of order 1e-2 m whose last place is
/// 3.5e-18 m). Over thousands of steps the two would part, as any two granular trajectories
/// differing by round-off do. 1e-14 m leaves a wide margin for that growth and is still
/// 1e-11 of a radius, so a wrong or lost force, history or rebuild fails it.
#[test]
fn three_threads_follow_the_serial_run_through_rebuilds_and_removals() {
    let mut serial = Simulation::new(scene()).unwrap();
    let mut team = Simulation::new(scene()).unwrap();
    team.set_threads(3);
    let tol = 1e-14;

    let builds = serial.neighbors.builds;
    serial.run(300).unwrap();
    team.run(300).unwrap();
    assert!(
        serial.neighbors.builds >= builds + 5,
        "the lid and the flying spheres must force rebuilds: {}",
        serial.neighbors.builds - builds
    );
    assert!(serial.contact_count() > 20, "{}", serial.contact_count());
    same_counts(&serial, &team);
    let w = worst(&serial, &team);
    println!("largest position difference after the moving lid: {w:e} m");
    assert!(w < tol, "after the moving lid: {w:e} m");
    assert_ne!(
        serial.particles.f, team.particles.f,
        "the team must actually have run (its sums differ in the last bits)"
    );

    for s in [&mut serial, &mut team] {
        s.set_wall_active(LID, false);
        let top = s.particles.x.iter().map(|x| x[2]).fold(0.0, f64::max);
        let cut: Vec<bool> = s.particles.x.iter().map(|x| x[2] > top - 0.004).collect();
        assert!(s.remove_particles(&cut) > 10);
    }
    // Still enough particles for three members (64 each), so the team keeps running.
    assert!(team.particles.len() >= 3 * 64);
    let builds = serial.neighbors.builds;
    serial.run(151).unwrap();
    team.run(151).unwrap();
    assert!(
        serial.neighbors.builds >= builds + 2,
        "rebuilds after the removals"
    );
    same_counts(&serial, &team);
    let w = worst(&serial, &team);
    println!("largest position difference after the removals: {w:e} m");
    assert!(w < tol, "after the removals: {w:e} m");
}
