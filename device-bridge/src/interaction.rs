//! Interaction (paper 003): hands grab, drag and release icons; the 3D mouse's
//! buttons work the 3D menu (constraint/load, position/tangent/normal,
//! driving/passive/sleeping) and its axes move the selected icon.
//!
//! This is a pure state machine: validated [`Sample`]s and the icon state the
//! server reports go in, [`Command`]s for the server come out. It never does I/O.
//!
//! * A hand closing near icons grabs the nearest one within reach (sleeping icons
//!   and icons held by another hand are skipped): it is bound to the hand's sensor
//!   and becomes driving. Moving the hand by Δx drags it: a constraint icon gets the
//!   displaced target `p0 + Δx` directly; a load icon gets the spring force
//!   `f = k Δx` ([`DragSpring`]). Opening the hand releases it: unbound, passive.
//! * Load springs adapt from the icon displacement Δy the server reports.
//! * Rotation turns a direction: a normal or tangent constraint's direction (its
//!   target, held from the icon's point on the surface) follows the grabbing
//!   hand's change of orientation, or the 3D mouse's twist of the cap at
//!   `menu.rotation_speed` rad/s at full deflection about the scene's axes. A
//!   position constraint or a load has no orientation: a twist leaves it alone.
//!   (The view is each client's own; the bridge does not turn it.)

use crate::config::{Config, MenuConfig};
use crate::device::{Reading, Sample, SourceId, Timestamp};
use crate::gate::{MotionGate, Verdict};
use crate::hand::{Gesture, Hand};
use crate::spring::DragSpring;
use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Icon ids as the server numbers them.
pub type IconId = u64;

/// Constraint or load.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IconRole {
    /// Holds the surface (position, tangent or normal).
    Constraint,
    /// Pulls the surface through the spring model.
    Load,
}

/// What a constraint icon holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IconKind {
    /// w(u', v') = P0.
    Position,
    /// w_u(u', v') = T.
    Tangent,
    /// N · w_u = N · w_v = 0.
    Normal,
}

/// Icon state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IconState {
    /// Bound to a sensor; moving it drives the deformation.
    Driving,
    /// No sensor; a constraint still holds.
    Passive,
    /// No effect.
    Sleeping,
}

/// The bridge's view of an icon, as the server reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IconView {
    /// Id (unique across the design's parts).
    pub id: IconId,
    /// The part it is on.
    pub part: u64,
    /// Current position on the surface, in scene units.
    pub position: DVec3,
    /// Its target (a position, derivative vector or normal direction); drags
    /// start from `position`, where the icon is on the surface.
    pub target: DVec3,
    /// Constraint or load.
    pub role: IconRole,
    /// Position, tangent or normal.
    pub kind: IconKind,
    /// Driving, passive or sleeping.
    pub state: IconState,
}

/// Entries of the 3D menu, in ring order.
pub const MENU: [MenuEntry; 8] = [
    MenuEntry::Role(IconRole::Constraint),
    MenuEntry::Role(IconRole::Load),
    MenuEntry::Kind(IconKind::Position),
    MenuEntry::Kind(IconKind::Tangent),
    MenuEntry::Kind(IconKind::Normal),
    MenuEntry::State(IconState::Driving),
    MenuEntry::State(IconState::Passive),
    MenuEntry::State(IconState::Sleeping),
];

/// One entry of the 3D menu.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MenuEntry {
    /// Make the selected icon a constraint or a load.
    Role(IconRole),
    /// Make the selected constraint a position, tangent or normal constraint.
    Kind(IconKind),
    /// Set the selected icon's state.
    State(IconState),
}

/// What a 3D-mouse button does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MenuAction {
    /// Highlight the next menu entry.
    NextEntry,
    /// Highlight the previous menu entry.
    PreviousEntry,
    /// Apply the highlighted entry to the selected icon.
    ApplyEntry,
    /// Select the next icon (by id).
    SelectNextIcon,
    /// Select the first icon (by id) of the next part (by part id) that has
    /// icons to grab: the menu's way through a product's parts.
    SelectNextPart,
}

/// A device's availability as reported to the server.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceCondition {
    /// Open and delivering.
    Connected,
    /// Gone; being reopened.
    Disconnected,
}

/// An instruction for the server.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// Take `icon` with `sensor`: bind the sensor and start dragging (driving).
    Grab {
        /// Icon.
        icon: IconId,
        /// Sensor name (the hand's name, or the 3D mouse's device name).
        sensor: String,
    },
    /// Let go of `icon`: end the drag (it becomes passive, the shape is kept) and unbind.
    Release {
        /// Icon.
        icon: IconId,
        /// Sensor name.
        sensor: String,
    },
    /// Move a held icon's target: a constraint's displaced target, or a load's
    /// pulled-to point (the spring model's force expressed as a point, see
    /// [`DragSpring::pull_point`]).
    Drag {
        /// Icon.
        icon: IconId,
        /// Target in scene units.
        target: DVec3,
    },
    /// Set an icon's state.
    SetState {
        /// Icon.
        icon: IconId,
        /// New state.
        state: IconState,
    },
    /// Make an icon a constraint or a load.
    SetRole {
        /// Icon.
        icon: IconId,
        /// New role.
        role: IconRole,
    },
    /// Make an icon a position, tangent or normal constraint.
    SetKind {
        /// Icon.
        icon: IconId,
        /// New kind.
        kind: IconKind,
    },
    /// Where a hand is (for other clients to draw it); the newest wins.
    HandSample {
        /// Sensor name (the hand's name).
        sensor: String,
        /// Scene position.
        position: DVec3,
        /// Scene orientation.
        orientation: DQuat,
        /// Finger joint flexion in radians, per glove sensor (empty without a glove).
        flexion: Vec<f64>,
        /// When the tracker record arrived.
        time: Timestamp,
    },
    /// A device's availability changed.
    DeviceStatus {
        /// The device's configured name.
        device: String,
        /// Its condition.
        condition: DeviceCondition,
        /// Details.
        message: String,
    },
}

