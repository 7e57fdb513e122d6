//! The flat-bottom hopper discharge experiment (seed 000) on small scenes (a few seconds each,
//! the first also checked against Beverloo), and the tighter Beverloo check on the seed's
//! apparatus with the default fill (ignored: ~2-3 min):
//!
//! cargo test --release --test hopper -- --ignored --nocapture

use mbgc::experiments::hopper::{write_series_csv, Hopper, HopperRun};
use mbgc::experiments::{Experiment, ParamSet, RunOptions};

/// Mid-friction beads, soft for speed (seed 000: E does not change flow rate or angles).
fn params(d50: f64, mu_pp: f64) -> ParamSet {
    ParamSet::from_pairs(&[
        ("E_p", 1e7),
        ("E_w", 1e7),
        ("nu_p", 0.3),
        ("e_pp", 0.5),
        ("e_pw", 0.5),
        ("mu_pp", mu_pp),
        ("mu_pw", 0.5),
        ("mu_r_pp", 0.1),
        ("mu_r_pw", 0.1),
        ("rho_p", 2500.0),
        ("d50", d50),
    ])
}

/// ~1100 beads of 3 mm (0.04 kg), the softest E of the seed-004 space and little restitution, so
/// that the small pile does not scatter over the plate: a few seconds per run.
fn tiny(mu_pp: f64) -> ParamSet {
    let mut p = params(3.0, mu_pp);
    p.set("E_p", 5e6)
        .set("E_w", 5e6)
        .set("e_pp", 0.1)
        .set("e_pw", 0.1)
        .set("fill_mass", 0.04);
    p
}

fn report(label: &str, r: &HopperRun) -> String {
    let o = &r.outcome;
    let g = |k: &str| o.get(k).unwrap_or(f64::NAN);
    format!(
        "{label}: {} particles, {} steps ({} settling, dt {:.2e} s, discharge {:.2} s), wall \
         {:.1} s; flow {:.4} kg/s (R2 {:.4}), Beverloo ratio {:.3}, rho_b {:.0}, fill {:.1} mm, \
         discharged {:.3}; top {:.1} {:.1?}, bottom {:.1} {:.1?}; settled {}; warnings {:?}",
        o.diagnostics.particles,
        o.diagnostics.steps,
        r.settle_steps,
        r.dt,
        r.discharge_time,
        o.diagnostics.wall_time_s,
        g("flow_rate"),
        g("flow_R2"),
        g("beverloo_ratio"),
        g("bulk_density"),
        r.fill_height * 1e3,
        g("discharged_fraction"),
        g("repose_angle_top"),
        r.top_angles,
        g("repose_angle_bottom"),
        r.bottom_angles,
        o.diagnostics.settled,
        o.diagnostics.warnings
    )
}

#[test]
fn impossible_parameter_sets_are_refused_before_anything_runs() {
    let h = Hopper::default();
    let cases: [(&str, f64, &str); 6] = [
        ("rho_p", -2500.0, "rho_p"),
        // 4 mm beads: the 15 mm orifice is less than 4 particles wide.
        ("d50", 4.0, "d50"),
        ("sigma_ln", -0.2, "sigma_ln"),
        ("scale", 0.0, "scale"),
        // 2 kg do not fit in the 50 x 70 mm cylinder.
        ("fill_mass", 2.0, "fill_mass"),
        ("mu_pp", f64::NAN, "mu_pp"),
    ];
    for (name, value, named) in cases {
        let mut p = params(2.0, 0.5);
        p.set(name, value);
        let e = h.check(&p).unwrap_err().to_string();
        assert!(e.contains(named), "{name} = {value}: {e}");
        let t = std::time::Instant::now();
        let e = h
            .run(&p, 1, &RunOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(named) && t.elapsed().as_secs_f64() < 0.1, "{e}");
    }
    let mut p = params(2.0, 0.5);
    p.set("E_p", -1.0);
    assert!(h.check(&p).unwrap_err().to_string().contains("E_p"));
    // A wide PSD brings particles too large for the orifice even at d50 = 2 mm.
    let mut p = params(2.0, 0.5);
    p.set("sigma_ln", 0.6);
    assert!(h.check(&p).unwrap_err().to_string().contains("d50"));
    // Scaling the apparatus up makes room for the same particles.
    let mut p = params(4.0, 0.5);
    p.set("scale", 1.5);
    h.check(&p).unwrap();
    p.set("sigma_ln", 0.1);
    h.check(&p).unwrap();
}

