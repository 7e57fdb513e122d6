//! One writer per campaign table: an advisory lock on `<table>.lock`, held for the whole run.
//! The lock lives beside the table rather than on it because a new table is created by an
//! atomic rename, which would leave a lock on the old file. The operating system releases the
//! lock when the process ends, however it ends, so a crash never leaves a table locked.

use std::fs::{File, OpenOptions, TryLockError};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Held while a process writes the table; dropping it releases the lock.
#[derive(Debug)]
pub struct TableLock {
    _file: File,
    path: PathBuf,
}

/// The lock file of a table: `<table>.lock`.
pub fn lock_path(table: &Path) -> PathBuf {
    let mut name = table.file_name().unwrap_or_default().to_os_string();
    name.push(".lock");
    table.with_file_name(name)
}

impl TableLock {
    /// Takes the lock of `table`, or fails at once (never waits) when another process holds it.
    pub fn acquire(table: &Path) -> Result<TableLock> {
        let path = lock_path(table);
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        let file = OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .map_err(|e| Error::io(&path, e))?;
        match file.try_lock() {
            Ok(()) => Ok(TableLock { _file: file, path }),
            Err(TryLockError::WouldBlock) => Err(Error::invalid(format!(
                "{}: another mbgc process is writing this table (it holds {}); wait for it to \
                 finish, or give this run another --out (shards: one table each, then `mbgc \
                 campaign merge`)",
                table.display(),
                path.display()
            ))),
            Err(TryLockError::Error(e)) => Err(Error::io(&path, e)),
        }
    }

    /// The lock file held, next to the table.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_writer_is_refused_until_the_first_lets_go() {
        let dir = tempfile::tempdir().unwrap();
        let table = dir.path().join("run.csv");
        let first = TableLock::acquire(&table).unwrap();
        assert_eq!(first.path(), dir.path().join("run.csv.lock"));
        let e = TableLock::acquire(&table).unwrap_err().to_string();
        assert!(
            e.contains("another mbgc process") && e.contains("run.csv"),
            "{e}"
        );
        drop(first);
        TableLock::acquire(&table).unwrap();
    }
}
