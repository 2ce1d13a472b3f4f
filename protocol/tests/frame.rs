//! The binary geometry frame: exact round trip, the documented layout, and
//! an error (never a panic) for every other byte string.

use vsculpt_protocol::frame::{HEADER_BYTES, KIND_CURVE, KIND_SURFACE, Layout};
use vsculpt_protocol::{FrameIcon, GeometryFrame};

fn uniform(n: usize, p: usize) -> Vec<f64> {
    let spans = n - p;
    let mut k = vec![0.0; p + 1];
    k.extend((1..spans).map(|i| i as f64 / spans as f64));
    k.extend(vec![1.0; p + 1]);
    k
}

fn frame(nu: usize, nv: usize, icons: usize) -> GeometryFrame {
    GeometryFrame {
        kind: KIND_SURFACE,
        design: 7,
        part: 42,
        revision: 123_456_789_012,
        flags: 1,
        degree_u: 3,
        degree_v: 3,
        nu: nu as u32,
        nv: nv as u32,
        knots_u: uniform(nu, 3),
        knots_v: uniform(nv, 3),
        points: (0..nu * nv)
            .map(|k| [k as f32, (k as f32).sin(), -0.5])
            .collect(),
        icons: (0..icons)
            .map(|k| FrameIcon {
                id: 1000 + k as u64,
                xyz: [k as f32, 1.0, 2.0],
            })
            .collect(),
    }
}

#[test]
fn round_trip_is_exact_and_layout_is_as_documented() {
    let f = frame(20, 15, 3);
    let bytes = f.encode().unwrap();
    assert_eq!(&bytes[0..4], b"VSGF");
    assert_eq!(bytes[4], 1);
    assert_eq!(bytes[5], 2);
    assert_eq!(u64::from_le_bytes(bytes[8..16].try_into().unwrap()), 7);
    assert_eq!(u64::from_le_bytes(bytes[16..24].try_into().unwrap()), 42);
    assert_eq!(
        u64::from_le_bytes(bytes[24..32].try_into().unwrap()),
        123_456_789_012
    );
    assert_eq!(u32::from_le_bytes(bytes[32..36].try_into().unwrap()), 20);
    assert_eq!(u32::from_le_bytes(bytes[36..40].try_into().unwrap()), 15);
    assert_eq!(u32::from_le_bytes(bytes[44..48].try_into().unwrap()), 3);
    assert_eq!(HEADER_BYTES, 48);
    let l = Layout::new(KIND_SURFACE, 20, 15, 3, 3, 3).unwrap();
    assert_eq!(l.knots_u, HEADER_BYTES);
    assert_eq!(l.points % 4, 0);
    assert_eq!(l.icons % 8, 0);
    assert_eq!(bytes.len(), l.total);
    // The first control point's y sits at points + 4.
    let y = f32::from_le_bytes(bytes[l.points + 16..l.points + 20].try_into().unwrap());
    assert_eq!(y, f.points[1][1]);
    assert_eq!(GeometryFrame::decode(&bytes).unwrap(), f);
}

#[test]
fn frame_sizes() {
    for (nu, nv) in [(20, 15), (38, 32), (42, 40), (91, 54), (81, 159)] {
        let bytes = frame(nu, nv, 6).encode().unwrap();
        // 4× control resolution tessellation, positions only, f32.
        let mesh = (4 * nu) * (4 * nv) * 12;
        println!(
            "{nu}×{nv}: frame {} bytes, tessellated positions {} bytes",
            bytes.len(),
            mesh
        );
        assert!(bytes.len() < mesh / 10);
    }
}

