//! Quick throughput probe of the benchmark scene (no LIGGGHTS): settle, then time.
//! cargo run --release --example dem_speed -- [particles] [settle] [timed] [threads]
use std::time::Instant;

fn main() {
    let a: Vec<usize> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("integer arguments"))
        .collect();
    let spec = mbgc_studies::dem_scene::BenchSpec {
        particles: *a.first().unwrap_or(&3300),
        ..Default::default()
    };
    let settle = *a.get(1).unwrap_or(&40000) as u64;
    let timed = *a.get(2).unwrap_or(&20000) as u64;
    let threads = *a.get(3).unwrap_or(&1);
    let (x, r) = mbgc_studies::dem_scene::initial_packing(&spec).expect("packing");
    let mut sim =
        mbgc::dem::Simulation::new(mbgc_studies::dem_scene::scene(&spec, &x, &r).expect("scene"))
            .expect("sim");
    sim.set_threads(threads);
    let t = Instant::now();
    sim.run(settle).expect("settle");
    println!(
        "settle {settle} steps: {:.2} s, builds {}",
        t.elapsed().as_secs_f64(),
        sim.neighbors.builds
    );
    let b0 = sim.neighbors.builds;
    let t = Instant::now();
    sim.run(timed).expect("timed run");
    let s = t.elapsed().as_secs_f64();
    let (et, er) = sim.kinetic_energy();
    println!(
        "timed {timed} steps: {s:.2} s, {:.2} M particle-steps/s, pairs {}, contacts {}, builds {}, KE {et:.3e} rot {er:.3e}",
        (spec.particles as f64 * timed as f64) / s / 1e6,
        sim.neighbors.pairs(),
        sim.contact_count(),
        sim.neighbors.builds - b0
    );
}
