//! The per-client send rate (`/ws?pace=1`): a client that asks for it
//! reports, in `received` messages, how many bytes of binary messages it
//! has received; its writer then keeps the bytes *in flight* (sent, not yet
//! reported) within a window sized from what that client's link was
//! measured to carry. Geometry that does not fit waits, and latest-wins
//! replaces it meanwhile, so a viewer on a slow link gets fewer frames, each
//! complete and recent, instead of a queue that grows in the link (a real
//! link buffers seconds of data before TCP pushes back); a fast one gets
//! every frame, and no other client or the design waits for either.
//!
//! The window is the one of BBR (Cardwell et al., ACM Queue 2016): a
//! delivery-rate sample per report, `(reported now − reported when the
//! message left) / (now − the time of that report)`, taken from the message
//! the report completes; a windowed maximum of those samples times the
//! minimum round trip seen is the link's bandwidth-delay product, and the
//! window is twice that (so a link that could carry more shows it in the
//! next samples), never below [`FLOOR`]. A message is sent whenever the
//! bytes in flight are within the window, whatever its own size, so a frame
//! larger than the window still goes out, alone.
//!
//! Times are arguments, so the arithmetic is tested without sleeping.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// The smallest window, bytes: what a client may have in flight before
/// anything is measured. 32 KiB is 131 ms of a 2 Mbit/s link.
pub const FLOOR: u64 = 32 * 1024;

/// The window's gain over the measured bandwidth-delay product.
pub const GAIN: f64 = 2.0;

/// How long a delivery-rate sample counts towards the maximum.
pub const RATE_MEMORY: Duration = Duration::from_secs(4);

/// How long a round-trip sample counts towards the minimum.
pub const RTT_MEMORY: Duration = Duration::from_secs(10);

/// A binary message not yet reported whole.
#[derive(Clone, Copy, Debug)]
struct Flight {
    /// The byte count sent once this message is out.
    end: u64,
    /// When it was sent.
    sent_at: Instant,
    /// The bytes reported when it was sent.
    reported: u64,
    /// The time of that report (or the send time, if nothing was in
    /// flight: idle time is not link time).
    reported_at: Instant,
}

/// One client's send-rate state: what was sent, what it reported, and the
/// link's measured rate and round trip.
#[derive(Clone, Debug)]
pub struct Pacer {
    sent: u64,
    reported: u64,
    reported_at: Instant,
    flights: VecDeque<Flight>,
    /// (when, bytes a second).
    rates: VecDeque<(Instant, f64)>,
    /// (when, round trip).
    rtts: VecDeque<(Instant, Duration)>,
}

impl Pacer {
    /// Nothing sent yet.
    pub fn new(now: Instant) -> Self {
        Self {
            sent: 0,
            reported: 0,
            reported_at: now,
            flights: VecDeque::new(),
            rates: VecDeque::new(),
            rtts: VecDeque::new(),
        }
    }

    /// Bytes sent and not yet reported received.
    pub fn in_flight(&self) -> u64 {
        self.sent - self.reported
    }

    /// Total bytes of binary messages sent.
    pub fn sent(&self) -> u64 {
        self.sent
    }

    /// A binary message of `len` bytes was sent at `now`.
    pub fn on_sent(&mut self, len: usize, now: Instant) {
        if len == 0 {
            return;
        }
        let idle = self.in_flight() == 0;
        self.sent += len as u64;
        self.flights.push_back(Flight {
            end: self.sent,
            sent_at: now,
            reported: self.reported,
            reported_at: if idle { now } else { self.reported_at },
        });
    }

    /// The client reported `total` bytes received at `now`. A report that
    /// does not advance is ignored, and one beyond what was sent counts as
    /// everything sent (a client cannot widen its own window).
    pub fn on_report(&mut self, total: u64, now: Instant) {
        let total = total.min(self.sent);
        if total <= self.reported {
            return;
        }
        self.reported = total;
        self.reported_at = now;
        let mut done = None;
        while let Some(f) = self.flights.front() {
            if f.end > total {
                break;
            }
            done = self.flights.pop_front();
        }
        let Some(f) = done else { return };
        let rtt = now.saturating_duration_since(f.sent_at);
        self.rtts.push_back((now, rtt));
        let span = now.saturating_duration_since(f.reported_at).as_secs_f64();
        if span > 0.0 {
            self.rates
                .push_back((now, (total - f.reported) as f64 / span));
        }
        forget(&mut self.rates, now, RATE_MEMORY);
        forget(&mut self.rtts, now, RTT_MEMORY);
    }

    /// The highest delivery rate measured lately, bytes a second.
    pub fn rate(&self) -> Option<f64> {
        self.rates.iter().map(|r| r.1).reduce(f64::max)
    }

    /// The shortest round trip measured lately.
    pub fn min_rtt(&self) -> Option<Duration> {
        self.rtts.iter().map(|r| r.1).min()
    }

    /// The bytes that may be in flight: twice the measured bandwidth-delay
    /// product, at least [`FLOOR`].
    pub fn window(&self) -> u64 {
        match (self.rate(), self.min_rtt()) {
            (Some(rate), Some(rtt)) => {
                let bdp = GAIN * rate * rtt.as_secs_f64();
                (bdp as u64).max(FLOOR)
            }
            _ => FLOOR,
        }
    }

    /// Whether a message may be sent now.
    pub fn open(&self) -> bool {
        self.in_flight() <= self.window()
    }
}

/// Drops samples older than `memory`, keeping the newest one whatever its age
/// (an idle link keeps what it last measured).
fn forget<T>(samples: &mut VecDeque<(Instant, T)>, now: Instant, memory: Duration) {
    while samples.len() > 1
        && samples
            .front()
            .is_some_and(|s| now.saturating_duration_since(s.0) > memory)
    {
        samples.pop_front();
    }
}
