//! One task per design: it alone holds the design's kernel state (no locks
//! around the solver), runs every command in arrival order, coalesces drag
//! frames, keeps undo/redo, tracks presence, persists the working state at
//! most `persist_delay` after a change, and publishes
//!
//! * geometry on a `watch` channel — latest wins, a slow client skips frames;
//! * ordered events on a bounded `broadcast` channel — never dropped
//!   silently: a client that lags past its capacity resyncs from a fresh
//!   full state (see [`Request::Resync`]).

use super::command::{Ack, Command};
use super::error::{CommandError, ErrorKind};
use super::model::{DesignDoc, DesignModel, Geometry};
use super::undo::UndoStack;
use crate::metrics::Metrics;
use crate::store::{DesignId, Role, Store, VersionInfo};
use glam::DVec3;
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::{broadcast, mpsc, oneshot, watch};

/// Capacity of a design's event channel; a client further behind resyncs.
pub const EVENT_CAPACITY: usize = 256;
/// Capacity of a design's request queue.
pub const REQUEST_CAPACITY: usize = 1024;

/// Who a connected client is.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ClientInfo {
    /// Server-assigned connection id.
    pub id: u64,
    /// Display name the client gave.
    pub name: String,
    /// Its role on this design.
    pub role: Role,
}

/// One entry of the presence list.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Presence {
    /// The client.
    pub client: ClientInfo,
    /// The icon it is dragging, if any.
    pub holding: Option<u64>,
}

/// An ordered event every client of a design receives.
#[derive(Clone, Debug)]
pub enum DesignEvent {
    /// The design's full state changed (icons, material, surface layout).
    State(Arc<DesignDoc>),
    /// Who is here and what they hold.
    Presence(Arc<Vec<Presence>>),
    /// A version was committed.
    Committed(VersionInfo),
    /// The working state was replaced by a version (restore or revert).
    Restored(u64),
    /// A device bridge reported something (forwarded verbatim).
    Device(Arc<serde_json::Value>),
    /// The design was deleted; the actor stops.
    Deleted,
}

/// What a joining (or resyncing) client gets, consistent with each other.
pub struct Joined {
    /// Full state at the moment of joining.
    pub state: Arc<DesignDoc>,
    /// Current presence.
    pub presence: Arc<Vec<Presence>>,
    /// Events after that state.
    pub events: broadcast::Receiver<DesignEvent>,
    /// Latest geometry.
    pub geometry: watch::Receiver<Arc<Geometry>>,
}

/// A request to the actor.
pub enum Request {
    /// A client joins.
    Join {
        /// Who.
        client: ClientInfo,
        /// The answer.
        reply: oneshot::Sender<Joined>,
    },
    /// A lagging client asks for a fresh state and event stream.
    Resync {
        /// The answer.
        reply: oneshot::Sender<Joined>,
    },
    /// A client left.
    Leave {
        /// Its connection id.
        client: u64,
    },
    /// A command from a client.
    Command {
        /// Connection id.
        client: u64,
        /// The command.
        command: Command,
        /// The answer (drag frames pass `None`: no ack per frame).
        reply: Option<oneshot::Sender<Result<Ack, CommandError>>>,
    },
    /// Forward a device report to every client.
    Device {
        /// Connection id of the bridge.
        client: u64,
        /// The report.
        report: serde_json::Value,
    },
    /// The current full state.
    State {
        /// The answer.
        reply: oneshot::Sender<Arc<DesignDoc>>,
    },
    /// A tessellation for mesh export.
    Mesh {
        /// Samples per knot span.
        density: usize,
        /// The answer.
        reply: oneshot::Sender<Result<super::model::MeshData, CommandError>>,
    },
    /// Replace the surface (IGES import) as an undoable edit by `author`.
    Replace {
        /// The new document.
        doc: Box<DesignDoc>,
        /// The answer.
        reply: oneshot::Sender<Result<Ack, CommandError>>,
    },
    /// The design was deleted: tell clients and stop.
    Delete,
    /// Flush the working state and stop.
    Stop {
        /// Answered once flushed.
        reply: oneshot::Sender<()>,
    },
}

/// A handle to a running design actor.
#[derive(Clone, Debug)]
pub struct DesignHandle {
    /// The design.
    pub id: DesignId,
    tx: mpsc::Sender<Request>,
}

fn gone() -> CommandError {
    CommandError::new(ErrorKind::UnknownDesign, "the design is closed or deleted")
}

impl DesignHandle {
    /// Sends a request (waits when the queue is full).
    pub async fn send(&self, r: Request) -> Result<(), CommandError> {
        self.tx.send(r).await.map_err(|_| gone())
    }

    /// Whether the actor has stopped.
    pub fn is_closed(&self) -> bool {
        self.tx.is_closed()
    }

