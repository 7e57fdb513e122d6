//! The fill of the hopper and the clogging silo: particles poured at random into a vertical
//! cylinder ([`random_fill`]), settled under gravity before the orifice opens ([`settle`]).

use std::f64::consts::PI;

use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};
use mbgc_dem::insertion::random_pack_cylinder;
use mbgc_dem::particles::Particles;
use mbgc_dem::sim::Simulation;

/// Solid fraction of the poured column: the shear box's (docs/shear_box.md), below random
/// sequential insertion's jamming (near 0.38 in the bulk, lower beside walls), so that a free
/// spot is quickly found.
const POUR_FRACTION: f64 = 0.2;

/// Particles of diameters `diam` (m) at random positions, none overlapping another or the wall,
/// in a cylinder of `radius` about the z axis from the bottom (z = 0) up to the height that
/// holds them at solid fraction [`POUR_FRACTION`] (random sequential insertion, as the shear
/// box pours: [`random_pack_cylinder`]). The column is then about three times as tall as the
/// settled fill whatever the size distribution. The lattice spaced for the largest particle
/// that this replaced held a wide distribution's small particles far apart: for the test's
/// diameters (0.55-1.85 d50) its column stood 3.9 times taller, 6.7 m for the gravel's 3000
/// grains in the silo. Refuses a cylinder too narrow for the largest particle, naming d50.
pub(crate) fn random_fill(
    diam: &[f64],
    radius: f64,
    d_max: f64,
    rho: f64,
    material: u16,
    rng: &mut ChaCha8Rng,
) -> Result<Particles> {
    if radius <= 0.5 * d_max {
        return Err(Error::invalid(format!(
            "parameter d50: particles up to {:.3} mm do not fit in the container",
            d_max * 1e3
        )));
    }
    let solid: f64 = diam.iter().map(|d| PI / 6.0 * d.powi(3)).sum();
    let height = (solid / (POUR_FRACTION * PI * radius * radius)).max(2.0 * d_max);
    let centres = random_pack_cylinder(diam, radius, 0.0, height, rng).map_err(|e| {
        Error::invalid(format!(
            "parameter d50: {} particles up to {:.3} mm could not be poured into the container \
             ({:.1} mm wide, a column {:.1} mm tall): {e}",
            diam.len(),
            d_max * 1e3,
            2e3 * radius,
            height * 1e3
        ))
    })?;
    let mut particles = Particles::new();
    for (&d, &x) in diam.iter().zip(&centres) {
        particles.add(x, 0.5 * d, rho, material)?;
    }
    Ok(particles)
}

/// Runs `sim` in chunks of `chunk` steps until it has fallen for at least `t_fall` and its
/// translational kinetic energy per particle is below `ke_rest` (EPSD2 has no rolling dashpot,
/// so rotation keeps the total energy high long after the packing is at rest), or until its
/// time passes `cap`: then the warning to report. A blow-up is an error naming `experiment`.
pub(crate) fn settle(
    sim: &mut Simulation,
    chunk: u64,
    t_fall: f64,
    cap: f64,
    ke_rest: f64,
    experiment: &str,
) -> Result<Option<String>> {
    let n = sim.particles.len().max(1) as f64;
    loop {
        sim.run(chunk)
            .map_err(|e| Error::invalid(format!("{experiment} run (settling) stopped: {e}")))?;
        let ke = sim.particles.translational_energy() / n;
        if sim.time >= t_fall && ke < ke_rest {
            return Ok(None);
        }
        if sim.time > cap {
            return Ok(Some(format!(
                "fill not at rest after {:.2} s (translational energy per particle {ke:.2e} J, \
                 rest below {ke_rest:.2e} J)",
                sim.time
            )));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// Diameters spread as a wide PSD's (0.55-1.85 d50), from a seeded draw.
    fn wide(n: usize, d50: f64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        (0..n)
            .map(|_| d50 * (0.55 + 1.3 * rng.random::<f64>()))
            .collect()
    }

    fn top(p: &Particles) -> f64 {
        p.x.iter().map(|x| x[2]).fold(0.0, f64::max)
    }

    #[test]
    fn random_fill_is_clear_inside_and_short_for_a_wide_psd() {
        let (d50, n) = (4e-3, 1500);
        let diam = wide(n, d50);
        let d_max = 1.85 * d50;
        let radius = 6.0 * d50;
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let p = random_fill(&diam, radius, d_max, 2500.0, 0, &mut rng).unwrap();
        assert_eq!(p.len(), n);
        for i in 0..n {
            let (x, r) = (p.x[i], p.r[i]);
            assert!(
                (x[0] * x[0] + x[1] * x[1]).sqrt() + r <= radius,
                "particle {i} crosses the wall"
            );
            assert!(x[2] - r >= 0.0, "particle {i} below the floor");
            for j in 0..i {
                let y = p.x[j];
                let dist =
                    ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt();
                assert!(dist >= r + p.r[j], "particles {j} and {i} overlap");
            }
        }
        // Solid fraction of the column: the pour's, whatever the spread of sizes.
        let solid: f64 =
            p.r.iter()
                .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3))
                .sum();
        let column = std::f64::consts::PI * radius * radius * top(&p);
        let fraction = solid / column;
        assert!(
            (0.17..0.23).contains(&fraction),
            "random fill's solid fraction {fraction:.3}"
        );
        // Same seed, same fill.
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let again = random_fill(&diam, radius, d_max, 2500.0, 0, &mut rng).unwrap();
        assert_eq!(again.x, p.x);
    }

    #[test]
    fn random_fill_refuses_a_container_narrower_than_the_largest_particle() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let e = random_fill(&[4e-3], 1.5e-3, 4e-3, 2500.0, 0, &mut rng).unwrap_err();
        assert!(e.to_string().contains("d50"), "{e}");
    }
}
