//! Runs a plan: worker threads (one run each) send finished lines over a channel to the calling
//! thread, the only writer, which appends each line with one `write_all` and `sync_data`. A kill
//! at any moment therefore loses at most the runs in flight and leaves at worst an incomplete last
//! line, which the next start truncates before redoing that run.

use std::collections::{HashMap, HashSet};
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Instant;

use csv::StringRecord;

use super::columns::{
    identity_len, is_pre_class_header, FIXED_COLUMNS, MODEL_CLASS_COLUMN, PRE_CLASS_TABLE,
};
use super::lock::TableLock;
use super::observer::ObserverHandle;
use super::plan::{Plan, PlannedRun};
use super::status::{meta_path, Meta};
use super::table::{self, csv_line, read_table, Table, DONE, FAILED};
use crate::error::{write_atomic, Error, Result};
use crate::experiments::{Experiment, Outcome, RunOptions};

/// How a campaign runs: the table, the threads and what else to write.
#[derive(Debug, Clone)]
pub struct CampaignOptions {
    /// The table; an existing one is resumed.
    pub out: PathBuf,
    /// Worker threads, each running one run at a time.
    pub threads: usize,
    /// Each run gets `vtk_dir/<run_id>/` for its snapshots.
    pub vtk_dir: Option<PathBuf>,
    /// Told of each recorded run (a progress bar, a log); nobody when `None`.
    pub observer: Option<ObserverHandle>,
    /// Run again the rows whose earlier run failed (their failed lines are removed first).
    pub retry_failed: bool,
    /// Each run gets `work_dir/<run_id>/` for an external backend's deck, log and dumps.
    pub work_dir: Option<PathBuf>,
    /// Run only these run ids of the shard (`campaign import`: the decks that have results);
    /// the others are left for a later invocation, neither run nor recorded.
    pub only: Option<HashSet<String>>,
    /// Set by the caller to stop the campaign: no run starts after it is set, the runs in
    /// flight finish and are recorded (a caller's Ctrl-C, without losing finished work).
    pub cancel: Option<Arc<AtomicBool>>,
}

impl CampaignOptions {
    /// A campaign into `out` on `threads` threads, nothing else asked for.
    pub fn new(out: PathBuf, threads: usize) -> Self {
        CampaignOptions {
            out,
            threads,
            vtk_dir: None,
            observer: None,
            retry_failed: false,
            work_dir: None,
            only: None,
            cancel: None,
        }
    }
}

/// What [`run_campaign`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Rows of this shard (all design rows without a shard).
    pub planned: usize,
    /// Rows already in the table (done or failed) and therefore not run again.
    pub skipped: usize,
    /// Of those, rows whose earlier run failed (not retried without `retry_failed`).
    pub failed_before: usize,
    /// Failed rows removed from the table to be run again (`retry_failed`).
    pub retried: usize,
    /// Runs completed and recorded as done in this invocation.
    pub done: usize,
    /// Of the runs done now, those that measured no value (NaN) of some response: a shear box
    /// whose material ran out flat has no flank. They are in the table as done, and a fit
    /// leaves them out.
    pub no_value: usize,
    /// Runs that ended in an error in this invocation (recorded as failed).
    pub failed: usize,
    /// The first of those, as its run id and the error recorded in its row: the reason a
    /// caller shows without making the user open the table.
    pub first_failure: Option<(String, String)>,
    /// Bytes of an incomplete last line removed from the table before resuming.
    pub truncated_bytes: u64,
    /// Response columns the experiment gained since the table was written, added to it with
    /// NaN (no value) in the runs already there.
    pub added_columns: Vec<String>,
    /// Worker threads used.
    pub threads: usize,
    /// Wall-clock time of the invocation, s.
    pub elapsed_s: f64,
    /// Rows of this shard neither in the table before nor run now: left for a later
    /// invocation because `cancel` stopped this one (0 when it ran to the end).
    pub cancelled: usize,
}

