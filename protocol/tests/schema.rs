//! The JSON Schema generated from the types is the checked-in
//! `protocol/schema/protocol.schema.json`; every JSON example in
//! protocol/README.md validates against it (with an independent validator,
//! the `jsonschema` crate); every message type the schema knows has an
//! example in the README, and every error code is documented there.
//!
//! Refresh the checked-in schema after changing a message type with
//! `VSCULPT_UPDATE_SCHEMA=1 cargo test -p vsculpt-protocol --test schema`.

mod common;

use std::collections::BTreeSet;

use common::readme_blocks;
use serde_json::{Value, json};
use vsculpt_protocol::client::CLIENT_TYPES;
use vsculpt_protocol::schema::{
    CLIENT_DEF, SERVER_DEF, direction_schema, message_types, protocol_schema,
};

const SCHEMA_PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/schema/protocol.schema.json");

fn generated_text() -> String {
    serde_json::to_string_pretty(&protocol_schema()).unwrap() + "\n"
}

#[test]
fn checked_in_schema_matches_the_types() {
    let generated = generated_text();
    if std::env::var_os("VSCULPT_UPDATE_SCHEMA").is_some() {
        std::fs::write(SCHEMA_PATH, &generated).unwrap();
    }
    let on_disk = std::fs::read_to_string(SCHEMA_PATH).unwrap_or_default();
    assert!(
        on_disk == generated,
        "protocol/schema/protocol.schema.json differs from the types; refresh it with \
         `VSCULPT_UPDATE_SCHEMA=1 cargo test -p vsculpt-protocol --test schema` and commit it"
    );
}

#[test]
fn the_schema_is_a_valid_draft_2020_12_schema() {
    let schema: Value = serde_json::from_str(&generated_text()).unwrap();
    jsonschema::meta::validate(&schema).unwrap();
}

fn validator(def: &str) -> jsonschema::Validator {
    jsonschema::draft202012::new(&direction_schema(def)).unwrap()
}

fn check_examples(tag: &str, def: &str) -> BTreeSet<String> {
    let v = validator(def);
    let mut seen = BTreeSet::new();
    let examples = readme_blocks(tag);
    assert!(!examples.is_empty());
    for text in examples {
        let instance: Value = serde_json::from_str(&text).unwrap();
        let errors: Vec<String> = v
            .iter_errors(&instance)
            .map(|e| format!("{} at {}", e, e.instance_path()))
            .collect();
        assert!(
            errors.is_empty(),
            "{text}\ndoes not match {def}: {errors:#?}"
        );
        seen.insert(instance["type"].as_str().unwrap().to_string());
    }
    seen
}

#[test]
fn every_client_example_validates_and_every_client_type_has_one() {
    let seen = check_examples("client", CLIENT_DEF);
    let types = message_types(&protocol_schema(), CLIENT_DEF);
    let in_schema: BTreeSet<String> = types.iter().cloned().collect();
    let in_code: BTreeSet<String> = CLIENT_TYPES.iter().map(|t| t.to_string()).collect();
    assert_eq!(in_schema, in_code, "schema and CLIENT_TYPES disagree");
    for t in &types {
        assert!(
            seen.contains(t),
            "README has no `json client` example of {t}"
        );
    }
    assert!(
        seen.is_subset(&in_schema),
        "README examples of unknown types"
    );
}

#[test]
fn every_server_example_validates_and_every_server_type_has_one() {
    let seen = check_examples("server", SERVER_DEF);
    let types = message_types(&protocol_schema(), SERVER_DEF);
    assert!(types.len() >= 20, "{types:?}");
    for t in &types {
        assert!(
            seen.contains(t),
            "README has no `json server` example of {t}"
        );
    }
    let in_schema: BTreeSet<String> = types.into_iter().collect();
    assert!(
        seen.is_subset(&in_schema),
        "README examples of unknown types"
    );
}

#[test]
fn every_error_code_in_the_schema_is_documented() {
    let schema = protocol_schema();
    let codes = error_codes(&schema["$defs"]["ErrorCode"]);
    assert!(codes.len() >= 20, "{codes:?}");
    let readme = include_str!("../README.md");
    for code in codes {
        assert!(
            readme.contains(&format!("`{code}`")),
            "error code {code} is not documented in protocol/README.md"
        );
    }
}

fn error_codes(def: &Value) -> Vec<String> {
    if let Some(list) = def["enum"].as_array() {
        return list
            .iter()
            .filter_map(|c| c.as_str().map(String::from))
            .collect();
    }
    def["oneOf"]
        .as_array()
        .into_iter()
        .flatten()
        .flat_map(|alt| {
            alt["const"]
                .as_str()
                .map(|c| vec![c.to_string()])
                .unwrap_or_else(|| error_codes(alt))
        })
        .collect()
}

/// The validator is not a rubber stamp: messages the decoder refuses for
/// their shape are refused by the schema too.
#[test]
fn the_schema_refuses_what_the_decoder_refuses() {
    let client = validator(CLIENT_DEF);
    for bad in [
        json!({"type": "hello", "protocol": 2, "design": 1}),
        json!({"type": "no_such_message"}),
        json!({"type": "drag", "part": 1, "icon": 3, "xyz": [1, 2]}),
        json!({"type": "create_icon", "part": 1, "spec": {"anchor": {"kind": "point", "u": 0.5}, "role": {"kind": "load"}}}),
        json!({"type": "set_state", "part": 1, "icon": 3, "state": "asleep"}),
        json!({"type": "ping", "req": -1}),
    ] {
        assert!(
            vsculpt_protocol::parse_client(&bad.to_string()).is_err(),
            "decoder takes {bad}"
        );
        assert!(!client.is_valid(&bad), "schema takes {bad}");
    }
    let server = validator(SERVER_DEF);
    for bad in [
        json!({"type": "error", "code": "no_such_code", "message": "x"}),
        json!({"type": "welcome", "client_id": 4, "access": "editor", "design": 1}),
    ] {
        assert!(!server.is_valid(&bad), "schema takes {bad}");
    }
}
