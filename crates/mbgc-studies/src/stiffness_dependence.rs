//! Where do the shear box's responses stop depending on the particle stiffness (issue 40)? Runs
//! lines of the dimensionless stiffness K_p = E_p / (rho_p g d50) (E_w = E_p, so K_w = K_p)
//! through fixed points of the space, with and without cohesion (at a fixed cohesion group
//! Bo = ced_pp / (rho_p g d50)), several seeds each, and states for each line and response the
//! smallest K_p from which every stiffer point agrees with the stiffest within the noise. The
//! cost of a run grows about as sqrt(K_p) (the time step falls as 1/sqrt(E)), so the lines are
//! run cheapest first: a study cut short has its soft ends complete.
//!
//! `mbgc bench stiffness --report docs/stiffness.md`; every run is a row of `--table`, appended
//! as it finishes, so a killed study resumes.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context as _;

use super::rest_tables::{append, outcome_columns, read_tsv, run_queue};
use super::shear_box_check::point;
use super::shear_box_fill::mean_se;
use mbgc::dem::contact::ModelClass;
use mbgc::experiments::shear_box::{RestRule, ShearBox};
use mbgc::experiments::{Experiment, ParamSet, RunOptions};

/// Standard gravity of the groups, as the metamodels' K_p (m/s^2).
const G: f64 = 9.81;

/// `mbgc bench stiffness`.
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Args {
    /// Values of K_p = E_p / (rho_p g d50) on every line (E_w = E_p).
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ',', default_values_t = vec![1e4, 3e4, 1e5, 3e5, 1e6, 3e6]))]
    pub k: Vec<f64>,
    /// Points the lines go through (`bench shear-box-check`'s: a low, c middle, b high
    /// friction at sigma_ln 0.15; a2, c2, b2 at 0.25; or r1 to r64, points of a Sobol design
    /// over the shipped space's other parameters, see [`random_point`]); d50 8 mm, rho_p 2600.
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ',', default_values_t = ["a".to_string(), "b".into()]))]
    pub points: Vec<String>,
    /// Cohesion groups Bo = ced_pp / (rho_p g d50) of the lines (ced_pw = 0); 0: without
    /// cohesion (class hertz,mindlin,epsd2), otherwise hertz,mindlin,epsd2,sjkr. At most
    /// 0.01 K_p on every point of the line: beyond, the box stops measuring (the cohesive
    /// space's constraint ced_pp <= 0.01 E_p, examples/space_shear_box_sjkr.toml).
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ',', default_values_t = vec![0.0, 100.0]))]
    pub bond: Vec<f64>,
    /// Seeds per point of a line (1..=seeds).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 3))]
    pub seeds: u64,
    /// Runs at a time, one thread each.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 1))]
    pub jobs: usize,
    /// The runs, one row each (appended as they finish).
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value = "docs/data/stiffness/runs.tsv")
    )]
    pub table: PathBuf,
    /// Markdown report.
    #[cfg_attr(feature = "cli", arg(long))]
    pub report: Option<PathBuf>,
    /// Standard output holds one JSON object (where the report went); text goes to standard
    /// error.
    #[cfg_attr(feature = "cli", arg(long))]
    pub json: bool,
}

const HEADER: &str =
    "point\tbond\tk_p\tseed\tshear_angle\tbulk_density\tsettled\tsteps\tparticles\tseconds";
/// The points a line may go through: `bench shear-box-check`'s, which share d50 and rho_p.
const POINTS: [&str; 6] = ["a", "c", "b", "a2", "c2", "b2"];
/// The random lines: `r1` to `r{RANDOM_POINTS}`.
const RANDOM_POINTS: usize = 64;
/// Seed of the random lines' Sobol design (fixed: `r3` is the same point in every study).
const RANDOM_SEED: u64 = 40;
/// The space the random lines are drawn from: the shipped base model's.
pub(crate) const SHIPPED_SPACE: &str = include_str!("../../../examples/space_shear_box.toml");

