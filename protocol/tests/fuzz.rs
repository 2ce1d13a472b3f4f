//! Property-based fuzzing on stable Rust (proptest) of the two decoders
//! that take untrusted bytes from the network: the JSON control decoder
//! ([`parse_client`]) and the binary geometry frame decoder
//! ([`GeometryFrame::decode`]). Inputs are arbitrary bytes and structured
//! mutations (bit flips, truncations, splices, number and token swaps) of
//! the committed corpus in `protocol/fuzz/corpus/` (valid messages and
//! nasty ones). Every input must give a value or a typed error with one of
//! the documented codes, never a panic, and no single allocation may be
//! much larger than the input (a header cannot make the decoder reserve
//! gigabytes).
//!
//! `cargo test` runs 256 cases per property; run longer locally with
//! `PROPTEST_CASES=100000 cargo test --release -p vsculpt-protocol --test fuzz`.
//! A failing case is shrunk and printed; add it to the corpus.

use proptest::prelude::*;
use std::path::PathBuf;
use vsculpt_protocol::limits::MAX_MESSAGE_BYTES;
use vsculpt_protocol::{ErrorCode, GeometryFrame, parse_client};

mod largest_allocation;
use largest_allocation::measured;

/// The allocation a decoder may make for an input of `len` bytes: a
/// multiple of the input (a JSON number of 2 bytes becomes an 8-byte f64
/// in a Vec that may double) plus a small constant.
fn allowed(len: usize) -> usize {
    64 * len + 64 * 1024
}

fn corpus(kind: &str) -> Vec<Vec<u8>> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(kind);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    let out: Vec<Vec<u8>> = files.iter().map(|p| std::fs::read(p).unwrap()).collect();
    assert!(out.len() >= 5, "corpus {kind} is too small");
    out
}

const CLIENT_CODES: &[ErrorCode] = &[
    ErrorCode::TooLarge,
    ErrorCode::Malformed,
    ErrorCode::UnknownMessage,
    ErrorCode::NotFinite,
    ErrorCode::OutOfRange,
];

const FRAME_CODES: &[ErrorCode] = &[
    ErrorCode::TooLarge,
    ErrorCode::Malformed,
    ErrorCode::BadVersion,
    ErrorCode::NotFinite,
    ErrorCode::OutOfRange,
];

/// Feeds `bytes` to the JSON decoder as the server does (text messages are
/// UTF-8; other bytes are refused by the WebSocket layer, so they are
/// decoded lossily here to still reach the parser).
fn check_client(bytes: &[u8]) -> Result<(), TestCaseError> {
    let text = String::from_utf8_lossy(bytes);
    let (result, largest) = measured(|| parse_client(&text));
    if let Err(e) = &result {
        prop_assert!(CLIENT_CODES.contains(&e.code), "{e:?} for {text:?}");
        prop_assert!(!e.message.is_empty());
    }
    if let Ok(envelope) = &result {
        // Whatever is accepted survives a round trip unchanged.
        let again = parse_client(&serde_json::to_string(envelope).unwrap());
        prop_assert_eq!(again.as_ref(), Ok(envelope));
    }
    prop_assert!(
        largest <= allowed(text.len().min(MAX_MESSAGE_BYTES)),
        "{largest} bytes allocated for a {}-byte message",
        text.len()
    );
    Ok(())
}

fn check_frame(bytes: &[u8]) -> Result<(), TestCaseError> {
    let (result, largest) = measured(|| GeometryFrame::decode(bytes));
    match &result {
        Err(e) => prop_assert!(FRAME_CODES.contains(&e.code), "{e:?}"),
        Ok(frame) => {
            // Whatever is accepted re-encodes to the same bytes.
            let again = frame.encode().unwrap();
            prop_assert_eq!(again.as_slice(), bytes);
        }
    }
    prop_assert!(
        largest <= allowed(bytes.len()),
        "{largest} bytes allocated for a {}-byte frame",
        bytes.len()
    );
    Ok(())
}

/// One structured mutation of a seed.
#[derive(Clone, Debug)]
enum Mutation {
    FlipBit(usize, u8),
    SetByte(usize, u8),
    Truncate(usize),
    Remove(usize, usize),
    Duplicate(usize, usize),
    Insert(usize, Vec<u8>),
    /// Overwrites 4 bytes with a little-endian u32 (binary sizes).
    SetU32(usize, u32),
}

