//! Neighbour search: a cell grid, particles sorted by cell, and a half Verlet list in compressed
//! rows with the contact history of every pair stored beside it.
//!
//! The list holds every pair closer than r_i + r_j + skin and is rebuilt when some particle has
//! moved more than skin / 2 since the last build (the LAMMPS/LIGGGHTS criterion). At a rebuild the
//! particles are reordered by cell, so that neighbours in space are neighbours in memory, and the
//! history of every pair still in contact is carried to the new list by merging sorted pairs.
//!
//! With periodic axes ([`NeighborList::with_periodic`]) a rebuild first wraps the positions into
//! the period box, the grid spans exactly that box along the periodic axes, the search wraps
//! around it and distances are minimum-image ones.

use super::contact::History;
use super::near;
use super::particles::{Particles, PermuteScratch};
use super::periodic::PeriodicBox;
use super::vec3::*;

/// The half Verlet list in compressed rows (CSR), with one contact history per entry.
#[derive(Debug, Default, Clone)]
pub struct NeighborList {
    /// Skin distance, m: pairs within r_i + r_j + skin are listed, so the list stays valid until
    /// some particle has moved skin / 2. Larger skins rebuild less often but list more pairs;
    /// mbgc uses a fraction of the smallest diameter.
    pub skin: f64,
    /// Row i holds partners `nb[start[i]..start[i + 1]]`, all with index > i, ascending.
    pub start: Vec<u32>,
    /// Partner indices of all rows, concatenated (see `start`).
    pub nb: Vec<u32>,
    /// Contact history per list entry. Whoever makes a history non-zero sets its `live` flag:
    /// a rebuild carries only the histories of live entries.
    pub hist: Vec<History>,
    /// Per list entry: 0 promises that its history is zero. Most entries are separated pairs;
    /// the force loop then skips them without touching their 48-byte histories.
    pub live: Vec<u8>,
    /// The near list (`crate::near`): row i's entries closer than touching plus the near skin,
    /// in `near[start[i]..start[i] + near_len[i]]`. Rebuilt by the step
    /// at the first step of every run and whenever it is used up.
    pub(crate) near: Vec<near::Entry>,
    pub(crate) near_len: Vec<u32>,
    /// Positions at the last near build.
    pub(crate) x_near: Vec<V3>,
    /// Whether the near list is valid for the particles as the last step left them: false after
    /// a rebuild outside the step, which the step's next run then follows with a near build.
    pub(crate) near_fresh: bool,
    /// With `near_fresh`: the skin for which every particle's near skin plus its distance from
    /// its list build position stayed within half the skin at the near build (`crate::step`),
    /// which spares the step the list's displacement check of particles inside their near skin.
    /// `None` if not, after a rebuild, and while a run is under way (a run stopped by a failed
    /// check leaves it so).
    pub(crate) near_bounded: Option<f64>,
    /// Per particle: its squared near skin at the last near build (how far it may move).
    pub(crate) near_s2: Vec<f64>,
    /// Per particle: radius plus the near skin its speed asked for at the near build.
    pub(crate) reach: Vec<f64>,
    x_build: Vec<V3>,
    pbox: PeriodicBox,
    /// Number of rebuilds so far (for performance reports: a run rebuilding every few steps has
    /// too small a skin).
    pub builds: u64,
    // Scratch kept between builds so a rebuild does not allocate once warmed up.
    cell_of: Vec<u32>,
    cell_start: Vec<u32>,
    order: Vec<u32>,
    new_index: Vec<u32>,
    carried: Vec<(u32, u32, History)>,
    permute: PermuteScratch,
    wall_scratch: Vec<History>,
    new_nb: Vec<u32>,
    new_hist: Vec<History>,
    fine: FineGrid,
}

