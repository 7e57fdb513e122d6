//! Random sequential insertion: spheres placed one by one at uniformly random positions in a box
//! region ([`random_pack`]) or a vertical cylinder ([`random_pack_cylinder`]), a position taken only if the sphere overlaps no sphere placed before and stays inside
//! the region. This is what LIGGGHTS' `fix insert/pack ... overlapcheck yes` does, and it stands
//! for material poured into a container: a random, dilute, isotropic cloud with no layering.

use super::vec3::V3;
use crate::error::{Error, Result};
use rand::{Rng, RngExt};

/// Attempts per sphere before the region is declared too full. Random sequential addition of
/// equal spheres jams near a solid fraction of 0.38; well below it a free spot is found within a
/// few dozen attempts, so hitting this limit means the region is too small, not bad luck.
const MAX_ATTEMPTS: usize = 20_000;

/// Centres for spheres of `diameters` (returned in that order) inside the box `lo`..`hi`, no two
/// overlapping. The largest spheres are placed first, as LIGGGHTS' particle distributions do:
/// placed last, they would find no gap left between the small ones of a wide distribution.
/// The region should offer at least four times the spheres' volume.
pub fn random_pack<R: Rng>(diameters: &[f64], lo: V3, hi: V3, rng: &mut R) -> Result<Vec<V3>> {
    let volume = (0..3).map(|k| hi[k] - lo[k]).product();
    pack(diameters, lo, hi, volume, |_, _| true, rng)
}

/// As [`random_pack`], in the vertical cylinder of `radius` about the z axis from `z_lo` to
/// `z_hi`: a position is drawn in the enclosing box and taken only if the sphere lies inside
/// the cylinder as well (a hopper's or a silo's fill).
pub fn random_pack_cylinder<R: Rng>(
    diameters: &[f64],
    radius: f64,
    z_lo: f64,
    z_hi: f64,
    rng: &mut R,
) -> Result<Vec<V3>> {
    pack(
        diameters,
        [-radius, -radius, z_lo],
        [radius, radius, z_hi],
        std::f64::consts::PI * radius * radius * (z_hi - z_lo),
        |c: V3, r: f64| (c[0] * c[0] + c[1] * c[1]).sqrt() + r <= radius,
        rng,
    )
}

