//! The hand-off from the device threads to the interaction: a queue that keeps
//! every input in arrival order but wakes the interaction's task only when an
//! input may change what is sent.
//!
//! A 1 kHz tracker delivers a record every millisecond, yet drags leave at
//! `rates.drag_hz` and hand samples at presence rate: most records only update
//! the hand and its gate. Waking the async task for each (a futex wake and a
//! park of a runtime worker, twice a millisecond across threads) was most of the
//! bridge's CPU. Now a device thread appends its samples to the queue and wakes
//! the task only when they are *urgent*: anything but a tracker pose (a glove
//! gesture, a button, the 3D mouse, a status change), or a pose at or after the
//! moment the interaction said something falls due ([`Inbox::set_due`], from
//! [`crate::interaction::Interaction::next_due`]). The task takes the whole queue
//! at each wake-up and at its drag-rate tick, so a quiet record waits at most one
//! drag period, and the interaction sees exactly the inputs, in exactly the order,
//! it saw before: the commands are the same, only the wake-ups are fewer.

use crate::bridge::Input;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use tokio::sync::Notify;

struct Shared {
    queue: Mutex<Vec<Input>>,
    notify: Notify,
    senders: AtomicUsize,
    /// Sample time (µs) from which a tracker pose is urgent.
    due: AtomicU64,
    /// The receiver is gone.
    closed: std::sync::atomic::AtomicBool,
}

/// The sending side (one per device thread; clone for more).
pub struct InboxSender(Arc<Shared>);

/// The receiving side (the interaction's task).
pub struct InboxReceiver(Arc<Shared>);

/// A new inbox.
pub fn inbox() -> (InboxSender, InboxReceiver) {
    let shared = Arc::new(Shared {
        queue: Mutex::new(Vec::new()),
        notify: Notify::new(),
        senders: AtomicUsize::new(1),
        due: AtomicU64::new(0),
        closed: std::sync::atomic::AtomicBool::new(false),
    });
    (InboxSender(shared.clone()), InboxReceiver(shared))
}

impl InboxSender {
    /// Queues `input`; wakes the receiver when `urgent`. False when the receiver
    /// is gone.
    pub fn push(&self, input: Input, urgent: bool) -> bool {
        if self.0.closed.load(Ordering::Acquire) {
            return false;
        }
        self.0
            .queue
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(input);
        if urgent {
            self.0.notify.notify_one();
        }
        true
    }

    /// The sample time (µs) from which a tracker pose is urgent.
    pub fn due(&self) -> u64 {
        self.0.due.load(Ordering::Relaxed)
    }
}

impl Clone for InboxSender {
    fn clone(&self) -> Self {
        self.0.senders.fetch_add(1, Ordering::AcqRel);
        Self(self.0.clone())
    }
}

impl Drop for InboxSender {
    fn drop(&mut self) {
        if self.0.senders.fetch_sub(1, Ordering::AcqRel) == 1 {
            // The last sender: the receiver must see the end.
            self.0.notify.notify_one();
        }
    }
}

impl InboxReceiver {
    /// Waits until an urgent input (or the last sender's end) was signalled.
    pub async fn wait(&self) {
        self.0.notify.notified().await;
    }

    /// Moves every queued input to `out`, in arrival order; true when every
    /// sender is gone and nothing is left (the inputs have ended).
    pub fn drain(&self, out: &mut Vec<Input>) -> bool {
        // Read the count before taking the queue: a sender that pushes and then
        // drops is either seen alive (and its input comes next time) or gone with
        // its input already queued.
        let ended = self.0.senders.load(Ordering::Acquire) == 0;
        out.append(&mut self.0.queue.lock().unwrap_or_else(|e| e.into_inner()));
        ended
    }

    /// Sets the sample time (µs) from which a tracker pose is urgent.
    pub fn set_due(&self, due: u64) {
        self.0.due.store(due, Ordering::Relaxed);
    }
}

impl Drop for InboxReceiver {
    fn drop(&mut self) {
        self.0.closed.store(true, Ordering::Release);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::SourceId;
    use crate::device::runner::DeviceStatus;
    use std::time::Duration;

    fn status(n: u16) -> Input {
        Input::Status(SourceId(n), DeviceStatus::Open)
    }

    #[tokio::test]
    async fn keeps_order_wakes_only_when_urgent_and_ends_with_its_senders() {
        let (tx, rx) = inbox();
        let tx2 = tx.clone();
        assert!(tx.push(status(1), false));
        assert!(tx2.push(status(2), false));
        // nothing urgent: no wake-up
        let woke = tokio::time::timeout(Duration::from_millis(50), rx.wait()).await;
        assert!(woke.is_err());
        assert!(tx.push(status(3), true));
        rx.wait().await;
        let mut got = Vec::new();
        assert!(!rx.drain(&mut got));
        assert_eq!(got, vec![status(1), status(2), status(3)]);
        rx.set_due(42);
        assert_eq!(tx2.due(), 42);
        // the senders go: the end is signalled and seen once the queue is empty
        tx2.push(status(4), false);
        drop(tx);
        drop(tx2);
        rx.wait().await;
        got.clear();
        assert!(rx.drain(&mut got));
        assert_eq!(got, vec![status(4)]);
        // a receiver gone refuses further inputs
        let (tx, rx) = inbox();
        drop(rx);
        assert!(!tx.push(status(5), true));
    }
}
