//! Shear box in mbgc and replayed in LIGGGHTS on the identical configuration.
//! cargo run --release --example shear_box_vs_liggghts -- [k] [mu_pp] [mu_r_pp] [d50_mm] [sigma_ln] [E] [seed] [mu_pw] [mu_r_pw]
use mbgc::experiments::{shear_box::ShearBox, ParamSet, RunOptions};
use mbgc_studies::shear_box_vs_liggghts::replay;

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let f = |i: usize, d: f64| a.get(i).map(|s| s.parse().expect("number")).unwrap_or(d);
    let p = ParamSet::from_pairs(&[
        ("E_p", f(5, 5e6)),
        ("E_w", f(5, 5e6)),
        ("nu_p", 0.3),
        ("e_pp", 0.6),
        ("e_pw", 0.6),
        ("mu_pp", f(1, 0.5)),
        ("mu_pw", f(7, 0.363)),
        ("mu_r_pp", f(2, 0.3)),
        ("mu_r_pw", f(8, 0.3)),
        ("rho_p", 2600.0),
        ("d50", f(3, 5.0)),
        ("sigma_ln", f(4, 0.1)),
    ]);
    let sb = ShearBox {
        box_scale: f(0, 6.0),
        ..Default::default()
    };
    let (o, rec) = sb
        .run_recorded(&p, f(6, 1.0) as u64, &RunOptions::default())
        .expect("mbgc run");
    println!(
        "mbgc: {:?}, {} particles, fill {} + relax {} + flow {} steps",
        o.responses, o.diagnostics.particles, rec.fill_steps, rec.relax_steps, rec.flow_steps
    );
    let t = std::time::Instant::now();
    let l = replay(std::path::Path::new("target/shear-box-liggghts"), &p, &rec)
        .expect("LIGGGHTS replay");
    println!("LIGGGHTS ({:.1} s): {l:?}", t.elapsed().as_secs_f64());
    println!(
        "difference: shear angle {:+.2} deg, bulk density {:+.2} %",
        o.get("shear_angle").unwrap() - l.shear_angle,
        100.0 * (o.get("bulk_density").unwrap() / l.bulk_density - 1.0)
    );
}