/// Point `rN` (1-based) of the random lines: row N of a scrambled Sobol design over the free
/// parameters of the shipped space other than E_p and E_w (which the line sets), at d50 8 mm and
/// rho_p 2600 like the named points. The named points share restitution 0.5, nu_p 0.3 and the
/// wall frictions; these vary everything the shipped model does, so that the lines speak for
/// its whole space.
pub fn random_point(name: &str) -> Option<ParamSet> {
    let n: usize = name.strip_prefix('r')?.parse().ok()?;
    if !(1..=RANDOM_POINTS).contains(&n) {
        return None;
    }
    let space =
        mbgc::space::Space::from_toml_str(SHIPPED_SPACE, "examples/space_shear_box.toml").ok()?;
    let sampler = mbgc::sampling::Method::Sobol.sampler();
    let design = mbgc::sampling::extend_design(
        sampler.as_ref(),
        &mbgc::sampling::Points::new(space.dim()),
        RANDOM_POINTS,
        RANDOM_SEED,
    )
    .ok()?;
    let x = space.to_physical(design.row(n - 1));
    let pairs: Vec<(String, f64)> = space
        .names()
        .into_iter()
        .zip(x)
        .map(|(k, v)| match k {
            "rho_p" => (k.to_string(), 2600.0),
            "d50" => (k.to_string(), 8.0),
            _ => (k.to_string(), v),
        })
        .collect();
    Some(ParamSet::from_pairs(&pairs))
}

/// A named or a random point.
pub(crate) fn line_point(name: &str) -> Option<ParamSet> {
    if POINTS.contains(&name) {
        point(name)
    } else {
        random_point(name)
    }
}

/// One run of a line.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Job {
    pub(crate) point: String,
    pub(crate) bond: f64,
    pub(crate) k: f64,
    pub(crate) seed: u64,
}

impl Job {
    fn key(&self) -> (String, u64, u64, u64) {
        (
            self.point.clone(),
            self.bond.to_bits(),
            self.k.to_bits(),
            self.seed,
        )
    }

    /// The shear box and the parameters of this run.
    fn scene(&self) -> anyhow::Result<(ShearBox, ParamSet)> {
        let base = line_point(&self.point).with_context(|| {
            format!(
                "--points {}: expected a point among {} or r1 to r{RANDOM_POINTS}",
                self.point,
                POINTS.join(", ")
            )
        })?;
        let get = |n: &str| base.get(n).with_context(|| format!("point without {n}"));
        let (rho, d50_mm) = (get("rho_p")?, get("d50")?);
        let weight = rho * G * d50_mm * 1e-3;
        let e = self.k * weight;
        let mut pairs: Vec<(String, f64)> = base
            .iter()
            .map(|(n, v)| (n.to_string(), v))
            .filter(|(n, _)| n != "E_p" && n != "E_w")
            .collect();
        pairs.push(("E_p".into(), e));
        pairs.push(("E_w".into(), e));
        let class = if self.bond > 0.0 {
            pairs.push(("ced_pp".into(), self.bond * weight));
            pairs.push(("ced_pw".into(), 0.0));
            ModelClass::parse("hertz,mindlin,epsd2,sjkr")?
        } else {
            ModelClass::default()
        };
        let sb = ShearBox {
            class,
            // The rule of every shipped campaign, so that the lines speak for their models.
            rest: RestRule::Kinetic,
            ..ShearBox::default()
        };
        Ok((sb, ParamSet::from_pairs(&pairs)))
    }
}

/// A finished run.
#[derive(Clone, Debug)]
pub(crate) struct Row {
    pub(crate) job: Job,
    pub(crate) angle: f64,
    pub(crate) density: f64,
    pub(crate) settled: bool,
    pub(crate) seconds: f64,
}

/// The table's runs; a second row of a run (two studies writing one table) is left out with a
/// warning, so that it does not count as another seed.
pub(crate) fn read_rows(path: &std::path::Path) -> anyhow::Result<Vec<Row>> {
    let mut rows: Vec<Row> = Vec::new();
    for (k, c) in read_tsv(path, HEADER)?.into_iter().enumerate() {
        let num = |i: usize| -> anyhow::Result<f64> {
            c[i].parse().with_context(|| {
                format!(
                    "{}: line {}, field {}: expected a number, found {:?}",
                    path.display(),
                    k + 2,
                    i + 1,
                    c[i]
                )
            })
        };
        let job = Job {
            point: c[0].clone(),
            bond: num(1)?,
            k: num(2)?,
            seed: num(3)? as u64,
        };
        if rows.iter().any(|r| r.job == job) {
            eprintln!(
                "warning: {}: line {}: a second row of {job:?}; left out",
                path.display(),
                k + 2
            );
            continue;
        }
        rows.push(Row {
            job,
            angle: num(4)?,
            density: num(5)?,
            settled: c[6] == "1",
            seconds: num(9)?,
        });
    }
    Ok(rows)
}