/// Tokens that stress a JSON decoder when spliced into a message.
const TOKENS: &[&str] = &[
    "1e400",
    "-1e400",
    "NaN",
    "Infinity",
    "1e9",
    "1000000001",
    "-0",
    "18446744073709551616",
    "4294967296",
    "null",
    "true",
    "[]",
    "{}",
    "\"\"",
    "\"\\ud800\"",
    "[[[[[[[[",
    "]]]]",
    "\u{0}",
    "\"type\":\"hello\"",
    "\"req\":",
    ",",
    ":",
    "\"",
    "\\",
    "é",
    "\u{202e}",
];

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 0u8..8).prop_map(|(i, b)| Mutation::FlipBit(i, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::SetByte(i, b)),
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), 1usize..64).prop_map(|(i, n)| Mutation::Remove(i, n)),
        (any::<usize>(), 1usize..64).prop_map(|(i, n)| Mutation::Duplicate(i, n)),
        (any::<usize>(), prop::sample::select(TOKENS))
            .prop_map(|(i, t)| Mutation::Insert(i, t.as_bytes().to_vec())),
        (any::<usize>(), prop::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(i, b)| Mutation::Insert(i, b)),
        (
            any::<usize>(),
            prop_oneof![
                Just(0u32),
                Just(1),
                Just(2048),
                Just(2049),
                Just(65_536),
                Just(u32::MAX),
                any::<u32>()
            ]
        )
            .prop_map(|(i, v)| Mutation::SetU32(i, v)),
    ]
}

fn apply(seed: &[u8], mutations: &[Mutation]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for m in mutations {
        let at = |i: usize, len: usize| if len == 0 { 0 } else { i % len };
        match m {
            Mutation::FlipBit(i, bit) if !b.is_empty() => {
                let k = at(*i, b.len());
                b[k] ^= 1 << bit;
            }
            Mutation::SetByte(i, v) if !b.is_empty() => {
                let k = at(*i, b.len());
                b[k] = *v;
            }
            Mutation::Truncate(i) => b.truncate(at(*i, b.len() + 1)),
            Mutation::Remove(i, n) if !b.is_empty() => {
                let k = at(*i, b.len());
                let end = (k + n).min(b.len());
                b.drain(k..end);
            }
            Mutation::Duplicate(i, n) if !b.is_empty() => {
                let k = at(*i, b.len());
                let end = (k + n).min(b.len());
                let piece = b[k..end].to_vec();
                b.splice(end..end, piece);
            }
            Mutation::Insert(i, piece) => {
                let k = at(*i, b.len() + 1);
                b.splice(k..k, piece.iter().copied());
            }
            // Header fields of a frame sit at 4-aligned offsets.
            Mutation::SetU32(i, v) if b.len() >= 4 => {
                let k = at(*i, b.len() / 4) * 4;
                b[k..k + 4].copy_from_slice(&v.to_le_bytes());
            }
            _ => {}
        }
    }
    b
}

/// A seed and a few mutations of it.
fn mutated(kind: &'static str) -> impl Strategy<Value = Vec<u8>> {
    let seeds = corpus(kind);
    (
        prop::sample::select(seeds),
        prop::collection::vec(mutation(), 1..6),
    )
        .prop_map(|(seed, ms)| apply(&seed, &ms))
}

#[test]
fn every_corpus_seed_decodes_or_fails_typed() {
    for seed in corpus("client") {
        check_client(&seed).unwrap();
    }
    for seed in corpus("frame") {
        check_frame(&seed).unwrap();
    }
}

/// The valid seeds are valid: the corpus exercises the decoders past their
/// first checks (a fuzzer fed only garbage tests only the first branch).
#[test]
fn the_valid_seeds_are_accepted_and_the_nasty_ones_refused() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus");
    for kind in ["client", "frame"] {
        for entry in std::fs::read_dir(dir.join(kind)).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().to_string();
            let bytes = std::fs::read(&path).unwrap();
            let ok = match kind {
                "client" => parse_client(&String::from_utf8_lossy(&bytes)).is_ok(),
                _ => GeometryFrame::decode(&bytes).is_ok(),
            };
            assert_eq!(ok, !name.starts_with("nasty_"), "{kind}/{name}");
        }
    }
}

/// The allocation guard is not vacuous: it sees a large allocation.
#[test]
fn the_allocation_tracker_sees_allocations() {
    let (v, largest) = measured(|| vec![0u8; 1 << 20]);
    assert_eq!(v.len(), 1 << 20);
    assert!(largest >= 1 << 20);
}

proptest! {
    #[test]
    fn client_decoder_survives_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..2048)) {
        check_client(&bytes)?;
    }

    #[test]
    fn client_decoder_survives_arbitrary_text(text in "\\PC{0,512}") {
        check_client(text.as_bytes())?;
    }

    #[test]
    fn client_decoder_survives_mutated_messages(bytes in mutated("client")) {
        check_client(&bytes)?;
    }

    #[test]
    fn frame_decoder_survives_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..1024)) {
        check_frame(&bytes)?;
    }

    #[test]
    fn frame_decoder_survives_arbitrary_headers(
        mut header in prop::collection::vec(any::<u8>(), 48..49),
        tail in prop::collection::vec(any::<u8>(), 0..512),
    ) {
        // Past the magic, kind and version checks: the sizes are arbitrary.
        header[..4].copy_from_slice(b"VSGF");
        header[4] = 1 + header[4] % 2;
        header[5] = vsculpt_protocol::PROTOCOL_VERSION as u8;
        header.extend_from_slice(&tail);
        check_frame(&header)?;
    }

    #[test]
    fn frame_decoder_survives_mutated_frames(bytes in mutated("frame")) {
        check_frame(&bytes)?;
    }
}