impl Summary {
    /// What to tell the user when this invocation widened the table at `out` with response
    /// columns the experiment records since the table was written (`None` when it did not):
    /// its earlier runs hold what their lines tell, NaN where they cannot.
    pub fn added_columns_note(&self, out: &Path) -> Option<String> {
        (!self.added_columns.is_empty()).then(|| {
            format!(
                "{}: added the column(s) {} that the experiment records since the table was \
                 written, filled for its earlier runs from what their lines tell, NaN where they \
                 cannot (to record a run's value, delete its line and resume)",
                out.display(),
                self.added_columns.join(", ")
            )
        })
    }

    /// The summary as `mbgc simulate --json` prints it: the table `out`, what `plan` ran it
    /// with, and the counts.
    pub fn json(&self, plan: &Plan, out: &Path) -> serde_json::Value {
        serde_json::json!({
            "out": out,
            "experiment": plan.experiment,
            "model_class": plan.model_class.map(|c| c.to_string()),
            "backend": plan.settings.backend.label(),
            "design": plan.design,
            "design_rows": plan.rows.len(),
            "shard": plan.shard.map(|k| k.to_string()),
            "planned": self.planned,
            "skipped": self.skipped,
            "done": self.done,
            "no_value": self.no_value,
            "failed": self.failed,
            "failed_before": self.failed_before,
            "first_failure": self.first_failure.as_ref().map(|(id, e)| {
                serde_json::json!({ "run_id": id, "error": e })
            }),
            "retried": self.retried,
            "truncated_bytes": self.truncated_bytes,
            "added_columns": self.added_columns,
            "threads": self.threads,
            "elapsed_s": self.elapsed_s,
            "cancelled": self.cancelled,
        })
    }
}

/// The worker threads of a campaign: `given` (`--threads`, at least 1), else one per core
/// divided among the `mpi` processes each LIGGGHTS run takes.
pub fn worker_threads(given: Option<usize>, mpi: Option<usize>) -> Result<usize> {
    match given {
        Some(0) => Err(Error::invalid("--threads: expected at least 1")),
        Some(n) => Ok(n),
        None => Ok((std::thread::available_parallelism().map_or(1, |n| n.get())
            / mpi.unwrap_or(1).max(1))
        .max(1)),
    }
}

