//! The near list: the entries of the Verlet list whose spheres are within a small skin of
//! touching, rebuilt from that list far more often than the list itself is rebuilt from the
//! cell grid.
//!
//! The Verlet list's skin is wide (a whole smallest diameter in the shear box) so that the
//! pouring column can fall many steps between grid searches; in a settled bed it then lists
//! about nine pairs for every pair in contact, and testing those separated pairs every step was
//! 40 % of the force loop. The near list keeps, per row, only the entries closer than
//! r_i + s_i + r_j + s_j, where each particle's near skin s_k is what it would cover at its
//! current speed in a few steps ([`near_skin`]): a particle at rest gets a sliver, a falling one
//! half the Verlet skin. It stays valid until some particle has moved its own s_k since the
//! build. One fast particle thus shortens the life of the near list only if it speeds up, not
//! the near skins of all the others.
//!
//! The contacts computed are the same contacts in the same order as a scan of the whole list,
//! so a run's results are the same bits: a pair left out is farther apart than touching until
//! the next near build, and a pair left out while its history is still set (it separated in
//! this very step) has its history cleared here, in the step where the whole scan would have
//! cleared it.
//!
//! Storage: row i's near entries are kept in the Verlet list's own range of row i
//! (`near[start[i]..start[i] + near_len[i]]`, each an [`Entry`]: the list entry's index with
//! the partner, its radius and the pair's effective radius and mass, so that the force loop
//! reads in order what it would otherwise look up through the list or divide anew every step),
//! and every member of a thread team rebuilds the rows it computes without a global prefix sum.

use super::contact::History;
use super::periodic::PeriodicBox;
use super::vec3::*;

/// Steps a particle moving at its current speed takes to use up its near skin.
pub(crate) const TARGET_STEPS: f64 = 16.0;
/// Smallest near skin, as a fraction of the Verlet skin: a particle at rest still gets this
/// much, so that a bed at rest does not rebuild the near list at every tremor.
pub(crate) const MIN_FRACTION: f64 = 0.02;

/// The near skin of a particle moving at `speed` (m/s): what it covers in [`TARGET_STEPS`]
/// steps of `dt`, between [`MIN_FRACTION`] of the Verlet skin and half of it (two particles
/// of half the skin each take the whole skin). A speed that is not finite gives half the skin.
pub(crate) fn near_skin(speed: f64, dt: f64, skin: f64) -> f64 {
    let s = TARGET_STEPS * speed * dt;
    if !s.is_finite() {
        return 0.5 * skin;
    }
    s.clamp(MIN_FRACTION * skin, 0.5 * skin)
}

/// The Verlet list's rows `rows`, seen by the near build.
pub(crate) struct Rows<'a> {
    /// Row starts of the Verlet list (all rows).
    pub start: &'a [u32],
    /// Partners of all rows.
    pub nb: &'a [u32],
    /// Entry index of `hist[0]`, `live[0]` and `near[0]` (the rows' first entry).
    pub base: usize,
    /// First row of `near_len[0]`.
    pub row0: usize,
}

/// One entry of the near list: besides the index `e` of its Verlet list entry, what the force
/// loop of the common law would otherwise look up or divide anew every step. 32 bytes, read in
/// order.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub(crate) struct Entry {
    /// Radius of the partner.
    pub rj: f64,
    /// Effective radius r_i r_j / (r_i + r_j).
    pub r_eff: f64,
    /// Effective mass m_i m_j / (m_i + m_j).
    pub m_eff: f64,
    /// Index of the Verlet list entry.
    pub e: u32,
    /// The partner j (`nb[e]`).
    pub j: u32,
}

/// The near list of some rows, as the build writes it.
pub(crate) struct Out<'a> {
    pub near: &'a mut [Entry],
    pub near_len: &'a mut [u32],
}

