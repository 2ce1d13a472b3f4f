//! The per-client writer task: the only place that writes to a client's
//! socket. It merges three sources, in priority order:
//!
//! 1. replies to this client (acks, errors, design lists) from a bounded
//!    queue its reader fills — a client that never reads stalls only its
//!    own reader. Before each reply go the events and the drag feedback the
//!    actor published before it answered: a client that has its answer has
//!    seen what its command did (a replaying bridge relies on it);
//! 2. the design's ordered events (broadcast): never skipped silently — if
//!    this client falls more than the channel's capacity behind, it gets a
//!    fresh full snapshot from the actor and continues from there;
//! 3. this client's drag feedback, its refused drag frames and the geometry
//!    (all `watch`): latest wins — a slow client skips intermediate frames
//!    instead of queueing them, and a stream of refused drags yields one
//!    error per wake-up, not one per frame. A paced client (`pace=1`,
//!    [`super::pace`]) gets geometry only while its window is open; what
//!    waits is sent, latest, when its next `received` report opens it.

use crate::convert;
use crate::design::{DesignEvent, DesignHandle, Joined};
use crate::metrics::Metrics;
use axum::body::Bytes;
use axum::extract::ws::{CloseFrame, Message, WebSocket};
use futures_util::SinkExt;
use futures_util::stream::SplitSink;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;
use tokio::sync::broadcast::error::{RecvError, TryRecvError};
use tokio::sync::{mpsc, watch};

use super::pace::Pacer;

/// What the reader hands the writer.
pub enum Out {
    /// Send this message.
    Msg(Message),
    /// Close with this code and reason, then stop.
    Close(u16, String),
}

type Sink = SplitSink<WebSocket, Message>;

/// What a client holds of each part's drag stream: the revision of the last
/// full frame sent and the basis sent after it (see
/// [`crate::design::drag_stream`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Held {
    full: u64,
    basis: Option<u64>,
}

/// The forms of binary messages a client asked for besides whole frames.
#[derive(Clone, Copy, Debug, Default)]
struct Forms {
    /// Deflated messages (`deflate=1`, kind 7).
    deflate: bool,
    /// Mesh deltas (`mesh_delta=1`, kind 8).
    mesh_delta: bool,
}

/// Sends one binary message, counted in the metrics and, for a paced
/// client, in its [`Pacer`].
async fn send_binary(
    sink: &mut Sink,
    bytes: Bytes,
    metrics: &Metrics,
    pacer: Option<&mut Pacer>,
) -> Result<(), axum::Error> {
    let len = bytes.len();
    metrics.frame_sent(len);
    if let Some(p) = pacer {
        p.on_sent(len, Instant::now());
    }
    sink.send(Message::Binary(bytes)).await
}

