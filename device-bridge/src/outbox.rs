//! The queue of commands waiting for the server link: ordered for discrete
//! commands (bind, state changes), latest-wins for continuous ones (drag, load),
//! so a slow link skips stale drag targets instead of falling behind.
//!
//! Continuous commands are coalesced per subject (an icon's drag, a hand's sample).
//! Order is kept where it matters: a discrete command about an icon first flushes
//! that icon's pending drag, so "drag then release" never arrives reversed.
//!
//! A replay's outbox is [in order](Outbox::in_order): nothing is coalesced, every
//! command leaves in order, and it counts the answers the server owes, so the
//! replay can wait for them (delivery pace must not change what the server does).

use crate::interaction::{Command, Subject};
use std::collections::{BTreeMap, VecDeque};

/// Pending commands.
#[derive(Debug, Default)]
pub struct Outbox {
    ordered: VecDeque<Command>,
    latest: BTreeMap<Subject, Command>,
    coalesced: u64,
    in_order: bool,
    /// Answers owed for commands queued so far (cumulative).
    owed: u64,
    /// Answers received so far (cumulative).
    answered: u64,
}

impl Outbox {
    /// An empty outbox.
    pub fn new() -> Self {
        Self::default()
    }

    /// An outbox that keeps every command, in order (a replay).
    pub fn in_order() -> Self {
        Self {
            in_order: true,
            ..Self::default()
        }
    }

    /// True for an [in-order](Outbox::in_order) outbox.
    pub fn is_in_order(&self) -> bool {
        self.in_order
    }

    /// Queues `cmd`.
    pub fn push(&mut self, cmd: Command) {
        let subject = cmd.subject();
        if self.in_order {
            self.ordered.push_back(cmd);
        } else if cmd.is_continuous() {
            if self.latest.insert(subject, cmd).is_some() {
                self.coalesced += 1;
            }
        } else {
            if let Some(pending) = self.latest.remove(&subject) {
                self.ordered.push_back(pending);
            }
            self.ordered.push_back(cmd);
        }
    }

    /// Takes everything due, in sending order, each with `true` when it must stay
    /// in order with its neighbours (discrete commands, and a drag flushed ahead
    /// of a discrete command about the same icon) and `false` for coalesced ones.
    pub fn drain(&mut self) -> Vec<(Command, bool)> {
        let mut v: Vec<(Command, bool)> = self.ordered.drain(..).map(|c| (c, true)).collect();
        v.extend(
            std::mem::take(&mut self.latest)
                .into_values()
                .map(|c| (c, false)),
        );
        v
    }

    /// Drops everything (a new connection restores state from scratch); the
    /// answers the old connection owed are written off.
    pub fn clear(&mut self) {
        self.ordered.clear();
        self.latest.clear();
        self.answered = self.owed;
    }

    /// Counts `n` more answers owed (for commands just queued); returns the
    /// total owed, the answer count at which they are all in.
    pub fn owe(&mut self, n: u64) -> u64 {
        self.owed += n;
        self.owed
    }

    /// One answer came; returns the total received.
    pub fn answer(&mut self) -> u64 {
        self.answered = (self.answered + 1).min(self.owed);
        self.answered
    }

    /// True when nothing is pending.
    pub fn is_empty(&self) -> bool {
        self.ordered.is_empty() && self.latest.is_empty()
    }

    /// Continuous commands replaced by a newer one before they were sent.
    pub fn coalesced(&self) -> u64 {
        self.coalesced
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interaction::{IconId, IconState};
    use glam::DVec3;

    fn drag(icon: IconId, x: f64) -> Command {
        Command::Drag {
            icon,
            target: DVec3::X * x,
        }
    }

    #[test]
    fn latest_wins_per_icon_and_order_is_kept_around_discrete_commands() {
        let mut o = Outbox::new();
        o.push(drag(1, 1.0));
        o.push(drag(2, 1.0));
        o.push(drag(1, 2.0));
        o.push(drag(1, 3.0));
        assert_eq!(o.coalesced(), 2);
        let release = Command::Release {
            icon: 1,
            sensor: "right".into(),
        };
        o.push(release.clone());
        o.push(drag(2, 5.0));
        let v = o.drain();
        assert_eq!(
            v,
            vec![(drag(1, 3.0), true), (release, true), (drag(2, 5.0), false)]
        );
        assert!(o.is_empty());
        o.push(Command::SetState {
            icon: 3,
            state: IconState::Passive,
        });
        o.clear();
        assert!(o.drain().is_empty());
    }

    #[test]
    fn in_order_keeps_every_drag_in_sending_order_and_counts_answers() {
        let mut o = Outbox::in_order();
        o.push(drag(1, 1.0));
        o.push(drag(2, 1.0));
        o.push(drag(1, 2.0));
        assert_eq!(o.coalesced(), 0);
        assert_eq!(
            o.drain(),
            vec![
                (drag(1, 1.0), true),
                (drag(2, 1.0), true),
                (drag(1, 2.0), true)
            ]
        );
        assert_eq!(o.owe(3), 3);
        assert_eq!(o.answer(), 1);
        assert_eq!(o.owe(1), 4);
        o.clear();
        // a lost connection's answers never come: written off
        assert_eq!(o.owe(1), 5);
        assert_eq!(o.answer(), 5);
    }
}
