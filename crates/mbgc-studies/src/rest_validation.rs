//! Does the candidate rest rule keep the shipped model's accuracy at a lower cost (issue 38)?
//! Reruns every finished row of a campaign's validation table with its own seed under
//! [`RestRule::CANDIDATE`], then compares, on the same rows, the cost (core-hours and steps)
//! against what the table recorded under the kinetic rule, and the shipped model's validation
//! RMSE on the rerun responses against its RMSE on the recorded ones. The kinetic rule repeats a
//! recorded run bit for bit (`docs/rest_detection.md`), so every difference is the rule's.
//!
//! `mbgc bench rest-validation --threads 2 --report docs/rest_validation.md`; finished runs are
//! appended to `--out` as they come, so a killed study resumes.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use anyhow::Context as _;

use super::noise_floor::replicate_noise;
use super::rest_tables::{append, design_box, design_rows, read_tsv};
use mbgc::experiments::shear_box::RestRule;
use mbgc::experiments::{Experiment, RunOptions};
use mbgc::metamodel::{Metamodel, Metrics};

/// `mbgc bench rest-validation`.
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Args {
    /// The validation table rerun (inputs, seeds, responses and costs recorded under the
    /// kinetic rule).
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value = "training_data/shear_box_validation.csv")
    )]
    pub design: PathBuf,
    /// The replicate table of the same campaign, for the noise the shifts are judged by.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value = "training_data/shear_box_replicates.csv")
    )]
    pub replicates: PathBuf,
    /// The model scored on the recorded and on the rerun responses.
    #[cfg_attr(feature = "cli", arg(long, default_value = "models/shear_box.json"))]
    pub model: PathBuf,
    /// The reruns, one row per finished run (appended as runs finish).
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value = "docs/data/rest_detection/validation.tsv")
    )]
    pub out: PathBuf,
    /// Runs at once, one thread each (as a campaign's `--threads`).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 1))]
    pub threads: usize,
    /// Markdown report.
    #[cfg_attr(feature = "cli", arg(long))]
    pub report: Option<PathBuf>,
    /// Standard output holds one JSON object (where the report went); text goes to standard
    /// error.
    #[cfg_attr(feature = "cli", arg(long))]
    pub json: bool,
}

const HEADER: &str = "row\tseed\tshear_angle\tbulk_density\tsettled\tsteps\tseconds";

/// What a validation row recorded, or what its rerun measured.
#[derive(Clone, Copy, Debug)]
struct Outcome {
    angle: f64,
    density: f64,
    steps: f64,
    seconds: f64,
    /// Whether the run came to rest (a rerun's own record; recorded rows are done runs).
    settled: bool,
}

/// The recorded outcome and the model's inputs of every done row of the design table.
fn recorded(path: &Path, inputs: &[String]) -> anyhow::Result<BTreeMap<u64, (Outcome, Vec<f64>)>> {
    let mut r = csv::Reader::from_path(path).with_context(|| path.display().to_string())?;
    let header = r.headers()?.clone();
    let col = |n: &str| {
        header
            .iter()
            .position(|c| c == n)
            .with_context(|| format!("{}: no column {n}", path.display()))
    };
    let (c_row, c_status) = (col("row")?, col("status")?);
    let (c_a, c_b, c_steps, c_wall) = (
        col("shear_angle")?,
        col("bulk_density")?,
        col("steps")?,
        col("wall_time_s")?,
    );
    let c_in: Vec<usize> = inputs
        .iter()
        .map(|n| col(n))
        .collect::<anyhow::Result<_>>()?;
    let mut out = BTreeMap::new();
    for (k, rec) in r.records().enumerate() {
        let rec = rec.with_context(|| format!("{}: record {}", path.display(), k + 1))?;
        if &rec[c_status] != "done" {
            continue;
        }
        let num = |c: usize| -> anyhow::Result<f64> {
            rec[c].parse().with_context(|| {
                format!(
                    "{}: record {}, column {}: expected a number, found {:?}",
                    path.display(),
                    k + 1,
                    &header[c],
                    &rec[c]
                )
            })
        };
        let row: u64 = num(c_row)? as u64;
        let o = Outcome {
            angle: num(c_a)?,
            density: num(c_b)?,
            steps: num(c_steps)?,
            seconds: num(c_wall)?,
            settled: true,
        };
        let x = c_in
            .iter()
            .map(|&c| num(c))
            .collect::<anyhow::Result<_>>()?;
        out.insert(row, (o, x));
    }
    Ok(out)
}

