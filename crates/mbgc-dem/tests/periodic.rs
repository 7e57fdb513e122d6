//! Periodic boundaries and driven particles on small scenes: a collision across the boundary, a
//! periodic gas against a brute-force nearest-image count, a bed settled in a cell periodic in x
//! and y (serial and threaded), a driven particle under contact and gravity, a lid of driven
//! particles on a bed between driven floor particles, and the refusal of too short a period.

use mbgc_dem::contact::ModelClass;
use mbgc_dem::vec3::*;
use mbgc_dem::walls::box_planes;
use mbgc_dem::{BlowUp, Interaction, Materials, Particles, Scene, Simulation, Solid};
use rand::{RngExt, SeedableRng};

fn rng(seed: u64) -> rand_chacha::ChaCha8Rng {
    rand_chacha::ChaCha8Rng::seed_from_u64(seed)
}

fn materials(youngs: f64, i: Interaction) -> Materials {
    let mut m = Materials::new();
    let a = m
        .add(Solid {
            name: "grain".into(),
            youngs_modulus: youngs,
            poisson: 0.3,
        })
        .unwrap();
    m.set_interaction(a, a, i).unwrap();
    m
}

fn scene(particles: Particles, materials: Materials, periodic: [bool; 3]) -> Scene {
    Scene {
        particles,
        walls: Vec::new(),
        materials,
        class: ModelClass::default(),
        gravity: [0.0; 3],
        dt: 2e-5,
        skin: 2e-4,
        domain: ([0.0; 3], [0.02; 3]),
        max_dt_fraction: 0.3,
        periodic,
    }
}

/// Total momentum, kg m/s.
fn momentum(p: &Particles) -> V3 {
    let mut q = [0.0; 3];
    for i in 0..p.len() {
        add_assign(&mut q, scale(p.v[i], p.m[i]));
    }
    q
}

/// Touching pairs (count, summed overlap) by brute force over all pairs, nearest images in the
/// period box of `sim`.
fn brute_force_contacts(sim: &Simulation) -> (usize, f64) {
    let (p, b) = (&sim.particles, sim.periodic_box());
    let (mut count, mut overlap) = (0, 0.0);
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let d = b.min_image(sub(b.wrap(p.x[i]), b.wrap(p.x[j])));
            let s = p.r[i] + p.r[j];
            if norm2(d) < s * s {
                count += 1;
                overlap += s - norm(d);
            }
        }
    }
    (count, overlap)
}

/// The half-list invariants: rows of partners above the row, strictly ascending.
fn assert_half_list(sim: &Simulation) {
    let nl = &sim.neighbors;
    for i in 0..sim.particles.len() {
        let row = &nl.nb[nl.start[i] as usize..nl.start[i + 1] as usize];
        assert!(
            row.windows(2).all(|w| w[0] < w[1]) && row.iter().all(|&j| j as usize > i),
            "row {i}: {row:?}"
        );
    }
}

/// What a two-bead collision ends with: both velocities, both spins.
struct Rebound {
    out: [V3; 4],
    momentum: V3,
    builds: u64,
    /// Steps in contact with the left bead's centre in the right half of the box, and in the
    /// left half (before and after it is wrapped across x = L).
    touching_right: usize,
    touching_left: usize,
}