/// The search grid of a closed domain: cells of half the sorting grid's size, aligned with it,
/// holding each particle's position and radius in cell order. A particle searches only the
/// fine cells its own largest cutoff r_i + skin + r_max reaches, where the sorting grid's cells
/// (sized for the largest pair) would make the small particles of a wide size distribution test
/// several times the partners they can have. The sorting grid still orders the particles, so
/// every result stays what it was. The list too, but for one rounding edge in the new search's
/// favour: when the sorting cell size rounds an ulp below the cutoff, the 13-cell search could
/// miss a pair about one cell apart, which the fine cells list; with a positive skin such a
/// pair is farther apart than touching, so no force or history changes.
#[derive(Debug, Default, Clone)]
struct FineGrid {
    start: Vec<u32>,
    /// Per slot: the particle's index in the sorted order.
    index: Vec<u32>,
    /// Per slot: x, y, z and the radius.
    pts: Vec<[f64; 4]>,
    cursor: Vec<u32>,
}

impl NeighborList {
    /// An empty list with this skin (m); the first [`NeighborList::rebuild`] fills it.
    pub fn new(skin: f64) -> Self {
        NeighborList {
            skin,
            ..Default::default()
        }
    }

    /// An empty list with this skin (m) for a domain periodic as `pbox`.
    pub fn with_periodic(skin: f64, pbox: PeriodicBox) -> Self {
        NeighborList {
            skin,
            pbox,
            ..Default::default()
        }
    }

    /// The period box the list wraps positions into ([`PeriodicBox::NONE`] if none).
    pub fn periodic_box(&self) -> PeriodicBox {
        self.pbox
    }

    /// Whether some particle moved more than half the skin since the last build.
    pub fn needs_rebuild(&self, x: &[V3]) -> bool {
        if self.x_build.len() != x.len() {
            return true;
        }
        let lim = 0.25 * self.skin * self.skin;
        x.iter()
            .zip(&self.x_build)
            .any(|(a, b)| norm2(sub(*a, *b)) > lim)
    }

    /// Positions at the last build (empty before the first).
    pub fn x_build(&self) -> &[V3] {
        &self.x_build
    }

    /// Number of list entries (pairs within the cutoff).
    pub fn pairs(&self) -> usize {
        self.nb.len()
    }

