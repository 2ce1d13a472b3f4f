//! The mesh frame (kind 3) against bytes built by hand here from the layout in
//! protocol/README.md (not by our encoder), round trips, and refusals of
//! corrupt frames; the DSM part and edit messages' validation.

use vsculpt_protocol::mesh_frame::{KIND_MESH, MeshFrame};
use vsculpt_protocol::{ErrorCode, parse_client};

/// A tetrahedron-like frame: 4 vertices, 2 triangles, written field by field.
fn hand_built() -> Vec<u8> {
    let mut b: Vec<u8> = Vec::new();
    b.extend_from_slice(b"VSGF");
    b.push(3); // kind
    b.push(2); // version
    b.extend_from_slice(&[1, 0]); // flags = drag
    b.extend_from_slice(&[7, 0, 0, 0, 0, 0, 0, 0]); // design 7
    b.extend_from_slice(&[9, 0, 0, 0, 0, 0, 0, 0]); // part 9
    b.extend_from_slice(&[0x2c, 0x01, 0, 0, 0, 0, 0, 0]); // revision 300
    b.extend_from_slice(&[4, 0, 0, 0]); // V
    b.extend_from_slice(&[2, 0, 0, 0]); // T
    // origin (-1, 0.5, 2) and step 0.25 as IEEE-754 single bit patterns.
    b.extend_from_slice(&[0x00, 0x00, 0x80, 0xbf]);
    b.extend_from_slice(&[0x00, 0x00, 0x00, 0x3f]);
    b.extend_from_slice(&[0x00, 0x00, 0x00, 0x40]);
    b.extend_from_slice(&[0x00, 0x00, 0x80, 0x3e]);
    b.push(2); // u16 indices
    b.extend_from_slice(&[0; 7]);
    assert_eq!(b.len(), 64);
    // positions (q) : (0,0,0) (4,0,0) (0,8,0) (0,0,65535)
    for q in [[0u16, 0, 0], [4, 0, 0], [0, 8, 0], [0, 0, 0xffff]] {
        for c in q {
            b.push((c & 0xff) as u8);
            b.push((c >> 8) as u8);
        }
    }
    // normals: +x, -y (0x8001 = -32767), +z, +z
    for n in [
        [0x7fffu16, 0, 0],
        [0, 0x8001, 0],
        [0, 0, 0x7fff],
        [0, 0, 0x7fff],
    ] {
        for c in n {
            b.push((c & 0xff) as u8);
            b.push((c >> 8) as u8);
        }
    }
    for i in [0u8, 1, 2, 0, 2, 3] {
        b.extend_from_slice(&[i, 0]);
    }
    b
}

