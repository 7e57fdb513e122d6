//! The eight verification tests of Chung & Ooi (2011) (`reference/chung_ooi_benchmarks.md`), with
//! the contact law of LIGGGHTS 3.8.

use mbgc::dem::contact::{ModelClass, TangentialKind};
use mbgc::dem::impact::{hertz_theory, run_impact, Body, Impact, ImpactResult};
use mbgc::dem::Interaction;

const GLASS: (f64, f64, f64) = (48e9, 0.20, 2800.0);
const LIMESTONE: (f64, f64, f64) = (20e9, 0.25, 2500.0);
const AL_ALLOY: (f64, f64, f64) = (70e9, 0.30, 2699.0);
const MG_ALLOY: (f64, f64, f64) = (40e9, 0.35, 1800.0);
const AL_OXIDE: (f64, f64, f64) = (380e9, 0.23, 4000.0);
const CAST_IRON: (f64, f64, f64) = (100e9, 0.25, 7000.0);
const AL_ALLOY_T4: (f64, f64, f64) = (70e9, 0.33, 2700.0);
const STEEL: (f64, f64, f64) = (208e9, 0.30, 7850.0);
const POLYETHYLENE: (f64, f64, f64) = (1e9, 0.40, 1400.0);
const NYLON: (f64, f64, f64) = (2.5e9, 0.40, 1000.0);
const COPPER: (f64, f64, f64) = (1.2e11, 0.35, 8900.0);

fn body(m: (f64, f64, f64), radius: f64) -> Body {
    Body {
        youngs_modulus: m.0,
        poisson: m.1,
        density: m.2,
        radius,
    }
}

