//! Whole-simulation physics on small scenes: energy conservation without damping, a sphere at rest
//! on a plane, a rolling sphere stopped by EPSD2, and the guards against bad time steps and
//! blow-ups.

use mbgc::dem::contact::ModelClass;
use mbgc::dem::walls::box_planes;
use mbgc::dem::{Interaction, Materials, Particles, Scene, Shape, Simulation, Solid, Wall};
use rand::RngExt;

fn materials(e: f64, mu: f64, mu_r: f64, youngs: f64) -> Materials {
    let mut m = Materials::new();
    let a = m
        .add(Solid {
            name: "grain".into(),
            youngs_modulus: youngs,
            poisson: 0.3,
        })
        .unwrap();
    m.set_interaction(
        a,
        a,
        Interaction {
            restitution: e,
            friction: mu,
            rolling_friction: mu_r,
            ..Default::default()
        },
    )
    .unwrap();
    m
}

fn scene(
    particles: Particles,
    walls: Vec<Wall>,
    materials: Materials,
    class: ModelClass,
    gravity: [f64; 3],
    dt: f64,
    domain: ([f64; 3], [f64; 3]),
) -> Scene {
    Scene {
        particles,
        walls,
        materials,
        class,
        gravity,
        dt,
        skin: 1e-3,
        domain,
        max_dt_fraction: 0.3,
        periodic: [false; 3],
    }
}

/// 64 spheres of radius 4-6 mm at rest on a 20 mm grid from 10 mm.
fn grid_of_spheres(rng: &mut impl rand::Rng) -> Particles {
    let mut p = Particles::new();
    for i in 0..4 {
        for j in 0..4 {
            for k in 0..4 {
                let x = [
                    0.01 + 0.02 * i as f64,
                    0.01 + 0.02 * j as f64,
                    0.01 + 0.02 * k as f64,
                ];
                p.add(x, 0.004 + 0.002 * rng.random::<f64>(), 2500.0, 0)
                    .unwrap();
            }
        }
    }
    p
}

/// Elastic, frictionless spheres bouncing in a closed box without gravity: kinetic plus elastic
/// energy stays constant through hundreds of collisions.
#[test]
fn energy_is_conserved_without_damping() {
    let mut rng = mbgc::sampling::rng(11);
    let mut p = grid_of_spheres(&mut rng);
    for v in &mut p.v {
        *v = [
            rng.random::<f64>() - 0.5,
            rng.random::<f64>() - 0.5,
            rng.random::<f64>() - 0.5,
        ];
    }
    let lo = [0.0; 3];
    let hi = [0.08; 3];
    let walls = box_planes(lo, hi, 0);
    let model = ModelClass::from_names(&["hertz", "mindlin"]).unwrap();
    let mut sim = Simulation::new(scene(
        p,
        walls,
        materials(1.0, 0.0, 0.0, 1e7),
        model,
        [0.0; 3],
        1e-5,
        ([-0.01; 3], [0.09; 3]),
    ))
    .unwrap();
    let energy = |s: &Simulation| {
        let (t, r) = s.kinetic_energy();
        t + r + s.elastic_energy()
    };
    let e0 = energy(&sim);
    let mut contacts = 0;
    for _ in 0..100 {
        sim.run(200).unwrap();
        contacts += sim.contact_count();
        let e = energy(&sim);
        assert!((e - e0).abs() / e0 < 2e-4, "energy drifted: {e} vs {e0}");
    }
    assert!(
        contacts > 50,
        "the test must actually exercise collisions ({contacts})"
    );
}

