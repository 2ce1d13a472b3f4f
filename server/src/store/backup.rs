//! Online backup and restore of a data directory's database.
//!
//! **Backup** (`vsculpt-server backup --data DIR OUT`) works while a server
//! runs on DIR: a second SQLite connection runs `VACUUM INTO`, which copies
//! one read transaction's snapshot — every transaction committed before it
//! began, nothing half-written — into a fresh, compact file. Under WAL a
//! reader never blocks the writer, so editors are not stopped. The copy is
//! written next to OUT, checked with `PRAGMA integrity_check`, synced and
//! renamed into place; an existing OUT is refused unless `force`.
//!
//! **Restore** (`vsculpt-server restore --data DIR BACKUP`) takes DIR's
//! ownership lock (so it refuses while a server runs there), checks the
//! backup, and replaces `DIR/vsculpt.db` with a copy of it (the old WAL and
//! shared-memory files are removed: they belong to the old database). An
//! existing database is refused unless `force`. The design tokens live in the
//! database and come back with it; `DIR/admin-token` is DIR's own.

use super::lock::{DataDirLock, LockError};
use rusqlite::{Connection, OpenFlags};
use std::path::{Path, PathBuf};
use thiserror::Error;

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
/// `out` as one consistent snapshot.
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
        let conn = Connection::open(&db)?;
        conn.busy_timeout(std::time::Duration::from_secs(10))?;
        conn.execute("VACUUM INTO ?1", [partial.to_string_lossy().as_ref()])?;
        drop(conn);
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
