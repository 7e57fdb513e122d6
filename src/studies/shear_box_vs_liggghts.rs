//! The shear box in mbgc against LIGGGHTS 3.8 replaying the identical run
//! ([`crate::liggghts::shear_box`] writes the deck: mbgc's initial particles, walls and schedule).
//! Both final states are measured by the same code, so the difference is the codes' alone.

use crate::cli::output::Output;
use crate::say;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::reference::Reference;
use crate::dem::experiments::shear_box::ShearBox;
use crate::dem::experiments::{Experiment, RunOptions};

use crate::dem::analysis::sphere_box_volume;
use crate::dem::experiments::shear_box::{measure_flank, RunRecord};
use crate::dem::experiments::ParamSet;
use crate::dem::particles::Particles;
use crate::error::{read_to_string, write_atomic, Error, Result};
use crate::liggghts::shear_box::{write_deck, FILLED_DUMP, FINAL_DUMP, INPUT, LOG};
use crate::liggghts::{parse_dump_rows, require_binary, run_deck};
use crate::numeric::mean_sd;

fn particles_of(rows: &[(usize, f64, [f64; 3])]) -> Particles {
    let mut p = Particles::new();
    for (_, r, x) in rows {
        // Density is irrelevant to the geometric measures.
        let _ = p.add(*x, *r, 1.0, 0);
    }
    p
}

/// LIGGGHTS' shear angle, bulk density and flank R^2 for the replayed run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReplayResult {
    pub shear_angle: f64,
    pub bulk_density: f64,
    pub flank_r2: f64,
    pub particles_left: usize,
}

/// Replays a recorded mbgc run in LIGGGHTS (in `dir`) and measures it as mbgc does.
pub fn replay(dir: &Path, p: &ParamSet, rec: &RunRecord) -> Result<ReplayResult> {
    let binary = require_binary()?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    for stale in [FILLED_DUMP, FINAL_DUMP, LOG] {
        let f = dir.join(stale);
        if f.exists() {
            std::fs::remove_file(&f).map_err(|e| Error::io(&f, e))?;
        }
    }
    write_deck(dir, p, rec)?;
    run_deck(&binary, dir, INPUT, LOG)?;
    let [l, w, h] = rec.layout.size;
    let rho = p.get("rho_p").unwrap_or(f64::NAN);
    let read = |name: &str| -> Result<Vec<(usize, f64, [f64; 3])>> {
        let f = dir.join(name);
        parse_dump_rows(&f.display().to_string(), &read_to_string(&f)?)
    };
    let filled = read(FILLED_DUMP)?;
    let mass: f64 = filled
        .iter()
        .map(|(_, r, x)| rho * sphere_box_volume(*x, *r, [0.0; 3], [l, w, h]))
        .sum();
    let fin = particles_of(&read(FINAL_DUMP)?);
    let flank = measure_flank(&fin, rec.layout.size, rec.layout.d_max);
    Ok(ReplayResult {
        shear_angle: (-flank.slope).atan().to_degrees(),
        bulk_density: mass / (l * w * h),
        flank_r2: flank.r2,
        particles_left: fin.len(),
    })
}

/// `mbgc bench shear-box`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Box scale k for the comparison runs.
    #[arg(long, default_value_t = 6.0)]
    pub box_scale: f64,
    /// Seeds per parameter set (1..=seeds).
    #[arg(long, default_value_t = 5)]
    pub seeds: u64,
    /// Run the identical cases in LIGGGHTS.
    #[arg(long, value_enum)]
    pub vs: Option<Reference>,
    /// Skip the cost table.
    #[arg(long)]
    pub no_cost: bool,
    /// Only (re)make the cost table, replacing that section of an existing report.
    #[arg(long)]
    pub cost_only: bool,
    /// Cost-table cases with more particles than this are sized but not run.
    #[arg(long, default_value_t = 6000)]
    pub cost_max_particles: usize,
    #[arg(long, default_value = "target/bench-shear-box")]
    pub work_dir: PathBuf,
    /// Markdown report (e.g. docs/experiments.md).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Standard output holds one JSON object (the results); the text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

