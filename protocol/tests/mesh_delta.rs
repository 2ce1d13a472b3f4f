//! The mesh delta (kind 8) against bytes built by hand here from the layout
//! in protocol/README.md ("Binary mesh delta (kind 8)"), not by our encoder;
//! applying it to its base against the frame worked out by hand; refusals of
//! corrupt deltas and wrong bases; and `between` → `apply` round trips.

use vsculpt_protocol::ErrorCode;
use vsculpt_protocol::mesh_delta::{KIND_MESH_DELTA, LITERAL, MeshDelta, Run};
use vsculpt_protocol::mesh_frame::MeshFrame;

/// The base: design 7, part 9, revision 300; 6 vertices (vertex k at
/// quanta (k, 10k, 100k), normal +x for even k, +z for odd), 3 triangles.
fn base() -> MeshFrame {
    MeshFrame {
        design: 7,
        part: 9,
        revision: 300,
        flags: 0,
        origin: [-1.0, 0.5, 2.0],
        step: 0.25,
        positions: (0..6u16).map(|k| [k, 10 * k, 100 * k]).collect(),
        normals: (0..6)
            .map(|k| {
                if k % 2 == 0 {
                    [32767, 0, 0]
                } else {
                    [0, 0, 32767]
                }
            })
            .collect(),
        triangles: vec![[0, 1, 2], [2, 3, 4], [3, 4, 5]],
    }
}

fn u32le(b: &mut Vec<u8>, x: u32) {
    b.extend_from_slice(&x.to_le_bytes());
}

/// Revision 301 from base 300, written field by field: vertices = base 2, 3,
/// 4, two literal vertices, base 0; triangles = base triangle 1, then two
/// literal ones.
fn hand_built() -> Vec<u8> {
    let mut b: Vec<u8> = Vec::new();
    b.extend_from_slice(b"VSGF");
    b.push(8); // kind
    b.push(2); // version
    b.extend_from_slice(&[1, 0]); // flags = drag
    b.extend_from_slice(&[7, 0, 0, 0, 0, 0, 0, 0]); // design 7
    b.extend_from_slice(&[9, 0, 0, 0, 0, 0, 0, 0]); // part 9
    b.extend_from_slice(&[0x2d, 0x01, 0, 0, 0, 0, 0, 0]); // revision 301
    b.extend_from_slice(&[0x2c, 0x01, 0, 0, 0, 0, 0, 0]); // base 300
    u32le(&mut b, 6); // V
    u32le(&mut b, 3); // T
    u32le(&mut b, 3); // RV
    u32le(&mut b, 2); // RT
    u32le(&mut b, 2); // LV
    u32le(&mut b, 2); // LT
    // origin (-1, 0.5, 2) and step 0.25 as IEEE-754 single bit patterns.
    b.extend_from_slice(&[0x00, 0x00, 0x80, 0xbf]);
    b.extend_from_slice(&[0x00, 0x00, 0x00, 0x3f]);
    b.extend_from_slice(&[0x00, 0x00, 0x00, 0x40]);
    b.extend_from_slice(&[0x00, 0x00, 0x80, 0x3e]);
    b.push(2); // u16 indices
    b.extend_from_slice(&[0; 7]);
    assert_eq!(b.len(), 88);
    // Vertex runs: base 2..5, 2 literals, base 0..1.
    for (s, n) in [(2u32, 3u32), (0xffff_ffff, 2), (0, 1)] {
        u32le(&mut b, s);
        u32le(&mut b, n);
    }
    // Triangle runs: base triangle 1, 2 literals.
    for (s, n) in [(1u32, 1u32), (0xffff_ffff, 2)] {
        u32le(&mut b, s);
        u32le(&mut b, n);
    }
    // Literal positions (7, 8, 9) and (65535, 0, 1).
    for c in [7u16, 8, 9, 0xffff, 0, 1] {
        b.extend_from_slice(&c.to_le_bytes());
    }
    // Literal normals: -y (0x8001 = -32767), +x.
    for c in [0u16, 0x8001, 0, 0x7fff, 0, 0] {
        b.extend_from_slice(&c.to_le_bytes());
    }
    // Literal triangles (new numbering): (0, 3, 4), (4, 3, 5).
    for i in [0u16, 3, 4, 4, 3, 5] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    b
}

