//! Online backup and restore of a data directory's database.
//!
//! **Backup** (`vsculpt-server backup --data DIR OUT`) works while a server
//! runs on DIR. A second SQLite connection opens one read transaction and
//! keeps it for the whole copy: under WAL that is one snapshot — every
//! transaction committed before it began, nothing half-written — and a reader
//! never blocks the writer. SQLite's online backup API copies that snapshot
//! in slices of [`SLICE_PAGES`] pages; after each slice the copy is synced
//! (`fdatasync`) and the copier pauses for [`SLICE_PAUSE`]. Because the read
//! transaction stays open, a commit by the server between two slices does not
//! restart the copy (SQLite restarts a stepped backup only when the source
//! connection starts a new read transaction and finds the file changed), so a
//! studio committing at full rate cannot starve it. The pacing is what keeps
//! editors going: a one-shot copy (`VACUUM INTO`) leaves ~100 MB of dirty
//! pages in the OS cache, and every commit's `fsync` then queues behind their
//! writeback (commit → ack p99 25 → 171 ms in `benches/backup_pause.rs`);
//! synced slices keep that backlog to one slice. The copy is written next to
//! OUT, checked with `PRAGMA integrity_check`, synced and renamed into place;
//! an existing OUT is refused unless `force`.
//!
//! **Restore** (`vsculpt-server restore --data DIR BACKUP`) takes DIR's
//! ownership lock (so it refuses while a server runs there), checks the
//! backup, and replaces `DIR/vsculpt.db` with a copy of it (the old WAL and
//! shared-memory files are removed: they belong to the old database). An
//! existing database is refused unless `force`. The design tokens live in the
//! database and come back with it; `DIR/admin-token` is DIR's own.

use super::lock::{DataDirLock, LockError};
use rusqlite::backup::{Backup, StepResult};
use rusqlite::{Connection, OpenFlags};
use std::path::{Path, PathBuf};
use std::time::Duration;
use thiserror::Error;

/// Pages copied per slice of a backup (1 MiB at SQLite's default 4 KiB page):
/// the most dirty data a backup leaves for the OS to write back at once.
pub const SLICE_PAGES: i32 = 256;

/// Pause after each synced slice, leaving the disk to the server's commits.
pub const SLICE_PAUSE: Duration = Duration::from_millis(2);

/// The database file's name inside the data directory.
pub const DB_FILE: &str = "vsculpt.db";

/// Why a backup or restore failed (nothing was overwritten).
#[derive(Debug, Error)]
pub enum BackupError {
    /// The target exists and `force` was not given.
    #[error("{} exists; give --force to overwrite it", .0.display())]
    Exists(PathBuf),
    /// The source database is missing.
    #[error("no database at {}", .0.display())]
    Missing(PathBuf),
    /// The copy failed its integrity check.
    #[error("{} is damaged: {reason}", path.display())]
    Damaged {
        /// The file.
        path: PathBuf,
        /// What the check said.
        reason: String,
    },
    /// A server owns the data directory.
    #[error("{0}")]
    Locked(#[from] LockError),
    /// SQLite failed.
    #[error("database: {0}")]
    Sqlite(#[from] rusqlite::Error),
    /// A file operation failed.
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// What a backup or restore copied.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Copied {
    /// Live designs.
    pub designs: u64,
    /// Committed versions (of all designs).
    pub versions: u64,
}

fn sibling(path: &Path, suffix: &str) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(suffix);
    path.with_file_name(name)
}

/// Checks `db` with `PRAGMA integrity_check` and counts what it holds.
pub fn verify(db: &Path) -> Result<Copied, BackupError> {
    let conn = Connection::open_with_flags(db, OpenFlags::SQLITE_OPEN_READ_ONLY)?;
    let check: String = conn.query_row("PRAGMA integrity_check", [], |r| r.get(0))?;
    if check != "ok" {
        return Err(BackupError::Damaged {
            path: db.to_path_buf(),
            reason: check,
        });
    }
    let count = |sql: &str| -> Result<u64, BackupError> {
        Ok(conn
            .query_row(sql, [], |r| r.get::<_, i64>(0))
            .map_err(|e| BackupError::Damaged {
                path: db.to_path_buf(),
                reason: e.to_string(),
            })? as u64)
    };
    Ok(Copied {
        designs: count("SELECT COUNT(*) FROM designs WHERE deleted = 0")?,
        versions: count("SELECT COUNT(*) FROM versions")?,
    })
}

fn sync_file(path: &Path) -> std::io::Result<()> {
    std::fs::File::open(path)?.sync_all()
}

fn sync_dir(path: &Path) {
    // Makes the rename durable where the platform allows opening a directory.
    if let Some(dir) = path.parent()
        && let Ok(d) = std::fs::File::open(if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        })
    {
        let _ = d.sync_all();
    }
}

