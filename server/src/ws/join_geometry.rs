//! The compact join's geometry and the name of it that a browser keeps.
//!
//! A `geometry_first` join sends every part's current frame, flagged as the
//! snapshot's shape, before the snapshot. The SHA-256 of exactly those frames
//! (inflated, in the order sent, each preceded by its length) names them in
//! the `welcome`; a browser that kept the frames of an earlier visit under
//! that name offers it in its next hello (`cached_geometry`), and when it
//! still names the frames the join would send, they are not sent again.
//! Any change to any part's frame — a commit, a drag, another client's edit,
//! an added or removed part — changes the hash, and a stale or forged name
//! matches nothing, so such a client gets the frames as before.

use std::collections::BTreeMap;

use axum::body::Bytes;
use ring::digest;

use crate::design::Joined;

/// The frames of one compact join and the hash that names them.
#[derive(Debug)]
pub struct JoinGeometry {
    /// SHA-256 of the frames, lower-case hex (the `welcome`'s `geometry`).
    pub hash: String,
    /// The messages to send: each part's flagged frame, deflated when the
    /// client asked and it pays (the same frames the hash names, inflated).
    pub messages: Vec<Bytes>,
}

/// Every part's current frame flagged as the snapshot's shape, and its hash;
/// records each part's revision in `sent` (the client holds it once these
/// frames are sent, or when it kept the very frames the hash names).
pub fn join_geometry(
    joined: &mut Joined,
    sent: &mut BTreeMap<u64, u64>,
    deflate: bool,
) -> JoinGeometry {
    let set = joined.geometry.borrow_and_update().clone();
    let mut flagged = Vec::with_capacity(set.parts.len());
    let mut messages = Vec::with_capacity(set.parts.len());
    for (part, g) in &set.parts {
        sent.insert(*part, g.rev);
        let frame = Bytes::from(vsculpt_protocol::frame::with_flags(
            &g.frame,
            vsculpt_protocol::frame::FLAG_SNAPSHOT,
        ));
        messages.push(g.snapshot_deflated.pick(&frame, deflate));
        flagged.push(frame);
    }
    JoinGeometry {
        hash: geometry_hash(flagged.iter().map(|f| f.as_ref())),
        messages,
    }
}

/// SHA-256, lower-case hex, of `frames` in order, each preceded by its length
/// as a little-endian u32 (so no two different lists of frames share an input).
pub fn geometry_hash<'a>(frames: impl IntoIterator<Item = &'a [u8]>) -> String {
    let mut ctx = digest::Context::new(&digest::SHA256);
    for f in frames {
        ctx.update(&(f.len() as u32).to_le_bytes());
        ctx.update(f);
    }
    ctx.finish()
        .as_ref()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::geometry_hash;

    #[test]
    fn the_hash_is_sha256_of_the_length_prefixed_frames() {
        // Expected values from Python's hashlib over the hand-built inputs.
        assert_eq!(
            geometry_hash(std::iter::empty()),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
        );
        // 03 00 00 00 'a' 'b' 'c'
        assert_eq!(
            geometry_hash([b"abc".as_slice()]),
            "3da9865b43fa2ec490f78da9db16acd5638704dbce5cc7b3df2e3c7a23addf19"
        );
        // 02 00 00 00 'a' 'b' 01 00 00 00 'c': the same bytes split differently.
        assert_eq!(
            geometry_hash([b"ab".as_slice(), b"c"]),
            "60014a36d7b05b0730e42a8b96faa1ffb4bd28469aea4000191179f01561ddb7"
        );
    }
}
