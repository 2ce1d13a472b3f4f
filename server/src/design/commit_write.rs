//! A design's commits, written off its actor. A commit is one durable store
//! transaction (the new version and the working state) ending in an fsync:
//! tens of milliseconds on a real disk, seconds on a stalled one. The actor
//! only takes the snapshot and queues it here; the write runs on the
//! blocking pool while the actor goes on serving drags and every other
//! client, and the actor hears of it when it lands (the run loop selects on
//! [`CommitWrites::landed`]).
//!
//! Rules (the actor keeps them, see `actor.rs`):
//!
//! * **The snapshot is taken when the commit is asked.** Edits that arrive
//!   while the write is in flight belong to the next version (and to the
//!   next working-state write), never to this one.
//! * **One write of the design at a time, in order.** A commit starts only
//!   when no other write of the design (a commit or a working-state write)
//!   is in flight; a second commit queues behind the first, so version
//!   numbers follow the order in which commits were asked.
//! * **Nothing is said before it is durable.** The commit's reply (with its
//!   version), the `committed` event and the version in the design's list
//!   go out only once the transaction has returned (WAL, `synchronous=FULL`).
//! * **A failed write changes nothing**: no version, the client gets a
//!   `storage` error saying why, the design keeps its state in memory and a
//!   working-state write is due again; the next commit may succeed.

use super::command::Ack;
use super::error::{CommandError, ErrorKind};
use super::model::DesignDoc;
use crate::store::{DesignId, Store, VersionInfo};
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;
use tokio::sync::oneshot;
use tokio::task::JoinHandle;

/// Where a commit's outcome goes (a client's request).
pub type Reply = oneshot::Sender<Result<Ack, CommandError>>;

/// A commit as it was asked.
pub struct Asked {
    /// The design as it was when the commit was asked.
    pub doc: DesignDoc,
    /// Who committed.
    pub author: String,
    /// The commit message.
    pub message: String,
    /// Who waits for the outcome.
    pub reply: Option<Reply>,
    /// The working-state write that was due when the commit was asked: the
    /// commit writes that state too, so the actor dropped it; a failed
    /// commit hands it back.
    pub persist_due: Option<Instant>,
}

/// A commit whose write has ended, durable or not.
pub struct Landed {
    /// The new version, or why there is none.
    pub outcome: Result<VersionInfo, CommandError>,
    /// Who waits for the outcome.
    pub reply: Option<Reply>,
    /// See [`Asked::persist_due`].
    pub persist_due: Option<Instant>,
}

/// The write in flight.
struct InFlight {
    handle: JoinHandle<Result<VersionInfo, String>>,
    reply: Option<Reply>,
    persist_due: Option<Instant>,
}

/// The commits of one design: those waiting, oldest first, and the one
/// being written.
pub struct CommitWrites {
    store: Arc<Store>,
    design: DesignId,
    waiting: VecDeque<Asked>,
    in_flight: Option<InFlight>,
}

impl CommitWrites {
    /// No commits yet, for `design` in `store`.
    pub fn new(store: Arc<Store>, design: DesignId) -> Self {
        Self {
            store,
            design,
            waiting: VecDeque::new(),
            in_flight: None,
        }
    }

    /// Queues a commit behind those already asked (it starts with
    /// [`CommitWrites::start`]).
    pub fn ask(&mut self, asked: Asked) {
        self.waiting.push_back(asked);
    }

    /// Whether a commit is being written.
    pub fn in_flight(&self) -> bool {
        self.in_flight.is_some()
    }

    /// Whether a commit is being written or waits to be.
    pub fn pending(&self) -> bool {
        self.in_flight.is_some() || !self.waiting.is_empty()
    }

    /// Starts writing the oldest waiting commit on the blocking pool, unless
    /// one is already in flight; true if one started. The caller makes sure
    /// no other write of the design is in flight.
    pub fn start(&mut self) -> bool {
        if self.in_flight.is_some() {
            return false;
        }
        let Some(asked) = self.waiting.pop_front() else {
            return false;
        };
        let store = self.store.clone();
        let design = self.design;
        let Asked {
            doc,
            author,
            message,
            reply,
            persist_due,
        } = asked;
        let handle = tokio::task::spawn_blocking(move || {
            // Serialising a large design takes milliseconds: here, not on
            // the actor.
            let bytes = doc.to_bytes();
            store
                .commit(design, &author, &message, &bytes)
                .map_err(|e| e.to_string())
        });
        self.in_flight = Some(InFlight {
            handle,
            reply,
            persist_due,
        });
        true
    }

    /// Waits for the commit in flight to land; never returns while none is
    /// in flight. Cancel-safe: dropped before it returns, the write stays in
    /// flight and a later call reports it.
    pub async fn landed(&mut self) -> Landed {
        let joined = match self.in_flight.as_mut() {
            Some(w) => (&mut w.handle).await,
            None => return std::future::pending().await,
        };
        let (reply, persist_due) = self
            .in_flight
            .take()
            .map_or((None, None), |w| (w.reply, w.persist_due));
        let outcome = match joined {
            Ok(Ok(info)) => Ok(info),
            Ok(Err(e)) => Err(not_stored(&e)),
            Err(e) => Err(not_stored(&format!("the writer task failed: {e}"))),
        };
        Landed {
            outcome,
            reply,
            persist_due,
        }
    }
}

/// The error a client gets for a commit that could not be written.
fn not_stored(why: &str) -> CommandError {
    CommandError::new(
        ErrorKind::Storage,
        format!(
            "the commit was not stored ({why}); no version was made and the design keeps its state"
        ),
    )
}