/// The reruns written so far, by row; `seeds`: the design's seed of each row, which a rerun must
/// have (a rerun of another table's row is refused, naming the line).
fn reruns(path: &Path, seeds: &BTreeMap<u64, u64>) -> anyhow::Result<BTreeMap<u64, Outcome>> {
    let mut out = BTreeMap::new();
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
        let (row, seed) = (num(0)? as u64, c[1].parse::<u64>().ok());
        if seeds.get(&row) != seed.as_ref() {
            anyhow::bail!(
                "{}: line {}: row {row} with seed {}, but the design's row {row} has seed {}: \
                 the reruns of another table? Give another --out",
                path.display(),
                k + 2,
                c[1],
                seeds
                    .get(&row)
                    .map_or("none (no such done row)".into(), |s| s.to_string())
            );
        }
        let o = Outcome {
            angle: num(2)?,
            density: num(3)?,
            steps: num(5)?,
            seconds: num(6)?,
            settled: c[4] == "1",
        };
        if out.insert(row, o).is_some() {
            anyhow::bail!(
                "{}: line {}: row {row} a second time (two studies writing one file?)",
                path.display(),
                k + 2
            );
        }
    }
    Ok(out)
}

/// Ties `--out` to its design: a sidecar `<out>.design` holds the design's path, written with
/// the first rerun; another design with the same `--out` is refused.
fn check_out_design(args: &Args) -> anyhow::Result<()> {
    let side = PathBuf::from(format!("{}.design", args.out.display()));
    let design = args.design.display().to_string();
    match std::fs::read_to_string(&side) {
        Ok(t) if t.trim() == design => Ok(()),
        Ok(t) => anyhow::bail!(
            "--out {}: it holds reruns of {} ({}), not of --design {design}; give another --out",
            args.out.display(),
            t.trim(),
            side.display()
        ),
        Err(_) => {
            if let Some(d) = side.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(d).with_context(|| d.display().to_string())?;
            }
            std::fs::write(&side, format!("{design}\n")).with_context(|| side.display().to_string())
        }
    }
}

/// Runs the rows not yet in `--out`, `threads` at a time; returns the failures (a failed row is
/// tried again by the next call).
fn run_missing(args: &Args, seeds: &BTreeMap<u64, u64>) -> anyhow::Result<Vec<String>> {
    // The table's own box (model class, scale) under the candidate rule.
    let sb = design_box(&args.design, RestRule::CANDIDATE)?;
    let design = design_rows(&args.design, &sb)?;
    let done = reruns(&args.out, seeds)?;
    let todo: Vec<_> = design
        .iter()
        .filter(|(r, _)| !done.contains_key(r))
        .collect();
    if todo.is_empty() {
        return Ok(Vec::new());
    }
    eprintln!(
        "{} of {} rows to rerun under the candidate rule, {} at a time",
        todo.len(),
        design.len(),
        args.threads
    );
    let next = AtomicUsize::new(0);
    let write = Mutex::new(());
    let failures: Mutex<Vec<String>> = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..args.threads.max(1) {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some((row, (seed, p, _))) = todo.get(k) else {
                    return;
                };
                let result = sb
                    .run(p, *seed, &RunOptions::default())
                    .with_context(|| format!("design row {row}, seed {seed}"))
                    .and_then(|o| {
                        let line = format!(
                            "{row}\t{seed}\t{:.6}\t{:.4}\t{}\t{}\t{:.3}",
                            o.get("shear_angle").unwrap_or(f64::NAN),
                            o.get("bulk_density").unwrap_or(f64::NAN),
                            u8::from(o.diagnostics.settled),
                            o.diagnostics.steps,
                            o.diagnostics.wall_time_s
                        );
                        let _guard = write.lock().map_err(|_| anyhow::anyhow!("poisoned"))?;
                        eprintln!("row {row} done");
                        append(&args.out, HEADER, &[line])
                    });
                if let Err(e) = result {
                    if let Ok(mut f) = failures.lock() {
                        f.push(format!("{e:#}"));
                    }
                }
            });
        }
    });
    Ok(failures.into_inner().unwrap_or_default())
}

