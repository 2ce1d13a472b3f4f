//! The body frame (kind 4) against bytes written by hand from the README's
//! table (not by our encoder), every truncation and corruption refused
//! without a panic; and the body messages' validation (`body_edit`,
//! `body_morph`, a `body` part's lattice).

use vsculpt_protocol::body_frame::KIND_BODY;
use vsculpt_protocol::{BodyFrame, ErrorCode, parse_client};

/// N = 2·2·2 lattice points (trilinear), V = 3 vertices, T = 1 triangle,
/// L = 1 line of S = 2 samples, degrees (1, 1, 1) and knots (0, 0, 1, 1) per
/// direction, at the README's offsets.
fn hand_written() -> Vec<u8> {
    let mut b = Vec::new();
    b.extend_from_slice(b"VSGF");
    b.push(4);
    b.push(2);
    b.extend_from_slice(&1u16.to_le_bytes());
    for x in [7u64, 9, 42] {
        b.extend_from_slice(&x.to_le_bytes());
    }
    b.extend_from_slice(&0.25f32.to_le_bytes());
    for x in [2u32, 2, 2, 3, 1, 1, 2] {
        b.extend_from_slice(&x.to_le_bytes());
    }
    assert_eq!(b.len(), 64);
    let f32s = |b: &mut Vec<u8>, xs: &[f32]| {
        xs.iter()
            .for_each(|x| b.extend_from_slice(&x.to_le_bytes()))
    };
    let lattice: Vec<f32> = (0..8)
        .flat_map(|n| {
            [
                (n >> 2) as f32,
                ((n >> 1) & 1) as f32 * 2.0,
                (n & 1) as f32 * 3.0,
            ]
        })
        .collect();
    f32s(&mut b, &lattice);
    f32s(&mut b, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    f32s(&mut b, &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    for i in [0u32, 1, 2, 2] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    f32s(&mut b, &[0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
    for p in [1u32, 1, 1] {
        b.extend_from_slice(&p.to_le_bytes());
    }
    for _ in 0..3 {
        f32s(&mut b, &[0.0, 0.0, 1.0, 1.0]);
    }
    assert_eq!(
        b.len(),
        64 + 12 * 8 + 24 * 3 + 12 + 4 + 12 * 2 + 12 + 4 * 12
    );
    b
}

#[test]
fn decodes_hand_written_bytes_and_encodes_them_back() {
    let bytes = hand_written();
    let f = BodyFrame::decode(&bytes).unwrap();
    assert_eq!(
        (f.design, f.part, f.revision, f.flags, f.t),
        (7, 9, 42, 1, 0.25)
    );
    assert_eq!(f.counts, [2, 2, 2]);
    assert_eq!(f.lattice[1], [0.0, 0.0, 3.0]);
    assert_eq!(f.lattice[6], [1.0, 2.0, 0.0]);
    assert_eq!(f.degrees, [1, 1, 1]);
    assert_eq!(f.knots, [0, 1, 2].map(|_| vec![0.0, 0.0, 1.0, 1.0]));
    assert_eq!(f.triangles, vec![[0, 1, 2]]);
    assert_eq!(f.line_dirs, vec![2]);
    assert_eq!(f.line_samples, 2);
    assert_eq!(f.line_points, vec![[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]);
    assert_eq!(f.encode().unwrap(), bytes);
    assert_eq!(f.byte_len(), bytes.len());
    assert_eq!(bytes[4], KIND_BODY);
}

#[test]
fn refuses_truncated_corrupt_and_oversized_frames() {
    let bytes = hand_written();
    for n in 0..bytes.len() {
        assert!(BodyFrame::decode(&bytes[..n]).is_err(), "{n} bytes");
    }
    let patched = |at: usize, v: u32| {
        let mut b = bytes.clone();
        b[at..at + 4].copy_from_slice(&v.to_le_bytes());
        b
    };
    // A triangle naming vertex 3 of 3; a line direction 3; a huge lattice.
    let tri = 64 + 96 + 72;
    assert!(BodyFrame::decode(&patched(tri + 8, 3)).is_err());
    assert!(BodyFrame::decode(&patched(tri + 12, 3)).is_err());
    // The spline section: a degree 0 or 6, a degree that needs more knots
    // than sent, decreasing knots, a NaN knot.
    let spline = tri + 12 + 4 + 24;
    assert!(BodyFrame::decode(&patched(spline, 0)).is_err());
    assert!(BodyFrame::decode(&patched(spline + 4, 6)).is_err());
    assert!(BodyFrame::decode(&patched(spline + 8, 2)).is_err());
    let knot = |k: usize, x: f32| patched(spline + 12 + 4 * k, x.to_bits());
    assert!(BodyFrame::decode(&knot(5, -1.0)).is_err());
    assert_eq!(
        BodyFrame::decode(&knot(9, f32::NAN)).unwrap_err().code,
        ErrorCode::NotFinite
    );
    assert!(BodyFrame::decode(&knot(9, 0.5)).is_ok());
    let e = BodyFrame::decode(&patched(36, u32::MAX)).unwrap_err();
    assert_eq!(e.code, ErrorCode::TooLarge);
    // NaN in the lattice.
    let mut nan = bytes.clone();
    nan[64..68].copy_from_slice(&f32::NAN.to_le_bytes());
    assert_eq!(
        BodyFrame::decode(&nan).unwrap_err().code,
        ErrorCode::NotFinite
    );
    // Another kind or version.
    let mut kind = bytes.clone();
    kind[4] = 3;
    assert!(BodyFrame::decode(&kind).is_err());
    let mut version = bytes.clone();
    version[5] = 1;
    assert_eq!(
        BodyFrame::decode(&version).unwrap_err().code,
        ErrorCode::BadVersion
    );
}

#[test]
fn body_messages_are_validated() {
    let code = |text: &str| parse_client(text).map(|_| ()).map_err(|e| e.code);
    let unit = r#"{"u": {"degree": 1, "knots": [0, 0, 1, 1]}, "v": {"degree": 1, "knots": [0, 0, 1, 1]}, "w": {"degree": 1, "knots": [0, 0, 1, 1]}, "points": [[0,0,0],[0,0,1],[0,1,0],[0,1,1],[1,0,0],[1,0,1],[1,1,0],[1,1,1]]}"#;
    let create = |lattice: &str| {
        format!(
            r#"{{"type": "create_part", "spec": {{"name": "b", "shape": {{"kind": "body", "body": {{"lattice": {lattice}}}}}}}}}"#
        )
    };
    assert_eq!(code(&create(unit)), Ok(()));
    let seven = unit.replace(",[1,1,1]]", "]");
    assert_eq!(code(&create(&seven)), Err(ErrorCode::OutOfRange));
    let far = unit.replace("[1,1,1]]", "[1e10,1,1]]");
    assert_eq!(code(&create(&far)), Err(ErrorCode::OutOfRange));
    let deg = unit.replace(
        r#""w": {"degree": 1, "knots": [0, 0, 1, 1]}"#,
        r#""w": {"degree": 6, "knots": [0,0,0,0,0,0,0,1,1,1,1,1,1,1]}"#,
    );
    assert_eq!(code(&create(&deg)), Err(ErrorCode::OutOfRange));
    let many: Vec<String> = (0..60).map(|k| format!("{}", k as f64 / 59.0)).collect();
    let long = unit.replace(
        r#""u": {"degree": 1, "knots": [0, 0, 1, 1]}"#,
        &format!(
            r#""u": {{"degree": 1, "knots": [0, {}, 1]}}"#,
            many.join(", ")
        ),
    );
    assert_eq!(code(&create(&long)), Err(ErrorCode::TooLarge));
    let edit = |select: &str, delta: &str| {
        format!(
            r#"{{"type": "body_edit", "part": 3, "edit": {{"select": {select}, "delta": {delta}}}}}"#
        )
    };
    assert_eq!(code(&edit(r#"{"point": [1, 0, 1]}"#, "[0, 0, 1]")), Ok(()));
    assert_eq!(code(&edit(r#"{"face": "w_max"}"#, "[0, 0, 1]")), Ok(()));
    assert_eq!(
        code(&edit(r#"{"edge": ["u_max", "w_min"]}"#, "[0, 0, 1]")),
        Ok(())
    );
    assert_eq!(
        code(&edit(r#"{"edge": ["u_max", "u_min"]}"#, "[0, 0, 1]")),
        Err(ErrorCode::OutOfRange)
    );
    assert_eq!(
        code(&edit(r#"{"point": [1, 0, 1]}"#, "[1e300, 0, 1]")),
        Err(ErrorCode::OutOfRange)
    );
    assert_eq!(
        code(&edit(r#"{"point": [1, 0, 1]}"#, "[NaN, 0, 1]")),
        Err(ErrorCode::Malformed)
    );
    assert_eq!(
        code(&edit(r#"{"vertex": [1, 0, 1]}"#, "[0, 0, 1]")),
        Err(ErrorCode::Malformed)
    );
    assert_eq!(
        code(r#"{"type": "body_morph", "part": 3, "t": 0.5}"#),
        Ok(())
    );
    assert_eq!(
        code(r#"{"type": "body_morph", "part": 3, "t": -0.1}"#),
        Err(ErrorCode::OutOfRange)
    );
    assert_eq!(
        code(r#"{"type": "body_morph", "part": 3, "t": 1.01}"#),
        Err(ErrorCode::OutOfRange)
    );
}
