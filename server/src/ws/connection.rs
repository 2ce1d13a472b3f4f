//! One WebSocket connection: the hello (protocol version + token), joining
//! the design, then the reader loop that validates every message at the
//! edge and turns it into a design command. Bad input of any kind (malformed
//! JSON, unknown message, oversized message, NaN, unknown ids, a viewer's
//! edit) gets an error reply with a stable code; the connection and the
//! server stay up and the design is unchanged.

use super::join_geometry;
use super::rate::{self, RateLimiter};
use super::writer::{self, Out};
use crate::app::{AppState, Caller};
use crate::convert::{self, Inbound, WireError};
use crate::design::{ClientInfo, CommandError, DesignHandle, ErrorKind};
use crate::store::{DesignId, Role};
use axum::extract::ws::{Message, WebSocket};
use futures_util::StreamExt;
use futures_util::stream::SplitStream;
use std::collections::HashMap;
use std::sync::atomic::Ordering;
use std::time::Duration;
use tokio::sync::mpsc;

/// How long a new connection may take to send its hello.
pub const HELLO_TIMEOUT: Duration = Duration::from_secs(10);
/// Capacity of a client's reply queue.
pub const REPLY_CAPACITY: usize = 64;

struct ClientGuard(std::sync::Arc<crate::metrics::Metrics>);

impl Drop for ClientGuard {
    fn drop(&mut self) {
        self.0.client(-1);
    }
}

/// The session of an authenticated connection.
struct Session {
    state: AppState,
    client: u64,
    name: String,
    token: String,
    role: Role,
    handle: DesignHandle,
    out: mpsc::Sender<Out>,
    limiter: RateLimiter,
    /// A paced client's reports of what it received, read by its writer.
    reports: Option<tokio::sync::watch::Sender<(u64, std::time::Instant)>>,
}

/// Close code 1007: a text message that is not UTF-8 (RFC 6455 §7.4.1).
pub const CLOSE_INVALID_DATA: u16 = 1007;
/// Close code 1008: policy violation (bad handshake, bad token).
pub const CLOSE_POLICY: u16 = 1008;
/// Close code 1009: a message too big to process.
pub const CLOSE_TOO_BIG: u16 = 1009;
/// Close code 1002: a WebSocket protocol error.
pub const CLOSE_PROTOCOL: u16 = 1002;

/// What to tell a client whose socket failed to read: the error it gets
/// and the close code, or `None` when the connection is simply gone (reset,
/// closed) and nothing can be sent.
pub fn read_failure(e: axum::Error) -> Option<(WireError, u16)> {
    use tungstenite::Error as E;
    let inner = e.into_inner();
    let e = inner.downcast_ref::<E>()?;
    match e {
        E::Utf8(detail) => Some((
            WireError::malformed(format!(
                "a text message is not valid UTF-8 ({detail}); closing"
            )),
            CLOSE_INVALID_DATA,
        )),
        E::Capacity(c) => Some((
            WireError::new(
                vsculpt_protocol::ErrorCode::TooLarge,
                format!(
                    "{c}; the hard limit is {} bytes; closing",
                    super::HARD_MESSAGE_LIMIT
                ),
            ),
            CLOSE_TOO_BIG,
        )),
        E::Protocol(p) => Some((
            WireError::malformed(format!("WebSocket protocol error: {p}; closing")),
            CLOSE_PROTOCOL,
        )),
        _ => None,
    }
}

async fn send_now(socket: &mut WebSocket, text: axum::extract::ws::Utf8Bytes) {
    let _ = socket.send(Message::Text(text)).await;
}

async fn refuse(mut socket: WebSocket, err: WireError, close_code: u16) {
    send_now(&mut socket, convert::error(None, &err)).await;
    let _ = socket
        .send(Message::Close(Some(axum::extract::ws::CloseFrame {
            code: close_code,
            reason: err.message.chars().take(100).collect::<String>().into(),
        })))
        .await;
}

