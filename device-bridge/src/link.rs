//! The WebSocket link to the server (tokio-tungstenite).
//!
//! [`Link::spawn`] keeps one connection alive: it connects, sends the hello with
//! the device token, forwards what the server says as [`ServerEvent`]s, and sends
//! whatever the [`Outbox`] holds each time it is notified — at the device rate,
//! but with drags coalesced to the newest. When the server vanishes it reconnects
//! with exponential backoff and reports [`ServerEvent::Connected`] again, so the
//! caller can restore its bindings. Failures are logged once per outage.
//!
//! The JSON mapping lives in a [`Wire`] (see [`crate::wire`]), so this file only
//! knows about connections.

use crate::interaction::{Command, IconView};
use crate::outbox::Outbox;
use futures_util::{SinkExt, StreamExt};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::{Notify, mpsc, watch};
use tokio_tungstenite::tungstenite::Message;

/// What the server told the bridge.
#[derive(Clone, Debug, PartialEq)]
pub enum ServerEvent {
    /// The server accepted the hello (the wire's own event; the link then reports
    /// [`ServerEvent::Connected`]).
    Welcome,
    /// A connection was (re)established and accepted.
    Connected,
    /// The connection is gone; a reconnect is under way.
    Disconnected,
    /// The full icon set and the surface area (a snapshot).
    Icons {
        /// Every icon.
        icons: Vec<IconView>,
        /// Surface area S (for the spring stiffness), if known.
        area: Option<f64>,
    },
    /// One icon changed (position after a solve, state, role …).
    Icon(IconView),
    /// An icon was deleted.
    IconRemoved(u64),
    /// After a solved drag frame: where the dragged icon actually is (Δy for the spring).
    Feedback {
        /// The icon.
        icon: u64,
        /// Its position on the solved surface.
        actual: glam::DVec3,
    },
    /// The server refused something; the text says what.
    Error(String),
    /// The server answered a numbered request (ack, error or pong); the wire
    /// reports it, the link turns it into [`ServerEvent::Answered`].
    Reply(u64),
    /// Answers received so far on an [in-order](LinkOptions::in_order) link,
    /// after every event that came before the last of them (compare with
    /// the total [`Link::send`] returned).
    Answered(u64),
    /// The server will never accept this hello (bad token, unknown design, other
    /// protocol version): retrying cannot help, the bridge stops.
    Rejected(Rejection, String),
}

/// Why the server refused the hello for good.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rejection {
    /// The token is not valid for the design.
    Token,
    /// No such design.
    Design,
    /// The server speaks another protocol version.
    Version,
}

impl Rejection {
    /// What to tell the person running the bridge.
    pub fn explain(self, design: Option<u64>, detail: &str) -> String {
        let design = design.unwrap_or(1);
        match self {
            Rejection::Token => format!(
                "token rejected for design {design} ({detail}): use the \"device:\" link the \
                 server prints for this design"
            ),
            Rejection::Design => format!("design {design} does not exist on the server ({detail})"),
            Rejection::Version => format!("the server speaks another protocol version ({detail})"),
        }
    }
}

/// Maps bridge commands and server messages to the protocol's JSON.
pub trait Wire: Send + Sync + 'static {
    /// The first message of a connection (version + token).
    fn hello(&self, token: &str, design: Option<u64>) -> String;
    /// The message(s) for one command; `ordered` when it must be processed in
    /// order with the commands around it (see [`Outbox::drain`]).
    fn encode(&self, cmd: &Command, ordered: bool) -> Vec<String>;
    /// Events in one server text message; an `Err` closes the connection.
    fn decode(&self, text: &str) -> Result<Vec<ServerEvent>, String>;
    /// Events in one binary server message (geometry frames); the default ignores them.
    fn decode_binary(&self, _bytes: &[u8]) -> Vec<ServerEvent> {
        Vec::new()
    }
    /// True once `event` means the server accepted the hello.
    fn accepts(&self, event: &ServerEvent) -> bool;
    /// How many answers ([`ServerEvent::Reply`]) the server owes for `cmd`'s
    /// messages (the numbered ones); none by default.
    fn answers(&self, _cmd: &Command, _ordered: bool) -> u64 {
        0
    }
}

