//! When is a shear-box run at rest (issue 38)? Runs rows of a campaign table again with their
//! own seeds under the kinetic rule every campaign used, records the state after every chunk of
//! steps, and replays other rest rules on those traces with the very functions a run applies
//! (`mbgc::experiments::shear_box_rest`): where each rule would have stopped the fill and the
//! outflow, the steps and seconds that saves, and how far the measured responses then are from
//! the kinetic rule's. The outflow replay is exact (the trajectory up to the earlier stop is the
//! same run); a fill stopped earlier also changes the outflow after it, which only a rerun with
//! the rule shows (the validation rerun in the report).
//!
//! `mbgc bench rest --report docs/rest_detection.md`; each run's trace is kept in
//! `--traces` (one row per chunk) and its summary in `--runs`, so a killed study resumes.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context as _;

use super::noise_floor::replicate_noise;
use super::rest_tables::{append, design_box, design_rows, read_tsv};
use mbgc::experiments::shear_box::{ChunkState, Phase, RestRule, ShearBox, Thresholds};
use mbgc::experiments::{Experiment, ParamSet, RunOptions};

/// `mbgc bench rest`.
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Args {
    /// The campaign table whose rows are rerun (inputs and seed taken from it; its responses
    /// show that the rerun repeats the recorded run).
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
    /// Rows of the table to rerun (its `row` column).
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ',', default_values_t = vec![0, 1, 2, 3, 4, 5, 6]))]
    pub rows: Vec<u64>,
    /// Per-chunk traces of the runs (appended as runs finish).
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value = "docs/data/rest_detection/traces.tsv")
    )]
    pub traces: PathBuf,
    /// One row per finished run: its schedule's thresholds and what it measured.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value = "docs/data/rest_detection/runs.tsv")
    )]
    pub runs: PathBuf,
    /// Seeds per row (1..=seeds) of the check: each row run under the kinetic rule and under
    /// the candidate response rule with the same seed; 0 skips the check.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 3))]
    pub seeds: u64,
    /// The check's runs, one row per run.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value = "docs/data/rest_detection/check.tsv")
    )]
    pub check: PathBuf,
    /// Markdown report.
    #[cfg_attr(feature = "cli", arg(long))]
    pub report: Option<PathBuf>,
    /// Standard output holds one JSON object (where the report went); text goes to standard
    /// error.
    #[cfg_attr(feature = "cli", arg(long))]
    pub json: bool,
}

/// The rules replayed: windows of chunks, and tolerances of the density (relative) and of the
/// angle (degrees).
fn rules() -> Vec<RestRule> {
    let mut v = vec![RestRule::Kinetic];
    for window in [3, 5, 8] {
        for (density_tol, angle_tol) in [(2.5e-4, 0.02), (5e-4, 0.05), (1e-3, 0.1)] {
            v.push(RestRule::Response {
                window,
                density_tol,
                angle_tol,
            });
        }
    }
    v
}

fn rule_name(r: &RestRule) -> String {
    match r {
        RestRule::Kinetic => "kinetic (campaigns so far)".into(),
        RestRule::Response {
            window,
            density_tol,
            angle_tol,
        } => format!(
            "response: {window} chunks, density {:.3} %, angle {angle_tol} deg",
            density_tol * 100.0
        ),
    }
}

/// A rerun: the design row, its thresholds and what it measured.
#[derive(Clone, Debug)]
struct RunRow {
    row: u64,
    limits: Thresholds,
    open_time: f64,
    recorded: (f64, f64),
    measured: (f64, f64),
    seconds: f64,
    steps: u64,
}

const RUN_HEADER: &str = "row\tv_rest\tv_move\tfall\tmin_flow_time\topen_time\trecorded_angle\trecorded_density\tshear_angle\tbulk_density\tseconds\tsteps";
const CHECK_HEADER: &str = "row\tseed\trule\tshear_angle\tbulk_density\tsteps\tseconds";
const TRACE_HEADER: &str =
    "row\tphase\tstep\ttime\tseconds\trms_speed\tmax_speed\tmax_step\tremoved\tresponse";

