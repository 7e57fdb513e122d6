//! `simulate`: a calibration experiment for every row of a design, into a campaign table that a
//! repeated call resumes, as `mbgc simulate --out` runs it (src/simulate.rs): the same checks,
//! plan, table and sidecar, so the command line can resume what Python started and the other
//! way round. The DEM runs without the GIL; progress is reported to a Python callable; a Ctrl-C
//! (KeyboardInterrupt) stops it after the runs in flight, which are recorded for the next call.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use pyo3::exceptions::PyKeyboardInterrupt;
use pyo3::prelude::*;

use mbgc::campaign::{
    experiment_by_name, parse_set, run_campaign, worker_threads, Backend, CampaignOptions,
    ExperimentSettings, Observer, ObserverHandle, Plan, Shard,
};
use mbgc::dem::contact::ModelClass;

use crate::errors::{invalid, to_py, OrRaise};

/// Counts the runs for a Python callable `progress(done, total)`. The campaign's thread only
/// queues the counts; the calling thread, which polls for signals anyway, makes the calls with
/// the GIL, in order. The first exception the callable raises is kept and raised after the
/// campaign (the campaign itself goes on: its runs are worth keeping).
struct Callback {
    progress: Py<PyAny>,
    total: AtomicUsize,
    done: AtomicUsize,
    queued: Mutex<Vec<(usize, usize)>>,
    error: Mutex<Option<PyErr>>,
}

impl Callback {
    fn queue(&self) {
        let counts = (
            self.done.load(Ordering::SeqCst),
            self.total.load(Ordering::SeqCst),
        );
        self.queued
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(counts);
    }

    /// The callable raised a KeyboardInterrupt.
    fn interrupted(&self, py: Python<'_>) -> bool {
        self.error
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .as_ref()
            .is_some_and(|e| e.is_instance_of::<PyKeyboardInterrupt>(py))
    }

    /// Calls the callable with every queued count; the caller holds the GIL.
    fn call_queued(&self, py: Python<'_>) {
        let queued = std::mem::take(&mut *self.queued.lock().unwrap_or_else(|e| e.into_inner()));
        let mut error = self.error.lock().unwrap_or_else(|e| e.into_inner());
        for (done, total) in queued {
            if error.is_some() {
                return;
            }
            if let Err(e) = self.progress.call1(py, (done, total)) {
                *error = Some(e);
            }
        }
    }
}

impl Observer for Callback {
    fn started(&self, to_run: usize, _already_done: usize) {
        self.total.store(to_run, Ordering::SeqCst);
        self.queue();
    }

    fn run_recorded(&self, _failed: bool) {
        self.done.fetch_add(1, Ordering::SeqCst);
        self.queue();
    }
}

/// Shares the callback between the campaign (which owns its observer) and this call (which
/// raises what the callback raised).
struct Shared(Arc<Callback>);

impl Observer for Shared {
    fn started(&self, to_run: usize, already_done: usize) {
        self.0.started(to_run, already_done);
    }

    fn run_recorded(&self, failed: bool) {
        self.0.run_recorded(failed);
    }
}

