//! Neighbour search: a cell grid, particles sorted by cell, and a half Verlet list in compressed
//! rows with the contact history of every pair stored beside it.
//!
//! The list holds every pair closer than r_i + r_j + skin and is rebuilt when some particle has
//! moved more than skin / 2 since the last build (the LAMMPS/LIGGGHTS criterion). At a rebuild the
//! particles are reordered by cell, so that neighbours in space are neighbours in memory, and the
//! history of every pair still in contact is carried to the new list by merging sorted pairs.

use super::contact::History;
use super::particles::{Particles, PermuteScratch};
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
    /// Contact history per list entry.
    pub hist: Vec<History>,
    /// Per list entry: 0 promises that its history is zero. Most entries are separated pairs;
    /// the force loop then skips them without touching their 48-byte histories.
    pub live: Vec<u8>,
    x_build: Vec<V3>,
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
}

impl NeighborList {
    /// An empty list with this skin (m); the first [`NeighborList::rebuild`] fills it.
    pub fn new(skin: f64) -> Self {
        NeighborList {
            skin,
            ..Default::default()
        }
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
    pub fn rebuild(&mut self, p: &mut Particles, wall_hist: &mut Vec<History>, n_walls: usize) {
        let n = p.len();
        self.builds += 1;
        if n == 0 {
            self.start.clear();
            self.start.push(0);
            self.nb.clear();
            self.hist.clear();
            self.live.clear();
            self.x_build.clear();
            return;
        }
        // Grid over the particles' bounding box; cells at least as large as the largest cutoff.
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

        // Forward half stencil: neighbour cells with a larger linear index, in increasing order,
        // so every row comes out sorted.
        const STENCIL: [(i64, i64, i64); 13] = [
            (0, 0, 1),
            (0, 1, -1),
            (0, 1, 0),
            (0, 1, 1),
            (1, -1, -1),
            (1, -1, 0),
            (1, -1, 1),
            (1, 0, -1),
            (1, 0, 0),
            (1, 0, 1),
            (1, 1, -1),
            (1, 1, 0),
            (1, 1, 1),
        ];
        let stencil = &STENCIL;
        self.start.clear();
        self.new_nb.clear();
        let skin = self.skin;
        let mut ci = 0usize;
        for i in 0..n {
            self.start.push(self.new_nb.len() as u32);
            let c = self.cell_of[i] as usize;
            let (ix, iy, iz) = (
                c % dims[0],
                (c / dims[0]) % dims[1],
                c / (dims[0] * dims[1]),
            );
            let xi = p.x[i];
            let ri = p.r[i] + skin;
            // Own cell: later particles only.
            let end = self.cell_start[c + 1] as usize;
            for j in i + 1..end {
                let cut = ri + p.r[j];
                if norm2(sub(xi, p.x[j])) < cut * cut {
                    self.new_nb.push(j as u32);
                }
            }
            for &(dz, dy, dx) in stencil {
                let (jx, jy, jz) = (ix as i64 + dx, iy as i64 + dy, iz as i64 + dz);
                if jx < 0
                    || jy < 0
                    || jz < 0
                    || jx >= dims[0] as i64
                    || jy >= dims[1] as i64
                    || jz >= dims[2] as i64
                {
                    continue;
                }
                let cj = ((jz as usize * dims[1]) + jy as usize) * dims[0] + jx as usize;
                for j in self.cell_start[cj] as usize..self.cell_start[cj + 1] as usize {
                    let cut = ri + p.r[j];
                    if norm2(sub(xi, p.x[j])) < cut * cut {
                        self.new_nb.push(j as u32);
                    }
                }
            }
            // Merge the carried histories of row i.
            let row = self.start[i] as usize;
            self.new_hist.resize(self.new_nb.len(), History::default());
            for e in row..self.new_nb.len() {
                self.new_hist[e] = History::default();
            }
            let mut e = row;
            while ci < self.carried.len() && self.carried[ci].0 as usize == i {
                let (_, b, h) = self.carried[ci];
                while e < self.new_nb.len() && self.new_nb[e] < b {
                    e += 1;
                }
                if e < self.new_nb.len() && self.new_nb[e] == b {
                    self.new_hist[e] = h;
                }
                ci += 1;
            }
        }
        self.start.push(self.new_nb.len() as u32);
        self.new_hist.truncate(self.new_nb.len());
        std::mem::swap(&mut self.nb, &mut self.new_nb);
        std::mem::swap(&mut self.hist, &mut self.new_hist);
        self.live.clear();
        self.live
            .extend(self.hist.iter().map(|h| u8::from(!h.is_zero())));
        self.x_build.clear();
        self.x_build.extend_from_slice(&p.x);
    }

    /// After the counting sort, particle k sits in the cell whose range contains k.
    fn cell_of_sorted(&self, k: usize) -> u32 {
        // partition_point over cell_start: the last cell whose start <= k.
        (self.cell_start.partition_point(|&s| s as usize <= k) - 1) as u32
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
}