    /// Joins the design.
    pub async fn join(&self, client: ClientInfo) -> Result<Joined, CommandError> {
        let (reply, rx) = oneshot::channel();
        self.send(Request::Join { client, reply }).await?;
        rx.await.map_err(|_| gone())
    }

    /// A fresh state and event stream for a client that lagged.
    pub async fn resync(&self) -> Result<Joined, CommandError> {
        let (reply, rx) = oneshot::channel();
        self.send(Request::Resync { reply }).await?;
        rx.await.map_err(|_| gone())
    }

    /// Runs a command and waits for its outcome.
    pub async fn command(&self, client: u64, command: Command) -> Result<Ack, CommandError> {
        let (reply, rx) = oneshot::channel();
        self.send(Request::Command {
            client,
            command,
            reply: Some(reply),
        })
        .await?;
        rx.await.map_err(|_| gone())?
    }

    /// Queues a drag frame (no ack; errors come back only as events).
    pub async fn drag(&self, client: u64, icon: u64, xyz: DVec3) -> Result<(), CommandError> {
        self.send(Request::Command {
            client,
            command: Command::Drag { icon, xyz },
            reply: None,
        })
        .await
    }

    /// The design's current state.
    pub async fn state(&self) -> Result<Arc<DesignDoc>, CommandError> {
        let (reply, rx) = oneshot::channel();
        self.send(Request::State { reply }).await?;
        rx.await.map_err(|_| gone())
    }

    /// A tessellation of the current surface.
    pub async fn mesh(&self, density: usize) -> Result<super::model::MeshData, CommandError> {
        let (reply, rx) = oneshot::channel();
        self.send(Request::Mesh { density, reply }).await?;
        rx.await.map_err(|_| gone())?
    }

    /// Replaces the design's document (undoable).
    pub async fn replace(&self, doc: DesignDoc) -> Result<Ack, CommandError> {
        let (reply, rx) = oneshot::channel();
        self.send(Request::Replace {
            doc: Box::new(doc),
            reply,
        })
        .await?;
        rx.await.map_err(|_| gone())?
    }

    /// Flushes and stops the actor.
    pub async fn stop(&self) {
        let (reply, rx) = oneshot::channel();
        if self.send(Request::Stop { reply }).await.is_ok() {
            let _ = rx.await;
        }
    }
}

/// The actor's state.
struct Actor {
    id: DesignId,
    model: DesignModel,
    store: Arc<Store>,
    metrics: Arc<Metrics>,
    persist_delay: Duration,
    undo: UndoStack,
    clients: BTreeMap<u64, Presence>,
    events: broadcast::Sender<DesignEvent>,
    geometry: watch::Sender<Arc<Geometry>>,
    state: Arc<DesignDoc>,
    rev: u64,
    persist_at: Option<Instant>,
    /// The icon being dragged per client, and whether its undo point is taken.
    dragging: BTreeMap<u64, u64>,
}

/// Starts the actor of design `id` from `doc`.
pub fn spawn(
    id: DesignId,
    doc: DesignDoc,
    store: Arc<Store>,
    metrics: Arc<Metrics>,
    persist_delay: Duration,
) -> Result<DesignHandle, CommandError> {
    let model = DesignModel::load(&doc)?;
    let (tx, rx) = mpsc::channel(REQUEST_CAPACITY);
    let state = Arc::new(model.to_doc());
    let geometry = watch::channel(Arc::new(model.geometry(0))).0;
    let actor = Actor {
        id,
        model,
        store,
        metrics: metrics.clone(),
        persist_delay,
        undo: UndoStack::new(64),
        clients: BTreeMap::new(),
        events: broadcast::channel(EVENT_CAPACITY).0,
        geometry,
        state,
        rev: 0,
        persist_at: None,
        dragging: BTreeMap::new(),
    };
    metrics.design_open(1);
    tokio::spawn(actor.run(rx));
    Ok(DesignHandle { id, tx })
}

impl Actor {
    async fn run(mut self, mut rx: mpsc::Receiver<Request>) {
        let mut batch: Vec<Request> = Vec::with_capacity(64);
        loop {
            let sleep = async {
                match self.persist_at {
                    Some(t) => tokio::time::sleep_until(t.into()).await,
                    None => std::future::pending().await,
                }
            };
            tokio::select! {
                n = rx.recv_many(&mut batch, 256) => {
                    if n == 0 {
                        break;
                    }
                    if self.handle_batch(&mut batch).await {
                        break;
                    }
                }
                _ = sleep => self.persist().await,
            }
        }
        self.persist().await;
        self.metrics.design_open(-1);
        tracing::debug!(design = self.id, "design actor stopped");
    }