/// Every run of the study, cheapest first: by K_p, then seed, then line.
fn jobs(a: &Args) -> Vec<Job> {
    let mut ks = a.k.clone();
    ks.sort_by(f64::total_cmp);
    ks.dedup();
    let mut bonds = a.bond.clone();
    bonds.sort_by(f64::total_cmp);
    bonds.dedup();
    let mut points: Vec<String> = Vec::new();
    for p in &a.points {
        if !points.contains(p) {
            points.push(p.clone());
        }
    }
    let mut v: Vec<Job> = Vec::new();
    for &k in &ks {
        for seed in 1..=a.seeds {
            for &bond in &bonds {
                for p in &points {
                    v.push(Job {
                        point: p.clone(),
                        bond,
                        k,
                        seed,
                    });
                }
            }
        }
    }
    v
}

/// Runs the study.
pub fn run(a: &Args) -> anyhow::Result<()> {
    if let Some(k) = a.k.iter().find(|k| !(k.is_finite() && **k > 0.0)) {
        anyhow::bail!("--k {k}: expected positive finite values of K_p");
    }
    if let Some(b) = a.bond.iter().find(|b| !(b.is_finite() && **b >= 0.0)) {
        anyhow::bail!("--bond {b}: expected cohesion groups of at least 0");
    }
    let k_min = a.k.iter().copied().fold(f64::INFINITY, f64::min);
    if let Some(b) = a.bond.iter().find(|b| **b > 0.01 * k_min) {
        anyhow::bail!(
            "--bond {b}: above 0.01 K_p at K_p = {k_min:e}, where the shear box stops measuring \
             (no flank, or a fill that never comes to rest; ced_pp <= 0.01 E_p in \
             examples/space_shear_box_sjkr.toml); expected at most {}",
            0.01 * k_min
        );
    }
    if a.seeds == 0 || a.jobs == 0 {
        anyhow::bail!("--seeds and --jobs: expected at least 1");
    }
    let todo: Vec<Job> = {
        let done: Vec<_> = read_rows(&a.table)?.iter().map(|r| r.job.key()).collect();
        jobs(a)
            .into_iter()
            .filter(|j| !done.contains(&j.key()))
            .collect()
    };
    // Every scene is built before anything runs: a bad point fails at once.
    for j in &todo {
        j.scene()?;
    }
    eprintln!("stiffness: {} runs to do, {} at a time", todo.len(), a.jobs);
    let failures = run_queue(
        a.jobs,
        todo,
        |_| String::new(),
        |j, write| {
            j.scene().and_then(|(sb, p)| {
                let o = sb
                    .run(&p, j.seed, &RunOptions::default())
                    .with_context(|| format!("{j:?}"))?;
                let line = format!(
                    "{}\t{}\t{}\t{}\t{}",
                    j.point,
                    j.bond,
                    j.k,
                    j.seed,
                    outcome_columns(&o)
                );
                let _g = write.lock().map_err(|_| anyhow::anyhow!("poisoned"))?;
                eprintln!("{line}");
                append(&a.table, HEADER, &[line])
            })
        },
    );
    let rows = read_rows(&a.table)?;
    let text = report(a, &rows);
    crate::emit_report(
        a.json,
        a.report.as_deref(),
        &text,
        serde_json::json!({ "runs": rows.len() }),
    )?;
    if !failures.is_empty() {
        anyhow::bail!("{} runs failed (listed above)", failures.len());
    }
    Ok(())
}

/// Per K_p of one line: (K_p, (mean, se) of the angle, of the density, mean seconds, runs,
/// unsettled runs).
type LinePoint = (f64, (f64, f64), (f64, f64), f64, usize, usize);

