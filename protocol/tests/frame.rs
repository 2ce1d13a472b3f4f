//! The binary geometry frame: exact round trip, the documented layout, and
//! an error (never a panic) for every other byte string.

use vsculpt_protocol::frame::{HEADER_BYTES, Layout};
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
        design: 7,
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
    assert_eq!(u64::from_le_bytes(bytes[8..16].try_into().unwrap()), 7);
    assert_eq!(u32::from_le_bytes(bytes[24..28].try_into().unwrap()), 20);
    let l = Layout::new(20, 15, 3, 3, 3).unwrap();
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
    let l = Layout::new(6, 5, 3, 3, 2).unwrap();
    nan[l.points..l.points + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    assert!(GeometryFrame::decode(&nan).is_err());
    // Decreasing knots.
    let mut knots = bytes.clone();
    knots[l.knots_u + 8 * 5..l.knots_u + 8 * 6].copy_from_slice(&(-1.0f64).to_le_bytes());
    assert!(GeometryFrame::decode(&knots).is_err());
    // Huge sizes in the header must not allocate or panic.
    let mut huge = bytes.clone();
    huge[24..28].copy_from_slice(&u32::MAX.to_le_bytes());
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