/// A sphere dropped on a plane comes to rest with the Hertz overlap of its weight:
/// delta = (3 m g / (4 Y* sqrt R))^(2/3).
#[test]
fn sphere_comes_to_rest_on_a_plane_with_the_hertz_overlap() {
    let (r, rho, youngs, nu) = (0.005, 2500.0, 1e7, 0.3);
    let mut p = Particles::new();
    p.add([0.0, 0.0, r + 0.001], r, rho, 0).unwrap();
    let mut m = Materials::new();
    let a = m
        .add(Solid {
            name: "grain".into(),
            youngs_modulus: youngs,
            poisson: nu,
        })
        .unwrap();
    let w = m
        .add(Solid {
            name: "rigid".into(),
            youngs_modulus: 1e40,
            poisson: 0.0,
        })
        .unwrap();
    m.set_interaction(
        a,
        w,
        Interaction {
            restitution: 0.3,
            friction: 0.5,
            ..Default::default()
        },
    )
    .unwrap();
    m.set_interaction(a, a, Interaction::default()).unwrap();
    let plane = Wall::new(
        "floor",
        Shape::Plane {
            point: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
        },
        w,
    )
    .unwrap();
    let mut sim = Simulation::new(scene(
        p,
        vec![plane],
        m,
        ModelClass::default(),
        [0.0, 0.0, -9.81],
        2e-5,
        ([-1.0; 3], [1.0; 3]),
    ))
    .unwrap();
    sim.run(50_000).unwrap();
    let mass = sim.particles.m[0];
    let y_eff = youngs / (1.0 - nu * nu);
    let want = (3.0 * mass * 9.81 / (4.0 * y_eff * r.sqrt())).powf(2.0 / 3.0);
    let got = r - sim.particles.x[0][2];
    println!("rest overlap {got:.6e}, Hertz {want:.6e}");
    assert!((got - want).abs() / want < 0.01, "{got} vs {want}");
    assert!(sim.particles.v[0][2].abs() < 1e-4);
}

/// A sphere rolling on a plane is stopped by the EPSD2 rolling resistance M = mu_r R m g: it
/// decelerates at mu_r g / 1.4 and stops after 0.7 v0^2 / (mu_r g).
#[test]
fn rolling_sphere_stops_where_epsd2_says() {
    let (r, v0, mu_r) = (0.005, 0.5, 0.1);
    let mut p = Particles::new();
    p.add([0.0, 0.0, r], r, 2500.0, 0).unwrap();
    let mut m = materials(0.5, 0.5, mu_r, 1e7);
    let w = m
        .add(Solid {
            name: "rigid".into(),
            youngs_modulus: 1e40,
            poisson: 0.0,
        })
        .unwrap();
    m.set_interaction(
        0,
        w,
        Interaction {
            restitution: 0.5,
            friction: 0.5,
            rolling_friction: mu_r,
            ..Default::default()
        },
    )
    .unwrap();
    let plane = Wall::new(
        "floor",
        Shape::Plane {
            point: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
        },
        w,
    )
    .unwrap();
    let mut sim = Simulation::new(scene(
        p,
        vec![plane],
        m,
        ModelClass::from_names(&["hertz", "mindlin", "epsd2"]).unwrap(),
        [0.0, 0.0, -9.81],
        5e-5,
        ([-1.0; 3], [2.0; 3]),
    ))
    .unwrap();
    // Let it settle onto the plane first, then start it rolling without slip.
    sim.run(4000).unwrap();
    let x0 = sim.particles.x[0][0];
    sim.particles.v[0] = [v0, 0.0, 0.0];
    sim.particles.w[0] = [0.0, v0 / r, 0.0];
    let want = 0.7 * v0 * v0 / (mu_r * 9.81);
    let mut stop = None;
    let mut late_speed: f64 = 0.0;
    for step in 0..200_000 {
        sim.advance();
        let v = sim.particles.v[0][0];
        if stop.is_none() && v <= 0.0 {
            stop = Some(sim.particles.x[0][0] - x0);
        }
        if step > 190_000 {
            late_speed = late_speed.max(v.abs());
        }
    }
    let got = stop.expect("the sphere must stop");
    println!("stopping distance {got:.5} m, theory {want:.5} m; speed at the end {late_speed:.2e}");
    assert!((got - want).abs() / want < 0.03, "{got} vs {want}");
    assert!(
        late_speed < 5e-3,
        "it must stay (nearly) at rest: {late_speed}"
    );
}

