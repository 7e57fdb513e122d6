//! The columns of a campaign table: `run_id,row,status,seed,model_class`, `backend` when the
//! runs are not the embedded engine's, the inputs, the responses, then the diagnostics. The plan
//! names them before anything runs; the table writes and reads them.

use super::backend::Backend;

/// The identity columns every campaign table starts with, in this order.
pub const FIXED_COLUMNS: [&str; 5] = ["run_id", "row", "status", "seed", "model_class"];
/// Where the model class is among [`FIXED_COLUMNS`].
pub const MODEL_CLASS_COLUMN: usize = 4;
/// The diagnostic columns every campaign table ends with, in this order: whether the run reached
/// its stop criterion, its steps, particles, wall time (s), warnings and error message.
pub const DIAGNOSTIC_COLUMNS: [&str; 6] = [
    "settled",
    "steps",
    "particles",
    "wall_time_s",
    "warnings",
    "error",
];
/// The one column that legitimately differs between two executions of the same run.
pub const WALL_TIME_COLUMN: &str = "wall_time_s";

/// `status` of a run that finished and has its responses.
pub const DONE: &str = "done";
/// `status` of a run that ended in an error (given in the `error` column); resume retries it.
pub const FAILED: &str = "failed";

/// The column naming the backend, after the fixed ones, in tables of an external backend only
/// (tables without it are the embedded engine's, as every table written before it existed).
pub const BACKEND_COLUMN: &str = "backend";

/// The full header of a campaign table for these inputs and responses.
pub fn columns(inputs: &[String], responses: &[String], backend: Backend) -> Vec<String> {
    FIXED_COLUMNS
        .iter()
        .map(|s| s.to_string())
        .chain(backend.is_recorded().then(|| BACKEND_COLUMN.to_string()))
        .chain(inputs.iter().cloned())
        .chain(responses.iter().cloned())
        .chain(DIAGNOSTIC_COLUMNS.iter().map(|s| s.to_string()))
        .collect()
}

/// Whether a header is a campaign table's (fixed columns first, diagnostics last).
pub fn is_campaign_header(header: &[String]) -> bool {
    let n = header.len();
    n >= FIXED_COLUMNS.len() + DIAGNOSTIC_COLUMNS.len()
        && header[..FIXED_COLUMNS.len()]
            .iter()
            .zip(FIXED_COLUMNS)
            .all(|(a, b)| a == b)
        && header[n - DIAGNOSTIC_COLUMNS.len()..]
            .iter()
            .zip(DIAGNOSTIC_COLUMNS)
            .all(|(a, b)| a == b)
}

/// The identity columns a header starts with: the fixed ones, and `backend` if it has it.
pub fn identity_len(header: &[String]) -> usize {
    let n = FIXED_COLUMNS.len();
    n + usize::from(header.get(n).is_some_and(|h| h == BACKEND_COLUMN))
}

/// The backend of a table's lines, from its header and a line.
pub fn backend_of(header: &[String], record: &csv::StringRecord) -> Option<String> {
    (identity_len(header) > FIXED_COLUMNS.len())
        .then(|| record.get(FIXED_COLUMNS.len()).unwrap_or("").to_string())
}

/// Whether a header is a campaign table's from before model classes (no `model_class` column).
pub fn is_pre_class_header(header: &[String]) -> bool {
    header.len() > 4
        && header[..4]
            .iter()
            .zip(&FIXED_COLUMNS[..4])
            .all(|(a, b)| a == b)
        && header[4] != FIXED_COLUMNS[MODEL_CLASS_COLUMN]
}

/// What to do with a table from before model classes.
pub const PRE_CLASS_TABLE: &str = "written by an mbgc from before model classes (no model_class \
     column after seed); add that column holding the class its runs used (hertz+mindlin+epsd2 \
     for shear-box and hopper, hertz+mindlin for wall-impact, whose old version had no rolling \
     resistance), then resume, merge or fit it";
