//! Who is told how a campaign is going: a progress bar in the command line, a log line in a
//! cluster job, a callback in Python. The campaign reports; the observer decides what to show.

use std::sync::Arc;

/// Told of a campaign's progress, from the thread that writes the table (one call at a time).
pub trait Observer: Send + Sync {
    /// The runs to make now, and the rows of the shard already in the table.
    fn started(&self, _to_run: usize, _already_done: usize) {}
    /// One run's line is in the table (`failed`: recorded as a failed run).
    fn run_recorded(&self, _failed: bool) {}
    /// The campaign stopped: `completed` is false when a write error ended it early.
    fn ended(&self, _completed: bool) {}
}

/// An observer as an option field: cloneable and printable, like the rest of the options.
#[derive(Clone)]
pub struct ObserverHandle(pub Arc<dyn Observer>);

impl ObserverHandle {
    /// Wraps an observer.
    pub fn new(observer: impl Observer + 'static) -> Self {
        ObserverHandle(Arc::new(observer))
    }
}

impl std::fmt::Debug for ObserverHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ObserverHandle(..)")
    }
}
