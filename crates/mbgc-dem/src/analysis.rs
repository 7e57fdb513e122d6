//! Code-independent measures of a packed bed of spheres, applied identically to the settled state
//! of every DEM code that mbgc compares (its own engine, LIGGGHTS): solid fraction in a measuring
//! box, coordination number, and the free-surface height used to place that box.
//!
//! Each measure has a `_periodic` twin for a domain periodic along some axes ([`PeriodicBox`]):
//! spheres count with their images across the box and pairs touch through their nearest images.
//! The plain forms are the twins with [`PeriodicBox::NONE`].
//!
//! The `f64` measures return NaN when they are undefined (no particles, `positions` and `radii` of
//! different lengths, an empty measuring box), so a misuse shows up in the numbers instead of as a
//! panic.

use std::collections::HashMap;
use std::f64::consts::PI;

use crate::periodic::PeriodicBox;
use crate::{Error, Result};

/// Solid volume fraction inside the axis-aligned measuring box `[lo, hi]`.
///
/// Spheres cut by the box faces count with the part of their volume inside the box
/// ([`sphere_box_volume`]), so the result does not jump when a sphere crosses a face. Overlaps
/// between particles are counted twice, as every DEM post-processor does; with the overlaps of a
/// settled bed (1e-6..1e-4 of a diameter) this is far below the noise of the measure.
pub fn packing_fraction(positions: &[[f64; 3]], radii: &[f64], lo: [f64; 3], hi: [f64; 3]) -> f64 {
    packing_fraction_periodic(positions, radii, lo, hi, &PeriodicBox::NONE)
}

/// [`packing_fraction`] in a periodic domain: a sphere counts with the parts of its images
/// ([`sphere_box_volume_periodic`]) inside the box, so a measuring box spanning a whole period
/// holds every sphere's whole volume.
pub fn packing_fraction_periodic(
    positions: &[[f64; 3]],
    radii: &[f64],
    lo: [f64; 3],
    hi: [f64; 3],
    pbox: &PeriodicBox,
) -> f64 {
    let box_volume = (0..3).map(|k| hi[k] - lo[k]).product::<f64>();
    if positions.len() != radii.len() || !(0..3).all(|k| hi[k] > lo[k]) {
        return f64::NAN;
    }
    let solid: f64 = positions
        .iter()
        .zip(radii)
        .map(|(c, &r)| sphere_box_volume_periodic(*c, r, lo, hi, pbox))
        .sum();
    solid / box_volume
}

/// [`sphere_box_volume`] summed over the sphere's images in a periodic domain: the sphere
/// wrapped into the period box, shifted by -1, 0 and +1 periods along every periodic axis. For a
/// measuring box no wider than a period, this is the sphere's volume inside the box however the
/// box and the sphere sit across the period box's faces.
pub fn sphere_box_volume_periodic(
    c: [f64; 3],
    r: f64,
    lo: [f64; 3],
    hi: [f64; 3],
    pbox: &PeriodicBox,
) -> f64 {
    if !pbox.any() {
        return sphere_box_volume(c, r, lo, hi);
    }
    if !c.iter().all(|v| v.is_finite()) {
        return 0.0;
    }
    let c = pbox.wrap(c);
    let shifts = |k: usize| -> &'static [f64] {
        if pbox.is_periodic(k) {
            &[-1.0, 0.0, 1.0]
        } else {
            &[0.0]
        }
    };
    let l = pbox.period();
    let mut total = 0.0;
    for &sz in shifts(2) {
        for &sy in shifts(1) {
            for &sx in shifts(0) {
                // 0 * inf along a non-periodic axis would be NaN: its shift is never applied.
                let image: [f64; 3] = std::array::from_fn(|k| {
                    let s = [sx, sy, sz][k];
                    if s == 0.0 {
                        c[k]
                    } else {
                        c[k] + s * l[k]
                    }
                });
                total += sphere_box_volume(image, r, lo, hi);
            }
        }
    }
    total
}