    /// Sorts the particles by cell, rebuilds the list and carries the history of touching pairs.
    /// `wall_hist` holds `n_walls` entries per particle and is reordered with the particles.
    /// Along periodic axes the positions are wrapped into the period box first.
    ///
    /// Along a periodic axis, the period must exceed twice the largest cutoff 2 r_max + skin
    /// ([`crate::Simulation::new`] checks it): a pair is listed once, through its nearest image.
    pub fn rebuild(&mut self, p: &mut Particles, wall_hist: &mut Vec<History>, n_walls: usize) {
        let n = p.len();
        self.builds += 1;
        self.near_fresh = false;
        self.near_bounded = None;
        if n == 0 {
            self.start.clear();
            self.start.push(0);
            self.nb.clear();
            self.hist.clear();
            self.live.clear();
            self.x_build.clear();
            self.near.clear();
            self.near_len.clear();
            self.x_near.clear();
            self.near_s2.clear();
            self.reach.clear();
            return;
        }
        let pbox = self.pbox;
        let periodic = pbox.any();
        if periodic {
            // Before the sort, so that cells, the list and `x_build` all see the wrapped
            // positions (the displacement test then measures the drift since this build).
            for x in p.x.iter_mut() {
                *x = pbox.wrap(*x);
            }
        }
        // Grid over the particles' bounding box, exactly the period box along periodic axes;
        // cells at least as large as the largest cutoff.
        let r_max = p.r.iter().copied().fold(0.0, f64::max);
        let mut h = 2.0 * r_max + self.skin;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for x in &p.x {
            for k in 0..3 {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
        for k in (0..3).filter(|&k| pbox.is_periodic(k)) {
            lo[k] = pbox.lo()[k];
            hi[k] = lo[k] + pbox.period()[k];
        }
        let cells_along = |h: f64| -> [usize; 3] {
            let mut d = [1usize; 3];
            for k in 0..3 {
                d[k] = (((hi[k] - lo[k]) / h).floor() as usize).max(1);
            }
            d
        };
        let mut dims = cells_along(h);
        // A stray particle must not blow the grid up: cap the cell count at a few per particle.
        while (dims[0] * dims[1] * dims[2]) > 8 * n + 64 {
            h *= 1.5;
            dims = cells_along(h);
        }
        let size = [
            (hi[0] - lo[0]) / dims[0] as f64,
            (hi[1] - lo[1]) / dims[1] as f64,
            (hi[2] - lo[2]) / dims[2] as f64,
        ];
        let n_cells = dims[0] * dims[1] * dims[2];
        let coord = |x: f64, k: usize| -> usize {
            if size[k] > 0.0 {
                (((x - lo[k]) / size[k]) as usize).min(dims[k] - 1)
            } else {
                0
            }
        };
        self.cell_of.clear();
        self.cell_of.extend(p.x.iter().map(|x| {
            ((coord(x[2], 2) * dims[1] + coord(x[1], 1)) * dims[0] + coord(x[0], 0)) as u32
        }));
        // Counting sort by cell (stable).
        self.cell_start.clear();
        self.cell_start.resize(n_cells + 1, 0);
        for &c in &self.cell_of {
            self.cell_start[c as usize + 1] += 1;
        }
        for c in 0..n_cells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.order.clear();
        self.order.resize(n, 0);
        {
            let mut fill: Vec<u32> = Vec::new();
            std::mem::swap(&mut fill, &mut self.new_nb); // reuse as a cursor buffer
            fill.clear();
            fill.extend_from_slice(&self.cell_start[..n_cells]);
            for (i, &c) in self.cell_of.iter().enumerate() {
                let slot = &mut fill[c as usize];
                self.order[*slot as usize] = i as u32;
                *slot += 1;
            }
            std::mem::swap(&mut fill, &mut self.new_nb);
        }
        self.new_index.clear();
        self.new_index.resize(n, 0);
        for (k, &old) in self.order.iter().enumerate() {
            self.new_index[old as usize] = k as u32;
        }

        // Histories worth keeping, in new indices, oriented from the lower to the higher index.
        self.carried.clear();
        if self.start.len() == n + 1 {
            for i in 0..n {
                for e in self.start[i] as usize..self.start[i + 1] as usize {
                    // `live` promises the zero histories of most entries from one byte each,
                    // where reading them would stream the whole history array.
                    if self.live[e] == 0 {
                        continue;
                    }
                    let h = self.hist[e];
                    if h.is_zero() {
                        continue;
                    }
                    let a = self.new_index[i];
                    let b = self.new_index[self.nb[e] as usize];
                    if a < b {
                        self.carried.push((a, b, h));
                    } else {
                        // Swapping the roles of i and j flips both history vectors.
                        let flipped = History {
                            shear: scale(h.shear, -1.0),
                            rolling: scale(h.rolling, -1.0),
                        };
                        self.carried.push((b, a, flipped));
                    }
                }
            }
        }
        self.carried.sort_unstable_by_key(|&(a, b, _)| (a, b));

        p.permute(&self.order, &mut self.permute);
        if n_walls > 0 {
            self.wall_scratch.clear();
            for &old in &self.order {
                let o = old as usize * n_walls;
                self.wall_scratch
                    .extend_from_slice(&wall_hist[o..o + n_walls]);
            }
            std::mem::swap(wall_hist, &mut self.wall_scratch);
        }
        // Cell of each particle in the new order.
        for k in 0..n {
            self.cell_of[k] = self.cell_of_sorted(k);
        }
        // Fine cells: half the sorting cells, aligned with them. Halving the size is exact in
        // floating point (along an axis of two or more cells they are at least a cutoff wide,
        // never subnormal; along an axis of one, every fine coordinate halves to 0 anyway), so
        // a particle's fine coordinate halved (rounded down) is its sorting coordinate, which
        // the search relies on to skip the cells below its own.
        let fsize = [0.5 * size[0], 0.5 * size[1], 0.5 * size[2]];
        let fdims = [2 * dims[0], 2 * dims[1], 2 * dims[2]];
        let fcoord = move |x: f64, k: usize| -> usize {
            if fsize[k] > 0.0 {
                (((x - lo[k]) / fsize[k]) as usize).min(fdims[k] - 1)
            } else {
                0
            }
        };
        if !periodic {
            self.fine.fill(&p.x, &p.r, fdims, fcoord);
        }

        self.start.clear();
        self.new_nb.clear();
        // From here on `live` describes the new list: only the carried histories are live.
        self.live.clear();
        let skin = self.skin;
        let mut ci = 0usize;
        // Periodic search: the distinct cells around the current one with an index >= its own,
        // ascending (particles are sorted by cell, so a partner j > i lies in such a cell, and
        // ascending cells give an ascending row). Wrapped offsets can meet the same cell twice
        // when an axis has fewer than three cells; the dedup lists each pair once.
        let mut around = [0u32; 27];
        let mut n_around = 0usize;
        let mut around_of = usize::MAX;
        for i in 0..n {
            self.start.push(self.new_nb.len() as u32);
            let c = self.cell_of[i] as usize;
            let xi = p.x[i];
            let ri = p.r[i] + skin;
            if periodic {
                if around_of != c {
                    around_of = c;
                    n_around = 0;
                    let at = [
                        c % dims[0],
                        (c / dims[0]) % dims[1],
                        c / (dims[0] * dims[1]),
                    ];
                    for dz in -1i64..=1 {
                        for dy in -1i64..=1 {
                            for dx in -1i64..=1 {
                                let mut q = [0usize; 3];
                                let mut inside = true;
                                for (k, d) in [dx, dy, dz].into_iter().enumerate() {
                                    let j = at[k] as i64 + d;
                                    let m = dims[k] as i64;
                                    q[k] = if pbox.is_periodic(k) {
                                        j.rem_euclid(m) as usize
                                    } else if (0..m).contains(&j) {
                                        j as usize
                                    } else {
                                        inside = false;
                                        0
                                    };
                                }
                                let cj = (q[2] * dims[1] + q[1]) * dims[0] + q[0];
                                if inside && cj >= c {
                                    around[n_around] = cj as u32;
                                    n_around += 1;
                                }
                            }
                        }
                    }
                    let cells = &mut around[..n_around];
                    cells.sort_unstable();
                    let mut kept = 0;
                    for k in 0..cells.len() {
                        if k == 0 || cells[k] != cells[kept - 1] {
                            cells[kept] = cells[k];
                            kept += 1;
                        }
                    }
                    n_around = kept;
                }
                for &cj in &around[..n_around] {
                    let cj = cj as usize;
                    let first = if cj == c {
                        i + 1
                    } else {
                        self.cell_start[cj] as usize
                    };
                    for j in first..self.cell_start[cj + 1] as usize {
                        let cut = ri + p.r[j];
                        if norm2(pbox.min_image(sub(xi, p.x[j]))) < cut * cut {
                            self.new_nb.push(j as u32);
                        }
                    }
                }
            } else {
                self.fine.row(
                    i,
                    c,
                    &xi,
                    ri + r_max,
                    p.r[i] + skin,
                    dims,
                    fcoord,
                    &mut self.new_nb,
                );
            }
            // Merge the carried histories of row i.
            let row = self.start[i] as usize;
            self.new_hist.resize(self.new_nb.len(), History::default());
            for e in row..self.new_nb.len() {
                self.new_hist[e] = History::default();
            }
            self.live.resize(self.new_nb.len(), 0);
            let mut e = row;
            while ci < self.carried.len() && self.carried[ci].0 as usize == i {
                let (_, b, h) = self.carried[ci];
                while e < self.new_nb.len() && self.new_nb[e] < b {
                    e += 1;
                }
                if e < self.new_nb.len() && self.new_nb[e] == b {
                    self.new_hist[e] = h;
                    self.live[e] = 1;
                }
                ci += 1;
            }
        }
        self.start.push(self.new_nb.len() as u32);
        self.new_hist.truncate(self.new_nb.len());
        std::mem::swap(&mut self.nb, &mut self.new_nb);
        std::mem::swap(&mut self.hist, &mut self.new_hist);
        self.live.truncate(self.nb.len());
        self.x_build.clear();
        self.x_build.extend_from_slice(&p.x);
        // Sized for the step, which fills them (a near list lives no longer than its list).
        self.near.resize(self.nb.len(), near::Entry::default());
        self.near_len.resize(n, 0);
        self.x_near.clear();
        self.x_near.extend_from_slice(&p.x);
        self.near_s2.clear();
        self.near_s2.resize(n, 0.0);
        self.reach.resize(n, 0.0);
    }

    /// After the counting sort, particle k sits in the cell whose range contains k.
    fn cell_of_sorted(&self, k: usize) -> u32 {
        // partition_point over cell_start: the last cell whose start <= k.
        (self.cell_start.partition_point(|&s| s as usize <= k) - 1) as u32
    }
}

impl FineGrid {
    /// Sorts the particles (already in sorting-grid order) into the fine cells; each cell keeps
    /// them in ascending index.
    fn fill(
        &mut self,
        x: &[V3],
        r: &[f64],
        fdims: [usize; 3],
        fcoord: impl Fn(f64, usize) -> usize,
    ) {
        let n_cells = fdims[0] * fdims[1] * fdims[2];
        let cell =
            |x: &V3| (fcoord(x[2], 2) * fdims[1] + fcoord(x[1], 1)) * fdims[0] + fcoord(x[0], 0);
        self.start.clear();
        self.start.resize(n_cells + 1, 0);
        for x in x {
            self.start[cell(x) + 1] += 1;
        }
        for c in 0..n_cells {
            self.start[c + 1] += self.start[c];
        }
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.start[..n_cells]);
        self.index.resize(x.len(), 0);
        self.pts.resize(x.len(), [0.0; 4]);
        for (k, (x, &r)) in x.iter().zip(r).enumerate() {
            let slot = &mut self.cursor[cell(x)];
            self.index[*slot as usize] = k as u32;
            self.pts[*slot as usize] = [x[0], x[1], x[2], r];
            *slot += 1;
        }
    }

    /// Appends row i of the half list to `out`, ascending: every j > i closer than
    /// r_i + skin + r_j. `reach` is r_i + skin + r_max, `c` the sorting cell of particle i.
    /// Partners j > i lie in sorting cells at or after c, so the fine cells before it are
    /// skipped whole.
    #[allow(clippy::too_many_arguments)]
    fn row(
        &self,
        i: usize,
        c: usize,
        xi: &V3,
        reach: f64,
        ri_skin: f64,
        dims: [usize; 3],
        fcoord: impl Fn(f64, usize) -> usize,
        out: &mut Vec<u32>,
    ) {
        let (cx, cy, cz) = (
            c % dims[0],
            (c / dims[0]) % dims[1],
            c / (dims[0] * dims[1]),
        );
        let fdx = 2 * dims[0];
        let fdy = 2 * dims[1];
        let lo = |k: usize| fcoord(xi[k] - reach, k);
        let hi = |k: usize| fcoord(xi[k] + reach, k);
        let (ax, bx) = (lo(0), hi(0));
        let (ay, by) = (lo(1), hi(1));
        let first = out.len();
        let i32_ = i as u32;
        for fz in lo(2).max(2 * cz)..=hi(2) {
            for fy in ay..=by {
                let x0 = if fz / 2 > cz || fy / 2 > cy {
                    ax
                } else if fy / 2 == cy {
                    ax.max(2 * cx)
                } else {
                    continue;
                };
                if x0 > bx {
                    continue;
                }
                let row = (fz * fdy + fy) * fdx;
                let (s, e) = (
                    self.start[row + x0] as usize,
                    self.start[row + bx + 1] as usize,
                );
                // Written without a branch: which candidates are partners is unpredictable,
                // and a mispredicted branch costs more than the store.
                out.reserve(e - s);
                let spare = out.spare_capacity_mut();
                let mut kept = 0;
                for (&j, q) in self.index[s..e].iter().zip(&self.pts[s..e]) {
                    let d = [xi[0] - q[0], xi[1] - q[1], xi[2] - q[2]];
                    let cut = ri_skin + q[3];
                    let near = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < cut * cut;
                    // Every candidate is written to the next free slot, which only a partner
                    // then keeps; kept <= candidates seen < e - s, within the reserve.
                    spare[kept].write(j);
                    kept += usize::from((j > i32_) & near);
                }
                // SAFETY: the slots 0..kept of the spare capacity were written in this pass.
                unsafe { out.set_len(out.len() + kept) };
            }
        }
        out[first..].sort_unstable();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_exactly_the_pairs_within_the_cutoff_and_keeps_history() {
        let mut p = Particles::new();
        let mut rng = crate::test_rng(4);
        use rand::RngExt;
        for _ in 0..300 {
            let x = [
                rng.random::<f64>(),
                rng.random::<f64>(),
                rng.random::<f64>(),
            ];
            p.add(x, 0.02 + 0.03 * rng.random::<f64>(), 1000.0, 0)
                .unwrap();
        }
        let mut nl = NeighborList::new(0.01);
        let mut wh = Vec::new();
        nl.rebuild(&mut p, &mut wh, 0);
        let mut brute = 0;
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                let cut = p.r[i] + p.r[j] + 0.01;
                if norm2(sub(p.x[i], p.x[j])) < cut * cut {
                    brute += 1;
                    let row = &nl.nb[nl.start[i] as usize..nl.start[i + 1] as usize];
                    assert!(row.contains(&(j as u32)), "pair {i} {j} missing");
                }
            }
        }
        assert_eq!(nl.pairs(), brute);
        // Mark histories by particle ids, shuffle positions slightly, rebuild: histories follow.
        let mut marks = std::collections::HashMap::new();
        for i in 0..p.len() {
            for e in nl.start[i] as usize..nl.start[i + 1] as usize {
                let j = nl.nb[e] as usize;
                let v = (p.id[i] * 1000 + p.id[j]) as f64;
                nl.hist[e].shear = [v, 0.0, 0.0];
                nl.live[e] = 1;
                marks.insert((p.id[i], p.id[j]), v);
            }
        }
        for x in p.x.iter_mut() {
            x[0] += 0.001;
        }
        nl.rebuild(&mut p, &mut wh, 0);
        let mut seen = 0;
        for i in 0..p.len() {
            for e in nl.start[i] as usize..nl.start[i + 1] as usize {
                let j = nl.nb[e] as usize;
                let s = nl.hist[e].shear[0];
                if let Some(v) = marks.get(&(p.id[i], p.id[j])) {
                    assert_eq!(s, *v);
                    seen += 1;
                } else if let Some(v) = marks.get(&(p.id[j], p.id[i])) {
                    assert_eq!(s, -*v, "swapped pair must flip its history");
                    seen += 1;
                }
            }
        }
        assert_eq!(seen, marks.len());
    }

