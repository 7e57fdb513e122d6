//! Multi-threaded time stepping with a team of threads that lives for a whole chunk of steps.
//!
//! A step is a few hundred microseconds, so waking pool threads for every parallel loop costs as
//! much as it saves (we measured rayon's per-step regions slower on 2 cores than 1 thread).
//! Instead T threads run the step loop together and meet at spin barriers:
//!
//! 1. each thread kicks and drifts its own particle range and measures how far its particles
//!    moved since the list build; thread 0 moves the walls. Barrier. If the skin is used up,
//!    thread 0 rebuilds the lists while the others wait at a second barrier.
//! 2. each thread computes the contacts of its rows of the half list (balanced by entries) and
//!    the wall contacts of its particles; thread 0 accumulates into the particle forces (reset to
//!    gravity by their owners in phase 1), the others into their own buffers, which they clear
//!    only from the lowest index they can write. Barrier.
//! 3. each thread adds the buffers into its particles' forces and applies the second half kick.
//!    No barrier: the next step's first phase touches only the thread's own particles.
//!
//! Results differ from the serial path only by the order of floating-point sums.

use std::cell::UnsafeCell;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use super::contact::{Cohesion, History, Law, NormalForce, Rolling};
use super::sim::{pair_rows, wall_contacts, BlowUp, Simulation, WallView, P};
use super::vec3::*;
use crate::with_law;
use std::sync::atomic::AtomicBool;

/// Runs `steps` steps of `sim` with `threads` threads, checking for blow-ups every
/// `check_every` steps and after the last one.
pub(crate) fn run_steps(
    sim: &mut Simulation,
    steps: u64,
    threads: usize,
    check_every: u64,
) -> Result<(), BlowUp> {
    let model = sim.model;
    with_law!(model, |law| run_with(
        sim,
        &law,
        steps,
        threads,
        check_every
    ))
}

struct SpinBarrier {
    count: AtomicUsize,
    generation: AtomicUsize,
    n: usize,
}

impl SpinBarrier {
    fn new(n: usize) -> Self {
        SpinBarrier {
            count: AtomicUsize::new(0),
            generation: AtomicUsize::new(0),
            n,
        }
    }

    fn wait(&self) {
        let gen = self.generation.load(Ordering::Acquire);
        if self.count.fetch_add(1, Ordering::AcqRel) + 1 == self.n {
            self.count.store(0, Ordering::Relaxed);
            self.generation.fetch_add(1, Ordering::Release);
        } else {
            let mut spins = 0u32;
            while self.generation.load(Ordering::Acquire) == gen {
                spins += 1;
                if spins < 20_000 {
                    std::hint::spin_loop();
                } else {
                    // Oversubscribed machine: let the thread we wait for run.
                    std::thread::yield_now();
                }
            }
        }
    }
}

/// Raw views of the simulation's arrays, republished by thread 0 after every rebuild (which
/// reorders the particles and may move the arrays).
#[derive(Clone, Copy)]
struct Raw {
    n: usize,
    x: *mut V3,
    v: *mut V3,
    w: *mut V3,
    f: *mut V3,
    t: *mut V3,
    r: *const f64,
    m: *const f64,
    inv_m: *const f64,
    inv_i: *const f64,
    mat: *const u16,
    x_build: *const V3,
    start: *const u32,
    nb: *const u32,
    hist: *mut History,
    entries: usize,
    wall_hist: *mut History,
}

impl Raw {
    fn new(sim: &mut Simulation) -> Raw {
        let p = &mut sim.particles;
        let nl = &mut sim.neighbors;
        Raw {
            n: p.x.len(),
            x: p.x.as_mut_ptr(),
            v: p.v.as_mut_ptr(),
            w: p.w.as_mut_ptr(),
            f: p.f.as_mut_ptr(),
            t: p.t.as_mut_ptr(),
            r: p.r.as_ptr(),
            m: p.m.as_ptr(),
            inv_m: p.inv_m.as_ptr(),
            inv_i: p.inv_i.as_ptr(),
            mat: p.material.as_ptr(),
            x_build: nl.x_build().as_ptr(),
            start: nl.start.as_ptr(),
            nb: nl.nb.as_ptr(),
            hist: nl.hist.as_mut_ptr(),
            entries: nl.nb.len(),
            wall_hist: sim.wall_hist.as_mut_ptr(),
        }
    }
}