/// Runs one connection to its end.
pub async fn run(mut socket: WebSocket, state: AppState, query: HashMap<String, String>) {
    state.metrics.client(1);
    let _guard = ClientGuard(state.metrics.clone());
    let limit = state.config.max_message_bytes;

    // 1. The hello.
    let first = tokio::select! {
        m = tokio::time::timeout(HELLO_TIMEOUT, socket.recv()) => m,
        _ = state.shutdown.wait() => return,
    };
    let text = match first {
        Ok(Some(Ok(Message::Text(t)))) => t,
        Ok(Some(Ok(_))) => {
            return refuse(
                socket,
                WireError::handshake("the first message must be a JSON hello"),
                CLOSE_POLICY,
            )
            .await;
        }
        Ok(Some(Err(e))) => {
            return match read_failure(e) {
                Some((err, code)) => {
                    tracing::info!(
                        code,
                        "closing a connection before its hello: {}",
                        err.message
                    );
                    refuse(socket, err, code).await
                }
                None => tracing::debug!("connection lost before its hello"),
            };
        }
        Ok(_) => return,
        Err(_) => {
            return refuse(
                socket,
                WireError::handshake("no hello within 10 s"),
                CLOSE_POLICY,
            )
            .await;
        }
    };
    if text.len() > limit {
        return refuse(
            socket,
            WireError::too_large(text.len(), limit),
            CLOSE_TOO_BIG,
        )
        .await;
    }
    let hello = match convert::decode_hello(text.as_str()) {
        Ok(h) => h,
        Err(e) => return refuse(socket, e, CLOSE_POLICY).await,
    };
    let design = hello.design;
    // A device link may carry its token in the URL (the banner's device
    // link) and leave the hello's token empty.
    let token = if hello.token.is_empty() {
        query.get("token").cloned().unwrap_or_default()
    } else {
        hello.token.clone()
    };
    let role = match state.role_on(&token, design).await {
        Ok(Some(r)) => r,
        _ => return refuse(socket, WireError::unauthorized(), CLOSE_POLICY).await,
    };
    let handle = match state.hub.open(design).await {
        Ok(h) => h,
        // 1013: try again later (the design is restarting).
        Err(e) if e.kind == ErrorKind::Unavailable => {
            return refuse(socket, WireError::from(e), 1013).await;
        }
        Err(e) => return refuse(socket, WireError::from(e), CLOSE_POLICY).await,
    };
    let client = state.next_client.fetch_add(1, Ordering::Relaxed);
    // The name is shown to every client of the design and becomes the
    // author of commits: control characters are replaced by spaces.
    let cleaned: String = hello
        .name
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    let name = if cleaned.trim().is_empty() {
        format!("{role:?} {client}").to_lowercase()
    } else {
        cleaned.trim().to_string()
    };
    let info = ClientInfo {
        id: client,
        name: name.clone(),
        role,
    };
    let mut joined = match handle.join(info).await {
        Ok(j) => j,
        Err(e) => return refuse(socket, WireError::from(e), 1011).await,
    };
    tracing::info!(design, client, ?role, "client connected");

    // 2. Welcome and the full snapshot, then the writer takes over (and
    //    sends the current geometry frame first). The compact join sends
    //    the geometry frame, flagged as the snapshot's shape, before a
    //    snapshot without points: the picture can be drawn while the rest
    //    is still on its way, and the net crosses the link once.
    let compact = hello.geometry_first;
    // Binary messages deflated (protocol kind 7) for a client that asked.
    let deflate = query
        .get("deflate")
        .is_some_and(|v| v == "1" || v == "true");
    let mut sent = std::collections::BTreeMap::new();
    // The join's frames and their name; not sent again to a client that kept
    // the very frames that name (its browser's geometry cache).
    let geometry = compact.then(|| join_geometry::join_geometry(&mut joined, &mut sent, deflate));
    let cached = geometry
        .as_ref()
        .is_some_and(|g| hello.cached_geometry.as_deref() == Some(g.hash.as_str()));
    let welcome = socket
        .send(Message::Text(convert::welcome(
            client,
            design,
            role,
            geometry.as_ref().map(|g| g.hash.clone()),
            cached,
        )))
        .await;
    let mut shape = Ok(());
    let mut joined_bytes = 0u64;
    if let (Ok(()), Some(g), false) = (&welcome, geometry, cached) {
        for frame in g.messages {
            joined_bytes += frame.len() as u64;
            state.metrics.frame_sent(frame.len());
            shape = socket.send(Message::Binary(frame)).await;
            if shape.is_err() {
                break;
            }
        }
    }
    if welcome.is_err()
        || shape.is_err()
        || socket
            .send(Message::Text(convert::snapshot(&joined.view, !compact)))
            .await
            .is_err()
    {
        let _ = handle
            .send(crate::design::actor::Request::Leave { client })
            .await;
        return;
    }
    // A device link (the bridge) gets no geometry frames unless its URL asks
    // for them with `geometry=1`: it only needs the icon events and its drag
    // feedback, and a frame per drag would cost it megabytes a second.
    let frames = role != Role::Device
        || query
            .get("geometry")
            .is_some_and(|v| v == "1" || v == "true");
    let (sink, stream) = socket.split();
    let (out_tx, out_rx) = mpsc::channel(REPLY_CAPACITY);
    // A send rate matched to the client's link: it reports what it received.
    let (reports, pace) = if query.get("pace").is_some_and(|v| v == "1" || v == "true") {
        let (tx, rx) = tokio::sync::watch::channel((0, std::time::Instant::now()));
        (
            Some(tx),
            Some(writer::Paced {
                reports: rx,
                joined_bytes,
            }),
        )
    } else {
        (None, None)
    };
    let writer = tokio::spawn(writer::run(
        sink,
        out_rx,
        joined,
        handle.clone(),
        client,
        state.metrics.clone(),
        writer::Delivery {
            compact,
            frames,
            sent,
            drag_stream: query
                .get("drag_stream")
                .is_some_and(|v| v == "1" || v == "true"),
            deflate,
            mesh_delta: query
                .get("mesh_delta")
                .is_some_and(|v| v == "1" || v == "true"),
            pace,
        },
    ));
    let mut session = Session {
        state: state.clone(),
        client,
        name,
        token,
        role,
        handle,
        out: out_tx,
        limiter: RateLimiter::new(std::time::Instant::now()),
        reports,
    };
    session.read(stream).await;
    let _ = session
        .handle
        .send(crate::design::actor::Request::Leave { client })
        .await;
    drop(session);
    let _ = writer.await;
    tracing::info!(design, client, "client disconnected");
}