/// Copies the database of `data_dir` (a server may be running on it) into
/// `out` as one consistent snapshot, in paced slices (see the module doc).
pub fn backup(data_dir: &Path, out: &Path, force: bool) -> Result<Copied, BackupError> {
    let db = data_dir.join(DB_FILE);
    if !db.is_file() {
        return Err(BackupError::Missing(db));
    }
    if out.exists() && !force {
        return Err(BackupError::Exists(out.to_path_buf()));
    }
    let partial = sibling(out, ".partial");
    let _ = std::fs::remove_file(&partial);
    let result = (|| {
        copy_snapshot(&db, &partial, SLICE_PAGES, SLICE_PAUSE, |_| {})?;
        let copied = verify(&partial)?;
        sync_file(&partial)?;
        if out.exists() && !force {
            return Err(BackupError::Exists(out.to_path_buf()));
        }
        std::fs::rename(&partial, out)?;
        sync_dir(out);
        Ok(copied)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    result
}

/// Copies the database `db` into the new file `dest` as the snapshot of one
/// read transaction held for the whole copy: `slice` pages at a time, each
/// slice synced to disk before a `pause`. `after_slice` runs after every
/// slice (with the pages still to copy), outside any lock a writer needs.
/// Returns the number of slices.
pub fn copy_snapshot(
    db: &Path,
    dest: &Path,
    slice: i32,
    pause: Duration,
    mut after_slice: impl FnMut(i32),
) -> Result<u64, BackupError> {
    let src = Connection::open_with_flags(db, OpenFlags::SQLITE_OPEN_READ_WRITE)?;
    src.busy_timeout(Duration::from_secs(10))?;
    // The snapshot: a read transaction opened now and kept until the copy is
    // done, so commits meanwhile neither show in the copy nor restart it.
    src.execute_batch("BEGIN")?;
    src.query_row("SELECT COUNT(*) FROM sqlite_master", [], |r| {
        r.get::<_, i64>(0)
    })?;
    let mut dst = Connection::open(dest)?;
    // The copy is worthless until it is complete and renamed into place: no
    // journal, and syncing is done here, slice by slice.
    dst.execute_batch("PRAGMA journal_mode = OFF; PRAGMA synchronous = OFF;")?;
    let file = std::fs::OpenOptions::new().write(true).open(dest)?;
    let mut slices = 0;
    {
        let copy = Backup::new(&src, &mut dst)?;
        loop {
            let step = copy.step(slice.max(1))?;
            file.sync_data()?;
            slices += 1;
            after_slice(copy.progress().remaining);
            match step {
                StepResult::Done => break,
                // More, or a lock held elsewhere for a moment: go on after the pause.
                _ => std::thread::sleep(pause),
            }
        }
    }
    src.execute_batch("COMMIT")?;
    // The source is in WAL mode and the copy took its header; a backup file is
    // a plain rollback-journal database that opens read-only anywhere.
    dst.pragma_update(None, "journal_mode", "DELETE")?;
    drop(dst);
    file.sync_data()?;
    Ok(slices)
}

/// Makes `backup_file` the database of `data_dir`; refuses while a server
/// owns `data_dir`, and over an existing database unless `force`.
pub fn restore(backup_file: &Path, data_dir: &Path, force: bool) -> Result<Copied, BackupError> {
    if !backup_file.is_file() {
        return Err(BackupError::Missing(backup_file.to_path_buf()));
    }
    let copied = verify(backup_file)?;
    let _lock = DataDirLock::acquire(data_dir)?;
    let db = data_dir.join(DB_FILE);
    if db.exists() && !force {
        return Err(BackupError::Exists(db));
    }
    let incoming = sibling(&db, ".restoring");
    let result = (|| {
        std::fs::copy(backup_file, &incoming)?;
        sync_file(&incoming)?;
        verify(&incoming)?;
        for stale in ["-wal", "-shm"] {
            match std::fs::remove_file(sibling(&db, stale)) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(e.into()),
                _ => {}
            }
        }
        std::fs::rename(&incoming, &db)?;
        sync_dir(&db);
        Ok(copied)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&incoming);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A WAL database of `rows` rows of 4 KiB each, and a second connection
    /// to write to it as a server would.
    fn studio(dir: &Path, rows: i64) -> (PathBuf, Connection) {
        let db = dir.join(DB_FILE);
        let w = Connection::open(&db).unwrap();
        w.pragma_update(None, "journal_mode", "WAL").unwrap();
        w.execute_batch("CREATE TABLE t (k INTEGER PRIMARY KEY, v BLOB NOT NULL)")
            .unwrap();
        for k in 0..rows {
            w.execute("INSERT INTO t (k, v) VALUES (?1, zeroblob(4000))", [k])
                .unwrap();
        }
        (db, w)
    }

    /// Commits from another connection between every two slices (a studio
    /// committing at full rate) neither restart the copy — the pages still to
    /// copy only ever go down, one slice at a time — nor show in it: the copy
    /// is the snapshot the backup began with.
    #[test]
    fn commits_between_slices_neither_restart_nor_leak_into_the_copy() {
        let dir = tempfile::tempdir().unwrap();
        let (db, writer) = studio(dir.path(), 300);
        let pages: i64 = writer
            .query_row("PRAGMA page_count", [], |r| r.get(0))
            .unwrap();
        let dest = dir.path().join("copy.db");
        let mut remaining = Vec::new();
        let mut next = 300;
        let slices = copy_snapshot(&db, &dest, 8, Duration::ZERO, |left| {
            remaining.push(left);
            // A bounded number of writes, so a copy that restarts still ends.
            if remaining.len() < 200 {
                writer
                    .execute("INSERT INTO t (k, v) VALUES (?1, zeroblob(4000))", [next])
                    .unwrap();
                writer
                    .execute("DELETE FROM t WHERE k = ?1", [next - 300])
                    .unwrap();
                next += 1;
            }
        })
        .unwrap();
        assert!(
            remaining.windows(2).all(|w| w[1] < w[0]),
            "the copy restarted: {remaining:?}"
        );
        assert_eq!(slices as i64, (pages + 7) / 8, "{remaining:?}");
        assert!(next > 300 + 10, "the writer was not kept going");
        let copy = Connection::open_with_flags(&dest, OpenFlags::SQLITE_OPEN_READ_ONLY).unwrap();
        let check: String = copy
            .query_row("PRAGMA integrity_check", [], |r| r.get(0))
            .unwrap();
        assert_eq!(check, "ok");
        let (n, lo, hi): (i64, i64, i64) = copy
            .query_row("SELECT COUNT(*), MIN(k), MAX(k) FROM t", [], |r| {
                Ok((r.get(0)?, r.get(1)?, r.get(2)?))
            })
            .unwrap();
        assert_eq!((n, lo, hi), (300, 0, 299));
        let mode: String = copy
            .query_row("PRAGMA journal_mode", [], |r| r.get(0))
            .unwrap();
        assert_eq!(mode, "delete");
        // the studio itself has moved on
        let live: i64 = writer
            .query_row("SELECT MIN(k) FROM t", [], |r| r.get(0))
            .unwrap();
        assert_eq!(live, next - 300);
    }
}
