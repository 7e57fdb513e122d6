//! The velocity-Verlet step with rotation (as LIGGGHTS `fix nve/sphere`), written once for the
//! serial path and the thread team.
//!
//! A run is T members stepping together over a [`Board`]; member t owns particles
//! `n t / T .. n (t + 1) / T`, and member 0, the leader, also does the work that cannot be split.
//! The serial path is one member whose meetings are no-ops ([`Alone`]); the team
//! ([`super::team`]) runs T threads whose meetings are spin barriers. A step, for member t:
//!
//! 1. half kick and drift of its particles, their largest displacement since the list build, and
//!    their forces reset to gravity; the leader moves the walls and counts the step. Meet. If the
//!    skin is used up, the leader rebuilds the lists (reordering the particles) and publishes the
//!    new array views while the others wait at a second meeting. If the near list (`near`) is
//!    used up too, or the lists were rebuilt, each member sets its particles' reaches, they meet,
//!    and each rebuilds the near list of its own rows.
//! 2. contacts of its rows of the half list (rows balanced by list entries) and the wall
//!    contacts of its particles. The leader accumulates into the particle forces, the others into
//!    their own buffers, which they clear only from the lowest index they can write. Meet.
//! 3. the buffers added into its particles' forces, and the second half kick. No meeting: the
//!    next step's first phase touches only the member's own particles. Alone, unless the run
//!    ends or checks after this step, the second half kick is left to the next step's first
//!    phase, which kicks twice from the same forces (one pass over the particles fewer).
//!
//! Every `check_every` steps the members meet, the leader looks for a blow-up, and they meet
//! again so that all stop at the same step.
//!
//! With one member this is the serial loop, operation for operation. With more, only the order
//! of the force sums differs (a particle's contacts are split between the leader's array and the
//! buffers, gathered in phase 3), so results differ from the serial path by round-off only.

use std::cell::UnsafeCell;
use std::marker::PhantomData;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use super::blowup::BlowUp;
use super::contact::{lanes, Contact, ContactLaw, ContactOutput, History};
use super::kick;
use super::material::Materials;
use super::near;
use super::neighbor::NeighborList;
use super::particles::Particles;
use super::periodic::PeriodicBox;
use super::vec3::*;
use super::walls::Wall;

/// The simulation as the step sees it. Only the leader calls these, while the other members
/// wait at a meeting or work on their own particles through a [`Raw`] view.
pub(crate) trait Host {
    fn params(&self) -> Params;
    /// Views of the arrays, valid until the next rebuild.
    fn views(&mut self) -> Raw;
    /// Advances the moving walls by one step; returns how far the farthest-moved wall has gone
    /// since the last list build.
    fn move_walls(&mut self) -> f64;
    /// Rebuilds the lists, unless a position is not finite: a blown-up particle must not trigger
    /// a rebuild every step (the check will stop the run).
    fn rebuild_if_finite(&mut self);
    /// Counts one more step (and its time).
    fn tick(&mut self);
    fn step_count(&self) -> u64;
    fn check(&self) -> Result<(), BlowUp>;
    /// Marks the near list valid for the state a finished run leaves, and records whether every
    /// particle is bounded ([`Raw::build_near`]).
    fn near_done(&mut self, bounded: bool);
    /// Forgets the bound recorded by [`Host::near_done`]: a run under way rewrites the near
    /// builds' positions and skins, and one stopped by a failed check does not record it anew.
    fn forget_bound(&mut self);
}

#[derive(Clone, Copy)]
pub(crate) struct Params {
    pub dt: f64,
    pub gravity: V3,
    pub skin: f64,
    /// Whether the near list is valid for the particles as they are ([`NeighborList`]).
    pub near_fresh: bool,
    /// With `near_fresh`: whether every particle was bounded ([`Raw::build_near`]) when the
    /// last run ended.
    pub near_bounded: bool,
}

#[derive(Clone, Copy)]
pub(crate) struct Plan {
    pub steps: u64,
    /// Blow-up checks every so many steps and after the last one; none if `None`.
    pub check_every: Option<u64>,
}

/// A meeting point of the members of a run.
pub(crate) trait Crew: Sync {
    /// Returns when every member has arrived, or with [`Abandoned`] if a member failed and will
    /// never arrive.
    fn meet(&self) -> Result<(), Abandoned>;
}

/// The run is being abandoned: a member failed.
#[derive(Debug)]
pub(crate) struct Abandoned;

/// The serial path: a crew of one, who never waits.
pub(crate) struct Alone;

impl Crew for Alone {
    #[inline(always)]
    fn meet(&self) -> Result<(), Abandoned> {
        Ok(())
    }
}

/// Moves the walls with a velocity by one step; returns the largest distance a wall has moved
/// since the last list build.
pub(crate) fn move_walls(walls: &mut [Wall], moved: &mut [f64], dt: f64) -> f64 {
    let mut farthest = 0.0f64;
    for (w, m) in walls.iter_mut().zip(moved) {
        if w.active && w.velocity != [0.0; 3] {
            w.advance(dt);
            *m += norm(w.velocity) * dt;
            farthest = farthest.max(*m);
        }
    }
    farthest
}

/// Raw views of the simulation's arrays, republished by the leader after every rebuild (which
/// reorders the particles and may move the arrays).
#[derive(Clone, Copy)]
pub(crate) struct Raw {
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
    /// Positions at the last list build; null if there is no list for these particles.
    x_build: *const V3,
    start: *const u32,
    nb: *const u32,
    hist: *mut History,
    live: *mut u8,
    entries: usize,
    /// The near list (`crate::near`), the positions and squared near skins at its build, and
    /// the reaches the particles' current speeds ask for.
    near: *mut near::Entry,
    near_len: *mut u32,
    x_near: *mut V3,
    near_s2: *mut f64,
    reach: *mut f64,
    wall_hist: *mut History,
    walls: *const Wall,
    n_walls: usize,
    wall_nb: *const Vec<u32>,
    materials: *const Materials,
    pbox: PeriodicBox,
    /// Whether some particle is driven; the flags change only between runs.
    any_driven: bool,
    /// Whether every particle has the same material (the pair loop's constants are then one).
    one_material: bool,
}

