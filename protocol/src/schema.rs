//! The machine-readable message reference: a JSON Schema (draft 2020-12)
//! of every client and server message, generated from the types so it
//! cannot drift from them. The checked-in copy is
//! `protocol/schema/protocol.schema.json`; `tests/schema.rs` regenerates
//! it and fails when the two differ.

use schemars::generate::SchemaSettings;
use serde_json::{Value, json};

use crate::client::ClientEnvelope;
use crate::server::ServerMessage;
use crate::version::PROTOCOL_VERSION;

/// Name of the definition every client → server message matches.
pub const CLIENT_DEF: &str = "ClientEnvelope";
/// Name of the definition every server → client message matches.
pub const SERVER_DEF: &str = "ServerMessage";

/// The JSON Schema of the protocol: `$defs` holds every message and value
/// type; a message is valid when it matches `$defs/ClientEnvelope` (client
/// → server) or `$defs/ServerMessage` (server → client).
pub fn protocol_schema() -> Value {
    let mut generator = SchemaSettings::draft2020_12().into_generator();
    generator.subschema_for::<ClientEnvelope>();
    generator.subschema_for::<ServerMessage>();
    let defs = generator.take_definitions(true);
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": format!("https://vsculpt.invalid/protocol/v{PROTOCOL_VERSION}.schema.json"),
        "title": format!("vsculpt protocol version {PROTOCOL_VERSION}"),
        "description": "Every JSON text message on /ws. Client → server messages match \
            $defs/ClientEnvelope, server → client messages match $defs/ServerMessage. \
            Generated from the vsculpt-protocol types; protocol/README.md explains them.",
        "anyOf": [
            {"$ref": format!("#/$defs/{CLIENT_DEF}")},
            {"$ref": format!("#/$defs/{SERVER_DEF}")}
        ],
        "$defs": defs,
    })
}

/// The schema of one direction: the protocol schema whose root is
/// `$defs/<def>` ([`CLIENT_DEF`] or [`SERVER_DEF`]).
pub fn direction_schema(def: &str) -> Value {
    let mut schema = protocol_schema();
    schema["anyOf"] = json!([{ "$ref": format!("#/$defs/{def}") }]);
    schema
}

/// The `type` tags the schema allows in `$defs/<def>`, in schema order.
pub fn message_types(schema: &Value, def: &str) -> Vec<String> {
    let mut out = Vec::new();
    collect_type_consts(&schema["$defs"][def], &mut out);
    out
}

fn collect_type_consts(v: &Value, out: &mut Vec<String>) {
    match v {
        Value::Object(map) => {
            if let Some(t) = map
                .get("properties")
                .and_then(|p| p.get("type"))
                .and_then(|t| t.get("const"))
                .and_then(Value::as_str)
            {
                out.push(t.to_string());
            }
            for (k, child) in map {
                if k != "properties" {
                    collect_type_consts(child, out);
                }
            }
        }
        Value::Array(items) => items.iter().for_each(|c| collect_type_consts(c, out)),
        _ => {}
    }
}
