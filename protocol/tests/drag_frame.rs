//! The drag stream's messages (drag basis, kind 5; drag frame, kind 6)
//! against bytes built by hand here from the layout in protocol/README.md
//! (not by our encoder), round trips, refusals of corrupt messages, and the
//! net a client computes from them.

use vsculpt_protocol::ErrorCode;
use vsculpt_protocol::drag_frame::{DragBasis, DragFrame, KIND_DRAG_BASIS, KIND_DRAG_FRAME};
use vsculpt_protocol::frame::FrameIcon;

/// A basis of 3 control points: design 7, part 9, basis 5, reference 300,
/// ρ = (1, 0.5, -2), written byte by byte.
fn hand_basis() -> Vec<u8> {
    let mut b: Vec<u8> = Vec::new();
    b.extend_from_slice(b"VSGF");
    b.push(5); // kind
    b.push(2); // version
    b.extend_from_slice(&[0, 0]); // zero
    b.extend_from_slice(&[7, 0, 0, 0, 0, 0, 0, 0]); // design
    b.extend_from_slice(&[9, 0, 0, 0, 0, 0, 0, 0]); // part
    b.extend_from_slice(&[5, 0, 0, 0, 0, 0, 0, 0]); // basis id
    b.extend_from_slice(&[0x2c, 0x01, 0, 0, 0, 0, 0, 0]); // reference 300
    b.extend_from_slice(&[3, 0, 0, 0]); // n
    b.extend_from_slice(&[0; 4]);
    assert_eq!(b.len(), 48);
    // 1.0, 0.5, -2.0 as IEEE-754 single bit patterns.
    b.extend_from_slice(&[0x00, 0x00, 0x80, 0x3f]);
    b.extend_from_slice(&[0x00, 0x00, 0x00, 0x3f]);
    b.extend_from_slice(&[0x00, 0x00, 0x00, 0xc0]);
    b
}

/// A drag frame: design 7, part 9, revision 301, basis 5, d = (2, -0.5, 0),
/// one icon 11 at (1, 2, 3).
fn hand_frame() -> Vec<u8> {
    let mut b: Vec<u8> = Vec::new();
    b.extend_from_slice(b"VSGF");
    b.push(6); // kind
    b.push(2); // version
    b.extend_from_slice(&[1, 0]); // flags = drag
    b.extend_from_slice(&[7, 0, 0, 0, 0, 0, 0, 0]);
    b.extend_from_slice(&[9, 0, 0, 0, 0, 0, 0, 0]);
    b.extend_from_slice(&[0x2d, 0x01, 0, 0, 0, 0, 0, 0]); // revision 301
    b.extend_from_slice(&[5, 0, 0, 0, 0, 0, 0, 0]); // basis 5
    // 2.0, -0.5, 0.0 as IEEE-754 double bit patterns.
    b.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0x00, 0x40]);
    b.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0xe0, 0xbf]);
    b.extend_from_slice(&[0; 8]);
    b.extend_from_slice(&[1, 0, 0, 0]); // m
    b.extend_from_slice(&[0; 4]);
    assert_eq!(b.len(), 72);
    b.extend_from_slice(&[11, 0, 0, 0, 0, 0, 0, 0]);
    b.extend_from_slice(&[0x00, 0x00, 0x80, 0x3f]); // 1
    b.extend_from_slice(&[0x00, 0x00, 0x00, 0x40]); // 2
    b.extend_from_slice(&[0x00, 0x00, 0x40, 0x40]); // 3
    b.extend_from_slice(&[0; 4]);
    b
}

#[test]
fn hand_built_basis_decodes_and_reencodes_to_the_same_bytes() {
    let bytes = hand_basis();
    let b = DragBasis::decode(&bytes).expect("decodes");
    assert_eq!(
        b,
        DragBasis {
            design: 7,
            part: 9,
            basis: 5,
            reference: 300,
            rho: vec![1.0, 0.5, -2.0],
        }
    );
    assert_eq!(b.encode().unwrap(), bytes);
    assert_eq!(bytes[4], KIND_DRAG_BASIS);
}

#[test]
fn hand_built_drag_frame_decodes_and_reencodes_to_the_same_bytes() {
    let bytes = hand_frame();
    let f = DragFrame::decode(&bytes).expect("decodes");
    assert_eq!(
        f,
        DragFrame {
            design: 7,
            part: 9,
            revision: 301,
            basis: 5,
            d: [2.0, -0.5, 0.0],
            icons: vec![FrameIcon {
                id: 11,
                xyz: [1.0, 2.0, 3.0]
            }],
        }
    );
    assert_eq!(f.encode().unwrap(), bytes);
    assert_eq!(bytes[4], KIND_DRAG_FRAME);
}

