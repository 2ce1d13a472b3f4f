//! The running bridge: device runners (or a replay) feed samples into the
//! [`Interaction`] state machine, whose commands go to the server [`Link`]; what
//! the server reports about icons flows back into the interaction (positions for
//! grabbing, displacements for the spring). On every (re)connection the held
//! bindings are restored.

use crate::config::{Config, DeviceKind, build_driver};
use crate::device::Sample;
use crate::device::SourceId;
use crate::device::runner::{DeviceRunner, DeviceStatus, RunOptions};
use crate::device::{TapEvent, Timestamp};
use crate::interaction::{Command, DeviceCondition, Interaction};
use crate::link::{Link, LinkOptions, ServerEvent, Wire};
use crate::recording::{Recorder, RecordingError, Replayer, recorded_config};
use std::future::Future;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::mpsc;

/// How long a finished replay waits for its last commands to leave.
const DRAIN_GRACE: Duration = Duration::from_millis(500);
/// Distinct server refusals remembered for log-once.
const MAX_REFUSALS: usize = 64;
/// How long a replay waits for the server before playing anyway.
const REPLAY_WAIT: Duration = Duration::from_secs(10);

/// Silence after which a VRPN server counts as hung (it is pinged every 200 ms).
pub const VRPN_SILENCE: Duration = Duration::from_millis(800);

/// The runtime the bridge runs on: one thread (named `bridge-rt`), driven by
/// the caller's `block_on`. Every device reads in its own thread; the runtime
/// only hands their samples to the interaction and talks to the server, which
/// one thread does without the wake-ups of two workers handing each other
/// tasks (a device's samples woke one worker, which woke the other for the
/// link). Blocking work goes to `spawn_blocking`.
pub fn runtime() -> std::io::Result<tokio::runtime::Runtime> {
    tokio::runtime::Builder::new_current_thread()
        .thread_name("bridge-rt")
        .enable_all()
        .build()
}

/// What the devices (or a replay) hand to the interaction.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    /// A batch of samples.
    Samples(Vec<Sample>),
    /// A device's availability changed.
    Status(SourceId, DeviceStatus),
}

/// Runner timing for a device family.
pub fn run_options(kind: DeviceKind) -> RunOptions {
    RunOptions {
        silence: match kind {
            // Serial trackers and gloves talk all the time (streamed or polled).
            DeviceKind::Flock | DeviceKind::Fastrak | DeviceKind::Cyberglove => {
                Some(Duration::from_secs(3))
            }
            // A VRPN server answers the bridge's pings (every 200 ms) even when its
            // tracker is still: silence means it hung, and a grab must not outlive
            // it by more than a second.
            DeviceKind::Vrpn => Some(VRPN_SILENCE),
            // An untouched 3D mouse is legitimately quiet.
            DeviceKind::SpacemouseHid | DeviceKind::Spacenavd => None,
        },
        ..RunOptions::default()
    }
}

/// Applies one server event to the interaction, sending what it implies (the
/// restored bindings after a snapshot) through `link`.
pub fn apply_event(interaction: &mut Interaction, event: ServerEvent, link: Option<&Link>) {
    match event {
        ServerEvent::Connected => {
            if let Some(l) = link {
                l.clear();
            }
        }
        ServerEvent::Disconnected
        | ServerEvent::Welcome
        | ServerEvent::Reply(_)
        | ServerEvent::Answered(_) => {}
        ServerEvent::Icons { icons, area } => {
            if let Some(a) = area {
                interaction.set_surface_area(a);
            }
            interaction.set_icons(icons);
            // A snapshot follows every (re)connection: put the bindings back.
            if let Some(l) = link {
                l.send(interaction.restore());
            }
        }
        ServerEvent::Icon(icon) => interaction.update_icon(icon),
        ServerEvent::IconRemoved(id) => interaction.remove_icon(id),
        ServerEvent::Feedback { icon, actual } => interaction.feedback(icon, actual),
        ServerEvent::Error(e) => tracing::debug!(error = %e, "server refused a command"),
        ServerEvent::Rejected(..) => {}
    }
}

/// Why the bridge stopped short.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    /// The recording could not be written or read.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The server refused the bridge for good (token, design, protocol version);
    /// the text says what to do.
    #[error("{0}")]
    Rejected(String),
}

/// Drives the interaction from `inputs` until they end (plus a grace period to
/// flush) or `shutdown` completes. Without a server URL, commands are only logged.
/// `Err` when the server rejected the bridge for good (the text says why).
pub async fn drive(
    config: &Config,
    wire: Arc<dyn Wire>,
    inputs: mpsc::UnboundedReceiver<Input>,
    shutdown: impl Future<Output = ()>,
) -> Result<(), String> {
    drive_inner(config, wire, inputs, shutdown, None).await
}

/// How a replay and its driver keep in step.
pub struct Lockstep {
    /// Told once the server's icons are known (the first snapshot after
    /// connecting), so the replay can wait before it starts playing.
    pub ready: std::sync::mpsc::Sender<()>,
    /// Told once per input, when the server has answered every command the
    /// input made and the interaction has taken in everything the server
    /// said before those answers: only then may the next input come.
    pub done: std::sync::mpsc::Sender<()>,
}

