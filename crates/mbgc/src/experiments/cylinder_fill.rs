//! The fill of the hopper and the clogging silo: a loose jittered lattice of particles in a
//! vertical cylinder ([`lattice_fill`]), settled under gravity before the orifice opens
//! ([`settle`]).

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};
use mbgc_dem::particles::Particles;
use mbgc_dem::sim::Simulation;

/// Particles of diameters `diam` (m) on a square lattice of spacing 1.3 `d_max`, layer after
/// layer from the bottom (z = 0) up, inside a cylinder of `radius` about the z axis; each site
/// jittered by up to 45 % of the gap (from `rng`), with room for the jitter inside the wall.
/// Refuses a cylinder too narrow for one site, naming d50 (the parameter that sets d_max).
pub(crate) fn lattice_fill(
    diam: &[f64],
    radius: f64,
    d_max: f64,
    rho: f64,
    material: u16,
    rng: &mut ChaCha8Rng,
) -> Result<Particles> {
    let spacing = 1.3 * d_max;
    let jitter = 0.45 * (spacing - d_max);
    let site_r = radius - 0.5 * d_max - jitter * 2f64.sqrt() - 1e-3 * d_max;
    let m_side = (2.0 * site_r / spacing).floor() as i64 + 1;
    let off = 0.5 * (m_side - 1) as f64 * spacing;
    let layer: Vec<(f64, f64)> = (0..m_side)
        .flat_map(|i| (0..m_side).map(move |j| (i, j)))
        .map(|(i, j)| (i as f64 * spacing - off, j as f64 * spacing - off))
        .filter(|(x, y)| (x * x + y * y).sqrt() <= site_r)
        .collect();
    if layer.is_empty() {
        return Err(Error::invalid(format!(
            "parameter d50: particles up to {:.3} mm do not fit in the container",
            d_max * 1e3
        )));
    }
    let mut particles = Particles::new();
    let z0 = 0.5 * spacing;
    for (i, &d) in diam.iter().enumerate() {
        let (x, y) = layer[i % layer.len()];
        let z = z0 + (i / layer.len()) as f64 * spacing;
        let mut j = || (rng.random::<f64>() * 2.0 - 1.0) * jitter;
        let pos = [x + j(), y + j(), z + j()];
        particles.add(pos, 0.5 * d, rho, material)?;
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