/// Runs `row` under the kinetic rule; its summary and trace.
fn rerun(
    sb: &ShearBox,
    row: u64,
    seed: u64,
    p: &ParamSet,
    recorded: (f64, f64),
) -> anyhow::Result<(RunRow, Vec<ChunkState>)> {
    let (o, rec) = sb
        .run_recorded(p, seed, &RunOptions::default())
        .with_context(|| format!("design row {row}"))?;
    let rho = p.get("rho_p").unwrap_or(f64::NAN);
    let e = p.get("E_p").unwrap_or(f64::NAN);
    let nu = p.get("nu_p").unwrap_or(f64::NAN);
    let sched = sb.schedule(&rec.layout, rho, e, nu);
    let open = rec
        .trace
        .iter()
        .rfind(|c| c.phase == Phase::Fill)
        .map_or(f64::NAN, |c| c.time)
        + rec.relax_steps as f64 * rec.dt;
    Ok((
        RunRow {
            row,
            limits: sched.thresholds(),
            open_time: open,
            recorded,
            measured: (
                o.get("shear_angle").unwrap_or(f64::NAN),
                o.get("bulk_density").unwrap_or(f64::NAN),
            ),
            seconds: o.diagnostics.wall_time_s,
            steps: o.diagnostics.steps,
        },
        rec.trace,
    ))
}

fn f(s: &str) -> f64 {
    s.parse().unwrap_or(f64::NAN)
}

fn load(args: &Args) -> anyhow::Result<Vec<(RunRow, Vec<ChunkState>)>> {
    let runs: Vec<RunRow> = read_tsv(&args.runs, RUN_HEADER)?
        .into_iter()
        .map(|c| RunRow {
            row: c[0].parse().unwrap_or(u64::MAX),
            limits: Thresholds {
                v_rest: f(&c[1]),
                v_move: f(&c[2]),
                fall: f(&c[3]),
                min_flow_time: f(&c[4]),
            },
            open_time: f(&c[5]),
            recorded: (f(&c[6]), f(&c[7])),
            measured: (f(&c[8]), f(&c[9])),
            seconds: f(&c[10]),
            steps: c[11].parse().unwrap_or(0),
        })
        .collect();
    let mut traces: BTreeMap<u64, Vec<ChunkState>> = BTreeMap::new();
    for c in read_tsv(&args.traces, TRACE_HEADER)? {
        let row: u64 = c[0].parse().unwrap_or(u64::MAX);
        traces.entry(row).or_default().push(ChunkState {
            phase: if c[1] == "fill" {
                Phase::Fill
            } else {
                Phase::Outflow
            },
            step: c[2].parse().unwrap_or(0),
            time: f(&c[3]),
            seconds: f(&c[4]),
            rms_speed: f(&c[5]),
            max_speed: f(&c[6]),
            max_step: f(&c[7]),
            removed: c[8].parse().unwrap_or(0),
            response: f(&c[9]),
        });
    }
    Ok(runs
        .into_iter()
        .filter_map(|r| traces.remove(&r.row).map(|t| (r, t)))
        .collect())
}

/// Where `rule` stops a recorded run: (fill chunk index, outflow chunk index) into its trace.
fn stops(rule: &RestRule, run: &RunRow, trace: &[ChunkState]) -> (usize, usize) {
    let n_fill = trace.iter().take_while(|c| c.phase == Phase::Fill).count();
    let (fill, flow) = trace.split_at(n_fill);
    let fi = (1..=fill.len())
        .find(|&k| rule.fill_done(&fill[..k], &run.limits))
        .unwrap_or(fill.len())
        - 1;
    let oi = (1..=flow.len())
        .find(|&k| rule.outflow_done(&flow[..k], run.open_time, &run.limits))
        .unwrap_or(flow.len())
        - 1;
    (fi, n_fill + oi)
}

/// What a rule does on every recorded run.
struct Replay {
    steps_saved: f64,
    seconds_saved: f64,
    d_density: Vec<f64>,
    d_angle: Vec<f64>,
}