/// Runs the study.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.threads == 0 {
        anyhow::bail!("--threads 0: expected at least 1");
    }
    let model = Metamodel::load(&args.model).with_context(|| args.model.display().to_string())?;
    let inputs = model.input_names();
    let rec = recorded(&args.design, &inputs)?;
    let seeds: BTreeMap<u64, u64> = design_rows(
        &args.design,
        &design_box(&args.design, RestRule::CANDIDATE)?,
    )?
    .into_iter()
    .map(|(row, (seed, _, _))| (row, seed))
    .collect();
    check_out_design(args)?;
    let failures = run_missing(args, &seeds)?;
    for f in &failures {
        eprintln!("failed: {f}");
    }
    let new = reruns(&args.out, &seeds)?;
    let noise = replicate_noise(&args.design, &args.replicates)?;
    let text = report(args, &model, &rec, &new, noise.as_ref())?;
    crate::emit_report(
        args.json,
        args.report.as_deref(),
        &text,
        serde_json::json!({ "rows": new.len(), "failed": failures.len() }),
    )?;
    if !failures.is_empty() {
        anyhow::bail!(
            "{} reruns failed (listed above; the next call tries them again)",
            failures.len()
        );
    }
    Ok(())
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn sd(v: &[f64]) -> f64 {
    let m = mean(v);
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() as f64 - 1.0)).sqrt()
}