impl Raw {
    pub(crate) fn new(
        p: &mut Particles,
        nl: &mut NeighborList,
        wall_hist: &mut [History],
        walls: &[Wall],
        wall_nb: &[Vec<u32>],
        materials: &Materials,
    ) -> Raw {
        let n = p.len();
        // The force loops index all of these by particle, list entry or (particle, wall) without
        // bounds checks.
        for len in [
            p.v.len(),
            p.w.len(),
            p.f.len(),
            p.t.len(),
            p.r.len(),
            p.m.len(),
        ] {
            debug_assert_eq!(len, n, "particle arrays of unequal length");
        }
        for len in [
            p.inv_m.len(),
            p.inv_i.len(),
            p.material.len(),
            p.driven.len(),
        ] {
            debug_assert_eq!(len, n, "particle arrays of unequal length");
        }
        debug_assert_eq!(
            nl.start.len(),
            n + 1,
            "one row start per particle, plus the end"
        );
        debug_assert_eq!(
            nl.start[n] as usize,
            nl.nb.len(),
            "rows end at the last entry"
        );
        debug_assert_eq!(nl.hist.len(), nl.nb.len(), "one history per list entry");
        debug_assert_eq!(nl.live.len(), nl.nb.len(), "one live flag per list entry");
        debug_assert_eq!(nl.near.len(), nl.nb.len(), "near list sized as the list");
        debug_assert_eq!(nl.near_len.len(), n, "one near row per particle");
        debug_assert_eq!(
            wall_hist.len(),
            n * walls.len(),
            "wall history per particle"
        );
        debug_assert_eq!(wall_nb.len(), walls.len(), "one list per wall");
        let xb = nl.x_build();
        let pbox = nl.periodic_box();
        Raw {
            n,
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
            x_build: if xb.len() == n
                && nl.x_near.len() == n
                && nl.near_s2.len() == n
                && nl.reach.len() == n
            {
                xb.as_ptr()
            } else {
                std::ptr::null()
            },
            start: nl.start.as_ptr(),
            nb: nl.nb.as_ptr(),
            hist: nl.hist.as_mut_ptr(),
            live: nl.live.as_mut_ptr(),
            entries: nl.nb.len(),
            near: nl.near.as_mut_ptr(),
            near_len: nl.near_len.as_mut_ptr(),
            x_near: nl.x_near.as_mut_ptr(),
            near_s2: nl.near_s2.as_mut_ptr(),
            reach: nl.reach.as_mut_ptr(),
            wall_hist: wall_hist.as_mut_ptr(),
            walls: walls.as_ptr(),
            n_walls: walls.len(),
            wall_nb: wall_nb.as_ptr(),
            materials,
            pbox,
            any_driven: p.driven.contains(&true),
            one_material: p.material.windows(2).all(|w| w[0] == w[1]),
        }
    }

    /// Half kick and drift of the particles in `own`, forces reset to gravity (to zero for
    /// driven particles, whose zero inverse mass makes the kick a no-op). Returns 1 if one of
    /// them has moved more than `lim2` (squared) since the list build, else 0, and 1 if one has
    /// moved beyond its near skin since the near build, else 0 (both 1 without a list).
    ///
    /// With `BOUNDED`, the last near build found every particle's near skin plus its distance
    /// from its list build position below `lim2`'s root ([`Raw::build_near`]): a particle still
    /// inside its near skin then cannot be beyond the list's limit, so only those that left it
    /// are measured against their build positions. The same decisions, one distance per particle
    /// fewer in most steps of a settled state.
    ///
    /// # Safety
    /// The views are current and nobody else accesses these particles meanwhile.
    #[inline(always)]
    unsafe fn kick_drift<const TWICE: bool, const BOUNDED: bool>(
        &self,
        own: Range<usize>,
        dt: f64,
        g: V3,
        lim2: f64,
    ) -> (f64, f64) {
        let (lo, len) = (own.start, own.len());
        let x = std::slice::from_raw_parts_mut(self.x.add(lo), len);
        let v = std::slice::from_raw_parts_mut(self.v.add(lo), len);
        let w = std::slice::from_raw_parts_mut(self.w.add(lo), len);
        let f = std::slice::from_raw_parts_mut(self.f.add(lo), len);
        let t = std::slice::from_raw_parts_mut(self.t.add(lo), len);
        let m = std::slice::from_raw_parts(self.m.add(lo), len);
        let inv_m = std::slice::from_raw_parts(self.inv_m.add(lo), len);
        let inv_i = std::slice::from_raw_parts(self.inv_i.add(lo), len);
        let xb = if self.x_build.is_null() {
            None
        } else {
            Some((
                std::slice::from_raw_parts(self.x_build.add(lo), len),
                std::slice::from_raw_parts(self.x_near.add(lo), len),
                std::slice::from_raw_parts(self.near_s2.add(lo), len),
            ))
        };
        kick::kick_drift::<TWICE>(
            kick::Block {
                x: &mut *x,
                v,
                w,
                f: &mut *f,
                t,
                m,
                inv_m,
                inv_i,
            },
            dt,
            g,
        );
        let mut over = false;
        let mut near_out = false;
        if let Some((xb, xn, s2)) = xb {
            for k in 0..len {
                // A NaN position asks for a near build, as the whole list would see it, but no
                // list rebuild (NaN compares false), so that a blown-up particle does not
                // trigger endless rebuilds.
                let d2 = norm2(sub(x[k], xn[k]));
                let out = d2 > s2[k] || d2.is_nan();
                near_out |= out;
                if !BOUNDED || out {
                    over |= norm2(sub(x[k], xb[k])) > lim2;
                }
            }
        }
        // A driven particle's force is its contacts alone: what a lid's servo needs. A pass of
        // its own, so that scenes without driven particles pay nothing in the loop above.
        if self.any_driven {
            for k in 0..len {
                if inv_m[k] == 0.0 {
                    f[k] = [0.0; 3];
                }
            }
        }
        if xb.is_none() {
            over = true;
            near_out = true;
        }
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        (flag(over), flag(near_out))
    }

    /// Sets the reach of the particles in `own` from their speeds: their radii plus their near
    /// skins ([`near::near_skin`]).
    ///
    /// # Safety
    /// The views are current; nobody writes these particles meanwhile, nor reads their reaches.
    unsafe fn set_reach(&self, own: Range<usize>, dt: f64, skin: f64) {
        if self.x_build.is_null() {
            return;
        }
        for i in own {
            *self.reach.add(i) = *self.r.add(i) + near::near_skin(norm(*self.v.add(i)), dt, skin);
        }
    }

