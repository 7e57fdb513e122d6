//! The throughput benchmark scene (`reference/peer_throughput.md`): polydisperse spheres
//! (d = 7.5-10 mm) in a closed box 0.12 x 0.12 x 0.36 m, rho = 2600, E = 5e7 Pa, nu = 0.3,
//! e = 0.5, mu = 0.5, EPSD2 mu_r = 0.3, dt = 2e-5 s; settled, then timed.
//!
//! The scene is shared by the throughput study ([`super::dem_throughput`]), the DEM tests that
//! need a realistic packing, and the LIGGGHTS comparison ([`liggghts_case`]).

use rand::RngExt;

use mbgc::dem::contact::ModelClass;
use mbgc::dem::material::{Interaction, Materials, Solid};
use mbgc::dem::particles::Particles;
use mbgc::dem::sim::Scene;
use mbgc::dem::vec3::V3;
use mbgc::dem::walls::box_planes;
use mbgc::error::{Error, Result};
use mbgc::liggghts::LiggghtsCase;

/// The benchmark box, m (lower corner at the origin).
pub const BENCHMARK_BOX: [f64; 3] = [0.12, 0.12, 0.36];

#[derive(Debug, Clone)]
pub struct BenchSpec {
    pub particles: usize,
    pub seed: u64,
    pub box_hi: V3,
    pub d_min: f64,
    pub d_max: f64,
    pub density: f64,
    pub youngs_modulus: f64,
    pub poisson: f64,
    pub restitution: f64,
    pub friction: f64,
    pub rolling_friction: f64,
    pub dt: f64,
    pub skin: f64,
    pub gravity: f64,
}

impl Default for BenchSpec {
    fn default() -> Self {
        BenchSpec {
            particles: 3300,
            seed: 1,
            box_hi: BENCHMARK_BOX,
            d_min: 7.5e-3,
            d_max: 10e-3,
            density: 2600.0,
            youngs_modulus: 5e7,
            poisson: 0.3,
            restitution: 0.5,
            friction: 0.5,
            rolling_friction: 0.3,
            dt: 2e-5,
            skin: 2e-3,
            gravity: 9.81,
        }
    }
}

/// Initial positions and radii of the benchmark scene.
pub fn initial_packing(spec: &BenchSpec) -> Result<(Vec<V3>, Vec<f64>)> {
    jittered_lattice(
        spec.particles,
        [0.0; 3],
        spec.box_hi,
        spec.d_min,
        spec.d_max,
        spec.seed,
    )
}

/// A loose initial state, reproducible from `seed`: `n` spheres with diameters uniform in
/// `[d_min, d_max]` on a jittered lattice filling the box `[lo, hi]` from the bottom, with no
/// overlaps between particles or with the walls. The lattice spacing is the largest that holds
/// `n` sites (ties broken by fewest sites, so the box fills to the top: 10 x 10 x 33 for the
/// benchmark's 3300 particles), and each site moves by up to 45 % of the free gap per axis.
///
/// The RNG draws, per particle, the diameter then the x, y, z jitter, so another code can
/// rebuild the same state from the same seed.
pub fn jittered_lattice(
    n: usize,
    lo: [f64; 3],
    hi: [f64; 3],
    d_min: f64,
    d_max: f64,
    seed: u64,
) -> Result<(Vec<[f64; 3]>, Vec<f64>)> {
    if !(d_min > 0.0 && d_min <= d_max && d_max.is_finite()) {
        return Err(Error::invalid(format!(
            "jittered_lattice: diameters [{d_min}, {d_max}]: expected 0 < d_min <= d_max"
        )));
    }
    let len: [f64; 3] = std::array::from_fn(|k| hi[k] - lo[k]);
    if !len.iter().all(|l| *l > 0.0 && l.is_finite()) {
        return Err(Error::invalid(format!(
            "jittered_lattice: box {lo:?}..{hi:?}: expected finite bounds with lo < hi"
        )));
    }
    let max_count = |k: usize| (len[k] / d_max).floor().min(1e6) as usize;
    // (min spacing, sites, counts): largest min spacing, then fewest sites.
    let mut best: Option<(f64, usize, [usize; 3])> = None;
    for nx in 1..=max_count(0) {
        for ny in 1..=max_count(1) {
            let layer = nx * ny;
            let nz = n.div_ceil(layer).max(1);
            if nz > max_count(2) {
                continue;
            }
            let s = (len[0] / nx as f64)
                .min(len[1] / ny as f64)
                .min(len[2] / nz as f64);
            let sites = layer * nz;
            let better = match best {
                None => true,
                Some((bs, bsites, _)) => {
                    s > bs * (1.0 + 1e-12) || (s >= bs * (1.0 - 1e-12) && sites < bsites)
                }
            };
            if better {
                best = Some((s, sites, [nx, ny, nz]));
            }
        }
    }
    let Some((_, _, counts)) = best else {
        return Err(Error::invalid(format!(
            "jittered_lattice: {n} spheres of diameter up to {d_max} do not fit in the box \
             {lo:?}..{hi:?} on a lattice"
        )));
    };
    let spacing: [f64; 3] = std::array::from_fn(|k| len[k] / counts[k] as f64);
    let jitter: [f64; 3] = std::array::from_fn(|k| 0.45 * (spacing[k] - d_max).max(0.0));
    let mut rng = mbgc::sampling::rng(seed);
    let mut positions = Vec::with_capacity(n);
    let mut radii = Vec::with_capacity(n);
    for i in 0..n {
        let (ix, iy, iz) = (
            i % counts[0],
            (i / counts[0]) % counts[1],
            i / (counts[0] * counts[1]),
        );
        let d = if d_max > d_min {
            rng.random_range(d_min..=d_max)
        } else {
            d_min
        };
        let idx = [ix, iy, iz];
        let p: [f64; 3] = std::array::from_fn(|k| {
            let u: f64 = rng.random::<f64>() * 2.0 - 1.0;
            lo[k] + (idx[k] as f64 + 0.5) * spacing[k] + u * jitter[k]
        });
        positions.push(p);
        radii.push(0.5 * d);
    }
    Ok((positions, radii))
}