/// A bead hitting a resting one obliquely, with spin, so that the tangential and rolling
/// histories matter. `xa` is the centre of the moving bead; the other starts 2.002 r further
/// along x (through the boundary if that is beyond the box). A skin of 0.002 r rebuilds the list
/// every few steps, so the beads are wrapped and reordered while they touch.
fn collide(xa: f64, periodic: bool) -> Rebound {
    let r = 2e-3;
    let l = 0.05;
    let mut p = Particles::new();
    let xb = xa + 2.002 * r;
    let xb = if xb >= l { xb - l } else { xb };
    p.add([xa, 0.01, 0.01], r, 2500.0, 0).unwrap();
    p.add([xb, 0.01 + 0.4 * r, 0.01 - 0.1 * r], r, 2500.0, 0)
        .unwrap();
    p.v[0] = [0.2, 0.0, 0.0];
    p.v[1] = [0.0, 0.01, 0.0];
    p.w[0] = [0.0, 0.0, 20.0];
    p.w[1] = [5.0, 0.0, 0.0];
    let m = materials(
        5e7,
        Interaction {
            restitution: 0.6,
            friction: 0.4,
            rolling_friction: 0.2,
            ..Default::default()
        },
    );
    let mut s = scene(p, m, [periodic, false, false]);
    s.dt = 5e-6;
    s.skin = 0.002 * r;
    s.domain = ([0.0; 3], [l, 0.02, 0.02]);
    let mut sim = Simulation::new(s).unwrap();
    let (mut touching_right, mut touching_left) = (0, 0);
    for _ in 0..400 {
        sim.advance();
        if sim.contact_count() > 0 {
            let a = sim.particles.index_of_ids()[0];
            if sim.particles.x[a][0] > 0.5 * l {
                touching_right += 1;
            } else {
                touching_left += 1;
            }
        }
    }
    assert!(
        touching_right + touching_left > 20,
        "the beads must touch for a while"
    );
    let idx = sim.particles.index_of_ids();
    let p = &sim.particles;
    Rebound {
        out: [p.v[idx[0]], p.v[idx[1]], p.w[idx[0]], p.w[idx[1]]],
        momentum: momentum(p),
        builds: sim.neighbors.builds,
        touching_right,
        touching_left,
    }
}

#[test]
fn a_collision_across_the_boundary_rebounds_as_one_in_the_middle_of_the_box() {
    let (r, l) = (2e-3, 0.05);
    let middle = collide(0.5 * l - r, false);
    assert!(
        middle.out[0][0] < 0.5 * middle.out[1][0],
        "a collision: {:?}",
        middle.out
    );
    // The point of contact on the boundary x = L: the pair touches only through the image.
    let straddling = collide(l - r - 0.05 * r, true);
    assert!(straddling.touching_right > 20 && straddling.touching_left == 0);
    // The moving bead's centre crosses x = L while they touch (it travels about 0.05 r before
    // the contact, 0.015 r during it), and is wrapped by a rebuild.
    let crossing = collide(l - 0.05 * r, true);
    assert!(
        crossing.touching_right > 5 && crossing.touching_left > 5,
        "wrapped during the contact: {} steps before, {} after",
        crossing.touching_right,
        crossing.touching_left
    );
    for case in [&straddling, &crossing] {
        assert!(case.builds > 50, "rebuilds while touching: {}", case.builds);
        for (n, (a, b)) in case.out.iter().zip(&middle.out).enumerate() {
            // Velocities ~0.1 m/s, spins ~10 rad/s; the runs differ only in the round-off of
            // the positions (coordinates near 0.05, 0.025 or 0 m): 3e-14 m/s and 1e-11 rad/s
            // measured.
            let unit = if n < 2 { 0.1 } else { 10.0 };
            for k in 0..3 {
                assert!(
                    (a[k] - b[k]).abs() < 1e-10 * unit,
                    "bead {}: {a:?} vs {b:?} in the middle",
                    n % 2
                );
            }
        }
        let dq = sub(case.momentum, middle.momentum);
        assert!(norm(dq) < 1e-15, "{dq:?}");
    }
}

