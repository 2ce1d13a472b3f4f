//! A design's comment writes, off its actor. Each comment request ends in
//! one durable store transaction (an fsync: tens of milliseconds on a real
//! disk, seconds on a stalled one). Waited for inside the actor, it would
//! pause every drag of the design — and a viewer, who may comment but not
//! edit, could hold an editor's drags up by commenting. So the actor only
//! queues the request here; the write runs on the blocking pool while the
//! actor goes on, and the actor hears of it when it lands (its run loop
//! selects on [`CommentWrites::landed`]).
//!
//! Rules (the actor keeps them, see `actor.rs`):
//!
//! * **One comment write at a time, in the order asked.** A request is
//!   checked against the comments and the design when its turn comes (after
//!   the writes before it have landed), so it sees their outcome: a reply to
//!   a comment deleted just before is refused as for any unknown comment.
//! * **Nothing is said before it is durable**: the ack and the fan-out to
//!   every client follow the landed write; a failed write changes nothing
//!   and the asker gets why.

use super::comments::{CommentOp, Write, Written};
use super::commit_write::Reply;
use crate::store::{DesignId, Store, StoreError};
use std::collections::VecDeque;
use std::sync::Arc;
use tokio::task::JoinHandle;

/// A comment request as it was asked.
pub struct Asked {
    /// Who asked (0: REST).
    pub client: u64,
    /// What they asked.
    pub op: CommentOp,
    /// Who waits for the outcome.
    pub reply: Option<Reply>,
}

/// A comment write that has ended, durable or not.
pub struct Landed {
    /// What was stored, or why not.
    pub outcome: Result<Written, StoreError>,
    /// Who waits for the outcome.
    pub reply: Option<Reply>,
}

/// The write in flight.
struct InFlight {
    handle: JoinHandle<Result<Written, StoreError>>,
    reply: Option<Reply>,
}

/// The comment requests of one design: those waiting, oldest first, and
/// the one being written.
pub struct CommentWrites {
    store: Arc<Store>,
    design: DesignId,
    waiting: VecDeque<Asked>,
    in_flight: Option<InFlight>,
}

impl CommentWrites {
    /// No requests yet, for `design` in `store`.
    pub fn new(store: Arc<Store>, design: DesignId) -> Self {
        Self {
            store,
            design,
            waiting: VecDeque::new(),
            in_flight: None,
        }
    }

    /// Queues a request behind those already asked.
    pub fn ask(&mut self, asked: Asked) {
        self.waiting.push_back(asked);
    }

    /// The oldest waiting request, if no write is in flight (its turn has
    /// come: the caller checks it, then [`CommentWrites::start`]s its
    /// write or answers it).
    pub fn take_turn(&mut self) -> Option<Asked> {
        if self.in_flight.is_some() {
            return None;
        }
        self.waiting.pop_front()
    }

    /// Whether a write is in flight or a request waits.
    pub fn pending(&self) -> bool {
        self.in_flight.is_some() || !self.waiting.is_empty()
    }

    /// Starts `write` on the blocking pool; `reply` hears when it lands.
    /// The caller took the request with [`CommentWrites::take_turn`].
    pub fn start(&mut self, write: Write, reply: Option<Reply>) {
        let store = self.store.clone();
        let design = self.design;
        let handle = tokio::task::spawn_blocking(move || write.run(&store, design));
        self.in_flight = Some(InFlight { handle, reply });
    }

    /// Waits for the write in flight to land; never returns while none is
    /// in flight. Cancel-safe: dropped before it returns, the write stays in
    /// flight and a later call reports it.
    pub async fn landed(&mut self) -> Landed {
        let joined = match self.in_flight.as_mut() {
            Some(w) => (&mut w.handle).await,
            None => return std::future::pending().await,
        };
        let reply = self.in_flight.take().and_then(|w| w.reply);
        let outcome = match joined {
            Ok(r) => r,
            Err(e) => Err(StoreError::Io(std::io::Error::other(format!(
                "the comment writer task failed: {e}"
            )))),
        };
        Landed { outcome, reply }
    }
}