/// Where and how to connect.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkOptions {
    /// `ws://host:port/ws?design=…&token=…`.
    pub url: String,
    /// The device token for the hello (taken from the URL when `None`).
    pub token: Option<String>,
    /// The design (taken from the URL when `None`).
    pub design: Option<u64>,
    /// First reconnect delay.
    pub backoff_min: Duration,
    /// Longest reconnect delay.
    pub backoff_max: Duration,
    /// Keep every command in order, none coalesced, and count the server's
    /// answers (a replay: the server must see the same commands at any pace).
    pub in_order: bool,
}

impl LinkOptions {
    /// Options for `url` with default backoff (100 ms doubling to 5 s).
    pub fn new(url: impl Into<String>) -> Self {
        Self {
            url: url.into(),
            token: None,
            design: None,
            backoff_min: Duration::from_millis(100),
            backoff_max: Duration::from_secs(5),
            in_order: false,
        }
    }

    fn query(&self, key: &str) -> Option<String> {
        let q = self.url.split_once('?')?.1;
        q.split('&')
            .filter_map(|kv| kv.split_once('='))
            .find(|(k, _)| *k == key)
            .map(|(_, v)| v.to_owned())
    }

    /// The token to present.
    pub fn token(&self) -> String {
        self.token
            .clone()
            .or_else(|| self.query("token"))
            .unwrap_or_default()
    }

    /// The design to open.
    pub fn design(&self) -> Option<u64> {
        self.design
            .or_else(|| self.query("design").and_then(|d| d.parse().ok()))
    }
}

/// Counters of the link.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Connections accepted so far.
    pub connections: u64,
    /// Messages sent.
    pub sent: u64,
    /// Times the connection task panicked and was restarted.
    pub restarts: u64,
}

/// The running link; dropping it stops the connection task.
pub struct Link {
    wire: Arc<dyn Wire>,
    outbox: Arc<Mutex<Outbox>>,
    notify: Arc<Notify>,
    stats: watch::Receiver<LinkStats>,
    task: tokio::task::JoinHandle<()>,
}

impl Link {
    /// Starts the connection task; events go to `events`.
    pub fn spawn(
        options: LinkOptions,
        wire: Arc<dyn Wire>,
        events: mpsc::UnboundedSender<ServerEvent>,
    ) -> Self {
        let outbox = Arc::new(Mutex::new(if options.in_order {
            Outbox::in_order()
        } else {
            Outbox::new()
        }));
        let notify = Arc::new(Notify::new());
        let (stats_tx, stats) = watch::channel(LinkStats::default());
        let task = tokio::spawn(supervise(
            options,
            wire.clone(),
            events,
            outbox.clone(),
            notify.clone(),
            Arc::new(stats_tx),
        ));
        Self {
            wire,
            outbox,
            notify,
            stats,
            task,
        }
    }

    /// Queues commands for the server. On an [in-order](LinkOptions::in_order)
    /// link, returns the answer count at which the server has answered them
    /// all (see [`ServerEvent::Answered`]), when it owes any.
    pub fn send(&self, cmds: impl IntoIterator<Item = Command>) -> Option<u64> {
        let mut any = false;
        let mut owed = 0;
        let total = {
            let mut o = self.outbox.lock().unwrap_or_else(|e| e.into_inner());
            for c in cmds {
                if o.is_in_order() {
                    owed += self.wire.answers(&c, true);
                }
                o.push(c);
                any = true;
            }
            o.owe(owed)
        };
        if any {
            self.notify.notify_one();
        }
        (owed > 0).then_some(total)
    }

