//! Multi-threaded time stepping: a team of threads that lives for a whole chunk of steps, each
//! thread one member of the step kernel ([`super::step`]).
//!
//! A step is a few hundred microseconds, so waking pool threads for every parallel loop costs as
//! much as it saves (we measured rayon's per-step regions slower on 2 cores than 1 thread).
//! Instead T threads run the step loop together and meet at spin barriers, at the points the
//! kernel's phases require.
//!
//! A thread that panics must not leave the others spinning at a barrier forever: each thread
//! runs under `catch_unwind`, a panic poisons the barrier, whoever waits there leaves, and the
//! run ends with [`BlowUp::WorkerPanic`] carrying the panic message.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;

use super::blowup::BlowUp;
use super::contact::ContactLaw;
use super::step::{Abandoned, Board, Crew, Host, Plan};

/// Runs `plan` with `threads` threads; the calling thread is member 0.
pub(crate) fn run<H, L>(host: &mut H, law: &L, plan: Plan, threads: usize) -> Result<(), BlowUp>
where
    H: Host + Send,
    L: ContactLaw,
{
    let board = Board::new(host, law, plan, threads);
    let barrier = SpinBarrier::new(threads);
    let panicked: Mutex<Option<(usize, String)>> = Mutex::new(None);
    let member = |t: usize| {
        if let Err(payload) = catch_unwind(AssertUnwindSafe(|| board.member(t, &barrier))) {
            let message = panic_message(payload.as_ref());
            let mut first = panicked.lock().unwrap_or_else(|e| e.into_inner());
            first.get_or_insert((t, message));
            barrier.poison();
        }
    };
    std::thread::scope(|s| {
        for t in 1..threads {
            let member = &member;
            s.spawn(move || member(t));
        }
        member(0);
    });
    let panicked = panicked.into_inner().unwrap_or_else(|e| e.into_inner());
    let failure = board.into_failure();
    match panicked {
        Some((thread, message)) => Err(BlowUp::WorkerPanic {
            // The step in progress: the leader counts a step at its start.
            step: host.step_count(),
            thread,
            message,
        }),
        None => failure,
    }
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_string()
    }
}

struct SpinBarrier {
    count: AtomicUsize,
    generation: AtomicUsize,
    n: usize,
    /// Set when a member panicked: it will never arrive.
    poisoned: AtomicBool,
}

impl SpinBarrier {
    fn new(n: usize) -> Self {
        SpinBarrier {
            count: AtomicUsize::new(0),
            generation: AtomicUsize::new(0),
            n,
            poisoned: AtomicBool::new(false),
        }
    }

    fn poison(&self) {
        self.poisoned.store(true, Ordering::Release);
    }
}

