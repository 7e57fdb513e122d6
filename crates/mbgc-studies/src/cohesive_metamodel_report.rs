//! The shipped cohesive metamodel's report (issue 35): `mbgc bench cohesive-metamodel --report
//! docs/metamodel_sjkr.md` regenerates it from the shipped files alone: what it extends, its
//! space and the limit where the shear box stops measuring (failure rates from the campaign
//! table), its groups, the cost of its new runs against the budget, and its validation on both
//! faces of the space (cohesion off and on), each against its own replicate noise, beside the
//! base model on the same rows.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;

use mbgc::metamodel::Metamodel;
use mbgc::space::Space;
use mbgc::train::{TrainPaths, TrainRecord};

use crate::metamodel_report::{equation_section, parameter_table};
use crate::noise_floor::{replicate_noise, NoiseFloor};

/// The issue's budget of new runs, core-hours.
const BUDGET_CORE_H: f64 = 14.0;
/// The acceptance: validation RMSE within this factor of the replicate noise.
const NOISE_FACTOR: f64 = 1.5;
/// Bins of ced_pp / E_p for the failure table.
const RATIO_BINS: [f64; 7] = [0.0, 0.002, 0.005, 0.01, 0.02, 0.04, f64::INFINITY];

/// `mbgc bench cohesive-metamodel`.
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Args {
    /// Directory holding sampling/, training_data/ and models/ (as `mbgc train --out-dir`).
    #[cfg_attr(feature = "cli", arg(long, default_value = "."))]
    pub dir: PathBuf,
    /// Name of the trained cohesive model (as `mbgc train --name`).
    #[cfg_attr(feature = "cli", arg(long, default_value = "shear_box_sjkr"))]
    pub name: String,
    #[cfg_attr(feature = "cli", arg(long, default_value = "docs/metamodel_sjkr.md"))]
    pub report: PathBuf,
    /// Standard output holds one JSON object (where the report went); text goes to standard
    /// error.
    #[cfg_attr(feature = "cli", arg(long))]
    pub json: bool,
}

/// One run of a campaign table, as the report needs it.
struct Run {
    copied: bool,
    done: bool,
    settled: bool,
    wall_s: f64,
    /// Inputs by name (every numeric column before the responses).
    values: Vec<(String, f64)>,
    angle: f64,
    bulk: f64,
}

impl Run {
    fn get(&self, name: &str) -> f64 {
        self.values
            .iter()
            .find(|(n, _)| n == name)
            .map_or(f64::NAN, |(_, v)| *v)
    }

    fn cohesive(&self) -> bool {
        self.get("ced_pp") > 0.0 || self.get("ced_pw") > 0.0
    }

    fn measured(&self) -> bool {
        self.done && self.settled && self.angle.is_finite() && self.bulk.is_finite()
    }
}