/// What the delta stands for, worked out by hand from the rules.
fn expected() -> MeshFrame {
    let b = base();
    MeshFrame {
        revision: 301,
        flags: 1,
        positions: vec![
            b.positions[2],
            b.positions[3],
            b.positions[4],
            [7, 8, 9],
            [65535, 0, 1],
            b.positions[0],
        ],
        normals: vec![
            b.normals[2],
            b.normals[3],
            b.normals[4],
            [0, -32767, 0],
            [32767, 0, 0],
            b.normals[0],
        ],
        // Base triangle 1 = (2, 3, 4) → new (0, 1, 2).
        triangles: vec![[0, 1, 2], [0, 3, 4], [4, 3, 5]],
        ..b
    }
}

#[test]
fn decodes_and_applies_a_delta_built_by_hand() {
    let bytes = hand_built();
    assert_eq!(bytes.len(), 88 + 8 * 5 + 12 * 2 + 6 * 2);
    assert_eq!(bytes[4], KIND_MESH_DELTA);
    let d = MeshDelta::decode(&bytes).unwrap();
    assert_eq!(
        (d.design, d.part, d.revision, d.base, d.flags),
        (7, 9, 301, 300, 1)
    );
    assert_eq!(
        d.vertex_runs,
        vec![
            Run {
                source: 2,
                count: 3
            },
            Run {
                source: LITERAL,
                count: 2
            },
            Run {
                source: 0,
                count: 1
            }
        ]
    );
    assert_eq!(d.counts(), (6, 3));
    let f = d.apply(&base()).unwrap();
    assert_eq!(f, expected());
    assert_eq!(
        f.encode().unwrap(),
        expected().encode().unwrap(),
        "same bytes as the whole frame"
    );
    // Our encoder writes the same bytes.
    assert_eq!(d.encode().unwrap(), bytes);
}

#[test]
fn refuses_corrupt_deltas_and_wrong_bases_without_panicking() {
    let good = hand_built();
    let runs = 88;
    let mut cases: Vec<(Vec<u8>, &str)> = Vec::new();
    let mut b = good.clone();
    b[runs + 4] = 0; // first vertex run of 0
    cases.push((b, "empty"));
    let mut b = good.clone();
    b[40] = 7; // V = 7, the runs make 6
    cases.push((b, "header says"));
    let mut b = good.clone();
    b[56] = 3; // LV = 3: the length no longer matches
    cases.push((b, "bytes"));
    let mut b = good.clone();
    b[80] = 4; // u32 indices for 6 vertices
    cases.push((b, "index width"));
    let mut b = good.clone();
    b[85] = 1;
    cases.push((b, "padding"));
    let mut b = good.clone();
    let last = b.len() - 2;
    b[last] = 6; // literal index 6 of 6 vertices
    cases.push((b, "beyond"));
    let mut b = good.clone();
    b[76..80].copy_from_slice(&f32::NAN.to_le_bytes());
    cases.push((b, "non-finite"));
    let mut b = good.clone();
    b[4] = 3;
    cases.push((b, "not 8"));
    cases.push((good[..good.len() - 1].to_vec(), "bytes"));
    for (bytes, why) in cases {
        let e = MeshDelta::decode(&bytes).expect_err(why);
        assert!(e.message.contains(why), "{why}: {}", e.message);
    }
    for n in 0..good.len() {
        assert!(MeshDelta::decode(&good[..n]).is_err());
    }

    // Decodes, but does not fit the base.
    let fits = |b: Vec<u8>| MeshDelta::decode(&b).unwrap().apply(&base());
    let mut b = good.clone();
    b[runs + 16] = 1; // third vertex run copies base vertex 1…
    b[runs] = 1; // …and the first copies 1..4: vertex 1 twice
    assert!(fits(b).unwrap_err().message.contains("twice"));
    let mut b = good.clone();
    b[runs] = 4; // base 4..7 of 6
    assert!(fits(b).unwrap_err().message.contains("copies vertices"));
    let mut b = good.clone();
    b[runs + 24] = 0; // base triangle 0 names base vertex 1, which no run copies
    assert!(fits(b).unwrap_err().message.contains("does not keep"));
    let mut b = good.clone();
    b[runs + 24] = 3; // base triangle 3 of 3
    assert!(fits(b).unwrap_err().message.contains("copies triangles"));
    let d = MeshDelta::decode(&good).unwrap();
    let other = MeshFrame {
        revision: 299,
        ..base()
    };
    assert_eq!(d.apply(&other).unwrap_err().code, ErrorCode::Conflict);
    let moved = MeshFrame {
        step: 0.5,
        ..base()
    };
    assert_eq!(d.apply(&moved).unwrap_err().code, ErrorCode::Conflict);
}