/// What a pending command is about, for coalescing.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Subject {
    /// An icon.
    Icon(IconId),
    /// A sensor.
    Sensor(String),
    /// A device.
    Device(String),
}

impl Command {
    /// What the command is about.
    pub fn subject(&self) -> Subject {
        match self {
            Command::Grab { icon, .. }
            | Command::Release { icon, .. }
            | Command::Drag { icon, .. }
            | Command::SetState { icon, .. }
            | Command::SetRole { icon, .. }
            | Command::SetKind { icon, .. } => Subject::Icon(*icon),
            Command::HandSample { sensor, .. } => Subject::Sensor(sensor.clone()),
            Command::DeviceStatus { device, .. } => Subject::Device(device.clone()),
        }
    }

    /// True for the continuous commands (drags, hand samples), which may be
    /// coalesced to the newest.
    pub fn is_continuous(&self) -> bool {
        matches!(self, Command::Drag { .. } | Command::HandSample { .. })
    }
}

/// A drag in progress, by a hand or the 3D mouse.
#[derive(Clone, Debug)]
struct Hold {
    icon: IconId,
    /// The sensor holding it.
    sensor: String,
    /// Where the hand (or virtual hand) was when the drag began.
    origin: DVec3,
    /// Where the icon was on the surface when the drag began.
    icon_origin: DVec3,
    /// Current displacement Δx.
    offset: DVec3,
    /// The spring of a load drag.
    spring: Option<DragSpring>,
    /// A direction constraint's direction at the grab (a normal as a lever of
    /// [`NORMAL_LEVER`] surface sizes), which [`Hold::turn`] rotates.
    direction: Option<DVec3>,
    /// The rotation applied to `direction` since the grab.
    turn: DQuat,
    /// The hand's orientation for which `turn` is the identity (hands only).
    reference: DQuat,
    /// When a drag of this hold last left (sample time).
    sent_at: Option<Timestamp>,
    /// A newer drag than the last one sent is waiting for its slot.
    pending: bool,
    /// The target of the last drag queued: a drag to the same target is not
    /// sent again (a still hand or a 3D mouse at rest sends nothing).
    last_target: Option<DVec3>,
}

impl Hold {
    /// Queues the current drag: it leaves now when the rate allows (`period_us`
    /// since the last one, by sample time), else it waits as the latest.
    ///
    /// Records read in one chunk share its arrival time and make one slot: when
    /// the drag just queued in `out` came from an earlier record of the same
    /// chunk, this one takes its place, so the chunk's latest record leaves.
    fn drag_at(&mut self, time: Timestamp, period_us: u64, out: &mut Vec<Command>) {
        if self.sent_at == Some(time) {
            let icon = self.icon;
            if let Some(queued) = out
                .iter_mut()
                .rev()
                .find(|c| matches!(c, Command::Drag { icon: i, .. } if *i == icon))
            {
                *queued = self.drag();
                self.last_target = Some(self.target());
                self.pending = false;
                return;
            }
        }
        if self.last_target == Some(self.target()) {
            // Nothing new for the server: no drag, nothing waiting, and the
            // next change leaves at once if its slot is due.
            self.pending = false;
            return;
        }
        let due = self
            .sent_at
            .is_none_or(|t| time.0.saturating_sub(t.0) >= period_us);
        if due {
            self.sent_at = Some(time);
            self.pending = false;
            self.last_target = Some(self.target());
            out.push(self.drag());
        } else {
            self.pending = true;
        }
    }

    /// Sends the waiting drag, if any.
    fn flush(&mut self, out: &mut Vec<Command>) {
        if self.pending {
            self.pending = false;
            self.last_target = Some(self.target());
            out.push(self.drag());
        }
    }

    fn drag(&self) -> Command {
        Command::Drag {
            icon: self.icon,
            target: self.target(),
        }
    }

    /// Where the drag pulls the icon now.
    fn target(&self) -> DVec3 {
        match (&self.spring, self.direction) {
            (Some(s), _) => s.pull_point(self.icon_origin, self.offset),
            // The server reads a direction icon's drag as the point its direction
            // points to from the icon (pointer − icon).
            (None, Some(d)) => self.icon_origin + self.turn * d + self.offset,
            (None, None) => self.icon_origin + self.offset,
        }
    }

    /// Lets go: the last drag (if one is waiting) first, then the release.
    fn release(mut self, out: &mut Vec<Command>) {
        self.flush(out);
        out.push(Command::Release {
            icon: self.icon,
            sensor: self.sensor.clone(),
        });
    }
}

/// A normal is held as a lever this many surface sizes (√ area) long, so the
/// icon's own slide on the surface while the normal turns (the server measures
/// the direction from where the icon is now) tilts it by at most 1e-3 of the
/// slide over the surface size.
pub const NORMAL_LEVER: f64 = 1000.0;

/// Hands are reported to other clients at presence rate (architecture: 10–30 Hz,
/// latest wins), not at the tracker's rate; drags still go at the tracker's rate.
pub const HAND_SAMPLE_PERIOD_US: u64 = 33_000;

struct HandSlot {
    last_report: Option<Timestamp>,
    tracker: SourceId,
    sensor: u16,
    glove: Option<SourceId>,
    name: String,
    reach: f64,
    hand: Hand,
    hold: Option<Hold>,
    gate: MotionGate,
    tracker_name: String,
    /// Rejected count at the last log line.
    logged_rejects: u64,
}

/// The interaction state machine.
pub struct Interaction {
    hands: Vec<HandSlot>,
    icons: BTreeMap<IconId, IconView>,
    menu_device: Option<SourceId>,
    menu_sensor: String,
    menu: MenuConfig,
    entry: usize,
    selected: Option<IconId>,
    mouse_hold: Option<Hold>,
    mouse_time: Option<Timestamp>,
    surface_area: f64,
    drag_period_us: u64,
}