#[test]
fn a_time_step_above_the_rayleigh_limit_is_refused() {
    let mut p = Particles::new();
    p.add([0.0, 0.0, 0.01], 0.005, 2500.0, 0).unwrap();
    let s = scene(
        p,
        vec![],
        materials(0.5, 0.5, 0.0, 1e7),
        ModelClass::default(),
        [0.0; 3],
        1e-3,
        ([-1.0; 3], [1.0; 3]),
    );
    let e = Simulation::new(s).err().expect("must refuse").to_string();
    assert!(e.contains("Rayleigh"), "{e}");
}

#[test]
fn a_run_that_blows_up_is_flagged_not_returned() {
    // Two strongly overlapping spheres with a time step far beyond the stable one.
    let mut p = Particles::new();
    p.add([0.0, 0.0, 0.0], 0.005, 2500.0, 0).unwrap();
    p.add([0.005, 0.0, 0.0], 0.005, 2500.0, 0).unwrap();
    let mut s = scene(
        p,
        vec![],
        materials(0.9, 0.5, 0.0, 1e9),
        ModelClass::default(),
        [0.0; 3],
        2e-4,
        ([-0.1; 3], [0.1; 3]),
    );
    s.max_dt_fraction = 100.0;
    let mut sim = Simulation::new(s).unwrap();
    let r = sim.run(1000);
    assert!(r.is_err(), "expected a blow-up, got {:?}", sim.particles.x);
    println!("{}", r.unwrap_err());
}

#[test]
fn effects_are_chosen_by_name() {
    use mbgc::dem::contact::{CohesionKind, NormalKind, RollingKind, TangentialKind};
    let m = ModelClass::parse("tsuji,mindlin,epsd2,sjkr").unwrap();
    assert_eq!(m.normal, NormalKind::Tsuji);
    assert_eq!(m.tangential, TangentialKind::Mindlin);
    assert_eq!(m.rolling, RollingKind::Epsd2);
    assert_eq!(m.cohesion, CohesionKind::Sjkr);
    assert_eq!(m.to_string(), "tsuji,mindlin,epsd2,sjkr");
    assert_eq!(ModelClass::parse(&m.label()).unwrap(), m);
    assert_eq!(
        ModelClass::parse("hertz, mindlin ,epsd2").unwrap(),
        ModelClass::default()
    );
    assert_eq!(
        ModelClass::parse("hertz,mindlin,no-rolling,no-cohesion").unwrap(),
        ModelClass::parse("hertz,mindlin").unwrap()
    );
    for (bad, want) in [
        ("hertz,mindlin,jkr-full", "unknown effect `jkr-full`"),
        ("hertz,tsuji,mindlin", "both a normal force"),
        ("mindlin,epsd2", "no normal force"),
        ("hertz,epsd2", "no tangential force"),
        ("hertz,mindlin,epsd2,cdt", "both a rolling resistance"),
        ("hertz,,mindlin", "empty name"),
        ("tsuji,mindlin,limit-force", "limit-force"),
        ("hertz,mindlin,none", "unknown effect `none`"),
        (
            "hertz,mindlin,epsd2,no-rolling",
            "both a rolling resistance",
        ),
        ("hertz,mindlin,limit-force,limit-force", "named twice"),
    ] {
        let e = ModelClass::parse(bad).unwrap_err().to_string();
        assert!(e.contains(want), "{bad}: {e}");
    }
}

