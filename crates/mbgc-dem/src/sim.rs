//! A simulation: the scene's state, the run loop (serial, or a thread team), neighbour list
//! upkeep, particle removal, and the checks that turn a blown-up run into an error instead of
//! numbers. The step itself (velocity Verlet with rotation, as LIGGGHTS `fix nve/sphere`) is in
//! the crate-private `step` module.

pub use super::blowup::BlowUp;
use super::contact::{History, ModelClass};
use super::material::Materials;
use super::neighbor::NeighborList;
use super::particles::Particles;
use super::periodic::PeriodicBox;
use super::step::{self, Host, Params, Plan, Raw};
use super::team;
use super::timestep::rayleigh_time;
use super::vec3::*;
use super::walls::{Shape, Wall};
use crate::error::{Error, Result};
use crate::with_law;

/// Everything that defines a run; [`Simulation::new`] checks it and takes it over.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The spheres and their initial velocities.
    pub particles: Particles,
    /// The walls, in the order [`Simulation::set_wall_active`] indexes them.
    pub walls: Vec<Wall>,
    /// The solids and an interaction for every pair of materials that can meet.
    pub materials: Materials,
    /// The effects of the contact law.
    pub class: ModelClass,
    /// Gravitational acceleration, m/s^2 (`[0, 0, -9.81]` on earth; zero for impact tests).
    pub gravity: V3,
    /// Time step, s; at most `max_dt_fraction` of the Rayleigh time of the smallest particle.
    pub dt: f64,
    /// Neighbour skin, m (> 0): see [`NeighborList::skin`].
    pub skin: f64,
    /// Particles outside this box (lo, hi) make the run fail: they have left the experiment.
    /// Along a periodic axis it is the period box instead, and leaving it is no failure.
    pub domain: (V3, V3),
    /// Per axis (x, y, z), whether the domain box `domain` is periodic along it; the period is
    /// `domain.1[k] - domain.0[k]` and must exceed twice the largest neighbour cutoff,
    /// 2 (2 r_max + skin). A particle leaving the box through one face comes back through the
    /// opposite one, and pairs interact through their nearest images.
    ///
    /// Walls do not know about periodicity: a plane is infinite and a finite wall has no image
    /// across the box. Bound a periodic domain along its other axes only (e.g. Plane walls
    /// normal to z for a cell periodic in x and y), or with rough layers of driven particles
    /// ([`Particles::drive`]).
    pub periodic: [bool; 3],
    /// Largest accepted dt as a fraction of the Rayleigh time (dimensionless; 0.2..0.3 is usual,
    /// seed 004 runs at 0.25). A guard against a mistyped step, not a stability proof: Hertz
    /// contacts at high impact speed can need less.
    pub max_dt_fraction: f64,
}

/// A running simulation: the scene's state, its neighbour lists and contact histories, the step
/// count and the limits of its blow-up checks.
///
/// The particle arrays are reordered at every neighbour-list rebuild; look particles up by
/// [`Particles::id`] (e.g. through [`Particles::index_of_ids`]) rather than by index.
///
/// A clone is an independent copy of the state, contact histories included: an experiment can
/// branch several tests from one prepared sample (the shear cell's failure points from one
/// pre-sheared state).
#[derive(Clone)]
pub struct Simulation {
    /// The spheres' current state.
    pub particles: Particles,
    /// The walls' current state (moving walls are advanced every step).
    pub walls: Vec<Wall>,
    /// Materials and pair constants (with the `limit-force` damping solved if the class uses it).
    pub materials: Materials,
    /// The effects of the contact law.
    pub class: ModelClass,
    /// Gravitational acceleration, m/s^2.
    pub gravity: V3,
    /// Time step, s.
    pub dt: f64,
    /// Box (lo, hi), m, outside which a particle makes the run fail ([`BlowUp::LeftDomain`]);
    /// along periodic axes it is the period box, fixed at [`Simulation::new`] (changing it here
    /// does not change the period).
    pub domain: (V3, V3),
    /// Pair list and the pair contact histories.
    pub neighbors: NeighborList,
    /// Contact history of every particle with every wall: `[i * n_walls + w]`.
    pub wall_hist: Vec<History>,
    /// Steps taken since [`Simulation::new`].
    pub step: u64,
    /// Simulated time since [`Simulation::new`], s (`step` times `dt`).
    pub time: f64,
    /// Speed beyond which a particle signals a blow-up, m/s: ten times the free-fall speed over
    /// the domain diagonal plus the fastest wall and the fastest initial particle, plus 1 m/s.
    /// [`Simulation::check`] adds ten times the current speed of the fastest driven particle.
    pub speed_limit: f64,
    /// Energy the scene starts with (kinetic, elastic, and potential down to the domain floor,
    /// driven particles' kinetic and potential energy left out); without moving walls or driven
    /// particles, cohesion, or gravity along a periodic axis, the kinetic energy can never
    /// exceed it.
    pub energy_budget: f64,
    /// Per wall, the particles within reach of it (r + skin) at the last list build.
    pub(crate) wall_nb: Vec<Vec<u32>>,
    /// How far each wall has moved since the last list build.
    pub(crate) wall_moved: Vec<f64>,
    threads: usize,
    pbox: PeriodicBox,
}