/// Runs `experiment` on every row of the design file (of this shard) that the table `out`
/// does not hold yet; returns the summary as `--json` prints it.
#[pyfunction]
#[pyo3(signature = (design, experiment, out, set, seed, threads, shard, model_class, box_scale, backend, mpi, retry_failed, vtk, progress))]
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    py: Python<'_>,
    design: PathBuf,
    experiment: &str,
    out: PathBuf,
    set: Vec<(String, f64)>,
    seed: u64,
    threads: Option<usize>,
    shard: Option<String>,
    model_class: Option<String>,
    box_scale: Option<f64>,
    backend: &str,
    mpi: Option<usize>,
    retry_failed: bool,
    vtk: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    mbgc::outputs::refuse_overwriting_inputs("--out", &out, &[("--design", &design)])
        .or_raise(py)?;
    let backend = Backend::parse(backend).or_raise(py)?;
    let model_class = model_class
        .as_deref()
        .map(ModelClass::parse)
        .transpose()
        .map_err(|e| invalid(py, format!("--model-class: {e}")))?;
    let settings = ExperimentSettings {
        box_scale,
        model_class,
        backend,
        mpi,
        ..Default::default()
    };
    if let (Backend::Liggghts, Some(v)) = (backend, &vtk) {
        return Err(invalid(
            py,
            format!(
                "--vtk {}: the LIGGGHTS backend writes no VTK snapshots, so it would do nothing",
                v.display()
            ),
        ));
    }
    let experiment = experiment_by_name(experiment, &settings).or_raise(py)?;
    if backend == Backend::Liggghts {
        // Checked before the table is touched: otherwise every row would become a failed line.
        mbgc::liggghts::require_binary().or_raise(py)?;
        if mpi.unwrap_or(1) > 1 {
            mbgc::liggghts::require_mpirun().or_raise(py)?;
        }
    }
    let shard = shard
        .as_deref()
        .map(Shard::parse)
        .transpose()
        .or_raise(py)?;
    // `--set NAME=VALUE` as the command line reads it: the same checks and messages. `{v:?}`
    // prints the shortest text that reads back as the same number.
    let set = set
        .iter()
        .map(|(k, v)| parse_set(&format!("{k}={v:?}")))
        .collect::<mbgc::Result<Vec<_>>>()
        .or_raise(py)?;
    let threads = worker_threads(threads, mpi).or_raise(py)?;
    let plan =
        Plan::new(experiment.as_ref(), &design, &set, seed, &settings, shard).or_raise(py)?;
    let callback = progress.map(|p| {
        Arc::new(Callback {
            progress: p,
            total: AtomicUsize::new(0),
            done: AtomicUsize::new(0),
            queued: Mutex::new(Vec::new()),
            error: Mutex::new(None),
        })
    });
    let opts = CampaignOptions {
        vtk_dir: vtk,
        observer: callback
            .as_ref()
            .map(|c| ObserverHandle::new(Shared(Arc::clone(c)))),
        retry_failed,
        cancel: Some(Arc::new(AtomicBool::new(false))),
        ..CampaignOptions::new(out.clone(), threads)
    };
    // The campaign runs on its own thread while this one wakes every 50 ms to call `progress`
    // and to let Python handle signals: a Ctrl-C stops the campaign after the runs in flight,
    // which are recorded.
    let cancel = Arc::clone(opts.cancel.as_ref().expect("set above"));
    let outcome = std::thread::scope(|scope| {
        let worker = scope.spawn(|| run_campaign(experiment.as_ref(), &plan, &opts));
        let mut interrupted = None;
        loop {
            let finished = worker.is_finished();
            if let Some(c) = &callback {
                c.call_queued(py);
                // A Ctrl-C that lands while the callable runs is raised there: it stops the
                // campaign all the same.
                if c.interrupted(py) {
                    cancel.store(true, Ordering::SeqCst);
                }
            }
            if finished {
                // A Ctrl-C that came after the last poll (the callable's calls above may be
                // where it landed, between two of them) is raised, not lost.
                if interrupted.is_none() {
                    interrupted = py.check_signals().err();
                }
                break;
            }
            py.detach(|| std::thread::sleep(Duration::from_millis(50)));
            if interrupted.is_none() {
                if let Err(e) = py.check_signals() {
                    cancel.store(true, Ordering::SeqCst);
                    interrupted = Some(e);
                }
            }
        }
        let result = worker.join();
        (result, interrupted)
    });
    let (result, interrupted) = outcome;
    // The campaign's own error says more than the interrupt that came while it failed.
    let s = match result {
        Ok(r) => r.map_err(|e| to_py(py, e))?,
        Err(panic) => std::panic::resume_unwind(panic),
    };
    if let Some(e) = interrupted {
        return Err(e);
    }
    if let Some(e) = callback.and_then(|c| c.error.lock().ok().and_then(|mut e| e.take())) {
        return Err(e);
    }
    Ok(s.json(&plan, &out).to_string())
}