    /// A wide size distribution (radii over a factor 8) in a pile with empty space around it:
    /// the fine search finds exactly the brute-force pairs, rows ascending above the diagonal.
    #[test]
    fn a_wide_size_distribution_gets_exactly_the_brute_force_list() {
        use rand::RngExt;
        let mut rng = crate::test_rng(11);
        let mut p = Particles::new();
        for k in 0..600 {
            let r = 0.005 * 8f64.powf(rng.random::<f64>());
            let spread = if k % 50 == 0 { 2.0 } else { 0.3 };
            let x = [
                spread * rng.random::<f64>(),
                0.3 * rng.random::<f64>(),
                -1.0 + spread * rng.random::<f64>(),
            ];
            p.add(x, r, 1000.0, 0).unwrap();
        }
        let skin = 0.01;
        let mut nl = NeighborList::new(skin);
        nl.rebuild(&mut p, &mut Vec::new(), 0);
        let mut brute = 0;
        for i in 0..p.len() {
            let row = &nl.nb[nl.start[i] as usize..nl.start[i + 1] as usize];
            assert!(row.windows(2).all(|w| w[0] < w[1]), "row {i}: {row:?}");
            assert!(row.iter().all(|&j| j as usize > i), "row {i}: {row:?}");
            for j in i + 1..p.len() {
                let c = p.r[i] + skin + p.r[j];
                if norm2(sub(p.x[i], p.x[j])) < c * c {
                    brute += 1;
                    assert!(row.contains(&(j as u32)), "pair {i} {j} missing");
                }
            }
        }
        assert_eq!(nl.pairs(), brute);
        assert!(brute > 600, "the test must see pairs: {brute}");
    }