impl Crew for SpinBarrier {
    fn meet(&self) -> Result<(), Abandoned> {
        let gen = self.generation.load(Ordering::Acquire);
        if self.count.fetch_add(1, Ordering::AcqRel) + 1 == self.n {
            self.count.store(0, Ordering::Relaxed);
            self.generation.fetch_add(1, Ordering::Release);
        } else {
            let mut spins = 0u32;
            while self.generation.load(Ordering::Acquire) == gen {
                if self.poisoned.load(Ordering::Acquire) {
                    return Err(Abandoned);
                }
                spins += 1;
                // A balanced wait is a few microseconds; past that, the member we wait for is
                // probably descheduled (more threads than free cores), and spinning on keeps it
                // off the core. 1000 spins is some microseconds; the earlier 20 000 cost about a
                // millisecond per meeting with three threads on two busy cores.
                if spins < 1_000 {
                    std::hint::spin_loop();
                } else {
                    std::thread::yield_now();
                }
            }
        }
        // A member that arrived last after a panic elsewhere must not go on alone.
        if self.poisoned.load(Ordering::Acquire) {
            return Err(Abandoned);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::contact::ModelClass;
    use crate::step::{FAIL_AT, NEAR_ALL, NO_BOUND};
    use crate::walls::box_planes;
    use crate::{BlowUp, Interaction, Materials, Particles, Scene, Simulation, Solid};
    use std::time::Duration;

    /// 216 spheres settling in a box: enough for a team of three.
    fn sim() -> Simulation {
        let mut m = Materials::new();
        let a = m
            .add(Solid {
                name: "g".into(),
                youngs_modulus: 5e6,
                poisson: 0.3,
            })
            .unwrap();
        m.set_interaction(a, a, Interaction::default()).unwrap();
        let mut p = Particles::new();
        for i in 0..6 {
            for j in 0..6 {
                for k in 0..6 {
                    let x = [i, j, k].map(|c| 0.0025 + 0.005 * c as f64);
                    p.add(x, 0.002, 2500.0, 0).unwrap();
                }
            }
        }
        Simulation::new(Scene {
            particles: p,
            walls: box_planes([0.0; 3], [0.03; 3], 0),
            materials: m,
            class: ModelClass::default(),
            gravity: [0.0, 0.0, -9.81],
            dt: 2e-5,
            skin: 5e-4,
            domain: ([-0.01; 3], [0.04; 3]),
            max_dt_fraction: 0.3,
            periodic: [false; 3],
        })
        .unwrap()
    }

    /// Runs with member `t` of `threads` panicking in step `s`; fails instead of hanging if the
    /// others never leave their barriers.
    fn run_failing(threads: usize, t: usize, s: u64) -> BlowUp {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut sim = sim();
            sim.set_threads(threads);
            FAIL_AT.with(|f| f.set(Some((t, s))));
            let _ = tx.send(sim.run(100));
        });
        match rx.recv_timeout(Duration::from_secs(60)) {
            Ok(r) => r.expect_err("the run must fail"),
            Err(_) => panic!("the team hung after member {t} of {threads} panicked"),
        }
    }

    #[test]
    fn a_panicking_member_ends_the_run_with_its_message() {
        for (threads, t, s) in [(3, 1, 7), (3, 2, 0), (2, 0, 60), (3, 0, 99)] {
            let e = run_failing(threads, t, s);
            let expected = format!("injected failure of member {t} in step {s}");
            match &e {
                BlowUp::WorkerPanic {
                    thread, message, ..
                } => {
                    assert_eq!(*thread, t);
                    assert_eq!(*message, expected);
                }
                other => panic!("expected a worker panic, got {other:?}"),
            }
            assert!(e.to_string().contains(&expected), "{e}");
        }
    }

    #[test]
    fn a_team_without_failure_runs_to_the_end() {
        let mut sim = sim();
        sim.set_threads(3);
        sim.run(120).unwrap();
        assert_eq!(sim.step, 120);
    }

    /// The state after a run as bits: positions, velocities and spins.
    fn bits(sim: &Simulation) -> Vec<u64> {
        let p = &sim.particles;
        (0..p.len())
            .flat_map(|i| p.x[i].into_iter().chain(p.v[i]).chain(p.w[i]))
            .map(f64::to_bits)
            .collect()
    }

    /// A run leaves a step's second half kick to the next step's first (`step::Board::member`);
    /// single steps (`advance`) never do. Both give the same bits, through the lattice's fall,
    /// impacts and list rebuilds.
    #[test]
    fn a_run_gives_the_bits_of_single_steps() {
        // Sideways and spinning starts (fixed, not random), so that impacts are oblique and
        // every kicked quantity (velocity and spin) matters.
        let start = || {
            let mut sim = sim();
            for (i, (v, w)) in sim
                .particles
                .v
                .iter_mut()
                .zip(&mut sim.particles.w)
                .enumerate()
            {
                let s = (i as f64 * 0.7).sin();
                *v = [0.3 * s, -0.2 * s, 0.1];
                *w = [20.0 * s, 0.0, -10.0 * s];
            }
            sim
        };
        let (mut run, mut single) = (start(), start());
        run.run(2000).unwrap();
        for _ in 0..2000 {
            single.advance();
        }
        assert!(
            run.neighbors.builds > 3,
            "only {} builds",
            run.neighbors.builds
        );
        assert!(run.contact_count() > 20, "{}", run.contact_count());
        assert!(
            bits(&run) == bits(&single),
            "the run differs from single steps"
        );
    }