    /// Drops every pending command (before restoring state on a new connection).
    pub fn clear(&self) {
        self.outbox
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clear();
    }

    /// Drags replaced by newer ones before they were sent.
    pub fn coalesced(&self) -> u64 {
        self.outbox
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .coalesced()
    }

    /// Counters.
    pub fn stats(&self) -> LinkStats {
        *self.stats.borrow()
    }
}

impl Drop for Link {
    fn drop(&mut self) {
        self.task.abort();
    }
}

/// Aborts the task it holds when dropped (the link stops with its supervisor).
struct AbortOnDrop(tokio::task::JoinHandle<()>);

impl Drop for AbortOnDrop {
    fn drop(&mut self) {
        self.0.abort();
    }
}

/// Runs the connection task and restarts it, with backoff, whenever it
/// panics: the panic is logged, counted in [`LinkStats::restarts`] and
/// reported as [`ServerEvent::Disconnected`], after which the new task
/// reconnects and the bridge restores its bindings as after any outage.
async fn supervise(
    o: LinkOptions,
    wire: Arc<dyn Wire>,
    events: mpsc::UnboundedSender<ServerEvent>,
    outbox: Arc<Mutex<Outbox>>,
    notify: Arc<Notify>,
    stats: Arc<watch::Sender<LinkStats>>,
) {
    let mut backoff = o.backoff_min;
    loop {
        let mut task = AbortOnDrop(tokio::spawn(run(
            o.clone(),
            wire.clone(),
            events.clone(),
            outbox.clone(),
            notify.clone(),
            stats.clone(),
        )));
        let panic = match (&mut task.0).await {
            Err(e) if e.is_panic() => e.into_panic(),
            _ => return,
        };
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a non-text panic".into());
        stats.send_modify(|s| s.restarts += 1);
        tracing::error!(url = %o.url, panic = %what, ?backoff, "server link task panicked; restarting");
        if events.send(ServerEvent::Disconnected).is_err() {
            return;
        }
        tokio::time::sleep(backoff).await;
        backoff = (backoff * 2).min(o.backoff_max);
    }
}

async fn run(
    o: LinkOptions,
    wire: Arc<dyn Wire>,
    events: mpsc::UnboundedSender<ServerEvent>,
    outbox: Arc<Mutex<Outbox>>,
    notify: Arc<Notify>,
    stats: Arc<watch::Sender<LinkStats>>,
) {
    let mut backoff = o.backoff_min;
    let mut outage_logged = false;
    let token = o.token();
    let design = o.design();
    loop {
        let outcome = session(
            &o.url,
            &token,
            design,
            wire.as_ref(),
            &events,
            &outbox,
            &notify,
            &stats,
        )
        .await;
        if let Err(End::Rejected(why, detail)) = &outcome {
            let text = why.explain(design, detail);
            tracing::error!(url = %o.url, "{text}");
            let _ = events.send(ServerEvent::Rejected(*why, text));
            return;
        }
        match outcome {
            Ok(accepted) => {
                if accepted {
                    backoff = o.backoff_min;
                    outage_logged = false;
                    tracing::warn!(url = %o.url, "server connection closed; reconnecting");
                }
            }
            Err(End::Failed(e)) => {
                if !outage_logged {
                    tracing::warn!(url = %o.url, error = %e, "server unreachable; retrying with backoff");
                    outage_logged = true;
                }
            }
            Err(End::Rejected(..)) => return,
        }
        if events.send(ServerEvent::Disconnected).is_err() {
            return;
        }
        tokio::time::sleep(backoff).await;
        backoff = (backoff * 2).min(o.backoff_max);
    }
}

/// How a connection that was never accepted ended.
enum End {
    /// Unreachable, closed, broken: retry.
    Failed(String),
    /// Refused for good.
    Rejected(Rejection, String),
}

impl From<String> for End {
    fn from(e: String) -> Self {
        End::Failed(e)
    }
}