#[test]
fn every_truncation_and_corruption_is_an_error_not_a_panic() {
    let f = frame(6, 5, 2);
    let bytes = f.encode().unwrap();
    for len in 0..bytes.len() {
        assert!(
            GeometryFrame::decode(&bytes[..len]).is_err(),
            "truncated to {len}"
        );
    }
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(GeometryFrame::decode(&longer).is_err());
    // Non-finite control point.
    let mut nan = bytes.clone();
    let l = Layout::new(KIND_SURFACE, 6, 5, 3, 3, 2).unwrap();
    nan[l.points..l.points + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    assert!(GeometryFrame::decode(&nan).is_err());
    // Decreasing knots.
    let mut knots = bytes.clone();
    knots[l.knots_u + 8 * 5..l.knots_u + 8 * 6].copy_from_slice(&(-1.0f64).to_le_bytes());
    assert!(GeometryFrame::decode(&knots).is_err());
    // Huge sizes in the header must not allocate or panic.
    let mut huge = bytes.clone();
    huge[32..36].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(GeometryFrame::decode(&huge).is_err());
    // Pseudo-random byte strings and single-byte mutations.
    let mut x: u64 = 12345;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    for _ in 0..3000 {
        let n = (next() % 300) as usize;
        let soup: Vec<u8> = (0..n).map(|_| next() as u8).collect();
        assert!(GeometryFrame::decode(&soup).is_err());
        let mut m = bytes.clone();
        let i = (next() as usize) % m.len();
        m[i] ^= (next() as u8) | 1;
        let _ = GeometryFrame::decode(&m);
    }
}

#[test]
fn encode_refuses_inconsistent_frames() {
    let mut f = frame(6, 5, 0);
    f.points.pop();
    assert!(f.encode().is_err());
    let mut f = frame(6, 5, 0);
    f.points[0][2] = f32::INFINITY;
    assert!(f.encode().is_err());
    let mut f = frame(6, 5, 0);
    f.degree_u = 0;
    assert!(f.encode().is_err());
}

#[test]
fn with_flags_sets_bits_in_place_and_leaves_everything_else() {
    use vsculpt_protocol::frame::{FLAG_DRAG, FLAG_SNAPSHOT, with_flags};
    let mut f = frame(5, 4, 2);
    f.flags = FLAG_DRAG;
    let bytes = f.encode().unwrap();
    let flagged = with_flags(&bytes, FLAG_SNAPSHOT);
    // Only bytes 6–7 (the flags, little-endian) differ.
    assert_eq!(flagged.len(), bytes.len());
    for (k, (a, b)) in bytes.iter().zip(&flagged).enumerate() {
        if k != 6 {
            assert_eq!(a, b, "byte {k}");
        }
    }
    assert_eq!(
        u16::from_le_bytes([flagged[6], flagged[7]]),
        FLAG_DRAG | FLAG_SNAPSHOT
    );
    let back = GeometryFrame::decode(&flagged).unwrap();
    assert_eq!(back.flags, FLAG_DRAG | FLAG_SNAPSHOT);
    assert_eq!(back.points, f.points);
    // Bytes that are not a frame are copied unchanged.
    for junk in [
        &b"VSG"[..],
        &b"not a frame at all, but long enough to have a header"[..],
    ] {
        assert_eq!(with_flags(junk, FLAG_SNAPSHOT), junk);
    }
}

/// A curve frame written byte by byte from the table in protocol/README.md
/// (not with our encoder): a quadratic with 4 control points, knots
/// 0 0 0 .5 1 1 1, one icon.
fn curve_bytes_from_the_readme() -> Vec<u8> {
    let mut b = Vec::new();
    b.extend_from_slice(b"VSGF");
    b.push(2); // kind: curve
    b.push(2); // version
    b.extend_from_slice(&[1, 0]); // flags: drag
    b.extend_from_slice(&9u64.to_le_bytes()); // design
    b.extend_from_slice(&3u64.to_le_bytes()); // part
    b.extend_from_slice(&77u64.to_le_bytes()); // revision
    b.extend_from_slice(&4u32.to_le_bytes()); // nu
    b.extend_from_slice(&1u32.to_le_bytes()); // nv
    b.extend_from_slice(&[2, 0, 0, 0]); // pu, pv, zero
    b.extend_from_slice(&1u32.to_le_bytes()); // icons
    assert_eq!(b.len(), 48);
    for k in [0.0f64, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0] {
        b.extend_from_slice(&k.to_le_bytes());
    }
    // No v knots for a curve; control points at 48 + 56 = 104.
    for p in [
        [0.0f32, 0.0, 1.0],
        [1.0, 0.25, 1.0],
        [2.0, 0.0, 1.5],
        [3.0, 0.0, 1.0],
    ] {
        for c in p {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    // 104 + 48 = 152, already a multiple of 8.
    b.extend_from_slice(&7u64.to_le_bytes());
    for c in [1.5f32, 0.1, 1.2] {
        b.extend_from_slice(&c.to_le_bytes());
    }
    b.extend_from_slice(&[0; 4]);
    b
}

#[test]
fn a_curve_frame_from_the_documented_layout_decodes() {
    let bytes = curve_bytes_from_the_readme();
    let f = GeometryFrame::decode(&bytes).unwrap();
    assert_eq!(f.kind, KIND_CURVE);
    assert_eq!((f.design, f.part, f.revision, f.flags), (9, 3, 77, 1));
    assert_eq!((f.nu, f.nv, f.degree_u, f.degree_v), (4, 1, 2, 0));
    assert!(f.knots_v.is_empty());
    assert_eq!(f.points[2], [2.0, 0.0, 1.5]);
    assert_eq!(f.icons[0].id, 7);
    assert_eq!(f.icons[0].xyz, [1.5, 0.1, 1.2]);
    // Our encoder writes the same bytes.
    assert_eq!(f.encode().unwrap(), bytes);
    let l = Layout::new(KIND_CURVE, 4, 1, 2, 0, 1).unwrap();
    assert_eq!((l.points, l.icons, l.total), (104, 152, 176));
}

#[test]
fn a_curve_frame_with_v_knots_or_a_surface_shape_is_refused() {
    let bytes = curve_bytes_from_the_readme();
    // nv = 2 on a curve.
    let mut m = bytes.clone();
    m[36..40].copy_from_slice(&2u32.to_le_bytes());
    assert!(GeometryFrame::decode(&m).is_err());
    // A degree along v on a curve.
    let mut m = bytes.clone();
    m[41] = 1;
    assert!(GeometryFrame::decode(&m).is_err());
    // Unknown kind.
    let mut m = bytes.clone();
    m[4] = 3;
    assert!(GeometryFrame::decode(&m).is_err());
    // A version-1 frame.
    let mut m = bytes;
    m[5] = 1;
    let e = GeometryFrame::decode(&m).unwrap_err();
    assert_eq!(e.code, vsculpt_protocol::ErrorCode::BadVersion);
}

/// The documented zero bytes are zero: a frame with one set (header offset 42,
/// the padding before the icons, an icon record's last four bytes) is refused,
/// so a frame has exactly one encoding (found by `tests/fuzz.rs`).
#[test]
fn a_frame_whose_zero_bytes_are_not_zero_is_refused() {
    // 5 × 5 control points: 48 + 144 + 300 = 492 bytes, 4 bytes of padding before the icons.
    let f = frame(5, 5, 2);
    let bytes = f.encode().unwrap();
    assert_eq!(GeometryFrame::decode(&bytes).unwrap(), f);
    let icons_at = bytes.len() - 24 * 2;
    let knots = 8 * ((5 + 3 + 1) * 2);
    let padding = 48 + knots + 12 * 25;
    assert!(padding < icons_at, "the test frame has padding");
    for at in [
        42,
        43,
        padding,
        icons_at - 1,
        icons_at + 20,
        icons_at + 24 + 23,
    ] {
        let mut bad = bytes.clone();
        bad[at] = 1;
        let e = GeometryFrame::decode(&bad).unwrap_err();
        assert!(e.message.contains("zero"), "byte {at}: {e:?}");
    }
}