fn shear_box_params(
    mu_pp: f64,
    mu_r_pp: f64,
    mu_pw: f64,
    mu_r_pw: f64,
    d50: f64,
    sigma: f64,
    e: f64,
) -> crate::dem::experiments::ParamSet {
    crate::dem::experiments::ParamSet::from_pairs(&[
        ("E_p", e),
        ("E_w", e),
        ("nu_p", 0.3),
        ("e_pp", 0.6),
        ("e_pw", 0.6),
        ("mu_pp", mu_pp),
        ("mu_pw", mu_pw),
        ("mu_r_pp", mu_r_pp),
        ("mu_r_pw", mu_r_pw),
        ("rho_p", 2600.0),
        ("d50", d50),
        ("sigma_ln", sigma),
    ])
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    let mut rows: Vec<serde_json::Value> = Vec::new();
    if a.seeds == 0 {
        anyhow::bail!("--seeds must be at least 1");
    }
    if a.vs.is_some() && crate::liggghts::find_binary().is_none() {
        anyhow::bail!(
            "--vs liggghts: no LIGGGHTS binary on PATH (Debian: apt-get install liggghts)"
        );
    }
    let sets = [
        (
            "low friction",
            shear_box_params(0.3, 0.1, 0.3, 0.1, 5.0, 0.1, 5e6),
        ),
        (
            "mid friction",
            shear_box_params(0.5, 0.3, 0.363, 0.3, 5.0, 0.1, 5e6),
        ),
        (
            "high friction",
            shear_box_params(0.9, 0.6, 0.6, 0.5, 5.0, 0.1, 5e6),
        ),
    ];
    let sb = ShearBox {
        box_scale: a.box_scale,
        ..Default::default()
    };
    let mut s = String::new();
    if a.cost_only {
        // Keep the comparison of an earlier run; only the cost section is made again.
        let existing = a
            .report
            .as_ref()
            .and_then(|p| std::fs::read_to_string(p).ok())
            .unwrap_or_default();
        s = existing
            .split("\n## Cost of a shear-box run")
            .next()
            .unwrap_or("")
            .trim_end()
            .to_string();
        s.push('\n');
    } else {
        let cmd = format!(
            "cargo run --release -- bench shear-box --box-scale {} --seeds {}{}{} --report {}",
            a.box_scale,
            a.seeds,
            if a.vs.is_some() { " --vs liggghts" } else { "" },
            if a.no_cost { " --no-cost" } else { "" },
            a.report
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_default()
        );
        let _ = writeln!(
            s,
            "# Calibration experiments\n\nRegenerate with\n\n```\n{cmd}\n```\n"
        );
        let _ = writeln!(s, "## Shear box: mbgc against LIGGGHTS 3.8\n");
        let _ = writeln!(s, "Each run is made by mbgc (its own rest criteria decide when the fill is at rest and when the outflow has \
        stopped), then replayed in LIGGGHTS from the identical particles and positions with the same schedule: fill, strike \
        off at the rim, relax, remove the flap, remove what fell below the floor every chunk (`src/liggghts/shear_box.rs` \
        writes the data file, the walls as STL meshes (the flap as a plane: LIGGGHTS takes one mesh wall fix) and the input \
        script). Both final states are measured by the same code. Box scale k = {}, E = 5e6 Pa, e = 0.6, rho_p = 2600, \
        d50 = 5 mm, sigma_ln = 0.1, seeds 1..={}. Granular outflow is chaotic: two codes (or two seeds) differ run by run by \
        a few degrees, so the comparison is of means over seeds, with the standard error of the difference.\n", a.box_scale, a.seeds);
        let _ = writeln!(s, "| set | mu_pp, mu_r_pp, mu_pw, mu_r_pw | shear angle mbgc (deg) | LIGGGHTS | difference +- s.e. | bulk density mbgc (kg/m3) | LIGGGHTS | difference |");
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
        for (name, p) in &sets {
            let (mut am, mut al, mut rm, mut rl, mut da) = (vec![], vec![], vec![], vec![], vec![]);
            for seed in 1..=a.seeds {
                eprintln!("{name}: seed {seed}");
                let (o, rec) = sb.run_recorded(p, seed, &RunOptions::default())?;
                am.push(o.get("shear_angle").unwrap_or(f64::NAN));
                rm.push(o.get("bulk_density").unwrap_or(f64::NAN));
                if a.vs.is_some() {
                    let l = replay(
                        &a.work_dir
                            .join(format!("{}-{seed}", name.replace(' ', "-"))),
                        p,
                        &rec,
                    )?;
                    al.push(l.shear_angle);
                    rl.push(l.bulk_density);
                    da.push(am.last().copied().unwrap_or(f64::NAN) - l.shear_angle);
                }
            }
            let fr = |k: &str| p.get(k).unwrap_or(f64::NAN);
            let (ma, sa) = mean_sd(&am);
            let (mr, _) = mean_sd(&rm);
            if a.vs.is_some() {
                let (la, ls) = mean_sd(&al);
                let (lr, _) = mean_sd(&rl);
                let (_, sd_diff) = mean_sd(&da);
                let se = sd_diff / (a.seeds as f64).sqrt();
                let _ = writeln!(s, "| {name} | {}, {}, {}, {} | {ma:.2} (sd {sa:.2}) | {la:.2} (sd {ls:.2}) | {:+.2} +- {se:.2} | {mr:.1} | {lr:.1} | {:+.2} % |",
                fr("mu_pp"), fr("mu_r_pp"), fr("mu_pw"), fr("mu_r_pw"), ma - la, 100.0 * (mr / lr - 1.0));
                say!(out, "{name}: shear angle mbgc {ma:.2} LIGGGHTS {la:.2} ({:+.2} +- {se:.2}); bulk density mbgc {mr:.1} LIGGGHTS {lr:.1} ({:+.2} %)", ma - la, 100.0 * (mr / lr - 1.0));
                rows.push(serde_json::json!({
                    "set": name,
                    "shear_angle_mbgc": ma,
                    "shear_angle_liggghts": la,
                    "difference_se": se,
                    "bulk_density_mbgc": mr,
                    "bulk_density_liggghts": lr,
                }));
            } else {
                let _ = writeln!(s, "| {name} | {}, {}, {}, {} | {ma:.2} (sd {sa:.2}) | not run | | {mr:.1} | not run | |", fr("mu_pp"), fr("mu_r_pp"), fr("mu_pw"), fr("mu_r_pw"));
            }
        }
    }
    // Keep what is measured even if the cost table is interrupted; with --no-cost, keep the cost
    // section of an existing report.
    if let (Some(path), false) = (&a.report, a.cost_only) {
        if a.no_cost {
            if let Some(cost) = std::fs::read_to_string(path).ok().and_then(|old| {
                old.find("\n## Cost of a shear-box run")
                    .map(|i| old[i..].to_string())
            }) {
                s.push_str(&cost);
            }
        }
        write_atomic(path, s.as_bytes())?;
    }
    if !a.no_cost {
        let _ = writeln!(s, "\n## Cost of a shear-box run (mbgc, one thread)\n");
        let _ = writeln!(s, "Regenerate this section alone with `cargo run --release -- bench shear-box --cost-only --report docs/experiments.md`.\n");
        let _ = writeln!(s, "Mid friction (mu_pp 0.5, mu_r_pp 0.3), rho_p 2600, seed 1; dt = 0.25 Rayleigh time of the smallest particle. \
            The particle count follows the PSD's width (the box is k d_max wide, the particles are counted by number), the step \
            count follows the modulus (dt ~ 1/sqrt(E)). Particles: drawn for the fill (before striking off) when not run, \
            in the box after striking off when run. Wall times are of one thread on the shared 2-core machine that wrote the file.\n");
        let _ = writeln!(s, "| k | d50 (mm) | sigma_ln | E (Pa) | particles | steps | wall time (s) | shear angle | bulk density |");
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
        for k in [6.0, 10.0] {
            for (d50, sigma) in [(5.0, 0.1), (5.0, 0.3), (11.16, 0.26)] {
                for e in [5e6, 5e7] {
                    let sb = ShearBox {
                        box_scale: k,
                        ..Default::default()
                    };
                    let p = shear_box_params(0.5, 0.3, 0.363, 0.3, d50, sigma, e);
                    let n = sb.layout(&p, 1)?.diameters.len();
                    if n > a.cost_max_particles {
                        let _ = writeln!(s, "| {k} | {d50} | {sigma} | {e:e} | {n} (drawn) | not run (over --cost-max-particles {}) | | | |", a.cost_max_particles);
                        continue;
                    }
                    eprintln!("cost: k {k} d50 {d50} sigma {sigma} E {e:e}: {n} particles drawn");
                    let o = sb.run(&p, 1, &RunOptions::default())?;
                    let _ = writeln!(
                        s,
                        "| {k} | {d50} | {sigma} | {e:e} | {} | {} | {:.1} | {:.2} | {:.1} |",
                        o.diagnostics.particles,
                        o.diagnostics.steps,
                        o.diagnostics.wall_time_s,
                        o.get("shear_angle").unwrap_or(f64::NAN),
                        o.get("bulk_density").unwrap_or(f64::NAN)
                    );
                }
            }
        }
    }
    if let Some(path) = &a.report {
        write_atomic(path, s.as_bytes())?;
        say!(out, "wrote {}", path.display());
    } else {
        say!(out, "{s}");
    }
    out.object(&serde_json::json!({ "report": a.report, "text": s, "comparison": rows }))
}
