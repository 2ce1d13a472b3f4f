//! Untrusted text gets the right error code and never a panic.

use vsculpt_protocol::{ClientMessage, ErrorCode, parse_client};

fn code(text: &str) -> ErrorCode {
    parse_client(text).expect_err(text).code
}

#[test]
fn malformed_and_unknown_are_told_apart() {
    assert_eq!(code("not json"), ErrorCode::Malformed);
    assert_eq!(code("[1,2]"), ErrorCode::Malformed);
    assert_eq!(code(r#"{"icon": 3}"#), ErrorCode::Malformed);
    assert_eq!(code(r#"{"type": 7}"#), ErrorCode::Malformed);
    assert_eq!(code(r#"{"type": "explode"}"#), ErrorCode::UnknownMessage);
    // Right type, wrong field types or missing fields.
    assert_eq!(
        code(r#"{"type": "move_icon", "icon": "three", "xyz": [0,0,0]}"#),
        ErrorCode::Malformed
    );
    assert_eq!(
        code(r#"{"type": "move_icon", "icon": 3}"#),
        ErrorCode::Malformed
    );
    assert_eq!(
        code(r#"{"type": "move_icon", "icon": 3, "xyz": [0,0]}"#),
        ErrorCode::Malformed
    );
    assert_eq!(
        code(r#"{"type": "set_state", "part": 1, "icon": 3, "state": "asleep"}"#),
        ErrorCode::Malformed
    );
    assert_eq!(
        code(r#"{"type": "move_icon", "icon": -1, "xyz": [0,0,0]}"#),
        ErrorCode::Malformed
    );
}

#[test]
fn non_finite_and_out_of_range_numbers_are_refused() {
    // JSON has no NaN; overflowing literals are refused by the parser.
    assert_eq!(
        code(r#"{"type": "drag", "part": 1, "icon": 1, "xyz": [1e999, 0, 0]}"#),
        ErrorCode::Malformed
    );
    assert_eq!(
        code(r#"{"type": "drag", "part": 1, "icon": 1, "xyz": [NaN, 0, 0]}"#),
        ErrorCode::Malformed
    );
    assert_eq!(
        code(r#"{"type": "drag", "part": 1, "icon": 1, "xyz": [1e12, 0, 0]}"#),
        ErrorCode::OutOfRange
    );
    // Values built in memory are checked by validate().
    let m = ClientMessage::Drag {
        part: 1,
        icon: 1,
        xyz: [f64::NAN, 0.0, 0.0],
    };
    assert_eq!(m.validate().unwrap_err().code, ErrorCode::NotFinite);
    let m = ClientMessage::MoveIcon {
        part: 1,
        icon: 1,
        xyz: [0.0, f64::INFINITY, 0.0],
    };
    assert_eq!(m.validate().unwrap_err().code, ErrorCode::NotFinite);
    let bad_quat = r#"{"type": "device_sample", "sensor": "h", "position": [0,0,0], "orientation": [2,0,0,0], "time_us": 1}"#;
    assert_eq!(code(bad_quat), ErrorCode::OutOfRange);
    let neg = r#"{"type": "set_material", "part": 1, "material": {"alpha11": -1, "alpha12": 0, "alpha22": 0, "beta11": 1, "beta12": 1, "beta22": 1}}"#;
    assert_eq!(code(neg), ErrorCode::OutOfRange);
}

#[test]
fn oversized_messages_and_strings_are_refused() {
    let big = format!(
        r#"{{"type": "commit", "message": "{}"}}"#,
        "x".repeat(300 * 1024)
    );
    assert_eq!(code(&big), ErrorCode::TooLarge);
    let long = format!(r#"{{"type": "commit", "message": "{}"}}"#, "x".repeat(2000));
    assert_eq!(code(&long), ErrorCode::TooLarge);
    let empty = r#"{"type": "bind_sensor", "part": 1, "icon": 1, "sensor": "  "}"#;
    assert_eq!(code(empty), ErrorCode::OutOfRange);
}

#[test]
fn request_numbers_are_kept() {
    let env = parse_client(r#"{"type": "undo", "req": 42}"#).unwrap();
    assert_eq!(env.req, Some(42));
    assert_eq!(env.msg, ClientMessage::Undo);
    let env = parse_client(r#"{"type": "undo"}"#).unwrap();
    assert_eq!(env.req, None);
}

#[test]
fn arbitrary_text_never_panics() {
    // Deterministic pseudo-random byte soup, and mutations of a valid message.
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let valid = r#"{"type": "create_icon", "req": 1, "part": 1, "spec": {"anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "load"}}}"#;
    for _ in 0..5000 {
        let mut bytes = valid.as_bytes().to_vec();
        for _ in 0..(next() % 4 + 1) {
            let i = (next() as usize) % bytes.len();
            bytes[i] = (next() % 128) as u8;
        }
        if let Ok(text) = std::str::from_utf8(&bytes) {
            let _ = parse_client(text);
        }
        let soup: String = (0..(next() % 64))
            .map(|_| (next() % 95 + 32) as u8 as char)
            .collect();
        assert!(parse_client(&soup).is_err() || soup.contains("type"));
    }
}

#[test]
fn a_presence_camera_must_be_a_camera() {
    let ok =
        r#"{"type": "presence", "camera": {"eye": [3, -3, 3], "target": [0, 0, 0], "fov": 45}}"#;
    let env = parse_client(ok).expect("a camera");
    match env.msg {
        ClientMessage::Presence {
            pointer: None,
            camera: Some(c),
        } => {
            assert_eq!(c.eye, [3.0, -3.0, 3.0]);
            assert_eq!(c.fov, 45.0);
        }
        m => panic!("{m:?}"),
    }
    // The eye at the target, a field of view no camera has, a far-away eye, unknown fields.
    let at_target =
        r#"{"type": "presence", "camera": {"eye": [1, 2, 3], "target": [1, 2, 3], "fov": 45}}"#;
    assert_eq!(code(at_target), ErrorCode::OutOfRange);
    for fov in ["0", "180", "-10", "400"] {
        let t = format!(
            r#"{{"type": "presence", "camera": {{"eye": [3, 0, 0], "target": [0, 0, 0], "fov": {fov}}}}}"#
        );
        assert_eq!(code(&t), ErrorCode::OutOfRange, "{fov}");
    }
    let far =
        r#"{"type": "presence", "camera": {"eye": [1e12, 0, 0], "target": [0, 0, 0], "fov": 45}}"#;
    assert_eq!(code(far), ErrorCode::OutOfRange);
    let extra = r#"{"type": "presence", "camera": {"eye": [3, 0, 0], "target": [0, 0, 0], "fov": 45, "roll": 1}}"#;
    assert_eq!(code(extra), ErrorCode::Malformed);
    let m = ClientMessage::Presence {
        pointer: None,
        camera: Some(vsculpt_protocol::Camera {
            eye: [f64::NAN, 0.0, 0.0],
            target: [0.0; 3],
            fov: 45.0,
        }),
    };
    assert_eq!(m.validate().unwrap_err().code, ErrorCode::NotFinite);
}