    /// Runs a batch; returns true when the actor must stop.
    async fn handle_batch(&mut self, batch: &mut Vec<Request>) -> bool {
        // Coalesce drag frames: a frame is skipped when a later frame of the
        // same client and icon follows before any other command of that client.
        let n = batch.len();
        let mut skip = vec![false; n];
        for k in 0..n {
            if let Request::Command {
                client,
                command: Command::Drag { icon, .. },
                reply: None,
            } = &batch[k]
            {
                for later in &batch[k + 1..] {
                    if let Request::Command {
                        client: c2,
                        command,
                        ..
                    } = later
                    {
                        if c2 != client {
                            continue;
                        }
                        if let Command::Drag { icon: i2, .. } = command
                            && i2 == icon
                        {
                            skip[k] = true;
                        }
                        break;
                    }
                }
            }
        }
        let mut geometry_dirty = false;
        let mut stop = false;
        for (k, req) in batch.drain(..).enumerate() {
            if skip[k] || stop {
                continue;
            }
            match req {
                Request::Join { client, reply } => {
                    tracing::info!(design = self.id, client = client.id, role = ?client.role, "client joined");
                    self.clients.insert(
                        client.id,
                        Presence {
                            client,
                            holding: None,
                        },
                    );
                    let presence = self.broadcast_presence();
                    let _ = reply.send(self.joined(presence));
                }
                Request::Resync { reply } => {
                    let presence = Arc::new(self.clients.values().cloned().collect());
                    let _ = reply.send(self.joined(presence));
                }
                Request::Leave { client } => {
                    if let Some(icon) = self.dragging.remove(&client) {
                        let _ = self.model.release(icon);
                        geometry_dirty = true;
                    }
                    if self.clients.remove(&client).is_some() {
                        self.broadcast_presence();
                    }
                }
                Request::Command {
                    client,
                    command,
                    reply,
                } => {
                    let out = self.command(client, command, &mut geometry_dirty).await;
                    if let Some(reply) = reply {
                        let _ = reply.send(out);
                    } else if let Err(e) = out {
                        tracing::debug!(design = self.id, client, "drag refused: {e}");
                    }
                }
                Request::Device { client, report } => {
                    let mut report = report;
                    if let Some(obj) = report.as_object_mut() {
                        obj.insert("client".into(), client.into());
                    }
                    let _ = self.events.send(DesignEvent::Device(Arc::new(report)));
                }
                Request::State { reply } => {
                    let _ = reply.send(self.state.clone());
                }
                Request::Mesh { density, reply } => {
                    let _ = reply.send(self.model.mesh(density));
                }
                Request::Replace { doc, reply } => {
                    let before = self.model.to_doc();
                    let out = match DesignModel::load(&doc) {
                        Ok(m) => {
                            self.undo.push(before);
                            self.model = m;
                            self.dragging.clear();
                            self.changed(true);
                            geometry_dirty = true;
                            Ok(Ack::default())
                        }
                        Err(e) => Err(e),
                    };
                    let _ = reply.send(out);
                }
                Request::Delete => {
                    let _ = self.events.send(DesignEvent::Deleted);
                    self.persist_at = None;
                    stop = true;
                }
                Request::Stop { reply } => {
                    self.persist().await;
                    let _ = reply.send(());
                    stop = true;
                }
            }
        }
        if geometry_dirty {
            self.publish_geometry();
        }
        stop
    }

    fn joined(&self, presence: Arc<Vec<Presence>>) -> Joined {
        Joined {
            state: self.state.clone(),
            presence,
            events: self.events.subscribe(),
            geometry: self.geometry.subscribe(),
        }
    }

    fn broadcast_presence(&self) -> Arc<Vec<Presence>> {
        let list: Arc<Vec<Presence>> = Arc::new(self.clients.values().cloned().collect());
        let _ = self.events.send(DesignEvent::Presence(list.clone()));
        list
    }

    fn set_holding(&mut self, client: u64, icon: Option<u64>) {
        let changed = match self.clients.get_mut(&client) {
            Some(p) if p.holding != icon => {
                p.holding = icon;
                true
            }
            _ => false,
        };
        if changed {
            self.broadcast_presence();
        }
    }

    /// After a change: refresh the shared state (when icons or layout
    /// changed), schedule a persist.
    fn changed(&mut self, state_changed: bool) {
        if state_changed {
            self.state = Arc::new(self.model.to_doc());
            let _ = self.events.send(DesignEvent::State(self.state.clone()));
        }
        if self.persist_at.is_none() {
            self.persist_at = Some(Instant::now() + self.persist_delay);
        }
    }

    fn publish_geometry(&mut self) {
        self.rev += 1;
        let g = Arc::new(self.model.geometry(self.rev));
        self.geometry.send_replace(g);
    }