/// Rebuilds the near list of `rows` from positions `x` and each particle's reach (its radius
/// plus its near skin): an entry is kept if its spheres are closer than the sum of their
/// reaches, or always with `all`. Clears the history of every entry left out that still has one.
/// The effective radius r_i r_j / (r_i + r_j) and mass m_i m_j / (m_i + m_j) of a kept pair are
/// the force loop's operations in its order, so its results stay the same bits.
#[allow(clippy::too_many_arguments)]
#[allow(clippy::needless_range_loop)] // e indexes nb and, offset by base, hist and live
pub(crate) fn build<const PERIODIC: bool>(
    rows: std::ops::Range<usize>,
    list: Rows,
    (x, r, m): (&[V3], &[f64], &[f64]),
    reach: &[f64],
    pbox: &PeriodicBox,
    all: bool,
    out: Out,
    hist: &mut [History],
    live: &mut [u8],
) {
    let n = x.len();
    let (x, r, m) = (&x[..n], &r[..n], &m[..n]);
    let reach = if all { reach } else { &reach[..n] };
    let Out { near, near_len } = out;
    let Rows {
        start,
        nb,
        base,
        row0,
    } = list;
    for i in rows {
        let (xi, ri) = (x[i], reach[i]);
        let (e0, e1) = (start[i] as usize, start[i + 1] as usize);
        let mut kept = e0 - base;
        for e in e0..e1 {
            let j = nb[e] as usize;
            assert!(j < n, "list entry {i} -> {j} beyond the {n} particles");
            let mut d = sub(xi, x[j]);
            if PERIODIC {
                d = pbox.min_image(d);
            }
            let cut = ri + reach[j];
            let le = e - base;
            // A NaN distance is kept, as the whole list's force loop takes it for a contact.
            let d2 = norm2(d);
            if all || d2 < cut * cut || d2.is_nan() {
                let (ri, rj, mi, mj) = (r[i], r[j], m[i], m[j]);
                near[kept] = Entry {
                    rj,
                    r_eff: ri * rj / (ri + rj),
                    m_eff: mi * mj / (mi + mj),
                    e: e as u32,
                    j: j as u32,
                };
                kept += 1;
            } else if live[le] != 0 {
                hist[le] = History::default();
                live[le] = 0;
            }
        }
        near_len[i - row0] = (kept - (e0 - base)) as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_near_skin_follows_the_speed_within_its_bounds() {
        let (skin, dt) = (1e-3, 1e-5);
        assert_eq!(near_skin(0.0, dt, skin), MIN_FRACTION * skin);
        assert_eq!(near_skin(f64::NAN, dt, skin), 0.5 * skin);
        assert_eq!(near_skin(f64::INFINITY, dt, skin), 0.5 * skin);
        assert_eq!(near_skin(10.0, dt, skin), 0.5 * skin);
        let speed = 0.5; // a near skin of 8e-5 m, inside the bounds
        assert!((near_skin(speed, dt, skin) - TARGET_STEPS * speed * dt).abs() < 1e-18);
    }

    #[test]
    fn keeps_the_close_entries_in_order_and_clears_a_separated_history() {
        // Particle 0 with partners 1 (touching), 2 (a gap of 0.5 mm, outside a 0.2 mm near
        // skin, with a stale history) and 3 (a gap of 0.1 mm).
        let x = vec![
            [0.0, 0.0, 0.0],
            [0.0019, 0.0, 0.0],
            [0.0, 0.0025, 0.0],
            [0.0, 0.0, 0.0021],
        ];
        // Radius 1 mm plus a near skin of 0.1 mm each.
        let reach = vec![1.1e-3; 4];
        let start = vec![0u32, 3, 3, 3, 3];
        let nb = vec![1u32, 2, 3];
        let stale = History {
            shear: [1e-6, 0.0, 0.0],
            rolling: [0.0; 3],
        };
        let mut hist = vec![History::default(), stale, History::default()];
        let mut live = vec![0u8, 1, 0];
        // Radii a power of two, so that the effective radius is exactly half.
        let r = vec![1.0 / 1024.0; 4];
        let m = vec![1.0, 2.0, 3.0, 4.0];
        let mut near = vec![Entry::default(); 3];
        let mut near_len = vec![0u32; 4];
        let rows = || Rows {
            start: &start,
            nb: &nb,
            base: 0,
            row0: 0,
        };
        let mut run = |all: bool, hist: &mut Vec<History>, live: &mut Vec<u8>| {
            build::<false>(
                0..4,
                rows(),
                (&x, &r, &m),
                &reach,
                &PeriodicBox::NONE,
                all,
                Out {
                    near: &mut near,
                    near_len: &mut near_len,
                },
                hist,
                live,
            );
            (near.clone(), near_len.clone())
        };
        let (near, near_len) = run(false, &mut hist, &mut live);
        assert_eq!(near_len, [2, 0, 0, 0]);
        let kept: Vec<_> = near[..2].iter().map(|n| (n.e, n.j)).collect();
        assert_eq!(kept, [(0, 1), (2, 3)], "entries and partners");
        // Equal radii (a power of two) halve exactly; masses 1 and 2 give 2/3, 1 and 4 give 4/5.
        let r = 1.0 / 1024.0;
        let pairs: Vec<_> = near[..2].iter().map(|n| [n.rj, n.r_eff, n.m_eff]).collect();
        assert_eq!(pairs, [[r, r / 2.0, 2.0 / 3.0], [r, r / 2.0, 0.8]]);
        assert!(
            hist[1].is_zero() && live[1] == 0,
            "the separated pair's history is cleared"
        );
        // `all` keeps everything.
        let (near, near_len) = run(true, &mut hist, &mut live);
        assert_eq!(near_len[0], 3);
        let kept: Vec<_> = near.iter().map(|n| (n.e, n.j)).collect();
        assert_eq!(kept, [(0, 1), (1, 2), (2, 3)]);
    }
}
