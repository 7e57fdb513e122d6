//! `simulate`: a calibration experiment for every row of a design, into a campaign table that a
//! repeated call resumes, as `mbgc simulate --out` runs it (src/simulate.rs): the same checks,
//! plan, table and sidecar, so the command line can resume what Python started and the other
//! way round. The DEM runs without the GIL; progress is reported to a Python callable.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use pyo3::prelude::*;

use mbgc::campaign::{
    experiment_by_name, parse_set, run_campaign, worker_threads, Backend, CampaignOptions,
    ExperimentSettings, Observer, ObserverHandle, Plan, Shard,
};
use mbgc::dem::contact::ModelClass;

use crate::errors::{invalid, to_py, OrRaise};

/// Tells a Python callable `progress(done, total)` of each run recorded, from the thread that
/// writes the table; the first exception it raises is kept and raised after the campaign (the
/// campaign itself goes on: its runs are worth keeping).
struct Callback {
    progress: Py<PyAny>,
    total: AtomicUsize,
    done: AtomicUsize,
    error: Mutex<Option<PyErr>>,
}

impl Callback {
    fn call(&self) {
        let (done, total) = (
            self.done.load(Ordering::SeqCst),
            self.total.load(Ordering::SeqCst),
        );
        let mut error = self.error.lock().unwrap_or_else(|e| e.into_inner());
        if error.is_some() {
            return;
        }
        if let Err(e) = Python::attach(|py| self.progress.call1(py, (done, total)).map(drop)) {
            *error = Some(e);
        }
    }
}

impl Observer for Callback {
    fn started(&self, to_run: usize, _already_done: usize) {
        self.total.store(to_run, Ordering::SeqCst);
        self.call();
    }

    fn run_recorded(&self, _failed: bool) {
        self.done.fetch_add(1, Ordering::SeqCst);
        self.call();
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
            error: Mutex::new(None),
        })
    });
    let opts = CampaignOptions {
        vtk_dir: vtk,
        observer: callback
            .as_ref()
            .map(|c| ObserverHandle::new(Shared(Arc::clone(c)))),
        retry_failed,
        ..CampaignOptions::new(out.clone(), threads)
    };
    let s = py
        .detach(|| run_campaign(experiment.as_ref(), &plan, &opts))
        .map_err(|e| to_py(py, e))?;
    if let Some(e) = callback.and_then(|c| c.error.lock().ok().and_then(|mut e| e.take())) {
        return Err(e);
    }
    Ok(s.json(&plan, &out).to_string())
}
