//! Every experiment builds its contact law from the model class: switching an effect changes the
//! result, the parameters an experiment needs follow from the class, and a parameter of an
//! effect the class does not switch on is refused before anything runs (by the campaign plan,
//! naming the parameter and the effect).

use std::path::Path;

use mbgc::campaign::{ExperimentSettings, Plan};
use mbgc::dem::contact::ModelClass;
use mbgc::experiments::hopper::Hopper;
use mbgc::experiments::shear_box::ShearBox;
use mbgc::experiments::wall_impact::WallImpact;
use mbgc::experiments::{Experiment, Outcome, ParamSet, RunOptions};

fn class(s: &str) -> ModelClass {
    ModelClass::parse(s).unwrap()
}

/// The campaign plan of a one-row design of `params`.
fn plan(exp: &dyn Experiment, params: &ParamSet, dir: &Path) -> mbgc::Result<Plan> {
    let names: Vec<&str> = params.iter().map(|(n, _)| n).collect();
    let values: Vec<String> = params.iter().map(|(_, v)| format!("{v:?}")).collect();
    let design = dir.join("design.csv");
    std::fs::write(
        &design,
        format!("{}\n{}\n", names.join(","), values.join(",")),
    )
    .unwrap();
    Plan::new(exp, &design, &[], 1, &ExperimentSettings::default(), None)
}

fn plan_error(exp: &dyn Experiment, params: &ParamSet, dir: &Path) -> String {
    plan(exp, params, dir).expect_err("refused").to_string()
}

fn plan_ok(exp: &dyn Experiment, params: &ParamSet, dir: &Path) {
    plan(exp, params, dir).unwrap();
}

#[test]
fn wall_impact_follows_its_class() {
    let dir = tempfile::tempdir().unwrap();
    let mut p = ParamSet::from_pairs(&[
        ("E_p", 2e11),
        ("nu_p", 0.3),
        ("rho_p", 7800.0),
        ("d50", 10.0),
        ("E_w", 2e11),
        ("mu_pw", 0.1),
        ("impact_speed", 1.0),
        ("impact_angle", 30.0),
        ("e_pw", 0.8),
    ]);
    let hertz = WallImpact {
        class: class("hertz,mindlin"),
    };
    let a = hertz.run(&p, 1, &RunOptions::default()).unwrap();
    assert!((a.get("cnr").unwrap() - 0.8).abs() < 0.01);
    // Kuwabara-Kono's dashpot instead of Hertz's: e_pw belongs to hertz, gamma_n_pw is needed.
    let kk = WallImpact {
        class: class("kuwabara-kono,mindlin"),
    };
    let params = kk.parameters();
    assert!(
        params.contains(&"gamma_n_pw") && !params.contains(&"e_pw"),
        "{params:?}"
    );
    let e = plan_error(&kk, &p, dir.path());
    assert!(e.contains("e_pw") && e.contains("'hertz'"), "{e}");
    let mut q = ParamSet::new();
    for (n, v) in p.iter().filter(|(n, _)| *n != "e_pw") {
        q.set(n, v);
    }
    q.set("gamma_n_pw", 2e3);
    let b = kk.run(&q, 1, &RunOptions::default()).unwrap();
    assert!(
        (b.get("cnr").unwrap() - a.get("cnr").unwrap()).abs() > 0.01,
        "{a:?} {b:?}"
    );
    // Cohesion on the wall contact, named and refused without sjkr, used with it (a soft, slow
    // sphere, where adhesion matters).
    p.set("E_p", 5e6).set("E_w", 5e6).set("impact_speed", 0.05);
    let a = hertz.run(&p, 1, &RunOptions::default()).unwrap();
    p.set("ced_pw", 3e4);
    let e = plan_error(&hertz, &p, dir.path());
    assert!(e.contains("ced_pw") && e.contains("sjkr"), "{e}");
    let sticky = WallImpact {
        class: class("hertz,mindlin,sjkr"),
    };
    plan_ok(&sticky, &p, dir.path());
    let c = sticky.run(&p, 1, &RunOptions::default()).unwrap();
    assert!(
        c.get("cnr").unwrap() < a.get("cnr").unwrap() - 0.01,
        "cohesion holds the sphere back: {a:?} {c:?}"
    );
}

