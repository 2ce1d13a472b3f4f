//! One task per design: it alone holds the design's kernel state (no locks
//! around the solver), runs every command in arrival order, coalesces drag
//! frames, keeps undo/redo, tracks presence, persists the working state at
//! most `persist_delay` after a change — on the blocking pool, while it goes
//! on serving drags (one write in flight at a time, settled before any other
//! write of this design so the store sees them in order), writes commits
//! on the blocking pool too, answering them once durable
//! ([`super::commit_write`]) — and publishes
//!
//! * geometry on a `watch` channel — latest wins, a slow client skips frames;
//! * ordered events on a bounded `broadcast` channel — never dropped
//!   silently: a client that lags past its capacity resyncs from a fresh
//!   full state (see [`Request::Resync`]).

use super::command::{Ack, Command};
use super::doc::IconDoc;
use super::edit::MaterialEdit;
use super::error::{CommandError, ErrorKind};
use super::model::{DesignDoc, DesignModel, GeometrySet};
use super::part::{PartDoc, RelationDoc};
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
/// First retry of a failed working-state write.
pub const PERSIST_RETRY_MIN: Duration = Duration::from_millis(500);
/// Longest wait between retries of a failed working-state write.
pub const PERSIST_RETRY_MAX: Duration = Duration::from_secs(5);

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
    /// Where its pointer or hand is, if it said.
    pub pointer: Option<[f64; 3]>,
    /// Where its view camera is, if it said (others may follow it).
    pub camera: Option<vsculpt_protocol::Camera>,
}

/// The full state a client needs to (re)build its view.
#[derive(Clone, Debug)]
pub struct SnapshotView {
    /// The design id.
    pub design: DesignId,
    /// The document.
    pub doc: Arc<DesignDoc>,
    /// Shape revision.
    pub revision: u64,
    /// Committed versions, oldest first.
    pub versions: Arc<Vec<VersionInfo>>,
    /// Who is here.
    pub presence: Arc<Vec<Presence>>,
    /// Undo available.
    pub can_undo: bool,
    /// Redo available.
    pub can_redo: bool,
    /// The review comments, oldest first.
    pub comments: Arc<Vec<super::comments::CommentThread>>,
    /// The fairing jobs running, each with its latest progress.
    pub fairing: Vec<super::fairing_job::JobProgress>,
}

/// Where a dragged icon actually went (the bridge's spring model needs it).
/// The parts whose geometry a batch of requests changed.
#[derive(Clone, Debug, Default)]
struct Dirty {
    /// Every part (a new state: undo, restore, import).
    all: bool,
    /// A part was deleted (its frame goes from the set).
    removed: bool,
    /// These parts moved.
    parts: std::collections::BTreeSet<u64>,
    /// These parts' drags ended: their frames go out full, not as drag
    /// frames, even when a drag of another part ran in the same batch.
    rest: std::collections::BTreeSet<u64>,
}

impl Dirty {
    fn parts(&mut self, ids: Vec<u64>) {
        self.parts.extend(ids);
    }