fn read_runs(path: &Path) -> anyhow::Result<Vec<Run>> {
    let mut r = csv::Reader::from_path(path).with_context(|| path.display().to_string())?;
    let header = r.headers()?.clone();
    let col = |name: &str| {
        header
            .iter()
            .position(|c| c == name)
            .with_context(|| format!("{}: no column {name}", path.display()))
    };
    let (first, angle, bulk) = (
        col("model_class")? + 1,
        col("shear_angle")?,
        col("bulk_density")?,
    );
    let (status, settled, wall, warnings) = (
        col("status")?,
        col("settled")?,
        col("wall_time_s")?,
        col("warnings")?,
    );
    let num = |rec: &csv::StringRecord, i: usize| rec[i].parse().unwrap_or(f64::NAN);
    let mut out = Vec::new();
    for rec in r.records() {
        let rec = rec.with_context(|| path.display().to_string())?;
        out.push(Run {
            copied: rec[warnings].contains("copied from ") && rec[warnings].contains(", run by "),
            done: &rec[status] == "done",
            settled: &rec[settled] == "true",
            wall_s: num(&rec, wall),
            values: (first..angle)
                .map(|i| (header[i].to_string(), num(&rec, i)))
                .collect(),
            angle: num(&rec, angle),
            bulk: num(&rec, bulk),
        });
    }
    Ok(out)
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let dir = if a.dir == Path::new(".") {
        PathBuf::new()
    } else {
        a.dir.clone()
    };
    let paths = TrainPaths::new(&dir, &a.name);
    mbgc::outputs::refuse_overwriting_inputs(
        "--report",
        &a.report,
        &[
            ("the model", &paths.model),
            ("the training table", &paths.table),
        ],
    )?;
    let record: TrainRecord = serde_json::from_str(
        &std::fs::read_to_string(&paths.record)
            .with_context(|| paths.record.display().to_string())?,
    )
    .with_context(|| paths.record.display().to_string())?;
    let model = Metamodel::load(&paths.model)?;
    let space = Space::from_file(&dir.join(&record.space))?;
    let train = read_runs(&paths.table)?;
    let valid = if paths.validation_table.exists() {
        read_runs(&paths.validation_table)?
    } else {
        Vec::new()
    };
    let replicate_table = paths
        .validation_table
        .with_file_name(format!("{}_replicates.csv", a.name));
    let replicates = if replicate_table.exists() {
        read_runs(&replicate_table)?
    } else {
        Vec::new()
    };
    let base = record.extends.as_ref().map(|e| e.from.clone());
    let correction = record.extends.as_ref().is_some_and(|e| e.correction);

    let mut w = String::new();
    let _ = writeln!(
        w,
        "# The shipped cohesive metamodel: `{}`\n\nRegenerated by `cargo run --release -- bench \
         cohesive-metamodel --report {}` from the shipped files. Made by\n\n```\nmbgc train \
         --space {} --experiment {} --name {}{} --n {} --validation {} --seed {} --population \
         {} --generations {} --parsimony {} --max-length {} --restarts {} --select {}\n```\n\n\
         (mbgc {}, model class `{}`, box scale k = {}).",
        paths.model.display(),
        a.report.display(),
        record.space,
        record.experiment,
        a.name,
        base.as_ref().map_or(String::new(), |b| format!(
            " --extends {b}{}",
            if correction { " --correction" } else { "" }
        )),
        record.n,
        record.validation,
        record.seed,
        model.settings.population,
        model.settings.generations,
        model.settings.parsimony,
        model.settings.max_length,
        model.settings.restarts,
        model.settings.selection.flag(),
        record.mbgc_version,
        record.model_class.as_deref().unwrap_or("-"),
        record.box_scale.map_or("-".into(), |k| k.to_string()),
    );
    if let Some(b) = &base {
        let _ = writeln!(
            w,
            "\nIt extends `{b}`: that model's runs are its rows at ced_pp = ced_pw = 0, copied, \
             not rerun; only the cohesive rows ran.{}",
            if correction {
                " Its equations are that model's plus a fitted correction (the sizes below \
                 count both)."
            } else {
                ""
            }
        );
    }
    space_section(&mut w, &space, &record, &train);
    cost_section(
        &mut w,
        &paths,
        &train,
        &valid,
        &replicate_table,
        &replicates,
    );
    validation_section(
        &mut w,
        &dir,
        &paths,
        &model,
        &space,
        &valid,
        base.as_deref(),
    )?;
    equation_section(&mut w, &model);

    crate::write_report(
        a.json,
        &a.report,
        &w,
        serde_json::json!({ "model": a.name }),
    )
}

fn space_section(w: &mut String, space: &Space, record: &TrainRecord, train: &[Run]) {
    let _ = writeln!(
        w,
        "\n## The space\n\n`{}` (its comments give the reasons for each range). The fit works \
         in the groups {}: E_p, E_w, rho_p, d50, ced_pp and ced_pw act only through them, so \
         the campaign holds rho_p and d50 at one value. A group that reaches zero (a cohesion \
         switched off) is fitted linearly, the stiffnesses in their logarithm.\n",
        record.space,
        record.groups.join("; ")
    );
    parameter_table(w, space);
    if space.constraints.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "\nThe space is limited by {}: the design rows beyond are not run (those run before the \
         limit was set are not fitted), and a calibration on the model is kept inside. Why, from \
         the campaign's own new runs: the share without a usable shear angle (failed, no flank, \
         or outflow or fill not at rest) by ced_pp / E_p (= C_pp / K_p).\n\n\
         | ced_pp / E_p | new runs | without a usable angle | share |\n|---|---|---|---|",
        space
            .constraints
            .iter()
            .map(|c| format!("`{}`", c.text))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for b in RATIO_BINS.windows(2) {
        let runs: Vec<&Run> = train
            .iter()
            .filter(|r| !r.copied && r.cohesive())
            .filter(|r| {
                let q = r.get("ced_pp") / r.get("E_p");
                q >= b[0] && q < b[1]
            })
            .collect();
        let bad = runs
            .iter()
            .filter(|r| !(r.done && r.settled && r.angle.is_finite()))
            .count();
        let _ = writeln!(
            w,
            "| {} - {} | {} | {} | {} |",
            b[0],
            if b[1].is_finite() {
                b[1].to_string()
            } else {
                "max".into()
            },
            runs.len(),
            bad,
            if runs.is_empty() {
                "-".into()
            } else {
                format!("{:.0} %", 100.0 * bad as f64 / runs.len() as f64)
            }
        );
    }
}