/// Sends the frames of the parts whose revision this client has not had
/// (every part the first time), and forgets parts that are gone: latest
/// wins per part, and a frame of one part never stands in for another's.
/// A client of the drag stream (`held` is `Some`) gets a drag frame where
/// there is one, preceded by the reference frame and the basis it lacks; a
/// client of mesh deltas gets one where there is one and the last frame it
/// was sent of that part is the delta's base.
/// A paced client (`pacer` is `Some`) gets a part's messages only while its
/// window is open: `Ok(false)` says some part is still owed (the caller
/// tries again when the client reports what it received), `Ok(true)` that
/// the client has every part's latest frame.
async fn send_geometry(
    sink: &mut Sink,
    joined: &mut Joined,
    sent: &mut BTreeMap<u64, u64>,
    mut held: Option<&mut BTreeMap<u64, Held>>,
    forms: Forms,
    metrics: &Metrics,
    mut pacer: Option<&mut Pacer>,
) -> Result<bool, axum::Error> {
    let deflate = forms.deflate;
    let set = joined.geometry.borrow_and_update().clone();
    sent.retain(|part, _| set.parts.contains_key(part));
    if let Some(h) = held.as_deref_mut() {
        h.retain(|part, _| set.parts.contains_key(part));
    }
    for (part, g) in &set.parts {
        if sent.get(part) == Some(&g.rev) {
            continue;
        }
        if pacer.as_deref().is_some_and(|p| !p.open()) {
            return Ok(false);
        }
        match (held.as_deref_mut(), &g.stream) {
            (Some(held), Some(s)) => {
                let h = held.entry(*part).or_default();
                if h.full != s.basis.reference {
                    let bytes = s
                        .basis
                        .reference_deflated
                        .pick(&s.basis.reference_frame, deflate);
                    send_binary(sink, bytes, metrics, pacer.as_deref_mut()).await?;
                    *h = Held {
                        full: s.basis.reference,
                        basis: None,
                    };
                }
                if h.basis != Some(s.basis.id) {
                    let bytes = s.basis.deflated.pick(&s.basis.frame, deflate);
                    send_binary(sink, bytes, metrics, pacer.as_deref_mut()).await?;
                    h.basis = Some(s.basis.id);
                }
                send_binary(sink, s.frame.clone(), metrics, pacer.as_deref_mut()).await?;
            }
            (held, _) => {
                let bytes = match &g.mesh_delta {
                    Some(d) if forms.mesh_delta && sent.get(part) == Some(&d.base) => {
                        d.deflated.pick(&d.frame, deflate)
                    }
                    _ => g.deflated.pick(&g.frame, deflate),
                };
                send_binary(sink, bytes, metrics, pacer.as_deref_mut()).await?;
                if let Some(held) = held {
                    held.insert(
                        *part,
                        Held {
                            full: g.rev,
                            basis: None,
                        },
                    );
                }
            }
        }
        sent.insert(*part, g.rev);
    }
    Ok(true)
}

/// Sends one ordered event, if it has a wire form.
async fn ev_send(sink: &mut Sink, ev: &DesignEvent, compact: bool) -> Result<(), axum::Error> {
    match convert::event(ev, !compact) {
        Some(text) => sink.send(Message::Text(text)).await,
        None => Ok(()),
    }
}

/// How geometry reaches one client.
#[derive(Debug)]
pub struct Delivery {
    /// The compact join: the connection already sent the current frame, and
    /// snapshots go without their points.
    pub compact: bool,
    /// Geometry frames at all (a device link must ask for them).
    pub frames: bool,
    /// The revision of each part's frame the connection already sent (the
    /// compact join's frames); the writer sends the others first.
    pub sent: BTreeMap<u64, u64>,
    /// The client asked for the drag stream (`drag_stream=1` in the URL).
    pub drag_stream: bool,
    /// The client asked for deflated messages (`deflate=1` in the URL).
    pub deflate: bool,
    /// The client asked for mesh deltas (`mesh_delta=1` in the URL).
    pub mesh_delta: bool,
    /// The client asked for a send rate matched to its link (`pace=1`).
    pub pace: Option<Paced>,
}

/// What the writer of a paced client needs from its reader.
#[derive(Debug)]
pub struct Paced {
    /// The client's latest `received` report: the bytes of binary messages
    /// it has received, and when the reader read the report.
    pub reports: watch::Receiver<(u64, Instant)>,
    /// The bytes of binary messages sent before the writer started (the
    /// compact join's frames).
    pub joined_bytes: u64,
}

/// A client that fell too far behind its design's events.
struct Lagged<'a> {
    handle: &'a DesignHandle,
    client: u64,
    skipped: u64,
    compact: bool,
    frames: bool,
    forms: Forms,
}

/// How a resync ended.
enum Resynced {
    /// The client has a fresh snapshot (and geometry).
    Done,
    /// The design is gone: no more geometry.
    DesignGone,
    /// The socket failed.
    SocketFailed,
}