    /// Rebuilds the near list of `rows` (every entry with `all`) and records the positions and
    /// near skins of the particles in `own` as those of its build. Returns whether each of them
    /// is, by its near skin plus its distance from its list build position, closer than `lim`
    /// to that position (with a margin for rounding): then none can pass the list's limit
    /// before it leaves its near skin, which [`Raw::kick_drift`] checks anyway.
    ///
    /// # Safety
    /// The views are current and the reaches set; nobody writes positions or reaches
    /// meanwhile, nor the histories and near entries of these rows, nor the build positions and
    /// skins of `own`.
    unsafe fn build_near(
        &self,
        rows: Range<usize>,
        own: Range<usize>,
        all: bool,
        lim: f64,
    ) -> bool {
        let n = self.n;
        let x = std::slice::from_raw_parts(self.x, n);
        let reach: &[f64] = if self.x_build.is_null() {
            &[]
        } else {
            std::slice::from_raw_parts(self.reach, n)
        };
        let all = all || self.x_build.is_null();
        let start = std::slice::from_raw_parts(self.start, n + 1);
        let nb = std::slice::from_raw_parts(self.nb, self.entries);
        let (e0, e1) = (start[rows.start] as usize, start[rows.end] as usize);
        let hist = std::slice::from_raw_parts_mut(self.hist.add(e0), e1 - e0);
        let live = std::slice::from_raw_parts_mut(self.live.add(e0), e1 - e0);
        let out = near::Out {
            near: std::slice::from_raw_parts_mut(self.near.add(e0), e1 - e0),
            near_len: std::slice::from_raw_parts_mut(self.near_len.add(rows.start), rows.len()),
        };
        let r = std::slice::from_raw_parts(self.r, n);
        let m = std::slice::from_raw_parts(self.m, n);
        let list = near::Rows {
            start,
            nb,
            base: e0,
            row0: rows.start,
        };
        // Two instances, so that the non-periodic one carries no image test.
        let build = if self.pbox.any() {
            near::build::<true>
        } else {
            near::build::<false>
        };
        build(
            rows,
            list,
            (x, r, m),
            reach,
            &self.pbox,
            all,
            out,
            hist,
            live,
        );
        if self.x_build.is_null() {
            return false;
        }
        // Relative rounding of the distances is of order 1e-16; the margin dwarfs it.
        let bound = lim * (1.0 - 1e-9);
        let mut bounded = true;
        for i in own {
            let xi = *self.x.add(i);
            *self.x_near.add(i) = xi;
            let s = *self.reach.add(i) - *self.r.add(i);
            *self.near_s2.add(i) = s * s;
            // False for a NaN too.
            bounded &= s + norm(sub(xi, *self.x_build.add(i))) < bound;
        }
        bounded
    }