    async fn persist(&mut self) {
        if self.persist_at.take().is_none() {
            return;
        }
        let bytes = self.model.to_doc().to_bytes();
        let store = self.store.clone();
        let id = self.id;
        match tokio::task::spawn_blocking(move || store.save_working(id, &bytes)).await {
            Ok(Ok(())) => {}
            Ok(Err(e)) => tracing::error!(design = id, "cannot save working state: {e}"),
            Err(e) => tracing::error!(design = id, "working-state writer failed: {e}"),
        }
    }

    fn role(&self, client: u64) -> Option<Role> {
        self.clients.get(&client).map(|p| p.client.role)
    }

    async fn command(
        &mut self,
        client: u64,
        command: Command,
        geometry_dirty: &mut bool,
    ) -> Result<Ack, CommandError> {
        // Clients that never joined (REST callers) pass id 0 with the role
        // already checked by the caller.
        let role = if client == 0 {
            Role::Editor
        } else {
            self.role(client)
                .ok_or_else(|| CommandError::new(ErrorKind::Forbidden, "not joined"))?
        };
        let allowed = match &command {
            Command::Edit(_) | Command::Drag { .. } | Command::Release { .. } => role.can_edit(),
            _ => role.can_manage(),
        };
        if !allowed {
            return Err(CommandError::new(
                ErrorKind::Forbidden,
                format!("a {role:?} may not do this"),
            ));
        }
        match command {
            Command::Edit(edit) => {
                let before = self.model.to_doc();
                let created = self.model.apply(edit)?;
                self.undo.push(before);
                self.changed(true);
                *geometry_dirty = true;
                Ok(Ack {
                    created_icon: created,
                    version: None,
                })
            }
            Command::Drag { icon, xyz } => {
                let first = self.dragging.get(&client) != Some(&icon);
                let before = first.then(|| self.model.to_doc());
                let t = Instant::now();
                self.model.drag(icon, xyz)?;
                self.metrics.solve(t.elapsed());
                if let Some(before) = before {
                    self.undo.push(before);
                    self.dragging.insert(client, icon);
                    self.set_holding(client, Some(icon));
                }
                self.changed(false);
                *geometry_dirty = true;
                Ok(Ack::default())
            }
            Command::Release { icon } => {
                self.model.release(icon)?;
                self.dragging.remove(&client);
                self.set_holding(client, None);
                self.changed(true);
                *geometry_dirty = true;
                Ok(Ack::default())
            }
            Command::Undo | Command::Redo => {
                let current = self.model.to_doc();
                let target = if matches!(command, Command::Undo) {
                    self.undo.undo(current)
                } else {
                    self.undo.redo(current)
                };
                let doc = target.ok_or_else(|| {
                    CommandError::new(ErrorKind::NothingToUndo, "nothing to undo or redo")
                })?;
                self.model = DesignModel::load(&doc)?;
                self.dragging.clear();
                self.changed(true);
                *geometry_dirty = true;
                Ok(Ack::default())
            }
            Command::Commit { message } => {
                let author = self
                    .clients
                    .get(&client)
                    .map(|p| p.client.name.clone())
                    .unwrap_or_else(|| "rest".into());
                let bytes = self.model.to_doc().to_bytes();
                let store = self.store.clone();
                let id = self.id;
                let info = tokio::task::spawn_blocking(move || {
                    store.commit(id, &author, &message, &bytes)
                })
                .await
                .map_err(|e| CommandError::new(ErrorKind::Storage, e.to_string()))?
                .map_err(|e| CommandError::new(ErrorKind::Storage, e.to_string()))?;
                // The commit also wrote the working state.
                self.persist_at = None;
                let number = info.number;
                let _ = self.events.send(DesignEvent::Committed(info));
                Ok(Ack {
                    created_icon: None,
                    version: Some(number),
                })
            }
            Command::Revert | Command::Restore { .. } => {
                let store = self.store.clone();
                let id = self.id;
                let wanted = match command {
                    Command::Restore { version } => Some(version),
                    _ => None,
                };
                let found = tokio::task::spawn_blocking(move || match wanted {
                    Some(v) => store.version(id, v),
                    None => store.latest_version(id),
                })
                .await
                .map_err(|e| CommandError::new(ErrorKind::Storage, e.to_string()))?
                .map_err(|e| CommandError::new(ErrorKind::Storage, e.to_string()))?;
                let (info, bytes) = found.ok_or_else(|| {
                    CommandError::new(ErrorKind::UnknownVersion, "no such version")
                })?;
                let doc = DesignDoc::from_bytes(&bytes)?;
                let model = DesignModel::load(&doc)?;
                self.undo.push(self.model.to_doc());
                self.model = model;
                self.dragging.clear();
                self.changed(true);
                let _ = self.events.send(DesignEvent::Restored(info.number));
                *geometry_dirty = true;
                Ok(Ack {
                    created_icon: None,
                    version: Some(info.number),
                })
            }
        }
    }
}
