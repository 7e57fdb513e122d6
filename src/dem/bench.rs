//! The throughput benchmark scene (`reference/peer_throughput.md`): polydisperse spheres
//! (d = 7.5-10 mm) in a closed box 0.12 x 0.12 x 0.36 m, rho = 2600, E = 5e7 Pa, nu = 0.3,
//! e = 0.5, mu = 0.5, EPSD2 mu_r = 0.3, dt = 2e-5 s; settled, then timed.

use rand::RngExt;

use super::contact::ContactModel;
use super::material::{Interaction, Material, Materials};
use super::particles::Particles;
use super::sim::Scene;
use super::vec3::V3;
use super::walls::box_planes;
use crate::error::{Error, Result};

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
            box_hi: [0.12, 0.12, 0.36],
            d_min: 7.5e-3,
            d_max: 10e-3,
            density: 2600.0,
            youngs_modulus: 5e7,
            poisson: 0.3,
            restitution: 0.5,
            friction: 0.5,
            rolling_friction: 0.3,
            dt: 2e-5,
            skin: 1.5e-3,
            gravity: 9.81,
        }
    }
}

/// Initial positions and radii: a jittered lattice filling the box from the bottom, diameters
/// uniform in [d_min, d_max], no overlaps. Deterministic for the seed.
pub fn initial_packing(spec: &BenchSpec) -> Result<(Vec<V3>, Vec<f64>)> {
    let mut rng = crate::sampling::rng(spec.seed);
    let pitch = spec.d_max * 1.05;
    let per_axis = |len: f64| ((len - pitch) / pitch).floor() as usize + 1;
    let (nx, ny) = (per_axis(spec.box_hi[0]), per_axis(spec.box_hi[1]));
    let layers = spec.particles.div_ceil(nx * ny);
    if (layers as f64) * pitch > spec.box_hi[2] {
        return Err(Error::invalid(format!(
            "{} particles of {} mm do not fit the box",
            spec.particles,
            spec.d_max * 1e3
        )));
    }
    let slack = 0.5 * (pitch - spec.d_max);
    let mut x = Vec::with_capacity(spec.particles);
    let mut r = Vec::with_capacity(spec.particles);
    'fill: for k in 0..layers {
        for j in 0..ny {
            for i in 0..nx {
                if x.len() == spec.particles {
                    break 'fill;
                }
                let jitter =
                    |rng: &mut rand_chacha::ChaCha8Rng| slack * (2.0 * rng.random::<f64>() - 1.0);
                let p = [
                    0.5 * pitch + i as f64 * pitch + jitter(&mut rng),
                    0.5 * pitch + j as f64 * pitch + jitter(&mut rng),
                    0.5 * pitch + k as f64 * pitch + jitter(&mut rng),
                ];
                x.push(p);
                r.push(0.5 * (spec.d_min + (spec.d_max - spec.d_min) * rng.random::<f64>()));
            }
        }
    }
    Ok((x, r))
}

/// The mbgc scene for the spec, from given positions and radii.
pub fn scene(spec: &BenchSpec, x: &[V3], r: &[f64]) -> Result<Scene> {
    let mut materials = Materials::new();
    let m = materials.add(Material {
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
        model: ContactModel::default(),
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
    })
}