    #[test]
    fn the_near_list_gives_the_whole_lists_results_to_the_bit() {
        // The lattice falls onto the floor and piles up: contacts open, close and slide, the
        // particles' speeds and with them their near skins vary, and the Verlet list is rebuilt
        // several times (which forces a near build) besides the near list's own rebuilds.
        for threads in [1, 3] {
            let run = |all: bool| {
                let mut sim = sim();
                sim.set_threads(threads);
                NEAR_ALL.with(|f| f.set(all));
                // In chunks, as experiments run: every run starts with a near build.
                for _ in 0..8 {
                    sim.run(250).unwrap();
                }
                NEAR_ALL.with(|f| f.set(false));
                assert!(
                    sim.neighbors.builds > 3,
                    "only {} list builds",
                    sim.neighbors.builds
                );
                bits(&sim)
            };
            let (near, whole) = (run(false), run(true));
            assert!(
                near == whole,
                "{threads} thread(s): the near list changed the run"
            );
        }
    }

    #[test]
    fn the_bound_on_displacements_changes_no_decision() {
        // The lattice falls and piles up: near skins widen and narrow with the speeds, and the
        // bound holds in some steps and not in others. Skipping the list's displacement check
        // where it holds must neither miss nor add a list build.
        for threads in [1, 3] {
            let run = |no_bound: bool| {
                let mut sim = sim();
                sim.set_threads(threads);
                NO_BOUND.with(|f| f.set(no_bound));
                let mut held = false;
                for _ in 0..8 {
                    sim.run(250).unwrap();
                    held |= sim.neighbors.near_bounded.is_some();
                }
                NO_BOUND.with(|f| f.set(false));
                (bits(&sim), sim.neighbors.builds, held)
            };
            let ((bounded, builds, held), (checked, builds_checked, _)) = (run(false), run(true));
            assert!(
                held,
                "{threads} thread(s): the bound never held, so nothing was tested"
            );
            assert!(builds > 3, "only {builds} list builds");
            assert_eq!(
                builds, builds_checked,
                "{threads} thread(s): list builds differ"
            );
            assert!(
                bounded == checked,
                "{threads} thread(s): the bound changed the run"
            );
        }
    }

    #[test]
    fn a_changed_skin_or_a_stopped_run_voids_the_bound() {
        use crate::step::Host;
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut sim = sim();
            sim.run(250).unwrap();
            let skin = sim.neighbors.skin;
            let held = sim.neighbors.near_bounded == Some(skin) && Host::params(&sim).near_bounded;
            // Proven for half the old skin, not the new one.
            sim.neighbors.skin = 0.5 * skin;
            let after_skin = Host::params(&sim).near_bounded;
            sim.neighbors.skin = skin;
            // A run stopped midway leaves near builds whose bound nobody recorded.
            sim.set_threads(2);
            FAIL_AT.with(|f| f.set(Some((1, 5))));
            let failed = sim.run(100).is_err();
            let _ = tx.send((held, after_skin, failed, sim.neighbors.near_bounded));
        });
        let (held, after_skin, failed, after_stop) = rx
            .recv_timeout(Duration::from_secs(60))
            .expect("the team hung");
        assert!(
            held,
            "the bound did not hold in the lattice at rest: nothing is tested"
        );
        assert!(!after_skin, "a smaller skin kept the bound");
        assert!(failed, "the injected failure did not stop the run");
        assert_eq!(after_stop, None, "a stopped run kept a bound");
    }
}