struct Shared {
    sim: *mut Simulation,
    raw: UnsafeCell<Raw>,
    /// Row bounds of the half list per thread (T + 1 entries).
    rows: UnsafeCell<Vec<usize>>,
    /// Per thread, the lowest particle index it can write in phase 2: a row i only touches
    /// j > i, and walls touch the thread's own particles. Buffers are valid from there on.
    low: UnsafeCell<Vec<usize>>,
    barrier: SpinBarrier,
    /// Per thread, the largest squared displacement since the list build (f64 bits).
    disp: Vec<AtomicU64>,
    wall_moved: AtomicU64,
    /// Force and torque buffers of threads 1..T.
    bufs: Vec<UnsafeCell<(Vec<V3>, Vec<V3>)>>,
    /// Set by thread 0 when a check failed; everybody stops at the same step.
    abort: AtomicBool,
    failure: UnsafeCell<Option<BlowUp>>,
}

// SAFETY: every access through the raw pointers follows the phase discipline of the module
// documentation: within a phase, threads write disjoint ranges (their particles, their rows,
// their buffer) and read only data nobody writes in that phase; the barriers order the phases.
unsafe impl Sync for Shared {}

/// Splits rows so that each thread gets about the same number of list entries.
fn row_bounds(start: &[u32], threads: usize) -> Vec<usize> {
    let n = start.len() - 1;
    let total = start[n] as usize;
    let mut b = vec![0usize];
    for c in 1..threads {
        let target = (total * c / threads) as u32;
        let k = start.partition_point(|&s| s < target).min(n);
        b.push(k.max(*b.last().expect("non-empty")));
    }
    b.push(n);
    b
}

fn lowest_written(rows: &[usize], parts: &[Range<usize>]) -> Vec<usize> {
    parts
        .iter()
        .enumerate()
        .map(|(t, p)| rows[t].min(p.start))
        .collect()
}

fn run_with<N: NormalForce, C: Cohesion, R: Rolling>(
    sim: &mut Simulation,
    law: &Law<N, C, R>,
    steps: u64,
    threads: usize,
    check_every: u64,
) -> Result<(), BlowUp> {
    let n = sim.particles.len();
    let parts: Vec<Range<usize>> = (0..threads)
        .map(|t| n * t / threads..n * (t + 1) / threads)
        .collect();
    let raw = Raw::new(sim);
    let rows = row_bounds(&sim.neighbors.start, threads);
    let low = lowest_written(&rows, &parts);
    let gravity = sim.gravity;
    let dt = sim.dt;
    let skin = sim.neighbors.skin;
    let shared = Shared {
        sim: sim as *mut Simulation,
        raw: UnsafeCell::new(raw),
        rows: UnsafeCell::new(rows),
        low: UnsafeCell::new(low),
        barrier: SpinBarrier::new(threads),
        disp: (0..threads).map(|_| AtomicU64::new(0)).collect(),
        wall_moved: AtomicU64::new(0),
        bufs: (1..threads)
            .map(|_| UnsafeCell::new((vec![[0.0; 3]; n], vec![[0.0; 3]; n])))
            .collect(),
        abort: AtomicBool::new(false),
        failure: UnsafeCell::new(None),
    };
    let ctx = Ctx {
        sh: &shared,
        law,
        parts: &parts,
        threads,
        steps,
        gravity,
        dt,
        skin,
        check_every,
        start_step: sim.step,
        start_time: sim.time,
    };
    std::thread::scope(|s| {
        for t in 1..threads {
            let ctx = &ctx;
            s.spawn(move || ctx.worker(t));
        }
        ctx.worker(0);
    });
    match shared.failure.into_inner() {
        Some(b) => Err(b),
        None => Ok(()),
    }
}

