//! The registry of running design actors and their supervisor: starts an
//! actor on first use from the store's working state, hands out handles,
//! deletes designs and stops every actor (flushing its working state) at
//! shutdown.
//!
//! Supervision: every actor task is watched. An actor that panics is logged
//! with its design id, counted (`vsculpt_actor_panics_total`) and restarted
//! from the design's last persisted working state, after a back-off that
//! grows while panics repeat. Until it is back the design is *down*: joins
//! get `unavailable`, and `/healthz` reports the server degraded (see
//! [`Hub::down`]). Clients of the dead actor are told and disconnected by
//! their writer task (the web client and the bridge reconnect by themselves).

use super::actor::{self, DesignHandle, Request};
use super::error::{CommandError, ErrorKind};
use super::model::DesignDoc;
use crate::metrics::Metrics;
use crate::store::{DesignId, DesignRecord, Store};
use std::collections::{BTreeSet, HashMap};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use tokio::sync::Mutex;
use tokio::task::JoinHandle;

/// First restart delay after a panic.
pub const RESTART_MIN: Duration = Duration::from_millis(100);
/// Longest restart delay while panics repeat.
pub const RESTART_MAX: Duration = Duration::from_secs(5);
/// An actor that ran this long before panicking restarts after [`RESTART_MIN`].
pub const RESTART_RESET: Duration = Duration::from_secs(30);

/// Every running design actor of one server (cheap to clone: shared).
#[derive(Clone)]
pub struct Hub {
    store: Arc<Store>,
    metrics: Arc<Metrics>,
    persist_delay: Duration,
    /// Most comments and replies per design.
    comment_limit: usize,
    running: Arc<Mutex<HashMap<DesignId, DesignHandle>>>,
    down: Arc<std::sync::Mutex<BTreeSet<DesignId>>>,
    stopping: Arc<AtomicBool>,
    #[cfg(feature = "fault-injection")]
    hold_restarts: Arc<tokio::sync::watch::Sender<bool>>,
}

fn storage(e: impl std::fmt::Display) -> CommandError {
    CommandError::new(ErrorKind::Storage, e.to_string())
}

fn restarting(id: DesignId) -> CommandError {
    CommandError::new(
        ErrorKind::Unavailable,
        format!("design {id} is restarting after a failure; reconnect in a moment"),
    )
}

/// The text of a panic payload.
fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "a non-text panic".into()
    }
}

impl Hub {
    /// A hub over `store`.
    pub fn new(store: Arc<Store>, metrics: Arc<Metrics>, persist_delay: Duration) -> Self {
        Self {
            store,
            metrics,
            persist_delay,
            comment_limit: vsculpt_protocol::limits::MAX_COMMENTS_PER_DESIGN,
            running: Arc::new(Mutex::new(HashMap::new())),
            down: Arc::new(std::sync::Mutex::new(BTreeSet::new())),
            stopping: Arc::new(AtomicBool::new(false)),
            #[cfg(feature = "fault-injection")]
            hold_restarts: Arc::new(tokio::sync::watch::channel(false).0),
        }
    }

    /// The same hub with designs holding at most `limit` comments and
    /// replies each.
    pub fn with_comment_limit(mut self, limit: usize) -> Self {
        self.comment_limit = limit;
        self
    }

    /// The store.
    pub fn store(&self) -> &Arc<Store> {
        &self.store
    }

    /// Designs whose actor is down or restarting after a failure.
    pub fn down(&self) -> Vec<DesignId> {
        self.down
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .iter()
            .copied()
            .collect()
    }

    fn set_down(&self, id: DesignId, down: bool) {
        let mut d = self.down.lock().unwrap_or_else(|p| p.into_inner());
        if down {
            d.insert(id);
        } else {
            d.remove(&id);
        }
    }

    fn is_down(&self, id: DesignId) -> bool {
        self.down
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .contains(&id)
    }

    /// The handle of design `id`, starting its actor when needed.
    pub async fn open(&self, id: DesignId) -> Result<DesignHandle, CommandError> {
        let mut running = self.running.lock().await;
        if let Some(h) = running.get(&id)
            && !h.is_closed()
        {
            return Ok(h.clone());
        }
        if self.is_down(id) {
            return Err(restarting(id));
        }
        let (handle, task) = self.load(id).await?;
        running.insert(id, handle.clone());
        drop(running);
        tokio::spawn(self.clone().supervise(id, task));
        Ok(handle)
    }