fn shear_box_params() -> ParamSet {
    ParamSet::from_pairs(&[
        ("E_p", 5e6),
        ("E_w", 5e6),
        ("nu_p", 0.3),
        ("e_pp", 0.6),
        ("e_pw", 0.6),
        ("mu_pp", 0.5),
        ("mu_pw", 0.363),
        ("mu_r_pp", 0.3),
        ("mu_r_pw", 0.3),
        ("rho_p", 2600.0),
        ("d50", 5.0),
        ("sigma_ln", 0.1),
    ])
}

fn shear_box(c: &str, p: &ParamSet) -> Outcome {
    let sb = ShearBox {
        box_scale: 5.0,
        class: class(c),
        ..Default::default()
    };
    let o = sb.run(p, 1, &RunOptions::default()).unwrap();
    println!("{c}: {:?}", o.responses);
    o
}

#[test]
fn the_shear_box_follows_its_class() {
    let dir = tempfile::tempdir().unwrap();
    let mut p = shear_box_params();
    let base = shear_box("hertz,mindlin,epsd2", &p);
    // Without rolling resistance the mu_r columns would do nothing: refused, naming EPSD2.
    let free = ShearBox {
        class: class("hertz,mindlin"),
        ..Default::default()
    };
    let e = plan_error(&free, &p, dir.path());
    assert!(e.contains("mu_r_pp") && e.contains("epsd2"), "{e}");
    let mut q = ParamSet::new();
    for (n, v) in p.iter().filter(|(n, _)| !n.starts_with("mu_r")) {
        q.set(n, v);
    }
    let rolling_free = shear_box("hertz,mindlin", &q);
    assert!(
        rolling_free.get("outflow_fraction").unwrap() > base.get("outflow_fraction").unwrap() + 0.1,
        "rolling resistance holds the material back"
    );
    // Cohesion: refused under the default class, changes the result with sjkr.
    p.set("ced_pp", 1e5).set("ced_pw", 1e5);
    let e = plan_error(&ShearBox::default(), &p, dir.path());
    assert!(e.contains("ced_pp") && e.contains("sjkr"), "{e}");
    let cohesive = shear_box("hertz,mindlin,epsd2,sjkr", &p);
    assert_ne!(
        cohesive.get("shear_angle").unwrap().to_bits(),
        base.get("shear_angle").unwrap().to_bits()
    );
    assert!(
        cohesive.get("bulk_density").unwrap() < base.get("bulk_density").unwrap(),
        "cohesion keeps the fill looser: {cohesive:?} {base:?}"
    );
}

#[test]
fn the_hopper_follows_its_class() {
    let dir = tempfile::tempdir().unwrap();
    let p = ParamSet::from_pairs(&[
        ("E_p", 5e6),
        ("E_w", 5e6),
        ("nu_p", 0.3),
        ("e_pp", 0.1),
        ("e_pw", 0.1),
        ("mu_pp", 0.5),
        ("mu_pw", 0.5),
        ("mu_r_pp", 0.1),
        ("mu_r_pw", 0.1),
        ("rho_p", 2500.0),
        ("d50", 3.0),
        ("fill_mass", 0.03),
    ]);
    let run = |c: &str| {
        let o = Hopper { class: class(c) }
            .run(&p, 5, &RunOptions::default())
            .unwrap();
        println!("{c}: {:?}", o.responses);
        o
    };
    let epsd2 = run("hertz,mindlin,epsd2");
    let cdt = run("hertz,mindlin,cdt");
    assert_ne!(
        epsd2.get("discharged_mass").unwrap().to_bits(),
        cdt.get("discharged_mass").unwrap().to_bits()
    );
    let e = plan_error(
        &Hopper {
            class: class("hertz,mindlin"),
        },
        &p,
        dir.path(),
    );
    assert!(
        e.contains("mu_r_pp") && e.contains("'epsd2' or 'cdt'"),
        "{e}"
    );
}
