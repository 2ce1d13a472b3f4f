//! The deflated message (kind 7): any other binary message (a geometry
//! frame, a drag basis, a mesh or body frame), byte-shuffled and compressed
//! with DEFLATE (RFC 1951), for clients that ask for it (`/ws?deflate=1`).
//! protocol/README.md, "Deflated message (kind 7)", gives the layout.
//!
//! Why shuffled: a frame is mostly little-endian f32 numbers of a smooth
//! shape. Their high bytes (sign, exponent, top of the mantissa) repeat from
//! one number to the next, their low bytes look random. Grouping byte `j` of
//! every record together (the HDF5/Blosc "shuffle" filter; a record is a
//! control point's 12 bytes x, y, z in a geometry frame, a 4-byte ρ in a
//! drag basis) puts the repeating bytes next to each other, where DEFLATE
//! finds them. Measured on 81 × 159: a smooth surface frame 156.6 → 39 KB
//! (90 KB deflated by 4-byte words, 84 KB unshuffled), the paper scene's
//! drag basis 51.5 → 20 KB (33 KB unshuffled) — losslessly, so the
//! exactness rules of every wrapped kind still hold. DEFLATE because every
//! browser inflates it natively (`DecompressionStream('deflate-raw')`).
//!
//! Decoding never trusts the stated length: inflation stops one byte past
//! it, so a small message that inflates without end (a "zip bomb") costs at
//! most [`MAX_INFLATED_BYTES`] and is refused.

use crate::drag_frame::{BASIS_HEADER_BYTES, KIND_DRAG_BASIS};
use crate::error::{ErrorCode, ProtocolError};
use crate::frame::{HEADER_BYTES, KIND_CURVE, KIND_SURFACE, Layout, MAGIC};
use crate::version::PROTOCOL_VERSION;
use flate2::Compression;
use flate2::read::DeflateDecoder;
use flate2::write::DeflateEncoder;
use std::io::{Read, Write};

/// Frame kind: a deflated message.
pub const KIND_DEFLATED: u8 = 7;
/// Size of a deflated message's header in bytes (the DEFLATE data follows).
pub const DEFLATED_HEADER_BYTES: usize = 16;
/// Largest inner message a deflated message may stand for, in bytes.
pub const MAX_INFLATED_BYTES: usize = 64 * 1024 * 1024;
/// Messages shorter than this are sent as they are: their header would eat
/// what DEFLATE saves.
pub const MIN_DEFLATE_BYTES: usize = 1024;

fn bad(message: impl Into<String>) -> ProtocolError {
    ProtocolError::new(ErrorCode::Malformed, message)
}

/// Groups byte `j` of every `word`-byte record together (plane `j` holds
/// byte `j` of records 0, 1, 2, …); the bytes after the last whole record
/// follow as they are.
pub fn shuffle(bytes: &[u8], word: usize) -> Vec<u8> {
    if word <= 1 {
        return bytes.to_vec();
    }
    let words = bytes.len() / word;
    let mut out = vec![0u8; bytes.len()];
    for (i, w) in bytes[..words * word].chunks_exact(word).enumerate() {
        for (j, &b) in w.iter().enumerate() {
            out[j * words + i] = b;
        }
    }
    out[words * word..].copy_from_slice(&bytes[words * word..]);
    out
}

/// The inverse of [`shuffle`].
pub fn unshuffle(bytes: &[u8], word: usize) -> Vec<u8> {
    if word <= 1 {
        return bytes.to_vec();
    }
    let words = bytes.len() / word;
    let mut out = vec![0u8; bytes.len()];
    for (i, w) in out[..words * word].chunks_exact_mut(word).enumerate() {
        for (j, b) in w.iter_mut().enumerate() {
            *b = bytes[j * words + i];
        }
    }
    out[words * word..].copy_from_slice(&bytes[words * word..]);
    out
}

/// Where the records of `inner` start and how long each is: a geometry
/// frame's control points (12 bytes each, after its knots), a drag basis's
/// ρ (4 bytes each, after its header); other kinds are not shuffled.
fn records(inner: &[u8]) -> (usize, usize) {
    let le = crate::frame::Le(inner);
    match inner[4] {
        KIND_SURFACE | KIND_CURVE if inner.len() >= HEADER_BYTES => {
            let (nu, nv) = (le.u32(32) as usize, le.u32(36) as usize);
            let (du, dv) = (inner[40] as usize, inner[41] as usize);
            match Layout::new(inner[4], nu, nv, du, dv, 0) {
                Some(l) if l.points <= inner.len() => (12, l.points),
                _ => (1, 0),
            }
        }
        KIND_DRAG_BASIS => (4, BASIS_HEADER_BYTES),
        _ => (1, 0),
    }
}