/// [`drive`] for a replay, in lockstep with it ([`Lockstep`]): the server sees
/// every command in order, none coalesced, and the interaction sees the
/// server's state at the same point of the recording whatever the pace; drags
/// leave only as the recorded samples make them due (no wall clock). So every
/// replay speed sends the same commands and gets the same answers.
pub async fn drive_in_lockstep(
    config: &Config,
    wire: Arc<dyn Wire>,
    inputs: mpsc::UnboundedReceiver<Input>,
    shutdown: impl Future<Output = ()>,
    lockstep: Lockstep,
) -> Result<(), String> {
    drive_inner(config, wire, inputs, shutdown, Some(lockstep)).await
}

async fn drive_inner(
    config: &Config,
    wire: Arc<dyn Wire>,
    mut inputs: mpsc::UnboundedReceiver<Input>,
    shutdown: impl Future<Output = ()>,
    lockstep: Option<Lockstep>,
) -> Result<(), String> {
    let live = lockstep.is_none();
    let (mut ready, done) = match lockstep {
        Some(l) => (Some(l.ready), Some(l.done)),
        None => (None, None),
    };
    // The answer count that completes the input being replayed.
    let mut awaiting: Option<u64> = None;
    // No answers come while the link is down: a replay then goes on unanswered.
    let mut connected = false;
    let mut interaction = Interaction::new(config);
    let (ev_tx, mut events) = mpsc::unbounded_channel();
    let link = (!config.server.url.is_empty()).then(|| {
        let mut o = LinkOptions::new(config.server.url.clone());
        o.token = config.server.token.clone();
        o.design = config.server.design;
        o.in_order = !live;
        Link::spawn(o, wire, ev_tx.clone())
    });
    tokio::pin!(shutdown);
    let mut cmds: Vec<Command> = Vec::new();
    let mut samples_open = true;
    let mut refusals = std::collections::HashSet::new();
    // Once the inputs end, a grace period for the last commands to leave (one
    // deadline: the flush timer's wake-ups must not restart it).
    let drain = tokio::time::sleep(Duration::from_secs(1 << 30));
    tokio::pin!(drain);
    let mut flush = tokio::time::interval(interaction.drag_period());
    flush.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        tokio::select! {
            // Only while a drag waits for its slot: no wake-ups for nothing.
            _ = flush.tick(), if live && interaction.drag_waiting() => {
                cmds.clear();
                interaction.flush_due(Timestamp::now(), &mut cmds);
                if !cmds.is_empty() && let Some(l) = &link {
                    l.send(cmds.drain(..));
                }
            }
            input = inputs.recv(), if samples_open => match input {
                Some(input) => {
                    cmds.clear();
                    match input {
                        Input::Samples(batch) => {
                            for s in &batch {
                                interaction.handle(s, &mut cmds);
                            }
                        }
                        Input::Status(source, status) => {
                            let device = config
                                .devices
                                .get(usize::from(source.0))
                                .map_or_else(|| source.0.to_string(), |d| d.name.clone());
                            let (condition, message) = match status {
                                DeviceStatus::Open => (DeviceCondition::Connected, String::new()),
                                DeviceStatus::Unavailable(e) => (DeviceCondition::Disconnected, e),
                                DeviceStatus::Lost(e) => {
                                    interaction.device_lost(source, &mut cmds);
                                    (DeviceCondition::Disconnected, e)
                                }
                            };
                            cmds.push(Command::DeviceStatus { device, condition, message });
                        }
                    }
                    let mut owed = None;
                    if !cmds.is_empty() {
                        match &link {
                            Some(l) => owed = l.send(cmds.drain(..)),
                            None => tracing::debug!(?cmds, "no server configured"),
                        }
                    }
                    if let Some(done) = &done {
                        match owed {
                            Some(total) if connected => awaiting = Some(total),
                            _ => {
                                let _ = done.send(());
                            }
                        }
                    }
                }
                None => {
                    samples_open = false;
                    drain.as_mut().reset(tokio::time::Instant::now() + DRAIN_GRACE);
                }
            },
            ev = events.recv() => if let Some(ev) = ev {
                if let ServerEvent::Rejected(_, text) = &ev {
                    return Err(text.clone());
                }
                if let ServerEvent::Error(e) = &ev && refusals.insert(e.clone()) {
                    // Each distinct refusal is logged once (a refused drag would repeat at
                    // the device rate); the set is bounded.
                    tracing::warn!(error = %e, "server refused a command");
                    if refusals.len() > MAX_REFUSALS {
                        refusals.clear();
                    }
                }
                let snapshot = matches!(ev, ServerEvent::Icons { .. });
                // The replayed input's commands are all answered, or the
                // connection they went on is gone (the restore re-sends state).
                let settled = match ev {
                    ServerEvent::Answered(n) => awaiting.is_some_and(|a| n >= a),
                    ServerEvent::Connected | ServerEvent::Disconnected => {
                        connected = matches!(ev, ServerEvent::Connected);
                        true
                    }
                    _ => false,
                };
                apply_event(&mut interaction, ev, link.as_ref());
                if snapshot && let Some(r) = ready.take() {
                    let _ = r.send(());
                }
                if settled
                    && awaiting.take().is_some()
                    && let Some(done) = &done
                {
                    let _ = done.send(());
                }
            },
            _ = &mut drain, if !samples_open => break,
            _ = &mut shutdown => break,
        }
    }
    Ok(())
}

