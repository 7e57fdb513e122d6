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
use super::contact::{Cohesion, Law, NormalForce, Rolling};
use super::step::{Abandoned, Board, Crew, Host, Plan};

/// Runs `plan` with `threads` threads; the calling thread is member 0.
pub(crate) fn run<H, N, C, R>(
    host: &mut H,
    law: &Law<N, C, R>,
    plan: Plan,
    threads: usize,
) -> Result<(), BlowUp>
where
    H: Host + Send,
    N: NormalForce,
    C: Cohesion,
    R: Rolling,
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
                if spins < 20_000 {
                    std::hint::spin_loop();
                } else {
                    // Oversubscribed machine: let the thread we wait for run.
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
