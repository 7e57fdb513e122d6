//! mbgc's shear box against an independent LIGGGHTS deck that fills itself (issue 13).
//! cargo run --release --example shear_box_fill -- CODE POINT SEEDS [k] [classes] [out.tsv]
//! CODE: mbgc | liggghts | replay (mbgc, then LIGGGHTS continuing from mbgc's initial particles: the
//! replay deck, whose row is printed as code "replay-liggghts"); POINT: a point of
//! `mbgc_studies::shear_box_check::point` (a, c, b, a2, c2, b2, gravel);
//! classes: mbgc's PSD quantised to that many classes (0: continuous), or LIGGGHTS' templates.
//! column (LIGGGHTS only): "lattice" (mbgc's poured column, from the floor; the name is historical) or "above" (the same
//! height, starting at the rim), or "above:F": above the rim at solid fraction F.
use std::io::Write as _;

use mbgc::experiments::shear_box::ShearBox;
use mbgc_studies::shear_box_fill::{fill_deck, mean_se, run_liggghts, run_mbgc, FillMeasure};

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let code = a.first().map(String::as_str).unwrap_or("mbgc").to_owned();
    let point = a.get(1).map(String::as_str).unwrap_or("a").to_owned();
    let seeds: u64 = a.get(2).map(|s| s.parse().expect("seeds")).unwrap_or(3);
    let k: f64 = a.get(3).map(|s| s.parse().expect("k")).unwrap_or(10.0);
    let classes: usize = a.get(4).map(|s| s.parse().expect("classes")).unwrap_or(5);
    let out = a
        .get(5)
        .cloned()
        .unwrap_or("target/shear-box-fill.tsv".into());
    let col = a.get(6).cloned().unwrap_or("lattice".into());
    let p =
        mbgc_studies::shear_box_check::point(&point).expect("point: a, c, b, a2, c2, b2 or gravel");
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&out)
        .expect("output table");
    let (mut angle, mut bulk) = (Vec::new(), Vec::new());
    for seed in 1..=seeds {
        let t = std::time::Instant::now();
        if code == "replay" {
            let sb = ShearBox {
                box_scale: k,
                ..Default::default()
            };
            let (o, rec) = run_mbgc(&sb, &p, seed).expect("mbgc run");
            let dir = format!("target/shear-box-fill/replay-{point}-{seed}");
            let r =
                mbgc_studies::shear_box_vs_liggghts::replay(std::path::Path::new(&dir), &p, &rec)
                    .expect("LIGGGHTS replay");
            let line = format!(
                "mbgc\t{point}\t{k}\t0/lattice\t{seed}\t{}\nreplay-liggghts\t{point}\t{k}\t0\t{seed}\t{:.3}\t{:.1}",
                o.row(),
                r.shear_angle,
                r.bulk_density
            );
            println!("{line}");
            writeln!(file, "{line}").expect("write");
            angle.push(r.shear_angle);
            bulk.push(r.bulk_density);
            continue;
        }
        let m: FillMeasure = if code == "mbgc" {
            let sb = ShearBox {
                box_scale: k,
                psd_classes: classes,
                ..Default::default()
            };
            run_mbgc(&sb, &p, seed).expect("mbgc run").0
        } else {
            let sb = ShearBox {
                box_scale: k,
                ..Default::default()
            };
            let lattice = fill_deck(&sb, &p, seed, classes, None).expect("deck");
            let lay = sb.layout(&p, seed).expect("layout");
            let [l, w, h] = lay.size;
            let column = match col.split_once(':') {
                _ if col == "lattice" => None,
                None => Some((h, h + lattice.column.1 - lattice.column.0)),
                Some((_, f)) => {
                    let f: f64 = f.parse().expect("solid fraction");
                    Some((
                        h,
                        h + lattice.mass / p.get("rho_p").expect("rho_p") / (f * l * w),
                    ))
                }
            };
            let deck = fill_deck(&sb, &p, seed, classes, column).expect("deck");
            let d_max = lay.d_max;
            let dir = format!("target/shear-box-fill/{code}-{point}-{classes}-{col}-{seed}");
            run_liggghts(std::path::Path::new(&dir), &p, &deck, d_max).expect("LIGGGHTS run")
        };
        let line = format!(
            "{code}\t{point}\t{k}\t{classes}/{col}\t{seed}\t{}\t{:.1}",
            m.row(),
            t.elapsed().as_secs_f64()
        );
        println!("{line}");
        writeln!(file, "{line}").expect("write");
        angle.push(m.shear_angle);
        bulk.push(m.bulk_density);
    }
    let (am, ase) = mean_se(&angle);
    let (bm, bse) = mean_se(&bulk);
    println!(
        "# {code} point {point} k {k} classes {classes}: angle {am:.2} +- {ase:.2} deg, bulk {bm:.1} +- {bse:.1} kg/m3 (n = {seeds}); columns: code point k classes seed {} wall_s",
        FillMeasure::HEADER.replace('\t', " ")
    );
}