fn impact(b: Body, partner: Option<Body>, v: [f64; 3], e: f64, mu: f64) -> Impact {
    Impact {
        body: b,
        partner,
        wall_youngs_modulus: None,
        velocity: v,
        spin: [0.0; 3],
        partner_velocity: [0.0; 3],
        partner_spin: [0.0; 3],
        interaction: Interaction {
            restitution: e,
            friction: mu,
            ..Default::default()
        },
        class: ModelClass::parse("hertz,mindlin").unwrap(),
        steps_per_contact: 1000.0,
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

fn mass(b: &Body) -> f64 {
    b.density * 4.0 / 3.0 * std::f64::consts::PI * b.radius.powi(3)
}

fn y_eff(a: (f64, f64, f64), b: Option<(f64, f64, f64)>) -> f64 {
    let s = (1.0 - a.1 * a.1) / a.0 + b.map_or(0.0, |b| (1.0 - b.1 * b.1) / b.0);
    1.0 / s
}

/// Test 1: identical spheres head-on at +-10 m/s, elastic.
#[test]
fn test1_normal_impact_of_two_spheres() {
    for (m, table) in [
        (GLASS, (10.70e3, 274e-6, 40.3e-6)),
        (LIMESTONE, (7.11e3, 368e-6, 54.2e-6)),
    ] {
        let b = body(m, 0.01);
        let mut imp = impact(b.clone(), Some(b.clone()), [10.0, 0.0, 0.0], 1.0, 0.0);
        imp.partner_velocity = [-10.0, 0.0, 0.0];
        let r = run_impact(&imp).unwrap();
        let (d, f, t) = hertz_theory(y_eff(m, Some(m)), 0.005, mass(&b) / 2.0, 20.0);
        println!(
            "test1 {m:?}: F {:.4e} ({f:.4e}), d {:.4e} ({d:.4e}), t {:.4e} ({t:.4e})",
            r.max_normal_force, r.max_overlap, r.contact_time
        );
        assert!(
            rel(r.max_normal_force, f) < 0.01
                && rel(r.max_overlap, d) < 0.01
                && rel(r.contact_time, t) < 0.01
        );
        // And the rounded values printed by Chung & Ooi.
        assert!(
            rel(r.max_normal_force, table.0) < 0.01
                && rel(r.max_overlap, table.1) < 0.01
                && rel(r.contact_time, table.2) < 0.01
        );
    }
}

/// Test 2: sphere onto a rigid plane at 0.2 m/s, frictionless, elastic.
#[test]
fn test2_normal_impact_on_a_plane() {
    for (m, table) in [
        (AL_ALLOY, (11.37e3, 49.7e-6, 732e-6)),
        (MG_ALLOY, (7.23e3, 52.1e-6, 767e-6)),
    ] {
        let b = body(m, 0.1);
        let r = run_impact(&impact(b.clone(), None, [0.0, 0.0, -0.2], 1.0, 0.0)).unwrap();
        let (d, f, t) = hertz_theory(y_eff(m, None), 0.1, mass(&b), 0.2);
        println!(
            "test2 {m:?}: F {:.4e} ({f:.4e}), d {:.4e} ({d:.4e}), t {:.4e} ({t:.4e})",
            r.max_normal_force, r.max_overlap, r.contact_time
        );
        assert!(
            rel(r.max_normal_force, f) < 0.01
                && rel(r.max_overlap, d) < 0.01
                && rel(r.contact_time, t) < 0.01
        );
        assert!(
            rel(r.max_normal_force, table.0) < 0.01
                && rel(r.max_overlap, table.1) < 0.01
                && rel(r.contact_time, table.2) < 0.01
        );
        assert!(
            rel(r.velocity[2], 0.2) < 1e-3,
            "elastic rebound {}",
            r.velocity[2]
        );
    }
}

/// Test 3: restitution out equals restitution in, for LIGGGHTS' law and with `limit-force`.
#[test]
fn test3_restitution() {
    for limit_force in [false, true] {
        for m in [AL_OXIDE, CAST_IRON] {
            for e in [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95] {
                let mut imp = impact(body(m, 0.0025), None, [0.0, 0.0, -3.9], e, 0.0);
                imp.class.limit_force = limit_force;
                let r = run_impact(&imp).unwrap();
                let out = r.velocity[2] / 3.9;
                println!(
                    "test3 limit {limit_force} {m:?} e {e}: out {out:.5} ({:+.3} %)",
                    100.0 * (out - e) / e
                );
                assert!(rel(out, e) < 0.01, "e {e}: out {out}");
            }
        }
    }
}

/// Test 4 at a given angle from the normal: tangential restitution of the centre velocity and
/// the rebound spin.
fn oblique(m: (f64, f64, f64), angle_deg: f64) -> (f64, f64) {
    let th = angle_deg.to_radians();
    let v = 3.9;
    let imp = impact(
        body(m, 0.0025),
        None,
        [v * th.sin(), 0.0, -v * th.cos()],
        0.98,
        0.092,
    );
    let r: ImpactResult = run_impact(&imp).unwrap();
    (r.velocity[0] / (v * th.sin()), r.spin[1])
}

#[test]
fn test4_oblique_impact_sliding_branch() {
    let (mu, e, v, radius) = (0.092, 0.98, 3.9, 0.0025);
    for m in [AL_OXIDE, AL_ALLOY_T4] {
        for angle in [40.0, 50.0, 60.0, 70.0, 80.0] {
            let th = f64::to_radians(angle);
            let et_theory = 1.0 - mu * (1.0 + e) / th.tan();
            let w_theory = 5.0 * mu * (1.0 + e) * v * th.cos() / (2.0 * radius);
            let (et, w) = oblique(m, angle);
            println!("test4 {m:?} {angle}: e_t {et:.4} ({et_theory:.4}), w {w:.2} ({w_theory:.2})");
            assert!(
                rel(et, et_theory) < 0.02,
                "{angle}: e_t {et} vs {et_theory}"
            );
            assert!(
                rel(w.abs(), w_theory) < 0.02,
                "{angle}: w {w} vs {w_theory}"
            );
        }
    }
}

/// Below the sliding limit, against Chung & Ooi's digitised results for aluminium oxide.
#[test]
fn test4_oblique_impact_stick_branch() {
    // Tolerances: the points are read off a figure whose axes span 0-1 (e_t) and about
    // -700-0 rad/s (spin), so reading errors are about 1-2 % of the span; below the sliding
    // limit the answer also depends on the tangential stiffness, where the codes compared by
    // Chung & Ooi differ by a few percent. Hence 0.02 on e_t and 15 rad/s on the spin.
    // Chung & Ooi count the rebound spin negative; our forward roll is +y.
    let digitised = [
        (5.0, 0.948, -19.0),
        (10.0, 0.687, -213.0),
        (20.0, 0.616, -511.0),
        (30.0, 0.684, -617.0),
    ];
    for (angle, et_ref, w_ref) in digitised {
        let (et, w) = oblique(AL_OXIDE, angle);
        println!(
            "test4 stick {angle}: e_t {et:.4} ({et_ref}), w {:.1} ({w_ref})",
            -w
        );
        assert!((et - et_ref).abs() <= 0.02, "{angle}: e_t {et} vs {et_ref}");
        assert!((-w - w_ref).abs() <= 15.0, "{angle}: w {} vs {w_ref}", -w);
    }
}

/// Test 5: fixed normal speed, growing tangential speed, elastic, mu = 0.3: the rebound spin
/// levels off at R w' / (mu V_n) = (5/2)(1 + e) = 5 once sliding lasts the whole contact.
#[test]
fn test5_spin_levels_off_at_high_tangential_speed() {
    let (mu, vn, radius) = (0.3, 5.0, 10e-6);
    for m in [STEEL, POLYETHYLENE] {
        let mut last = 0.0;
        for vt in [1.0, 3.0, 6.0, 10.0, 30.0, 70.0] {
            let r = run_impact(&impact(body(m, radius), None, [vt, 0.0, -vn], 1.0, mu)).unwrap();
            let s = radius * r.spin[1] / (mu * vn);
            println!(
                "test5 {m:?} V_t/(mu V_n) {:.2}: R w'/(mu V_n) {s:.4}",
                vt / (mu * vn)
            );
            if vt / (mu * vn) >= 5.0 {
                assert!(rel(s, 5.0) < 0.02, "vt {vt}: {s}");
            }
            assert!(s >= last - 1e-9, "the spin grows with the tangential speed");
            last = s;
        }
    }
}

/// Spinning sphere dropped on a plane (test 6) or on a much larger, heavier sphere (test 8).
fn spinning(m: (f64, f64, f64), partner: Option<Body>, w0: f64) -> ImpactResult {
    let (mu, e, vn, radius) = (0.4, 0.5, 0.2, 0.1);
    let mut imp = impact(body(m, radius), partner.clone(), [0.0, 0.0, -vn], e, mu);
    imp.class.limit_force = true;
    strict(&mut imp);
    if partner.is_some() {
        // The big sphere lies on +x: approach along +x, spin about z.
        imp.velocity = [vn, 0.0, 0.0];
        imp.spin = [0.0, 0.0, w0];
    } else {
        imp.spin = [0.0, w0, 0.0];
    }
    run_impact(&imp).unwrap()
}

/// The spin tests (6-8) assume that the friction impulse is mu times the normal impulse. With
/// LIGGGHTS' law it is not: the restitution-based damping turns the normal force attractive just
/// before the bodies part, and the Coulomb cap mu |F_n| counts that attraction as load. At
/// e = 0.5 the sliding impulse comes out about 17 % too large. We keep that law as the default
/// (it is what seed 004's LIGGGHTS runs used) and check it here; the spin tests run with
/// `limit-force`, where the normal force never pulls and e is still the restitution.
#[test]
fn liggghts_law_inflates_the_friction_impulse_of_a_damped_impact() {
    let (mu, e, vn) = (0.4, 0.5, 0.2);
    let mut imp = impact(body(AL_ALLOY, 0.1), None, [0.0, 0.0, -vn], e, mu);
    imp.spin = [0.0, 15.0, 0.0];
    let r = run_impact(&imp).unwrap();
    let ratio = r.velocity[0].abs() / (mu * (1.0 + e) * vn);
    println!("LIGGGHTS law: friction impulse / (mu x normal impulse) = {ratio:.4}");
    assert!(ratio > 1.1 && ratio < 1.25, "{ratio}");
}

/// Test 6: sliding branch (x = 3.5 mu (1 + e) V_n / (R w0) < 1): the contact slides all along,
/// so v_t' = mu (1 + e) V_n = 0.12 m/s and R w' = R w0 - 0.30 m/s.
#[test]
fn test6_spinning_sphere_onto_a_plane() {
    for m in [AL_ALLOY, NYLON] {
        for w0 in [6.0, 10.0, 15.0, 21.0] {
            let r = spinning(m, None, w0);
            let vt = r.velocity[0].abs();
            let rw = 0.1 * r.spin[1];
            println!(
                "test6 {m:?} w0 {w0}: v_t' {vt:.4} (0.12), R w' {rw:.4} ({:.4})",
                0.1 * w0 - 0.3
            );
            assert!(rel(vt, 0.12) < 0.02, "w0 {w0}: v_t {vt}");
            assert!(rel(rw, 0.1 * w0 - 0.3) < 0.02, "w0 {w0}: R w {rw}");
        }
    }
}

/// Test 7: two identical spheres, both spinning the same way, at +-0.2 m/s. Sliding for
/// w0 >= 4.2 rad/s: each sphere gains 0.12 m/s tangentially and loses 3 rad/s. Sticking below:
/// rigid-body theory gives v_t' = (2/7) R w0 and w' = (2/7) w0.
#[test]
fn test7_two_spinning_spheres() {
    for m in [AL_ALLOY, COPPER] {
        let b = body(m, 0.1);
        for w0 in [5.0, 8.0, 12.0, 18.0, 23.0] {
            let mut imp = impact(b.clone(), Some(b.clone()), [0.2, 0.0, 0.0], 0.5, 0.4);
            imp.partner_velocity = [-0.2, 0.0, 0.0];
            imp.spin = [0.0, 0.0, w0];
            imp.partner_spin = [0.0, 0.0, w0];
            imp.class.limit_force = true;
            strict(&mut imp);
            let r = run_impact(&imp).unwrap();
            let dv = r.velocity[1].abs();
            let dw = w0 - r.spin[2];
            println!("test7 {m:?} w0 {w0}: dv_t {dv:.4} (0.12), dw {dw:.4} (3)");
            assert!(
                rel(dv, 0.12) < 0.02 && rel(dw, 3.0) < 0.02,
                "w0 {w0}: dv {dv}, dw {dw}"
            );
            // Momentum is exchanged, not created: the partner moves the other way.
            assert!((r.velocity[1] + r.partner_velocity[1]).abs() < 1e-9);
        }
        // Stick branch: the tangential spring stores and returns energy, so the outcome differs
        // from rigid-body sticking (v_t' = (2/7) R w0, w' = (2/7) w0); measured 2-7 % off.
        // Tolerance 10 %: the elastic rebound of the spring is physics the formula leaves out.
        for w0 in [1.0, 2.0] {
            let mut imp = impact(b.clone(), Some(b.clone()), [0.2, 0.0, 0.0], 0.5, 0.4);
            imp.partner_velocity = [-0.2, 0.0, 0.0];
            imp.spin = [0.0, 0.0, w0];
            imp.partner_spin = [0.0, 0.0, w0];
            let r = run_impact(&imp).unwrap();
            let (vt, w) = (r.velocity[1].abs(), r.spin[2]);
            println!(
                "test7 stick {m:?} w0 {w0}: v_t' {vt:.4} ({:.4}), w' {w:.4} ({:.4})",
                2.0 / 7.0 * 0.1 * w0,
                2.0 / 7.0 * w0
            );
            assert!(
                rel(vt, 2.0 / 7.0 * 0.1 * w0) < 0.1 && rel(w, 2.0 / 7.0 * w0) < 0.1,
                "w0 {w0}: {vt} {w}"
            );
        }
    }
}

/// Test 8: a sphere onto a much larger and heavier sphere tends to test 6.
#[test]
fn test8_sphere_onto_a_large_heavy_sphere() {
    for m in [AL_ALLOY, NYLON] {
        let big = Body {
            youngs_modulus: m.0,
            poisson: m.1,
            density: m.2 * 1000.0,
            radius: 10.0,
        };
        for w0 in [10.0, 21.0] {
            let r = spinning(m, Some(big.clone()), w0);
            let vt = r.velocity[1].abs();
            let rw = 0.1 * r.spin[2];
            println!(
                "test8 {m:?} w0 {w0}: v_t' {vt:.4} (0.12), R w' {rw:.4} ({:.4})",
                0.1 * w0 - 0.3
            );
            assert!(rel(vt, 0.12) < 0.03, "w0 {w0}: v_t {vt}");
            assert!(rel(rw, 0.1 * w0 - 0.3) < 0.03, "w0 {w0}: R w {rw}");
        }
    }
}

/// Strict Coulomb: the class's tangential effect, and its flag in the interaction that the impact
/// is given directly.
fn strict(imp: &mut Impact) {
    imp.class.tangential = TangentialKind::StrictCoulomb;
    imp.interaction.strict_coulomb = true;
}