    /// Every pair within the cutoff through its nearest image, listed once, in ascending rows of
    /// partners above the row, for boxes of one, two and many cells along the periodic axes.
    #[test]
    fn periodic_lists_hold_each_nearest_image_pair_once() {
        use crate::periodic::PeriodicBox;
        use rand::RngExt;
        let mut rng = crate::test_rng(8);
        let (r, skin) = (0.02, 0.01);
        let cut = 2.0 * r + skin;
        // First box, x: barely over two cutoffs (two cells), y: many cells; z is not periodic.
        // The last box holds 12 particles spread 3 m in z, so that the cell cap (8 n + 64)
        // coarsens the grid to one cell along x and y, where every wrapped offset is the cell
        // itself.
        for (lx, ly, n, height) in [
            (2.05 * cut, 1.0, 300, 0.3),
            (0.3, 0.25, 400, 0.3),
            (2.2 * cut, 2.2 * cut, 12, 3.0),
        ] {
            let pbox =
                PeriodicBox::new(([0.0, -0.5, 0.0], [lx, ly - 0.5, 1.0]), [true, true, false])
                    .unwrap();
            let mut p = Particles::new();
            for k in 0..n {
                // Some start outside the box: the rebuild wraps them in.
                let z = match (height > 1.0, k) {
                    (true, 0) => 0.0,
                    (true, 1) => height,
                    (true, _) => 0.05 * rng.random::<f64>(),
                    _ => height * rng.random::<f64>(),
                };
                let x = [
                    -lx + 3.0 * lx * rng.random::<f64>(),
                    -0.5 + ly * rng.random::<f64>(),
                    z,
                ];
                p.add(x, r * (0.5 + 0.5 * rng.random::<f64>()), 1000.0, 0)
                    .unwrap();
            }
            let mut nl = NeighborList::with_periodic(skin, pbox);
            nl.rebuild(&mut p, &mut Vec::new(), 0);
            let lo = pbox.lo();
            for x in &p.x {
                assert!(x[0] >= lo[0] && x[0] < lo[0] + lx, "wrapped in x: {x:?}");
                assert!(x[1] >= lo[1] && x[1] < lo[1] + ly, "wrapped in y: {x:?}");
            }
            assert_eq!(
                nl.x_build(),
                &p.x[..],
                "the build remembers wrapped positions"
            );
            let mut brute = 0;
            for i in 0..p.len() {
                let row = &nl.nb[nl.start[i] as usize..nl.start[i + 1] as usize];
                assert!(
                    row.windows(2).all(|w| w[0] < w[1]),
                    "row {i} ascending: {row:?}"
                );
                assert!(
                    row.iter().all(|&j| j as usize > i),
                    "row {i} above the diagonal"
                );
                for j in i + 1..p.len() {
                    let c = p.r[i] + p.r[j] + skin;
                    if norm2(pbox.min_image(sub(p.x[i], p.x[j]))) < c * c {
                        brute += 1;
                        assert!(row.contains(&(j as u32)), "pair {i} {j} missing");
                    }
                }
            }
            assert_eq!(nl.pairs(), brute, "box {lx} x {ly}");
            assert!(brute > n / 3, "the test must see pairs: {brute}");
        }
    }
}
