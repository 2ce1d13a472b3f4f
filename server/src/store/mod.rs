//! The embedded store: one SQLite file (`vsculpt.db` in the data directory,
//! WAL journal, `synchronous=FULL`) holding designs, their tokens, every
//! committed version and the current working state.
//!
//! Durability: every write is its own transaction, and with WAL +
//! `synchronous=FULL` a transaction is on disk when `commit` returns, so a
//! version is durable before the client's ack is sent. WAL checkpoints run
//! on a thread of their own, never inside a commit ([`checkpoint`]). Working state is
//! written by the design actor at most about a second after a change (and on
//! shutdown), so a crash loses at most that last second of uncommitted work.
//!
//! Calls block (SQLite is synchronous); async callers go through
//! `tokio::task::spawn_blocking`.

pub mod backup;
pub mod checkpoint;
pub mod comments;
pub mod lock;
pub mod token_index;
pub mod tokens;

pub use comments::{CommentRecord, NewComment};
use rusqlite::{Connection, OptionalExtension, params};
use serde::Serialize;
use std::path::Path;
use std::sync::Mutex;
use std::time::{SystemTime, UNIX_EPOCH};
use thiserror::Error;
pub use tokens::{Role, Tokens};

/// Design id as stored and sent on the wire.
pub type DesignId = u64;

/// Why a store operation failed.
#[derive(Debug, Error)]
pub enum StoreError {
    /// SQLite failed.
    #[error("database: {0}")]
    Sqlite(#[from] rusqlite::Error),
    /// The data directory could not be created.
    #[error("data directory: {0}")]
    Io(#[from] std::io::Error),
    /// The OS random generator failed.
    #[error("random tokens: {0}")]
    Random(String),
    /// No (live) design with this id.
    #[error("design {0} does not exist")]
    UnknownDesign(DesignId),
    /// No comment with this id in the design (or it is a reply, which
    /// cannot be replied to).
    #[error("design {0} has no comment {1}")]
    UnknownComment(DesignId, u64),
    /// The database was written by a newer server (its schema version is
    /// above every migration this one knows): opening it could lose data.
    #[error(
        "the database has schema version {found}; this server knows up to {known}: use a newer server"
    )]
    NewerSchema {
        /// The database's `user_version`.
        found: i64,
        /// The newest version this server migrates to.
        known: i64,
    },
}

/// One design's row.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DesignRecord {
    /// Design id.
    pub id: DesignId,
    /// Human name.
    pub name: String,
    /// Creation time, ms since the Unix epoch.
    pub created_ms: i64,
    /// Access tokens.
    #[serde(skip)]
    pub tokens: Tokens,
}

/// A committed version's metadata.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VersionInfo {
    /// Version number, 1, 2, … per design.
    pub number: u64,
    /// Commit time, ms since the Unix epoch.
    pub time_ms: i64,
    /// Who committed.
    pub author: String,
    /// Commit message.
    pub message: String,
}

/// The database handle (one connection behind a mutex; writes are few),
/// with its checkpointer thread.
pub struct Store {
    conn: Mutex<Connection>,
    /// Held for its life (dropping it stops and joins the thread); read
    /// only by the test-only `hold_checkpoints`.
    #[cfg_attr(not(feature = "fault-injection"), allow(dead_code))]
    checkpointer: checkpoint::Checkpointer,
    /// Test-only: store calls waiting for the connection (see `waiting`).
    #[cfg(feature = "fault-injection")]
    waiting: std::sync::atomic::AtomicUsize,
}

/// Milliseconds since the Unix epoch.
pub fn now_ms() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}

/// Schema version 1: designs, versions, working states. Databases written
/// before the schema was versioned (`user_version` 0) have exactly these
/// tables, hence `IF NOT EXISTS`.
const SCHEMA: &str = "
CREATE TABLE IF NOT EXISTS designs (
    id           INTEGER PRIMARY KEY AUTOINCREMENT,
    name         TEXT    NOT NULL,
    created_ms   INTEGER NOT NULL,
    editor_token TEXT    NOT NULL,
    viewer_token TEXT    NOT NULL,
    device_token TEXT    NOT NULL,
    deleted      INTEGER NOT NULL DEFAULT 0
);
CREATE TABLE IF NOT EXISTS versions (
    design_id INTEGER NOT NULL REFERENCES designs(id),
    number    INTEGER NOT NULL,
    time_ms   INTEGER NOT NULL,
    author    TEXT    NOT NULL,
    message   TEXT    NOT NULL,
    snapshot  BLOB    NOT NULL,
    PRIMARY KEY (design_id, number)
);
CREATE TABLE IF NOT EXISTS working (
    design_id  INTEGER PRIMARY KEY REFERENCES designs(id),
    updated_ms INTEGER NOT NULL,
    snapshot   BLOB    NOT NULL
);
";