    fn is_empty(&self) -> bool {
        !self.all && !self.removed && self.parts.is_empty()
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Feedback {
    /// The part the icon is on.
    pub part: u64,
    /// The icon.
    pub icon: u64,
    /// Where the client asked it to be.
    pub requested: DVec3,
    /// Where it is on the solved surface.
    pub actual: DVec3,
    /// Shape revision.
    pub revision: u64,
    /// Why the solve misses a constraint, if it does.
    pub warning: Option<String>,
}

/// A drag frame without a request number that was refused (unknown icon,
/// held by another client, …): the client still hears of it, latest wins,
/// so a stream of refused frames costs one error per writer wake-up.
#[derive(Clone, Debug, PartialEq)]
pub struct Refusal {
    /// Counts refusals for this client, so equal errors still notify.
    pub seq: u64,
    /// Why.
    pub error: CommandError,
}

/// An ordered event every client of a design receives.
#[derive(Clone, Debug)]
pub enum DesignEvent {
    /// The whole state changed (undo, redo, revert, restore, import).
    Snapshot(Arc<SnapshotView>),
    /// An icon was created on a part (with its holder).
    IconCreated(u64, IconDoc, Option<u64>),
    /// An icon of a part changed (with its holder).
    IconUpdated(u64, IconDoc, Option<u64>),
    /// An icon of a part was deleted.
    IconDeleted(u64, u64),
    /// A part's material changed.
    MaterialChanged(u64, MaterialEdit),
    /// A part was created (with the holders of its icons).
    PartCreated(PartDoc, BTreeMap<u64, u64>),
    /// A part was deleted.
    PartDeleted(u64),
    /// A part was renamed, shown or hidden, locked or unlocked, recoloured.
    PartChanged(PartDoc),
    /// A network part's curves or faired faces changed (with its meetings
    /// and faces).
    NetworkChanged(u64, Arc<super::network_engine::NetworkView>),
    /// A DSM part's shape data changed (its mesh follows as a frame).
    DsmChanged(PartDoc),
    /// A fairing job's progress (see [`super::fairing_job`]).
    FairingProgress(Box<super::fairing_job::JobProgress>),
    /// A fairing job ended.
    FairingEnded(Box<super::fairing_job::JobEnded>),
    /// A relation was created.
    RelationCreated(RelationDoc),
    /// A relation was removed.
    RelationDeleted(u64),
    /// A review comment was added, changed or deleted.
    Comment(super::comments::CommentChange),
    /// A version was committed.
    Committed(VersionInfo),
    /// A client joined, or what it holds or points at changed.
    PresenceChanged(Presence),
    /// A client left.
    PresenceLeft(u64),
    /// Undo/redo availability changed.
    History {
        /// Undo available.
        can_undo: bool,
        /// Redo available.
        can_redo: bool,
    },
    /// The design was deleted; the actor stops.
    Deleted(DesignId),
}

/// What a joining (or resyncing) client gets, consistent with each other.
pub struct Joined {
    /// Full state at the moment of joining.
    pub view: Arc<SnapshotView>,
    /// Events after that state.
    pub events: broadcast::Receiver<DesignEvent>,
    /// Latest geometry.
    pub geometry: watch::Receiver<Arc<GeometrySet>>,
    /// This client's drag feedback (latest wins).
    pub feedback: watch::Receiver<Option<Feedback>>,
    /// This client's refused drag frames (latest wins).
    pub refusals: watch::Receiver<Option<Refusal>>,
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
        /// Its connection id.
        client: u64,
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
    /// A client's pointer moved (presence).
    Pointer {
        /// Connection id.
        client: u64,
        /// Where, if anywhere.
        pointer: Option<[f64; 3]>,
        /// The view camera: `Some` from a presence message (which states it,
        /// `Some(None)` for none), `None` from a device sample (which moves
        /// only the pointer and leaves the camera as it was).
        camera: Option<Option<vsculpt_protocol::Camera>>,
    },
    /// The committed versions.
    Versions {
        /// The answer.
        reply: oneshot::Sender<Arc<Vec<VersionInfo>>>,
    },
    /// The current full state.
    State {
        /// The answer.
        reply: oneshot::Sender<Arc<SnapshotView>>,
    },
    /// A tessellation for mesh export.
    Mesh {
        /// One part, or the whole product.
        part: Option<u64>,
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
    /// A fairing job's run came back (see [`super::fairing_job`]).
    FairingDone(Box<super::fairing_job::JobDone>),
    /// The design was deleted: tell clients and stop.
    Delete,
    /// Flush the working state and stop.
    Stop {
        /// Answered once flushed.
        reply: oneshot::Sender<()>,
    },
    /// Test-only fault injection: the actor panics when it runs this.
    #[cfg(feature = "fault-injection")]
    Panic,
}

/// Runs CPU-heavy model work (a rebuild and solve: a refactorisation on
/// large surfaces) without stalling the runtime's other tasks, where the
/// runtime allows it.
fn heavy<T>(f: impl FnOnce() -> T) -> T {
    match tokio::runtime::Handle::try_current().map(|h| h.runtime_flavor()) {
        Ok(tokio::runtime::RuntimeFlavor::MultiThread) => tokio::task::block_in_place(f),
        _ => f(),
    }
}

/// Test-only fault injection for the binary: with
/// `VSCULPT_FAULT_HANG_ON_STOP=<design id>` in a build with the
/// `fault-injection` feature, that design's actor never finishes its stop
/// (as if stuck in a solve), so the shutdown deadline can be tested.
#[cfg(feature = "fault-injection")]
fn hang_on_stop(id: DesignId) {
    let hang = std::env::var("VSCULPT_FAULT_HANG_ON_STOP")
        .ok()
        .and_then(|v| v.parse::<DesignId>().ok())
        == Some(id);
    if hang {
        heavy(|| std::thread::sleep(Duration::from_secs(3600)));
    }
}

/// A handle to a running design actor.
#[derive(Clone, Debug)]
pub struct DesignHandle {
    /// The design.
    pub id: DesignId,
    tx: mpsc::Sender<Request>,
    /// Set by the actor when it stops on purpose (the design was deleted,
    /// or the server is stopping), before it stops.
    retired: Arc<std::sync::atomic::AtomicBool>,
}

impl DesignHandle {
    /// Why the actor cannot answer: the design was deleted, or the actor
    /// died (it is being restarted by its supervisor).
    fn gone(&self) -> CommandError {
        if self.retired.load(std::sync::atomic::Ordering::SeqCst) {
            CommandError::new(ErrorKind::UnknownDesign, "the design is closed or deleted")
        } else {
            CommandError::new(
                ErrorKind::Unavailable,
                format!(
                    "design {} stopped after a failure and is restarting; reconnect",
                    self.id
                ),
            )
        }
    }
}

impl DesignHandle {
    /// Sends a request (waits when the queue is full).
    pub async fn send(&self, r: Request) -> Result<(), CommandError> {
        self.tx.send(r).await.map_err(|_| self.gone())
    }

    /// Whether the actor has stopped.
    pub fn is_closed(&self) -> bool {
        self.tx.is_closed()
    }

    /// Joins the design.
    pub async fn join(&self, client: ClientInfo) -> Result<Joined, CommandError> {
        let (reply, rx) = oneshot::channel();
        self.send(Request::Join { client, reply }).await?;
        rx.await.map_err(|_| self.gone())
    }

    /// A fresh state and event stream for a client that lagged.
    pub async fn resync(&self, client: u64) -> Result<Joined, CommandError> {
        let (reply, rx) = oneshot::channel();
        self.send(Request::Resync { client, reply }).await?;
        rx.await.map_err(|_| self.gone())
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
        rx.await.map_err(|_| self.gone())?
    }

    /// Queues a drag frame (no ack; errors come back only as events).
    pub async fn drag(
        &self,
        client: u64,
        part: u64,
        icon: u64,
        xyz: DVec3,
    ) -> Result<(), CommandError> {
        self.send(Request::Command {
            client,
            command: Command::Drag { part, icon, xyz },
            reply: None,
        })
        .await
    }

    /// The design's current state.
    pub async fn state(&self) -> Result<Arc<SnapshotView>, CommandError> {
        let (reply, rx) = oneshot::channel();
        self.send(Request::State { reply }).await?;
        rx.await.map_err(|_| self.gone())
    }

    /// The committed versions.
    pub async fn versions(&self) -> Result<Arc<Vec<VersionInfo>>, CommandError> {
        let (reply, rx) = oneshot::channel();
        self.send(Request::Versions { reply }).await?;
        rx.await.map_err(|_| self.gone())
    }

    /// A tessellation of one part, or of the whole product.
    pub async fn mesh(
        &self,
        part: Option<u64>,
        density: usize,
    ) -> Result<super::model::MeshData, CommandError> {
        let (reply, rx) = oneshot::channel();
        self.send(Request::Mesh {
            part,
            density,
            reply,
        })
        .await?;
        rx.await.map_err(|_| self.gone())?
    }

    /// Replaces the design's document (undoable).
    pub async fn replace(&self, doc: DesignDoc) -> Result<Ack, CommandError> {
        let (reply, rx) = oneshot::channel();
        self.send(Request::Replace {
            doc: Box::new(doc),
            reply,
        })
        .await?;
        rx.await.map_err(|_| self.gone())?
    }

    /// Flushes and stops the actor.
    pub async fn stop(&self) {
        let (reply, rx) = oneshot::channel();
        if self.send(Request::Stop { reply }).await.is_ok() {
            let _ = rx.await;
        }
    }
}

/// Counts the actor in `vsculpt_designs_open` for as long as it lives,
/// however it ends (a panic included).
struct OpenGauge(Arc<Metrics>);

impl Drop for OpenGauge {
    fn drop(&mut self) {
        self.0.design_open(-1);
    }
}

/// What woke the actor's loop.
enum Wake {
    /// This many requests arrived (0: every handle is gone).
    Requests(usize),
    /// A working-state write is due.
    PersistDue,
    /// The working-state write in flight landed.
    Written(Result<Result<(), String>, tokio::task::JoinError>),
    /// The commit in flight landed.
    Committed(super::commit_write::Landed),
    /// The comment write in flight landed.
    Commented(super::comment_write::Landed),
    /// Nothing is waiting and an edit left work for idle time.
    Idle,
}

/// The actor's state.
struct Actor {
    _open: OpenGauge,
    retired: Arc<std::sync::atomic::AtomicBool>,
    id: DesignId,
    model: DesignModel,
    store: Arc<Store>,
    metrics: Arc<Metrics>,
    persist_delay: Duration,
    undo: UndoStack,
    clients: BTreeMap<u64, Presence>,
    feedback: BTreeMap<u64, watch::Sender<Option<Feedback>>>,
    refusals: BTreeMap<u64, watch::Sender<Option<Refusal>>>,
    events: broadcast::Sender<DesignEvent>,
    geometry: watch::Sender<Arc<GeometrySet>>,
    doc: Arc<DesignDoc>,
    versions: Arc<Vec<VersionInfo>>,
    /// The version last committed, restored or reverted to (0: none), the
    /// one a comment written now is about.
    base_version: u64,
    /// The review comments.
    comments: super::comments::CommentBook,
    rev: u64,
    persist_at: Option<Instant>,
    /// The back-off of the working-state write while it fails.
    persist_retry: Option<Duration>,
    /// The working-state write in flight, if any: the actor keeps serving
    /// requests while it runs (a write with its fsync takes tens of
    /// milliseconds, which a drag must not wait for).
    persisting: Option<tokio::task::JoinHandle<Result<(), String>>>,
    /// Commits asked and not yet durable (see [`super::commit_write`]):
    /// written one at a time, in order, while the actor goes on.
    commits: super::commit_write::CommitWrites,
    /// Comment requests not yet durable (see [`super::comment_write`]):
    /// written one at a time, in order, while the actor goes on.
    comment_writes: super::comment_write::CommentWrites,
    /// The (part, icon) each client is dragging.
    dragging: BTreeMap<u64, (u64, u64)>,
    /// Whether the geometry published last came from a drag.
    drag_frame: bool,
    /// The parts' drag streams (see [`super::drag_stream`]).
    streams: super::drag_stream::DragStreams,
    /// The fairing jobs running off the actor.
    jobs: super::fairing_job::FairingJobs,
}

/// Starts the actor of design `id` from `doc`, with its committed versions;
/// the task's handle tells its supervisor how it ended.
pub fn spawn(
    id: DesignId,
    doc: DesignDoc,
    versions: Vec<VersionInfo>,
    comments: super::comments::CommentBook,
    store: Arc<Store>,
    metrics: Arc<Metrics>,
    persist_delay: Duration,
) -> Result<(DesignHandle, tokio::task::JoinHandle<()>), CommandError> {
    let model = DesignModel::load(&doc)?;
    let (tx, rx) = mpsc::channel(REQUEST_CAPACITY);
    let doc = Arc::new(model.to_doc());
    let geometry = watch::channel(Arc::new(model.geometry_set(id, 0))).0;
    metrics.design_open(1);
    let retired = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let events = broadcast::channel(EVENT_CAPACITY).0;
    let jobs = super::fairing_job::FairingJobs::new(tx.downgrade(), events.clone());
    let actor = Actor {
        _open: OpenGauge(metrics.clone()),
        retired: retired.clone(),
        id,
        model,
        commits: super::commit_write::CommitWrites::new(store.clone(), id),
        comment_writes: super::comment_write::CommentWrites::new(store.clone(), id),
        store,
        metrics: metrics.clone(),
        persist_delay,
        undo: UndoStack::new(64),
        clients: BTreeMap::new(),
        feedback: BTreeMap::new(),
        refusals: BTreeMap::new(),
        events,
        geometry,
        doc,
        base_version: versions.last().map_or(0, |v| v.number),
        versions: Arc::new(versions),
        comments,
        rev: 0,
        persist_at: None,
        persist_retry: None,
        persisting: None,
        dragging: BTreeMap::new(),
        drag_frame: false,
        streams: Default::default(),
        jobs,
    };
    let task = tokio::spawn(actor.run(rx));
    Ok((DesignHandle { id, tx, retired }, task))
}

impl Actor {
    async fn run(mut self, mut rx: mpsc::Receiver<Request>) {
        let mut batch: Vec<Request> = Vec::with_capacity(64);
        loop {
            // The next write is due only once the one in flight has landed.
            let persist_at = self.persist_at.filter(|_| !self.writing());
            let sleep = async move {
                match persist_at {
                    Some(t) => tokio::time::sleep_until(t.into()).await,
                    None => std::future::pending().await,
                }
            };
            let writing = self.persisting.as_mut();
            let committing = self.commits.landed();
            let commenting = self.comment_writes.landed();
            // Work an edit deferred (the refactor after a pin change) runs
            // only when no request waits and nobody drags: a grab then
            // finds it done, and no drag frame waits behind it.
            let idle = self.model.idle_work() && self.dragging.is_empty() && rx.is_empty();
            let wake = tokio::select! {
                n = rx.recv_many(&mut batch, 256) => Wake::Requests(n),
                _ = sleep => Wake::PersistDue,
                r = async move {
                    match writing {
                        Some(h) => h.await,
                        None => std::future::pending().await,
                    }
                } => Wake::Written(r),
                landed = committing => Wake::Committed(landed),
                landed = commenting => Wake::Commented(landed),
                () = std::future::ready(()), if idle => Wake::Idle,
            };
            match wake {
                Wake::Requests(0) => break,
                Wake::Requests(_) => {
                    if self.handle_batch(&mut batch).await {
                        break;
                    }
                }
                Wake::PersistDue => self.start_persist(),
                Wake::Written(r) => {
                    self.persisting = None;
                    self.written(r);
                    self.start_commit();
                }
                Wake::Committed(landed) => {
                    self.commit_landed(landed);
                    self.start_commit();
                }
                Wake::Commented(landed) => {
                    self.comment_landed(landed);
                    self.start_comment();
                }
                Wake::Idle => {
                    if let Err(e) = self.model.settle_idle() {
                        // The shape is untouched; the next solve refactors.
                        tracing::warn!(design = self.id, error = %e.message, "idle settle failed");
                    }
                }
            }
        }
        self.settle_comments().await;
        self.persist().await;
        tracing::debug!(design = self.id, "design actor stopped");
    }

    /// Marks drag frames that a later frame of the same client and icon
    /// supersedes before any other request of that client.
    pub(crate) fn superseded(batch: &[Request]) -> Vec<bool> {
        let n = batch.len();
        let mut skip = vec![false; n];
        for k in 0..n {
            let Request::Command {
                client,
                command: Command::Drag { part, icon, .. },
                reply: None,
            } = &batch[k]
            else {
                continue;
            };
            for later in &batch[k + 1..] {
                let c2 = match later {
                    Request::Command { client: c2, .. }
                    | Request::Leave { client: c2 }
                    | Request::Pointer { client: c2, .. } => *c2,
                    _ => continue,
                };
                if c2 != *client {
                    continue;
                }
                if let Request::Command {
                    command:
                        Command::Drag {
                            part: p2, icon: i2, ..
                        },
                    reply: None,
                    ..
                } = later
                    && i2 == icon
                    && p2 == part
                {
                    skip[k] = true;
                }
                break;
            }
        }
        skip
    }

    /// Runs a batch; returns true when the actor must stop.
    async fn handle_batch(&mut self, batch: &mut Vec<Request>) -> bool {
        let skip = Self::superseded(batch);
        let mut geometry_dirty = Dirty::default();
        let mut stop = false;
        for (k, req) in batch.drain(..).enumerate() {
            if skip[k] || stop {
                continue;
            }
            match req {
                Request::Join { client, reply } => {
                    tracing::info!(design = self.id, client = client.id, role = ?client.role, "client joined");
                    let id = client.id;
                    self.clients.insert(
                        id,
                        Presence {
                            client,
                            holding: None,
                            pointer: None,
                            camera: None,
                        },
                    );
                    // Subscribe first so the newcomer hears the presence too.
                    let joined = self.joined(id);
                    self.broadcast_presence(id);
                    let _ = reply.send(joined);
                }
                Request::Resync { client, reply } => {
                    let _ = reply.send(self.joined(client));
                }
                Request::Leave { client } => {
                    self.feedback.remove(&client);
                    self.refusals.remove(&client);
                    if let Some((part, icon)) = self.dragging.remove(&client)
                        && let Ok(moved) = self.model.release(part, icon)
                    {
                        self.changed();
                        self.announce_icon(icon);
                        geometry_dirty.parts(moved);
                        geometry_dirty.parts(self.streams.at_rest(part));
                        geometry_dirty.rest.insert(part);
                    }
                    if self.clients.remove(&client).is_some() {
                        self.broadcast_presence(client);
                    }
                }
                Request::Command {
                    client,
                    command:
                        Command::Edit(super::model::Edit::Network {
                            part,
                            edit: super::network_engine::NetworkEditDoc::Fair(f),
                        }),
                    reply,
                } => {
                    let role = self.role(client);
                    self.jobs.start(&self.model, client, role, part, &f, reply);
                }
                Request::FairingDone(done) => {
                    if let Some(apply) = self.jobs.finish(*done, &self.model) {
                        let edit = Command::Edit(apply.edit.clone());
                        let out = self.command(0, edit, &mut geometry_dirty).await;
                        self.jobs.applied(apply, out);
                    }
                }
                Request::Command {
                    client,
                    command: Command::Commit { message },
                    reply,
                } => self.ask_commit(client, message, reply),
                Request::Command {
                    client,
                    command: Command::Comment(op),
                    reply,
                } => self.ask_comment(client, op, reply),
                Request::Command {
                    client,
                    command,
                    reply,
                } => {
                    let out = self.command(client, command, &mut geometry_dirty).await;
                    match (reply, out) {
                        (Some(reply), out) => {
                            let _ = reply.send(out);
                        }
                        (None, Err(e)) => {
                            tracing::debug!(design = self.id, client, "drag refused: {e}");
                            if let Some(tx) = self.refusals.get(&client) {
                                tx.send_modify(|r| {
                                    let seq = r.as_ref().map_or(1, |r| r.seq + 1);
                                    *r = Some(Refusal { seq, error: e });
                                });
                            }
                        }
                        (None, Ok(_)) => {}
                    }
                }
                Request::Pointer {
                    client,
                    pointer,
                    camera,
                } => {
                    let changed = match self.clients.get_mut(&client) {
                        Some(p) => {
                            let camera = camera.unwrap_or(p.camera);
                            let changed = p.pointer != pointer || p.camera != camera;
                            p.pointer = pointer;
                            p.camera = camera;
                            changed
                        }
                        None => false,
                    };
                    if changed {
                        self.broadcast_presence(client);
                    }
                }
                Request::Versions { reply } => {
                    let _ = reply.send(self.versions.clone());
                }
                Request::State { reply } => {
                    let _ = reply.send(self.view());
                }
                Request::Mesh {
                    part,
                    density,
                    reply,
                } => {
                    let _ = reply.send(self.model.mesh(part, density));
                }
                Request::Replace { doc, reply } => {
                    let out = match heavy(|| DesignModel::load_replacing(&doc, &mut self.model)) {
                        Ok(m) => {
                            self.undo.push(self.model.to_doc());
                            self.model = m;
                            self.clear_drags();
                            self.changed();
                            self.broadcast_snapshot();
                            geometry_dirty.all = true;
                            Ok(Ack::default())
                        }
                        Err(e) => Err(e),
                    };
                    let _ = reply.send(out);
                }
                Request::Delete => {
                    // No write may land after the deletion; commits asked
                    // before it are answered first.
                    self.settle_writes().await;
                    self.retired
                        .store(true, std::sync::atomic::Ordering::SeqCst);
                    let _ = self.events.send(DesignEvent::Deleted(self.id));
                    self.persist_at = None;
                    stop = true;
                }
                Request::Stop { reply } => {
                    #[cfg(feature = "fault-injection")]
                    hang_on_stop(self.id);
                    self.retired
                        .store(true, std::sync::atomic::Ordering::SeqCst);
                    self.persist().await;
                    let _ = reply.send(());
                    stop = true;
                }
                #[cfg(feature = "fault-injection")]
                Request::Panic => panic!("fault injection: design {} actor panics", self.id),
            }
        }
        if !self.jobs.is_empty() {
            self.jobs.cancel_orphans(&self.model);
        }
        if !geometry_dirty.is_empty() && !stop {
            self.publish_geometry(&geometry_dirty);
        }
        stop
    }

    fn holders(&self) -> BTreeMap<u64, u64> {
        self.dragging.iter().map(|(&c, &(_, i))| (i, c)).collect()
    }

    fn view(&self) -> Arc<SnapshotView> {
        Arc::new(SnapshotView {
            design: self.id,
            doc: self.doc.clone(),
            revision: self.rev,
            versions: self.versions.clone(),
            presence: Arc::new(self.clients.values().cloned().collect()),
            can_undo: self.undo.can_undo(),
            can_redo: self.undo.can_redo(),
            comments: self.comments.view(),
            fairing: self.jobs.running(),
        })
    }

    fn joined(&mut self, client: u64) -> Joined {
        let feedback = watch::channel(None);
        self.feedback.insert(client, feedback.0);
        let refusals = watch::channel(None);
        self.refusals.insert(client, refusals.0);
        Joined {
            view: self.view(),
            events: self.events.subscribe(),
            geometry: self.geometry.subscribe(),
            feedback: feedback.1,
            refusals: refusals.1,
        }
    }

    /// Presence by deltas: what changed about `client` (it joined, holds
    /// or points elsewhere) or that it left — one entry, whatever the number
    /// of clients, instead of the whole list on every change.
    fn broadcast_presence(&self, client: u64) {
        let event = match self.clients.get(&client) {
            Some(p) => DesignEvent::PresenceChanged(p.clone()),
            None => DesignEvent::PresenceLeft(client),
        };
        let _ = self.events.send(event);
    }

    fn broadcast_snapshot(&self) {
        let _ = self.events.send(DesignEvent::Snapshot(self.view()));
    }

    fn broadcast_history(&self) {
        let _ = self.events.send(DesignEvent::History {
            can_undo: self.undo.can_undo(),
            can_redo: self.undo.can_redo(),
        });
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
            self.broadcast_presence(client);
        }
    }

    fn clear_drags(&mut self) {
        let held: Vec<u64> = self.dragging.keys().copied().collect();
        self.dragging.clear();
        for c in held {
            self.set_holding(c, None);
        }
    }

    /// After a change of the document: refresh it, schedule a persist.
    fn changed(&mut self) {
        self.doc = Arc::new(self.model.to_doc());
        if self.persist_at.is_none() {
            self.persist_at = Some(Instant::now() + self.persist_delay);
        }
    }

    /// Events for what differs between `before` and the current document:
    /// parts created, deleted and changed; per part, icons created, changed
    /// and deleted and the material; relations created and removed.
    fn announce_diff(&self, before: &DesignDoc) {
        let holders = self.holders();
        let send = |e: DesignEvent| {
            let _ = self.events.send(e);
        };
        for old in &before.parts {
            if self.doc.part(old.id).is_none() {
                send(DesignEvent::PartDeleted(old.id));
            }
        }
        for old in &before.relations {
            if !self.doc.relations.iter().any(|r| r.id == old.id) {
                send(DesignEvent::RelationDeleted(old.id));
            }
        }
        for part in &self.doc.parts {
            let Some(old) = before.part(part.id) else {
                send(DesignEvent::PartCreated(part.clone(), holders.clone()));
                continue;
            };
            if (&old.name, old.visible, old.locked, &old.colour)
                != (&part.name, part.visible, part.locked, &part.colour)
            {
                send(DesignEvent::PartChanged(part.clone()));
            }
            if old.body != part.body
                && let Some(n) = self.model.network(part.id)
            {
                send(DesignEvent::NetworkChanged(part.id, Arc::new(n.view())));
            }
            if let (super::part::PartBody::Dsm(a), super::part::PartBody::Dsm(b)) =
                (&old.body, &part.body)
                && a != b
            {
                send(DesignEvent::DsmChanged(part.clone()));
            }
            let old_icons = old.body.icons();
            for icon in part.body.icons() {
                match old_icons.iter().find(|i| i.id == icon.id) {
                    None => send(DesignEvent::IconCreated(
                        part.id,
                        icon.clone(),
                        holders.get(&icon.id).copied(),
                    )),
                    Some(o) if o != icon => send(DesignEvent::IconUpdated(
                        part.id,
                        icon.clone(),
                        holders.get(&icon.id).copied(),
                    )),
                    Some(_) => {}
                }
            }
            for o in old_icons {
                if !part.body.icons().iter().any(|i| i.id == o.id) {
                    send(DesignEvent::IconDeleted(part.id, o.id));
                }
            }
            let (m_old, m_new) = (
                crate::convert::parts::body_material(&old.body),
                crate::convert::parts::body_material(&part.body),
            );
            if m_old != m_new {
                send(DesignEvent::MaterialChanged(part.id, m_new));
            }
        }
        for r in &self.doc.relations {
            if !before.relations.iter().any(|o| o.id == r.id) {
                send(DesignEvent::RelationCreated(r.clone()));
            }
        }
    }

    fn announce_icon(&self, icon: u64) {
        if let Some((p, i)) = self.doc.icon(icon) {
            let _ = self.events.send(DesignEvent::IconUpdated(
                p.id,
                i.clone(),
                self.holders().get(&icon).copied(),
            ));
        }
    }

    /// Publishes new frames of the dirty parts (every part when `all`);
    /// the other parts keep their frames, so a writer resends only what
    /// changed.
    fn publish_geometry(&mut self, dirty: &Dirty) {
        self.rev += 1;
        let set = if dirty.all {
            self.streams.clear();
            self.model.geometry_set(self.id, self.rev)
        } else {
            let mut set = (**self.geometry.borrow()).clone();
            set.parts
                .retain(|id, _| self.model.doc().part(*id).is_some());
            for &part in &dirty.parts {
                let g = if self.drag_frame && !dirty.rest.contains(&part) {
                    let previous = set.parts.get(&part).cloned();
                    self.model.drag_geometry(
                        self.id,
                        part,
                        self.rev,
                        previous.as_deref(),
                        &mut self.streams,
                    )
                } else {
                    self.streams.forget(part);
                    let previous = set.parts.get(&part);
                    self.model
                        .geometry(self.id, part, self.rev, false)
                        .map(|mut g| {
                            // A bound DSM part's frame comes with its delta
                            // (kept encoded and patched); others are compared.
                            if g.mesh_delta.is_none() {
                                g.mesh_delta = previous.and_then(|p| {
                                    super::dsm_delta::mesh_delta(p.rev, &p.frame, &g.frame)
                                });
                            }
                            g
                        })
                };
                if let Some(g) = g {
                    set.parts.insert(part, Arc::new(g));
                }
            }
            set
        };
        self.geometry.send_replace(Arc::new(set));
        self.drag_frame = false;
    }

    /// Starts writing the working state on the blocking pool if a write is
    /// due and none is in flight (the run loop starts the next one when the
    /// one in flight lands).
    fn start_persist(&mut self) {
        if self.writing() || self.persist_at.take().is_none() {
            return;
        }
        let bytes = self.model.to_doc().to_bytes();
        let store = self.store.clone();
        let id = self.id;
        self.persisting = Some(tokio::task::spawn_blocking(move || {
            store.save_working(id, &bytes).map_err(|e| e.to_string())
        }));
    }

    /// Waits for the working-state write in flight, if any, and records how
    /// it ended: called before any other write of this design, so that an
    /// older working state never lands after a newer one.
    async fn settle_persist(&mut self) {
        if let Some(h) = self.persisting.take() {
            let r = h.await;
            self.written(r);
        }
    }

    /// Writes the working state now if a write is due (stop, shutdown),
    /// after every write in flight or queued (commits asked before the stop
    /// are written and answered: nothing acked is lost).
    async fn persist(&mut self) {
        self.settle_writes().await;
        self.start_persist();
        self.settle_persist().await;
    }

    /// Whether a write of this design (working state or commit) is in
    /// flight: the store gets one at a time, in order.
    fn writing(&self) -> bool {
        self.persisting.is_some() || self.commits.in_flight()
    }

    /// Starts the oldest queued commit if no write is in flight. Commits go
    /// before a due working-state write: they write the working state too.
    fn start_commit(&mut self) {
        if !self.writing() {
            self.commits.start();
        }
    }

    /// A client asks for a commit. The snapshot is the design as it is now:
    /// edits that arrive while the commit is written belong to the next
    /// version. The reply, the `committed` event and the version in the
    /// list wait until the write is durable ([`Actor::commit_landed`]);
    /// meanwhile the actor serves everyone as usual.
    fn ask_commit(
        &mut self,
        client: u64,
        message: String,
        reply: Option<super::commit_write::Reply>,
    ) {
        let command = Command::Commit { message };
        if let Err(e) = self.authorize(client, &command) {
            if let Some(reply) = reply {
                let _ = reply.send(Err(e));
            }
            return;
        }
        let Command::Commit { message } = command else {
            return;
        };
        let author = self
            .clients
            .get(&client)
            .map(|p| p.client.name.clone())
            .unwrap_or_else(|| "rest".into());
        self.commits.ask(super::commit_write::Asked {
            doc: self.model.to_doc(),
            author,
            message,
            reply,
            // The commit writes this state as the working state too.
            persist_due: self.persist_at.take(),
        });
        self.start_commit();
    }

    /// A commit's write ended: once durable, the version joins the list,
    /// every client hears `committed` and the asker gets the number; a
    /// failed write changes nothing (the asker gets why) and the working
    /// state it would have written is due again.
    fn commit_landed(&mut self, landed: super::commit_write::Landed) {
        let super::commit_write::Landed {
            outcome,
            reply,
            persist_due,
        } = landed;
        let out = match outcome {
            Ok(info) => {
                if self.persist_retry.take().is_some() {
                    tracing::info!(
                        design = self.id,
                        "working state saved again (with a commit)"
                    );
                }
                let number = info.number;
                self.base_version = number;
                let mut versions = (*self.versions).clone();
                versions.push(info.clone());
                self.versions = Arc::new(versions);
                let _ = self.events.send(DesignEvent::Committed(info));
                Ok(Ack {
                    version: Some(number),
                    ..Ack::default()
                })
            }
            Err(e) => {
                tracing::warn!(design = self.id, "commit not stored: {e}");
                if let Some(due) = persist_due {
                    self.persist_at = Some(self.persist_at.map_or(due, |t| t.min(due)));
                }
                Err(e)
            }
        };
        if let Some(reply) = reply {
            let _ = reply.send(out);
        }
    }

    /// Waits until no write of this design is in flight or queued,
    /// answering each commit as it lands (before a revert, a restore, a
    /// deletion, a stop).
    async fn settle_writes(&mut self) {
        loop {
            if self.persisting.is_some() {
                self.settle_persist().await;
            } else if self.commits.in_flight() {
                let landed = self.commits.landed().await;
                self.commit_landed(landed);
            } else if !self.commits.pending() {
                return;
            }
            self.start_commit();
        }
    }

    /// Records how a working-state write ended. A failed write (disk full,
    /// read-only, I/O error) keeps the state in memory and is retried after
    /// a back-off growing to [`PERSIST_RETRY_MAX`]; the first failure and
    /// the recovery are logged once.
    fn written(&mut self, r: Result<Result<(), String>, tokio::task::JoinError>) {
        let id = self.id;
        let failed = match r {
            Ok(Ok(())) => None,
            Ok(Err(e)) => Some(e),
            Err(e) => Some(format!("writer task failed: {e}")),
        };
        match failed {
            None => {
                if self.persist_retry.take().is_some() {
                    tracing::info!(design = id, "working state saved again");
                }
            }
            Some(e) => {
                self.metrics.store_write_failed();
                let retry = match self.persist_retry {
                    None => {
                        tracing::error!(
                            design = id,
                            "cannot save the working state: {e}; keeping it in memory and retrying"
                        );
                        PERSIST_RETRY_MIN
                    }
                    Some(d) => (d * 2).min(PERSIST_RETRY_MAX),
                };
                self.persist_retry = Some(retry);
                // Changes made meanwhile are written by the retry.
                self.persist_at = Some(Instant::now() + retry);
            }
        }
    }

    /// A client asks something of the comments: queued behind the comment
    /// requests before it, checked when its turn comes, written off the
    /// actor, answered and announced once durable ([`Actor::comment_landed`]).
    fn ask_comment(
        &mut self,
        client: u64,
        op: super::comments::CommentOp,
        reply: Option<super::commit_write::Reply>,
    ) {
        let command = Command::Comment(op);
        if let Err(e) = self.authorize(client, &command) {
            if let Some(reply) = reply {
                let _ = reply.send(Err(e));
            }
            return;
        }
        let Command::Comment(op) = command else {
            return;
        };
        self.comment_writes
            .ask(super::comment_write::Asked { client, op, reply });
        self.start_comment();
    }

    /// Starts the oldest waiting comment request's write if none is in
    /// flight: checked now against the comments and the design (so it sees
    /// the writes before it); one that fails its check is answered at once
    /// and the next one gets its turn.
    fn start_comment(&mut self) {
        while let Some(asked) = self.comment_writes.take_turn() {
            let super::comment_write::Asked { client, op, reply } = asked;
            let checked = match self.clients.get(&client) {
                Some(p) => Ok((p.client.role, p.client.name.clone())),
                None if client == 0 => Ok((Role::Editor, "rest".to_string())),
                None => Err(CommandError::new(ErrorKind::Forbidden, "not joined")),
            }
            .and_then(|(role, author)| {
                self.comments
                    .check(op, role, &author, self.base_version, &self.model)
            });
            match checked {
                Ok(write) => {
                    self.comment_writes.start(write, reply);
                    return;
                }
                Err(e) => {
                    if let Some(reply) = reply {
                        let _ = reply.send(Err(e));
                    }
                }
            }
        }
    }

    /// A comment write ended: once durable, every client hears of it and
    /// the asker gets the new id; a failed write changes nothing and the
    /// asker gets why.
    fn comment_landed(&mut self, landed: super::comment_write::Landed) {
        let super::comment_write::Landed { outcome, reply } = landed;
        let out = match outcome {
            Ok(written) => {
                let (created, change) = self.comments.apply(written);
                if let Some(change) = change {
                    let _ = self.events.send(DesignEvent::Comment(change));
                }
                Ok(Ack {
                    created_comment: created,
                    ..Ack::default()
                })
            }
            Err(crate::store::StoreError::UnknownComment(_, c)) => Err(CommandError::new(
                ErrorKind::InvalidValue,
                format!("no comment {c} in this design"),
            )),
            Err(e) => {
                tracing::warn!(design = self.id, "comment not stored: {e}");
                Err(CommandError::new(ErrorKind::Storage, e.to_string()))
            }
        };
        if let Some(reply) = reply {
            let _ = reply.send(out);
        }
    }

    /// Waits until no comment request is in flight or waiting, answering
    /// each as it lands (before the actor stops: nothing asked is dropped
    /// unanswered).
    async fn settle_comments(&mut self) {
        while self.comment_writes.pending() {
            self.start_comment();
            if !self.comment_writes.pending() {
                break;
            }
            let landed = self.comment_writes.landed().await;
            self.comment_landed(landed);
        }
    }

    fn role(&self, client: u64) -> Option<Role> {
        self.clients.get(&client).map(|p| p.client.role)
    }

    fn check_holder(&self, client: u64, icon: u64) -> Result<(), CommandError> {
        match self.holders().get(&icon) {
            Some(&holder) if holder != client => Err(CommandError::new(
                ErrorKind::Conflict,
                format!("icon {icon} is held by client {holder}"),
            )),
            _ => Ok(()),
        }
    }

    /// Whether `client`'s role allows `command`.
    fn authorize(&self, client: u64, command: &Command) -> Result<(), CommandError> {
        // REST callers (client 0) were checked by the HTTP layer.
        let role = if client == 0 {
            Role::Editor
        } else {
            self.role(client)
                .ok_or_else(|| CommandError::new(ErrorKind::Forbidden, "not joined"))?
        };
        // Comments have rights of their own (`comments`): viewers comment
        // too, devices do not.
        if let Command::Comment(op) = command {
            return match (role, op) {
                (Role::Device, _) => Err(CommandError::new(
                    ErrorKind::Forbidden,
                    "a device may not comment",
                )),
                _ => Ok(()),
            };
        }
        let allowed = match role {
            Role::Editor => true,
            Role::Viewer => false,
            // A device bridge drags icons, binds its sensors and switches an
            // icon's role and state (the 3D mouse's menu, paper 003); it may
            // not create, delete, commit or restore.
            Role::Device => matches!(
                command,
                Command::Grab { .. }
                    | Command::Drag { .. }
                    | Command::Release { .. }
                    | Command::Edit(super::model::Edit::Part {
                        edit: super::model::PartEdit::BindSensor { .. }
                            | super::model::PartEdit::UnbindSensor { .. }
                            | super::model::PartEdit::SetRole { .. }
                            | super::model::PartEdit::SetState { .. },
                        ..
                    })
            ),
        };
        if !allowed {
            return Err(CommandError::new(
                ErrorKind::Forbidden,
                format!("a {} may not do this", format!("{role:?}").to_lowercase()),
            ));
        }
        Ok(())
    }

    async fn command(
        &mut self,
        client: u64,
        command: Command,
        geometry_dirty: &mut Dirty,
    ) -> Result<Ack, CommandError> {
        self.authorize(client, &command)?;
        match command {
            Command::Edit(edit) => {
                if let super::model::Edit::Part {
                    edit: super::model::PartEdit::DeleteIcon { id },
                    ..
                } = &edit
                {
                    self.check_holder(client, *id)?;
                }
                if let super::model::Edit::DeletePart { part } = &edit
                    && let Some(holder) = self
                        .dragging
                        .iter()
                        .find(|(c, (p, _))| p == part && **c != client)
                        .map(|(c, _)| *c)
                {
                    return Err(CommandError::new(
                        ErrorKind::Conflict,
                        format!("part {part} has an icon held by client {holder}"),
                    ));
                }
                let before = self.doc.clone();
                let t = Instant::now();
                let (created, moved) = heavy(|| self.model.apply(edit))?;
                self.metrics.solve(t.elapsed());
                self.undo.push((*before).clone());
                // A deleted icon (or part) can no longer be held.
                let gone: Vec<u64> = self
                    .dragging
                    .iter()
                    .filter(|(_, (_, i))| self.model.icon(*i).is_none())
                    .map(|(&c, _)| c)
                    .collect();
                for c in gone {
                    self.dragging.remove(&c);
                    self.set_holding(c, None);
                }
                self.changed();
                self.announce_diff(&before);
                self.broadcast_history();
                geometry_dirty.parts(moved);
                // Parts whose frames must appear or vanish.
                if self.doc.parts.len() != before.parts.len() {
                    geometry_dirty.parts(
                        self.doc
                            .parts
                            .iter()
                            .map(|p| p.id)
                            .filter(|id| before.part(*id).is_none())
                            .collect(),
                    );
                    geometry_dirty.removed = true;
                }
                Ok(Ack {
                    created_icon: created.icon,
                    created_part: created.part,
                    created_relation: created.relation,
                    created_comment: None,
                    version: None,
                    warning: self.model.edit_warning().map(str::to_owned),
                })
            }
            Command::Grab { part, icon } => {
                self.model.check_icon(part, icon)?;
                self.model.check_unlocked(part)?;
                self.check_holder(client, icon)?;
                if self.dragging.get(&client) == Some(&(part, icon)) {
                    return Ok(Ack::default());
                }
                if let Some((pp, prev)) = self.dragging.remove(&client) {
                    let _ = self.model.release(pp, prev);
                    geometry_dirty.parts(self.streams.at_rest(pp));
                    geometry_dirty.rest.insert(pp);
                }
                self.undo.push(self.model.to_doc());
                self.model.grab(part, icon)?;
                self.dragging.insert(client, (part, icon));
                self.set_holding(client, Some(icon));
                self.changed();
                self.announce_icon(icon);
                self.broadcast_history();
                Ok(Ack::default())
            }
            Command::Drag { part, icon, xyz } => {
                self.check_holder(client, icon)?;
                if self.dragging.get(&client) != Some(&(part, icon)) {
                    // A drag without drag_start grabs implicitly.
                    Box::pin(self.command(client, Command::Grab { part, icon }, geometry_dirty))
                        .await?;
                }
                let t = Instant::now();
                let (actual, moved, warning) = self.model.drag(part, icon, xyz)?;
                self.metrics.solve(t.elapsed());
                if self.persist_at.is_none() {
                    self.persist_at = Some(Instant::now() + self.persist_delay);
                }
                self.drag_frame = true;
                geometry_dirty.parts(moved);
                if let Some(tx) = self.feedback.get(&client) {
                    tx.send_replace(Some(Feedback {
                        part,
                        icon,
                        requested: xyz,
                        actual,
                        revision: self.rev + 1,
                        warning,
                    }));
                }
                Ok(Ack::default())
            }
            Command::Release { part, icon } => {
                self.model.check_icon(part, icon)?;
                if self.dragging.get(&client) != Some(&(part, icon)) {
                    self.check_holder(client, icon)?;
                    return Ok(Ack::default());
                }
                let moved = self.model.release(part, icon)?;
                geometry_dirty.parts(self.streams.at_rest(part));
                geometry_dirty.rest.insert(part);
                self.dragging.remove(&client);
                self.set_holding(client, None);
                self.changed();
                self.announce_icon(icon);
                geometry_dirty.parts(moved);
                Ok(Ack::default())
            }
            Command::CancelFairing { part, face } => self.jobs.cancel(part, face, client),
            // A comment's reply waits for its write: `handle_batch` queues
            // it with `ask_comment` and never passes it here.
            Command::Comment(_) => Err(CommandError::new(
                ErrorKind::Unavailable,
                "a comment is answered once it is written",
            )),
            Command::BodyMorph { part, t } => {
                let moved = heavy(|| self.model.set_morph_time(part, t))?;
                geometry_dirty.parts(moved);
                Ok(Ack::default())
            }
            Command::Undo | Command::Redo => {
                let current = self.model.to_doc();
                let undo = matches!(command, Command::Undo);
                let target = if undo {
                    self.undo.undo(current.clone())
                } else {
                    self.undo.redo(current.clone())
                };
                let doc = target.ok_or_else(|| {
                    CommandError::new(
                        ErrorKind::NothingToUndo,
                        if undo {
                            "nothing to undo"
                        } else {
                            "nothing to redo"
                        },
                    )
                })?;
                match heavy(|| DesignModel::load_replacing(&doc, &mut self.model)) {
                    Ok(m) => self.model = m,
                    Err(e) => {
                        // Put the stacks back as they were.
                        if undo {
                            self.undo.redo(doc);
                        } else {
                            self.undo.undo(doc);
                        }
                        return Err(e);
                    }
                }
                self.clear_drags();
                self.changed();
                self.broadcast_snapshot();
                geometry_dirty.all = true;
                Ok(Ack::default())
            }
            // A commit's reply waits for its write: `handle_batch` queues it
            // with `ask_commit` and never passes it here.
            Command::Commit { .. } => Err(CommandError::new(
                ErrorKind::Unavailable,
                "a commit is answered once it is written",
            )),
            Command::Revert | Command::Restore { .. } => {
                // Commits asked before land first: the version they name
                // (or the latest) may be one of them.
                self.settle_writes().await;
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
                let model = heavy(|| DesignModel::load_replacing(&doc, &mut self.model))?;
                self.undo.push(self.model.to_doc());
                self.model = model;
                self.base_version = info.number;
                self.clear_drags();
                self.changed();
                self.broadcast_snapshot();
                geometry_dirty.all = true;
                Ok(Ack {
                    version: Some(info.number),
                    ..Ack::default()
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drag(client: u64, icon: u64, z: f64) -> Request {
        Request::Command {
            client,
            command: Command::Drag {
                part: 1,
                icon,
                xyz: DVec3::new(0.0, 0.0, z),
            },
            reply: None,
        }
    }

    #[test]
    fn only_the_newest_drag_frame_per_client_and_icon_runs() {
        let batch = vec![
            drag(1, 7, 1.0),
            drag(2, 7, 1.0),
            drag(1, 7, 2.0),
            drag(1, 8, 1.0),
            drag(1, 8, 2.0),
            Request::Command {
                client: 2,
                command: Command::Release { part: 1, icon: 7 },
                reply: None,
            },
            drag(2, 7, 3.0),
            drag(1, 8, 3.0),
        ];
        let skip = Actor::superseded(&batch);
        // Client 1: icon 7's first frame is superseded by its second; the
        // second is kept because a frame for another icon (8) follows; icon
        // 8's frames 3 and 4 are superseded by frame 7 (other clients'
        // requests in between do not matter). Client 2's frame before its own
        // release is kept: ordering with other commands holds.
        assert_eq!(
            skip,
            vec![true, false, false, true, true, false, false, false]
        );
    }
}