    /// Contacts of `rows` of the half list and wall contacts of the particles in `own`, added
    /// into `f_out` and `t_out` (indexed by particle).
    ///
    /// # Safety
    /// The views are current; nobody writes positions, velocities or properties meanwhile, nor
    /// the histories of these rows and of these particles' wall contacts.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    unsafe fn contacts<L: ContactLaw>(
        &self,
        law: &L,
        dt: f64,
        rows: Range<usize>,
        own: Range<usize>,
        f_out: &mut [V3],
        t_out: &mut [V3],
    ) {
        let n = self.n;
        let view = P {
            x: std::slice::from_raw_parts(self.x, n),
            v: std::slice::from_raw_parts(self.v, n),
            w: std::slice::from_raw_parts(self.w, n),
            r: std::slice::from_raw_parts(self.r, n),
            m: std::slice::from_raw_parts(self.m, n),
            inv_m: std::slice::from_raw_parts(self.inv_m, n),
            mat: std::slice::from_raw_parts(self.mat, n),
        };
        let materials = &*self.materials;
        let start = std::slice::from_raw_parts(self.start, n + 1);
        let nb = std::slice::from_raw_parts(self.nb, self.entries);
        let (e0, e1) = (start[rows.start] as usize, start[rows.end] as usize);
        let hist = std::slice::from_raw_parts_mut(self.hist.add(e0), e1 - e0);
        let live = std::slice::from_raw_parts_mut(self.live.add(e0), e1 - e0);
        let near = Near {
            entries: std::slice::from_raw_parts(self.near.add(e0), e1 - e0),
            len: std::slice::from_raw_parts(self.near_len.add(rows.start), rows.len()),
            row0: rows.start,
        };
        // Two instances of the pair loop, so that the non-periodic one carries no image test;
        // the common law's contacts go four at a time where the law and every pair allow.
        if law.four_lanes() && materials.lanes_ready() {
            let periodic = self.pbox.any();
            pair_rows_lanes_dispatch(
                (periodic, self.one_material),
                materials,
                dt,
                rows,
                start,
                nb,
                near,
                hist,
                live,
                e0,
                view,
                &self.pbox,
                f_out,
                t_out,
            );
        } else if self.pbox.any() {
            pair_rows::<L, true>(
                law, materials, dt, rows, start, nb, near, hist, live, e0, view, &self.pbox, f_out,
                t_out,
            );
        } else {
            pair_rows::<L, false>(
                law, materials, dt, rows, start, nb, near, hist, live, e0, view, &self.pbox, f_out,
                t_out,
            );
        }
        let n_walls = self.n_walls;
        if n_walls > 0 {
            let wh = std::slice::from_raw_parts_mut(
                self.wall_hist.add(own.start * n_walls),
                own.len() * n_walls,
            );
            let walls = WallView {
                walls: std::slice::from_raw_parts(self.walls, n_walls),
                lists: std::slice::from_raw_parts(self.wall_nb, n_walls),
            };
            wall_contacts(
                law,
                materials,
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
}

/// Adds every contact force (pairs, then walls) to the current forces.
pub(crate) fn add_contact_forces<H: Host, L: ContactLaw>(host: &mut H, law: &L) {
    let dt = host.params().dt;
    let raw = host.views();
    let n = raw.n;
    // SAFETY: `host` is borrowed exclusively, so the views are current and ours alone.
    unsafe {
        // Every entry: the positions may have moved anyhow since the last step. The next run
        // builds its own near list at its first step.
        // No particle of its own: the run's bound is not asked for.
        let _ = raw.build_near(0..n, 0..0, true, 0.0);
        let f = std::slice::from_raw_parts_mut(raw.f, n);
        let t = std::slice::from_raw_parts_mut(raw.t, n);
        raw.contacts(law, dt, 0..n, 0..n, f, t);
    }
}

/// Runs `plan` with one member: the serial path.
pub(crate) fn run_alone<H: Host, L: ContactLaw>(
    host: &mut H,
    law: &L,
    plan: Plan,
) -> Result<(), BlowUp> {
    let board = Board::new(host, law, plan, 1);
    // Alone never abandons.
    let _ = board.member(0, &Alone);
    board.into_failure()
}

/// What members 1..T keep on the board.
struct Slot {
    /// 1 if one of its particles has moved beyond the list's limit since the list build, else
    /// 0 (f64 bits).
    disp: AtomicU64,
    /// 1 if one of its particles has moved beyond its near skin since the near build, else 0.
    near: AtomicU64,
    /// Whether its particles were bounded ([`Raw::build_near`]) at its last near build.
    bounded: AtomicBool,
    /// First row of the half list it handles (its last is the next member's first).
    row_start: UnsafeCell<usize>,
    /// Lowest particle index it can write in phase 2: a row i only touches j > i, and walls
    /// touch its own particles. Its buffers are valid from there on.
    low: UnsafeCell<usize>,
    /// Force and torque buffer.
    buf: UnsafeCell<(Vec<V3>, Vec<V3>)>,
}

/// The state the members of a run share.
pub(crate) struct Board<'a, H, L> {
    host: *mut H,
    law: &'a L,
    params: Params,
    plan: Plan,
    members: usize,
    n: usize,
    raw: UnsafeCell<Raw>,
    lead_disp: AtomicU64,
    lead_near: AtomicU64,
    wall_moved: AtomicU64,
    /// Members 1..T; empty on the serial path, which so allocates nothing per call.
    others: Vec<Slot>,
    /// Set by the leader when a check failed; everybody stops at the same step.
    abort: AtomicBool,
    failure: UnsafeCell<Option<BlowUp>>,
    #[cfg(test)]
    fail_at: Option<(usize, u64)>,
    #[cfg(test)]
    near_all: bool,
    #[cfg(test)]
    no_bound: bool,
    _host: PhantomData<&'a mut H>,
}

// SAFETY: every access through the raw pointers and cells follows the phase discipline of the
// module documentation: within a phase, members write disjoint ranges (their particles, their
// rows, their buffer) and read only data nobody writes in that phase; only the leader touches the
// host, while the others wait or work on their own particles; the meetings order the phases.
unsafe impl<H: Send, L: Sync> Sync for Board<'_, H, L> {}

#[cfg(test)]
thread_local! {
    /// Test hook: the next run started on this thread makes member t panic in step s (counted
    /// from the run's start).
    pub(crate) static FAIL_AT: std::cell::Cell<Option<(usize, u64)>> =
        const { std::cell::Cell::new(None) };
    /// Test hook: runs started on this thread keep every list entry in the near list, so that
    /// a test can compare the near list's results with the whole list's.
    pub(crate) static NEAR_ALL: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    /// Test hook: runs started on this thread never skip the list's displacement check
    /// ([`Raw::build_near`]'s bound), so that a test can compare the decisions of both.
    pub(crate) static NO_BOUND: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

impl<'a, H: Host, L: ContactLaw> Board<'a, H, L> {
    pub(crate) fn new(host: &'a mut H, law: &'a L, plan: Plan, members: usize) -> Self {
        let params = host.params();
        host.forget_bound();
        #[cfg(test)]
        let params = Params {
            near_bounded: params.near_bounded && !NO_BOUND.with(|f| f.get()),
            ..params
        };
        let raw = host.views();
        let n = raw.n;
        let others = (1..members)
            .map(|_| Slot {
                disp: AtomicU64::new(0),
                near: AtomicU64::new(0),
                bounded: AtomicBool::new(params.near_fresh && params.near_bounded),
                row_start: UnsafeCell::new(0),
                low: UnsafeCell::new(0),
                buf: UnsafeCell::new((vec![[0.0; 3]; n], vec![[0.0; 3]; n])),
            })
            .collect();
        let board = Board {
            host,
            law,
            params,
            plan,
            members,
            n,
            raw: UnsafeCell::new(raw),
            lead_disp: AtomicU64::new(0),
            lead_near: AtomicU64::new(0),
            wall_moved: AtomicU64::new(0),
            others,
            abort: AtomicBool::new(false),
            failure: UnsafeCell::new(None),
            #[cfg(test)]
            fail_at: FAIL_AT.with(|f| f.take()),
            #[cfg(test)]
            near_all: NEAR_ALL.with(|f| f.get()),
            #[cfg(test)]
            no_bound: NO_BOUND.with(|f| f.get()),
            _host: PhantomData,
        };
        // SAFETY: nobody else sees the board yet.
        unsafe { board.split_rows() };
        board
    }

    /// The largest value the members posted this step in one of their slots (a displacement
    /// or a near-skin use); NaN never wins, as in the serial path.
    fn max_over_members(&self, slot: impl Fn(&Slot) -> &AtomicU64, lead: &AtomicU64) -> f64 {
        self.others
            .iter()
            .map(slot)
            .chain([lead])
            .map(|d| f64::from_bits(d.load(Ordering::Relaxed)))
            .fold(0.0, f64::max)
    }

    /// The particles member `t` owns; fixed for the run (a rebuild reorders, never adds).
    fn part(&self, t: usize) -> Range<usize> {
        self.n * t / self.members..self.n * (t + 1) / self.members
    }

    /// Splits the rows of the current list so that each member gets about the same number of
    /// entries, and sets the members' lowest written indices.
    ///
    /// # Safety
    /// Only the leader, while the others wait (or before they start).
    unsafe fn split_rows(&self) {
        let raw = *self.raw.get();
        let n = raw.n;
        debug_assert_eq!(n, self.n, "a rebuild keeps the particle count");
        let start = std::slice::from_raw_parts(raw.start, n + 1);
        let total = start[n] as usize;
        let mut prev = 0;
        for (k, slot) in self.others.iter().enumerate() {
            let c = k + 1;
            let target = (total * c / self.members) as u32;
            let row = start.partition_point(|&s| s < target).min(n).max(prev);
            *slot.row_start.get() = row;
            *slot.low.get() = row.min(self.part(c).start);
            prev = row;
        }
    }

    /// Rows of the half list member `t` handles.
    ///
    /// # Safety
    /// Not while the leader splits the rows.
    unsafe fn rows(&self, t: usize) -> Range<usize> {
        let first = if t == 0 {
            0
        } else {
            *self.others[t - 1].row_start.get()
        };
        let end = match self.others.get(t) {
            Some(next) => *next.row_start.get(),
            None => self.n,
        };
        // The buffers' clearing and the entry ranges of the histories rely on ordered rows.
        debug_assert!(
            first <= end && end <= self.n,
            "rows {first}..{end} of {}",
            self.n
        );
        first..end
    }

    /// Member `t`'s share of the run; returns early if the run is abandoned or a check failed.
    pub(crate) fn member<K: Crew>(&self, t: usize, crew: &K) -> Result<(), Abandoned> {
        let own = self.part(t);
        let Params {
            dt,
            gravity,
            skin,
            near_fresh,
            near_bounded,
        } = self.params;
        let lim2 = 0.25 * skin * skin;
        let steps = self.plan.steps;
        // Alone, the last step's second half kick is left to this step's kick_drift, which then
        // kicks twice from the same forces: the same operations on the same values, one pass
        // over the particles fewer (a team gathers its buffers first and kicks in phase 3).
        let mut kick_pending = false;
        // Whether this member's particles are bounded ([`Raw::build_near`]): as the last run
        // left them if the near list carries over, else decided by this run's first near build.
        let mut bounded = near_fresh && near_bounded;
        for s in 0..steps {
            // Phase 1.
            // SAFETY: own particles only; the leader alone touches the host and the walls.
            unsafe {
                let raw = *self.raw.get();
                let (md, nd) = match (kick_pending, bounded) {
                    (true, true) => raw.kick_drift::<true, true>(own.clone(), dt, gravity, lim2),
                    (true, false) => raw.kick_drift::<true, false>(own.clone(), dt, gravity, lim2),
                    (false, true) => raw.kick_drift::<false, true>(own.clone(), dt, gravity, lim2),
                    (false, false) => {
                        raw.kick_drift::<false, false>(own.clone(), dt, gravity, lim2)
                    }
                };
                kick_pending = false;
                if t == 0 {
                    self.lead_disp.store(md.to_bits(), Ordering::Relaxed);
                    self.lead_near.store(nd.to_bits(), Ordering::Relaxed);
                    let host = &mut *self.host;
                    let moved = host.move_walls();
                    self.wall_moved.store(moved.to_bits(), Ordering::Relaxed);
                    host.tick();
                } else {
                    let slot = &self.others[t - 1];
                    slot.disp.store(md.to_bits(), Ordering::Relaxed);
                    slot.near.store(nd.to_bits(), Ordering::Relaxed);
                }
            }
            crew.meet()?;
            let over = self.max_over_members(|o| &o.disp, &self.lead_disp);
            let near_out = self.max_over_members(|o| &o.near, &self.lead_near);
            let wall_moved = f64::from_bits(self.wall_moved.load(Ordering::Relaxed));
            // A moving wall uses up the skin too: rebuild before it can reach unlisted particles.
            // A blown-up (NaN) particle raises no flag (`kick_drift`): no endless rebuilds.
            let rebuild = wall_moved > 0.25 * skin || over > 0.0;
            if rebuild {
                if t == 0 {
                    // SAFETY: the others wait at the meeting below and hold no references.
                    unsafe {
                        let host = &mut *self.host;
                        host.rebuild_if_finite();
                        *self.raw.get() = host.views();
                        self.split_rows();
                    }
                }
                crew.meet()?;
            }
            // The near list (`crate::near`) is rebuilt at a run's first step too: the caller may
            // have moved particles between runs. Every member sees the same flags, so all decide
            // alike.
            if (s == 0 && !near_fresh) || rebuild || near_out > 0.0 {
                // SAFETY: each member sets its own particles' reaches; after the meeting, phase 2
                // of the module documentation: positions and reaches are only read, and each
                // member writes its own rows' near entries and histories and its own particles'
                // build positions and skins. No meeting is needed before the force loop, which
                // reads only the near entries of the member's own rows.
                unsafe { (*self.raw.get()).set_reach(own.clone(), dt, skin) };
                crew.meet()?;
                unsafe {
                    let raw = *self.raw.get();
                    #[cfg(not(test))]
                    let all = false;
                    #[cfg(test)]
                    let all = self.near_all;
                    bounded = raw.build_near(self.rows(t), own.clone(), all, 0.5 * skin);
                    #[cfg(test)]
                    if self.no_bound {
                        bounded = false;
                    }
                    if t > 0 {
                        // Read by the leader after the run's last meeting.
                        self.others[t - 1].bounded.store(bounded, Ordering::Relaxed);
                    }
                }
            }

            #[cfg(test)]
            if self.fail_at == Some((t, s)) {
                panic!("injected failure of member {t} in step {s}");
            }

            // Phase 2.
            // SAFETY: positions, velocities and properties are only read in this phase; each
            // member writes its own force target, its rows' histories and its particles' wall
            // histories.
            unsafe {
                let raw = *self.raw.get();
                let n = raw.n;
                let (f_out, t_out): (&mut [V3], &mut [V3]) = if t == 0 {
                    (
                        std::slice::from_raw_parts_mut(raw.f, n),
                        std::slice::from_raw_parts_mut(raw.t, n),
                    )
                } else {
                    let slot = &self.others[t - 1];
                    let lo = *slot.low.get();
                    let b = &mut *slot.buf.get();
                    debug_assert!(b.0.len() == n && b.1.len() == n, "buffers sized to n");
                    b.0[lo..].iter_mut().for_each(|x| *x = [0.0; 3]);
                    b.1[lo..].iter_mut().for_each(|x| *x = [0.0; 3]);
                    (&mut b.0[..], &mut b.1[..])
                };
                raw.contacts(self.law, dt, self.rows(t), own.clone(), f_out, t_out);
            }
            crew.meet()?;

            // Phase 3.
            let done = s + 1;
            let check_due = self
                .plan
                .check_every
                .is_some_and(|every| done % every == 0 || done == steps);
            if self.members == 1 && done < steps && !check_due {
                // Nothing reads the velocities before the next step's kick_drift: the host moves
                // only walls there, and a rebuild follows the kick.
                kick_pending = true;
            } else {
                // SAFETY: own particles; the buffers are only read until every member has passed
                // the next step's first meeting.
                unsafe { self.gather_and_kick(own.clone(), dt) };
            }

            if check_due {
                crew.meet()?;
                if t == 0 {
                    // SAFETY: the others wait at the meeting below.
                    unsafe {
                        if let Err(b) = (*self.host).check() {
                            *self.failure.get() = Some(b);
                            self.abort.store(true, Ordering::Relaxed);
                        }
                    }
                }
                crew.meet()?;
                if self.abort.load(Ordering::Relaxed) {
                    return Ok(());
                }
            }
        }
        if t == 0 {
            // SAFETY: the leader alone touches the host; the near list is valid after every
            // step, so the next run need not rebuild it unless the lists are rebuilt meanwhile.
            // Every member's last near build came before the last step's phase 2 meeting.
            let all = bounded
                && self
                    .others
                    .iter()
                    .all(|o| o.bounded.load(Ordering::Relaxed));
            unsafe { (*self.host).near_done(all) };
        }
        Ok(())
    }

    /// Adds the other members' buffers into the forces of `own` and applies the second half kick.
    ///
    /// # Safety
    /// As phase 3 of the module documentation.
    #[inline(always)]
    unsafe fn gather_and_kick(&self, own: Range<usize>, dt: f64) {
        let half = 0.5 * dt;
        let raw = *self.raw.get();
        for i in own {
            let f = &mut *raw.f.add(i);
            let tq = &mut *raw.t.add(i);
            for slot in &self.others {
                if i >= *slot.low.get() {
                    let b = &*slot.buf.get();
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

    /// The failed check that stopped the run, if any.
    pub(crate) fn into_failure(self) -> Result<(), BlowUp> {
        match self.failure.into_inner() {
            Some(b) => Err(b),
            None => Ok(()),
        }
    }
}

/// The near list of the rows a force loop computes (`crate::near`): row i's entries are
/// `entries[start[i] - base..][..len[i - row0]]`, each the index of a list entry.
#[derive(Clone, Copy)]
struct Near<'a> {
    entries: &'a [near::Entry],
    len: &'a [u32],
    row0: usize,
}

/// Read-only particle data for the force loops.
#[derive(Clone, Copy)]
struct P<'a> {
    x: &'a [V3],
    v: &'a [V3],
    w: &'a [V3],
    r: &'a [f64],
    m: &'a [f64],
    /// Zero for driven particles.
    inv_m: &'a [f64],
    mat: &'a [u16],
}

/// The walls and, per wall, the particles within reach (ascending indices).
#[derive(Clone, Copy)]
struct WallView<'a> {
    walls: &'a [Wall],
    lists: &'a [Vec<u32>],
}

/// Wall contacts of the particles in `range`; `wall_hist` holds the wall histories from
/// (particle, wall) entry `hist_base` on.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn wall_contacts<L: ContactLaw>(
    law: &L,
    materials: &Materials,
    dt: f64,
    walls: WallView,
    range: Range<usize>,
    hist_base: usize,
    wall_hist: &mut [History],
    p: P,
    f: &mut [V3],
    t: &mut [V3],
) {
    let n_walls = walls.walls.len();
    for (wi, wall) in walls.walls.iter().enumerate() {
        if !wall.active {
            continue;
        }
        let list = &walls.lists[wi];
        // The binary searches below find a member's particles only in an ascending list.
        debug_assert!(
            list.windows(2).all(|w| w[0] < w[1]),
            "wall list {wi} not ascending"
        );
        let lo = list.partition_point(|&i| (i as usize) < range.start);
        let hi = list.partition_point(|&i| (i as usize) < range.end);
        for &i in &list[lo..hi] {
            let i = i as usize;
            let h = &mut wall_hist[i * n_walls + wi - hist_base];
            let Some(out) = wall_contact(law, materials, dt, wall, p, i, h) else {
                *h = History::default();
                continue;
            };
            add_assign(&mut f[i], out.force);
            add_assign(&mut t[i], out.torque_i);
        }
    }
}

/// The contact of particle `i` with `wall` (`None` if they do not touch), advancing its history.
#[inline(always)]
fn wall_contact<L: ContactLaw>(
    law: &L,
    materials: &Materials,
    dt: f64,
    wall: &Wall,
    p: P,
    i: usize,
    h: &mut History,
) -> Option<ContactOutput> {
    let ri = p.r[i];
    let gap = wall.gap(p.x[i], ri)?;
    let overlap = ri - gap.distance;
    let area = if L::NEEDS_AREA {
        std::f64::consts::PI * (2.0 * ri * overlap - overlap * overlap).max(0.0)
    } else {
        0.0
    };
    let lever = ri - 0.5 * overlap;
    let c = Contact::new(
        gap.normal,
        overlap,
        ri,
        p.m[i],
        sub(p.v[i], wall.velocity),
        p.w[i],
        [0.0; 3],
        lever,
        0.0,
        area,
    );
    let pc = materials.pair(p.mat[i], wall.material);
    Some(law.force(&c, pc, h, dt))
}

/// The force the particles in `near` (those within reach of `wall`) exert on it in their
/// current state: minus the sum of its contact forces, each from a copy of its history (entry
/// `i * stride + offset` of `wall_hist`), which the step is not given back.
#[allow(clippy::too_many_arguments)]
pub(crate) fn wall_force<L: ContactLaw>(
    law: &L,
    materials: &Materials,
    dt: f64,
    wall: &Wall,
    q: &Particles,
    near: &[u32],
    wall_hist: &[History],
    (stride, offset): (usize, usize),
) -> V3 {
    if !wall.active {
        return [0.0; 3];
    }
    let p = P {
        x: &q.x,
        v: &q.v,
        w: &q.w,
        r: &q.r,
        m: &q.m,
        inv_m: &q.inv_m,
        mat: &q.material,
    };
    let mut total = [0.0; 3];
    for &i in near {
        let i = i as usize;
        let mut h = wall_hist[i * stride + offset];
        if let Some(out) = wall_contact(law, materials, dt, wall, p, i, &mut h) {
            sub_assign(&mut total, out.force);
        }
    }
    total
}

/// [`pair_rows_lanes`] compiled for AVX2 where the processor has it (checked once per process
/// by the standard library), else for the baseline instruction set: the results are the same
/// bits either way.
#[allow(clippy::too_many_arguments)]
fn pair_rows_lanes_dispatch(
    (periodic, one_material): (bool, bool),
    materials: &Materials,
    dt: f64,
    rows: Range<usize>,
    start: &[u32],
    nb: &[u32],
    near: Near,
    hist: &mut [History],
    live: &mut [u8],
    base: usize,
    p: P,
    pbox: &PeriodicBox,
    f: &mut [V3],
    t: &mut [V3],
) {
    // One instance per (periodic, one material): the common case carries neither the image
    // test nor a lookup of the pair constants per contact.
    macro_rules! call {
        ($f:ident) => {
            match (periodic, one_material) {
                (true, true) => $f::<true, true>(
                    materials, dt, rows, start, nb, near, hist, live, base, p, pbox, f, t,
                ),
                (true, false) => $f::<true, false>(
                    materials, dt, rows, start, nb, near, hist, live, base, p, pbox, f, t,
                ),
                (false, true) => $f::<false, true>(
                    materials, dt, rows, start, nb, near, hist, live, base, p, pbox, f, t,
                ),
                (false, false) => $f::<false, false>(
                    materials, dt, rows, start, nb, near, hist, live, base, p, pbox, f, t,
                ),
            }
        };
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2, checked just above.
        unsafe { call!(pair_rows_lanes_avx2) };
        return;
    }
    call!(pair_rows_lanes)
}

/// # Safety
/// Only on a processor with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn pair_rows_lanes_avx2<const PERIODIC: bool, const ONE_MATERIAL: bool>(
    materials: &Materials,
    dt: f64,
    rows: Range<usize>,
    start: &[u32],
    nb: &[u32],
    near: Near,
    hist: &mut [History],
    live: &mut [u8],
    base: usize,
    p: P,
    pbox: &PeriodicBox,
    f: &mut [V3],
    t: &mut [V3],
) {
    pair_rows_lanes::<PERIODIC, ONE_MATERIAL>(
        materials, dt, rows, start, nb, near, hist, live, base, p, pbox, f, t,
    );
}

/// [`pair_rows`] for the common law (`hertz,mindlin,epsd2`, `law.four_lanes()`): the test of
/// each list entry as there, the touching pairs gathered into [`BATCHES`] batches of four
/// ([`lanes::Lanes`]), each batch's forces computed together, and all added to the particles in
/// list order, so that every sum is the scalar loop's to the bit.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
#[allow(clippy::needless_range_loop)] // e indexes nb, hist and live at once (offset by base)
fn pair_rows_lanes<const PERIODIC: bool, const ONE_MATERIAL: bool>(
    materials: &Materials,
    dt: f64,
    rows: Range<usize>,
    start: &[u32],
    nb: &[u32],
    near: Near,
    hist: &mut [History],
    live: &mut [u8],
    base: usize,
    p: P,
    pbox: &PeriodicBox,
    f: &mut [V3],
    t: &mut [V3],
) {
    let n = p.x.len();
    let (x, r, inv_m, mat) = (&p.x[..n], &p.r[..n], &p.inv_m[..n], &p.mat[..n]);
    let (v, w) = (&p.v[..n], &p.w[..n]);
    let (f, t) = (&mut f[..n], &mut t[..n]);
    // Several batches are gathered before any is computed: a vector load of four values
    // stored one by one just before cannot be forwarded from the store buffer and stalls, so
    // the stores get time to retire (the first version, one batch at a time, was 15 % slower
    // than the scalar loop).
    let mut a = [lanes::Lanes::default(); BATCHES];
    // One material: every lane's pair constants are set once, not per contact.
    if ONE_MATERIAL && n > 0 {
        let pc = materials.pair(mat[0], mat[0]);
        for b in &mut a {
            for l in 0..lanes::LANES {
                b.set_pair(l, pc);
            }
        }
    }
    // Per lane: i, j and the history's index in `hist`.
    let mut who = [(0usize, 0usize, 0usize); BATCHES * lanes::LANES];
    let mut k = 0;
    for i in rows {
        let (xi, ri, mati) = (x[i], r[i], mat[i]);
        let driven_i = inv_m[i] == 0.0;
        debug_assert!(start[i] <= start[i + 1], "row starts ascending");
        let q0 = start[i] as usize - base;
        let q1 = q0 + near.len[i - near.row0] as usize;
        for &near::Entry {
            rj,
            r_eff,
            m_eff,
            e,
            j,
        } in &near.entries[q0..q1]
        {
            let (e, j) = (e as usize, j as usize);
            debug_assert_eq!(j, nb[e] as usize, "the near list's partner is the list's");
            debug_assert!(j > i, "{i} -> {j} is not a half-list entry");
            assert!(j < n, "list entry {i} -> {j} beyond the {n} particles");
            let le = e - base;
            let mut d = sub(xi, x[j]);
            if PERIODIC {
                d = pbox.min_image(d);
            }
            debug_assert_eq!(rj.to_bits(), r[j].to_bits(), "the near list's radius");
            let rsum = ri + rj;
            let dist2 = norm2(d);
            if dist2 >= rsum * rsum || (driven_i && inv_m[j] == 0.0) {
                if live[le] != 0 {
                    hist[le] = History::default();
                    live[le] = 0;
                }
                continue;
            }
            live[le] = 1;
            let v_rel = sub(v[i], v[j]);
            let (b, l) = (&mut a[k / lanes::LANES], k % lanes::LANES);
            for q in 0..3 {
                b.d[q][l] = d[q];
                b.v_rel[q][l] = v_rel[q];
                b.wi[q][l] = w[i][q];
                b.wj[q][l] = w[j][q];
                b.shear[q][l] = hist[le].shear[q];
                b.rolling[q][l] = hist[le].rolling[q];
            }
            b.dist2[l] = dist2;
            b.rsum[l] = rsum;
            b.ri[l] = ri;
            b.rj[l] = rj;
            b.r_eff[l] = r_eff;
            b.m_eff[l] = m_eff;
            if !ONE_MATERIAL {
                b.set_pair(l, materials.pair(mati, mat[j]));
            }
            who[k] = (i, j, le);
            k += 1;
            if k == who.len() {
                flush_lanes(&mut a, &who, k, dt, hist, f, t);
                k = 0;
            }
        }
    }
    if k > 0 {
        // The idle lanes of the last batch repeat its last contact: finite arithmetic, results
        // dropped.
        let last = &mut a[(k - 1) / lanes::LANES];
        for l in (k - 1) % lanes::LANES + 1..lanes::LANES {
            last.copy_lane((k - 1) % lanes::LANES, l);
        }
        flush_lanes(&mut a, &who, k, dt, hist, f, t);
    }
}

/// Batches of four gathered before they are computed ([`pair_rows_lanes`]).
const BATCHES: usize = 8;

/// The forces of a batch, added to the particles of lanes 0..count in lane order (so in list
/// order), and their histories stored. A function, not a closure, so that it is compiled
/// inline with its caller's instruction set.
#[inline(always)]
fn flush_lanes(
    a: &mut [lanes::Lanes; BATCHES],
    who: &[(usize, usize, usize); BATCHES * lanes::LANES],
    count: usize,
    dt: f64,
    hist: &mut [History],
    f: &mut [V3],
    t: &mut [V3],
) {
    // Each batch's forces are added right after they are computed: every batch was gathered
    // before the first is computed, and the lanes are still added in list order. (An array of
    // all batches' results cost a memset per flush: 4-5 % of a wide-PSD run, by perf.)
    for (b, who) in a.iter_mut().zip(who[..count].chunks(lanes::LANES)) {
        let out = lanes::forces(b, dt);
        for (l, &(i, j, e)) in who.iter().enumerate() {
            let lane = |q: &[[f64; lanes::LANES]; 3]| [q[0][l], q[1][l], q[2][l]];
            hist[e] = History {
                shear: lane(&b.shear),
                rolling: lane(&b.rolling),
            };
            let force = lane(&out.force);
            add_assign(&mut f[i], force);
            sub_assign(&mut f[j], force);
            add_assign(&mut t[i], lane(&out.torque_i));
            add_assign(&mut t[j], lane(&out.torque_j));
        }
    }
}

/// Contacts of rows `rows`; `hist` starts at list entry `base`. With `PERIODIC`, separations
/// are minimum images in `pbox`. Pairs of two driven particles are skipped as if apart.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn pair_rows<L: ContactLaw, const PERIODIC: bool>(
    law: &L,
    materials: &Materials,
    dt: f64,
    rows: Range<usize>,
    start: &[u32],
    nb: &[u32],
    near: Near,
    hist: &mut [History],
    live: &mut [u8],
    base: usize,
    p: P,
    pbox: &PeriodicBox,
    f: &mut [V3],
    t: &mut [V3],
) {
    // Every per-particle slice cut to the same length n, and each partner index tested once
    // against it: the compiler then drops the bounds checks of the many loads and stores by j.
    let n = p.x.len();
    let (x, r, inv_m, mat) = (&p.x[..n], &p.r[..n], &p.inv_m[..n], &p.mat[..n]);
    let (v, w) = (&p.v[..n], &p.w[..n]);
    let (f, t) = (&mut f[..n], &mut t[..n]);
    for i in rows {
        let (xi, ri, mati) = (x[i], r[i], mat[i]);
        let driven_i = inv_m[i] == 0.0;
        debug_assert!(start[i] <= start[i + 1], "row starts ascending");
        let q0 = start[i] as usize - base;
        let listed = &near.entries[q0..q0 + near.len[i - near.row0] as usize];
        // The near build has computed the partner, its radius and the effective radius and mass
        // with this loop's operations (`near::Entry`).
        for &near::Entry {
            rj,
            r_eff,
            m_eff,
            e,
            j,
        } in listed
        {
            let (e, j) = (e as usize, j as usize);
            debug_assert_eq!(j, nb[e] as usize, "the near list's partner is the list's");
            let (h, lv) = (&mut hist[e - base], &mut live[e - base]);
            // A half list: the team's buffers are cleared only from a member's first row on.
            debug_assert!(j > i, "{i} -> {j} is not a half-list entry");
            assert!(j < n, "list entry {i} -> {j} beyond the {n} particles");
            let mut d = sub(xi, x[j]);
            if PERIODIC {
                d = pbox.min_image(d);
            }
            let rsum = ri + rj;
            let dist2 = norm2(d);
            // A glued layer of driven particles exerts nothing on itself; the test costs a load
            // only for touching pairs.
            if dist2 >= rsum * rsum || (driven_i && inv_m[j] == 0.0) {
                // Most separated pairs have no history: skip them without loading it.
                if *lv != 0 {
                    *h = History::default();
                    *lv = 0;
                }
                continue;
            }
            *lv = 1;
            let dist = dist2.sqrt();
            let inv = 1.0 / dist;
            let n = scale(d, inv);
            let overlap = rsum - dist;
            let area = if L::NEEDS_AREA {
                // Area of the intersection circle of the two spheres.
                let q = (dist - ri - rj) * (dist + ri - rj) * (dist - ri + rj) * (dist + ri + rj);
                -std::f64::consts::PI / 4.0 * q * inv * inv
            } else {
                0.0
            };
            let c = Contact::new(
                n,
                overlap,
                r_eff,
                m_eff,
                sub(v[i], v[j]),
                w[i],
                w[j],
                ri - 0.5 * overlap,
                rj - 0.5 * overlap,
                area,
            );
            let pc = materials.pair(mati, mat[j]);
            let out = law.force(&c, pc, h, dt);
            add_assign(&mut f[i], out.force);
            sub_assign(&mut f[j], out.force);
            add_assign(&mut t[i], out.torque_i);
            add_assign(&mut t[j], out.torque_j);
        }
    }
}