/// The schema's migrations, oldest first: entry `k` brings a database from
/// `PRAGMA user_version` k to k + 1, in one transaction with the version
/// bump, so a database is always at exactly one version. Append only.
const MIGRATIONS: &[&str] = &[SCHEMA, comments::SCHEMA, comments::SCHEMA_EDITED];

/// Brings the database to the newest schema version; refuses a database
/// from a newer server.
fn migrate(conn: &mut Connection) -> Result<(), StoreError> {
    let found: i64 = conn.query_row("PRAGMA user_version", [], |r| r.get(0))?;
    let known = MIGRATIONS.len() as i64;
    if found > known {
        return Err(StoreError::NewerSchema { found, known });
    }
    for (k, sql) in MIGRATIONS.iter().enumerate().skip(found.max(0) as usize) {
        let tx = conn.transaction_with_behavior(rusqlite::TransactionBehavior::Immediate)?;
        tx.execute_batch(sql)?;
        tx.pragma_update(None, "user_version", k as i64 + 1)?;
        tx.commit()?;
        tracing::info!(version = k + 1, "store schema migrated");
    }
    Ok(())
}

impl Store {
    /// Opens (creating when missing) `dir/vsculpt.db`, migrating its schema
    /// to the newest version.
    pub fn open(dir: &Path) -> Result<Self, StoreError> {
        std::fs::create_dir_all(dir)?;
        let db = dir.join(backup::DB_FILE);
        let mut conn = Connection::open(&db)?;
        conn.pragma_update(None, "journal_mode", "WAL")?;
        conn.pragma_update(None, "synchronous", "FULL")?;
        conn.pragma_update(None, "foreign_keys", "ON")?;
        conn.busy_timeout(std::time::Duration::from_secs(5))?;
        migrate(&mut conn)?;
        let checkpointer = checkpoint::Checkpointer::start(&db, &mut conn)?;
        Ok(Self {
            conn: Mutex::new(conn),
            checkpointer,
            #[cfg(feature = "fault-injection")]
            waiting: Default::default(),
        })
    }