/// The mbgc scene for the spec, from given positions and radii.
pub fn scene(spec: &BenchSpec, x: &[V3], r: &[f64]) -> Result<Scene> {
    let mut materials = Materials::new();
    let m = materials.add(Solid {
        name: "grain".into(),
        youngs_modulus: spec.youngs_modulus,
        poisson: spec.poisson,
    })?;
    materials.set_interaction(
        m,
        m,
        Interaction {
            restitution: spec.restitution,
            friction: spec.friction,
            rolling_friction: spec.rolling_friction,
            ..Default::default()
        },
    )?;
    let mut particles = Particles::new();
    for (xi, ri) in x.iter().zip(r) {
        particles.add(*xi, *ri, spec.density, m)?;
    }
    let margin = 0.05;
    Ok(Scene {
        particles,
        walls: box_planes([0.0; 3], spec.box_hi, m),
        materials,
        class: ModelClass::default(),
        gravity: [0.0, 0.0, -spec.gravity],
        dt: spec.dt,
        skin: spec.skin,
        domain: (
            [-margin; 3],
            [
                spec.box_hi[0] + margin,
                spec.box_hi[1] + margin,
                spec.box_hi[2] + margin,
            ],
        ),
        max_dt_fraction: 0.3,
        periodic: [false; 3],
    })
}

/// The same scene as a LIGGGHTS case (particles and walls of one material).
pub fn liggghts_case(
    spec: &BenchSpec,
    positions: Vec<V3>,
    radii: Vec<f64>,
    settle_steps: u64,
    timed_steps: u64,
) -> LiggghtsCase {
    LiggghtsCase {
        positions,
        radii,
        density: spec.density,
        youngs_modulus: spec.youngs_modulus,
        poisson: spec.poisson,
        restitution: spec.restitution,
        friction: spec.friction,
        rolling_friction: spec.rolling_friction,
        wall_youngs_modulus: spec.youngs_modulus,
        wall_restitution: spec.restitution,
        wall_friction: spec.friction,
        wall_rolling_friction: spec.rolling_friction,
        cohesion_energy_density: 0.0,
        wall_cohesion_energy_density: 0.0,
        box_lo: [0.0; 3],
        box_hi: spec.box_hi,
        gravity: spec.gravity,
        dt: spec.dt,
        skin: spec.skin,
        settle_steps,
        timed_steps,
    }
}

/// Packing fraction and coordination number of a settled state, measured identically for every
/// code: in a box 2 d_max away from the side walls and the floor, up to 2 d_max below the free
/// surface (wall layers and the loose top are not bulk).
pub fn settled_measures(spec: &BenchSpec, x: &[V3], r: &[f64]) -> (f64, f64, [V3; 2]) {
    let m = 2.0 * spec.d_max;
    let top = mbgc::dem::analysis::free_surface_height(x, r) - m;
    let lo = [m, m, m];
    let hi = [spec.box_hi[0] - m, spec.box_hi[1] - m, top.max(m + 1e-3)];
    (
        mbgc::dem::analysis::packing_fraction(x, r, lo, hi),
        mbgc::dem::analysis::coordination_number_in(x, r, lo, hi),
        [lo, hi],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn benchmark_lattice_is_10_by_10_by_33_without_overlaps() {
        let (p, r) = jittered_lattice(3300, [0.0; 3], BENCHMARK_BOX, 0.0075, 0.01, 7).unwrap();
        assert_eq!(p.len(), 3300);
        assert!(r.iter().all(|&r| (0.00375..=0.005).contains(&r)));
        assert_eq!(mbgc::dem::analysis::coordination_number(&p, &r), 0.0);
        // Lattice rows of 10 in x (spacing 12 mm) and 100 per layer.
        assert!((p[1][0] - p[0][0] - 0.012).abs() < 0.002);
        assert!(p[100][2] > p[99][2]);
        let case = liggghts_case(&BenchSpec::default(), p.clone(), r.clone(), 40_000, 20_000);
        case.validate().unwrap();
        for (p, r) in p.iter().zip(&r) {
            for k in 0..3 {
                assert!(p[k] - r > 0.0 && p[k] + r < BENCHMARK_BOX[k], "{p:?} {r}");
            }
        }
        let again = jittered_lattice(3300, [0.0; 3], BENCHMARK_BOX, 0.0075, 0.01, 7).unwrap();
        assert_eq!(again, (p, r));
        assert!(jittered_lattice(4000, [0.0; 3], BENCHMARK_BOX, 0.0075, 0.011, 7).is_err());
    }
}