/// Brings a lagging client back: a fresh snapshot from the actor, sent,
/// then its geometry.
async fn resync(
    lagged: Lagged<'_>,
    sink: &mut Sink,
    joined: &mut Joined,
    sent: &mut BTreeMap<u64, u64>,
    held: Option<&mut BTreeMap<u64, Held>>,
    metrics: &Metrics,
    pacer: Option<&mut Pacer>,
) -> Resynced {
    let Lagged {
        handle,
        client,
        skipped,
        compact,
        frames,
        forms,
    } = lagged;
    tracing::info!(
        design = handle.id,
        skipped,
        "client lagged; resyncing with a full snapshot"
    );
    let Ok(j) = handle.resync(client).await else {
        return Resynced::DesignGone;
    };
    let snap = convert::snapshot(&j.view, !compact);
    *joined = j;
    if sink.send(Message::Text(snap)).await.is_err()
        || (frames
            && send_geometry(sink, joined, sent, held, forms, metrics, pacer)
                .await
                .is_err())
    {
        return Resynced::SocketFailed;
    }
    Resynced::Done
}

/// Runs until the reader drops its sender, a close is requested, the socket
/// fails or the design goes away; `delivery` says how geometry reaches this
/// client.
pub async fn run(
    mut sink: Sink,
    mut out: mpsc::Receiver<Out>,
    mut joined: Joined,
    handle: DesignHandle,
    client: u64,
    metrics: Arc<Metrics>,
    delivery: Delivery,
) {
    let Delivery {
        compact,
        frames,
        mut sent,
        drag_stream,
        deflate,
        mesh_delta,
        pace,
    } = delivery;
    let forms = Forms {
        deflate,
        mesh_delta,
    };
    // A paced client: its reports and its window.
    let (mut reports, mut pacer) = match pace {
        Some(Paced {
            reports,
            joined_bytes,
        }) => {
            let now = Instant::now();
            let mut p = Pacer::new(now);
            p.on_sent(joined_bytes as usize, now);
            (Some(reports), Some(p))
        }
        None => (None, None),
    };
    // Some part's latest frame still waits for the window to open.
    let mut owed = false;
    // Frames sent before the writer started (the compact join's) are full.
    let mut held: Option<BTreeMap<u64, Held>> = drag_stream.then(|| {
        sent.iter()
            .map(|(part, rev)| {
                (
                    *part,
                    Held {
                        full: *rev,
                        basis: None,
                    },
                )
            })
            .collect()
    });
    let mut geometry_live = true;
    let mut deleted = false;
    if frames {
        match send_geometry(
            &mut sink,
            &mut joined,
            &mut sent,
            held.as_mut(),
            forms,
            &metrics,
            pacer.as_mut(),
        )
        .await
        {
            Ok(all) => owed = !all,
            Err(_) => return,
        }
    }
    loop {
        tokio::select! {
            biased;
            o = out.recv() => {
                let ok = match o {
                    None => break,
                    Some(Out::Msg(m)) => {
                        // Read your own writes: what the actor published before
                        // it answered (a command's events, its drag feedback)
                        // goes out before the answer, so a client that waits
                        // for the answer has seen the state it left.
                        loop {
                            match joined.events.try_recv() {
                                Ok(ev) => {
                                    if ev_send(&mut sink, &ev, compact).await.is_err() {
                                        return;
                                    }
                                    if matches!(ev, DesignEvent::Deleted(_)) {
                                        deleted = true;
                                        geometry_live = false;
                                    }
                                }
                                Err(TryRecvError::Lagged(n)) => {
                                    // As below: too far behind, a fresh snapshot.
                                    let lagged = Lagged { handle: &handle, client, skipped: n, compact, frames, forms };
                                    match resync(lagged, &mut sink, &mut joined, &mut sent, held.as_mut(), &metrics, pacer.as_mut()).await {
                                        Resynced::Done => owed = pacer.is_some(),
                                        Resynced::DesignGone => geometry_live = false,
                                        Resynced::SocketFailed => return,
                                    }
                                    break;
                                }
                                // Closed is handled by the main loop's receive.
                                Err(_) => break,
                            }
                        }
                        let feedback = (geometry_live
                            && joined.feedback.has_changed().unwrap_or(false))
                        .then(|| joined.feedback.borrow_and_update().clone())
                        .flatten();
                        if let Some(f) = feedback
                            && sink.send(Message::Text(convert::feedback(&f))).await.is_err()
                        {
                            return;
                        }
                        sink.send(m).await.is_ok()
                    }
                    Some(Out::Close(code, reason)) => {
                        let _ = sink
                            .send(Message::Close(Some(CloseFrame { code, reason: reason.into() })))
                            .await;
                        break;
                    }
                };
                if !ok {
                    break;
                }
            }
            e = joined.events.recv() => {
                match e {
                    Ok(ev) => {
                        let is_deleted = matches!(ev, DesignEvent::Deleted(_));
                        if let Some(text) = convert::event(&ev, !compact)
                            && sink.send(Message::Text(text)).await.is_err()
                        {
                            break;
                        }
                        if is_deleted {
                            deleted = true;
                            geometry_live = false;
                        }
                    }
                    Err(RecvError::Lagged(n)) => {
                        let lagged = Lagged { handle: &handle, client, skipped: n, compact, frames, forms };
                        match resync(lagged, &mut sink, &mut joined, &mut sent, held.as_mut(), &metrics, pacer.as_mut()).await {
                            Resynced::Done => owed = pacer.is_some(),
                            Resynced::DesignGone => geometry_live = false,
                            Resynced::SocketFailed => break,
                        }
                    }
                    Err(RecvError::Closed) if !deleted => {
                        // The actor died (it panicked; its supervisor
                        // restarts it from the persisted state): say so
                        // and close, so the client reconnects to the new one.
                        let e = crate::convert::WireError::new(
                            vsculpt_protocol::ErrorCode::Unavailable,
                            format!("design {} stopped after a failure and is restarting; reconnect", handle.id),
                        );
                        metrics.error_sent();
                        let _ = sink.send(Message::Text(convert::error(None, &e))).await;
                        let _ = sink
                            .send(Message::Close(Some(CloseFrame { code: 1012, reason: "design restarting".into() })))
                            .await;
                        break;
                    }
                    Err(RecvError::Closed) => {
                        // The design was deleted: wait for the reader to
                        // close or rejoin.
                        geometry_live = false;
                        match out.recv().await {
                            Some(Out::Msg(m)) => {
                                if sink.send(m).await.is_err() {
                                    break;
                                }
                            }
                            Some(Out::Close(code, reason)) => {
                                let _ = sink
                                    .send(Message::Close(Some(CloseFrame { code, reason: reason.into() })))
                                    .await;
                                break;
                            }
                            None => break,
                        }
                    }
                }
            }
            r = joined.feedback.changed(), if geometry_live => {
                if r.is_err() {
                    continue;
                }
                let f = joined.feedback.borrow_and_update().clone();
                if let Some(f) = f
                    && sink.send(Message::Text(convert::feedback(&f))).await.is_err()
                {
                    break;
                }
            }
            r = joined.refusals.changed(), if geometry_live => {
                if r.is_err() {
                    continue;
                }
                let refused = joined.refusals.borrow_and_update().clone();
                if let Some(r) = refused {
                    metrics.error_sent();
                    let e = convert::WireError::from(r.error);
                    if sink.send(Message::Text(convert::error(None, &e))).await.is_err() {
                        break;
                    }
                }
            }
            r = joined.geometry.changed(), if geometry_live && frames => {
                if r.is_err() {
                    geometry_live = false;
                    continue;
                }
                match send_geometry(&mut sink, &mut joined, &mut sent, held.as_mut(), forms, &metrics, pacer.as_mut()).await {
                    Ok(all) => owed = !all,
                    Err(_) => break,
                }
            }
            live = async {
                match reports.as_mut() {
                    Some(r) => r.changed().await.is_ok(),
                    None => std::future::pending().await,
                }
            }, if reports.is_some() => {
                if !live {
                    // The reader is gone: the connection is ending.
                    reports = None;
                    continue;
                }
                let report = reports.as_mut().map(|r| *r.borrow_and_update());
                if let (Some((total, at)), Some(p)) = (report, pacer.as_mut()) {
                    p.on_report(total, at);
                }
                if owed && geometry_live && frames {
                    match send_geometry(&mut sink, &mut joined, &mut sent, held.as_mut(), forms, &metrics, pacer.as_mut()).await {
                        Ok(all) => owed = !all,
                        Err(_) => break,
                    }
                }
            }
        }
    }
}