#[test]
fn a_small_discharge_keeps_every_particle_stops_and_measures() {
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        picture: Some(dir.path().join("hopper.svg")),
        ..Default::default()
    };
    let r = Hopper::default()
        .run_detailed(&tiny(0.5), 3, &opts)
        .unwrap();
    println!("{}", report("tiny mu_pp 0.5", &r));
    let o = &r.outcome;
    let n = o.diagnostics.particles;
    assert!(o.diagnostics.settled, "{:?}", o.diagnostics.warnings);
    // Nobody left through a wall: above the orifice means inside the cylinder.
    assert_eq!(r.in_container + r.on_plate + r.off_plate, n);
    assert_eq!(r.in_container + r.passed, n);
    assert!(r.passed > n / 10 && r.in_container > n / 10, "{}", r.passed);
    // The flow stopped: the last 0.1 s of the series discharged nothing.
    let (t_end, m_end) = (
        *r.series.time_s.last().unwrap(),
        *r.series.mass_kg.last().unwrap(),
    );
    let k = r
        .series
        .time_s
        .iter()
        .position(|&t| t >= t_end - 0.1)
        .unwrap();
    assert_eq!(r.series.mass_kg[k], m_end);
    assert!(r.series.mass_kg.windows(2).all(|w| w[1] >= w[0]));
    for name in ["repose_angle_top", "repose_angle_bottom"] {
        let a = o.get(name).unwrap();
        assert!(a.is_finite() && a > 0.0 && a < 90.0, "{name} = {a}");
    }
    let w = o.get("flow_rate").unwrap();
    assert!(w.is_finite() && w > 0.0, "{w}");
    // Beverloo (C 0.58, k 1.5, the measured bulk density) within 25 %. This scene sits at the
    // edge of the correlation's validity (D_o / d = 5, a fill of 1.1 D_o whose rate decays
    // early), so the bound is loose; measured 0.84. A flow rate off by a physical factor
    // (gravity, density, the time step's units, the orifice size) falls far outside it.
    let ratio = o.get("beverloo_ratio").unwrap();
    assert!((ratio - 1.0).abs() < 0.25, "measured / Beverloo = {ratio}");
    assert!((o.get("discharged_mass").unwrap() - m_end).abs() < 1e-12);
    assert!(
        std::fs::metadata(dir.path().join("hopper.svg"))
            .unwrap()
            .len()
            > 1000
    );
    let csv = dir.path().join("series.csv");
    write_series_csv(&csv, &r.series).unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("time_s,discharged_mass_kg\n"));
    assert_eq!(text.lines().count(), r.series.time_s.len() + 1);
}

#[test]
fn higher_friction_leaves_a_steeper_crater() {
    // The top angle needs no pile: ~850 beads do.
    let run = |mu_pp| {
        let mut p = tiny(mu_pp);
        p.set("fill_mass", 0.03);
        Hopper::default()
            .run_detailed(&p, 5, &RunOptions::default())
            .unwrap()
    };
    let (low, high) = (run(0.1), run(0.8));
    println!("{}\n{}", report("mu 0.1", &low), report("mu 0.8", &high));
    let (a, b) = (
        low.outcome.get("repose_angle_top").unwrap(),
        high.outcome.get("repose_angle_top").unwrap(),
    );
    assert!(b > a + 5.0, "top angle {a} at mu_pp 0.1, {b} at 0.8");
    // Less material flows out when the grains hold together.
    assert!(
        high.outcome.get("discharged_mass").unwrap() < low.outcome.get("discharged_mass").unwrap()
    );
}

#[test]
fn the_seed_decides_everything() {
    let mut p = tiny(0.5);
    p.set("d50", 2.5)
        .set("sigma_ln", 0.1)
        .set("fill_mass", 0.004);
    let run = |seed| {
        Hopper::default()
            .run(&p, seed, &RunOptions::default())
            .unwrap()
    };
    // Bit patterns: NaN (e.g. no pile from 200 particles) must equal itself.
    let bits = |o: &mbgc::experiments::Outcome| -> Vec<u64> {
        o.responses.iter().map(|(_, v)| v.to_bits()).collect()
    };
    let (a, b, c) = (run(7), run(7), run(8));
    assert_eq!(bits(&a), bits(&b));
    assert_ne!(bits(&a), bits(&c));
}

/// Beverloo on the seed's apparatus: mid friction, 2 mm monosized beads, default fill.
#[test]
#[ignore = "~2-3 min: cargo test --release --test hopper -- --ignored --nocapture"]
fn flow_rate_follows_beverloo() {
    let r = Hopper::default()
        .run_detailed(&params(2.0, 0.5), 1, &RunOptions::default())
        .unwrap();
    println!("{}", report("Beverloo, d50 2 mm, mu_pp 0.5", &r));
    let ratio = r.outcome.get("beverloo_ratio").unwrap();
    assert!((ratio - 1.0).abs() < 0.25, "measured / Beverloo = {ratio}");
    assert!(r.outcome.diagnostics.settled);
}

/// Explore: HOPPER="mu_pp=0.5,d50=2,fill_mass=0.05" cargo test --release --test hopper explore
/// -- --ignored --nocapture (optional SEED, THREADS, PICTURE=file.svg, SERIES=file.csv).
#[test]
#[ignore = "exploration driver"]
fn explore() {
    let mut p = params(2.0, 0.5);
    let spec = std::env::var("HOPPER").unwrap_or_default();
    for kv in spec.split(',').filter(|s| !s.is_empty()) {
        let (k, v) = kv.split_once('=').expect("HOPPER: name=value,...");
        p.set(k.trim(), v.trim().parse().expect("HOPPER: a number"));
    }
    let threads = std::env::var("THREADS")
        .ok()
        .and_then(|t| t.parse().ok())
        .unwrap_or(1);
    let opts = RunOptions {
        threads,
        picture: std::env::var("PICTURE").ok().map(Into::into),
        ..Default::default()
    };
    let seed = std::env::var("SEED")
        .ok()
        .and_then(|t| t.parse().ok())
        .unwrap_or(1);
    let r = Hopper::default().run_detailed(&p, seed, &opts).unwrap();
    println!("{}", report(&format!("{spec} seed {seed}"), &r));
    if let Ok(path) = std::env::var("SERIES") {
        write_series_csv(path.as_ref(), &r.series).unwrap();
    }
}