fn cost_section(
    w: &mut String,
    paths: &TrainPaths,
    train: &[Run],
    valid: &[Run],
    replicate_table: &Path,
    replicates: &[Run],
) {
    let _ = writeln!(
        w,
        "\n## Cost\n\nWall time of each new run as the campaign table records it (one run per \
         core, two at a time on a 2-core machine, other work beside them: an upper bound of the \
         cost alone). Copied rows cost nothing here.\n\n\
         | table | copied | new runs | failed | without a usable angle | core-hours | median s | \
         max s |\n|---|---|---|---|---|---|---|---|"
    );
    let mut total = 0.0;
    for (path, runs) in [
        (paths.table.as_path(), train),
        (paths.validation_table.as_path(), valid),
        (replicate_table, replicates),
    ] {
        if runs.is_empty() {
            continue;
        }
        let new: Vec<&Run> = runs.iter().filter(|r| !r.copied).collect();
        let wall: Vec<f64> = new
            .iter()
            .map(|r| r.wall_s)
            .filter(|v| v.is_finite())
            .collect();
        let hours = wall.iter().sum::<f64>() / 3600.0;
        total += hours;
        let _ = writeln!(
            w,
            "| `{}` | {} | {} | {} | {} | {:.2} | {:.0} | {:.0} |",
            path.display(),
            runs.len() - new.len(),
            new.len(),
            new.iter().filter(|r| !r.done).count(),
            new.iter()
                .filter(|r| !(r.done && r.settled && r.angle.is_finite()))
                .count(),
            hours,
            mbgc::numeric::quantile(&wall, 0.5),
            mbgc::numeric::quantile(&wall, 1.0),
        );
    }
    let _ = writeln!(
        w,
        "\nTogether {total:.2} core-hours of new runs, of the budget of {BUDGET_CORE_H} ({:.0} %).",
        100.0 * total / BUDGET_CORE_H
    );
}

/// RMSE of `model`'s response `k` over `runs` (NaN without rows), and the rows.
fn rmse(model: &Metamodel, k: usize, runs: &[&Run]) -> (f64, usize) {
    let names = model.input_names();
    let mut s = 0.0;
    let mut n = 0;
    for r in runs {
        let x: Vec<f64> = names.iter().map(|nm| r.get(nm)).collect();
        let y = if model.responses[k].name == "shear_angle" {
            r.angle
        } else {
            r.bulk
        };
        let p = model.predict_point(&model.responses[k], &x);
        if p.is_finite() {
            s += (p - y).powi(2);
            n += 1;
        }
    }
    ((s / n.max(1) as f64).sqrt(), n)
}