    /// Starts design `id`'s actor from the store's working state.
    async fn load(&self, id: DesignId) -> Result<(DesignHandle, JoinHandle<()>), CommandError> {
        let store = self.store.clone();
        let loaded = tokio::task::spawn_blocking(move || -> Result<_, CommandError> {
            if store.design(id).map_err(storage)?.is_none() {
                return Err(CommandError::new(
                    ErrorKind::UnknownDesign,
                    format!("design {id} does not exist"),
                ));
            }
            Ok((
                store.working(id).map_err(storage)?,
                store.versions(id).map_err(storage)?,
                store.comments(id).map_err(storage)?,
            ))
        })
        .await
        .map_err(storage)??;
        let (working, versions, comments) = loaded;
        let bytes = working.ok_or_else(|| {
            CommandError::new(
                ErrorKind::Storage,
                format!("design {id} has no working state"),
            )
        })?;
        let doc = DesignDoc::from_bytes(&bytes)?;
        actor::spawn(
            id,
            doc,
            versions,
            super::comments::CommentBook::new(comments, self.comment_limit),
            self.store.clone(),
            self.metrics.clone(),
            self.persist_delay,
        )
    }

    /// Watches design `id`'s actor task; restarts it after a panic.
    async fn supervise(self, id: DesignId, mut task: JoinHandle<()>) {
        let mut delay = RESTART_MIN;
        loop {
            let started = Instant::now();
            let panic = match task.await {
                Ok(()) => return,
                Err(e) if e.is_panic() => panic_text(&*e.into_panic()),
                // Cancelled: the runtime is shutting down.
                Err(_) => return,
            };
            self.set_down(id, true);
            self.metrics.actor_panic();
            tracing::error!(
                design = id,
                panic = %panic,
                "design actor panicked; restarting it from its last persisted working state"
            );
            if started.elapsed() >= RESTART_RESET {
                delay = RESTART_MIN;
            }
            task = loop {
                tokio::time::sleep(delay).await;
                delay = (delay * 2).min(RESTART_MAX);
                #[cfg(feature = "fault-injection")]
                {
                    let mut hold = self.hold_restarts.subscribe();
                    let _ = hold.wait_for(|h| !h).await;
                }
                if self.stopping.load(Ordering::SeqCst) {
                    self.set_down(id, false);
                    return;
                }
                let mut running = self.running.lock().await;
                if running.get(&id).is_some_and(|h| !h.is_closed()) {
                    // A join started a fresh actor before this restart.
                    self.set_down(id, false);
                    return;
                }
                match self.load(id).await {
                    Ok((handle, task)) => {
                        running.insert(id, handle);
                        self.set_down(id, false);
                        self.metrics.actor_restart();
                        tracing::info!(design = id, "design actor restarted");
                        break task;
                    }
                    Err(e) if e.kind == ErrorKind::UnknownDesign => {
                        running.remove(&id);
                        self.set_down(id, false);
                        return;
                    }
                    Err(e) => {
                        tracing::error!(design = id, "cannot restart the design actor: {e}");
                    }
                }
            };
        }
    }

    /// Creates a design from `doc` (stored, with version 1 = `doc`).
    pub async fn create(&self, doc: DesignDoc, author: &str) -> Result<DesignRecord, CommandError> {
        let store = self.store.clone();
        let author = author.to_string();
        tokio::task::spawn_blocking(move || {
            // Validate by building the model once (CPU work: off the async
            // threads, like the store writes).
            super::model::DesignModel::load(&doc)?;
            let bytes = doc.to_bytes();
            let rec = store.create_design(&doc.name, &bytes).map_err(storage)?;
            store
                .commit(rec.id, &author, "created", &bytes)
                .map_err(storage)?;
            Ok(rec)
        })
        .await
        .map_err(storage)?
    }

    /// Deletes design `id`: clients are told, its actor stops.
    pub async fn delete(&self, id: DesignId) -> Result<(), CommandError> {
        let store = self.store.clone();
        tokio::task::spawn_blocking(move || store.delete_design(id))
            .await
            .map_err(storage)?
            .map_err(|e| CommandError::new(ErrorKind::UnknownDesign, e.to_string()))?;
        if let Some(h) = self.running.lock().await.remove(&id) {
            let _ = h.send(Request::Delete).await;
        }
        Ok(())
    }

    /// Stops every actor at once, each flushing its working state; no actor
    /// is restarted after this.
    pub async fn stop_all(&self) {
        self.stopping.store(true, Ordering::SeqCst);
        let handles: Vec<DesignHandle> =
            self.running.lock().await.drain().map(|(_, h)| h).collect();
        futures_util::future::join_all(handles.iter().map(|h| h.stop())).await;
    }

    /// Test-only fault injection: makes design `id`'s running actor panic.
    #[cfg(feature = "fault-injection")]
    pub async fn inject_panic(&self, id: DesignId) -> Result<(), CommandError> {
        let h = self.running.lock().await.get(&id).cloned();
        match h {
            Some(h) => h.send(Request::Panic).await,
            None => Err(CommandError::new(
                ErrorKind::UnknownDesign,
                format!("design {id} has no running actor"),
            )),
        }
    }

    /// Test-only: while `hold` is true, actors that panicked stay down.
    #[cfg(feature = "fault-injection")]
    pub fn hold_restarts(&self, hold: bool) {
        self.hold_restarts.send_replace(hold);
    }
}
