//! One shear-box run with a side-view picture:
//! cargo run --release --example shear_box -- [k] [mu_pp] [mu_r_pp] [d50_mm] [sigma_ln] [E] [picture.png] [trace.csv] [seed] [skin in d_min]
use mbgc::experiments::{shear_box::ShearBox, ParamSet, RunOptions};

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
        ("mu_pw", 0.363),
        ("mu_r_pp", f(2, 0.3)),
        ("mu_r_pw", 0.3),
        ("rho_p", 2600.0),
        ("d50", f(3, 5.0)),
        ("sigma_ln", f(4, 0.1)),
    ]);
    let sb = ShearBox {
        box_scale: f(0, 6.0),
        skin: f(9, mbgc::experiments::shear_box::SKIN),
        ..Default::default()
    };
    let opts = RunOptions {
        picture: a.get(6).filter(|s| !s.is_empty()).map(Into::into),
        threads: 1,
        ..Default::default()
    };
    let (o, rec) = sb
        .run_recorded(&p, a.get(8).map_or(1, |s| s.parse().expect("seed")), &opts)
        .expect("run");
    println!("{:?}\n{:?}", o.responses, o.diagnostics);
    // Where a whole run's time goes: the fill (creation, fall, rest, strike-off) and the outflow.
    println!(
        "created {} particles, {} in the box after the strike-off; fill {} steps {:.1} s, \
         outflow {} steps {:.1} s (dt {:.3e} s)",
        rec.created,
        o.diagnostics.particles,
        rec.fill_steps + rec.relax_steps,
        rec.fill_seconds,
        rec.flow_steps,
        rec.flow_seconds,
        rec.dt
    );
    if let Some(path) = a.get(7).filter(|s| !s.is_empty()) {
        let mut out =
            String::from("phase,step,time,rms_speed,max_speed,max_step,removed,response\n");
        for c in &rec.trace {
            out += &format!(
                "{:?},{},{:.6},{:.6e},{:.6e},{:.6e},{},{:.6}\n",
                c.phase,
                c.step,
                c.time,
                c.rms_speed,
                c.max_speed,
                c.max_step,
                c.removed,
                c.response
            );
        }
        std::fs::write(path, out).expect("writing the trace");
    }
}