#[test]
fn a_periodic_gas_conserves_momentum_and_lists_each_nearest_pair_once() {
    let mut rng = rng(3);
    let l = 0.02;
    let mut p = Particles::new();
    // 200 beads of radius 0.8-1.2 mm on a jittered 6^3 lattice in a 20 mm box: 10 % solids.
    'fill: for i in 0..6 {
        for j in 0..6 {
            for k in 0..6 {
                if p.len() == 200 {
                    break 'fill;
                }
                let x = [i, j, k].map(|c| (c as f64 + 0.5) * l / 6.0 + 2e-4 * rng.random::<f64>());
                let id = p
                    .add(x, 8e-4 + 4e-4 * rng.random::<f64>(), 2500.0, 0)
                    .unwrap();
                p.v[id as usize] = std::array::from_fn(|_| rng.random::<f64>() - 0.4);
            }
        }
    }
    let mut s = scene(
        p,
        materials(
            5e6,
            Interaction {
                restitution: 0.8,
                friction: 0.3,
                ..Default::default()
            },
        ),
        [true; 3],
    );
    s.skin = 1e-4;
    let mut sim = Simulation::new(s).unwrap();
    let q0 = momentum(&sim.particles);
    let q_scale: f64 = (0..200)
        .map(|i| sim.particles.m[i] * norm(sim.particles.v[i]))
        .sum();
    assert!(norm(q0) > 0.1 * q_scale, "a net drift to conserve");
    let (mut contacts, mut across) = (0, 0);
    for _ in 0..40 {
        sim.run(25).unwrap();
        let (count, overlap) = brute_force_contacts(&sim);
        assert_eq!(
            sim.contact_count(),
            count,
            "the list finds every touching pair once"
        );
        let listed: f64 = sim.touching_pairs().map(|(_, _, d)| d).sum();
        assert!(
            (listed - overlap).abs() <= 1e-12 * overlap.max(1e-12),
            "{listed} vs {overlap}"
        );
        assert_half_list(&sim);
        contacts += count;
        let x = &sim.particles.x;
        across += sim
            .touching_pairs()
            .filter(|&(i, j, _)| (0..3).any(|k| (x[i][k] - x[j][k]).abs() > 0.5 * l))
            .count();
    }
    assert!(
        sim.neighbors.builds > 40,
        "many rebuilds: {}",
        sim.neighbors.builds
    );
    assert!(contacts > 20, "contacts seen: {contacts}");
    assert!(across > 0, "some contacts through the boundary: {across}");
    let dq = sub(momentum(&sim.particles), q0);
    assert!(
        norm(dq) < 1e-13 * q_scale,
        "momentum drift {dq:?} of {q0:?}"
    );
    // Every particle in the box, give or take the drift since the last rebuild.
    let half_skin = 0.5 * sim.neighbors.skin;
    for x in &sim.particles.x {
        assert!(
            x.iter().all(|&c| c > -half_skin && c < l + half_skin),
            "{x:?}"
        );
    }
}

/// 320 beads dropped onto a plane floor in a cell periodic in x and y (16 mm square).
fn bed_scene() -> Scene {
    let mut rng = rng(11);
    let l = 0.016;
    let mut p = Particles::new();
    for k in 0..5 {
        for j in 0..8 {
            for i in 0..8 {
                let x = [
                    (i as f64 + 0.5) * 0.002 + 1e-4 * (rng.random::<f64>() - 0.5),
                    (j as f64 + 0.5) * 0.002 + 1e-4 * (rng.random::<f64>() - 0.5),
                    0.0012 + 0.0022 * k as f64,
                ];
                let id = p
                    .add(x, 8e-4 + 1e-4 * rng.random::<f64>(), 2500.0, 0)
                    .unwrap();
                p.v[id as usize] = [0.05 * (rng.random::<f64>() - 0.5), 0.0, 0.0];
            }
        }
    }
    let floor = box_planes([0.0; 3], [l; 3], 0).swap_remove(4);
    assert_eq!(floor.name, "zlo");
    Scene {
        particles: p,
        walls: vec![floor],
        materials: materials(
            5e6,
            Interaction {
                restitution: 0.3,
                friction: 0.5,
                rolling_friction: 0.2,
                ..Default::default()
            },
        ),
        class: ModelClass::default(),
        gravity: [0.0, 0.0, -9.81],
        dt: 2e-5,
        skin: 2e-4,
        domain: ([0.0, 0.0, -0.001], [l, l, 0.03]),
        max_dt_fraction: 0.3,
        periodic: [true, true, false],
    }
}