/// Volume of the part of the sphere (centre `c`, radius `r`) inside the box `[lo, hi]`.
///
/// Spheres inside the box, or cut only by the two faces normal to z, use the closed spherical-cap
/// form. Otherwise the volume is the integral over z of the exact area of the disk-rectangle
/// intersection; the integral is split where that area's form changes (a slice circle reaching a
/// face or a box edge) and each piece is done by 8-point Gauss-Legendre after a smoothstep change
/// of variable that tames the (t - t*)^(3/2) behaviour at the split points. The relative error is
/// below 1e-7 of the sphere volume (see the tests), far below the measure's statistical noise.
pub fn sphere_box_volume(c: [f64; 3], r: f64, lo: [f64; 3], hi: [f64; 3]) -> f64 {
    if r.is_nan() || r <= 0.0 || !c.iter().all(|v| v.is_finite()) {
        return 0.0;
    }
    // Disjoint or fully inside: no integration needed.
    if (0..3).any(|k| c[k] + r <= lo[k] || c[k] - r >= hi[k]) {
        return 0.0;
    }
    let ta = (lo[2] - c[2]).max(-r);
    let tb = (hi[2] - c[2]).min(r);
    let inside_xy = (0..2).all(|k| c[k] - r >= lo[k] && c[k] + r <= hi[k]);
    if inside_xy {
        // Integral of pi (r^2 - t^2) dt: whole sphere, cap or slab, exactly.
        let prim = |t: f64| PI * (r * r * t - t * t * t / 3.0);
        return prim(tb) - prim(ta);
    }

    // Rectangle relative to the centre; the slice circle at height t has radius sqrt(r^2 - t^2).
    let (x0, x1, y0, y1) = (lo[0] - c[0], hi[0] - c[0], lo[1] - c[1], hi[1] - c[1]);
    let area = |t: f64| {
        let rho = (r * r - t * t).max(0.0).sqrt();
        disk_rect_area(rho, x0, x1, y0, y1)
    };

    // Split points: heights where the slice circle touches a face line or a rectangle corner.
    let mut cuts = vec![ta, tb, 0.0];
    let (dx, dy) = ([x0.abs(), x1.abs()], [y0.abs(), y1.abs()]);
    let mut dists: Vec<f64> = dx.iter().chain(dy.iter()).copied().collect();
    for a in dx {
        for b in dy {
            dists.push(a.hypot(b));
        }
    }
    for d in dists {
        if d < r {
            let t = (r * r - d * d).sqrt();
            cuts.push(t);
            cuts.push(-t);
        }
    }
    cuts.retain(|&t| t >= ta && t <= tb);
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();

    cuts.windows(2)
        .map(|w| smooth_gauss(&area, w[0], w[1]))
        .sum()
}