impl Session {
    async fn reply(&self, text: axum::extract::ws::Utf8Bytes) {
        let _ = self.out.send(Out::Msg(Message::Text(text))).await;
    }

    async fn error(&self, id: Option<u64>, e: WireError) {
        self.state.metrics.error_sent();
        self.reply(convert::error(id, &e)).await;
    }

    async fn read(&mut self, mut stream: SplitStream<WebSocket>) {
        let limit = self.state.config.max_message_bytes;
        let shutdown = self.state.shutdown.clone();
        loop {
            let msg = tokio::select! {
                m = stream.next() => m,
                _ = shutdown.wait() => {
                    let _ = self.out.send(Out::Close(1001, "server shutting down".into())).await;
                    return;
                }
            };
            let text = match msg {
                None => return,
                Some(Err(e)) => {
                    // Invalid UTF-8, a frame over the hard limit or a
                    // protocol violation: the stream cannot be trusted any
                    // further. Say why, close with the matching code, log.
                    match read_failure(e) {
                        Some((err, code)) => {
                            tracing::info!(
                                design = self.handle.id,
                                client = self.client,
                                code,
                                "closing the connection: {}",
                                err.message
                            );
                            let reason = err.message.chars().take(100).collect();
                            self.error(None, err).await;
                            let _ = self.out.send(Out::Close(code, reason)).await;
                        }
                        None => tracing::debug!(
                            design = self.handle.id,
                            client = self.client,
                            "connection lost"
                        ),
                    }
                    return;
                }
                Some(Ok(Message::Close(_))) => return,
                Some(Ok(Message::Ping(_) | Message::Pong(_))) => continue,
                Some(Ok(Message::Binary(b))) => {
                    let e = if b.len() > limit {
                        WireError::too_large(b.len(), limit)
                    } else {
                        WireError::malformed("clients send JSON text messages only")
                    };
                    self.error(None, e).await;
                    continue;
                }
                Some(Ok(Message::Text(t))) => t,
            };
            if text.len() > limit {
                self.error(None, WireError::too_large(text.len(), limit))
                    .await;
                continue;
            }
            let decoded = convert::decode(text.as_str());
            let class = match &decoded {
                Ok((
                    _,
                    Inbound::Command(crate::design::Command::Drag { .. })
                    | Inbound::Presence { .. }
                    | Inbound::Received { .. }
                    | Inbound::DeviceSample { .. },
                )) => rate::Class::Stream,
                _ => rate::Class::Control,
            };
            match self.limiter.admit(class, std::time::Instant::now()) {
                rate::Verdict::Admit => {}
                verdict => {
                    self.state.metrics.rate_limited();
                    if verdict == rate::Verdict::Refuse {
                        let id = match &decoded {
                            Ok((id, _)) | Err((id, _)) => *id,
                        };
                        self.error(id, rate_limited(class)).await;
                    }
                    continue;
                }
            }
            match decoded {
                Ok((id, inbound)) => self.dispatch(id, inbound).await,
                Err((id, e)) => self.error(id, e).await,
            }
        }
    }

