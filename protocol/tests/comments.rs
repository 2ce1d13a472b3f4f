//! Review comments on the wire: every comment message survives a serialise
//! → parse round trip, and bad comments get the right code before they reach
//! a design (blank, too long, control characters, a lone u, no anchor, a
//! coordinate out of range).

use serde_json::json;
use vsculpt_protocol::limits::MAX_COMMENT_BYTES;
use vsculpt_protocol::{
    Access, ClientMessage, Comment, CommentAnchor, CommentReply, ErrorCode, ServerMessage,
    parse_client,
};

fn code(v: serde_json::Value) -> ErrorCode {
    parse_client(&v.to_string()).expect_err(&v.to_string()).code
}

fn add(anchor: serde_json::Value, text: &str) -> serde_json::Value {
    json!({"type": "add_comment", "req": 1, "part": 1, "anchor": anchor, "text": text})
}

#[test]
fn comment_messages_round_trip() {
    let msgs = [
        add(json!({"u": 0.25, "v": 0.75}), "softer here\nplease"),
        add(json!({"xyz": [1.5, -2.0, 3.25]}), "lower"),
        add(json!({"u": 0.0, "v": 1.0, "xyz": [0.0, 0.0, 0.0]}), "both"),
        json!({"type": "reply_comment", "comment": 7, "text": "done"}),
        json!({"type": "resolve_comment", "comment": 7, "resolved": false}),
        json!({"type": "delete_comment", "req": 3, "comment": 7}),
        json!({"type": "edit_comment", "req": 4, "comment": 7, "text": "softer,\nlike v3"}),
    ];
    for m in msgs {
        let env = parse_client(&m.to_string()).unwrap();
        let again = parse_client(&serde_json::to_string(&env).unwrap()).unwrap();
        assert_eq!(env, again);
        assert_eq!(serde_json::to_value(&env).unwrap(), m);
    }
    let env = parse_client(&add(json!({"u": 0.25, "v": 0.75}), "x").to_string()).unwrap();
    match env.msg {
        ClientMessage::AddComment { part, anchor, text } => {
            assert_eq!(part, 1);
            assert_eq!(anchor.uv(), Some((0.25, 0.75)));
            assert_eq!(anchor.xyz, None);
            assert_eq!(text, "x");
        }
        other => panic!("{other:?}"),
    }

    let comment = Comment {
        id: 12,
        part: 1,
        anchor: CommentAnchor {
            u: Some(0.5),
            v: Some(0.5),
            xyz: Some([0.1, 0.2, 0.3]),
        },
        text: "Softer?".into(),
        author: "Ben".into(),
        access: Access::Viewer,
        time_ms: 1_700_000_000_000,
        edited_ms: Some(1_700_000_000_500),
        version: 3,
        resolved: true,
        resolved_by: Some("Ana".into()),
        replies: vec![CommentReply {
            id: 13,
            text: "ok".into(),
            author: "Ana".into(),
            access: Access::Editor,
            time_ms: 1_700_000_000_001,
            edited_ms: None,
            version: 3,
        }],
    };
    for m in [
        ServerMessage::CommentAdded {
            comment: comment.clone(),
        },
        ServerMessage::CommentChanged { comment },
        ServerMessage::CommentDeleted { comment: 12 },
    ] {
        let text = serde_json::to_string(&m).unwrap();
        assert_eq!(serde_json::from_str::<ServerMessage>(&text).unwrap(), m);
    }
}

#[test]
fn a_snapshot_without_comments_still_parses() {
    // Servers before comments sent no `comments` field.
    let text = r#"{"type": "snapshot", "design": {"id": 1, "name": "d", "versions": 0}, "revision": 0,
        "parts": [], "relations": [], "versions": [], "presence": [], "can_undo": false, "can_redo": false}"#;
    match serde_json::from_str::<ServerMessage>(text).unwrap() {
        ServerMessage::Snapshot { comments, .. } => assert!(comments.is_empty()),
        other => panic!("{other:?}"),
    }
}

