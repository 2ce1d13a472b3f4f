//! The deflated message (kind 7) against its README layout: messages built
//! here by hand — the header written byte by byte, the shuffle done by index
//! arithmetic, the DEFLATE data a stored block laid out as RFC 1951 §3.2.4
//! says — inflate to their inner message; the server's own compression
//! round-trips real frames losslessly and shrinks them; hostile inputs
//! (an inflation bomb, a lying length, truncation, nesting, garbage) are
//! refused without a panic.

use proptest::prelude::*;
use vsculpt_protocol::deflated::{self, KIND_DEFLATED, MAX_INFLATED_BYTES};
use vsculpt_protocol::drag_frame::DragBasis;
use vsculpt_protocol::error::ErrorCode;
use vsculpt_protocol::frame::{GeometryFrame, KIND_SURFACE};

/// The README's header: magic, kind 7, version 2, record length, zero,
/// inner length, where the records start.
fn header(word: u8, inner_len: u32, start: u32) -> Vec<u8> {
    let mut h = b"VSGF".to_vec();
    h.extend_from_slice(&[7, 2, word, 0]);
    h.extend_from_slice(&inner_len.to_le_bytes());
    h.extend_from_slice(&start.to_le_bytes());
    h
}

/// One final stored DEFLATE block (RFC 1951 §3.2.4): the byte 0x01 (BFINAL
/// = 1, BTYPE = 00, padding), LEN and its one's complement NLEN, the bytes.
fn stored_block(data: &[u8]) -> Vec<u8> {
    assert!(data.len() <= 0xffff);
    let len = data.len() as u16;
    let mut out = vec![0x01];
    out.extend_from_slice(&len.to_le_bytes());
    out.extend_from_slice(&(!len).to_le_bytes());
    out.extend_from_slice(data);
    out
}

/// The bytes before `start` as they are, then plane j = byte j of every
/// `word`-byte record, then the tail (README).
fn planes(inner: &[u8], word: usize, start: usize) -> Vec<u8> {
    let records = (inner.len() - start) / word;
    let mut out = inner[..start].to_vec();
    for j in 0..word {
        for i in 0..records {
            out.push(inner[start + word * i + j]);
        }
    }
    out.extend_from_slice(&inner[start + word * records..]);
    out
}

/// A smooth 81 × 159 cubic surface frame, as the server sends it.
fn surface_frame() -> Vec<u8> {
    let (nu, nv) = (81usize, 159usize);
    let knots = |n: usize| {
        let spans = n - 3;
        let mut k = vec![0.0; 4];
        k.extend((1..spans).map(|i| i as f64 / spans as f64));
        k.extend([1.0; 4]);
        k
    };
    let mut points = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (x, y) = (i as f32 * 0.1, j as f32 * 0.1);
            points.push([x, y, 1.6 * (x * 0.39).sin() * (y * 0.2).sin()]);
        }
    }
    GeometryFrame {
        kind: KIND_SURFACE,
        design: 1,
        part: 1,
        revision: 7,
        flags: 0,
        degree_u: 3,
        degree_v: 3,
        nu: nu as u32,
        nv: nv as u32,
        knots_u: knots(nu),
        knots_v: knots(nv),
        points,
        icons: Vec::new(),
    }
    .encode()
    .unwrap()
}

#[test]
fn a_hand_made_stored_block_message_inflates_to_its_inner_message() {
    let inner = DragBasis {
        design: 3,
        part: 4,
        basis: 5,
        reference: 6,
        rho: (0..1001).map(|k| (k as f32 * 0.01).cos()).collect(),
    }
    .encode()
    .unwrap();
    let mut msg = header(4, inner.len() as u32, 48);
    msg.extend(stored_block(&planes(&inner, 4, 48)));
    assert_eq!(deflated::inflate(&msg).unwrap(), inner);
    // Any record length and start: 12-byte records from byte 8 (the header's
    // tail moves around; the magic stays in front).
    let mut msg = header(12, inner.len() as u32, 8);
    msg.extend(stored_block(&planes(&inner, 12, 8)));
    assert_eq!(deflated::inflate(&msg).unwrap(), inner);
    // Record length 1: no shuffle.
    let mut msg = header(1, inner.len() as u32, 0);
    msg.extend(stored_block(&inner));
    assert_eq!(deflated::inflate(&msg).unwrap(), inner);
    // Bytes not shuffled as the header says are not the message.
    let mut msg = header(4, inner.len() as u32, 48);
    msg.extend(stored_block(&inner));
    assert_ne!(deflated::inflate(&msg).unwrap(), inner);
}