#[test]
fn a_client_net_is_reference_plus_rho_times_d() {
    let b = DragBasis::decode(&hand_basis()).unwrap();
    let f = DragFrame::decode(&hand_frame()).unwrap();
    let reference = [[0.0f32, 0.0, 0.0], [1.0, 1.0, 1.0], [10.0, -1.0, 0.25]];
    let net = f.apply(&reference, &b.rho).unwrap();
    assert_eq!(
        net,
        vec![
            [2.0, -0.5, 0.0],
            [2.0, 0.75, 1.0],
            [6.0, 0.0, 0.25], // ρ = -2: 10 − 4, −1 + 1, 0.25
        ]
    );
    assert!(f.apply(&reference[..2], &b.rho).is_none());
}

#[test]
fn corrupt_messages_are_refused_with_a_code() {
    let basis = hand_basis();
    let frame = hand_frame();
    let code = |r: Result<(), vsculpt_protocol::ProtocolError>| r.unwrap_err().code;
    let basis_err = |b: &[u8]| code(DragBasis::decode(b).map(|_| ()));
    let frame_err = |b: &[u8]| code(DragFrame::decode(b).map(|_| ()));
    // Truncated, one byte too many, any prefix.
    assert_eq!(basis_err(&basis[..basis.len() - 1]), ErrorCode::Malformed);
    assert_eq!(frame_err(&frame[..frame.len() - 1]), ErrorCode::Malformed);
    let mut longer = basis.clone();
    longer.push(0);
    assert_eq!(basis_err(&longer), ErrorCode::Malformed);
    for n in 0..basis.len() {
        assert!(DragBasis::decode(&basis[..n]).is_err());
    }
    for n in 0..frame.len() {
        assert!(DragFrame::decode(&frame[..n]).is_err());
    }
    // Wrong kind (each decoder refuses the other's), magic, version.
    assert_eq!(basis_err(&frame), ErrorCode::Malformed);
    assert_eq!(frame_err(&basis), ErrorCode::Malformed);
    let mut b = basis.clone();
    b[0] = b'X';
    assert_eq!(basis_err(&b), ErrorCode::Malformed);
    let mut b = frame.clone();
    b[5] = 1;
    assert_eq!(frame_err(&b), ErrorCode::BadVersion);
    // Non-zero reserved bytes.
    let mut b = basis.clone();
    b[44] = 1;
    assert_eq!(basis_err(&b), ErrorCode::Malformed);
    let mut b = frame.clone();
    b[72 + 20] = 1;
    assert_eq!(frame_err(&b), ErrorCode::Malformed);
    // NaN in ρ and in d; a count beyond the limits.
    let mut b = basis.clone();
    b[48..52].copy_from_slice(&f32::NAN.to_le_bytes());
    assert_eq!(basis_err(&b), ErrorCode::NotFinite);
    let mut b = frame.clone();
    b[40..48].copy_from_slice(&f64::INFINITY.to_le_bytes());
    assert_eq!(frame_err(&b), ErrorCode::NotFinite);
    let mut b = basis.clone();
    b[40..44].copy_from_slice(&u32::MAX.to_le_bytes());
    assert_eq!(basis_err(&b), ErrorCode::TooLarge);
    let mut b = frame.clone();
    b[64..68].copy_from_slice(&u32::MAX.to_le_bytes());
    assert_eq!(frame_err(&b), ErrorCode::TooLarge);
}

#[test]
fn sizes_of_the_stream_for_the_largest_demo_net() {
    // 81 × 159: the basis once per grab, then a frame per drag step.
    let n = 81 * 159;
    let basis = DragBasis {
        design: 1,
        part: 1,
        basis: 1,
        reference: 1,
        rho: vec![0.5; n],
    };
    assert_eq!(basis.encode().unwrap().len(), 48 + 4 * n);
    let icons = (0..6).map(|id| FrameIcon { id, xyz: [0.0; 3] }).collect();
    let frame = DragFrame {
        design: 1,
        part: 1,
        revision: 2,
        basis: 1,
        d: [0.0; 3],
        icons,
    };
    assert_eq!(frame.encode().unwrap().len(), 72 + 24 * 6);
}