/// Runs every row of the plan's shard that the table does not hold yet.
pub fn run_campaign(
    experiment: &dyn Experiment,
    plan: &Plan,
    opts: &CampaignOptions,
) -> Result<Summary> {
    if opts.threads == 0 {
        return Err(Error::invalid("--threads: expected at least 1"));
    }
    if experiment.name() != plan.experiment {
        return Err(Error::invalid(format!(
            "the plan was made for {} but the experiment is {}",
            plan.experiment,
            experiment.name()
        )));
    }
    let t0 = Instant::now();
    // Outputs are checked before any run: a campaign must not run for hours and then find that
    // its snapshots cannot be written.
    if let Some(dir) = &opts.vtk_dir {
        check_writable_dir(dir, "--vtk")?;
    }
    // Before the table is read: a second process must not resume from a table that the first
    // is still appending to.
    let mut lock = TableLock::acquire(&opts.out)?;
    let Prepared {
        mut present,
        truncated_bytes,
        added_columns,
    } = prepare_table(experiment, plan, &opts.out)?;
    let selected: Vec<&PlannedRun> = plan
        .selected()
        .filter(|r| opts.only.as_ref().is_none_or(|ids| ids.contains(&r.run_id)))
        .collect();
    let failed_ids: HashSet<String> = selected
        .iter()
        .filter(|r| present.get(r.run_id.as_str()) == Some(&true))
        .map(|r| r.run_id.clone())
        .collect();
    let mut retried = 0;
    if opts.retry_failed && !failed_ids.is_empty() {
        retried = remove_failed_lines(&opts.out, &failed_ids)?;
        for id in &failed_ids {
            present.remove(id.as_str());
        }
    }
    let todo: Vec<&PlannedRun> = selected
        .iter()
        .copied()
        .filter(|r| !present.contains_key(r.run_id.as_str()))
        .collect();
    let threads = opts.threads.min(todo.len()).max(1);
    let mut summary = Summary {
        planned: selected.len(),
        skipped: selected.len() - todo.len(),
        failed_before: if opts.retry_failed {
            0
        } else {
            failed_ids.len()
        },
        retried,
        done: 0,
        no_value: 0,
        failed: 0,
        first_failure: None,
        truncated_bytes,
        added_columns,
        threads,
        elapsed_s: 0.0,
        cancelled: 0,
    };
    if todo.is_empty() {
        summary.elapsed_s = t0.elapsed().as_secs_f64();
        return Ok(summary);
    }
    // The table may have been created or rewritten (by a rename) since the lock was taken.
    lock.hold_table()?;
    let mut file = OpenOptions::new()
        .append(true)
        .open(&opts.out)
        .map_err(|e| Error::io(&opts.out, e))?;
    let observer = opts.observer.as_ref().map(|o| o.0.as_ref());
    if let Some(o) = observer {
        o.started(todo.len(), summary.skipped);
    }

    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let (tx, rx) = mpsc::channel::<(Option<(String, String)>, bool, Result<Vec<u8>>)>();
    let mut write_error = None;
    std::thread::scope(|s| {
        for _ in 0..threads {
            let tx = tx.clone();
            let (next, stop, todo) = (&next, &stop, &todo);
            s.spawn(move || {
                let cancelled = || {
                    opts.cancel
                        .as_ref()
                        .is_some_and(|c| c.load(Ordering::Relaxed))
                };
                while !stop.load(Ordering::Relaxed) && !cancelled() {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(run) = todo.get(i) else { break };
                    let (failed, no_value, line) = execute(experiment, plan, run, opts);
                    if tx.send((failed, no_value, line)).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        for (failed, no_value, line) in rx {
            if let Err(e) = line.and_then(|l| append(&mut file, &opts.out, &l)) {
                // Workers finish the runs in flight, whose lines are then dropped (and redone
                // on the next start); no new run starts.
                stop.store(true, Ordering::Relaxed);
                write_error = Some(e);
                break;
            }
            if let Some(f) = &failed {
                summary.failed += 1;
                summary.first_failure.get_or_insert_with(|| f.clone());
            } else {
                summary.done += 1;
                summary.no_value += usize::from(no_value);
            }
            if let Some(o) = observer {
                o.run_recorded(failed.is_some());
            }
        }
    });
    if let Some(e) = write_error {
        if let Some(o) = observer {
            o.ended(false);
        }
        return Err(e);
    }
    if let Some(o) = observer {
        o.ended(true);
    }
    summary.cancelled = todo.len() - summary.done - summary.failed;
    summary.elapsed_s = t0.elapsed().as_secs_f64();
    Ok(summary)
}

/// A directory exists (or is created) and takes a file, or the error names `option`.
fn check_writable_dir(dir: &Path, option: &str) -> Result<()> {
    let probe = std::fs::create_dir_all(dir).and_then(|()| tempfile::tempfile_in(dir));
    probe.map(drop).map_err(|e| {
        Error::invalid(format!(
            "{option} {}: cannot write there ({e}); expected a writable directory",
            dir.display()
        ))
    })
}

/// Rewrites the table without the failed lines of `ids`; returns how many were removed.
fn remove_failed_lines(out: &Path, ids: &HashSet<String>) -> Result<usize> {
    let t = read_table(out)?;
    let mut bytes = csv_line(&t.header)?;
    let mut removed = 0;
    for (_, rec) in &t.records {
        if rec[2] == *FAILED && ids.contains(&rec[0]) {
            removed += 1;
        } else {
            bytes.extend(csv_line(rec.iter())?);
        }
    }
    write_atomic(out, &bytes)?;
    Ok(removed)
}

/// What [`prepare_table`] found and did.
struct Prepared {
    /// The run ids already in the table, each with whether its run failed.
    present: HashMap<String, bool>,
    /// Bytes of an incomplete last line removed.
    truncated_bytes: u64,
    /// Response columns added to the table ([`with_added_responses`]).
    added_columns: Vec<String>,
}

/// Creates the table (header only) or checks an existing one against the plan, writes the
/// sidecar, and truncates an incomplete last line. A table that lacks only response columns the
/// experiment gained since it was written gets them (NaN in its runs). Nothing is modified when
/// the table belongs to another campaign.
fn prepare_table(experiment: &dyn Experiment, plan: &Plan, out: &Path) -> Result<Prepared> {
    let file = out.display().to_string();
    let columns = plan.columns();
    let mut present = HashMap::new();
    let exists = out.exists();
    let mut table = if exists { Some(read_table(out)?) } else { None };
    let mut added_columns = Vec::new();
    if let Some(t) = table.take() {
        let (t, added) = with_added_responses(experiment, t, &columns, &plan.responses);
        table = Some(t);
        added_columns = added;
    }
    if let Some(t) = &table {
        if t.header.is_empty() && t.partial_len > 0 {
            return Err(Error::input(
                &file,
                "header",
                "no complete header line: not a campaign table; choose another --out or \
                 remove the file",
            ));
        }
        // Before the header: another class usually means other columns too, and the class is
        // what the user has to change.
        let class = plan.model_class_label();
        let other_class = t.records.iter().find(|(_, rec)| {
            // `-`: an experiment without a contact law; the header tells that apart.
            rec.get(MODEL_CLASS_COLUMN)
                .is_some_and(|c| c != class && c != "-" && class != "-")
        });
        if let (Some((line, rec)), Some("model_class")) = (
            other_class,
            t.header.get(MODEL_CLASS_COLUMN).map(String::as_str),
        ) {
            let theirs = &rec[MODEL_CLASS_COLUMN];
            return Err(Error::input(
                &file,
                format!("line {line}, column model_class"),
                format!(
                    "run with the model class {theirs}, but this command asks for {class}: a \
                     campaign holds one class; pass --model-class {} to resume it, or choose \
                     another --out",
                    theirs.replace('+', ",")
                ),
            ));
        }
        if is_pre_class_header(&t.header) {
            return Err(Error::input(&file, "header", PRE_CLASS_TABLE));
        }
        let theirs_recorded = identity_len(&t.header) > FIXED_COLUMNS.len();
        let ours = plan.backend_field();
        if !t.header.is_empty() && theirs_recorded != ours.is_some() {
            return Err(Error::input(
                &file,
                "header",
                format!(
                    "a table of {}, but this command asks for --backend {}: one table holds \
                     the runs of one code; choose another --out",
                    if theirs_recorded {
                        "an external backend (its backend column)"
                    } else {
                        "the embedded engine (no backend column)"
                    },
                    plan.settings.backend
                ),
            ));
        }
        if let Some(ours) = &ours {
            for (line, rec) in &t.records {
                let theirs = rec.get(FIXED_COLUMNS.len()).unwrap_or("");
                if theirs != ours {
                    return Err(Error::input(
                        &file,
                        format!("line {line}, column backend"),
                        format!(
                            "run by {theirs}, but this command runs {ours} (--backend {}{}): \
                             LIGGGHTS repeats a run only on the same number of MPI processes, \
                             so a table holds one; pass the --mpi the table was made with \
                             (liggghts-npN: --mpi N), or choose another --out",
                            plan.settings.backend,
                            plan.settings
                                .mpi
                                .map(|n| format!(" --mpi {n}"))
                                .unwrap_or_default()
                        ),
                    ));
                }
            }
        }
        if !t.header.is_empty() && t.header != columns {
            return Err(header_mismatch(&file, &columns, &t.header));
        }
        let identity = plan.identity_len();
        for (line, rec) in &t.records {
            let field = || format!("line {line}");
            let row: usize = rec[1].parse().map_err(|_| {
                Error::input(
                    &file,
                    field(),
                    format!("row: expected a row number, found \"{}\"", &rec[1]),
                )
            })?;
            if rec[2] != *DONE && rec[2] != *FAILED {
                return Err(Error::input(
                    &file,
                    field(),
                    format!("status: expected done or failed, found \"{}\"", &rec[2]),
                ));
            }
            let Some(planned) = plan.rows.get(row) else {
                return Err(Error::input(
                    &file,
                    field(),
                    format!(
                        "row {row} is beyond the {} rows of {}: the table comes from another \
                         design; choose another --out",
                        plan.rows.len(),
                        plan.design.display()
                    ),
                ));
            };
            if planned.run_id != rec[0] {
                return Err(Error::input(
                    &file,
                    field(),
                    format!(
                        "row {row} has run_id {}, but {} on this design with this --seed, --set, \
                         --box-scale, --model-class, --rest-rule, --backend and --mpi gives {}: \
                         the table \
                         comes from another campaign (its <out>.meta.json says how it was run); \
                         choose another --out",
                        &rec[0], plan.experiment, planned.run_id
                    ),
                ));
            }
            // The run id is not recomputed from the line, so a hand-edited input would otherwise
            // pass as this campaign's run.
            for (k, (name, want)) in planned.params.iter().enumerate() {
                let field = &rec[identity + k];
                let same = field
                    .parse::<f64>()
                    .is_ok_and(|v| v.to_bits() == want.to_bits());
                if !same {
                    return Err(Error::input(
                        &file,
                        format!("line {line}, column {name}"),
                        format!(
                            "{want:?} as planned for row {row}, found \"{field}\": the line was \
                             edited or comes from another campaign; choose another --out"
                        ),
                    ));
                }
            }
            if rec[2] == *DONE {
                for (k, name) in plan.responses.iter().enumerate() {
                    let field = &rec[identity + plan.inputs.len() + k];
                    if field.parse::<f64>().is_err() {
                        return Err(Error::input(
                            &file,
                            format!("line {line}, column {name}"),
                            format!("a number for a done run, found \"{field}\""),
                        ));
                    }
                }
            }
            present.insert(rec[0].to_string(), rec[2] == *FAILED);
        }
    }
    if let (Some(t), Some(m)) = (&table, Meta::read(out)?) {
        let (theirs, ours) = (m.mpi.unwrap_or(1), plan.settings.mpi.unwrap_or(1));
        // Failed lines hold no result of either count.
        let done = t.records.iter().any(|(_, r)| r.get(2) == Some(DONE));
        if theirs != ours && done {
            return Err(Error::input(
                meta_path(out).display(),
                "mpi",
                format!(
                    "runs on {theirs} MPI process(es), but this command asks for {ours}: LIGGGHTS \
                     repeats a run only on the same count, so a table holds one; pass --mpi \
                     {theirs} to resume it, or choose another --out"
                ),
            ));
        }
    }
    Meta::of(plan).write(out)?;
    match &table {
        // Every check passed on the widened records: the table is this campaign's.
        Some(t) if !added_columns.is_empty() => {
            let mut bytes = csv_line(&t.header)?;
            for (_, rec) in &t.records {
                bytes.extend(csv_line(rec.iter())?);
            }
            write_atomic(out, &bytes)?;
        }
        Some(t) if !t.header.is_empty() => {
            if t.partial_len > 0 {
                let f = OpenOptions::new()
                    .write(true)
                    .open(out)
                    .map_err(|e| Error::io(out, e))?;
                f.set_len(t.complete_len)
                    .and_then(|()| f.sync_all())
                    .map_err(|e| Error::io(out, e))?;
            }
        }
        // New (or empty) table: the header appears whole or not at all.
        _ => write_atomic(out, &csv_line(&columns)?)?,
    }
    Ok(Prepared {
        present,
        truncated_bytes: table.map(|t| t.partial_len).unwrap_or(0),
        added_columns,
    })
}

/// The table with the response columns it lacks, when those are all it lacks: `columns`
/// without them is its header, in order. Each done run gets what its line tells of the value
/// ([`Experiment::backfill`]), else NaN (no value); a failed run empty cells. Returns the table
/// unchanged, and no names, otherwise.
fn with_added_responses(
    experiment: &dyn Experiment,
    mut t: Table,
    columns: &[String],
    responses: &[String],
) -> (Table, Vec<String>) {
    let missing: Vec<&String> = columns.iter().filter(|c| !t.header.contains(c)).collect();
    let only_responses = !missing.is_empty() && missing.iter().all(|c| responses.contains(c));
    let rest_in_order = columns
        .iter()
        .filter(|c| !missing.contains(c))
        .eq(t.header.iter());
    if t.header.is_empty() || !only_responses || !rest_in_order {
        return (t, Vec::new());
    }
    let header = t.header.clone();
    for (_, rec) in &mut t.records {
        let failed = rec.get(2) == Some(FAILED);
        let cell = |name: &str| {
            header
                .iter()
                .position(|h| h == name)
                .and_then(|k| rec.get(k))
                .map(str::to_string)
        };
        let mut old = rec.iter();
        let fields: Vec<String> = columns
            .iter()
            .map(|c| {
                if !missing.contains(&c) {
                    old.next().unwrap_or("").to_string()
                } else if failed {
                    // A failed run's response cells are empty.
                    String::new()
                } else {
                    experiment
                        .backfill(c, &cell)
                        .map_or_else(|| "NaN".to_string(), table::number)
                }
            })
            .collect();
        *rec = StringRecord::from(fields);
    }
    t.header = columns.to_vec();
    (t, missing.into_iter().cloned().collect())
}

fn header_mismatch(file: &str, want: &[String], found: &[String]) -> Error {
    let k = want
        .iter()
        .zip(found)
        .position(|(a, b)| a != b)
        .unwrap_or(want.len().min(found.len()));
    let at = |h: &[String]| h.get(k).map(|s| s.as_str()).unwrap_or("(none)").to_string();
    Error::input(
        file,
        "header",
        format!(
            "the table has other columns than this campaign (other experiment, design columns or \
             --set): column {} is {} in the file but {} here ({} vs {} columns); choose another \
             --out or remove the file",
            k + 1,
            at(found),
            at(want),
            found.len(),
            want.len()
        ),
    )
}

/// One run, its failures and panics included, as a table line.
fn execute(
    experiment: &dyn Experiment,
    plan: &Plan,
    run: &PlannedRun,
    campaign: &CampaignOptions,
) -> (Option<(String, String)>, bool, Result<Vec<u8>>) {
    let opts = RunOptions {
        vtk_dir: campaign.vtk_dir.as_ref().map(|d| d.join(&run.run_id)),
        picture: None,
        threads: 1,
        work_dir: campaign.work_dir.as_ref().map(|d| d.join(&run.run_id)),
    };
    let result: std::result::Result<Outcome, String> = match catch_unwind(AssertUnwindSafe(|| {
        experiment.run(&run.params, run.seed, &opts)
    })) {
        Ok(Ok(o)) => match plan.responses.iter().find(|r| o.get(r).is_none()) {
            None => Ok(o),
            Some(r) => Err(format!("the experiment returned no response {r}")),
        },
        Ok(Err(e)) => Err(e.to_string()),
        Err(payload) => Err(format!("panic: {}", panic_message(payload.as_ref()))),
    };
    let no_value = result.as_ref().is_ok_and(|o| {
        plan.responses
            .iter()
            .any(|r| o.get(r).is_some_and(f64::is_nan))
    });
    (
        result
            .as_ref()
            .err()
            .map(|e| (run.run_id.clone(), e.clone())),
        no_value,
        table::run_line(
            run,
            &plan.model_class_label(),
            plan.backend_field().as_deref(),
            &plan.responses,
            &result,
        ),
    )
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "(no message)".into()
    }
}

fn append(file: &mut File, path: &Path, line: &[u8]) -> Result<()> {
    // One write of the whole line, then to disk before the next: a crash leaves whole lines and
    // at most one incomplete last line.
    file.write_all(line)
        .and_then(|()| file.sync_data())
        .map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::plan::Shard;
    use crate::campaign::registry::sleep_test::SleepTest;
    use crate::campaign::registry::ExperimentSettings;

    /// The line of design row `row` in a table.
    fn line_of(t: &Table, row: &str) -> StringRecord {
        t.records
            .iter()
            .find(|(_, r)| &r[1] == row)
            .unwrap()
            .1
            .clone()
    }

    fn setup(design: &str, shard: Option<Shard>) -> (tempfile::TempDir, Plan, CampaignOptions) {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path().join("design.csv");
        std::fs::write(&d, design).unwrap();
        let plan = Plan::new(
            &SleepTest,
            &d,
            &[],
            1,
            &ExperimentSettings::default(),
            shard,
        )
        .unwrap();
        let opts = CampaignOptions::new(dir.path().join("out.csv"), 2);
        (dir, plan, opts)
    }

    #[test]
    fn failures_and_panics_become_failed_rows_and_resume_skips_everything() {
        let (_dir, plan, opts) =
            setup("x,y,fail,panic\n1,1,0,0\n2,1,1,0\n3,1,0,1\n4,1,0,0\n", None);
        let s = run_campaign(&SleepTest, &plan, &opts).unwrap();
        assert_eq!((s.planned, s.done, s.failed, s.skipped), (4, 2, 2, 0));
        let t = read_table(&opts.out).unwrap();
        let err = table::column(&t.header, "error").unwrap();
        let by_row = |row: &str| line_of(&t, row);
        assert_eq!(&by_row("1")[2], "failed");
        assert!(by_row("1")[err].contains(",\nsecond line"));
        assert_eq!(&by_row("2")[2], "failed");
        assert!(by_row("2")[err].starts_with("panic: sleep-test: panic on request"));
        assert_eq!(&by_row("3")[2], "done");

        let before = std::fs::read(&opts.out).unwrap();
        let s = run_campaign(&SleepTest, &plan, &opts).unwrap();
        assert_eq!((s.skipped, s.done, s.failed), (4, 0, 0));
        assert_eq!(std::fs::read(&opts.out).unwrap(), before);
    }

    /// A table written before the experiment recorded `noise` (the column cut out of every
    /// line, one run's line removed) gains the column with NaN in its runs; the run done now
    /// records it, and the first failure is named. A table that lacks a design column is
    /// another campaign's and stays as it is.
    #[test]
    fn a_table_without_a_response_the_experiment_gained_gets_the_column() {
        let (_dir, plan, opts) = setup("x,y,fail\n1,1,0\n2,1,1\n3,1,0\n", None);
        run_campaign(&SleepTest, &plan, &opts).unwrap();
        let full = read_table(&opts.out).unwrap();
        let noise = table::column(&full.header, "noise").unwrap();
        let cut = |keep: &dyn Fn(&StringRecord) -> bool, col: usize| {
            let drop_col = |r: &StringRecord| {
                r.iter()
                    .enumerate()
                    .filter(|(k, _)| *k != col)
                    .map(|(_, v)| v.to_string())
                    .collect::<Vec<_>>()
            };
            let mut bytes = csv_line(drop_col(&StringRecord::from(full.header.clone()))).unwrap();
            for (_, r) in full.records.iter().filter(|(_, r)| keep(r)) {
                bytes.extend(csv_line(drop_col(r)).unwrap());
            }
            bytes
        };
        std::fs::write(&opts.out, cut(&|r| &r[1] != "2", noise)).unwrap();
        let s = run_campaign(&SleepTest, &plan, &opts).unwrap();
        assert_eq!(s.added_columns, ["noise"]);
        let note = s.added_columns_note(&opts.out).unwrap();
        assert!(
            note.contains("column(s) noise") && note.contains("NaN"),
            "{note}"
        );
        assert_eq!((s.skipped, s.done, s.failed), (2, 1, 0));
        let t = read_table(&opts.out).unwrap();
        assert_eq!(t.header, full.header);
        let by_row = |row: &str| line_of(&t, row);
        assert_eq!(&by_row("0")[noise], "NaN");
        assert_eq!(&by_row("1")[noise], "");
        assert_eq!(&by_row("1")[2], "failed");
        let redone = full.records.iter().find(|(_, r)| &r[1] == "2").unwrap();
        assert_eq!(by_row("2")[noise], redone.1[noise]);
        let s = run_campaign(&SleepTest, &plan, &opts).unwrap();
        assert!(s.added_columns.is_empty() && s.skipped == 3);
        assert!(s.added_columns_note(&opts.out).is_none());

        let x = table::column(&full.header, "x").unwrap();
        let theirs = cut(&|_| true, x);
        std::fs::write(&opts.out, &theirs).unwrap();
        let e = run_campaign(&SleepTest, &plan, &opts)
            .unwrap_err()
            .to_string();
        assert!(e.contains("header") && e.contains("other columns"), "{e}");
        assert_eq!(std::fs::read(&opts.out).unwrap(), theirs);
    }

    #[test]
    fn a_failure_is_named_in_the_summary() {
        let (_dir, plan, opts) = setup("x,y,fail\n1,1,0\n2,1,1\n", None);
        let s = run_campaign(&SleepTest, &plan, &opts).unwrap();
        let (id, e) = s.first_failure.expect("a failure");
        assert_eq!(id, plan.rows[1].run_id);
        assert!(e.contains("second line"), "{e}");
    }

    #[test]
    fn an_incomplete_last_line_is_cut_and_its_run_redone() {
        let (_dir, plan, opts) = setup("x,y\n1,1\n2,1\n3,1\n", None);
        run_campaign(&SleepTest, &plan, &opts).unwrap();
        let full = std::fs::read(&opts.out).unwrap();
        let last_start = full[..full.len() - 1]
            .iter()
            .rposition(|&b| b == b'\n')
            .unwrap()
            + 1;
        std::fs::write(&opts.out, &full[..last_start + 7]).unwrap();
        let s = run_campaign(&SleepTest, &plan, &opts).unwrap();
        assert_eq!((s.truncated_bytes, s.skipped, s.done), (7, 2, 1));
        assert_eq!(std::fs::read(&opts.out).unwrap(), full);
    }

    #[test]
    fn a_cancelled_campaign_counts_the_rows_it_left() {
        let (_dir, plan, mut opts) = setup("x,y\n1,1\n2,1\n3,1\n", None);
        opts.cancel = Some(Arc::new(AtomicBool::new(true)));
        let s = run_campaign(&SleepTest, &plan, &opts).unwrap();
        assert_eq!((s.planned, s.done, s.cancelled), (3, 0, 3));
        assert_eq!(s.json(&plan, &opts.out)["cancelled"], 3);
        opts.cancel = None;
        let s = run_campaign(&SleepTest, &plan, &opts).unwrap();
        assert_eq!((s.done, s.cancelled), (3, 0));
    }

    #[test]
    fn shards_run_only_their_rows() {
        let (_dir, plan, opts) = setup(
            "x,y\n1,1\n2,1\n3,1\n4,1\n5,1\n",
            Some(Shard { index: 2, count: 2 }),
        );
        let s = run_campaign(&SleepTest, &plan, &opts).unwrap();
        assert_eq!((s.planned, s.done), (2, 2));
        let t = read_table(&opts.out).unwrap();
        let rows: HashSet<&str> = t.records.iter().map(|(_, r)| &r[1]).collect();
        assert_eq!(rows, HashSet::from(["1", "3"]));
    }
}