fn validation_section(
    w: &mut String,
    dir: &Path,
    paths: &TrainPaths,
    model: &Metamodel,
    space: &Space,
    valid: &[Run],
    base: Option<&str>,
) -> anyhow::Result<()> {
    let _ = writeln!(
        w,
        "\n## Validation\n\nOn `{}`, a uniform random design never trained on, its runs inside \
         the space's limit that came to rest with both responses. Every row is one run, so even \
         an exact model shows the seed-to-seed spread of single runs as its RMSE; the goal is an \
         RMSE within {NOISE_FACTOR}x of it. The spread differs between the faces of the space, \
         so each is judged by its own: validation rows rerun with another seed, sd = rms \
         difference / sqrt 2.",
        paths.validation_table.display()
    );
    if valid.is_empty() {
        let _ = writeln!(w, "\nThe validation runs have not been made yet.");
        return Ok(());
    }
    let inside = |r: &&Run| {
        let x: Vec<f64> = space.names().iter().map(|n| r.get(n)).collect();
        r.measured() && space.violated(&x).is_none()
    };
    let rows: Vec<&Run> = valid.iter().filter(inside).collect();
    let face: Vec<&Run> = rows.iter().copied().filter(|r| !r.cohesive()).collect();
    let cohesive: Vec<&Run> = rows.iter().copied().filter(|r| r.cohesive()).collect();
    let gripping: Vec<&Run> = cohesive
        .iter()
        .copied()
        .filter(|r| r.get("mu_pw") >= SLIDING_MU_PW)
        .collect();
    let base_noise = match base {
        Some(b) => {
            let root = Path::new(b)
                .parent()
                .and_then(Path::parent)
                .unwrap_or(Path::new(""));
            let stem = Path::new(b)
                .file_stem()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_default();
            let bp = TrainPaths::new(&dir.join(root), &stem);
            replicate_noise(
                &bp.validation_table,
                &bp.validation_table
                    .with_file_name(format!("{stem}_replicates.csv")),
            )?
            .map(|n| (n, bp))
        }
        None => None,
    };
    let own_noise = replicate_noise(
        &paths.validation_table,
        &paths
            .validation_table
            .with_file_name(format!("{}_replicates.csv", paths_name(paths))),
    )?;
    let base_model = match &base_noise {
        Some((_, bp)) if bp.model.exists() => Some(Metamodel::load(&bp.model)?),
        _ => None,
    };
    let noise_line = |n: &Option<NoiseFloor>, what: &str| match n {
        Some(n) => format!(
            "- {what}: {:.2} deg and {:.3} % of the bulk density ({} points rerun);",
            n.angle_sd,
            100.0 * n.bulk_rel_sd,
            n.points
        ),
        None => format!("- {what}: not measured yet;"),
    };
    let _ = writeln!(
        w,
        "\n{}\n{}",
        noise_line(
            &base_noise.as_ref().map(|(n, _)| n.clone()),
            "cohesion off (the extended model's replicates)"
        ),
        noise_line(&own_noise, "cohesive rows (this model's replicates)")
    );
    let _ = writeln!(
        w,
        "\n| rows | response | n | RMSE | noise sd | RMSE / noise | base model's RMSE |\n\
         |---|---|---|---|---|---|---|"
    );
    let mean_bulk = |runs: &[&Run]| runs.iter().map(|r| r.bulk).sum::<f64>() / runs.len() as f64;
    for (label, runs, noise) in [
        (
            "cohesion off",
            &face,
            base_noise.as_ref().map(|(n, _)| n.clone()),
        ),
        ("cohesive", &cohesive, own_noise.clone()),
        (GRIPPING, &gripping, own_noise.clone()),
    ] {
        if runs.is_empty() {
            continue;
        }
        for (k, r) in model.responses.iter().enumerate() {
            let (e, n) = rmse(model, k, runs);
            let sd = noise.as_ref().map(|nf| {
                if r.name == "shear_angle" {
                    nf.angle_sd
                } else {
                    nf.bulk_rel_sd * mean_bulk(runs)
                }
            });
            let base_rmse = base_model
                .as_ref()
                .filter(|_| label == "cohesion off")
                .and_then(|b| b.responses.iter().position(|br| br.name == r.name))
                .map(|bk| rmse(base_model.as_ref().expect("filtered"), bk, runs).0);
            let _ = writeln!(
                w,
                "| {label} | {} | {n} | {e:.3} | {} | {} | {} |",
                r.name,
                sd.map_or("-".into(), |s| format!("{s:.3}")),
                sd.map_or("-".into(), |s| format!("{:.2}", e / s)),
                base_rmse.map_or("-".into(), |b| format!("{b:.3}")),
            );
        }
    }
    let _ = writeln!(
        w,
        "\nThe bulk density's noise is its relative sd times the rows' mean density. Rows left \
         out: {} outside the limit or not at rest or without a value, of {}.",
        valid.len() - rows.len(),
        valid.len()
    );
    let sliding: Vec<&Run> = cohesive
        .iter()
        .copied()
        .filter(|r| r.get("mu_pw") < SLIDING_MU_PW)
        .collect();
    if let (false, Some(k)) = (
        sliding.is_empty(),
        model.responses.iter().position(|r| r.name == "shear_angle"),
    ) {
        let _ = writeln!(
            w,
            "\nWhere the angle error comes from: the cohesive rows with a wall friction below \
             {SLIDING_MU_PW}. On a nearly frictionless floor a cohesive bed can slide out of the \
             box as a block, leaving a low flank, or be held by the walls' cohesion; which one \
             happens turns on the balance of the particle and wall cohesions, a switch the \
             equations smooth over:\n\n\
             | mu_pw | ced_pp / E_p | ced_pw / ced_pp | angle measured | predicted |\n\
             |---|---|---|---|---|"
        );
        for r in &sliding {
            let x: Vec<f64> = model.input_names().iter().map(|n| r.get(n)).collect();
            let _ = writeln!(
                w,
                "| {:.3} | {:.4} | {:.2} | {:.1} | {:.1} |",
                r.get("mu_pw"),
                r.get("ced_pp") / r.get("E_p"),
                r.get("ced_pw") / r.get("ced_pp"),
                r.angle,
                model.predict_point(&model.responses[k], &x)
            );
        }
    }
    Ok(())
}

/// Wall friction below which a cohesive bed may slide out of the shear box as a block.
const SLIDING_MU_PW: f64 = 0.05;

/// The rows judged without the sliding regime.
const GRIPPING: &str = "cohesive, mu_pw >= 0.05";

/// The model's name from its paths (`training_data/<name>_validation.csv`).
fn paths_name(paths: &TrainPaths) -> String {
    paths
        .model
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default()
}