/// 8-point Gauss-Legendre abscissae and weights on [-1, 1] (positive half; symmetric).
const GL8: [(f64, f64); 4] = [
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// Integral of `f` over [a, b] with t = a + (b - a)(3u^2 - 2u^3): the map's zero slope at both
/// ends makes the endpoint kinks of a piecewise-smooth area smooth in u, where Gauss-Legendre
/// converges fast. Two 8-point panels in u.
fn smooth_gauss(f: &impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let h = b - a;
    if h.is_nan() || h <= 0.0 {
        return 0.0;
    }
    let mut sum = 0.0;
    for (u_lo, u_hi) in [(0.0, 0.5), (0.5, 1.0)] {
        let (mid, half) = (0.5 * (u_lo + u_hi), 0.5 * (u_hi - u_lo));
        for (x, w) in GL8 {
            for u in [mid - half * x, mid + half * x] {
                let t = a + h * u * u * (3.0 - 2.0 * u);
                let dt = h * 6.0 * u * (1.0 - u);
                sum += w * half * f(t) * dt;
            }
        }
    }
    sum
}

/// Exact area of the disk of radius `rho` centred at the origin inside `[x0, x1] x [y0, y1]`,
/// by inclusion-exclusion over lower-left quadrant areas.
fn disk_rect_area(rho: f64, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    if rho.is_nan() || rho <= 0.0 || x1 <= x0 || y1 <= y0 {
        return 0.0;
    }
    let q = |a, b| disk_quadrant_area(rho, a, b);
    (q(x1, y1) - q(x0, y1) - q(x1, y0) + q(x0, y0)).max(0.0)
}

/// Area of {x <= a, y <= b, x^2 + y^2 <= rho^2}, integrating the chord length over x in closed
/// form: for |x| <= w = sqrt(rho^2 - b^2) the chord is cut by y = b, outside it is whole (b >= 0)
/// or empty (b < 0).
fn disk_quadrant_area(rho: f64, a: f64, b: f64) -> f64 {
    let a = a.clamp(-rho, rho);
    // Integral of sqrt(rho^2 - x^2) from 0 to x.
    let s = |x: f64| {
        let x = x.clamp(-rho, rho);
        0.5 * (x * (rho * rho - x * x).max(0.0).sqrt() + rho * rho * (x / rho).asin())
    };
    let int = |p: f64, q: f64| if q > p { s(q) - s(p) } else { 0.0 };
    if b >= rho {
        2.0 * int(-rho, a)
    } else if b <= -rho {
        0.0
    } else {
        let w = (rho * rho - b * b).sqrt();
        let len = (a.min(w) + w).max(0.0);
        if b >= 0.0 {
            int(-rho, a) + b * len + int(-rho, a.min(-w)) + int(w, a)
        } else {
            b * len + int(-w, a.min(w))
        }
    }
}

/// Number of particle-particle contacts (centre distance < r_i + r_j, i.e. overlap > 0) of each
/// particle, found with a cell list of side 2 r_max so the cost is O(N).
pub fn contact_counts(positions: &[[f64; 3]], radii: &[f64]) -> Result<Vec<usize>> {
    contact_counts_periodic(positions, radii, &PeriodicBox::NONE)
}

/// [`contact_counts`] in a periodic domain: pairs touch through their nearest images. Refuses a
/// period not longer than two largest diameters (4 r_max), where a pair could touch through
/// two images at once.
pub fn contact_counts_periodic(
    positions: &[[f64; 3]],
    radii: &[f64],
    pbox: &PeriodicBox,
) -> Result<Vec<usize>> {
    if positions.len() != radii.len() {
        return Err(Error::invalid(format!(
            "contact_counts: {} positions but {} radii",
            positions.len(),
            radii.len()
        )));
    }
    if let Some(i) = (0..positions.len()).find(|&i| {
        !(radii[i] > 0.0 && radii[i].is_finite() && positions[i].iter().all(|v| v.is_finite()))
    }) {
        return Err(Error::invalid(format!(
            "contact_counts: particle {i} has a non-finite position or a radius that is not positive"
        )));
    }
    let n = positions.len();
    let mut counts = vec![0usize; n];
    if n == 0 {
        return Ok(counts);
    }
    let r_max = radii.iter().copied().fold(0.0, f64::max);
    let cell = 2.0 * r_max;
    let (lo, period) = (pbox.lo(), pbox.period());
    if let Some(k) = (0..3).find(|&k| pbox.is_periodic(k) && period[k] <= 2.0 * cell) {
        return Err(Error::invalid(format!(
            "contact_counts: the period {:.4e} m along axis {k} must exceed two largest \
             diameters ({:.4e} m)",
            period[k],
            2.0 * cell
        )));
    }
    // Along a periodic axis, a whole number of cells of at least 2 r_max spans the period, and
    // cell keys wrap around it.
    let dims: [i64; 3] = std::array::from_fn(|k| {
        if pbox.is_periodic(k) {
            ((period[k] / cell).floor() as i64).max(1)
        } else {
            0
        }
    });
    let wrapped: Vec<[f64; 3]> = positions.iter().map(|p| pbox.wrap(*p)).collect();
    let key = |p: &[f64; 3]| -> [i64; 3] {
        std::array::from_fn(|k| {
            if dims[k] > 0 {
                (((p[k] - lo[k]) / (period[k] / dims[k] as f64)).floor() as i64).min(dims[k] - 1)
            } else {
                (p[k] / cell).floor() as i64
            }
        })
    };
    let mut cells: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in wrapped.iter().enumerate() {
        cells.entry(key(p)).or_default().push(i);
    }
    let mut around: Vec<[i64; 3]> = Vec::with_capacity(27);
    for (i, p) in wrapped.iter().enumerate() {
        let k = key(p);
        around.clear();
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let d = [dx, dy, dz];
                    around.push(std::array::from_fn(|m| {
                        let c = k[m] + d[m];
                        if dims[m] > 0 {
                            c.rem_euclid(dims[m])
                        } else {
                            c
                        }
                    }));
                }
            }
        }
        // With fewer than three cells along an axis, two offsets wrap to the same cell.
        around.sort_unstable();
        around.dedup();
        for c in &around {
            let Some(members) = cells.get(c) else {
                continue;
            };
            // Each pair once (j > i), credited to both.
            for &j in members.iter().filter(|&&j| j > i) {
                let q = wrapped[j];
                let d = pbox.min_image(std::array::from_fn(|m| p[m] - q[m]));
                let d2 = (0..3).map(|m| d[m] * d[m]).sum::<f64>();
                let reach = radii[i] + radii[j];
                if d2 < reach * reach {
                    counts[i] += 1;
                    counts[j] += 1;
                }
            }
        }
    }
    Ok(counts)
}