/// Random sequential insertion in the box `lo`..`hi`, a position taken only where `inside`
/// (centre, radius) holds as well; `volume` is the region's, for the fraction an error reports.
fn pack<R: Rng>(
    diameters: &[f64],
    lo: V3,
    hi: V3,
    volume: f64,
    inside: impl Fn(V3, f64) -> bool,
    rng: &mut R,
) -> Result<Vec<V3>> {
    let d_max = diameters.iter().copied().fold(0.0, f64::max);
    if diameters.is_empty() {
        return Ok(Vec::new());
    }
    for k in 0..3 {
        if (hi[k] - lo[k]).partial_cmp(&d_max) != Some(std::cmp::Ordering::Greater) {
            return Err(Error::invalid(format!(
                "random insertion: the region ({:?} to {:?}) is narrower than the largest \
                 sphere ({d_max} m)",
                lo, hi
            )));
        }
    }
    // Grid of cells at least d_max wide: a sphere can only touch spheres in its own and the 26
    // neighbouring cells.
    let dims: [usize; 3] = std::array::from_fn(|k| (((hi[k] - lo[k]) / d_max) as usize).max(1));
    let size: [f64; 3] = std::array::from_fn(|k| (hi[k] - lo[k]) / dims[k] as f64);
    let cell_of = |x: V3| -> [usize; 3] {
        std::array::from_fn(|k| (((x[k] - lo[k]) / size[k]) as usize).min(dims[k] - 1))
    };
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
    let mut order: Vec<usize> = (0..diameters.len()).collect();
    order.sort_by(|&a, &b| diameters[b].total_cmp(&diameters[a]));
    let mut x: Vec<V3> = vec![[f64::NAN; 3]; diameters.len()];
    for (placed_before, &i) in order.iter().enumerate() {
        let d = diameters[i];
        let r = 0.5 * d;
        let mut placed = false;
        for _ in 0..MAX_ATTEMPTS {
            let c: V3 = std::array::from_fn(|k| rng.random_range(lo[k] + r..hi[k] - r));
            if !inside(c, r) {
                continue;
            }
            let [cx, cy, cz] = cell_of(c);
            let mut free = true;
            'search: for iz in cz.saturating_sub(1)..=(cz + 1).min(dims[2] - 1) {
                for iy in cy.saturating_sub(1)..=(cy + 1).min(dims[1] - 1) {
                    for ix in cx.saturating_sub(1)..=(cx + 1).min(dims[0] - 1) {
                        for &j in &cells[(iz * dims[1] + iy) * dims[0] + ix] {
                            let j = j as usize;
                            let reach = r + 0.5 * diameters[j];
                            let d2 = (0..3).map(|k| (c[k] - x[j][k]).powi(2)).sum::<f64>();
                            if d2 < reach * reach {
                                free = false;
                                break 'search;
                            }
                        }
                    }
                }
            }
            if free {
                let [cx, cy, cz] = cell_of(c);
                cells[(cz * dims[1] + cy) * dims[0] + cx].push(i as u32);
                x[i] = c;
                placed = true;
                break;
            }
        }
        if !placed {
            let v_placed: f64 = order[..placed_before]
                .iter()
                .map(|&j| std::f64::consts::PI / 6.0 * diameters[j].powi(3))
                .sum();
            return Err(Error::invalid(format!(
                "random insertion: no free spot for sphere {} of {} after {MAX_ATTEMPTS} \
                 attempts (solid fraction placed {:.3}); expected a larger region",
                placed_before + 1,
                diameters.len(),
                v_placed / volume
            )));
        }
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn places_every_sphere_inside_and_apart() {
        let mut rng = crate::test_rng(7);
        let d: Vec<f64> = (0..2000)
            .map(|i| 0.8 + 0.4 * ((i % 7) as f64 / 6.0))
            .collect();
        // 0.25 solid fraction of a 10 x 10 x h column.
        let v: f64 = d
            .iter()
            .map(|d| std::f64::consts::PI / 6.0 * d.powi(3))
            .sum();
        let h = v / (0.25 * 100.0);
        let x = random_pack(&d, [0.0; 3], [10.0, 10.0, h], &mut rng).unwrap();
        assert_eq!(x.len(), d.len());
        for i in 0..x.len() {
            for k in 0..3 {
                let hi = [10.0, 10.0, h][k];
                assert!(x[i][k] >= 0.5 * d[i] && x[i][k] <= hi - 0.5 * d[i]);
            }
            for j in 0..i {
                let d2: f64 = (0..3).map(|k| (x[i][k] - x[j][k]).powi(2)).sum();
                assert!(
                    d2.sqrt() >= 0.5 * (d[i] + d[j]) - 1e-12,
                    "{i} and {j} overlap"
                );
            }
        }
        // Random, not layered: the centres' heights spread evenly over the column.
        let lower = x.iter().filter(|c| c[2] < 0.5 * h).count() as f64 / x.len() as f64;
        assert!((lower - 0.5).abs() < 0.05, "{lower}");
        // Same seed, same cloud.
        let again = random_pack(&d, [0.0; 3], [10.0, 10.0, h], &mut crate::test_rng(7)).unwrap();
        assert_eq!(x, again);
    }

    #[test]
    fn a_cylinder_holds_every_sphere_inside_its_wall() {
        let d: Vec<f64> = (0..1500)
            .map(|i| 0.55 + 1.3 * ((i % 11) as f64 / 10.0))
            .collect();
        let (radius, h) = (6.0, 60.0);
        let x = random_pack_cylinder(&d, radius, 0.0, h, &mut crate::test_rng(3)).unwrap();
        for (i, c) in x.iter().enumerate() {
            let r = 0.5 * d[i];
            assert!(
                (c[0] * c[0] + c[1] * c[1]).sqrt() + r <= radius,
                "sphere {i} crosses the wall"
            );
            assert!(c[2] >= r && c[2] <= h - r, "sphere {i} leaves the column");
            for j in 0..i {
                let d2: f64 = (0..3).map(|k| (c[k] - x[j][k]).powi(2)).sum();
                assert!(
                    d2.sqrt() >= 0.5 * (d[i] + d[j]) - 1e-12,
                    "{i} and {j} overlap"
                );
            }
        }
        // The whole cross-section is used, not only a square inside it.
        let outer = x
            .iter()
            .filter(|c| (c[0] * c[0] + c[1] * c[1]).sqrt() > 0.8 * radius)
            .count();
        assert!(outer > 0, "no sphere near the wall");
    }

    #[test]
    fn a_region_too_small_is_refused_with_the_fraction_reached() {
        let d = vec![1.0; 400];
        let e = random_pack(&d, [0.0; 3], [4.0, 4.0, 4.0], &mut crate::test_rng(1))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no free spot") && e.contains("larger region"),
            "{e}"
        );
    }
}