impl Simulation {
    /// Checks the scene and prepares the run. Refuses a time step above `max_dt_fraction` of the
    /// Rayleigh time of the smallest particle.
    pub fn new(scene: Scene) -> Result<Simulation> {
        let Scene {
            particles,
            walls,
            mut materials,
            class,
            gravity,
            dt,
            skin,
            domain,
            max_dt_fraction,
            periodic,
        } = scene;
        if class.limit_force {
            materials.prepare_limit_force();
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::invalid(format!(
                "time step must be positive, found {dt}"
            )));
        }
        if !(skin.is_finite() && skin > 0.0) {
            return Err(Error::invalid(format!(
                "neighbour skin must be positive, found {skin}"
            )));
        }
        let n_mat = materials.count() as u16;
        if let Some(&m) = particles
            .material
            .iter()
            .chain(walls.iter().map(|w| &w.material))
            .find(|&&m| m >= n_mat)
        {
            return Err(Error::invalid(format!("material {m} is not defined")));
        }
        let mut pairs: Vec<(u16, u16)> = Vec::new();
        let mut pm: Vec<u16> = particles.material.clone();
        pm.sort_unstable();
        pm.dedup();
        for &a in &pm {
            for &b in &pm {
                pairs.push((a, b));
            }
            for w in &walls {
                pairs.push((a, w.material));
            }
        }
        materials.check_complete(pairs.into_iter())?;
        if !particles.is_empty() {
            let t_r = (0..particles.len())
                .map(|i| {
                    let mat = &materials.materials[particles.material[i] as usize];
                    rayleigh_time(
                        particles.r[i],
                        particles.density(i),
                        mat.youngs_modulus,
                        mat.poisson,
                    )
                })
                .fold(f64::INFINITY, f64::min);
            if dt > max_dt_fraction * t_r {
                return Err(Error::invalid(format!(
                    "time step {dt:.3e} s is {:.1} % of the Rayleigh time {t_r:.3e} s of the smallest \
                     particle; the limit is {:.0} %",
                    100.0 * dt / t_r,
                    100.0 * max_dt_fraction
                )));
            }
        }
        const AXES: [&str; 3] = ["x", "y", "z"];
        let Some(pbox) = PeriodicBox::new(domain, periodic) else {
            let k = (0..3)
                .find(|&k| {
                    let l = domain.1[k] - domain.0[k];
                    periodic[k] && !(l.is_finite() && l > 0.0 && domain.0[k].is_finite())
                })
                .unwrap_or(0);
            return Err(Error::invalid(format!(
                "periodic axis {}: the domain must span a positive, finite period, found {} to {}",
                AXES[k], domain.0[k], domain.1[k]
            )));
        };
        // Minimum image: no pair may come within the cutoff through two images at once.
        let r_max = particles.r.iter().copied().fold(0.0, f64::max);
        let min_period = 2.0 * (2.0 * r_max + skin);
        for k in (0..3).filter(|&k| periodic[k]) {
            let l = domain.1[k] - domain.0[k];
            if l <= min_period {
                return Err(Error::invalid(format!(
                    "periodic axis {}: the period {l:.4e} m must exceed twice the largest \
                     neighbour cutoff, 2 (2 r_max + skin) = {min_period:.4e} m",
                    AXES[k]
                )));
            }
        }
        // The step tells driven particles by their zero inverse mass.
        if let Some(i) = (0..particles.len()).find(|&i| {
            let (a, b) = (particles.inv_m[i], particles.inv_i[i]);
            if particles.driven[i] {
                a != 0.0 || b != 0.0
            } else {
                !(a > 0.0 && b > 0.0)
            }
        }) {
            return Err(Error::invalid(format!(
                "particle {i}: its driven flag and its inverse mass and inertia disagree (set them \
                 through Particles::drive and Particles::release)"
            )));
        }
        for (i, x) in particles.x.iter().enumerate() {
            // Along periodic axes the first rebuild wraps it in.
            if !inside(*x, domain, periodic) {
                return Err(Error::invalid(format!(
                    "particle {i} starts outside the domain at {x:?}"
                )));
            }
        }
        // Fastest a particle could move: free fall across the domain, plus the fastest wall, with
        // a wide margin. Beyond it, energy is being created.
        let diag = norm(sub(domain.1, domain.0));
        let wall_speed = walls.iter().map(|w| norm(w.velocity)).fold(0.0, f64::max);
        let v0 = particles.v.iter().map(|v| norm(*v)).fold(0.0, f64::max);
        let speed_limit = 10.0 * ((2.0 * norm(gravity) * diag).sqrt() + wall_speed + v0) + 1.0;
        let n_walls = walls.len();
        let wall_hist = vec![History::default(); particles.len() * n_walls];
        let mut sim = Simulation {
            particles,
            walls,
            materials,
            class,
            gravity,
            dt,
            domain,
            neighbors: NeighborList::with_periodic(skin, pbox),
            wall_hist,
            step: 0,
            time: 0.0,
            speed_limit,
            energy_budget: 0.0,
            wall_nb: vec![Vec::new(); n_walls],
            wall_moved: vec![0.0; n_walls],
            threads: 1,
            pbox,
        };
        sim.rebuild_lists();
        sim.compute_forces();
        let floor = sim.domain.0;
        // Driven particles cannot turn their height into motion.
        let potential: f64 = (0..sim.particles.len())
            .filter(|&i| !sim.particles.driven[i])
            .map(|i| {
                -sim.particles.m[i] * dot(sim.gravity, sub(sim.particles.x[i], floor)).min(0.0)
            })
            .sum::<f64>()
            .abs();
        let (kt, kr) = sim.kinetic_energy();
        sim.energy_budget = kt + kr + sim.elastic_energy() + potential;
        Ok(sim)
    }

    /// Number of threads for [`Simulation::run`] (1 = serial; 0 is taken as 1). More threads
    /// form a team that lives for the whole run and meets at spin barriers; scenes with fewer
    /// than 64 particles per thread run serially, where the barriers would cost more than the
    /// split saves. Results differ from the serial run by round-off only (the order of force
    /// sums).
    pub fn set_threads(&mut self, threads: usize) {
        self.threads = threads.max(1);
    }

    /// Per axis, whether the domain is periodic along it ([`Scene::periodic`]).
    pub fn periodic(&self) -> [bool; 3] {
        self.pbox.periodic()
    }

    /// The period box ([`PeriodicBox::NONE`] without periodic axes).
    pub fn periodic_box(&self) -> PeriodicBox {
        self.pbox
    }

    /// The separation x_i - x_j of particles `i` and `j` (current indices), m: the nearest
    /// image along periodic axes. Stress and fabric sums over pairs must use it, not the raw
    /// difference of positions.
    pub fn separation(&self, i: usize, j: usize) -> V3 {
        let x = &self.particles.x;
        self.pbox
            .min_image(sub(self.pbox.wrap(x[i]), self.pbox.wrap(x[j])))
    }

    /// The number of threads set by [`Simulation::set_threads`].
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// Advances `steps` time steps, checking for blow-ups every 50 steps and after the last.
    pub fn run(&mut self, steps: u64) -> std::result::Result<(), BlowUp> {
        let plan = Plan {
            steps,
            check_every: Some(50),
        };
        let model = self.class;
        let threads = self.threads;
        // Below some particles per thread, the barriers cost more than the split saves.
        if threads > 1 && self.particles.len() >= 64 * threads {
            return with_law!(model, |law| team::run(self, &law, plan, threads));
        }
        with_law!(model, |law| step::run_alone(self, &law, plan))
    }

    /// One velocity-Verlet step, without the blow-up checks.
    pub fn advance(&mut self) {
        let plan = Plan {
            steps: 1,
            check_every: None,
        };
        let model = self.class;
        with_law!(model, |law| step::run_alone(self, &law, plan))
            .expect("a step without checks cannot fail");
    }

    /// Rebuilds the pair list (sorting the particles) and the wall lists.
    pub(crate) fn rebuild_lists(&mut self) {
        let n_walls = self.walls.len();
        self.neighbors
            .rebuild(&mut self.particles, &mut self.wall_hist, n_walls);
        let skin = self.neighbors.skin;
        let p = &self.particles;
        for (wi, w) in self.walls.iter().enumerate() {
            let list = &mut self.wall_nb[wi];
            list.clear();
            if w.active {
                list.extend(
                    (0..p.len())
                        .filter(|&i| w.gap(p.x[i], p.r[i] + skin).is_some())
                        .map(|i| i as u32),
                );
            }
            self.wall_moved[wi] = 0.0;
        }
    }

    /// Removes the particles whose flag in `remove` (one per particle, current order) is set:
    /// material struck off a fill, or that has left an experiment. The contact history of the
    /// remaining pairs is kept. Returns the number removed.
    pub fn remove_particles(&mut self, remove: &[bool]) -> usize {
        let n = self.particles.len();
        assert_eq!(remove.len(), n, "one flag per particle");
        let keep: Vec<bool> = remove.iter().map(|r| !r).collect();
        let removed = keep.iter().filter(|k| !**k).count();
        if removed == 0 {
            return 0;
        }
        let p = &self.particles;
        let nl = &self.neighbors;
        let mut carried = std::collections::HashMap::new();
        for i in 0..n {
            for e in nl.start[i] as usize..nl.start[i + 1] as usize {
                let j = nl.nb[e] as usize;
                if keep[i] && keep[j] && !nl.hist[e].is_zero() {
                    carried.insert((p.id[i], p.id[j]), nl.hist[e]);
                }
            }
        }
        let n_walls = self.walls.len();
        let mut k = 0;
        self.wall_hist.retain(|_| {
            let i = k / n_walls.max(1);
            k += 1;
            keep[i]
        });
        self.particles.retain(&keep);
        self.neighbors = NeighborList::with_periodic(self.neighbors.skin, self.pbox);
        self.rebuild_lists();
        let p = &self.particles;
        let nl = &mut self.neighbors;
        for i in 0..p.len() {
            for e in nl.start[i] as usize..nl.start[i + 1] as usize {
                let j = nl.nb[e] as usize;
                if let Some(h) = carried.get(&(p.id[i], p.id[j])) {
                    nl.hist[e] = *h;
                    nl.live[e] = 1;
                } else if let Some(h) = carried.get(&(p.id[j], p.id[i])) {
                    nl.hist[e] = History {
                        shear: scale(h.shear, -1.0),
                        rolling: scale(h.rolling, -1.0),
                    };
                    nl.live[e] = 1;
                }
            }
        }
        removed
    }

    /// Removes (or restores) a wall; its contact history is cleared.
    pub fn set_wall_active(&mut self, wall: usize, active: bool) {
        self.walls[wall].active = active;
        let n_walls = self.walls.len();
        for i in 0..self.particles.len() {
            self.wall_hist[i * n_walls + wall] = History::default();
        }
        self.rebuild_lists();
    }

    /// Puts wall `w` at a new place (a lid lowered onto a settled bed), ends its contacts and
    /// rebuilds the lists, so that no particle within its new reach goes unlisted. Refuses a
    /// shape of another kind or one that [`Wall::new`] refuses.
    pub fn place_wall(&mut self, w: usize, shape: Shape) -> Result<()> {
        let old = &self.walls[w];
        if std::mem::discriminant(&old.shape) != std::mem::discriminant(&shape) {
            return Err(Error::invalid(format!(
                "wall {}: placed with a shape of another kind",
                old.name
            )));
        }
        let placed = Wall::new(&old.name, shape, old.material)?;
        self.walls[w].shape = placed.shape;
        let n_walls = self.walls.len();
        for i in 0..self.particles.len() {
            self.wall_hist[i * n_walls + w] = History::default();
        }
        self.rebuild_lists();
        Ok(())
    }

    pub(crate) fn positions_finite(&self) -> bool {
        self.particles
            .x
            .iter()
            .all(|x| x.iter().all(|c| c.is_finite()))
    }

    /// Looks for NaN, particles outside the domain (along non-periodic axes) and impossible
    /// speeds. Driven particles are not held to the speed limit (their speed is the caller's);
    /// the fastest of them raises the free particles' limit as a wall's speed does, and a moving
    /// one, like a moving wall, feeds energy in, so the energy check is then off.
    pub fn check(&self) -> std::result::Result<(), BlowUp> {
        let p = &self.particles;
        let mut driven_speed2 = 0.0f64;
        let mut driven_moving = false;
        for i in (0..p.len()).filter(|&i| p.driven[i]) {
            driven_speed2 = driven_speed2.max(norm2(p.v[i]));
            driven_moving |= p.v[i] != [0.0; 3] || p.w[i] != [0.0; 3];
        }
        // Gravity along a periodic axis does work without end (a chute flow).
        let gravity_periodic = (0..3).any(|k| self.pbox.is_periodic(k) && self.gravity[k] != 0.0);
        let closed = self.walls.iter().all(|w| w.velocity == [0.0; 3])
            && self.class.cohesion == super::contact::CohesionKind::None
            && !driven_moving
            && !gravity_periodic;
        if closed {
            let (kt, kr) = self.kinetic_energy();
            // A wide margin: this is a guard against runaway integration, not a balance.
            if kt + kr > 1.5 * self.energy_budget + 1e-12 {
                return Err(BlowUp::EnergyGrowth {
                    step: self.step,
                    kinetic: kt + kr,
                    budget: self.energy_budget,
                });
            }
        }
        let lim = self.speed_limit + 10.0 * driven_speed2.sqrt();
        let lim2 = lim * lim;
        let periodic = self.pbox.periodic();
        for i in 0..p.len() {
            let (x, v) = (p.x[i], p.v[i]);
            if !(x.iter().chain(&v).all(|c| c.is_finite())) {
                return Err(BlowUp::NotFinite {
                    step: self.step,
                    particle: p.id[i],
                });
            }
            if !inside(x, self.domain, periodic) {
                return Err(BlowUp::LeftDomain {
                    step: self.step,
                    particle: p.id[i],
                    position: x,
                });
            }
            if norm2(v) > lim2 && !p.driven[i] {
                return Err(BlowUp::TooFast {
                    step: self.step,
                    particle: p.id[i],
                    speed: norm(v),
                });
            }
        }
        Ok(())
    }

    /// Recomputes all forces and torques (gravity, contacts, walls; contacts only for driven
    /// particles).
    pub fn compute_forces(&mut self) {
        let g = self.gravity;
        let p = &mut self.particles;
        for i in 0..p.len() {
            p.f[i] = scale(g, if p.driven[i] { 0.0 } else { p.m[i] });
            p.t[i] = [0.0; 3];
        }
        let model = self.class;
        with_law!(model, |law| step::add_contact_forces(self, &law));
    }

    /// The force the particles exert on wall `w` now, N (zero for an inactive wall): minus the
    /// sum of its contact forces, computed from the current positions, velocities and contact
    /// histories. A tangential spring is taken one increment on from the force the last step
    /// applied, so this is the force the next step applies, not the last one.
    pub fn wall_force(&self, w: usize) -> V3 {
        let model = self.class;
        with_law!(model, |law| step::wall_force(
            &law,
            &self.materials,
            self.dt,
            &self.walls[w],
            &self.particles,
            &self.wall_nb[w],
            &self.wall_hist,
            (self.walls.len(), w),
        ))
    }

    /// Kinetic energy (translational, rotational) of the free particles, J; driven particles
    /// are left out (see [`Particles::translational_energy`]).
    pub fn kinetic_energy(&self) -> (f64, f64) {
        (
            self.particles.translational_energy(),
            self.particles.rotational_energy(),
        )
    }

    /// Gravitational potential energy -sum m g.x relative to the origin, J (positions as stored:
    /// along a periodic axis they jump by a period when wrapped).
    pub fn potential_energy(&self) -> f64 {
        let p = &self.particles;
        (0..p.len())
            .map(|i| -p.m[i] * dot(self.gravity, p.x[i]))
            .sum()
    }

    /// Touching particle pairs as (i, j, overlap in m), current indices, from the neighbour list
    /// (so only as current as its last rebuild's candidate pairs, which the skin guarantees);
    /// nearest images along periodic axes. Pairs of two driven particles are not contacts (the
    /// step skips them) and are left out.
    pub fn touching_pairs(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        let p = &self.particles;
        let nl = &self.neighbors;
        let pbox = self.pbox;
        (0..p.len()).flat_map(move |i| {
            (nl.start[i] as usize..nl.start[i + 1] as usize).filter_map(move |e| {
                let j = nl.nb[e] as usize;
                let s = p.r[i] + p.r[j];
                let d2 = norm2(pbox.min_image(sub(p.x[i], p.x[j])));
                (d2 < s * s && !(p.driven[i] && p.driven[j])).then(|| (i, j, s - d2.sqrt()))
            })
        })
    }

    /// Elastic energy of the Hertz normal springs, (8/15) Y* sqrt(R*) delta^(5/2) per contact
    /// (particle pairs and active walls), J. The tangential and rolling springs are not counted.
    pub fn elastic_energy(&self) -> f64 {
        let p = &self.particles;
        let pairs: f64 = self
            .touching_pairs()
            .map(|(i, j, d)| {
                let r_eff = p.r[i] * p.r[j] / (p.r[i] + p.r[j]);
                let y = self.materials.pair(p.material[i], p.material[j]).y_eff;
                8.0 / 15.0 * y * r_eff.sqrt() * d.powf(2.5)
            })
            .sum();
        let mut walls = 0.0;
        for i in 0..p.len() {
            for w in self.walls.iter().filter(|w| w.active) {
                if let Some(g) = w.gap(p.x[i], p.r[i]) {
                    let d = p.r[i] - g.distance;
                    let y = self.materials.pair(p.material[i], w.material).y_eff;
                    walls += 8.0 / 15.0 * y * p.r[i].sqrt() * d.powf(2.5);
                }
            }
        }
        pairs + walls
    }

    /// Number of touching particle-particle contacts.
    pub fn contact_count(&self) -> usize {
        self.touching_pairs().count()
    }
}

