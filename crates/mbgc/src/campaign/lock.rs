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
    /// The table's name as given, for messages.
    table: PathBuf,
    /// The table itself, locked too when it exists: a hard link elsewhere names the same file
    /// under another lock file.
    _table: Option<File>,
    path: PathBuf,
}

/// The table's own path with symlinks and `..` resolved (its folder's, when the table does not
/// exist yet), so that every name of one table leads to one lock file.
fn resolved(table: &Path) -> Result<PathBuf> {
    if table.exists() {
        return std::fs::canonicalize(table).map_err(|e| Error::io(table, e));
    }
    let name = table
        .file_name()
        .ok_or_else(|| Error::invalid(format!("{}: not a file path", table.display())))?;
    match table.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) if dir.exists() => Ok(std::fs::canonicalize(dir)
            .map_err(|e| Error::io(dir, e))?
            .join(name)),
        _ => Ok(table.to_path_buf()),
    }
}

/// Whether an open file and a path's metadata are one file (same device and inode).
#[cfg(unix)]
fn same_file(held: &File, now: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    held.metadata()
        .is_ok_and(|m| m.dev() == now.dev() && m.ino() == now.ino())
}

#[cfg(not(unix))]
fn same_file(_: &File, _: &std::fs::Metadata) -> bool {
    false
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
        // A device, a FIFO or a directory is no table: reading it would never end or block.
        if let Ok(meta) = std::fs::metadata(table) {
            if !meta.is_file() {
                return Err(Error::invalid(format!(
                    "{}: exists and is not a regular file: expected a campaign table (a CSV \
                     file) to create or resume",
                    table.display()
                )));
            }
        }
        let path = lock_path(&resolved(table)?);
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        let file = OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .map_err(|e| Error::io(&path, e))?;
        let busy = |path: &Path| {
            Error::invalid(format!(
                "{}: another mbgc process is writing this table (it holds {}); wait for it to \
                 finish, or give this run another --out (shards: one table each, then `mbgc \
                 campaign merge`)",
                table.display(),
                path.display()
            ))
        };
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => return Err(busy(&path)),
            Err(TryLockError::Error(e)) => return Err(Error::io(&path, e)),
        }
        let mut lock = TableLock {
            _file: file,
            table: table.to_path_buf(),
            _table: None,
            path,
        };
        lock.hold_table()?;
        Ok(lock)
    }

    /// Locks the file the table's name leads to now. A writer calls it again once it has
    /// created the table or replaced it by a rename: a hard link made to the new file (another
    /// name, hence another lock file) must still meet this lock.
    pub fn hold_table(&mut self) -> Result<()> {
        let table = self.table.as_path();
        // A second lock on the file already held would conflict with our own (flock locks
        // belong to the open file); a file replaced by a rename is a new one to lock.
        if let (Some(held), Ok(now)) = (&self._table, std::fs::metadata(table)) {
            if same_file(held, &now) {
                return Ok(());
            }
        }
        self._table = None;
        self._table = match OpenOptions::new().read(true).open(table) {
            Ok(f) => {
                match f.try_lock() {
                    Ok(()) => {}
                    Err(TryLockError::WouldBlock) => {
                        return Err(Error::invalid(format!(
                            "{}: another mbgc process is writing this table (through another \
                             name of the same file); wait for it to finish, or give this run \
                             another --out",
                            table.display()
                        )))
                    }
                    Err(TryLockError::Error(e)) => return Err(Error::io(table, e)),
                }
                Some(f)
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(e) => return Err(Error::io(table, e)),
        };
        Ok(())
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

    /// Another name of the same table (a symlink, a hard link, a path through `..`) is the
    /// same table: its writer is refused too.
    #[test]
    fn every_name_of_a_table_shares_its_lock() {
        let dir = tempfile::tempdir().unwrap();
        let table = dir.path().join("run.csv");
        std::fs::write(&table, "run_id\n").unwrap();
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        let first = TableLock::acquire(&table).unwrap();
        let soft = dir.path().join("soft.csv");
        std::os::unix::fs::symlink(&table, &soft).unwrap();
        let hard = sub.join("hard.csv");
        std::fs::hard_link(&table, &hard).unwrap();
        for other in [soft, hard, sub.join("../run.csv")] {
            let e = TableLock::acquire(&other).unwrap_err().to_string();
            assert!(
                e.contains("another mbgc process"),
                "{}: {e}",
                other.display()
            );
        }
        drop(first);
        TableLock::acquire(&sub.join("hard.csv")).unwrap();
    }

    /// A table created (or replaced by a rename) after the lock was taken: a hard link to the
    /// new file meets the lock once the writer holds the table again.
    #[test]
    fn a_table_made_after_the_lock_is_held_too() {
        let dir = tempfile::tempdir().unwrap();
        let table = dir.path().join("run.csv");
        let mut first = TableLock::acquire(&table).unwrap();
        std::fs::write(&table, "run_id\n").unwrap();
        first.hold_table().unwrap();
        let hard = dir.path().join("hard.csv");
        std::fs::hard_link(&table, &hard).unwrap();
        let e = TableLock::acquire(&hard).unwrap_err().to_string();
        assert!(e.contains("another mbgc process"), "{e}");
        // Replaced by a rename: the new file is held once the writer says so.
        let tmp = dir.path().join("tmp.csv");
        std::fs::write(&tmp, "run_id\n").unwrap();
        std::fs::rename(&tmp, &table).unwrap();
        first.hold_table().unwrap();
        let hard2 = dir.path().join("hard2.csv");
        std::fs::hard_link(&table, &hard2).unwrap();
        assert!(TableLock::acquire(&hard2).is_err());
        drop(first);
        TableLock::acquire(&hard2).unwrap();
    }

    #[test]
    fn a_device_or_a_fifo_is_no_table() {
        for target in ["/dev/full", "/dev/null"] {
            let e = TableLock::acquire(Path::new(target))
                .unwrap_err()
                .to_string();
            assert!(e.contains("not a regular file"), "{e}");
        }
        assert!(!Path::new("/dev/full.lock").exists());
    }
}