#[test]
fn a_bed_settles_in_a_cell_periodic_in_x_and_y_and_the_team_follows_the_serial_run() {
    let mut serial = Simulation::new(bed_scene()).unwrap();
    let mut team = Simulation::new(bed_scene()).unwrap();
    team.set_threads(2);
    assert!(
        team.particles.len() >= 2 * 64,
        "enough particles for a team"
    );
    // Through the impact on the floor, with rebuilds: the team sums forces in another order,
    // which the colliding trajectories amplify (2e-16 m measured after these 1500 steps, 6e-11 m
    // after 2500); 1e-13 m is 1e-10 of a radius, so a lost or doubled force fails it.
    serial.run(1500).unwrap();
    team.run(1500).unwrap();
    assert_eq!(
        serial.particles.id, team.particles.id,
        "same order after the rebuilds"
    );
    assert_eq!(serial.contact_count(), team.contact_count());
    assert!(serial.contact_count() > 100, "{}", serial.contact_count());
    assert!(
        serial.neighbors.builds > 3,
        "rebuilds: {}",
        serial.neighbors.builds
    );
    let worst = serial
        .particles
        .x
        .iter()
        .zip(&team.particles.x)
        .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
        .fold(0.0, f64::max);
    assert!(worst < 1e-13, "team vs serial: {worst:e} m");
    assert!(
        serial.particles.f != team.particles.f,
        "the team must actually have run (its sums differ in the last bits)"
    );

    // Settle (serially: the team's path is checked above).
    for _ in 0..40 {
        serial
            .run(250)
            .expect("no particle leaves the periodic cell");
        if serial.kinetic_energy().0 < 1e-9 {
            break;
        }
    }
    let p = &serial.particles;
    let weight: f64 = p.m.iter().map(|m| m * 9.81).sum();
    let floor = serial.wall_force(0)[2];
    assert!(
        (-floor / weight - 1.0).abs() < 0.02,
        "the floor carries the bed: {floor} N vs {weight} N"
    );
    let l = 0.016;
    let x = &p.x;
    let across = serial
        .touching_pairs()
        .filter(|&(i, j, _)| (0..2).any(|k| (x[i][k] - x[j][k]).abs() > 0.5 * l))
        .count();
    assert!(across > 10, "contacts through the periodic faces: {across}");
    let top = x.iter().map(|x| x[2]).fold(0.0, f64::max);
    assert!(top < 0.012, "settled, not flying: top at {top}");
    // Removing particles keeps the list periodic.
    let cut: Vec<bool> = x.iter().map(|x| x[2] > top - 0.002).collect();
    assert!(serial.remove_particles(&cut) > 10);
    assert_eq!(serial.neighbors.periodic_box(), serial.periodic_box());
    assert_eq!(serial.periodic(), [true, true, false]);
    let (count, _) = brute_force_contacts(&serial);
    assert_eq!(serial.contact_count(), count);
    serial.run(100).unwrap();
}

#[test]
fn a_driven_particle_keeps_its_velocity_drifts_and_reports_its_contact_force() {
    let r = 1e-3;
    let mut p = Particles::new();
    // The driven bead comes in along x; the free one hangs just in its path, under gravity.
    let d = p.add([0.005, 0.01, 0.01], r, 2500.0, 0).unwrap() as usize;
    let f = p
        .add([0.005 + 2.01 * r, 0.01, 0.01 + 0.5 * r], r, 2500.0, 0)
        .unwrap() as usize;
    let v = [0.2, 0.0, 0.0];
    let w = [0.0, 3.0, -7.0];
    p.v[d] = v;
    p.w[d] = w;
    p.drive(d);
    assert!(p.driven[d] && !p.driven[f] && p.driven_count() == 1);
    assert_eq!((p.inv_m[d], p.inv_i[d]), (0.0, 0.0));
    let mut s = scene(p, materials(5e6, Interaction::default()), [false; 3]);
    s.gravity = [0.0, 0.0, -9.81];
    s.dt = 1e-5;
    let mut sim = Simulation::new(s).unwrap();
    let m_f = sim.particles.m[f];
    let x0 = sim.particles.x[d];
    let (mut touching, mut impulse) = (0, 0.0);
    for step in 1..=200 {
        sim.advance();
        let p = &sim.particles;
        let idx = p.index_of_ids();
        let (i, j) = (idx[d], idx[f]);
        assert_eq!(
            p.v[i], v,
            "step {step}: the driven velocity is kept exactly"
        );
        assert_eq!(p.w[i], w, "step {step}: the driven spin is kept exactly");
        let t = step as f64 * sim.dt;
        for k in 0..3 {
            assert!(
                (p.x[i][k] - (x0[k] + v[k] * t)).abs() < 1e-15,
                "drift at step {step}"
            );
        }
        // Contacts only on the driven bead (no gravity); equal and opposite on the free one.
        let contact_on_free = sub(p.f[j], scale(sim.gravity, m_f));
        assert!(
            norm(add(p.f[i], contact_on_free)) < 1e-12,
            "step {step}: {:?}",
            p.f[i]
        );
        if sim.contact_count() > 0 {
            touching += 1;
            impulse += p.f[i][0] * sim.dt;
        } else {
            assert_eq!(
                p.f[i], [0.0; 3],
                "no contact, no force: gravity is not in f"
            );
        }
    }
    assert!(touching > 5, "a contact happened: {touching} steps");
    let idx = sim.particles.index_of_ids();
    let vf = sim.particles.v[idx[f]];
    assert!(
        vf[0] > 0.2,
        "the free bead is knocked ahead, faster than the driver: {vf:?}"
    );
    // The force reported on the driver is what gave the free bead its momentum along x.
    assert!(
        (m_f * vf[0] + impulse).abs() < 0.02 * m_f * vf[0],
        "{} vs {}",
        m_f * vf[0],
        -impulse
    );
    // The driver's energy is not the scene's: only the free bead's counts.
    let ke = 0.5 * m_f * norm2(vf);
    assert!((sim.kinetic_energy().0 - ke).abs() < 1e-12 * ke);

    // A driven bead far faster than the speed limit, alone: no false blow-up, and its
    // prescribed motion is not energy growth.
    let mut p = Particles::new();
    p.add([0.001, 0.01, 0.01], r, 2500.0, 0).unwrap();
    p.add([0.01, 0.01, 0.002], r, 2500.0, 0).unwrap();
    p.drive(0);
    let mut sim =
        Simulation::new(scene(p, materials(5e6, Interaction::default()), [false; 3])).unwrap();
    let fast = 3.0 * sim.speed_limit;
    let i = sim.particles.index_of_ids()[0];
    sim.particles.v[i] = [fast, 0.0, 0.0];
    sim.run(20).expect("a driven bead is not a blow-up");
    let i = sim.particles.index_of_ids()[0];
    assert!((sim.particles.x[i][0] - (0.001 + fast * 20.0 * sim.dt)).abs() < 1e-12);
    // Released, it is a free bead again and the speed check sees it.
    sim.particles.release(i);
    assert!(!sim.particles.driven[i] && sim.particles.inv_m[i] > 0.0);
    match sim.run(5) {
        // Its kinetic energy is now the scene's, far beyond the budget.
        Err(BlowUp::TooFast { particle: 0, .. } | BlowUp::EnergyGrowth { .. }) => {}
        other => panic!("a released bead is checked again: {other:?}"),
    }
}