fn inside(x: V3, (lo, hi): (V3, V3), periodic: [bool; 3]) -> bool {
    (0..3).all(|k| periodic[k] || (x[k] >= lo[k] && x[k] <= hi[k]))
}

impl Host for Simulation {
    fn params(&self) -> Params {
        Params {
            dt: self.dt,
            gravity: self.gravity,
            skin: self.neighbors.skin,
            near_fresh: self.neighbors.near_fresh,
            // A skin changed since (it is public) voids the bound.
            near_bounded: self.neighbors.near_bounded == Some(self.neighbors.skin),
        }
    }

    fn views(&mut self) -> Raw {
        Raw::new(
            &mut self.particles,
            &mut self.neighbors,
            &mut self.wall_hist,
            &self.walls,
            &self.wall_nb,
            &self.materials,
        )
    }

    fn move_walls(&mut self) -> f64 {
        step::move_walls(&mut self.walls, &mut self.wall_moved, self.dt)
    }

    fn rebuild_if_finite(&mut self) {
        if self.positions_finite() {
            self.rebuild_lists();
        }
    }

    fn tick(&mut self) {
        self.step += 1;
        self.time += self.dt;
    }

    fn step_count(&self) -> u64 {
        self.step
    }

    fn check(&self) -> std::result::Result<(), BlowUp> {
        Simulation::check(self)
    }

    fn near_done(&mut self, bounded: bool) {
        self.neighbors.near_fresh = true;
        self.neighbors.near_bounded = bounded.then_some(self.neighbors.skin);
    }

    fn forget_bound(&mut self) {
        self.neighbors.near_bounded = None;
    }
}
