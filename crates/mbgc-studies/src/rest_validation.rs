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
use super::rest_tables::{append, design_rows, read_tsv};
use mbgc::experiments::shear_box::{RestRule, ShearBox};
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
        };
        let x = c_in
            .iter()
            .map(|&c| num(c))
            .collect::<anyhow::Result<_>>()?;
        out.insert(row, (o, x));
    }
    Ok(out)
}

/// The reruns written so far, by row.
fn reruns(path: &Path) -> anyhow::Result<BTreeMap<u64, Outcome>> {
    let mut out = BTreeMap::new();
    for (k, c) in read_tsv(path, 7)?.into_iter().enumerate() {
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
        out.insert(
            num(0)? as u64,
            Outcome {
                angle: num(2)?,
                density: num(3)?,
                steps: num(5)?,
                seconds: num(6)?,
            },
        );
    }
    Ok(out)
}

/// Runs the rows not yet in `--out`, `threads` at a time.
fn run_missing(args: &Args) -> anyhow::Result<()> {
    let sb = ShearBox {
        rest: RestRule::CANDIDATE,
        ..ShearBox::default()
    };
    let design = design_rows(&args.design, &sb)?;
    let done = reruns(&args.out)?;
    let todo: Vec<_> = design
        .iter()
        .filter(|(r, _)| !done.contains_key(r))
        .collect();
    if todo.is_empty() {
        return Ok(());
    }
    eprintln!(
        "{} of {} rows to rerun under the candidate rule, {} at a time",
        todo.len(),
        design.len(),
        args.threads
    );
    let next = AtomicUsize::new(0);
    let write = Mutex::new(());
    let failure: Mutex<Option<anyhow::Error>> = Mutex::new(None);
    std::thread::scope(|s| {
        for _ in 0..args.threads.max(1) {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some((row, (seed, p, _))) = todo.get(k) else {
                    return;
                };
                if failure.lock().map(|f| f.is_some()).unwrap_or(true) {
                    return;
                }
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
                    if let Ok(mut f) = failure.lock() {
                        f.get_or_insert(e);
                    }
                    return;
                }
            });
        }
    });
    match failure.into_inner() {
        Ok(Some(e)) => Err(e),
        _ => Ok(()),
    }
}

/// Runs the study.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.threads == 0 {
        anyhow::bail!("--threads 0: expected at least 1");
    }
    let model = Metamodel::load(&args.model).with_context(|| args.model.display().to_string())?;
    let inputs = model.input_names();
    let rec = recorded(&args.design, &inputs)?;
    run_missing(args)?;
    let new = reruns(&args.out)?;
    let noise = replicate_noise(&args.design, &args.replicates)?;
    let text = report(args, &model, &rec, &new, noise.as_ref())?;
    match &args.report {
        Some(path) => crate::write_report(
            args.json,
            path,
            &text,
            serde_json::json!({ "rows": new.len() }),
        ),
        None => {
            print!("{text}");
            Ok(())
        }
    }
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
         with `cargo run --release -- bench rest-validation --threads {} --report \
         docs/rest_validation.md` (reruns every done row of `{}` with its own seed under the \
         candidate rule; runs kept in `{}`, so a killed study resumes).\n",
        args.threads,
        args.design.display(),
        args.out.display()
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
        "\nThe steps are the machine-independent part of the cost; the core-hours also carry \
         the machine and its load at the time of each campaign, and the engine changed in \
         between (the pair loop lost its bounds checks: 2.5 % fewer instructions, results bit \
         for bit the same).\n"
    );
    let _ = writeln!(
        w,
        "## The shipped model on both\n\n`{}` scored on the same {} rows:\n\n| response | RMSE on the \
         recorded runs | RMSE on the reruns | ratio | rerun - recorded: mean (se) | sd of the \
         difference | replicate sd x sqrt 2 |\n|---|---|---|---|---|---|---|",
        args.model.display(),
        rows.len()
    );
    let x: Vec<&Vec<f64>> = rows.iter().map(|r| &rec[r].1).collect();
    let cols: Vec<Vec<f64>> = (0..model.inputs.len())
        .map(|j| x.iter().map(|x| x[j]).collect())
        .collect();
    let mean_density = mean(&old.iter().map(|o| o.density).collect::<Vec<_>>());
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
            .filter(|&k| get(&old[k]).is_finite() && get(&now[k]).is_finite())
            .collect();
        let pick = |v: &[Outcome]| keep.iter().map(|&k| get(&v[k])).collect::<Vec<_>>();
        let p: Vec<f64> = keep.iter().map(|&k| pred[k]).collect();
        let (m_old, m_new) = (Metrics::of(&pick(&old), &p), Metrics::of(&pick(&now), &p));
        let d: Vec<f64> = keep.iter().map(|&k| get(&now[k]) - get(&old[k])).collect();
        let _ = writeln!(
            w,
            "| {name} | {:.3} | {:.3} | {:.3} | {:+.3} ({:.3}) | {:.3} | {} |",
            m_old.rmse,
            m_new.rmse,
            m_new.rmse / m_old.rmse,
            mean(&d),
            sd(&d) / (d.len() as f64).sqrt(),
            sd(&d),
            noise_sd.map_or("not measured".into(), |s| format!(
                "{:.3}",
                s * std::f64::consts::SQRT_2
            )),
        );
    }
    let _ = writeln!(
        w,
        "\nA rerun under another rule is another sample of the same noise where the rule cuts \
         in, so the difference of a row is at most about the replicate difference (sd x sqrt \
         2); a mean difference beyond 2 standard errors would be a bias of the rule."
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