#[test]
fn a_lid_of_driven_particles_pressed_on_a_bed_balances_it_with_the_floor() {
    let mut rng = rng(21);
    let (l, d) = (0.016, 0.002);
    let mut p = Particles::new();
    let mut floor = Vec::new();
    let mut lid = Vec::new();
    let lattice = |i: usize, j: usize| [(i as f64 + 0.5) * d, (j as f64 + 0.5) * d];
    // Rough floor and lid: 8 x 8 beads of radius 1 mm on a square lattice of pitch 2 mm, held
    // by prescription; between them, 256 free beads of radius 0.75-0.9 mm.
    for j in 0..8 {
        for i in 0..8 {
            let [x, y] = lattice(i, j);
            floor.push(p.add([x, y, 0.001], 1e-3, 2500.0, 0).unwrap());
            lid.push(p.add([x, y, 0.0165], 1e-3, 2500.0, 0).unwrap());
        }
    }
    for k in 0..4 {
        for j in 0..8 {
            for i in 0..8 {
                let [x, y] = lattice(i, j);
                let x = [x + 1e-3, y + 1e-3, 0.0030 + 0.0022 * k as f64];
                let r = 7.5e-4 + 1.5e-4 * rng.random::<f64>();
                p.add(x, r, 2500.0, 0).unwrap();
            }
        }
    }
    for &id in floor.iter().chain(&lid) {
        p.drive(id as usize);
    }
    let z_floor = p.x[floor[0] as usize][2];
    let s = Scene {
        particles: p,
        walls: Vec::new(),
        materials: materials(
            5e6,
            Interaction {
                restitution: 0.3,
                friction: 0.5,
                rolling_friction: 0.2,
                ..Default::default()
            },
        ),
        class: ModelClass::default(),
        gravity: [0.0, 0.0, -9.81],
        dt: 2e-5,
        skin: 2e-4,
        domain: ([0.0, 0.0, -0.001], [l, l, 0.03]),
        max_dt_fraction: 0.3,
        periodic: [true, true, false],
    };
    let mut sim = Simulation::new(s).unwrap();
    sim.set_threads(2);
    let free_weight: f64 = (0..sim.particles.len())
        .filter(|&i| !sim.particles.driven[i])
        .map(|i| sim.particles.m[i] * 9.81)
        .sum();
    let sum_f = |sim: &Simulation, ids: &[u32]| -> V3 {
        let idx = sim.particles.index_of_ids();
        let mut total = [0.0; 3];
        for &id in ids {
            add_assign(&mut total, sim.particles.f[idx[id as usize]]);
        }
        total
    };
    let set_lid_velocity = |sim: &mut Simulation, v: V3| {
        let idx = sim.particles.index_of_ids();
        for &id in &lid {
            sim.particles.v[idx[id as usize]] = v;
        }
    };
    // Settle, then lower the lid until it presses with about the bed's weight, then hold it.
    sim.run(3000).unwrap();
    set_lid_velocity(&mut sim, [0.0, 0.0, -0.2]);
    let mut pressed = false;
    for _ in 0..400 {
        sim.run(20).unwrap();
        if sum_f(&sim, &lid)[2] > free_weight {
            pressed = true;
            break;
        }
    }
    assert!(pressed, "the lid reached the bed");
    set_lid_velocity(&mut sim, [0.0; 3]);
    for _ in 0..40 {
        sim.run(250).unwrap();
        if sim.kinetic_energy().0 < 1e-10 {
            break;
        }
    }
    let lid_force = sum_f(&sim, &lid)[2];
    let floor_force = sum_f(&sim, &floor)[2];
    println!("lid {lid_force} N, floor {floor_force} N, free weight {free_weight} N");
    assert!(
        lid_force > 0.3 * free_weight,
        "the lid still presses: {lid_force}"
    );
    // The floor carries the bed's weight plus the lid's push (contacts only on driven beads):
    // on the bed, -floor - lid - weight = 0.
    let residual = floor_force + lid_force + free_weight;
    assert!(
        residual.abs() < 0.03 * floor_force.abs(),
        "lid {lid_force} N + floor {floor_force} N vs the bed's weight {free_weight} N"
    );
    assert!(floor_force < -free_weight, "the floor pushes the bed up");
    // The prescribed layers moved only as prescribed: rigidly.
    let idx = sim.particles.index_of_ids();
    let z_lid = sim.particles.x[idx[lid[0] as usize]][2];
    for (&a, &b) in floor.iter().zip(&lid) {
        assert_eq!(sim.particles.x[idx[a as usize]][2], z_floor);
        assert_eq!(sim.particles.x[idx[b as usize]][2], z_lid);
    }
    assert!(z_lid < 0.0165, "the lid went down: {z_lid}");
}