fn line_points(rows: &[&Row]) -> Vec<LinePoint> {
    let mut by: BTreeMap<u64, Vec<&Row>> = BTreeMap::new();
    for r in rows {
        by.entry(r.job.k.to_bits()).or_default().push(r);
    }
    let mut v: Vec<LinePoint> = by
        .into_iter()
        .map(|(k, rs)| {
            let of = |f: fn(&Row) -> f64| {
                let x: Vec<f64> = rs.iter().map(|r| f(r)).filter(|x| x.is_finite()).collect();
                if x.len() < 2 {
                    (x.first().copied().unwrap_or(f64::NAN), f64::NAN)
                } else {
                    mean_se(&x)
                }
            };
            (
                f64::from_bits(k),
                of(|r| r.angle),
                of(|r| r.density),
                rs.iter().map(|r| r.seconds).sum::<f64>() / rs.len() as f64,
                rs.len(),
                rs.iter().filter(|r| !r.settled).count(),
            )
        })
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

/// The two-sided 95 % quantile of Student's t with `df` degrees of freedom (tabulated; the
/// normal's 1.96 beyond 30).
fn t95(df: usize) -> f64 {
    const T: [f64; 10] = [12.71, 4.30, 3.18, 2.78, 2.57, 2.45, 2.36, 2.31, 2.26, 2.23];
    match df {
        0 => f64::INFINITY,
        1..=10 => T[df - 1],
        11..=20 => 2.09,
        21..=30 => 2.04,
        _ => 1.96,
    }
}

/// Where a line stops changing, or why that cannot be said.
#[derive(Debug, PartialEq)]
enum Plateau {
    /// Every point from this K_p on agrees with the stiffest (no difference detected).
    From(f64),
    /// The stiffest two points differ beyond the noise.
    StillMoving,
    /// Fewer than two points, or fewer than two seeds at one of them.
    TooFewRuns,
}

/// The smallest K_p from which no point differs from the stiffest detectably: the difference of
/// their seed means within t95 times the combined standard error (n seeds each). With 3 seeds
/// the test detects only shifts above about 3.5 standard errors of one point, so agreement here
/// is the absence of a detected change, not proof of none.
fn plateau(pts: &[(f64, (f64, f64), usize)]) -> Plateau {
    let Some(&(_, (top, se_top), n_top)) = pts.last() else {
        return Plateau::TooFewRuns;
    };
    if pts.len() < 2
        || pts
            .iter()
            .any(|p| p.2 < 2 || !p.1 .1.is_finite() || !p.1 .0.is_finite())
    {
        return Plateau::TooFewRuns;
    }
    let mut from = None;
    for &(k, (m, se), n) in pts.iter().rev().skip(1) {
        let tol = t95(n + n_top - 2) * (se * se + se_top * se_top).sqrt();
        if (m - top).abs() <= tol {
            from = Some(k);
        } else {
            break;
        }
    }
    from.map_or(Plateau::StillMoving, Plateau::From)
}

fn report(a: &Args, rows: &[Row]) -> String {
    let mut w = String::new();
    let _ = writeln!(
        w,
        "# How the shear box depends on the particle stiffness\n\nRegenerate with `cargo run \
         --release -- bench stiffness --report docs/stiffness.md` (runs in `{}`, one row per \
         run, appended as runs finish).\n",
        a.table.display()
    );
    let _ = writeln!(
        w,
        "Without cohesion the shear box sees E_p, rho_p and d50 only through K_p = E_p / (rho_p \
         g d50) (and K_w; here E_w = E_p, so K_w = K_p): every time of its schedule is a \
         multiple of sqrt(d_max / g). Each line below holds a point of the space (d50 8 mm, rho_p \
         2600 kg/m3, sigma_ln as named) and varies E_p = E_w. The cohesive lines hold Bo = \
         ced_pp / (rho_p g d50) fixed (ced_pw = 0). Seed means with standard errors; the kinetic \
         rest rule of the shipped campaigns.\n"
    );
    let mut lines: Vec<(String, u64)> = rows
        .iter()
        .map(|r| (r.job.point.clone(), r.job.bond.to_bits()))
        .collect();
    lines.sort();
    lines.dedup();
    let mut summary = Vec::new();
    for (pt, bond_bits) in lines {
        let bond = f64::from_bits(bond_bits);
        let rs: Vec<&Row> = rows
            .iter()
            .filter(|r| r.job.point == pt && r.job.bond.to_bits() == bond_bits)
            .collect();
        let pts = line_points(&rs);
        let what = line_point(&pt).map_or(String::new(), |p| {
            let g = |k: &str| p.get(k).unwrap_or(f64::NAN);
            format!(
                "mu_pp {}, mu_r_pp {}, sigma_ln {}",
                g("mu_pp"),
                g("mu_r_pp"),
                g("sigma_ln")
            )
        });
        let _ = writeln!(
            w,
            "## Point {pt} ({what}), {}\n\n| K_p | E_p (Pa) | runs | angle (deg) | bulk density \
             (kg/m3) | seconds per run |\n|---|---|---|---|---|---|",
            if bond > 0.0 {
                format!("cohesive, Bo = {bond}")
            } else {
                "without cohesion".into()
            }
        );
        let weight = 2600.0 * G * 8e-3;
        for (k, (am, ase), (dm, dse), secs, n, unsettled) in &pts {
            let _ = writeln!(
                w,
                "| {k:.0e} | {:.3e} | {n}{} | {am:.2} +- {ase:.2} | {dm:.1} +- {dse:.1} | {secs:.0} |",
                k * weight,
                if *unsettled > 0 {
                    format!(" ({unsettled} not settled)")
                } else {
                    String::new()
                },
            );
        }
        let angle: Vec<(f64, (f64, f64), usize)> = pts.iter().map(|p| (p.0, p.1, p.4)).collect();
        let density: Vec<(f64, (f64, f64), usize)> = pts.iter().map(|p| (p.0, p.2, p.4)).collect();
        let top = pts.last().map_or(f64::NAN, |p| p.0);
        let (pa, pd) = (plateau(&angle), plateau(&density));
        let _ = writeln!(
            w,
            "\nNo difference from the stiffest point (K_p {top:.0e}) detected (t test, 95 %): {} \
             (angle), {} (density).\n",
            show(&pa),
            show(&pd)
        );
        summary.push((pt, bond, pa, pd, top));
    }
    if !summary.is_empty() {
        let _ = writeln!(
            w,
            "## Summary\n\n| line | stiffest K_p run | angle stops changing from K_p | density \
             stops changing from K_p |\n|---|---|---|---|"
        );
        for (pt, bond, a, d, top) in summary {
            let _ = writeln!(
                w,
                "| {pt}, Bo {bond} | {top:.0e} | {} | {} |",
                show(&a),
                show(&d)
            );
        }
        let _ = writeln!(
            w,
            "\nWith 3 seeds a point's mean is known to about its standard error, and the test \
             detects only shifts above about 3.5 of them: \"from K_p\" is where no change was \
             detected, not a proof of none. Within the grid, the rigid limit begins at or below \
             the K_p named (the next softer point still differed)."
        );
    }
    w
}

fn show(p: &Plateau) -> String {
    match p {
        Plateau::From(k) => format!("from K_p {k:.0e} on"),
        Plateau::StillMoving => "the stiffest two points still differ".into(),
        Plateau::TooFewRuns => "too few runs to say (two points and two seeds each needed)".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_runs_stiffness_is_its_k_times_the_weight_group() {
        let j = Job {
            point: "a".into(),
            bond: 500.0,
            k: 1e5,
            seed: 1,
        };
        let (sb, p) = j.scene().unwrap();
        let weight = 2600.0 * G * 8e-3;
        let k = p.get("E_p").unwrap() / weight;
        assert!((k / 1e5 - 1.0).abs() < 1e-12, "K_p {k}");
        assert_eq!(p.get("E_w"), p.get("E_p"));
        assert!((p.get("ced_pp").unwrap() / weight / 500.0 - 1.0).abs() < 1e-12);
        assert!(sb.class.label().contains("sjkr"));
        let plain = Job { bond: 0.0, ..j };
        let (sb, p) = plain.scene().unwrap();
        assert!(p.get("ced_pp").is_none());
        assert!(!sb.class.label().contains("sjkr"));
    }

    #[test]
    fn random_lines_are_fixed_points_of_the_shipped_space() {
        let space =
            mbgc::space::Space::from_toml_str(SHIPPED_SPACE, "space_shear_box.toml").unwrap();
        let (r1, r2) = (random_point("r1").unwrap(), random_point("r2").unwrap());
        assert_eq!(
            random_point("r1"),
            Some(r1.clone()),
            "the same point every time"
        );
        assert_ne!(r1.get("mu_pp"), r2.get("mu_pp"));
        for p in space.parameters.iter().filter(|p| p.fixed.is_none()) {
            let v = r1.get(&p.name).unwrap();
            assert!(p.contains(v), "{} = {v}", p.name);
        }
        assert_eq!(r1.get("d50"), Some(8.0));
        assert!(random_point("r0").is_none() && random_point("r65").is_none());
        assert!(random_point("x1").is_none());
    }

    #[test]
    fn the_plateau_starts_where_the_points_join_the_stiffest() {
        let pts = [
            (1e4, (30.0, 0.2), 3),
            (1e5, (31.0, 0.2), 3),
            (1e6, (31.9, 0.2), 3),
            (1e7, (32.0, 0.2), 3),
        ];
        assert_eq!(plateau(&pts), Plateau::From(1e6));
        let moving = [(1e4, (30.0, 0.1), 3), (1e5, (31.0, 0.1), 3)];
        assert_eq!(plateau(&moving), Plateau::StillMoving);
        let one_seed = [(1e4, (30.0, f64::NAN), 1), (1e5, (30.0, f64::NAN), 1)];
        assert_eq!(plateau(&one_seed), Plateau::TooFewRuns);
    }
}