impl Interaction {
    /// Builds the hands and menu of `config`.
    pub fn new(config: &Config) -> Self {
        let hands = config
            .hands
            .iter()
            .filter_map(|h| {
                let (tracker, device) = config.device(&h.tracker)?;
                let glove = h.glove.as_ref().and_then(|g| config.device(g)).map(|g| g.0);
                Some(HandSlot {
                    gate: MotionGate::new(device.gate, device.record_interval()),
                    tracker_name: device.name.clone(),
                    logged_rejects: 0,
                    last_report: None,
                    tracker,
                    sensor: h.sensor,
                    glove,
                    name: h.name.clone(),
                    reach: h.reach,
                    hand: Hand::new(config.calibration, h.calibration.clone()),
                    hold: None,
                })
            })
            .collect();
        let menu_device = config.menu_device();
        let menu_sensor = menu_device
            .and_then(|d| config.devices.get(usize::from(d.0)))
            .map_or_else(|| "3d-mouse".to_owned(), |d| d.name.clone());
        Self {
            hands,
            icons: BTreeMap::new(),
            menu_device,
            menu_sensor,
            menu: config.menu.clone(),
            entry: 0,
            selected: None,
            mouse_hold: None,
            mouse_time: None,
            surface_area: 1.0,
            drag_period_us: config.rates.drag_period_us(),
        }
    }

    /// Sets the surface area S used for the spring stiffness k0 = κ S.
    pub fn set_surface_area(&mut self, area: f64) {
        if area.is_finite() && area > 0.0 {
            self.surface_area = area;
        }
    }

    /// The highlighted menu entry.
    pub fn menu_entry(&self) -> MenuEntry {
        MENU[self.entry]
    }

    /// The icon the 3D mouse acts on.
    pub fn selected(&self) -> Option<IconId> {
        self.selected
    }

    fn holds(&self) -> impl Iterator<Item = &Hold> {
        self.hands
            .iter()
            .filter_map(|h| h.hold.as_ref())
            .chain(self.mouse_hold.as_ref())
    }

    /// Sends the drags that waited for their slot and are due at `now` (on the
    /// sample clock): a hand that stops moving, or a tracker that only reports
    /// changes, still gets its latest drag out within one drag period.
    pub fn flush_due(&mut self, now: Timestamp, out: &mut Vec<Command>) {
        let period = self.drag_period_us;
        let holds = self
            .hands
            .iter_mut()
            .filter_map(|h| h.hold.as_mut())
            .chain(self.mouse_hold.as_mut());
        for g in holds.filter(|g| g.pending) {
            g.drag_at(now, period, out);
        }
    }

    /// True when a drag waits for its slot ([`Interaction::flush_due`] has work).
    pub fn drag_waiting(&self) -> bool {
        self.holds().any(|g| g.pending)
    }

    /// The minimum time between two drags of one icon.
    pub fn drag_period(&self) -> std::time::Duration {
        std::time::Duration::from_micros(self.drag_period_us)
    }

    /// Tracker records the plausibility gates refused so far (all hands).
    pub fn rejected_poses(&self) -> u64 {
        self.hands.iter().map(|h| h.gate.rejected()).sum()
    }

    /// Held icons with the sensor holding each.
    pub fn bindings(&self) -> Vec<(IconId, String)> {
        self.holds().map(|g| (g.icon, g.sensor.clone())).collect()
    }

    /// Commands that re-establish every held drag (after a reconnect).
    pub fn restore(&self) -> Vec<Command> {
        let mut out = Vec::new();
        for g in self.holds() {
            out.push(Command::Grab {
                icon: g.icon,
                sensor: g.sensor.clone(),
            });
            out.push(g.drag());
        }
        out
    }

    /// The icons as last reported.
    pub fn icons(&self) -> impl Iterator<Item = &IconView> {
        self.icons.values()
    }

    /// Replaces the whole icon set (a snapshot from the server); holds on icons that
    /// vanished are dropped.
    pub fn set_icons(&mut self, icons: impl IntoIterator<Item = IconView>) {
        self.icons = icons.into_iter().map(|i| (i.id, i)).collect();
        let gone = |g: &Option<Hold>, icons: &BTreeMap<IconId, IconView>| {
            g.as_ref().is_some_and(|g| !icons.contains_key(&g.icon))
        };
        for h in &mut self.hands {
            if gone(&h.hold, &self.icons) {
                h.hold = None;
            }
        }
        if gone(&self.mouse_hold, &self.icons) {
            self.mouse_hold = None;
        }
        if self.selected.is_some_and(|s| !self.icons.contains_key(&s)) {
            self.selected = None;
        }
    }

    /// Updates one icon as the server reports it.
    pub fn update_icon(&mut self, icon: IconView) {
        self.icons.insert(icon.id, icon);
    }

    /// The server solved a drag of `icon`: it now sits at `actual`. Adapts the
    /// spring of a held load from Δy = actual − start against the drag Δx.
    pub fn feedback(&mut self, icon: IconId, actual: DVec3) {
        if !actual.is_finite() {
            return;
        }
        if let Some(v) = self.icons.get_mut(&icon) {
            v.position = actual;
        }
        let holds = self
            .hands
            .iter_mut()
            .filter_map(|h| h.hold.as_mut())
            .chain(self.mouse_hold.as_mut());
        for g in holds.filter(|g| g.icon == icon) {
            if let Some(s) = &mut g.spring {
                s.observe(g.offset, actual - g.icon_origin);
            }
        }
    }

    /// Forgets an icon the server deleted.
    pub fn remove_icon(&mut self, id: IconId) {
        let rest: Vec<IconView> = self
            .icons
            .values()
            .filter(|i| i.id != id)
            .copied()
            .collect();
        self.set_icons(rest);
    }