/// Runs every configured device (recording raw traffic to `record` when given)
/// until `shutdown`.
pub async fn run_live(
    config: Config,
    wire: Arc<dyn Wire>,
    record: Option<&Path>,
    shutdown: impl Future<Output = ()>,
) -> Result<(), BridgeError> {
    let recorder = match record {
        Some(p) => Some(Recorder::create(p, &config)?),
        None => None,
    };
    let (tx, rx) = mpsc::unbounded_channel::<Input>();
    let mut runners = Vec::new();
    for (i, d) in config.devices.iter().enumerate() {
        let mut driver = build_driver(SourceId(i as u16), d);
        if matches!(d.kind, DeviceKind::Flock | DeviceKind::Fastrak) {
            // A tracker streaming at up to 1 kHz is read in bulk once a drag
            // slot: no drag could leave in between anyway.
            driver.set_coalesce(Duration::from_micros(config.rates.drag_period_us()));
        }
        let status_tap = recorder.as_ref().map(|r| r.tap());
        if let Some(r) = &recorder {
            driver.set_tap(r.tap());
        }
        let (tx, tx_status) = (tx.clone(), tx.clone());
        let source = SourceId(i as u16);
        runners.push(DeviceRunner::spawn_with_status(
            Box::new(driver),
            run_options(d.kind),
            move |s| tx.send(Input::Samples(s.to_vec())).is_ok(),
            move |st| {
                if let Some(tap) = &status_tap {
                    // Recorded in order with the device's frames (same thread).
                    let _ = tap.send(TapEvent::Status {
                        source,
                        time: Timestamp::now(),
                        status: st.clone(),
                    });
                }
                let _ = tx_status.send(Input::Status(source, st));
            },
        ));
    }
    drop(tx);
    let driven = drive(&config, wire, rx, shutdown).await;
    // Joining the device threads and the recorder blocks: off the runtime's
    // thread (works on the one-thread runtime of [`runtime`] as on any other).
    let finished = tokio::task::spawn_blocking(move || {
        for mut r in runners {
            r.stop();
        }
        recorder.map(Recorder::finish).transpose()
    })
    .await
    .map_err(|e| RecordingError::Format(format!("stopping the devices failed: {e}")))?;
    if let Some(n) = finished? {
        tracing::info!(events = n, "recording written");
    }
    driven.map_err(BridgeError::Rejected)
}

/// Replays `path` at `speed` through the same decoders and interaction, with the
/// configuration the session was recorded with (devices, hands, calibration, menu,
/// gates, rates); `config` supplies only the server link. Returns the number of
/// samples replayed.
pub async fn run_replay(
    config: Config,
    wire: Arc<dyn Wire>,
    path: &Path,
    speed: f64,
    shutdown: impl Future<Output = ()>,
) -> Result<u64, BridgeError> {
    let replayer = Replayer::open(path)?;
    let recorded = replayer.config().clone();
    if !config.devices.is_empty() && recorded_config(&config) != recorded {
        tracing::warn!(
            "the configuration differs from the recorded one; replay uses the recorded \
             devices, hands, calibration, menu and gates (only the server link is taken)"
        );
    }
    let config = Config {
        server: config.server,
        ..recorded
    };
    let (tx, rx) = mpsc::unbounded_channel::<Input>();
    // With a server, play only once its icons are known (or after a timeout), so
    // the recorded grabs find what they grabbed live; then each input only once
    // the server has answered the last one's commands (lockstep: the pace
    // changes neither what the server gets nor what the interaction knows).
    let (ready_tx, ready_rx) = std::sync::mpsc::channel::<()>();
    let (done_tx, done_rx) = std::sync::mpsc::channel::<()>();
    let wait = !config.server.url.is_empty();
    let player = tokio::task::spawn_blocking(move || {
        if wait {
            let _ = ready_rx.recv_timeout(REPLAY_WAIT);
        }
        let mut stalled = false;
        replayer.play(speed, |input| {
            if tx.send(input).is_err() {
                return false;
            }
            // A server that stops answering must not hang the replay for good.
            if stalled {
                while done_rx.try_recv().is_ok() {}
            } else if done_rx.recv_timeout(REPLAY_WAIT).is_err() {
                stalled = true;
                tracing::warn!(
                    "the server did not answer within {REPLAY_WAIT:?}; replaying on without waiting"
                );
            }
            true
        })
    });
    let lockstep = Lockstep {
        ready: ready_tx,
        done: done_tx,
    };
    let driven = drive_in_lockstep(&config, wire, rx, shutdown, lockstep).await;
    if let Err(text) = driven {
        player.abort();
        return Err(BridgeError::Rejected(text));
    }
    Ok(player
        .await
        .map_err(|e| RecordingError::Format(e.to_string()))??)
}