/// A grid-like mesh of `n` × `n` vertices with quanta from `f`.
fn sheet(n: u32, revision: u64, f: impl Fn(u32, u32) -> [u16; 3]) -> MeshFrame {
    let mut triangles = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let k = j * n + i;
            triangles.push([k, k + 1, k + n + 1]);
            triangles.push([k, k + n + 1, k + n]);
        }
    }
    MeshFrame {
        design: 1,
        part: 2,
        revision,
        flags: 0,
        origin: [0.0; 3],
        step: 1e-3,
        positions: (0..n * n).map(|k| f(k % n, k / n)).collect(),
        normals: vec![[0, 0, 32767]; (n * n) as usize],
        triangles,
    }
}

#[test]
fn a_local_change_gives_a_short_delta_that_applies_exactly() {
    let flat = |i: u32, j: u32| [i as u16 * 100, j as u16 * 100, 0];
    let a = sheet(60, 1, flat);
    // A bump near one corner: only those vertices move.
    let b = sheet(60, 2, |i, j| {
        let mut q = flat(i, j);
        if i < 6 && j < 6 {
            q[2] = 50;
        }
        q
    });
    let d = MeshDelta::between(&a, &b).unwrap();
    assert_eq!(d.apply(&a).unwrap(), b);
    assert_eq!(d.apply(&a).unwrap().encode().unwrap(), b.encode().unwrap());
    assert!(
        d.positions.len() <= 60 * 6,
        "{} literal vertices",
        d.positions.len()
    );
    assert!(
        d.byte_len() * 5 < b.byte_len(),
        "{} of {}",
        d.byte_len(),
        b.byte_len()
    );
    let round = MeshDelta::decode(&d.encode().unwrap()).unwrap();
    assert_eq!(round, d);
    // Vertices removed from the middle: the kept ones are renumbered and the
    // copied triangles follow them.
    let mut c = a.clone();
    c.revision = 3;
    c.positions.drain(1800..1860);
    c.normals.drain(1800..1860);
    c.triangles
        .retain(|t| t.iter().all(|&k| !(1800..1860).contains(&k)));
    for t in &mut c.triangles {
        for k in t.iter_mut() {
            if *k >= 1860 {
                *k -= 60;
            }
        }
    }
    let d = MeshDelta::between(&a, &c).unwrap();
    assert_eq!(d.apply(&a).unwrap(), c);
    assert!(d.byte_len() < 200, "{} bytes", d.byte_len());
    // Another cube, part or an unrelated mesh: no delta.
    let moved = MeshFrame {
        origin: [1.0, 0.0, 0.0],
        ..b.clone()
    };
    assert!(MeshDelta::between(&a, &moved).is_none());
    let other = MeshFrame {
        part: 3,
        ..b.clone()
    };
    assert!(MeshDelta::between(&a, &other).is_none());
    let shuffled = sheet(60, 4, |i, j| [j as u16 * 7 + 1, i as u16 * 13 + 1, 9]);
    assert!(MeshDelta::between(&a, &shuffled).is_none());
}