    fn start_hold(
        &self,
        icon: &IconView,
        sensor: String,
        origin: DVec3,
        orientation: DQuat,
    ) -> Hold {
        let load = icon.role == IconRole::Load;
        let direction = match (icon.role, icon.kind) {
            (IconRole::Constraint, IconKind::Normal) => icon
                .target
                .try_normalize()
                .map(|n| n * NORMAL_LEVER * self.surface_area.sqrt()),
            (IconRole::Constraint, IconKind::Tangent) => {
                Some(icon.target).filter(|t| t.is_finite())
            }
            _ => None,
        };
        Hold {
            icon: icon.id,
            sensor,
            origin,
            // Drags start from where the icon visibly is on the surface.
            icon_origin: icon.position,
            offset: DVec3::ZERO,
            spring: load.then(|| DragSpring::new(self.surface_area)),
            direction,
            turn: DQuat::IDENTITY,
            reference: orientation,
            sent_at: None,
            pending: false,
            last_target: None,
        }
    }

    fn nearest_free_icon(&self, at: DVec3, reach: f64) -> Option<IconView> {
        let held: Vec<IconId> = self.holds().map(|g| g.icon).collect();
        self.icons
            .values()
            .filter(|i| i.state != IconState::Sleeping && !held.contains(&i.id))
            .map(|i| (i.position.distance(at), i))
            .filter(|(d, _)| *d <= reach)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, i)| *i)
    }

    /// Handles one sample, appending the resulting commands to `out`.
    pub fn handle(&mut self, sample: &Sample, out: &mut Vec<Command>) {
        match sample.reading {
            Reading::Pose {
                sensor,
                position,
                orientation,
            } => {
                let period = self.drag_period_us;
                for h in &mut self.hands {
                    if h.tracker != sample.source || h.sensor != sensor {
                        continue;
                    }
                    let verdict = h.gate.check(position, orientation, sample.time);
                    if verdict == Verdict::Reject {
                        let n = h.gate.rejected();
                        if n > h.logged_rejects && (n.is_power_of_two() || n % 1000 == 0) {
                            tracing::warn!(
                                device = %h.tracker_name,
                                dropped = n,
                                "implausible tracker records dropped (bad bytes on the line?)"
                            );
                            h.logged_rejects = n;
                        }
                        continue;
                    }
                    let pose = h.hand.update_pose(position, orientation, sample.time);
                    let due = h.last_report.is_none_or(|t| {
                        sample.time.since(t).as_micros() as u64 >= HAND_SAMPLE_PERIOD_US
                    });
                    if due {
                        h.last_report = Some(sample.time);
                        out.push(Command::HandSample {
                            sensor: h.name.clone(),
                            position: pose.position,
                            orientation: pose.orientation,
                            flexion: h.hand.flexion_rad(),
                            time: sample.time,
                        });
                    }
                    if let Some(g) = &mut h.hold {
                        if verdict == Verdict::Reacquired {
                            // A new track: the drag continues from where it is.
                            g.origin = pose.position - g.offset;
                            g.reference = g.turn.inverse() * pose.orientation;
                        } else {
                            g.offset = pose.position - g.origin;
                            if g.direction.is_some() {
                                g.turn = (pose.orientation * g.reference.inverse()).normalize();
                            }
                            g.drag_at(sample.time, period, out);
                        }
                    }
                }
            }
            Reading::Glove(values) => {
                for i in 0..self.hands.len() {
                    if self.hands[i].glove != Some(sample.source) {
                        continue;
                    }
                    let Some(gesture) = self.hands[i].hand.update_glove(&values) else {
                        continue;
                    };
                    self.gesture(i, gesture, out);
                }
            }
            Reading::Button { button, pressed } => {
                if Some(sample.source) == self.menu_device
                    && pressed
                    && let Some(action) = self.menu.buttons.get(&button).copied()
                {
                    self.menu_action(action, out);
                }
            }
            Reading::Motion {
                translation,
                rotation,
            } => {
                if Some(sample.source) == self.menu_device {
                    self.mouse_motion(translation, rotation, sample.time, out);
                }
            }
        }
    }

    /// A device failed: hands using it let go of what they hold (a drag must not
    /// continue from a stale hand), and a mouse drag by it ends.
    pub fn device_lost(&mut self, source: SourceId, out: &mut Vec<Command>) {
        for i in 0..self.hands.len() {
            let h = &self.hands[i];
            if h.tracker == source || h.glove == Some(source) {
                self.gesture(i, Gesture::Open, out);
            }
            if self.hands[i].tracker == source {
                self.hands[i].gate.reset();
            }
        }
        if self.menu_device == Some(source) {
            if let Some(g) = self.mouse_hold.take() {
                g.release(out);
            }
            self.mouse_time = None;
        }
    }

    fn gesture(&mut self, i: usize, gesture: Gesture, out: &mut Vec<Command>) {
        match gesture {
            Gesture::Grab => {
                if self.hands[i].hold.is_some() {
                    return;
                }
                let Some(pose) = self.hands[i].hand.pose() else {
                    return;
                };
                // A mouse drag of the icon the hand reaches for yields to the hand.
                if let Some(icon) = self.nearest_any(pose.position, self.hands[i].reach)
                    && self.mouse_hold.as_ref().is_some_and(|m| m.icon == icon)
                    && let Some(m) = self.mouse_hold.take()
                {
                    m.release(out);
                }
                let Some(icon) = self.nearest_free_icon(pose.position, self.hands[i].reach) else {
                    return;
                };
                let hold = self.start_hold(
                    &icon,
                    self.hands[i].name.clone(),
                    pose.position,
                    pose.orientation,
                );
                tracing::info!(icon = icon.id, hand = %hold.sensor, "grab");
                out.push(Command::Grab {
                    icon: icon.id,
                    sensor: hold.sensor.clone(),
                });
                self.hands[i].hold = Some(hold);
                self.selected = Some(icon.id);
            }
            Gesture::Open | Gesture::Point => {
                if let Some(g) = self.hands[i].hold.take() {
                    tracing::info!(icon = g.icon, hand = %g.sensor, "release");
                    g.release(out);
                }
            }
        }
    }

    fn nearest_any(&self, at: DVec3, reach: f64) -> Option<IconId> {
        self.icons
            .values()
            .filter(|i| i.state != IconState::Sleeping)
            .map(|i| (i.position.distance(at), i.id))
            .filter(|(d, _)| *d <= reach)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, id)| id)
    }

    fn menu_action(&mut self, action: MenuAction, out: &mut Vec<Command>) {
        match action {
            MenuAction::NextEntry => self.entry = (self.entry + 1) % MENU.len(),
            MenuAction::PreviousEntry => self.entry = (self.entry + MENU.len() - 1) % MENU.len(),
            MenuAction::SelectNextIcon => {
                if let Some(g) = self.mouse_hold.take() {
                    g.release(out);
                }
                let next = match self.selected {
                    Some(s) => self
                        .icons
                        .range(s + 1..)
                        .next()
                        .or_else(|| self.icons.iter().next()),
                    None => self.icons.iter().next(),
                };
                self.selected = next.map(|(id, _)| *id);
            }
            MenuAction::SelectNextPart => {
                if let Some(g) = self.mouse_hold.take() {
                    g.release(out);
                }
                let current = self
                    .selected
                    .and_then(|s| self.icons.get(&s))
                    .map(|i| i.part);
                let first_of = |part: u64| {
                    self.icons
                        .values()
                        .filter(|i| i.part == part)
                        .map(|i| i.id)
                        .min()
                };
                let mut parts: Vec<u64> = self.icons.values().map(|i| i.part).collect();
                parts.sort_unstable();
                parts.dedup();
                let next = match current {
                    Some(c) => parts.iter().find(|&&p| p > c).or_else(|| parts.first()),
                    None => parts.first(),
                };
                self.selected = next.and_then(|&p| first_of(p));
            }
            MenuAction::ApplyEntry => {
                let Some(icon) = self.selected.and_then(|s| self.icons.get(&s)) else {
                    return;
                };
                let id = icon.id;
                match MENU[self.entry] {
                    MenuEntry::Role(role) if role != icon.role => {
                        out.push(Command::SetRole { icon: id, role });
                    }
                    MenuEntry::Kind(kind) if kind != icon.kind || icon.role == IconRole::Load => {
                        out.push(Command::SetKind { icon: id, kind });
                    }
                    MenuEntry::State(state) if state != icon.state => {
                        out.push(Command::SetState { icon: id, state });
                    }
                    _ => {}
                }
            }
        }
    }

    /// The 3D mouse's cap, calibrated by its device (dead zones applied there):
    /// translation `t` moves the selected icon, rotation `r` turns a direction
    /// icon's direction; both integrate over the time between events.
    fn mouse_motion(&mut self, t: DVec3, r: DVec3, time: Timestamp, out: &mut Vec<Command>) {
        if t == DVec3::ZERO && r == DVec3::ZERO {
            // The cap is back at rest: the mouse drag ends, the shape is kept, and the
            // integration clock stops, so the next push starts from zero motion.
            if let Some(g) = self.mouse_hold.take() {
                g.release(out);
            }
            self.mouse_time = None;
            return;
        }
        // The first event of a push only starts the clock; each later one moves by
        // its deflection over the time since the previous event (at most 0.1 s).
        let dt = self
            .mouse_time
            .map_or(0.0, |p| time.since(p).as_secs_f64().min(0.1));
        self.mouse_time = Some(time);
        let Some(icon) = self.selected.and_then(|s| self.icons.get(&s)).copied() else {
            return;
        };
        if self
            .hands
            .iter()
            .any(|h| h.hold.as_ref().is_some_and(|g| g.icon == icon.id))
        {
            return; // a hand holds it
        }
        let turns = icon.role == IconRole::Constraint && icon.kind != IconKind::Position;
        if t == DVec3::ZERO && !turns {
            return; // a twist does not move a position or a load
        }
        if self.mouse_hold.as_ref().is_none_or(|g| g.icon != icon.id) {
            if let Some(g) = self.mouse_hold.take() {
                g.release(out);
            }
            let hold = self.start_hold(
                &icon,
                self.menu_sensor.clone(),
                DVec3::ZERO,
                DQuat::IDENTITY,
            );
            out.push(Command::Grab {
                icon: icon.id,
                sensor: hold.sensor.clone(),
            });
            self.mouse_hold = Some(hold);
        }
        let (speed, turn_speed) = (self.menu.speed, self.menu.rotation_speed);
        let period = self.drag_period_us;
        if let Some(g) = &mut self.mouse_hold {
            g.offset += t * speed * dt;
            if g.direction.is_some() {
                let step = DQuat::from_scaled_axis(r * turn_speed * dt);
                g.turn = (step * g.turn).normalize();
            }
            g.drag_at(time, period, out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{DeviceConfig, DeviceKind, HandConfig};
    use crate::device::GloveValues;
    use crate::hand::{GloveCalibration, glove_shape};

    /// A gate that lets any motion through at once (these tests are about the
    /// interaction; the gate has its own).
    fn permissive() -> crate::gate::GateSettings {
        crate::gate::GateSettings {
            max_speed: 1e9,
            max_acceleration: 1e12,
            noise: 1e3,
            confirm: 1,
            max_angular_speed: 1e9,
            ..Default::default()
        }
    }

    /// Sample times 10 ms apart, in call order.
    fn tick() -> Timestamp {
        use std::sync::atomic::{AtomicU64, Ordering};
        static NOW: AtomicU64 = AtomicU64::new(1_000_000);
        Timestamp(NOW.fetch_add(10_000, Ordering::Relaxed))
    }

    fn config() -> Config {
        let mut tracker = DeviceConfig::new("tracker", DeviceKind::Flock);
        tracker.port = Some("/dev/null".into());
        tracker.gate = permissive();
        let mut glove = DeviceConfig::new("glove", DeviceKind::Cyberglove);
        glove.port = Some("/dev/null".into());
        let mouse = DeviceConfig::new("mouse", DeviceKind::Spacenavd);
        let c = Config {
            devices: vec![tracker, glove, mouse],
            hands: vec![HandConfig {
                name: "right".into(),
                tracker: "tracker".into(),
                sensor: 0,
                glove: Some("glove".into()),
                reach: 0.1,
                calibration: GloveCalibration::default(),
            }],
            ..Default::default()
        };
        c.validate().unwrap();
        c
    }

    fn icon(id: IconId, p: DVec3, role: IconRole) -> IconView {
        IconView {
            id,
            part: 1,
            position: p,
            target: p,
            role,
            kind: IconKind::Position,
            state: IconState::Passive,
        }
    }

    fn pose(p: DVec3) -> Sample {
        Sample {
            source: SourceId(0),
            time: tick(),
            reading: Reading::Pose {
                sensor: 0,
                position: p,
                orientation: DQuat::IDENTITY,
            },
        }
    }

    fn hand(index: f64, others: f64) -> Sample {
        Sample {
            source: SourceId(1),
            time: Timestamp(0),
            reading: Reading::Glove(GloveValues::new(&glove_shape(22, index, others)).unwrap()),
        }
    }

    /// Runs samples, dropping the hand samples (tested separately).
    fn run(i: &mut Interaction, samples: &[Sample]) -> Vec<Command> {
        let mut out = Vec::new();
        for s in samples {
            i.handle(s, &mut out);
        }
        out.retain(|c| !matches!(c, Command::HandSample { .. }));
        out
    }

    fn grab(icon: IconId) -> Command {
        Command::Grab {
            icon,
            sensor: "right".into(),
        }
    }

    fn release(icon: IconId) -> Command {
        Command::Release {
            icon,
            sensor: "right".into(),
        }
    }

    /// A pose at `ms` (its own clock: the shared [`tick`] would let other tests'
    /// samples widen the gaps past the gate's `max_gap`).
    fn turned(p: DVec3, q: DQuat, ms: u64) -> Sample {
        Sample {
            source: SourceId(0),
            time: Timestamp(ms * 1000),
            reading: Reading::Pose {
                sensor: 0,
                position: p,
                orientation: q,
            },
        }
    }

    #[test]
    fn a_hand_turns_a_held_normal_by_its_change_of_orientation() {
        let mut i = Interaction::new(&config());
        i.set_surface_area(1.0);
        let n0 = DVec3::new(0.0, 1.0, 0.0);
        i.set_icons([IconView {
            id: 3,
            part: 1,
            position: DVec3::ZERO,
            target: n0,
            role: IconRole::Constraint,
            kind: IconKind::Normal,
            state: IconState::Passive,
        }]);
        // the hand is held turned 0.3 rad about z when it grabs: that is the reference
        let q0 = DQuat::from_rotation_z(0.3);
        let out = run(&mut i, &[turned(DVec3::ZERO, q0, 10), hand(1.0, 1.0)]);
        assert_eq!(out, vec![grab(3)]);
        // turning it a further 0.5 rad about x (scene frame) turns the normal so
        let q1 = DQuat::from_rotation_x(0.5) * q0;
        let out = run(&mut i, &[turned(DVec3::ZERO, q1, 20)]);
        let Some(Command::Drag { icon: 3, target }) = out.last() else {
            panic!("{out:?}");
        };
        let want = DQuat::from_rotation_x(0.5) * n0;
        assert!((target.normalize() - want).length() < 1e-12, "{target}");
        assert!((target.length() - NORMAL_LEVER).abs() < 1e-9);
        // a position icon keeps ignoring the hand's orientation
        let mut i = Interaction::new(&config());
        i.set_icons([icon(4, DVec3::ZERO, IconRole::Constraint)]);
        run(&mut i, &[turned(DVec3::ZERO, q0, 10), hand(1.0, 1.0)]);
        let out = run(&mut i, &[turned(DVec3::X * 0.01, q1, 20)]);
        assert_eq!(
            out,
            vec![Command::Drag {
                icon: 4,
                target: DVec3::X * 0.01
            }]
        );
    }

    #[test]
    fn grab_nearest_drag_constraint_release() {
        let mut i = Interaction::new(&config());
        i.set_icons([
            icon(1, DVec3::new(0.0, 0.0, 0.0), IconRole::Constraint),
            icon(2, DVec3::new(0.05, 0.0, 0.0), IconRole::Constraint),
            icon(3, DVec3::new(0.5, 0.0, 0.0), IconRole::Constraint),
        ]);
        let out = run(&mut i, &[pose(DVec3::new(0.04, 0.0, 0.0)), hand(1.0, 1.0)]);
        assert_eq!(out, vec![grab(2)]);
        assert_eq!(i.bindings(), vec![(2, "right".to_string())]);
        let out = run(&mut i, &[pose(DVec3::new(0.04, 0.1, 0.0))]);
        assert_eq!(
            out,
            vec![Command::Drag {
                icon: 2,
                target: DVec3::new(0.05, 0.1, 0.0)
            }]
        );
        let out = run(&mut i, &[hand(0.0, 0.0)]);
        assert_eq!(out, vec![release(2)]);
        // moving an open hand drags nothing
        assert!(run(&mut i, &[pose(DVec3::ZERO)]).is_empty());
    }

    #[test]
    fn records_read_in_one_chunk_leave_as_one_drag_its_latest() {
        let mut i = Interaction::new(&config());
        i.set_icons([icon(1, DVec3::ZERO, IconRole::Constraint)]);
        let at = |us: u64, x: f64| {
            let mut s = pose(DVec3::X * x);
            s.time = Timestamp(us);
            s
        };
        run(&mut i, &[at(0, 0.0), hand(1.0, 1.0)]);
        // a tracker read in bulk: eight records of one chunk share its arrival time
        let chunk = |us: u64, ks: std::ops::RangeInclusive<u64>| -> Vec<Sample> {
            ks.map(|k| at(us, k as f64 * 1e-4)).collect()
        };
        let drag = |x: f64| Command::Drag {
            icon: 1,
            target: DVec3::X * x,
        };
        assert_eq!(run(&mut i, &chunk(10_000, 1..=8)), vec![drag(8e-4)]);
        assert!(!i.drag_waiting());
        // the next chunk one slot later: again one drag, from its latest record
        assert_eq!(run(&mut i, &chunk(18_400, 9..=16)), vec![drag(16e-4)]);
        // a chunk inside the slot waits as a whole, its latest record winning
        assert!(run(&mut i, &chunk(20_000, 17..=20)).is_empty());
        assert!(i.drag_waiting());
        let mut out = Vec::new();
        i.flush_due(Timestamp(26_800), &mut out);
        assert_eq!(out, vec![drag(20e-4)]);
        assert!(!i.drag_waiting());
    }

    #[test]
    fn a_still_hand_sends_no_drags_and_its_next_move_leaves_at_once() {
        let mut i = Interaction::new(&config());
        i.set_icons([icon(1, DVec3::ZERO, IconRole::Constraint)]);
        let at = |us: u64, x: f64| {
            let mut s = pose(DVec3::X * x);
            s.time = Timestamp(us);
            s
        };
        let drags = |out: &[Command]| -> Vec<f64> {
            out.iter()
                .filter_map(|c| match c {
                    Command::Drag { target, .. } => Some(target.x),
                    _ => None,
                })
                .collect()
        };
        run(&mut i, &[at(0, 0.0), hand(1.0, 1.0)]);
        assert_eq!(drags(&run(&mut i, &[at(1_000, 1e-3)])), vec![1e-3]);
        // the hand holds still for 100 ms of 1 kHz records: the server has that
        // target already, so nothing leaves and nothing waits (no flush tick)
        for k in 2..=101u64 {
            assert!(
                drags(&run(&mut i, &[at(k * 1000, 1e-3)])).is_empty(),
                "record {k}"
            );
            assert!(!i.drag_waiting(), "record {k}");
        }
        // it moves: the drag leaves with that record, its slot long due
        assert_eq!(drags(&run(&mut i, &[at(102_000, 2e-3)])), vec![2e-3]);
        // a move inside the slot and back again leaves nothing behind
        run(&mut i, &[at(103_000, 3e-3)]);
        assert!(i.drag_waiting());
        run(&mut i, &[at(104_000, 2e-3)]);
        assert!(!i.drag_waiting());
        // and the release is not preceded by a repeated drag
        assert_eq!(run(&mut i, &[hand(0.0, 0.0)]), vec![release(1)]);
    }

    #[test]
    fn drags_leave_at_the_drag_rate_latest_wins_and_the_last_before_a_release() {
        let mut i = Interaction::new(&config());
        i.set_icons([icon(1, DVec3::ZERO, IconRole::Constraint)]);
        let at = |us: u64, x: f64| {
            let mut s = pose(DVec3::X * x);
            s.time = Timestamp(us);
            s
        };
        run(&mut i, &[at(0, 0.0), hand(1.0, 1.0)]);
        // a 1 kHz tracker for 105 ms: at 120 Hz the drags leave at records 1, 10, 19 …
        // 100 (each ≥ 8.33 ms after the one before), 12 of 105
        let mut sent = Vec::new();
        for k in 1..=105u64 {
            for c in run(&mut i, &[at(k * 1000, k as f64 * 1e-4)]) {
                if let Command::Drag { target, .. } = c {
                    sent.push((k, target.x));
                }
            }
        }
        let ks: Vec<u64> = sent.iter().map(|s| s.0).collect();
        assert_eq!(ks, (0..12).map(|n| 1 + 9 * n).collect::<Vec<_>>());
        // the hand stops reporting: the waiting drag (record 105) leaves once due
        let mut out = Vec::new();
        i.flush_due(Timestamp(105_000), &mut out);
        assert!(out.is_empty(), "not due yet: {out:?}");
        i.flush_due(Timestamp(108_400), &mut out);
        assert_eq!(
            out,
            vec![Command::Drag {
                icon: 1,
                target: DVec3::X * 105.0 * 1e-4
            }]
        );
        // two more records inside the slot, then the hand opens: the latest drag
        // goes out before the release
        run(&mut i, &[at(109_000, 0.0107), at(110_000, 0.011)]);
        let out = run(&mut i, &[hand(0.0, 0.0)]);
        assert_eq!(
            out,
            vec![
                Command::Drag {
                    icon: 1,
                    target: DVec3::X * 0.011
                },
                release(1)
            ]
        );
    }

    #[test]
    fn hand_samples_carry_pose_and_flexion() {
        let mut i = Interaction::new(&config());
        let mut out = Vec::new();
        i.handle(&hand(1.0, 0.0), &mut out);
        i.handle(&pose(DVec3::new(0.1, 0.2, 0.3)), &mut out);
        match &out[..] {
            [
                Command::HandSample {
                    sensor,
                    position,
                    flexion,
                    ..
                },
            ] => {
                assert_eq!(sensor, "right");
                assert_eq!(*position, DVec3::new(0.1, 0.2, 0.3));
                assert_eq!(flexion.len(), 22);
                // index MPJ fully bent: 90°; middle MPJ open: 0°
                assert!((flexion[4] - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
                assert_eq!(flexion[7], 0.0);
            }
            o => panic!("{o:?}"),
        }
    }

    #[test]
    fn hand_samples_go_at_presence_rate() {
        let mut i = Interaction::new(&config());
        let mut out = Vec::new();
        for t in 0..100u64 {
            let mut s = pose(DVec3::X * t as f64);
            s.time = Timestamp(t * 1000); // a 1 kHz tracker for 0.1 s
            i.handle(&s, &mut out);
        }
        let n = out
            .iter()
            .filter(|c| matches!(c, Command::HandSample { .. }))
            .count();
        assert_eq!(n, 4); // t = 0, 33, 66, 99 ms
    }

    #[test]
    fn nothing_within_reach_or_sleeping_is_not_grabbed() {
        let mut i = Interaction::new(&config());
        let mut sleeping = icon(1, DVec3::ZERO, IconRole::Constraint);
        sleeping.state = IconState::Sleeping;
        i.set_icons([
            sleeping,
            icon(2, DVec3::new(1.0, 0.0, 0.0), IconRole::Constraint),
        ]);
        assert!(run(&mut i, &[pose(DVec3::ZERO), hand(1.0, 1.0)]).is_empty());
        assert!(i.bindings().is_empty());
    }

    #[test]
    fn load_icons_are_pulled_through_the_adapting_spring() {
        let mut c = config();
        c.hands[0].reach = 1.0;
        let mut i = Interaction::new(&c);
        i.set_surface_area(2.0);
        i.set_icons([icon(7, DVec3::ZERO, IconRole::Load)]);
        run(&mut i, &[pose(DVec3::ZERO), hand(1.0, 1.0)]);
        // at κ0 the pulled-to point is the hand displacement itself
        let out = run(&mut i, &[pose(DVec3::new(0.0, 0.0, 0.1))]);
        assert_eq!(
            out,
            vec![Command::Drag {
                icon: 7,
                target: DVec3::new(0.0, 0.0, 0.1)
            }]
        );
        // the server reports the icon moved only 0.02 (ratio 0.2): the spring stiffens
        // as the kernel's spring model says, and the pull point goes further
        i.feedback(7, DVec3::new(0.0, 0.0, 0.02));
        let mut expected = DragSpring::new(2.0);
        expected.observe(DVec3::new(0.0, 0.0, 0.1), DVec3::new(0.0, 0.0, 0.02));
        assert!(expected.kappa() > 1.0);
        let want = expected.pull_point(DVec3::ZERO, DVec3::new(0.0, 0.0, 0.1));
        let out = run(&mut i, &[pose(DVec3::new(0.0, 0.0, 0.1))]);
        match &out[0] {
            Command::Drag { target, .. } => {
                assert!((*target - want).length() < 1e-12, "{target} vs {want}");
                assert!(target.z > 0.1);
            }
            c => panic!("{c:?}"),
        }
        // a constraint's feedback never changes its target
        let out = run(&mut i, &[hand(0.0, 0.0)]);
        assert_eq!(out, vec![release(7)]);
    }

    #[test]
    fn menu_buttons_and_mouse_axes() {
        let mut i = Interaction::new(&config());
        i.set_icons([
            icon(4, DVec3::ZERO, IconRole::Constraint),
            icon(9, DVec3::ONE, IconRole::Constraint),
        ]);
        let button = |b: u16| Sample {
            source: SourceId(2),
            time: Timestamp(0),
            reading: Reading::Button {
                button: b,
                pressed: true,
            },
        };
        // select icon 4, move to the "load" entry, apply
        let out = run(&mut i, &[button(2), button(0), button(1)]);
        assert_eq!(i.selected(), Some(4));
        assert_eq!(
            out,
            vec![Command::SetRole {
                icon: 4,
                role: IconRole::Load
            }]
        );
        // previous entry twice wraps to "sleeping"
        run(&mut i, &[button(3), button(3)]);
        assert_eq!(i.menu_entry(), MenuEntry::State(IconState::Sleeping));
        // axes: full right for 0.1 s at 0.2 units/s moves the selected icon by 0.02
        let motion = |t: u64, x: f64| Sample {
            source: SourceId(2),
            time: Timestamp(t),
            reading: Reading::Motion {
                translation: DVec3::new(x, 0.0, 0.0),
                rotation: DVec3::ZERO,
            },
        };
        let out = run(&mut i, &[motion(0, 1.0), motion(100_000, 1.0)]);
        let mouse_grab = Command::Grab {
            icon: 4,
            sensor: "mouse".into(),
        };
        assert_eq!(out[0], mouse_grab);
        match out.last() {
            Some(Command::Drag { icon, target }) => {
                assert_eq!(*icon, 4);
                assert!((*target - DVec3::new(0.02, 0.0, 0.0)).length() < 1e-12);
            }
            c => panic!("{c:?}"),
        }
        // the cap back at rest ends the mouse drag
        let out = run(&mut i, &[motion(200_000, 0.0)]);
        assert_eq!(
            out,
            vec![Command::Release {
                icon: 4,
                sensor: "mouse".into()
            }]
        );
    }

    #[test]
    fn restore_regrabs_held_icons_and_lost_devices_release() {
        let mut i = Interaction::new(&config());
        i.set_icons([icon(5, DVec3::ZERO, IconRole::Constraint)]);
        run(
            &mut i,
            &[pose(DVec3::ZERO), hand(1.0, 1.0), pose(DVec3::X * 0.01)],
        );
        let r = i.restore();
        assert_eq!(
            r,
            vec![
                grab(5),
                Command::Drag {
                    icon: 5,
                    target: DVec3::X * 0.01
                }
            ]
        );
        // the glove failing releases the icon
        let mut out = Vec::new();
        i.device_lost(SourceId(1), &mut out);
        assert_eq!(out, vec![release(5)]);
        run(&mut i, &[hand(0.0, 0.0), hand(1.0, 1.0)]);
        assert_eq!(i.bindings().len(), 1);
        // an icon deleted on the server drops the hold
        i.remove_icon(5);
        assert!(i.bindings().is_empty());
        assert!(i.restore().is_empty());
    }
}
