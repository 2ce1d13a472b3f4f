//! Checkpoints off the commit path.
//!
//! Under WAL a commit appends its pages to `vsculpt.db-wal` and is durable
//! once they are synced there (`synchronous=FULL`); a *checkpoint* later
//! copies them into `vsculpt.db`, syncs it, and lets the WAL start over.
//! SQLite by default runs that checkpoint inside the commit that takes the
//! WAL past 1000 pages, so that commit's ack waits for it. Measured in
//! `benches/backup_pause.rs` (BENCHMARKS.md): every third commit of an
//! 81 × 159 design copied ~1100 pages inline (+25–75 ms), and while a backup
//! held its read transaction the checkpoint could not pass the backup's
//! snapshot, the WAL grew to 15 600 pages (64 MB), and the first commit after
//! the backup copied all of it inline: 699 ms of a 738 ms commit.
//!
//! Here the writer connection's WAL hook (which replaces SQLite's automatic
//! checkpoint) only notes the WAL's size and wakes a checkpointer thread with
//! its own connection, which runs `PASSIVE` checkpoints: they never wait for
//! (nor block) the writer or readers, and copy as far as the oldest reader
//! allows. When a reader held some frames back, the thread tries again every
//! [`RETRY`] until it has caught up, without waiting for another commit.
//!
//! Durability is unchanged: the checkpoint only moves pages whose commits are
//! already synced in the WAL, syncing the WAL before and the database after
//! (SQLite's checkpoint protocol, crash-safe at any point: the next open
//! recovers from the WAL). WAL growth is bounded as before by what is
//! committed during the longest read transaction (a backup) plus one
//! checkpoint, and under a steady stream of commits by [`WAL_CAP_FRAMES`].
//! Should the thread be gone, the hook checkpoints inline as SQLite would.

use rusqlite::hooks::Wal;
use rusqlite::wal::CheckpointMode;
use rusqlite::{Connection, OpenFlags};
use std::ffi::c_int;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// WAL size (pages) from which a checkpoint is due: SQLite's own default.
pub const CHECKPOINT_PAGES: c_int = 1000;

/// WAL length (frames) past which the thread makes the WAL start over
/// (16 MiB at 4 KiB pages). A commit that begins while a checkpoint runs
/// appends to the WAL instead of starting it over, so at a steady commit rate
/// the WAL could grow for ever; once it is this long and fully checkpointed,
/// a `RESTART` checkpoint holds the next commit back until the pages of the
/// commits since the last checkpoint are copied (the most a commit ever
/// waits for a checkpoint now) and that commit starts the WAL over.
pub const WAL_CAP_FRAMES: c_int = 4096;

/// Retry period while a reader holds WAL frames back.
pub const RETRY: Duration = Duration::from_millis(100);

/// Retry period after a failed checkpoint (full or read-only disk, I/O error).
const FAILED_RETRY: Duration = Duration::from_secs(1);

/// What the writer's hook tells the thread.
#[derive(Default)]
struct Wake {
    /// The WAL's size in pages at the last commit over the threshold (0 once
    /// the thread took the request).
    pages: c_int,
    /// The store is closing.
    stop: bool,
    /// Test-only: checkpoints are held back.
    held: bool,
}