struct Ctx<'a, N, C, R> {
    sh: &'a Shared,
    law: &'a Law<N, C, R>,
    parts: &'a [Range<usize>],
    threads: usize,
    steps: u64,
    gravity: V3,
    dt: f64,
    skin: f64,
    check_every: u64,
    start_step: u64,
    start_time: f64,
}

// SAFETY: as for `Shared`; the law is plain data.
unsafe impl<N: Sync, C: Sync, R: Sync> Sync for Ctx<'_, N, C, R> {}

impl<N: NormalForce, C: Cohesion, R: Rolling> Ctx<'_, N, C, R> {
    fn worker(&self, t: usize) {
        let sh = self.sh;
        let own = self.parts[t].clone();
        let (dt, half, g) = (self.dt, 0.5 * self.dt, self.gravity);
        let lim2 = 0.25 * self.skin * self.skin;
        for s in 0..self.steps {
            // Phase 1: half kick and drift of own particles.
            // SAFETY: own particle range only; nobody else touches it in this phase.
            unsafe {
                let raw = *sh.raw.get();
                let mut md = 0.0f64;
                for i in own.clone() {
                    let a = *raw.inv_m.add(i) * half;
                    let f = *raw.f.add(i);
                    let v = &mut *raw.v.add(i);
                    v[0] += a * f[0];
                    v[1] += a * f[1];
                    v[2] += a * f[2];
                    let x = &mut *raw.x.add(i);
                    x[0] += dt * v[0];
                    x[1] += dt * v[1];
                    x[2] += dt * v[2];
                    let b = *raw.inv_i.add(i) * half;
                    let tq = *raw.t.add(i);
                    let w = &mut *raw.w.add(i);
                    w[0] += b * tq[0];
                    w[1] += b * tq[1];
                    w[2] += b * tq[2];
                    md = md.max(norm2(sub(*x, *raw.x_build.add(i))));
                    // Forces restart from gravity; thread 0 accumulates onto them in phase 2.
                    *raw.f.add(i) = scale(g, *raw.m.add(i));
                    *raw.t.add(i) = [0.0; 3];
                }
                sh.disp[t].store(md.to_bits(), Ordering::Relaxed);
                if t == 0 {
                    // SAFETY: only thread 0 touches the walls outside phase 2.
                    let sim = &mut *sh.sim;
                    let mut moved = 0.0f64;
                    for (w, m) in sim.walls.iter_mut().zip(sim.wall_moved.iter_mut()) {
                        if w.active && w.velocity != [0.0; 3] {
                            w.advance(dt);
                            *m += norm(w.velocity) * dt;
                            moved = moved.max(*m);
                        }
                    }
                    sh.wall_moved.store(moved.to_bits(), Ordering::Relaxed);
                }
            }
            sh.barrier.wait();
            let max_disp = sh
                .disp
                .iter()
                .map(|d| f64::from_bits(d.load(Ordering::Relaxed)))
                .fold(0.0, f64::max);
            let wall_moved = f64::from_bits(sh.wall_moved.load(Ordering::Relaxed));
            if max_disp > lim2 || wall_moved > 0.25 * self.skin {
                if t == 0 {
                    // SAFETY: the other threads wait at the barrier below and hold no references.
                    unsafe {
                        let sim = &mut *sh.sim;
                        if sim.positions_finite() {
                            sim.rebuild_lists();
                        }
                        *sh.raw.get() = Raw::new(sim);
                        *sh.rows.get() = row_bounds(&sim.neighbors.start, self.threads);
                        *sh.low.get() = lowest_written(&*sh.rows.get(), self.parts);
                    }
                }
                sh.barrier.wait();
            }

            // Phase 2: contacts of own rows and own particles' wall contacts.
            // SAFETY: positions, velocities and properties are only read in this phase; each
            // thread writes its own force target, its rows' histories and its particles' wall
            // histories.
            unsafe {
                let raw = *sh.raw.get();
                let n = raw.n;
                let rows = &*sh.rows.get();
                let rows = rows[t]..rows[t + 1];
                let (f_out, t_out): (&mut [V3], &mut [V3]) = if t == 0 {
                    (
                        std::slice::from_raw_parts_mut(raw.f, n),
                        std::slice::from_raw_parts_mut(raw.t, n),
                    )
                } else {
                    let lo = (&*sh.low.get())[t];
                    let b = &mut *sh.bufs[t - 1].get();
                    b.0[lo..].iter_mut().for_each(|x| *x = [0.0; 3]);
                    b.1[lo..].iter_mut().for_each(|x| *x = [0.0; 3]);
                    (&mut b.0[..], &mut b.1[..])
                };
                let view = P {
                    x: std::slice::from_raw_parts(raw.x, n),
                    v: std::slice::from_raw_parts(raw.v, n),
                    w: std::slice::from_raw_parts(raw.w, n),
                    r: std::slice::from_raw_parts(raw.r, n),
                    m: std::slice::from_raw_parts(raw.m, n),
                    mat: std::slice::from_raw_parts(raw.mat, n),
                };
                let start = std::slice::from_raw_parts(raw.start, n + 1);
                let nb = std::slice::from_raw_parts(raw.nb, raw.entries);
                let (e0, e1) = (start[rows.start] as usize, start[rows.end] as usize);
                let hist = std::slice::from_raw_parts_mut(raw.hist.add(e0), e1 - e0);
                let sim = &*sh.sim;
                pair_rows(
                    self.law,
                    &sim.materials,
                    dt,
                    rows,
                    start,
                    nb,
                    hist,
                    e0,
                    view,
                    f_out,
                    t_out,
                );
                let n_walls = sim.walls.len();
                if n_walls > 0 {
                    let wh = std::slice::from_raw_parts_mut(
                        raw.wall_hist.add(own.start * n_walls),
                        own.len() * n_walls,
                    );
                    let walls = WallView {
                        walls: &sim.walls,
                        lists: &sim.wall_nb,
                    };
                    wall_contacts(
                        self.law,
                        &sim.materials,
                        dt,
                        walls,
                        own.clone(),
                        own.start * n_walls,
                        wh,
                        view,
                        f_out,
                        t_out,
                    );
                }
            }
            sh.barrier.wait();

            // Phase 3: gather the buffers into own particles and kick again.
            // SAFETY: own particle range; buffers are only read until every thread has passed
            // the next step's first barrier.
            unsafe {
                let raw = *sh.raw.get();
                let low = &*sh.low.get();
                for i in own.clone() {
                    let f = &mut *raw.f.add(i);
                    let tq = &mut *raw.t.add(i);
                    for (b, &lo) in sh.bufs.iter().zip(&low[1..]) {
                        if i >= lo {
                            let b = &*b.get();
                            add_assign(f, b.0[i]);
                            add_assign(tq, b.1[i]);
                        }
                    }
                    let a = *raw.inv_m.add(i) * half;
                    let v = &mut *raw.v.add(i);
                    v[0] += a * f[0];
                    v[1] += a * f[1];
                    v[2] += a * f[2];
                    let b = *raw.inv_i.add(i) * half;
                    let w = &mut *raw.w.add(i);
                    w[0] += b * tq[0];
                    w[1] += b * tq[1];
                    w[2] += b * tq[2];
                }
            }

            let done = s + 1;
            if done % self.check_every == 0 || done == self.steps {
                sh.barrier.wait();
                if t == 0 {
                    // SAFETY: the others wait at the barrier below.
                    unsafe {
                        let sim = &mut *sh.sim;
                        sim.step = self.start_step + done;
                        sim.time = self.start_time + done as f64 * dt;
                        if let Err(b) = sim.check() {
                            *sh.failure.get() = Some(b);
                            sh.abort.store(true, Ordering::Relaxed);
                        }
                    }
                }
                sh.barrier.wait();
                if sh.abort.load(Ordering::Relaxed) {
                    return;
                }
            }
        }
    }
}
