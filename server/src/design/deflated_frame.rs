//! The deflated form of a binary message (protocol kind 7, `/ws?deflate=1`),
//! made at most once per message: the first writer whose client asked for
//! it compresses, every other writer of the design reuses the bytes. A
//! message DEFLATE cannot shrink (small, or incompressible) goes as it is.

use axum::body::Bytes;
use std::sync::OnceLock;
use vsculpt_protocol::deflated;

/// The deflated bytes of one message, once made.
#[derive(Clone, Debug, Default)]
pub struct DeflatedFrame(OnceLock<Option<Bytes>>);

impl DeflatedFrame {
    /// What to send a client for the message `raw`: its deflated form when
    /// the client asked for it (`deflate`) and that form is shorter, else
    /// `raw`.
    pub fn pick(&self, raw: &Bytes, deflate: bool) -> Bytes {
        if !deflate {
            return raw.clone();
        }
        self.0
            .get_or_init(|| deflated::deflate(raw).map(Bytes::from))
            .clone()
            .unwrap_or_else(|| raw.clone())
    }
}
