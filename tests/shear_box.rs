//! Shear box on small scenes (box scale k = 5, about 400 particles): the trends seed 004's
//! metamodel relies on, and the refusal of impossible parameter sets.

use mbgc::experiments::{shear_box::ShearBox, Experiment, Outcome, ParamSet, RunOptions};

fn params(mu_pp: f64, mu_r_pp: f64) -> ParamSet {
    ParamSet::from_pairs(&[
        ("E_p", 5e6),
        ("E_w", 5e6),
        ("nu_p", 0.3),
        ("e_pp", 0.6),
        ("e_pw", 0.6),
        ("mu_pp", mu_pp),
        ("mu_pw", 0.363),
        ("mu_r_pp", mu_r_pp),
        ("mu_r_pw", 0.3),
        ("rho_p", 2600.0),
        ("d50", 5.0),
        ("sigma_ln", 0.1),
    ])
}

fn run(mu_pp: f64, mu_r_pp: f64) -> Outcome {
    let sb = ShearBox {
        box_scale: 5.0,
        ..Default::default()
    };
    let o = sb
        .run(&params(mu_pp, mu_r_pp), 1, &RunOptions::default())
        .unwrap();
    println!(
        "mu_pp {mu_pp} mu_r_pp {mu_r_pp}: {:?} {:?}",
        o.responses, o.diagnostics
    );
    assert!(o.diagnostics.settled, "{:?}", o.diagnostics.warnings);
    let f = o.get("outflow_fraction").unwrap();
    assert!(
        f > 0.05 && f < 0.95,
        "some material flows out, some stays: {f}"
    );
    // A 5 d_max box leaves about eight flank columns; a rolling flank (mu_r 0) bends there.
    assert!(o.get("flank_r2").unwrap() > 0.85);
    o
}

#[test]
fn shear_angle_rises_and_bulk_density_falls_with_friction() {
    let (lo, hi) = (run(0.1, 0.3), run(0.8, 0.3));
    let angle = |o: &Outcome| o.get("shear_angle").unwrap();
    let rho = |o: &Outcome| o.get("bulk_density").unwrap();
    assert!(
        angle(&hi) > angle(&lo) + 2.0,
        "{} vs {}",
        angle(&hi),
        angle(&lo)
    );
    assert!(rho(&hi) < rho(&lo) * 0.97, "{} vs {}", rho(&hi), rho(&lo));
    let (r0, r1) = (run(0.5, 0.0), run(0.5, 0.6));
    assert!(
        angle(&r1) > angle(&r0) + 5.0,
        "{} vs {}",
        angle(&r1),
        angle(&r0)
    );
}

#[test]
fn same_seed_same_result() {
    let sb = ShearBox {
        box_scale: 5.0,
        ..Default::default()
    };
    let a = sb
        .run(&params(0.5, 0.3), 7, &RunOptions::default())
        .unwrap();
    let b = sb
        .run(&params(0.5, 0.3), 7, &RunOptions::default())
        .unwrap();
    assert!(a.get("shear_angle").unwrap().is_finite());
    assert_eq!(a.responses, b.responses);
}

#[test]
fn impossible_parameter_sets_are_refused_before_running() {
    let sb = ShearBox::default();
    for (name, v) in [
        ("rho_p", -2600.0),
        ("mu_pp", -0.1),
        ("e_pp", 1.5),
        ("d50", 0.0),
        ("E_p", f64::NAN),
        ("sigma_ln", 3.0),
    ] {
        let mut p = params(0.5, 0.3);
        p.set(name, v);
        let e = sb.check(&p).unwrap_err().to_string();
        assert!(e.contains(name), "{name}: {e}");
    }
    let mut p = params(0.5, 0.3);
    p.set("sigma_ln", 1.17);
    let e = sb.check(&p).unwrap_err().to_string();
    assert!(
        e.contains("particles"),
        "a too wide PSD is refused by its size: {e}"
    );
}