/// The thread team computes the same forces as the serial loop; only the order of the force sums
/// differs. Both runs reach the same contact-rich state serially (bit for bit), then one goes on
/// with two threads: over a short window the trajectories agree to round-off. (Over thousands of
/// colliding steps they part, as any two granular trajectories differing by round-off do.)
#[test]
fn threaded_run_matches_the_serial_run() {
    let spec = mbgc_studies::dem_scene::BenchSpec {
        particles: 400,
        box_hi: [0.06, 0.06, 0.12],
        ..Default::default()
    };
    let (x, r) = mbgc_studies::dem_scene::initial_packing(&spec).unwrap();
    let mut serial =
        Simulation::new(mbgc_studies::dem_scene::scene(&spec, &x, &r).unwrap()).unwrap();
    let mut team = Simulation::new(mbgc_studies::dem_scene::scene(&spec, &x, &r).unwrap()).unwrap();
    serial.run(15000).unwrap();
    team.run(15000).unwrap();
    assert_eq!(
        serial.particles.x, team.particles.x,
        "serial runs are deterministic"
    );
    assert!(
        serial.contact_count() > 200,
        "the scene must be in contact: {}",
        serial.contact_count()
    );
    team.set_threads(2);
    serial.run(200).unwrap();
    team.run(200).unwrap();
    let mut worst: f64 = 0.0;
    for (pa, pb) in serial.particles.x.iter().zip(&team.particles.x) {
        worst = worst.max((0..3).map(|k| (pa[k] - pb[k]).abs()).fold(0.0, f64::max));
    }
    println!("largest position difference after 200 threaded steps: {worst:.3e} m");
    assert!(worst < 1e-12, "{worst}");
    assert_eq!(serial.step, team.step);
    assert_ne!(
        serial.particles.v, team.particles.v,
        "the team path must actually have run"
    );
}

/// Removing particles keeps the others' contacts (and their history) and changes nothing else.
#[test]
fn removing_particles_keeps_the_rest_of_the_packing() {
    let spec = mbgc_studies::dem_scene::BenchSpec {
        particles: 300,
        box_hi: [0.06, 0.06, 0.12],
        ..Default::default()
    };
    let (x, r) = mbgc_studies::dem_scene::initial_packing(&spec).unwrap();
    let mut sim = Simulation::new(mbgc_studies::dem_scene::scene(&spec, &x, &r).unwrap()).unwrap();
    sim.run(15000).unwrap();
    let top = sim.particles.x.iter().map(|x| x[2]).fold(0.0, f64::max);
    let contacts_below = |s: &Simulation| {
        let mut c = 0;
        for i in 0..s.particles.len() {
            for e in s.neighbors.start[i] as usize..s.neighbors.start[i + 1] as usize {
                let j = s.neighbors.nb[e] as usize;
                let d = s.particles.r[i] + s.particles.r[j];
                let dx: f64 = (0..3)
                    .map(|k| (s.particles.x[i][k] - s.particles.x[j][k]).powi(2))
                    .sum();
                if dx < d * d
                    && s.particles.x[i][2] < top - 0.03
                    && s.particles.x[j][2] < top - 0.03
                    && !s.neighbors.hist[e].is_zero()
                {
                    c += 1;
                }
            }
        }
        c
    };
    let before = contacts_below(&sim);
    let n0 = sim.particles.len();
    let cut: Vec<bool> = sim.particles.x.iter().map(|x| x[2] > top - 0.01).collect();
    let removed = sim.remove_particles(&cut);
    assert!(removed > 0 && sim.particles.len() == n0 - removed);
    assert_eq!(
        contacts_below(&sim),
        before,
        "contacts with history away from the cut survive"
    );
    sim.run(500).unwrap();
}