struct Shared {
    wake: Mutex<Wake>,
    cond: Condvar,
    /// The thread runs (false once it has ended, however).
    running: AtomicBool,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Wake> {
        self.wake.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// The checkpointer thread of one store; stopped and joined on drop.
pub(crate) struct Checkpointer {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl Checkpointer {
    /// Starts the thread on its own connection to `db` and hands the
    /// checkpoints of `writer` (the store's connection) over to it.
    pub(crate) fn start(db: &Path, writer: &mut Connection) -> Result<Self, super::StoreError> {
        let conn = Connection::open_with_flags(
            db,
            OpenFlags::SQLITE_OPEN_READ_WRITE | OpenFlags::SQLITE_OPEN_NO_MUTEX,
        )?;
        conn.pragma_update(None, "synchronous", "FULL")?;
        // Never wait for a lock: a `RESTART` checkpoint waiting for a reader
        // (a backup) would hold the writer lock, and commits, meanwhile.
        conn.busy_timeout(Duration::ZERO)?;
        let shared = Arc::new(Shared {
            wake: Mutex::new(Wake::default()),
            cond: Condvar::new(),
            running: AtomicBool::new(true),
        });
        let thread = {
            let shared = shared.clone();
            std::thread::Builder::new()
                .name("vsculpt-checkpoint".into())
                .spawn(move || run(&conn, &shared))?
        };
        let hook = shared.clone();
        writer.wal_hook(Some(move |wal: &mut Wal, pages: c_int| {
            if pages >= CHECKPOINT_PAGES {
                if hook.running.load(Ordering::Acquire) {
                    hook.lock().pages = pages;
                    hook.cond.notify_one();
                } else {
                    // No thread: what SQLite's automatic checkpoint does. An
                    // error must not fail the commit (it is already durable).
                    let _ = wal.checkpoint_v2(CheckpointMode::PASSIVE);
                }
            }
            Ok(())
        }))?;
        Ok(Self {
            shared,
            thread: Some(thread),
        })
    }

    /// Test-only: holds checkpoints back (`true`) or lets them run.
    #[cfg(feature = "fault-injection")]
    pub(crate) fn hold(&self, on: bool) {
        self.shared.lock().held = on;
        self.shared.cond.notify_one();
    }
}

impl Drop for Checkpointer {
    fn drop(&mut self) {
        self.shared.lock().stop = true;
        self.shared.cond.notify_one();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Marks the thread gone however it ends, so the hook takes over.
struct Running<'a>(&'a Shared);

impl Drop for Running<'_> {
    fn drop(&mut self) {
        self.0.running.store(false, Ordering::Release);
    }
}

fn run(conn: &Connection, shared: &Shared) {
    let _running = Running(shared);
    // Frames left behind by the last checkpoint (a reader held them).
    let mut behind = false;
    let mut failing = false;
    loop {
        {
            let mut w = shared.lock();
            loop {
                if w.stop {
                    return;
                }
                let due = w.pages >= CHECKPOINT_PAGES;
                if due && !w.held {
                    break;
                }
                if (behind || failing) && !w.held {
                    let wait = if failing { FAILED_RETRY } else { RETRY };
                    let (g, t) = shared
                        .cond
                        .wait_timeout(w, wait)
                        .unwrap_or_else(|p| p.into_inner());
                    w = g;
                    if t.timed_out() && !w.held && !w.stop {
                        break;
                    }
                } else {
                    w = shared.cond.wait(w).unwrap_or_else(|p| p.into_inner());
                }
            }
            w.pages = 0;
        }
        let t0 = Instant::now();
        match conn.wal_checkpoint_v2(Some("main"), CheckpointMode::PASSIVE) {
            Ok((log, done)) => {
                tracing::debug!(
                    wal_frames = log,
                    checkpointed = done,
                    ms = t0.elapsed().as_secs_f64() * 1e3,
                    "WAL checkpoint"
                );
                behind = done < log;
                if !behind && log >= WAL_CAP_FRAMES {
                    restart(conn);
                }
                if failing {
                    tracing::info!("WAL checkpoints succeed again");
                }
                failing = false;
            }
            Err(e) => {
                if !failing {
                    tracing::warn!("WAL checkpoint failed: {e}; retrying");
                }
                failing = true;
            }
        }
    }
}

/// Makes the next commit start the WAL over (see [`WAL_CAP_FRAMES`]); gives
/// up at once when a commit or a reader is in the way (tried again at the
/// next checkpoint).
fn restart(conn: &Connection) {
    let t0 = Instant::now();
    match conn.wal_checkpoint_v2(Some("main"), CheckpointMode::RESTART) {
        Ok((log, done)) => tracing::debug!(
            wal_frames = log,
            checkpointed = done,
            ms = t0.elapsed().as_secs_f64() * 1e3,
            "WAL restart checkpoint"
        ),
        Err(e) => tracing::debug!("WAL restart checkpoint not done: {e}"),
    }
}