#[test]
fn frames_round_trip_exactly_and_shrink() {
    let frame = surface_frame();
    let small = deflated::deflate(&frame).expect("a smooth surface frame compresses");
    eprintln!(
        "81 × 159 surface frame: {} → {} bytes",
        frame.len(),
        small.len()
    );
    // Records: the control points, 12 bytes each, after the header (48)
    // and the 85 + 163 knots.
    assert_eq!(
        &small[..8],
        &[b'V', b'S', b'G', b'F', KIND_DEFLATED, 2, 12, 0]
    );
    let u32_at = |o: usize| u32::from_le_bytes(small[o..o + 4].try_into().unwrap()) as usize;
    assert_eq!(u32_at(8), frame.len());
    assert_eq!(u32_at(12), 48 + 8 * (85 + 163));
    assert_eq!(deflated::inflate(&small).unwrap(), frame);
    assert!(
        small.len() * 3 < frame.len(),
        "{} → {} bytes",
        frame.len(),
        small.len()
    );
    // Short messages and messages that are not frames stay as they are.
    assert!(deflated::deflate(&frame[..500]).is_none());
    assert!(deflated::deflate(&vec![b'x'; 5000]).is_none());
    // A deflated message is never deflated again.
    let mut again = small.clone();
    again.resize(4096, 0);
    assert!(deflated::deflate(&again).is_none());
}

#[test]
fn an_inflation_bomb_is_refused_after_one_byte_more_than_it_claims() {
    use flate2::Compression;
    use flate2::write::DeflateEncoder;
    use std::io::Write;
    // 16 MiB of zeros deflate to ~16 KB; the header claims 4 KiB.
    let mut enc = DeflateEncoder::new(Vec::new(), Compression::best());
    let mut inner = b"VSGF\x01\x02".to_vec();
    inner.resize(16 << 20, 0);
    enc.write_all(&inner).unwrap();
    let data = enc.finish().unwrap();
    let mut msg = header(1, 4096, 0);
    msg.extend(&data);
    let e = deflated::inflate(&msg).unwrap_err();
    assert_eq!(e.code, ErrorCode::Malformed);
    assert!(e.message.contains("4097 or more"), "{}", e.message);
    // A stated length over the limit is refused before inflating.
    let mut msg = header(1, (MAX_INFLATED_BYTES + 1) as u32, 0);
    msg.extend(&data);
    assert_eq!(
        deflated::inflate(&msg).unwrap_err().code,
        ErrorCode::TooLarge
    );
}

#[test]
fn lies_truncation_nesting_and_bad_headers_are_refused() {
    let frame = surface_frame();
    let good = deflated::deflate(&frame).unwrap();
    // The inner length says one byte less / more than the data holds.
    for delta in [-1i64, 1] {
        let mut m = good.clone();
        let len = (frame.len() as i64 + delta) as u32;
        m[8..12].copy_from_slice(&len.to_le_bytes());
        assert!(deflated::inflate(&m).is_err(), "length off by {delta}");
    }
    // Truncated DEFLATE data.
    assert!(deflated::inflate(&good[..good.len() - 10]).is_err());
    // A nonzero zero byte, a bad record length, a bad version, records
    // starting past the end.
    for (at, v) in [(7usize, 1u8), (6, 0), (6, 13), (5, 3), (15, 1)] {
        let mut m = good.clone();
        m[at] = v;
        assert!(deflated::inflate(&m).is_err(), "byte {at} = {v}");
    }
    // A deflated message inside another.
    let mut m = header(1, good.len() as u32, 0);
    m.extend(stored_block(&good));
    assert!(deflated::inflate(&m).is_err());
    // An inner message without the frame magic.
    let mut m = header(1, 2000, 0);
    m.extend(stored_block(&[0x55; 2000]));
    assert!(deflated::inflate(&m).is_err());
}

proptest! {
    #[test]
    fn any_bytes_give_a_message_or_an_error(tail in proptest::collection::vec(any::<u8>(), 0..400), word in 0u8..20, len in 0u32..5000, start in 0u32..6000) {
        let mut m = header(word, len, start);
        m.extend(tail);
        let _ = deflated::inflate(&m);
    }

    #[test]
    fn any_frame_round_trips(points in proptest::collection::vec(-1e6f32..1e6, 300..900)) {
        let basis = DragBasis { design: 1, part: 2, basis: 3, reference: 4, rho: points };
        let inner = basis.encode().unwrap();
        if let Some(m) = deflated::deflate(&inner) {
            prop_assert_eq!(deflated::inflate(&m).unwrap(), inner);
        }
    }
}