    fn conn(&self) -> std::sync::MutexGuard<'_, Connection> {
        // A panic while holding the lock cannot leave SQLite inconsistent
        // (transactions roll back), so a poisoned lock is still usable.
        #[cfg(feature = "fault-injection")]
        self.waiting
            .fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        let conn = self.conn.lock().unwrap_or_else(|p| p.into_inner());
        #[cfg(feature = "fault-injection")]
        self.waiting
            .fetch_sub(1, std::sync::atomic::Ordering::SeqCst);
        conn
    }

    /// Creates a design with fresh tokens and its initial working state.
    pub fn create_design(&self, name: &str, snapshot: &[u8]) -> Result<DesignRecord, StoreError> {
        let tokens = Tokens::generate().map_err(|e| StoreError::Random(e.to_string()))?;
        let created_ms = now_ms();
        let mut conn = self.conn();
        let tx = conn.transaction()?;
        tx.execute(
            "INSERT INTO designs (name, created_ms, editor_token, viewer_token, device_token) VALUES (?1, ?2, ?3, ?4, ?5)",
            params![name, created_ms, tokens.editor, tokens.viewer, tokens.device],
        )?;
        let id = tx.last_insert_rowid() as DesignId;
        tx.execute(
            "INSERT INTO working (design_id, updated_ms, snapshot) VALUES (?1, ?2, ?3)",
            params![id as i64, created_ms, snapshot],
        )?;
        tx.commit()?;
        Ok(DesignRecord {
            id,
            name: name.to_string(),
            created_ms,
            tokens,
        })
    }

    fn row_to_record(row: &rusqlite::Row<'_>) -> rusqlite::Result<DesignRecord> {
        Ok(DesignRecord {
            id: row.get::<_, i64>(0)? as DesignId,
            name: row.get(1)?,
            created_ms: row.get(2)?,
            tokens: Tokens {
                editor: row.get(3)?,
                viewer: row.get(4)?,
                device: row.get(5)?,
            },
        })
    }

    /// Every live design, by id.
    pub fn designs(&self) -> Result<Vec<DesignRecord>, StoreError> {
        let conn = self.conn();
        let mut stmt = conn.prepare(
            "SELECT id, name, created_ms, editor_token, viewer_token, device_token FROM designs WHERE deleted = 0 ORDER BY id",
        )?;
        let rows = stmt.query_map([], Self::row_to_record)?;
        Ok(rows.collect::<Result<Vec<_>, _>>()?)
    }

    /// One live design.
    pub fn design(&self, id: DesignId) -> Result<Option<DesignRecord>, StoreError> {
        let conn = self.conn();
        Ok(conn
            .query_row(
                "SELECT id, name, created_ms, editor_token, viewer_token, device_token FROM designs WHERE id = ?1 AND deleted = 0",
                params![id as i64],
                Self::row_to_record,
            )
            .optional()?)
    }

    /// Marks a design deleted (its versions stay on disk but are unreachable).
    pub fn delete_design(&self, id: DesignId) -> Result<(), StoreError> {
        let n = self.conn().execute(
            "UPDATE designs SET deleted = 1 WHERE id = ?1 AND deleted = 0",
            params![id as i64],
        )?;
        if n == 0 {
            return Err(StoreError::UnknownDesign(id));
        }
        Ok(())
    }

    /// Writes the working state.
    pub fn save_working(&self, id: DesignId, snapshot: &[u8]) -> Result<(), StoreError> {
        self.conn().execute(
            "INSERT INTO working (design_id, updated_ms, snapshot) VALUES (?1, ?2, ?3)
             ON CONFLICT(design_id) DO UPDATE SET updated_ms = excluded.updated_ms, snapshot = excluded.snapshot",
            params![id as i64, now_ms(), snapshot],
        )?;
        Ok(())
    }

    /// The working state last written.
    pub fn working(&self, id: DesignId) -> Result<Option<Vec<u8>>, StoreError> {
        Ok(self
            .conn()
            .query_row(
                "SELECT snapshot FROM working WHERE design_id = ?1",
                params![id as i64],
                |r| r.get(0),
            )
            .optional()?)
    }

    /// Appends a version (number = last + 1) and makes it the working state,
    /// in one durable transaction.
    pub fn commit(
        &self,
        id: DesignId,
        author: &str,
        message: &str,
        snapshot: &[u8],
    ) -> Result<VersionInfo, StoreError> {
        let time_ms = now_ms();
        let t0 = std::time::Instant::now();
        let mut conn = self.conn();
        let locked = t0.elapsed();
        // IMMEDIATE: the write lock is taken with the snapshot. A deferred
        // transaction reads first and, should the WAL have been restarted
        // meanwhile (`checkpoint::WAL_CAP_FRAMES`), could not upgrade to a
        // write (`SQLITE_BUSY_SNAPSHOT`, not retried by the busy handler).
        let tx = conn.transaction_with_behavior(rusqlite::TransactionBehavior::Immediate)?;
        live_design(&tx, id)?;
        let number: i64 = tx.query_row(
            "SELECT COALESCE(MAX(number), 0) + 1 FROM versions WHERE design_id = ?1",
            params![id as i64],
            |r| r.get(0),
        )?;
        tx.execute(
            "INSERT INTO versions (design_id, number, time_ms, author, message, snapshot) VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
            params![id as i64, number, time_ms, author, message, snapshot],
        )?;
        tx.execute(
            "INSERT INTO working (design_id, updated_ms, snapshot) VALUES (?1, ?2, ?3)
             ON CONFLICT(design_id) DO UPDATE SET updated_ms = excluded.updated_ms, snapshot = excluded.snapshot",
            params![id as i64, time_ms, snapshot],
        )?;
        let written = t0.elapsed();
        tx.commit()?;
        tracing::debug!(
            design = id,
            version = number,
            lock_ms = locked.as_secs_f64() * 1e3,
            write_ms = (written - locked).as_secs_f64() * 1e3,
            commit_ms = (t0.elapsed() - written).as_secs_f64() * 1e3,
            "store commit"
        );
        Ok(VersionInfo {
            number: number as u64,
            time_ms,
            author: author.to_string(),
            message: message.to_string(),
        })
    }

    /// Every version's metadata, oldest first.
    pub fn versions(&self, id: DesignId) -> Result<Vec<VersionInfo>, StoreError> {
        let conn = self.conn();
        let mut stmt = conn.prepare(
            "SELECT number, time_ms, author, message FROM versions WHERE design_id = ?1 ORDER BY number",
        )?;
        let rows = stmt.query_map(params![id as i64], |r| {
            Ok(VersionInfo {
                number: r.get::<_, i64>(0)? as u64,
                time_ms: r.get(1)?,
                author: r.get(2)?,
                message: r.get(3)?,
            })
        })?;
        Ok(rows.collect::<Result<Vec<_>, _>>()?)
    }

    /// One version with its snapshot.
    pub fn version(
        &self,
        id: DesignId,
        number: u64,
    ) -> Result<Option<(VersionInfo, Vec<u8>)>, StoreError> {
        Ok(self
            .conn()
            .query_row(
                "SELECT number, time_ms, author, message, snapshot FROM versions WHERE design_id = ?1 AND number = ?2",
                params![id as i64, number as i64],
                |r| {
                    Ok((
                        VersionInfo {
                            number: r.get::<_, i64>(0)? as u64,
                            time_ms: r.get(1)?,
                            author: r.get(2)?,
                            message: r.get(3)?,
                        },
                        r.get(4)?,
                    ))
                },
            )
            .optional()?)
    }

    /// Test-only: caps the database at `pages` pages (SQLite's
    /// `max_page_count`; `None` lifts the cap), so a test can fill the
    /// "disk" and give the space back. Writes past the cap fail with
    /// `SQLITE_FULL`, exactly as on a full disk.
    #[cfg(feature = "fault-injection")]
    pub fn limit_pages(&self, pages: Option<u64>) -> Result<u64, StoreError> {
        let conn = self.conn();
        let n: i64 = match pages {
            Some(p) => conn.query_row(&format!("PRAGMA max_page_count = {p}"), [], |r| r.get(0))?,
            None => conn.query_row("PRAGMA max_page_count = 4294967294", [], |r| r.get(0))?,
        };
        Ok(n as u64)
    }

    /// Test-only: makes every write fail as on a read-only disk (SQLite's
    /// `query_only`: a write is refused with `SQLITE_READONLY`, "attempt to
    /// write a readonly database") or lifts that.
    #[cfg(feature = "fault-injection")]
    pub fn read_only(&self, on: bool) -> Result<(), StoreError> {
        self.conn().execute_batch(if on {
            "PRAGMA query_only = 1"
        } else {
            "PRAGMA query_only = 0"
        })?;
        Ok(())
    }

    /// Test-only: stalls the store as a slow disk would. A thread takes the
    /// database connection (every store call waits for it) before this
    /// returns and holds it until the returned sender is dropped.
    #[cfg(feature = "fault-injection")]
    pub fn stall(self: &std::sync::Arc<Self>) -> std::sync::mpsc::Sender<()> {
        let (release, held) = std::sync::mpsc::channel::<()>();
        let (taken, wait_taken) = std::sync::mpsc::sync_channel::<()>(0);
        let store = self.clone();
        std::thread::spawn(move || {
            let _conn = store.conn();
            let _ = taken.send(());
            let _ = held.recv();
        });
        let _ = wait_taken.recv();
        release
    }

    /// Test-only: how many store calls wait for the connection (behind a
    /// [`Store::stall`]), so a test can tell that a write has started.
    #[cfg(feature = "fault-injection")]
    pub fn waiting(&self) -> usize {
        self.waiting.load(std::sync::atomic::Ordering::SeqCst)
    }

    /// Test-only: holds the WAL checkpoints back (`true`) or lets them run,
    /// so a test can tell whether a commit checkpoints.
    #[cfg(feature = "fault-injection")]
    pub fn hold_checkpoints(&self, on: bool) {
        self.checkpointer.hold(on);
    }

    /// Test-only: the database's size in pages.
    #[cfg(feature = "fault-injection")]
    pub fn page_count(&self) -> Result<u64, StoreError> {
        let n: i64 = self
            .conn()
            .query_row("PRAGMA page_count", [], |r| r.get(0))?;
        Ok(n as u64)
    }

    /// The newest version with its snapshot.
    pub fn latest_version(
        &self,
        id: DesignId,
    ) -> Result<Option<(VersionInfo, Vec<u8>)>, StoreError> {
        let n: Option<i64> = self.conn().query_row(
            "SELECT MAX(number) FROM versions WHERE design_id = ?1",
            params![id as i64],
            |r| r.get(0),
        )?;
        match n {
            Some(n) => self.version(id, n as u64),
            None => Ok(None),
        }
    }
}

/// `UnknownDesign` unless design `id` exists and is not deleted (inside the
/// write transaction that is about to change it).
fn live_design(tx: &rusqlite::Transaction, id: DesignId) -> Result<(), StoreError> {
    let live: Option<i64> = tx
        .query_row(
            "SELECT id FROM designs WHERE id = ?1 AND deleted = 0",
            params![id as i64],
            |r| r.get(0),
        )
        .optional()?;
    match live {
        Some(_) => Ok(()),
        None => Err(StoreError::UnknownDesign(id)),
    }
}
