//! WAL checkpoints run off the commit path (`store::checkpoint`): a commit
//! that takes the WAL past SQLite's 1000-page threshold returns without
//! copying a page into `vsculpt.db` (SQLite's automatic checkpoint would copy
//! them inside that commit), the checkpointer thread then brings the database
//! file up to date by itself, and frames a reader (a backup's snapshot) held
//! back are checkpointed once the reader ends, with no further commit.
//!
//! What is observed is the database file itself: only a checkpoint writes
//! `vsculpt.db` under WAL, and a complete one leaves it `page_count` pages
//! long.

use rusqlite::{Connection, OpenFlags};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use vsculpt_server::store::Store;
use vsculpt_server::store::checkpoint::CHECKPOINT_PAGES;

const PAGE: u64 = 4096;

/// A 400 KB snapshot (≈ 100 pages as a version, as many again as working
/// state), different for every `k` so nothing is shared.
fn snapshot(k: u8) -> Vec<u8> {
    (0..400_000u32).map(|i| (i as u8) ^ k).collect()
}

fn db_file(dir: &Path) -> PathBuf {
    dir.join("vsculpt.db")
}

/// Frames in `vsculpt.db-wal` (a 32-byte header, then 24 + PAGE bytes each).
fn wal_frames(dir: &Path) -> u64 {
    let len = std::fs::metadata(dir.join("vsculpt.db-wal")).unwrap().len();
    len.saturating_sub(32) / (24 + PAGE)
}

fn file_len(dir: &Path) -> u64 {
    std::fs::metadata(db_file(dir)).unwrap().len()
}

/// Waits (a hang guard, not a time limit under test) until `vsculpt.db` is
/// `pages` pages long, i.e. every committed page has been checkpointed.
fn until_checkpointed(dir: &Path, pages: u64) {
    let start = Instant::now();
    while file_len(dir) != pages * PAGE {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the database file stayed {} bytes, {} pages committed",
            file_len(dir),
            pages
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn a_commit_past_the_threshold_does_not_checkpoint_and_the_thread_catches_up() {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    let d = store.create_design("shell", b"s0").unwrap();
    store.hold_checkpoints(true);
    let before = std::fs::read(db_file(dir.path())).unwrap();
    // Over 2 × CHECKPOINT_PAGES pages of commits: SQLite would have
    // checkpointed inside at least two of them.
    for k in 0..12 {
        store.commit(d.id, "ann", "step", &snapshot(k)).unwrap();
    }
    assert!(
        std::fs::read(db_file(dir.path())).unwrap() == before,
        "a commit wrote the database file (checkpointed inline)"
    );
    let frames = wal_frames(dir.path());
    assert!(
        frames > 2 * CHECKPOINT_PAGES as u64,
        "{frames} WAL frames only"
    );
    let pages = store.page_count().unwrap();
    store.hold_checkpoints(false);
    until_checkpointed(dir.path(), pages);
    // The checkpointed file holds every version on its own.
    drop(store);
    let store = Store::open(dir.path()).unwrap();
    assert_eq!(store.versions(d.id).unwrap().len(), 12);
    assert_eq!(store.latest_version(d.id).unwrap().unwrap().1, snapshot(11));
}

#[test]
fn frames_a_reader_held_back_are_checkpointed_when_it_ends_without_another_commit() {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    let d = store.create_design("shell", b"s0").unwrap();
    store.hold_checkpoints(true);
    for k in 0..6 {
        store.commit(d.id, "ann", "step", &snapshot(k)).unwrap();
    }
    // A reader (as a backup) takes its snapshot half way through the commits.
    let reader =
        Connection::open_with_flags(db_file(dir.path()), OpenFlags::SQLITE_OPEN_READ_ONLY).unwrap();
    reader.execute_batch("BEGIN").unwrap();
    let seen: i64 = reader
        .query_row("SELECT COUNT(*) FROM versions", [], |r| r.get(0))
        .unwrap();
    assert_eq!(seen, 6);
    let at_snapshot = store.page_count().unwrap();
    for k in 6..12 {
        store.commit(d.id, "ann", "step", &snapshot(k)).unwrap();
    }
    let pages = store.page_count().unwrap();
    assert!(
        pages > at_snapshot,
        "{pages} pages, {at_snapshot} at the snapshot"
    );
    assert!(wal_frames(dir.path()) > CHECKPOINT_PAGES as u64);
    let start_len = file_len(dir.path());
    store.hold_checkpoints(false);
    // The checkpointer copies up to the reader's snapshot and no further.
    until_checkpointed(dir.path(), at_snapshot);
    assert!(at_snapshot * PAGE > start_len);
    // The reader ends; nothing is committed after it, yet the rest follows.
    reader.execute_batch("COMMIT").unwrap();
    until_checkpointed(dir.path(), pages);
    assert_eq!(store.versions(d.id).unwrap().len(), 12);
}