#[test]
fn bad_comments_are_refused_with_their_code() {
    assert_eq!(
        code(add(json!({"u": 0.5, "v": 0.5}), "")),
        ErrorCode::OutOfRange
    );
    assert_eq!(
        code(add(json!({"u": 0.5, "v": 0.5}), " \n\t ")),
        ErrorCode::OutOfRange
    );
    let long = "é".repeat(MAX_COMMENT_BYTES / 2 + 1);
    assert_eq!(
        code(add(json!({"u": 0.5, "v": 0.5}), &long)),
        ErrorCode::TooLarge
    );
    // Exactly at the limit is fine.
    let at_limit = "é".repeat(MAX_COMMENT_BYTES / 2);
    assert!(parse_client(&add(json!({"u": 0.5, "v": 0.5}), &at_limit).to_string()).is_ok());
    assert_eq!(
        code(add(json!({"u": 0.5, "v": 0.5}), "bell\u{7}")),
        ErrorCode::OutOfRange
    );
    assert_eq!(
        code(add(json!({"u": 0.5, "v": 0.5}), "esc\u{1b}[2J")),
        ErrorCode::OutOfRange
    );
    assert_eq!(code(add(json!({"u": 0.5}), "x")), ErrorCode::OutOfRange);
    assert_eq!(code(add(json!({}), "x")), ErrorCode::OutOfRange);
    assert_eq!(
        code(add(json!({"u": 1e10, "v": 0.5}), "x")),
        ErrorCode::OutOfRange
    );
    assert_eq!(
        code(add(json!({"xyz": [0.0, -2e9, 0.0]}), "x")),
        ErrorCode::OutOfRange
    );
    // Unknown anchor fields are malformed, not ignored.
    assert_eq!(
        code(add(json!({"u": 0.5, "v": 0.5, "w": 1.0}), "x")),
        ErrorCode::Malformed
    );
    assert_eq!(
        code(json!({"type": "reply_comment", "comment": 7, "text": ""})),
        ErrorCode::OutOfRange
    );
    assert_eq!(
        code(json!({"type": "resolve_comment", "comment": 7})),
        ErrorCode::Malformed
    );
    // An edit's text follows a new comment's rules; it names its comment.
    for (text, want) in [
        ("", ErrorCode::OutOfRange),
        (" \n\t", ErrorCode::OutOfRange),
        ("a\u{1b}[2J", ErrorCode::OutOfRange),
    ] {
        assert_eq!(
            code(json!({"type": "edit_comment", "comment": 7, "text": text})),
            want,
            "{text:?}"
        );
    }
    assert_eq!(
        code(json!({"type": "edit_comment", "comment": 7, "text": "é".repeat(2049)})),
        ErrorCode::TooLarge
    );
    assert!(
        parse_client(
            &json!({"type": "edit_comment", "comment": 7, "text": "é".repeat(2048)}).to_string()
        )
        .is_ok()
    );
    assert_eq!(
        code(json!({"type": "edit_comment", "text": "x"})),
        ErrorCode::Malformed
    );
    // Values built in memory (JSON cannot carry NaN) are checked too.
    let m = ClientMessage::AddComment {
        part: 1,
        anchor: CommentAnchor {
            u: Some(f64::NAN),
            v: Some(0.5),
            xyz: None,
        },
        text: "x".into(),
    };
    assert_eq!(m.validate().unwrap_err().code, ErrorCode::NotFinite);
    let m = ClientMessage::AddComment {
        part: 1,
        anchor: CommentAnchor {
            u: None,
            v: None,
            xyz: Some([0.0, f64::INFINITY, 0.0]),
        },
        text: "x".into(),
    };
    assert_eq!(m.validate().unwrap_err().code, ErrorCode::NotFinite);
}