/// `inner` (a binary message of another kind) as a deflated message, or
/// `None` when that would not be shorter (small or incompressible
/// messages, and anything that is not a binary message or is too large).
pub fn deflate(inner: &[u8]) -> Option<Vec<u8>> {
    if inner.len() < MIN_DEFLATE_BYTES
        || inner.len() > MAX_INFLATED_BYTES
        || inner[..4] != MAGIC
        || inner[4] == KIND_DEFLATED
    {
        return None;
    }
    let (word, start) = records(inner);
    let mut out = Vec::with_capacity(inner.len() / 2);
    out.extend_from_slice(&MAGIC);
    out.push(KIND_DEFLATED);
    out.push(PROTOCOL_VERSION as u8);
    out.push(word as u8);
    out.push(0);
    out.extend_from_slice(&(inner.len() as u32).to_le_bytes());
    out.extend_from_slice(&(start as u32).to_le_bytes());
    // Level 3: within a few per cent of level 9's size on frames at a
    // fraction of its time (one compression per frame, shared by every
    // client that asked).
    let mut enc = DeflateEncoder::new(out, Compression::new(3));
    enc.write_all(&inner[..start]).ok()?;
    enc.write_all(&shuffle(&inner[start..], word)).ok()?;
    let out = enc.finish().ok()?;
    (out.len() < inner.len()).then_some(out)
}

/// The inner message of a deflated message. Any byte string gives the inner
/// message (not itself deflated, of the stated length, starting with the
/// frame magic) or an error; never a panic, never more than
/// [`MAX_INFLATED_BYTES`] allocated.
pub fn inflate(bytes: &[u8]) -> Result<Vec<u8>, ProtocolError> {
    crate::frame::check_header(
        bytes,
        KIND_DEFLATED,
        DEFLATED_HEADER_BYTES,
        "deflated message",
    )?;
    let word = bytes[6];
    if !(1..=12).contains(&word) {
        return Err(bad(format!(
            "deflated message: record length {word} is not 1 to 12"
        )));
    }
    if bytes[7] != 0 {
        return Err(bad(
            "a deflated message's zero byte (offset 7) must be zero",
        ));
    }
    let len = u32::from_le_bytes(bytes[8..12].try_into().unwrap_or([0; 4])) as usize;
    let start = u32::from_le_bytes(bytes[12..16].try_into().unwrap_or([0; 4])) as usize;
    if len > MAX_INFLATED_BYTES {
        return Err(ProtocolError::new(
            ErrorCode::TooLarge,
            format!("deflated message stands for {len} bytes, more than {MAX_INFLATED_BYTES}"),
        ));
    }
    let mut shuffled = Vec::with_capacity(len);
    DeflateDecoder::new(&bytes[DEFLATED_HEADER_BYTES..])
        .take(len as u64 + 1)
        .read_to_end(&mut shuffled)
        .map_err(|e| bad(format!("deflated message: {e}")))?;
    if shuffled.len() != len {
        return Err(bad(format!(
            "deflated message inflates to {}{} bytes, its header says {len}",
            shuffled.len(),
            if shuffled.len() > len { " or more" } else { "" }
        )));
    }
    if start > len {
        return Err(bad(format!(
            "deflated message: its records start at {start}, past its length {len}"
        )));
    }
    let mut inner = shuffled[..start].to_vec();
    inner.extend(unshuffle(&shuffled[start..], word as usize));
    if inner.len() < 8 || inner[..4] != MAGIC {
        return Err(bad("a deflated message's inner message has no frame magic"));
    }
    if inner[4] == KIND_DEFLATED {
        return Err(bad("a deflated message may not hold another"));
    }
    Ok(inner)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shuffle_puts_byte_j_of_every_word_in_plane_j() {
        let b: Vec<u8> = (0..11).collect();
        assert_eq!(shuffle(&b, 4), vec![0, 4, 1, 5, 2, 6, 3, 7, 8, 9, 10]);
        assert_eq!(unshuffle(&shuffle(&b, 4), 4), b);
        assert_eq!(shuffle(&b, 1), b);
    }
}
