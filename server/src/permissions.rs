//! The data directory holds every design's tokens (in `vsculpt.db`) and the
//! administrator token: it is made private to the server's user — the
//! directory 0700 before the database is opened, the database and its WAL
//! and shared-memory files 0600 after (SQLite gives the WAL and SHM files
//! the database file's mode when it creates them later).

use std::io;
use std::path::Path;

/// The database files of the store in `dir`.
const DB_FILES: [&str; 3] = ["vsculpt.db", "vsculpt.db-wal", "vsculpt.db-shm"];

/// Creates `dir` if needed and makes it 0700 (owner only).
pub fn private_dir(dir: &Path) -> io::Result<()> {
    std::fs::create_dir_all(dir)?;
    set_mode(dir, 0o700)
}

/// Makes the store's files in `dir` that exist 0600 (owner read/write).
pub fn private_db_files(dir: &Path) -> io::Result<()> {
    for name in DB_FILES {
        let path = dir.join(name);
        if path.exists() {
            set_mode(&path, 0o600)?;
        }
    }
    Ok(())
}

#[cfg(unix)]
fn set_mode(path: &Path, mode: u32) -> io::Result<()> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode))
}

#[cfg(not(unix))]
fn set_mode(_path: &Path, _mode: u32) -> io::Result<()> {
    Ok(())
}