/// One connection; `Ok(true)` when it was accepted before it ended.
#[allow(clippy::too_many_arguments)]
async fn session(
    url: &str,
    token: &str,
    design: Option<u64>,
    wire: &dyn Wire,
    events: &mpsc::UnboundedSender<ServerEvent>,
    outbox: &Mutex<Outbox>,
    notify: &Notify,
    stats: &watch::Sender<LinkStats>,
) -> Result<bool, End> {
    let (ws, _) = tokio_tungstenite::connect_async(url)
        .await
        .map_err(|e| End::Failed(e.to_string()))?;
    if let Ok(tcp) = match ws.get_ref() {
        tokio_tungstenite::MaybeTlsStream::Plain(s) => Ok(s),
        _ => Err(()),
    } {
        let _ = tcp.set_nodelay(true);
    }
    let (mut tx, mut rx) = ws.split();
    tx.send(Message::text(wire.hello(token, design)))
        .await
        .map_err(|e| End::Failed(e.to_string()))?;
    let mut accepted = false;
    loop {
        tokio::select! {
            msg = rx.next() => {
                let evs = match msg {
                    None => return Ok(accepted),
                    Some(Err(e)) => return if accepted { Ok(true) } else { Err(End::Failed(e.to_string())) },
                    Some(Ok(Message::Text(t))) => match wire.decode(t.as_str()) {
                        Ok(evs) => evs,
                        Err(e) => {
                            tracing::warn!(error = %e, "server message not understood");
                            Vec::new()
                        }
                    },
                    Some(Ok(Message::Binary(b))) => wire.decode_binary(&b),
                    Some(Ok(Message::Close(_))) => return if accepted { Ok(true) } else { Err(End::Failed("closed by server".into())) },
                    Some(Ok(_)) => Vec::new(),
                };
                for mut ev in evs {
                    if let ServerEvent::Reply(_) = ev {
                        let mut o = outbox.lock().unwrap_or_else(|e| e.into_inner());
                        if !o.is_in_order() {
                            continue;
                        }
                        ev = ServerEvent::Answered(o.answer());
                    }
                    if !accepted && wire.accepts(&ev) {
                        accepted = true;
                        stats.send_modify(|s| s.connections += 1);
                        tracing::info!(url, "connected to server");
                        if events.send(ServerEvent::Connected).is_err() {
                            return Ok(true);
                        }
                    }
                    if !accepted {
                        match &ev {
                            ServerEvent::Rejected(why, detail) => {
                                return Err(End::Rejected(*why, detail.clone()));
                            }
                            ServerEvent::Error(e) => return Err(End::Failed(e.clone())),
                            _ => {}
                        }
                    }
                    if events.send(ev).is_err() {
                        return Ok(accepted);
                    }
                }
            }
            _ = notify.notified(), if accepted => {
                let cmds = outbox.lock().unwrap_or_else(|e| e.into_inner()).drain();
                // Every message of the batch is queued, then one flush: one
                // write to the socket per batch rather than one per message.
                let mut sent = 0;
                for (c, ordered) in &cmds {
                    for text in wire.encode(c, *ordered) {
                        tracing::trace!(%text, "to server");
                        tx.feed(Message::text(text)).await.map_err(|e| End::Failed(e.to_string()))?;
                        sent += 1;
                    }
                }
                if sent > 0 {
                    tx.flush().await.map_err(|e| End::Failed(e.to_string()))?;
                    stats.send_modify(|s| s.sent += sent);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn token_and_design_from_the_printed_url() {
        let o = LinkOptions::new("ws://127.0.0.1:7878/ws?design=3&token=abc-123");
        assert_eq!(o.token(), "abc-123");
        assert_eq!(o.design(), Some(3));
        let mut o = LinkOptions::new("ws://h/ws");
        o.token = Some("t".into());
        o.design = Some(9);
        assert_eq!(o.token(), "t");
        assert_eq!(o.design(), Some(9));
    }
}
