//! The shear cell's verification (issue 36): `mbgc bench shear-cell --report
//! docs/shear_cell.md` regenerates it from the tables under `docs/data/shear_cell/` (the
//! commands that made them are in its READMEs): the noise of one run per response, whether a
//! cohesionless yield locus passes through the origin within that noise, how the cohesion intercept grows with the SJKR energy density against an order-of-magnitude
//! estimate from the contact pull-off, and the cost of a run. It runs no DEM itself.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::campaign_runs::{read_runs_if_any, Run};

/// The responses of the shear cell, in report order, with units.
const RESPONSES: [(&str, &str); 5] = [
    ("internal_friction", "deg"),
    ("cohesion", "Pa"),
    ("unconfined_yield_strength", "Pa"),
    ("bulk_density", "kg/m3"),
    ("shear_ratio", "-"),
];

/// Solid fraction and coordination number of the Rumpf estimate (a random packing).
const SOLID_FRACTION: f64 = 0.6;
const COORDINATION: f64 = 6.0;
/// The failure points lie at 0.25, 0.5 and 0.75 of the pre-shear stress: the estimate takes
/// the contacts at the middle one.
const FAILURE_SHARE: f64 = 0.5;

/// `mbgc bench shear-cell`.
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Args {
    /// Directory of the shear-cell campaign tables.
    #[cfg_attr(feature = "cli", arg(long, default_value = "docs/data/shear_cell"))]
    pub data: PathBuf,
    #[cfg_attr(feature = "cli", arg(long, default_value = "docs/shear_cell.md"))]
    pub report: PathBuf,
    /// Standard output holds one JSON object (where the report went); text goes to standard
    /// error.
    #[cfg_attr(feature = "cli", arg(long))]
    pub json: bool,
}

/// The done runs of a campaign table (an absent table gives none).
fn runs(path: &Path) -> anyhow::Result<Vec<Run>> {
    Ok(read_runs_if_any(path)?
        .into_iter()
        .filter(|r| r.done)
        .collect())
}

/// The cohesion intercept of each ced_pp level of `coh` (the table at `path`) beside the SJKR
/// estimate.
fn cohesion_table(w: &mut String, coh: &[Run], path: &Path) {
    let mut levels: Vec<f64> = coh.iter().map(|r| r.get("ced_pp")).collect();
    levels.sort_by(f64::total_cmp);
    levels.dedup();
    let _ = writeln!(
        w,
        "| ced_pp (J/m3) | runs | cohesion (Pa), each run | mean | estimate (Pa) | mean / \
         estimate | bulk density (kg/m3) | shear ratio |\n|---|---|---|---|---|---|---|---|"
    );
    if levels.is_empty() {
        let _ = writeln!(w, "| (no table `{}` yet) |", path.display());
    }
    for ced in levels {
        let at: Vec<&Run> = coh.iter().filter(|r| r.get("ced_pp") == ced).collect();
        let c: Vec<f64> = at.iter().map(|r| r.get("cohesion")).collect();
        let (m, _, _) = mean_sd(&c);
        let (rho, _, _) = mean_sd(&at.iter().map(|r| r.get("bulk_density")).collect::<Vec<_>>());
        let (ratio, _, _) = mean_sd(&at.iter().map(|r| r.get("shear_ratio")).collect::<Vec<_>>());
        let est = sjkr_estimate(at[0]);
        let _ = writeln!(
            w,
            "| {ced:.3e} | {} | {} | {m:.0} | {est:.0} | {:.2} | {rho:.1} | {ratio:.3} |",
            at.len(),
            c.iter()
                .map(|x| format!("{x:.0}"))
                .collect::<Vec<_>>()
                .join(", "),
            m / est
        );
    }
}

/// Mean and sample sd of the finite values (sd NaN below two).
fn mean_sd(v: &[f64]) -> (f64, f64, usize) {
    let v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    let n = v.len();
    if n == 0 {
        return (f64::NAN, f64::NAN, 0);
    }
    let m = v.iter().sum::<f64>() / n as f64;
    let sd = if n > 1 {
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
    } else {
        f64::NAN
    };
    (m, sd, n)
}

