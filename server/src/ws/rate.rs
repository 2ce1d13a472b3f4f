//! Per-connection rate limits on `/ws` messages: token buckets refilled at a
//! steady rate up to a burst. Control messages (edits, queries, pings) and
//! stream messages (`drag`, `device_sample`, `presence`, which a device or
//! a pointer sends every frame, and a paced client's `received`) have separate buckets, the stream one far
//! larger; a message over its bucket is dropped and answered
//! `rate_limited`, and those answers have their own bucket so a flood
//! cannot turn into a flood of errors. Nothing here closes a connection.
//!
//! A token bucket is a few lines of arithmetic on an [`Instant`]; taking
//! the time as an argument keeps it testable without sleeping.

use std::time::Instant;
use vsculpt_protocol::limits::{
    CONTROL_BURST, CONTROL_RATE, RATE_LIMITED_ERRORS_PER_SEC, STREAM_BURST, STREAM_RATE,
};

/// A token bucket: `burst` tokens at most, refilled at `per_sec`.
#[derive(Clone, Debug)]
pub struct TokenBucket {
    per_sec: f64,
    burst: f64,
    tokens: f64,
    last: Instant,
}

impl TokenBucket {
    /// A full bucket.
    pub fn new(per_sec: u32, burst: u32, now: Instant) -> Self {
        Self {
            per_sec: f64::from(per_sec),
            burst: f64::from(burst.max(1)),
            tokens: f64::from(burst.max(1)),
            last: now,
        }
    }

    /// Takes one token if there is one (refilling first for the time since
    /// the last call); `false` when the bucket is empty.
    pub fn take(&mut self, now: Instant) -> bool {
        let dt = now.saturating_duration_since(self.last).as_secs_f64();
        self.last = now;
        self.tokens = (self.tokens + dt * self.per_sec).min(self.burst);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }
}

/// Which bucket a message draws from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// Edits, queries, pings and anything undecodable.
    Control,
    /// Drag frames, device samples and pointer presence.
    Stream,
}

/// What to do with a message after [`RateLimiter::admit`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Within the limit: handle it.
    Admit,
    /// Over the limit: drop it and answer `rate_limited`.
    Refuse,
    /// Over the limit and over the error budget: drop it silently.
    Drop,
}

/// The buckets of one connection.
#[derive(Clone, Debug)]
pub struct RateLimiter {
    control: TokenBucket,
    stream: TokenBucket,
    errors: TokenBucket,
    refused: u64,
}

impl RateLimiter {
    /// The documented limits of `vsculpt_protocol::limits`.
    pub fn new(now: Instant) -> Self {
        Self {
            control: TokenBucket::new(CONTROL_RATE, CONTROL_BURST, now),
            stream: TokenBucket::new(STREAM_RATE, STREAM_BURST, now),
            errors: TokenBucket::new(
                RATE_LIMITED_ERRORS_PER_SEC,
                RATE_LIMITED_ERRORS_PER_SEC,
                now,
            ),
            refused: 0,
        }
    }

    /// Charges one message of `class`.
    pub fn admit(&mut self, class: Class, now: Instant) -> Verdict {
        let bucket = match class {
            Class::Control => &mut self.control,
            Class::Stream => &mut self.stream,
        };
        if bucket.take(now) {
            return Verdict::Admit;
        }
        self.refused += 1;
        if self.errors.take(now) {
            Verdict::Refuse
        } else {
            Verdict::Drop
        }
    }

    /// Messages refused so far on this connection.
    pub fn refused(&self) -> u64 {
        self.refused
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_bucket_gives_its_burst_then_its_rate() {
        let t0 = Instant::now();
        let mut b = TokenBucket::new(100, 200, t0);
        assert_eq!((0..300).filter(|_| b.take(t0)).count(), 200);
        // 50 ms later: 5 tokens.
        let t1 = t0 + Duration::from_millis(50);
        assert_eq!((0..20).filter(|_| b.take(t1)).count(), 5);
        // A long pause refills to the burst, not beyond.
        let t2 = t1 + Duration::from_secs(60);
        assert_eq!((0..1000).filter(|_| b.take(t2)).count(), 200);
    }

    #[test]
    fn a_steady_sender_at_the_rate_is_never_refused() {
        let t0 = Instant::now();
        let mut b = TokenBucket::new(100, 200, t0);
        for k in 1..=10_000u64 {
            assert!(b.take(t0 + Duration::from_millis(10 * k)), "message {k}");
        }
    }

    #[test]
    fn stream_messages_do_not_spend_the_control_budget() {
        let t0 = Instant::now();
        let mut r = RateLimiter::new(t0);
        for _ in 0..STREAM_BURST {
            assert_eq!(r.admit(Class::Stream, t0), Verdict::Admit);
        }
        assert_ne!(r.admit(Class::Stream, t0), Verdict::Admit);
        for _ in 0..CONTROL_BURST {
            assert_eq!(r.admit(Class::Control, t0), Verdict::Admit);
        }
    }

    #[test]
    fn refusals_are_answered_within_the_error_budget_then_dropped() {
        let t0 = Instant::now();
        let mut r = RateLimiter::new(t0);
        for _ in 0..CONTROL_BURST {
            r.admit(Class::Control, t0);
        }
        let verdicts: Vec<Verdict> = (0..100).map(|_| r.admit(Class::Control, t0)).collect();
        let answered = verdicts.iter().filter(|v| **v == Verdict::Refuse).count();
        assert_eq!(answered, RATE_LIMITED_ERRORS_PER_SEC as usize);
        assert!(verdicts[answered..].iter().all(|v| *v == Verdict::Drop));
        assert_eq!(r.refused(), 100);
        // A second later the client is welcome again.
        let t1 = t0 + Duration::from_secs(1);
        assert_eq!(r.admit(Class::Control, t1), Verdict::Admit);
    }
}