/// Mean number of particle-particle contacts (overlap > 0) per particle, over all particles.
/// Wall contacts are not counted. NaN if undefined (see the module docs).
pub fn coordination_number(positions: &[[f64; 3]], radii: &[f64]) -> f64 {
    coordination_number_periodic(positions, radii, &PeriodicBox::NONE)
}

/// [`coordination_number`] in a periodic domain ([`contact_counts_periodic`]).
pub fn coordination_number_periodic(
    positions: &[[f64; 3]],
    radii: &[f64],
    pbox: &PeriodicBox,
) -> f64 {
    match contact_counts_periodic(positions, radii, pbox) {
        Ok(c) if !c.is_empty() => c.iter().sum::<usize>() as f64 / c.len() as f64,
        _ => f64::NAN,
    }
}

/// Mean contact count of the particles whose centres lie in `[lo, hi]` (their contacts with
/// particles outside the box count too): the coordination number of the bulk, free of the
/// deficit of particles at walls and at the free surface. NaN if no centre is in the box.
pub fn coordination_number_in(
    positions: &[[f64; 3]],
    radii: &[f64],
    lo: [f64; 3],
    hi: [f64; 3],
) -> f64 {
    coordination_number_in_periodic(positions, radii, lo, hi, &PeriodicBox::NONE)
}

/// [`coordination_number_in`] in a periodic domain: contacts through nearest images
/// ([`contact_counts_periodic`]), centres taken wrapped into the period box.
pub fn coordination_number_in_periodic(
    positions: &[[f64; 3]],
    radii: &[f64],
    lo: [f64; 3],
    hi: [f64; 3],
    pbox: &PeriodicBox,
) -> f64 {
    let Ok(counts) = contact_counts_periodic(positions, radii, pbox) else {
        return f64::NAN;
    };
    let (sum, n) = positions
        .iter()
        .map(|p| pbox.wrap(*p))
        .zip(&counts)
        .filter(|(p, _)| (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k]))
        .fold((0usize, 0usize), |(s, n), (_, &c)| (s + c, n + 1));
    if n == 0 {
        f64::NAN
    } else {
        sum as f64 / n as f64
    }
}

