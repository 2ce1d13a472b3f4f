//! Every JSON example in protocol/README.md parses as the message it claims
//! to be and survives a serialise → parse round trip, and every message type
//! has an example: the README and the code cannot drift apart.

mod common;

use vsculpt_protocol::client::CLIENT_TYPES;
use vsculpt_protocol::{ServerMessage, parse_client};

fn blocks(tag: &str) -> Vec<String> {
    common::readme_blocks(tag)
}

#[test]
fn every_client_example_parses_and_round_trips() {
    let examples = blocks("client");
    assert!(examples.len() >= CLIENT_TYPES.len());
    let mut seen = std::collections::BTreeSet::new();
    for text in examples {
        let msg = parse_client(&text).unwrap_or_else(|e| panic!("{text}: {e}"));
        let json = serde_json::to_string(&msg).unwrap();
        let again = parse_client(&json).unwrap();
        assert_eq!(msg, again);
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        seen.insert(v["type"].as_str().unwrap().to_string());
    }
    for t in CLIENT_TYPES {
        assert!(seen.contains(*t), "README has no example of {t}");
    }
}

#[test]
fn every_server_example_parses_and_round_trips() {
    let examples = blocks("server");
    let mut seen = std::collections::BTreeSet::new();
    for text in examples {
        let msg: ServerMessage =
            serde_json::from_str(&text).unwrap_or_else(|e| panic!("{text}: {e}"));
        let json = serde_json::to_string(&msg).unwrap();
        let again: ServerMessage = serde_json::from_str(&json).unwrap();
        assert_eq!(msg, again);
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        seen.insert(v["type"].as_str().unwrap().to_string());
    }
    for t in [
        "welcome",
        "ack",
        "error",
        "snapshot",
        "icon_created",
        "icon_updated",
        "icon_deleted",
        "material_changed",
        "committed",
        "versions",
        "designs",
        "design_created",
        "presence",
        "presence_changed",
        "presence_left",
        "icon_feedback",
        "history",
        "pong",
        "part_created",
        "part_deleted",
        "part_changed",
        "relation_created",
        "relation_deleted",
        "fairing_progress",
        "fairing_ended",
        "comment_added",
        "comment_changed",
        "comment_deleted",
    ] {
        assert!(seen.contains(t), "README has no example of {t}");
    }
}