#[test]
fn decodes_a_frame_built_by_hand() {
    let bytes = hand_built();
    assert_eq!(bytes.len(), 64 + 12 * 4 + 6 * 2);
    let f = MeshFrame::decode(&bytes).unwrap();
    assert_eq!((f.design, f.part, f.revision, f.flags), (7, 9, 300, 1));
    assert_eq!(f.origin, [-1.0, 0.5, 2.0]);
    assert_eq!(f.step, 0.25);
    assert_eq!(f.position(1), [0.0, 0.5, 2.0]);
    assert_eq!(f.position(2), [-1.0, 2.5, 2.0]);
    assert_eq!(f.position(3), [-1.0, 0.5, 2.0 + 65535.0 * 0.25]);
    assert_eq!(f.normal(0), [1.0, 0.0, 0.0]);
    assert_eq!(f.normal(1), [0.0, -1.0, 0.0]);
    assert_eq!(f.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    // Our encoder writes the same bytes.
    assert_eq!(f.encode().unwrap(), bytes);
}

#[test]
fn refuses_corrupt_frames_without_panicking() {
    let good = hand_built();
    let mut cases: Vec<(Vec<u8>, &str)> = Vec::new();
    let mut b = good.clone();
    b[64 + 48] = 4; // first index → vertex 4 of 4
    cases.push((b, "beyond"));
    let mut b = good.clone();
    b[56] = 4; // u32 indices for 4 vertices
    cases.push((b, "index width"));
    let mut b = good.clone();
    b[60] = 1;
    cases.push((b, "padding"));
    cases.push((good[..good.len() - 1].to_vec(), "bytes"));
    let mut b = good.clone();
    b[52..56].copy_from_slice(&f32::NAN.to_le_bytes());
    cases.push((b, "non-finite"));
    let mut b = good.clone();
    b[4] = 1;
    cases.push((b, "not a mesh"));
    let mut b = good.clone();
    b[32..36].copy_from_slice(&u32::MAX.to_le_bytes());
    cases.push((b, "size limits"));
    for (bytes, want) in cases {
        let e = MeshFrame::decode(&bytes).unwrap_err();
        assert!(e.message.contains(want), "{want}: got {}", e.message);
    }
    // Every truncation is refused.
    for n in 0..good.len() {
        assert!(MeshFrame::decode(&good[..n]).is_err());
    }
}

#[test]
fn quantised_positions_are_within_half_a_step() {
    let n = 300;
    let positions: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let t = i as f64 * 0.37;
            [3.0 * t.cos() - 1.0, 2.0 * t.sin(), 0.01 * i as f64]
        })
        .collect();
    let normals: Vec<[f64; 3]> = (0..n)
        .map(|i| [0.0, (i as f64).cos(), (i as f64).sin()])
        .collect();
    let triangles: Vec<[u32; 3]> = (0..n as u32 - 2).map(|i| [i, i + 1, i + 2]).collect();
    let f = MeshFrame::quantise((1, 2, 3), 0, &positions, &normals, &triangles).unwrap();
    let bytes = f.encode().unwrap();
    assert_eq!(bytes[4], KIND_MESH);
    assert_eq!(bytes.len(), 64 + 12 * n + 6 * (n - 2));
    let g = MeshFrame::decode(&bytes).unwrap();
    assert_eq!(g, f);
    let step = g.step as f64;
    assert!((step - 6.0 / 65535.0).abs() < 1e-6);
    for (i, p) in positions.iter().enumerate() {
        let q = g.position(i);
        for a in 0..3 {
            // Half a step, plus f32 rounding of origin and step.
            assert!(
                (q[a] - p[a]).abs() <= 0.5 * step + 1e-5,
                "{i}: {q:?} vs {p:?}"
            );
        }
        let nn = g.normal(i);
        let d: f64 = (0..3)
            .map(|a| (nn[a] - normals[i][a]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(d < 1e-4);
    }
    assert!(
        MeshFrame::quantise(
            (1, 2, 3),
            0,
            &[[f64::NAN, 0.0, 0.0]],
            &[[0.0, 0.0, 1.0]],
            &[]
        )
        .is_err()
    );
    assert!(MeshFrame::quantise((1, 2, 3), 0, &positions, &normals, &[[0, 1, n as u32]]).is_err());
}

#[test]
fn a_fixed_cube_keeps_an_unmoved_vertex_quantised_alike() {
    // Two meshes sharing vertex 0, the second reaching further: on their
    // bounding cubes vertex 0 quantises differently, on one fixed cube alike
    // (what a delta between frames needs), and within half a step.
    let n = [[0.0, 0.0, 1.0]; 2];
    let a = [[0.3, -0.2, 0.7], [1.0, 1.0, 1.0]];
    let b = [[0.3, -0.2, 0.7], [-0.5, 1.0, 1.0]];
    let tri: [[u32; 3]; 0] = [];
    let fa = MeshFrame::quantise((1, 2, 3), 0, &a, &n, &tri).unwrap();
    let fb = MeshFrame::quantise((1, 2, 4), 0, &b, &n, &tri).unwrap();
    assert_ne!(fa.positions[0], fb.positions[0]);
    let cube = ([-1.0, -1.0, -1.0], 3.0);
    let fa = MeshFrame::quantise_in((1, 2, 3), 0, cube, &a, &n, &tri).unwrap();
    let fb = MeshFrame::quantise_in((1, 2, 4), 0, cube, &b, &n, &tri).unwrap();
    assert_eq!(fa.positions[0], fb.positions[0]);
    assert_eq!((fa.origin, fa.step), (fb.origin, fb.step));
    assert_eq!(fa.origin, [-1.0; 3]);
    let step = 3.0 / 65535.0;
    // Vertex 0 by hand: (p − origin) / step, rounded.
    let hand = [1.3f64, 0.8, 1.7].map(|x| (x / step).round() as u16);
    for a in 0..3 {
        assert!(fa.positions[0][a].abs_diff(hand[a]) <= 1, "{a}");
        assert!((fa.position(0)[a] - [0.3, -0.2, 0.7][a]).abs() <= 0.5 * step + 1e-6);
    }
    // Outside the cube: refused, not clamped.
    let out = [[0.3, -0.2, 0.7], [2.5, 1.0, 1.0]];
    let e = MeshFrame::quantise_in((1, 2, 5), 0, cube, &out, &n, &tri).unwrap_err();
    assert_eq!(e.code, ErrorCode::OutOfRange);
    let e = MeshFrame::quantise_in((1, 2, 5), 0, ([f64::NAN, 0.0, 0.0], 1.0), &a, &n, &tri)
        .unwrap_err();
    assert_eq!(e.code, ErrorCode::NotFinite);
}

#[test]
fn large_meshes_use_u32_indices() {
    let n = 70_000;
    let positions: Vec<[f64; 3]> = (0..n).map(|i| [i as f64, 0.0, 0.0]).collect();
    let normals = vec![[0.0, 0.0, 1.0]; n];
    let f = MeshFrame::quantise((1, 2, 3), 0, &positions, &normals, &[[0, 69_999, 5]]).unwrap();
    let bytes = f.encode().unwrap();
    assert_eq!(bytes[56], 4);
    assert_eq!(bytes.len(), 64 + 12 * n + 12);
    assert_eq!(
        MeshFrame::decode(&bytes).unwrap().triangles,
        vec![[0, 69_999, 5]]
    );
}

fn create(shape: &str) -> String {
    format!(
        r#"{{"type": "create_part", "spec": {{"name": "d", "shape": {{"kind": "dsm", "dsm": {shape}}}}}}}"#
    )
}

#[test]
fn dsm_parts_and_edits_are_validated() {
    let ok = r#"{"de": 1, "cells": 32, "groups": [{"op": "add", "primitives": [{"id": 1, "at": [0, 0, 0], "shape": {"type": "sphere", "radius": 1}}]}]}"#;
    parse_client(&create(ok)).unwrap();
    let bad = [
        (
            r#"{"de": 0, "cells": 32, "groups": []}"#,
            ErrorCode::OutOfRange,
            "de",
        ),
        (
            r#"{"de": 1, "cells": 4, "groups": []}"#,
            ErrorCode::OutOfRange,
            "cells",
        ),
        (
            r#"{"de": 1, "cells": 32, "groups": [{"op": "add", "primitives": [{"id": 1, "at": [0, 0, 1e300], "shape": {"type": "sphere", "radius": 1}}]}]}"#,
            ErrorCode::OutOfRange,
            "at",
        ),
        (
            r#"{"de": 1, "cells": 32, "groups": [{"op": "add", "primitives": [{"id": 1, "at": [0, 0, 0], "shape": {"type": "sphere", "radius": -1}}]}]}"#,
            ErrorCode::OutOfRange,
            "radius",
        ),
        (
            r#"{"de": 1, "cells": 32, "groups": [{"op": "add", "primitives": [{"id": 1, "at": [0, 0, 0], "shape": {"type": "sphere", "radius": 1}}, {"id": 1, "at": [0, 0, 0], "shape": {"type": "sphere", "radius": 1}}]}]}"#,
            ErrorCode::OutOfRange,
            "twice",
        ),
        (
            r#"{"de": 1, "cells": 32, "groups": [{"op": "add", "incorporated": [0], "primitives": []}]}"#,
            ErrorCode::OutOfRange,
            "earlier",
        ),
        (
            r#"{"de": 1, "cells": 32, "groups": [{"op": "add", "primitives": [{"id": 1, "at": [0, 0, 0], "axis": [0, 0, 0], "shape": {"type": "sphere", "radius": 1}}]}]}"#,
            ErrorCode::OutOfRange,
            "axis",
        ),
        (
            r#"{"de": 1, "cells": 32, "groups": [{"op": "add", "primitives": [{"id": 1, "at": [0, 0, 0], "shape": {"type": "net", "nu": 3, "nv": 3, "spacing": [1, 1], "heights": [1, 1, 1], "reducing": 1}}]}]}"#,
            ErrorCode::OutOfRange,
            "heights",
        ),
        (
            r#"{"de": 1, "cells": 32, "groups": [{"op": "add", "primitives": [{"id": 1, "at": [0, 0, 0], "shape": {"type": "net", "nu": 40, "nv": 3, "spacing": [1, 1], "heights": [], "reducing": 1}}]}]}"#,
            ErrorCode::OutOfRange,
            "nu",
        ),
        (
            r#"{"de": 1, "cells": 32, "groups": [{"op": "add", "primitives": [{"id": 1, "at": [0, 0, 0], "shape": {"type": "density_sphere", "density": 0, "reducing": 1}}]}]}"#,
            ErrorCode::OutOfRange,
            "density",
        ),
    ];
    for (shape, code, word) in bad {
        let e = parse_client(&create(shape)).unwrap_err();
        assert_eq!(e.code, code, "{shape}: {}", e.message);
        assert!(e.message.contains(word), "{shape}: {}", e.message);
    }
    // Too many primitives.
    let many: Vec<String> = (0..300)
        .map(|i| {
            format!(r#"{{"id": {i}, "at": [0, 0, 0], "shape": {{"type": "sphere", "radius": 1}}}}"#)
        })
        .collect();
    let shape = format!(
        r#"{{"de": 1, "cells": 32, "groups": [{{"op": "add", "primitives": [{}]}}]}}"#,
        many.join(",")
    );
    assert_eq!(
        parse_client(&create(&shape)).unwrap_err().code,
        ErrorCode::TooLarge
    );
    // A material on a DSM part does not fit.
    let with_material = create(ok).replace(
        r#""shape""#,
        r#""material": {"alpha": 1, "beta": 1}, "shape""#,
    );
    assert!(parse_client(&with_material).is_err());

    let edit = |e: &str| format!(r#"{{"type": "dsm_edit", "part": 1, "edit": {e}}}"#);
    parse_client(&edit(
        r#"{"op": "drag_node", "id": 3, "node": 4, "height": 0.5}"#,
    ))
    .unwrap();
    for (e, code) in [
        (
            r#"{"op": "drag_node", "id": 3, "node": 4, "height": 0}"#,
            ErrorCode::OutOfRange,
        ),
        (
            r#"{"op": "move_primitive", "id": 3, "at": [0, 2e9, 0]}"#,
            ErrorCode::OutOfRange,
        ),
        (
            r#"{"op": "set_density", "id": 3, "density": 1, "reducing": -1}"#,
            ErrorCode::OutOfRange,
        ),
        (
            r#"{"op": "resize_primitive", "id": 3, "shape": {"type": "box", "half": [1, 0, 1]}}"#,
            ErrorCode::OutOfRange,
        ),
    ] {
        assert_eq!(parse_client(&edit(e)).unwrap_err().code, code, "{e}");
    }
    // NaN cannot be written in JSON; a huge exponent overflows to a refusal.
    assert!(
        parse_client(&edit(
            r#"{"op": "drag_node", "id": 3, "node": 4, "height": 1e999}"#
        ))
        .is_err()
    );
}