/// A bed of 64 spheres settles in a frictionless box: the floor carries its whole weight and the
/// walls' forces balance, measured by `Simulation::wall_force` (the servo and the stresses of
/// the shear cell rest on it).
#[test]
fn the_floor_carries_the_weight_of_a_settled_bed() {
    let mut rng = mbgc::sampling::rng(12);
    let p = grid_of_spheres(&mut rng);
    let weight: f64 = p.m.iter().sum::<f64>() * 9.81;
    let lo = [0.0; 3];
    let hi = [0.08, 0.08, 0.2];
    let walls = box_planes(lo, hi, 0);
    let model = ModelClass::from_names(&["hertz", "mindlin"]).unwrap();
    let mut sim = Simulation::new(scene(
        p,
        walls,
        materials(0.3, 0.0, 0.0, 1e7),
        model,
        [0.0, 0.0, -9.81],
        2e-5,
        ([-0.01; 3], [0.09, 0.09, 0.21]),
    ))
    .unwrap();
    // A clone is an independent copy, histories included: both go on exactly alike.
    sim.run(3_000).unwrap();
    let mut twin = sim.clone();
    sim.run(2_000).unwrap();
    twin.run(2_000).unwrap();
    assert_eq!(sim.particles.x, twin.particles.x);
    sim.run(55_000).unwrap();
    let (t, _) = sim.kinetic_energy();
    assert!(t < 1e-9, "not settled: {t} J");
    let floor = (0..sim.walls.len())
        .find(|&w| matches!(sim.walls[w].shape, Shape::Plane { normal, .. } if normal[2] > 0.5))
        .unwrap();
    let f = sim.wall_force(floor);
    assert!(
        (f[2] + weight).abs() < 1e-3 * weight,
        "{f:?} vs weight {weight}"
    );
    let mut total = [0.0; 3];
    for w in 0..sim.walls.len() {
        let fw = sim.wall_force(w);
        for k in 0..3 {
            total[k] += fw[k];
        }
    }
    // The walls hold the bed: their forces add up to its weight, sideways to nothing.
    assert!(
        total[0].abs() < 1e-3 * weight && total[1].abs() < 1e-3 * weight,
        "{total:?}"
    );
    assert!((total[2] + weight).abs() < 1e-3 * weight, "{total:?}");
    // An inactive wall carries nothing.
    sim.set_wall_active(floor, false);
    assert_eq!(sim.wall_force(floor), [0.0; 3]);
}

/// A wall placed onto a settled bed takes load at once (its lists are rebuilt), and a shape of
/// another kind is refused.
#[test]
fn a_placed_wall_touches_what_lies_at_its_new_place() {
    let mut rng = mbgc::sampling::rng(13);
    let p = grid_of_spheres(&mut rng);
    let top =
        p.x.iter()
            .zip(&p.r)
            .map(|(x, r)| x[2] + r)
            .fold(0.0, f64::max);
    let mut walls = box_planes([0.0; 3], [0.08, 0.08, 0.3], 0);
    let lid = |z: f64| Shape::Rect {
        center: [0.04, 0.04, z],
        u: [1.0, 0.0, 0.0],
        v: [0.0, 1.0, 0.0],
        half_u: 0.04,
        half_v: 0.04,
    };
    walls.push(Wall::new("lid", lid(0.25), 0).unwrap());
    let n = walls.len() - 1;
    let mut sim = Simulation::new(scene(
        p,
        walls,
        materials(0.3, 0.3, 0.0, 1e7),
        ModelClass::from_names(&["hertz", "mindlin"]).unwrap(),
        [0.0; 3],
        2e-5,
        ([-0.01; 3], [0.09, 0.09, 0.31]),
    ))
    .unwrap();
    sim.run(10).unwrap();
    assert_eq!(sim.wall_force(n), [0.0; 3]);
    // Pressed 0.5 mm into the top spheres.
    sim.place_wall(n, lid(top - 5e-4)).unwrap();
    let f = sim.wall_force(n);
    assert!(f[2] > 0.0, "{f:?}");
    let plane = Shape::Plane {
        point: [0.0; 3],
        normal: [0.0, 0.0, 1.0],
    };
    let e = sim.place_wall(n, plane).unwrap_err().to_string();
    assert!(e.contains("lid") && e.contains("another kind"), "{e}");
}