#[test]
fn a_period_shorter_than_two_cutoffs_is_refused_naming_the_axis() {
    let mut p = Particles::new();
    p.add([0.001, 0.001, 0.001], 1e-3, 2500.0, 0).unwrap();
    let m = materials(5e6, Interaction::default());
    // Cutoff 2 r + skin = 2.2 mm: a period of 4 mm is too short along y, 20 mm along x is fine.
    let mut s = scene(p.clone(), m.clone(), [true, true, false]);
    s.domain = ([0.0; 3], [0.02, 0.004, 0.02]);
    let e = Simulation::new(s).err().expect("refused").to_string();
    assert!(
        e.contains("axis y") && e.contains("4.0000e-3") && e.contains("4.4000e-3"),
        "{e}"
    );
    // The same box periodic along x only is accepted, and along z the box is long enough.
    let mut s = scene(p.clone(), m.clone(), [true, false, true]);
    s.domain = ([0.0; 3], [0.02, 0.004, 0.02]);
    assert!(Simulation::new(s).is_ok());
    // A period that is no box at all.
    let mut s = scene(p.clone(), m.clone(), [false, false, true]);
    s.domain = ([0.0; 3], [0.02, 0.02, f64::INFINITY]);
    let e = Simulation::new(s).err().expect("refused").to_string();
    assert!(e.contains("axis z"), "{e}");
    // A particle outside the box along a periodic axis is wrapped in, not refused; along a
    // closed one it is refused.
    let mut q = p.clone();
    q.x[0] = [0.031, 0.001, 0.001];
    let sim = Simulation::new(scene(q.clone(), m.clone(), [true, false, false])).unwrap();
    assert!((sim.particles.x[0][0] - 0.011).abs() < 1e-15);
    assert!(Simulation::new(scene(q, m.clone(), [false, true, true])).is_err());
    // Inverse mass zeroed by hand without the driven flag: refused.
    let mut q = p;
    q.inv_m[0] = 0.0;
    let e = Simulation::new(scene(q, m, [false; 3]))
        .err()
        .expect("refused")
        .to_string();
    assert!(e.contains("driven"), "{e}");
}