fn replay(rule: &RestRule, runs: &[(RunRow, Vec<ChunkState>)]) -> Replay {
    let (mut steps, mut steps_all, mut secs, mut secs_all) = (0.0, 0.0, 0.0, 0.0);
    let (mut dd, mut da) = (Vec::new(), Vec::new());
    for (run, t) in runs {
        let n_fill = t.iter().take_while(|c| c.phase == Phase::Fill).count();
        let (fi, oi) = stops(rule, run, t);
        let (f_end, o_end) = (n_fill - 1, t.len() - 1);
        // Steps and seconds a rule saves in each phase, against the whole recorded run.
        steps += (t[f_end].step - t[fi].step + t[o_end].step - t[oi].step) as f64;
        steps_all += run.steps as f64;
        secs += t[f_end].seconds - t[fi].seconds + t[o_end].seconds - t[oi].seconds;
        secs_all += run.seconds;
        dd.push((t[fi].response - t[f_end].response) / t[f_end].response);
        da.push(t[oi].response - t[o_end].response);
    }
    Replay {
        steps_saved: steps / steps_all,
        seconds_saved: secs / secs_all,
        d_density: dd,
        d_angle: da,
    }
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Runs the study.
pub fn run(args: &Args) -> anyhow::Result<()> {
    // The reruns repeat the recorded runs: the table's box and the rule every campaign so far
    // used.
    let sb = design_box(&args.design, RestRule::Kinetic)?;
    let design = design_rows(&args.design, &sb)?;
    let done: Vec<u64> = load(args)?.iter().map(|(r, _)| r.row).collect();
    for &row in &args.rows {
        if done.contains(&row) {
            continue;
        }
        let (seed, p, recorded) = design.get(&row).with_context(|| {
            format!(
                "--rows {row}: {} has no finished run with that row",
                args.design.display()
            )
        })?;
        eprintln!("rerunning design row {row} (seed {seed})");
        let (r, trace) = rerun(&sb, row, *seed, p, *recorded)?;
        // The trace first: a run counts as done once its summary row is written.
        let lines: Vec<String> = trace
            .iter()
            .map(|c| {
                format!(
                    "{row}\t{}\t{}\t{:.6}\t{:.4}\t{:.6e}\t{:.6e}\t{:.6e}\t{}\t{:.6}",
                    if c.phase == Phase::Fill {
                        "fill"
                    } else {
                        "outflow"
                    },
                    c.step,
                    c.time,
                    c.seconds,
                    c.rms_speed,
                    c.max_speed,
                    c.max_step,
                    c.removed,
                    c.response
                )
            })
            .collect();
        append(&args.traces, TRACE_HEADER, &lines)?;
        let l = r.limits;
        append(
            &args.runs,
            RUN_HEADER,
            &[format!(
                "{row}\t{:.6e}\t{:.6e}\t{:.6}\t{:.6}\t{:.6}\t{:.6}\t{:.4}\t{:.6}\t{:.4}\t{:.3}\t{}",
                l.v_rest,
                l.v_move,
                l.fall,
                l.min_flow_time,
                r.open_time,
                r.recorded.0,
                r.recorded.1,
                r.measured.0,
                r.measured.1,
                r.seconds,
                r.steps
            )],
        )?;
    }
    let runs = load(args)?;
    // The check: both rules, the same seeds, whole runs.
    let checked = read_tsv(&args.check, CHECK_HEADER)?;
    for &row in &args.rows {
        for seed in 1..=args.seeds {
            for (name, rule) in [
                ("kinetic", RestRule::Kinetic),
                ("response", RestRule::CANDIDATE),
            ] {
                let key = [row.to_string(), seed.to_string(), name.to_string()];
                if checked.iter().any(|c| c.len() >= 3 && c[..3] == key) {
                    continue;
                }
                let (_, p, _) = design.get(&row).with_context(|| {
                    format!(
                        "--rows {row}: {} has no finished run with that row",
                        args.design.display()
                    )
                })?;
                eprintln!("check: design row {row}, seed {seed}, {name} rule");
                let b = ShearBox {
                    rest: rule,
                    ..sb.clone()
                };
                let o = b
                    .run(p, seed, &RunOptions::default())
                    .with_context(|| format!("design row {row}, seed {seed}"))?;
                append(
                    &args.check,
                    CHECK_HEADER,
                    &[format!(
                        "{row}\t{seed}\t{name}\t{:.6}\t{:.4}\t{}\t{:.3}",
                        o.get("shear_angle").unwrap_or(f64::NAN),
                        o.get("bulk_density").unwrap_or(f64::NAN),
                        o.diagnostics.steps,
                        o.diagnostics.wall_time_s
                    )],
                )?;
            }
        }
    }
    let checked = read_tsv(&args.check, CHECK_HEADER)?;
    let noise = replicate_noise(&args.design, &args.replicates)?;
    let mut text = report(args, &runs, noise.as_ref());
    text.push_str(&check_report(&checked, noise.as_ref()));
    match &args.report {
        Some(path) => crate::write_report(
            args.json,
            path,
            &text,
            serde_json::json!({ "runs": runs.len() }),
        ),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

fn report(
    args: &Args,
    runs: &[(RunRow, Vec<ChunkState>)],
    noise: Option<&super::noise_floor::NoiseFloor>,
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# When is a shear-box run at rest?\n\nRegenerate with `cargo run --release -- bench rest \
         --report docs/rest_detection.md` (reruns rows {:?} of `{}` with their own seeds, one \
         after the other, one thread each; traces in `{}`).\n",
        args.rows,
        args.design.display(),
        args.traces.display()
    );
    let _ = writeln!(
        s,
        "Every campaign so far ended the fill when the rms speed fell below v_rest = 0.01 \
         sqrt(g d_max), and the outflow after 5 chunks in a row with nothing leaving, no particle \
         in the box faster than v_move = 0.05 sqrt(g d_max) and the rms speed below v_rest (the \
         kinetic rule). A chunk is 0.3 sqrt(d_max / g) of simulated time. The response rule \
         also ends a phase when its own response has stayed within a tolerance for a window of \
         chunks: the bulk density of a strike-off at that state in the fill, the flank angle with \
         nothing leaving the box in the outflow. The replay below applies each rule to the \
         recorded traces of kinetic-rule runs with the functions a run uses \
         (`experiments::shear_box_rest`).\n"
    );
    let _ = writeln!(
        s,
        "## The reruns\n\n| row | recorded angle / density | rerun angle / density | steps | \
         seconds |\n|---|---|---|---|---|"
    );
    for (r, _) in runs {
        let _ = writeln!(
            s,
            "| {} | {:.3} / {:.2} | {:.3} / {:.2} | {} | {:.1} |",
            r.row, r.recorded.0, r.recorded.1, r.measured.0, r.measured.1, r.steps, r.seconds
        );
    }
    let same = runs
        .iter()
        .filter(|(r, _)| r.recorded.0 == r.measured.0 || (r.recorded.0 - r.measured.0).abs() < 5e-4)
        .count();
    let _ = writeln!(
        s,
        "\n{same} of {} reruns repeat the recorded shear angle to the printed digits (same seed, \
         same rule).\n",
        runs.len()
    );
    let _ = writeln!(
        s,
        "## Where a run's wall time goes\n\nFrom the traces (kinetic rule): the column's free \
         fall (up to the fall time from the column's top), the rest of the fill (landing and \
         settling), the outflow up to the last chunk that removed a particle, and the outflow's \
         tail after it. The wall seconds are as steady as the machine was (these reruns shared \
         it with campaigns); the shares within one run are comparable.\n\n| row | fall | \
         settling | outflow to the last removal | outflow tail | angle within 0.3 deg of its end \
         over the last |\n|---|---|---|---|---|---|"
    );
    for (r, t) in runs {
        let n_fill = t.iter().take_while(|c| c.phase == Phase::Fill).count();
        let (fill, flow) = t.split_at(n_fill);
        let total = t.last().map_or(f64::NAN, |c| c.seconds);
        let at = |c: Option<&ChunkState>| c.map_or(0.0, |c| c.seconds);
        let fall = at(fill.iter().rfind(|c| c.time <= r.limits.fall));
        let filled = at(fill.last());
        let last_removal = at(flow.iter().rfind(|c| c.removed > 0)).max(filled);
        let pc = |x: f64| 100.0 * x / total;
        let end = flow.last().map_or(f64::NAN, |c| c.response);
        let settled_from = flow
            .iter()
            .rposition(|c| (c.response - end).abs().is_nan() || (c.response - end).abs() > 0.3)
            .map_or(0, |k| k + 1);
        let _ = writeln!(
            s,
            "| {} | {:.0} % | {:.0} % | {:.0} % | {:.0} % | {:.0} % of its chunks |",
            r.row,
            pc(fall),
            pc(filled - fall),
            pc(last_removal - filled),
            pc(total - last_removal),
            100.0 * (flow.len() - settled_from) as f64 / flow.len().max(1) as f64
        );
    }
    let _ = writeln!(
        s,
        "\nThe outflow drains slowly: particles leave until the last few chunks, and the flank \
         angle creeps until late (last column), so little of the outflow is spent waiting. The fill's \
         settling is where the kinetic rule waits for a few particles rolling on the free \
         surface after the struck-off density has stopped changing.\n"
    );
    let (na, nb) = noise.map_or((f64::NAN, f64::NAN), |n| (n.angle_sd, n.bulk_rel_sd));
    let _ = writeln!(
        s,
        "## The rules replayed\n\nShifts are the rule's response at its stop minus the kinetic \
         rule's (the fill's strike-off density as traced, relative; the flank angle), over the {} \
         runs; the replicate noise of single runs is {:.3} deg and {:.3} % of the density \
         (`{}`). Saved: the steps and wall seconds after the rule's stop up to the kinetic \
         stop, over all steps and seconds of the runs.\n",
        runs.len(),
        na,
        nb * 100.0,
        args.replicates.display()
    );
    let _ = writeln!(
        s,
        "| rule | steps saved | seconds saved | density shift mean / max, % | angle shift mean / \
         max, deg | largest shift / noise |\n|---|---|---|---|---|---|"
    );
    for rule in rules() {
        if runs.is_empty() {
            break;
        }
        let r = replay(&rule, runs);
        let worst = (max_abs(&r.d_density) / nb).max(max_abs(&r.d_angle) / na);
        let _ = writeln!(
            s,
            "| {} | {:.1} % | {:.1} % | {:+.3} / {:.3} | {:+.3} / {:.3} | {:.2} |",
            rule_name(&rule),
            r.steps_saved * 100.0,
            r.seconds_saved * 100.0,
            mean(&r.d_density) * 100.0,
            max_abs(&r.d_density) * 100.0,
            mean(&r.d_angle),
            max_abs(&r.d_angle),
            worst
        );
    }
    s
}

/// The check's section: per row, the seed means of both rules, their difference and its
/// standard error (the differences are paired by seed); steps and wall seconds of both.
fn check_report(rows: &[Vec<String>], noise: Option<&super::noise_floor::NoiseFloor>) -> String {
    let mut s = String::new();
    // (row, seed) -> (kinetic, default): angle, density, steps, seconds.
    let mut pairs: BTreeMap<(u64, u64), [Option<[f64; 4]>; 2]> = BTreeMap::new();
    for c in rows {
        let (Ok(row), Ok(seed)) = (c[0].parse::<u64>(), c[1].parse::<u64>()) else {
            continue;
        };
        let k = usize::from(c[2] != "kinetic");
        pairs.entry((row, seed)).or_default()[k] = Some([f(&c[3]), f(&c[4]), f(&c[5]), f(&c[6])]);
    }
    type Pair = ((u64, u64), [f64; 4], [f64; 4]);
    let both: Vec<Pair> = pairs
        .into_iter()
        .filter_map(|(k, [a, b])| Some((k, a?, b?)))
        .collect();
    if both.is_empty() {
        return s;
    }
    let (na, nb) = noise.map_or((f64::NAN, f64::NAN), |n| (n.angle_sd, n.bulk_rel_sd));
    let _ = writeln!(
        s,
        "\n## The check: whole runs under both rules\n\nEach row run with seeds 1, 2, ... under \
         the kinetic rule and under the candidate response rule ({}), one run after the other. The \
         same seed gives both the same trajectory up to the candidate's earlier stop of the fill; \
         the outflow after it diverges like another seed's, so a difference has about the \
         spread of two independent runs. SE is the standard error of the mean difference over \
         the seeds. Cost: the candidate's steps and wall seconds over the kinetic rule's \
         (wall seconds only as steady as the machine was).\n",
        rule_name(&RestRule::CANDIDATE)
    );
    let _ = writeln!(
        s,
        "| row | seeds | angle kinetic / response, deg | difference +- SE | density kinetic / \
         response | difference +- SE | steps | seconds |\n|---|---|---|---|---|---|---|---|"
    );
    let rows_seen: Vec<u64> = {
        let mut v: Vec<u64> = both.iter().map(|((r, _), _, _)| *r).collect();
        v.dedup();
        v
    };
    let (mut within, mut steps, mut steps_k, mut secs, mut secs_k) = (0, 0.0, 0.0, 0.0, 0.0);
    let (mut all_da, mut all_dd) = (Vec::new(), Vec::new());
    for row in &rows_seen {
        let sel: Vec<_> = both.iter().filter(|((r, _), _, _)| r == row).collect();
        let col = |i: usize, k: bool| -> Vec<f64> {
            sel.iter()
                .map(|(_, a, b)| if k { a[i] } else { b[i] })
                .collect()
        };
        let da: Vec<f64> = sel.iter().map(|(_, a, b)| b[0] - a[0]).collect();
        let dd: Vec<f64> = sel.iter().map(|(_, a, b)| b[1] - a[1]).collect();
        all_da.extend(&da);
        all_dd.extend(dd.iter().zip(&sel).map(|(d, (_, a, _))| d / a[1]));
        let (ma, sa) = super::shear_box_fill::mean_se(&da);
        let (md, sd) = super::shear_box_fill::mean_se(&dd);
        // Within one SE of the seed means' own spread: the noise over sqrt(seeds).
        let n = sel.len() as f64;
        let se_a = na / n.sqrt();
        let se_d = nb * mean(&col(1, true)) / n.sqrt();
        if ma.abs() < se_a && md.abs() < se_d {
            within += 1;
        }
        steps += col(2, false).iter().sum::<f64>();
        steps_k += col(2, true).iter().sum::<f64>();
        secs += col(3, false).iter().sum::<f64>();
        secs_k += col(3, true).iter().sum::<f64>();
        let _ = writeln!(
            s,
            "| {row} | {} | {:.3} / {:.3} | {:+.3} +- {:.3} | {:.2} / {:.2} | {:+.2} +- {:.2} | {:.2} | {:.2} |",
            sel.len(),
            mean(&col(0, true)),
            mean(&col(0, false)),
            ma,
            sa,
            mean(&col(1, true)),
            mean(&col(1, false)),
            md,
            sd,
            col(2, false).iter().sum::<f64>() / col(2, true).iter().sum::<f64>(),
            col(3, false).iter().sum::<f64>() / col(3, true).iter().sum::<f64>(),
        );
    }
    let _ = writeln!(
        s,
        "\n- At {within} of {} rows both seed means moved by less than one standard error of a \
         seed mean (the replicate noise, {na:.3} deg and {:.3} % of the density, over the root \
         of the seeds).\n- Over all {} pairs: angle {:+.3} deg (largest {:.3}), density {:+.4} % \
         (largest {:.4} %).\n- The candidate took {:.2} of the kinetic rule's steps and {:.2} of its \
         wall seconds.",
        rows_seen.len(),
        nb * 100.0,
        all_da.len(),
        mean(&all_da),
        max_abs(&all_da),
        mean(&all_dd) * 100.0,
        max_abs(&all_dd) * 100.0,
        steps / steps_k,
        secs / secs_k
    );
    s
}