/// The cohesion intercept an SJKR bed of equal spheres would show, to an order of magnitude:
/// each contact carries the normal force of a random packing under the failure stress (Rumpf:
/// `sigma = phi k F / (pi d^2)`), its Hertz overlap sets the contact circle (`pi R delta` for two
/// equal spheres of radius R), SJKR pulls with `ced` times that area, and Rumpf's relation turns
/// the pull-off into a tensile strength, which the intercept is of the order of.
fn sjkr_estimate(run: &Run) -> f64 {
    let (e, nu, d) = (run.get("E_p"), run.get("nu_p"), 1e-3 * run.get("d50"));
    let (sigma, ced) = (FAILURE_SHARE * run.get("normal_stress"), run.get("ced_pp"));
    let rumpf = SOLID_FRACTION * COORDINATION / std::f64::consts::PI;
    let force = sigma * d * d / rumpf;
    let e_star = e / (2.0 * (1.0 - nu * nu));
    let r_star = d / 4.0;
    let overlap = (3.0 * force / (4.0 * e_star * r_star.sqrt())).powf(2.0 / 3.0);
    let pull = ced * std::f64::consts::PI * 0.5 * d * overlap;
    rumpf * pull / (d * d)
}

/// A table of mean ± sd per response, wall time, steps, spheres and steady runs, one line per
/// replicate set; returns the sets that have runs.
fn noise_table<'a>(
    w: &mut String,
    sets: &[(&'a str, PathBuf)],
) -> anyhow::Result<Vec<(&'a str, Vec<Run>)>> {
    let mut head = "| replicates | n |".to_string();
    let mut rule = "|---|---|".to_string();
    for (r, u) in RESPONSES {
        head.push_str(&format!(" {r} ({u}) |"));
        rule.push_str("---|");
    }
    head.push_str(" wall time, s (median, max) | time steps (median) | spheres | steady |");
    rule.push_str("---|---|---|---|");
    let _ = writeln!(w, "{head}\n{rule}");
    let mut rows = Vec::new();
    for (label, file) in sets {
        let rs = runs(file)?;
        if rs.is_empty() {
            let _ = writeln!(w, "| {label} | 0 | (no table `{}` yet) |", file.display());
            continue;
        }
        let mut line = format!("| {label} | {} |", rs.len());
        for (r, _) in RESPONSES {
            let (m, sd, _) = mean_sd(&rs.iter().map(|x| x.get(r)).collect::<Vec<_>>());
            line.push_str(&format!(" {m:.4} ± {sd:.4} |"));
        }
        let mut t: Vec<f64> = rs.iter().map(|x| x.get("wall_time_s")).collect();
        t.sort_by(f64::total_cmp);
        let med = mbgc::numeric::quantile_sorted(&t, 0.5);
        let mut steps: Vec<f64> = rs.iter().map(|x| x.get("steps")).collect();
        steps.sort_by(f64::total_cmp);
        line.push_str(&format!(
            " {med:.0}, {:.0} | {:.0} | {:.0} | {} |",
            t.last().copied().unwrap_or(f64::NAN),
            mbgc::numeric::quantile_sorted(&steps, 0.5),
            rs[0].get("particles"),
            rs.iter().filter(|x| x.get("settled") == 1.0).count()
        ));
        let _ = writeln!(w, "{line}");
        rows.push((*label, rs));
    }
    Ok(rows)
}

/// The cohesion intercept of each cohesionless set against its standard error.
fn origin_table(w: &mut String, rows: &[(&str, Vec<Run>)]) {
    let _ = writeln!(
        w,
        "| replicates | mean intercept (Pa) | standard error (Pa) | mean / se |\n|---|---|---|---|"
    );
    for (label, rs) in rows {
        let (m, sd, n) = mean_sd(&rs.iter().map(|x| x.get("cohesion")).collect::<Vec<_>>());
        let se = sd / (n as f64).sqrt();
        let _ = writeln!(w, "| {label} | {m:.1} | {se:.1} | {:.2} |", m / se);
    }
}

/// `mbgc bench shear-cell`: the report from the tables under `--data`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    let table = |name: &str| a.data.join(name);
    let periodic = [
        (
            "periodic, k = 12, eight, dead-load lid",
            table("periodic/k12_noise.csv"),
        ),
        (
            "periodic, k = 12, eight, servo lid",
            table("periodic/servo/k12_noise.csv"),
        ),
    ];
    let split: [(&str, &str); 5] = [
        ("split box, k = 8, three", "k8_cohesionless.csv"),
        ("split box, k = 12, three", "k12_cohesionless.csv"),
        ("split box, k = 12, eight", "k12_noise.csv"),
        (
            "split box, k = 12, eight, 2 d50, I 1e-3",
            "k12_preshear2_noise.csv",
        ),
        (
            "split box, k = 12, eight, 2 d50, I 2e-3",
            "k12_current_noise.csv",
        ),
    ];
    let split: Vec<(&str, PathBuf)> = split
        .iter()
        .map(|(l, f)| (*l, table(&format!("split_box/{f}"))))
        .collect();
    let engines_files = [
        ("mbgc", table("periodic/liggghts/mbgc_k12.csv")),
        ("LIGGGHTS 3.8", table("periodic/liggghts/liggghts_k12.csv")),
    ];
    let series = table("periodic/k12_cohesion_series.csv");
    let servo_series = table("periodic/servo/k12_cohesion_series.csv");
    let inputs: Vec<(&str, PathBuf)> = periodic
        .iter()
        .chain(&split)
        .chain(&engines_files)
        .map(|(_, f)| ("a table", f.clone()))
        .chain([
            ("a table", series.clone()),
            ("a table", servo_series.clone()),
        ])
        .collect();
    let refs: Vec<(&str, &Path)> = inputs.iter().map(|(w, p)| (*w, p.as_path())).collect();
    mbgc::outputs::refuse_overwriting_inputs("--report", &a.report, &refs)?;

    let mut w = String::new();
    let _ = writeln!(
        w,
        "# The shear cell: noise, the cohesionless locus, cohesion and cost (issue 36)\n\n\
         Regenerate with\n\n```\ncargo run --release -- bench shear-cell --report \
         docs/shear_cell.md\n```\n\n(seconds: it reads the tables under `{}`, whose READMEs \
         give the `mbgc simulate` commands that made them; it runs no DEM).\n\n\
         The cell (`crates/mbgc/src/experiments/shear_cell.rs` gives the procedure and the \
         reasons): periodic in the shear direction and across it, k = 12 d_max in both, a bed \
         about k tall between a glued floor and a glued lid of the material's own grains, \
         sheared without gravity under a dead-load lid (a free body of its grains' mass pressed \
         by the normal stress times the plan area; the tables under `periodic/servo/` and \
         `periodic/liggghts/servo/` were made with the servo-controlled lid that came before it, whose \
         stress overshot on a stiff bed: the experiment's `run_loaded` gives the numbers). The \
         material: \
         monosized spheres of 10 mm, E 5e7 Pa, nu 0.3, rho_p 2600 kg/m3, e 0.5, mu_pp 0.5, \
         rolling friction 0.1, class `hertz,mindlin,epsd2,sjkr`, pre-shear normal stress 5000 \
         Pa, failure at 0.25, 0.5 and 0.75 of it. Every row of a replicate table has the same \
         inputs; the runs differ by their seed only.",
        a.data.display()
    );
    let _ = writeln!(
        w,
        "\n## Noise of one run\n\nMean and sample sd over the replicates (n runs), cohesion 0. \
         `steady` counts the runs that reached a steady pre-shear and a failure peak at every \
         point. The wall times were taken beside other runs and builds on two cores; the time \
         steps measure the cost.\n"
    );
    let rows = noise_table(&mut w, &periodic)?;
    let _ = writeln!(
        w,
        "\n## A cohesionless locus through the origin\n\nThe cohesion intercept against its \
         standard error (sd / sqrt n): a locus through the origin gives |mean| below about \
         twice the standard error.\n"
    );
    origin_table(&mut w, &rows);

    let _ = writeln!(
        w,
        "\n## Cohesion against the SJKR energy density (k = 12, dead-load lid)\n\nThe estimate, to \
         an order of magnitude only: at half the pre-shear stress each contact carries the \
         normal force of a random packing (Rumpf's `sigma = phi k F / (pi d^2)` with phi \
         {SOLID_FRACTION}, k {COORDINATION}), its Hertz overlap sets the contact circle (pi R \
         delta for two equal spheres), SJKR pulls with ced times that area, and Rumpf's relation \
         turns the pull-off into a tensile strength. The measured intercept's noise is that of \
         the table above.\n"
    );
    cohesion_table(&mut w, &runs(&series)?, &series);
    let _ = writeln!(
        w,
        "\nThe same series made before with the servo-controlled lid (`periodic/servo/`), whose \
         failure points overshot their stresses on this stiff bed:\n"
    );
    cohesion_table(&mut w, &runs(&servo_series)?, &servo_series);

    // The LIGGGHTS deck of the same cell against mbgc's engine.
    let engines: Vec<(&str, Vec<Run>)> = engines_files
        .iter()
        .map(|(n, f)| Ok((*n, runs(f)?)))
        .collect::<anyhow::Result<_>>()?;
    let _ = writeln!(
        w,
        "\n## LIGGGHTS 3.8 against mbgc's engine\n\nThe same six rows (k = 12, 6 kPa, cohesionless, dead-load lid; \
         `periodic/liggghts/README.md` gives the commands and each run), mean ± sd per engine, \
         and the difference of the means over its standard error from the two engines' own \
         scatter.\n"
    );
    if engines.iter().any(|(_, rs)| rs.len() < 2) {
        let _ = writeln!(
            w,
            "Not yet run with the periodic cell (fewer than two runs in a table)."
        );
    } else {
        let mut head = "| engine | n |".to_string();
        let mut rule = "|---|---|".to_string();
        for (r, u) in RESPONSES {
            head.push_str(&format!(" {r} ({u}) |"));
            rule.push_str("---|");
        }
        let _ = writeln!(w, "{head} wall time, s (median) |\n{rule}---|");
        let stats = |rs: &[Run], r: &str| mean_sd(&rs.iter().map(|x| x.get(r)).collect::<Vec<_>>());
        for (name, rs) in &engines {
            let mut line = format!("| {name} | {} |", rs.len());
            for (r, _) in RESPONSES {
                let (m, sd, _) = stats(rs, r);
                line.push_str(&format!(" {m:.4} ± {sd:.4} |"));
            }
            let mut t: Vec<f64> = rs.iter().map(|x| x.get("wall_time_s")).collect();
            t.sort_by(f64::total_cmp);
            let _ = writeln!(w, "{line} {:.0} |", mbgc::numeric::quantile_sorted(&t, 0.5));
        }
        let mut line = "| LIGGGHTS - mbgc, z |  |".to_string();
        let mut largest = 0.0f64;
        for (r, _) in RESPONSES {
            let (ma, sa, na) = stats(&engines[0].1, r);
            let (mb, sb, nb) = stats(&engines[1].1, r);
            let se = (sa * sa / na as f64 + sb * sb / nb as f64).sqrt();
            line.push_str(&format!(" {:+.4} ({:+.2}) |", mb - ma, (mb - ma) / se));
            largest = largest.max(((mb - ma) / se).abs());
        }
        let _ = writeln!(w, "{line}  |");
        let _ = writeln!(
            w,
            "\nThe largest difference is {largest:.2} standard errors (three runs each)."
        );
    }

    // History: the split box.
    let _ = writeln!(
        w,
        "\n## History: the split box\n\nThe first version was Jenike's split box with end walls \
         (`split_box/README.md` gives its commands and commits). Its stress ratio climbed until \
         the halves had slid about 15 % of the cell's length apart and fell after it, so a \
         steady pre-shear was reached for this material at 2 d50 but not over most of the \
         campaign space (three of the first four campaign runs failed the steadiness test). \
         Its replicates of the same material, for comparison: their shear ratio (0.83-0.88) \
         and angle (42 deg) lie far above the periodic cell's, and their bulk density (1390 \
         kg/m3, over the whole box) below its interior's. The split box had walls the periodic \
         cell has not (end walls pushing the upper half, side walls with mu_pw 0.3 along the \
         bed, the halves' rims at the shear plane); which of them raised the ratio was not \
         measured.\n"
    );
    let old = noise_table(&mut w, &split)?;
    let _ = writeln!(w);
    origin_table(&mut w, &old);

    crate::write_report(a.json, &a.report, &w, serde_json::json!({ "data": a.data }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The estimate at the report's material: 10 mm spheres, E 5e7, 2500 Pa at failure give a
    /// contact force of 0.22 N, an overlap of 24 um, and with ced 1e5 an intercept of ~440 Pa;
    /// it is linear in ced.
    #[test]
    fn the_sjkr_estimate_is_linear_in_ced_and_of_the_expected_size() {
        let run = |ced: f64| {
            Run::with_values(vec![
                ("E_p".into(), 5e7),
                ("nu_p".into(), 0.3),
                ("d50".into(), 10.0),
                ("normal_stress".into(), 5000.0),
                ("ced_pp".into(), ced),
            ])
        };
        let a = sjkr_estimate(&run(1e5));
        let b = sjkr_estimate(&run(3e5));
        assert!((b / a - 3.0).abs() < 1e-12);
        assert!(a > 300.0 && a < 600.0, "{a}");
    }
}