/// Height of the free surface of a bed settled under gravity in -z: the xy extent of the
/// particles is divided into square columns of side 2 d_max (= 4 r_max), and the result is the
/// mean over non-empty columns of the highest particle top (z + r) in the column. Averaging
/// columns keeps a single particle perched on top from moving the surface. NaN if undefined.
pub fn free_surface_height(positions: &[[f64; 3]], radii: &[f64]) -> f64 {
    if positions.is_empty()
        || positions.len() != radii.len()
        || !positions.iter().flatten().all(|v| v.is_finite())
        || !radii.iter().all(|r| r.is_finite() && *r > 0.0)
    {
        return f64::NAN;
    }
    let r_max = radii.iter().copied().fold(0.0, f64::max);
    let side = 4.0 * r_max;
    let x_min = positions.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
    let y_min = positions.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    // Ordered, so the sum (and the result) is the same bit for bit on every run.
    let mut tops: std::collections::BTreeMap<(i64, i64), f64> = std::collections::BTreeMap::new();
    for (p, r) in positions.iter().zip(radii) {
        let col = (
            ((p[0] - x_min) / side).floor() as i64,
            ((p[1] - y_min) / side).floor() as i64,
        );
        let top = tops.entry(col).or_insert(f64::NEG_INFINITY);
        *top = top.max(p[2] + r);
    }
    tops.values().sum::<f64>() / tops.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// n^3 simple cubic lattice, spacing a, first centre at a/2 so the cells tile [0, n a]^3.
    fn cubic(n: usize, a: f64, r: f64) -> (Vec<[f64; 3]>, Vec<f64>) {
        let mut pos = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    pos.push([
                        (i as f64 + 0.5) * a,
                        (j as f64 + 0.5) * a,
                        (k as f64 + 0.5) * a,
                    ]);
                }
            }
        }
        let radii = vec![r; pos.len()];
        (pos, radii)
    }

    fn sphere_volume(r: f64) -> f64 {
        4.0 / 3.0 * PI * r.powi(3)
    }

    #[test]
    fn simple_cubic_packing_fraction_is_pi_over_six() {
        let r = 0.005;
        let a = 2.0 * r * (1.0 - 1e-6); // touching with a tiny overlap
        let (pos, radii) = cubic(8, a, r);
        // Faces between lattice planes: whole spheres only.
        let phi = packing_fraction(&pos, &radii, [a; 3], [7.0 * a; 3]);
        assert!((phi - PI / 6.0).abs() < 1e-3, "{phi}");
        // Faces through sphere centres: halves, quarters at edges and eighths at corners.
        let phi = packing_fraction(&pos, &radii, [1.5 * a; 3], [6.5 * a; 3]);
        assert!((phi - PI / 6.0).abs() < 1e-3, "{phi}");
        // Faces at an arbitrary offset: still pi/6 for a whole number of cells.
        let phi = packing_fraction(&pos, &radii, [1.3 * a; 3], [6.3 * a; 3]);
        assert!((phi - PI / 6.0).abs() < 1e-3, "{phi}");
    }

    #[test]
    fn simple_cubic_coordination() {
        let r = 0.005;
        let a = 2.0 * r * (1.0 - 1e-6);
        let n = 6;
        let (pos, radii) = cubic(n, a, r);
        let counts = contact_counts(&pos, &radii).unwrap();
        for (p, c) in pos.iter().zip(&counts) {
            let interior = p.iter().all(|&x| x > a && x < (n as f64 - 1.0) * a);
            if interior {
                assert_eq!(*c, 6, "interior particle at {p:?}");
            }
        }
        // 3 n^2 (n - 1) bonds, each shared by two particles.
        let expected = 6.0 * (n as f64 - 1.0) / n as f64;
        assert!((coordination_number(&pos, &radii) - expected).abs() < 1e-12);
        let z = coordination_number_in(&pos, &radii, [a; 3], [(n as f64 - 1.0) * a; 3]);
        assert_eq!(z, 6.0);
        // Exactly touching spheres (zero overlap) are not in contact.
        let (pos, radii) = cubic(3, 2.0 * r * (1.0 + 1e-9), r);
        assert_eq!(coordination_number(&pos, &radii), 0.0);
    }

    #[test]
    fn a_periodic_lattice_has_six_contacts_everywhere_and_counts_whole_spheres() {
        let r = 0.005;
        let a = 2.0 * r * (1.0 - 1e-6);
        for n in [5, 6] {
            // Centres at (i + 0.5) a, shifted so the lattice straddles the box faces.
            let (mut pos, radii) = cubic(n, a, r);
            for p in &mut pos {
                p[0] -= 0.5 * a;
                p[1] += 0.2 * a;
            }
            let l = n as f64 * a;
            let pbox = PeriodicBox::new(([0.0; 3], [l; 3]), [true; 3]).unwrap();
            let counts = contact_counts_periodic(&pos, &radii, &pbox).unwrap();
            assert!(counts.iter().all(|&c| c == 6), "n = {n}: {counts:?}");
            // Without periodicity the faces lose their bonds.
            let z = coordination_number(&pos, &radii);
            assert!((z - 6.0 * (n as f64 - 1.0) / n as f64).abs() < 1e-12, "{z}");
            assert_eq!(coordination_number_periodic(&pos, &radii, &pbox), 6.0);
            assert_eq!(
                coordination_number_in_periodic(&pos, &radii, [0.0; 3], [l; 3], &pbox),
                6.0
            );
            // The period box holds every sphere whole, the cut ones through their images.
            let phi = packing_fraction_periodic(&pos, &radii, [0.0; 3], [l; 3], &pbox);
            let expected = PI / 6.0 / (1.0 - 1e-6f64).powi(3);
            assert!((phi - expected).abs() < 1e-6, "{phi} vs {expected}");
            let plain = packing_fraction(&pos, &radii, [0.0; 3], [l; 3]);
            assert!(
                plain < 0.95 * expected,
                "without images, cut spheres are lost: {plain}"
            );
        }
        // Periodic along x only: the bonds across the y and z faces stay missing.
        let (pos, radii) = cubic(4, a, r);
        let l = 4.0 * a;
        let pbox = PeriodicBox::new(([0.0; 3], [l; 3]), [true, false, false]).unwrap();
        let total: usize = contact_counts_periodic(&pos, &radii, &pbox)
            .unwrap()
            .iter()
            .sum();
        assert_eq!(total, 2 * (16 * 4 + 2 * 16 * 3));
        // Too short a period for the nearest image to be unique.
        let pbox = PeriodicBox::new(([0.0; 3], [3.9 * r; 3]), [false, true, false]).unwrap();
        assert!(contact_counts_periodic(&pos, &radii, &pbox).is_err());
    }

    #[test]
    fn sphere_cut_by_the_box_gives_the_partial_volume() {
        let r = 0.004;
        let v = sphere_volume(r);
        let big = [1.0; 3];
        let close = |a: f64, b: f64| (a - b).abs() < 1e-7 * v;
        // Centre on one face, on an edge, on a corner.
        assert!(close(
            sphere_box_volume([0.0, 0.5, 0.5], r, [0.0; 3], big),
            v / 2.0
        ));
        assert!(close(
            sphere_box_volume([0.0, 0.0, 0.5], r, [0.0; 3], big),
            v / 4.0
        ));
        assert!(close(
            sphere_box_volume([0.0, 0.0, 0.0], r, [0.0; 3], big),
            v / 8.0
        ));
        // A cap of height h through an x face (numerical path) and a z face (closed form).
        let h = 0.3 * r;
        let cap = PI * h * h * (3.0 * r - h) / 3.0;
        let c = [r - h, 0.5, 0.5];
        assert!(close(sphere_box_volume(c, r, [0.0; 3], big), v - cap));
        let c = [0.5, 0.5, r - h];
        assert!(close(sphere_box_volume(c, r, [0.0; 3], big), v - cap));
        // A slab through the middle, thickness 2s: pi (2 s r^2 - 2 s^3 / 3), cut by x faces.
        let s = 0.5 * r;
        let slab = PI * (2.0 * s * r * r - 2.0 * s.powi(3) / 3.0);
        let got = sphere_box_volume([0.5, 0.5, 0.5], r, [0.5 - s, 0.0, 0.0], [0.5 + s, 1.0, 1.0]);
        assert!(close(got, slab), "{got} vs {slab}");
        // Off-centre edge cut: x >= a and y >= b with a, b > 0; compare with a fine Riemann sum.
        let (a, b) = (0.2 * r, 0.45 * r);
        let got = sphere_box_volume([-a, -b, 0.5], r, [0.0; 3], big);
        let m = 400;
        let step = 2.0 * r / m as f64;
        let mut reference = 0.0;
        for i in 0..m {
            let z = -r + (i as f64 + 0.5) * step;
            let rho = (r * r - z * z).sqrt();
            for j in 0..m {
                let x = a + (j as f64 + 0.5) * step;
                let half = (rho * rho - x * x).max(0.0).sqrt();
                reference += (half - b).max(0.0) * step * step;
            }
        }
        assert!((got - reference).abs() < 1e-3 * v, "{got} vs {reference}");
        // Outside, inside, degenerate.
        assert_eq!(sphere_box_volume([2.0, 0.5, 0.5], r, [0.0; 3], big), 0.0);
        assert!(close(sphere_box_volume([0.5; 3], r, [0.0; 3], big), v));
        assert_eq!(sphere_box_volume([0.5; 3], 0.0, [0.0; 3], big), 0.0);
    }

    #[test]
    fn free_surface_of_a_flat_bed() {
        let r = 0.005;
        let (pos, radii) = cubic(6, 2.0 * r, r);
        let h = free_surface_height(&pos, &radii);
        assert!((h - 12.0 * r).abs() < 1e-12, "{h}");
    }

    #[test]
    fn undefined_inputs_give_nan_or_errors_not_panics() {
        let pos = [[0.0; 3]; 2];
        assert!(packing_fraction(&pos, &[1.0], [0.0; 3], [1.0; 3]).is_nan());
        assert!(packing_fraction(&pos, &[1.0, 1.0], [0.0; 3], [0.0, 1.0, 1.0]).is_nan());
        assert!(coordination_number(&[], &[]).is_nan());
        assert!(coordination_number(&pos, &[1.0]).is_nan());
        assert!(contact_counts(&pos, &[1.0, f64::NAN]).is_err());
        assert!(free_surface_height(&[], &[]).is_nan());
        assert!(coordination_number_in(&pos, &[1.0, 1.0], [5.0; 3], [6.0; 3]).is_nan());
    }
}