    async fn dispatch(&mut self, id: Option<u64>, inbound: Inbound) {
        match inbound {
            Inbound::Hello => {
                self.error(id, WireError::handshake("already said hello"))
                    .await;
            }
            Inbound::Ping => self.reply(convert::pong(id)).await,
            Inbound::Received { bytes } => {
                // A paced client's report opens its window (the writer
                // reads it); without `pace=1` it changes nothing.
                if let Some(r) = &self.reports {
                    r.send_replace((bytes, std::time::Instant::now()));
                }
                self.ack(id).await;
            }
            Inbound::Command(crate::design::Command::Drag { part, icon, xyz }) if id.is_none() => {
                // Drag frames without a request number are fire-and-forget
                // and coalesced by the actor; the role is checked here so a
                // viewer still hears of its refusal.
                if !self.role.can_edit() {
                    self.error(id, WireError::from(forbidden(self.role))).await;
                } else if let Err(e) = self.handle.drag(self.client, part, icon, xyz).await {
                    self.error(id, WireError::from(e)).await;
                }
            }
            Inbound::Command(cmd) => {
                if cmd.edits() && !self.role.can_edit() {
                    self.error(id, WireError::from(forbidden(self.role))).await;
                    return;
                }
                if crate::design::fairing_job::is_fair(&cmd) {
                    // A fair's answer comes when its job ends: wait for it
                    // aside, so this client can go on (and cancel it). The
                    // reply queue is held weakly: a client that leaves
                    // meanwhile does not keep its writer waiting for the job.
                    let (handle, client, out) =
                        (self.handle.clone(), self.client, self.out.downgrade());
                    let metrics = self.state.metrics.clone();
                    tokio::spawn(async move {
                        let text = match handle.command(client, cmd).await {
                            Ok(ack) => convert::ack(id, &ack),
                            Err(e) => {
                                metrics.error_sent();
                                Some(convert::error(id, &WireError::from(e)))
                            }
                        };
                        if let (Some(t), Some(out)) = (text, out.upgrade()) {
                            let _ = out.send(Out::Msg(Message::Text(t))).await;
                        }
                    });
                    return;
                }
                match self.handle.command(self.client, cmd).await {
                    Ok(ack) => {
                        if let Some(t) = convert::ack(id, &ack) {
                            self.reply(t).await;
                        }
                    }
                    Err(e) => self.error(id, WireError::from(e)).await,
                }
            }
            Inbound::Presence { pointer, camera } => {
                let _ = self
                    .handle
                    .send(crate::design::actor::Request::Pointer {
                        client: self.client,
                        pointer: pointer.map(|p| p.to_array()),
                        camera: Some(camera),
                    })
                    .await;
                self.ack(id).await;
            }
            Inbound::DeviceSample { sensor, position } => {
                if self.role == Role::Viewer {
                    self.error(id, WireError::from(forbidden(self.role))).await;
                    return;
                }
                tracing::trace!(client = self.client, sensor = ?sensor, "device sample");
                let _ = self
                    .handle
                    .send(crate::design::actor::Request::Pointer {
                        client: self.client,
                        pointer: Some(position.to_array()),
                        camera: None,
                    })
                    .await;
                self.ack(id).await;
            }
            Inbound::DeviceStatus {
                device,
                condition,
                message,
            } => {
                if self.role == Role::Viewer {
                    self.error(id, WireError::from(forbidden(self.role))).await;
                    return;
                }
                // Debug formatting quotes and escapes the bridge's strings:
                // a line break or escape sequence cannot forge a log line.
                tracing::info!(
                    client = self.client,
                    device = ?device,
                    condition,
                    detail = ?message,
                    "device status"
                );
                self.ack(id).await;
            }
            Inbound::ListVersions => match self.handle.versions().await {
                Ok(v) => self.reply(convert::versions(id, &v)).await,
                Err(e) => self.error(id, WireError::from(e)).await,
            },
            Inbound::ListDesigns => self.list(id).await,
            Inbound::CreateDesign { name } => self.create(id, name).await,
            Inbound::DeleteDesign { design } => self.delete(id, design).await,
        }
    }