fn report(
    args: &Args,
    model: &Metamodel,
    rec: &BTreeMap<u64, (Outcome, Vec<f64>)>,
    new: &BTreeMap<u64, Outcome>,
    noise: Option<&super::noise_floor::NoiseFloor>,
) -> anyhow::Result<String> {
    // The rows both have, in row order.
    let rows: Vec<u64> = rec
        .keys()
        .copied()
        .filter(|r| new.contains_key(r))
        .collect();
    if rows.is_empty() {
        anyhow::bail!("{}: no rerun rows to compare", args.out.display());
    }
    let old: Vec<Outcome> = rows.iter().map(|r| rec[r].0).collect();
    let now: Vec<Outcome> = rows.iter().map(|r| new[r]).collect();
    let sum = |v: &[Outcome], f: fn(&Outcome) -> f64| v.iter().map(f).sum::<f64>();
    let (h_old, h_new) = (
        sum(&old, |o| o.seconds) / 3600.0,
        sum(&now, |o| o.seconds) / 3600.0,
    );
    let (s_old, s_new) = (sum(&old, |o| o.steps), sum(&now, |o| o.steps));
    let mut w = String::new();
    let _ = writeln!(
        w,
        "# The candidate rest rule on the shipped campaign's validation design\n\nRegenerate \
         with `cargo run --release -- bench rest-validation --threads {} --out {} --report \
         docs/rest_validation.md` (reruns every done row of `{}` with its own seed under the \
         candidate rule, {} at a time; runs kept in the `--out` table, so a killed study \
         resumes).\n",
        args.threads,
        args.out.display(),
        args.design.display(),
        args.threads,
    );
    let _ = writeln!(
        w,
        "The candidate rule ends the fill or the outflow also when its response has stayed \
         within 0.05 % (density) or 0.05 deg (angle) over 5 chunks (`RestRule::CANDIDATE`, \
         `docs/rest_detection.md`). The recorded runs used the kinetic rule.\n"
    );
    let _ = writeln!(
        w,
        "## Cost\n\n| | recorded (kinetic rule) | rerun (candidate rule) | ratio |\n|---|---|---|---|"
    );
    let _ = writeln!(
        w,
        "| runs | {} | {} | |\n| core-hours | {h_old:.3} | {h_new:.3} | {:.3} |\n| steps | {:.4e} | \
         {:.4e} | {:.3} |\n| median seconds per run | {:.1} | {:.1} | |",
        rows.len(),
        rows.len(),
        h_new / h_old,
        s_old,
        s_new,
        s_new / s_old,
        median(old.iter().map(|o| o.seconds).collect()),
        median(now.iter().map(|o| o.seconds).collect()),
    );
    let _ = writeln!(
        w,
        "\nThe steps are the machine-independent part of the cost. The core-hours also carry \
         the machine, its load and the engine of each campaign's day: only a reference rerun \
         in the same session tells how much of their ratio is the code's \
         (`docs/whole_run_cost.md`).\n"
    );
    let _ = writeln!(
        w,
        "## The model on both\n\n`{}` scored on the rows with a value in both runs and a \
         prediction (n):\n\n| response | n | RMSE on the recorded runs | RMSE on the reruns | \
         ratio | rerun - recorded: mean (se) | sd of the difference | replicate sd x sqrt 2 \
         |\n|---|---|---|---|---|---|---|---|",
        args.model.display(),
    );
    let x: Vec<&Vec<f64>> = rows.iter().map(|r| &rec[r].1).collect();
    let cols: Vec<Vec<f64>> = (0..model.inputs.len())
        .map(|j| x.iter().map(|x| x[j]).collect())
        .collect();
    let mean_density = mean(&old.iter().map(|o| o.density).collect::<Vec<_>>());
    let mut verdicts = Vec::new();
    for (name, get, noise_sd) in [
        (
            "shear_angle",
            (|o: &Outcome| o.angle) as fn(&Outcome) -> f64,
            noise.map(|n| n.angle_sd),
        ),
        (
            "bulk_density",
            |o: &Outcome| o.density,
            noise.map(|n| n.bulk_rel_sd * mean_density),
        ),
    ] {
        let Some(r) = model.response(name) else {
            continue;
        };
        let pred = model.predict(r, &cols);
        let keep: Vec<usize> = (0..rows.len())
            .filter(|&k| {
                get(&old[k]).is_finite() && get(&now[k]).is_finite() && pred[k].is_finite()
            })
            .collect();
        if keep.len() < 2 {
            let _ = writeln!(
                w,
                "| {name} | {} | too few rows to compare | | | | | |",
                keep.len()
            );
            continue;
        }
        let pick = |v: &[Outcome]| keep.iter().map(|&k| get(&v[k])).collect::<Vec<_>>();
        let p: Vec<f64> = keep.iter().map(|&k| pred[k]).collect();
        let (m_old, m_new) = (Metrics::of(&pick(&old), &p), Metrics::of(&pick(&now), &p));
        let d: Vec<f64> = keep.iter().map(|&k| get(&now[k]) - get(&old[k])).collect();
        let (md, se, sdd) = (mean(&d), sd(&d) / (d.len() as f64).sqrt(), sd(&d));
        let _ = writeln!(
            w,
            "| {name} | {} | {:.3} | {:.3} | {:.3} | {md:+.3} ({se:.3}) | {sdd:.3} | {} |",
            keep.len(),
            m_old.rmse,
            m_new.rmse,
            m_new.rmse / m_old.rmse,
            noise_sd.map_or("not measured".into(), |s| format!(
                "{:.3}",
                s * std::f64::consts::SQRT_2
            )),
        );
        verdicts.push(format!(
            "{name}: the model's RMSE on the reruns is {:.1} % {} than on the recorded runs \
             (the bar: within 10 %); the mean shift {md:+.3} is {} twice its standard error; the \
             rows' differences spread {}",
            100.0 * (m_new.rmse / m_old.rmse - 1.0).abs(),
            if m_new.rmse > m_old.rmse {
                "higher"
            } else {
                "lower"
            },
            if md.abs() > 2.0 * se {
                "beyond"
            } else {
                "within"
            },
            noise_sd.map_or("(no replicate noise to compare with)".into(), |n| format!(
                "{:.2} times what two replicate runs differ by (sd x sqrt 2)",
                sdd / (n * std::f64::consts::SQRT_2)
            ))
        ));
    }
    for v in &verdicts {
        let _ = writeln!(w, "\n- {v}.");
    }
    let unsettled = now.iter().filter(|o| !o.settled).count();
    let _ = writeln!(
        w,
        "\nA rerun under another rule is another sample of the run's noise after the point where \
         the rules part, so a row's difference can reach the replicate difference; a mean shift \
         beyond twice its standard error would be a bias of the rule. Reruns not at rest by the \
         rule's criterion: {unsettled} of {} (scored like the others).",
        now.len()
    );
    Ok(w)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}