    async fn ack(&self, id: Option<u64>) {
        if let Some(t) = convert::ack(id, &Default::default()) {
            self.reply(t).await;
        }
    }

    async fn list(&self, id: Option<u64>) {
        let admin = matches!(
            self.state.caller(&self.token).await.ok().flatten(),
            Some(Caller::Admin)
        );
        let store = self.state.store.clone();
        let token = self.token.clone();
        let listed =
            tokio::task::spawn_blocking(move || -> Result<Vec<_>, crate::store::StoreError> {
                let designs = if admin {
                    store.designs()?
                } else {
                    store
                        .design_by_token(&token)?
                        .into_iter()
                        .map(|(d, _)| d)
                        .collect()
                };
                let mut out = Vec::new();
                for d in designs {
                    let n = store.versions(d.id)?.len() as u64;
                    out.push((d.id, d.name, n));
                }
                Ok(out)
            })
            .await;
        match listed {
            Ok(Ok(visible)) => self.reply(convert::design_list(id, &visible)).await,
            _ => {
                self.error(
                    id,
                    WireError::from(CommandError::new(ErrorKind::Storage, "cannot list designs")),
                )
                .await
            }
        }
    }

    async fn create(&self, id: Option<u64>, name: String) {
        if self.role != Role::Editor {
            return self.error(id, WireError::from(forbidden(self.role))).await;
        }
        let name = name.trim().to_string();
        if let Err(e) = crate::design::demo::check_name(&name) {
            return self.error(id, WireError::from(e)).await;
        }
        let doc = match crate::design::demo::plate(&name, 16, 12) {
            Ok(d) => d,
            Err(e) => return self.error(id, WireError::from(e)).await,
        };
        match self.state.hub.create(doc, &self.name).await {
            Ok(rec) => self.reply(convert::design_created(id, &rec)).await,
            Err(e) => self.error(id, WireError::from(e)).await,
        }
    }

    async fn delete(&self, id: Option<u64>, design: DesignId) {
        match self.state.role_on(&self.token, design).await {
            Ok(Some(Role::Editor)) => {}
            Ok(Some(r)) => return self.error(id, WireError::from(forbidden(r))).await,
            _ => {
                return self
                    .error(
                        id,
                        WireError::from(CommandError::new(
                            ErrorKind::UnknownDesign,
                            format!("no design {design} for this token"),
                        )),
                    )
                    .await;
            }
        }
        match self.state.hub.delete(design).await {
            Ok(()) => self.ack(id).await,
            Err(e) => self.error(id, WireError::from(e)).await,
        }
    }
}

/// The reply to a message over its rate limit.
fn rate_limited(class: rate::Class) -> WireError {
    use vsculpt_protocol::limits::{CONTROL_BURST, CONTROL_RATE, STREAM_BURST, STREAM_RATE};
    let (what, rate, burst) = match class {
        rate::Class::Control => ("control messages", CONTROL_RATE, CONTROL_BURST),
        rate::Class::Stream => (
            "drag, device and pointer messages",
            STREAM_RATE,
            STREAM_BURST,
        ),
    };
    WireError::new(
        vsculpt_protocol::ErrorCode::RateLimited,
        format!("over the limit of {rate} {what} a second (bursts of {burst}): dropped, slow down"),
    )
}

fn forbidden(role: Role) -> CommandError {
    CommandError::new(
        ErrorKind::Forbidden,
        format!(
            "a {} may not change this design",
            format!("{role:?}").to_lowercase()
        ),
    )
}
