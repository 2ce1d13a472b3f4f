//! Parts in test documents (protocol v2): a part of a snapshot or of a
//! stored document by id, the icons of a part, the demo's load icon, and
//! `part` added to an icon message. Snapshots list parts with their icons
//! and `shape`; the stored document (REST `design`) lists parts with a
//! `body` holding the shape, material and icons.

use serde_json::{Value, json};

/// The demo's top shell (the old one-surface demo), holding its four icons.
pub const SHELL: u64 = 1;
/// The demo's side panels, joined G1 to the shell's long edges.
pub const SIDES: [u64; 2] = [2, 3];
/// The demo's feature line, a curve part the shell follows.
pub const FEATURE_LINE: u64 = 4;
/// A one-part design's part (`create_design` makes a plate as part 1).
pub const PLATE: u64 = 1;

/// Part `id` of a snapshot (or `part_created`-like list under `parts`) or
/// of a stored document.
pub fn part(doc: &Value, id: u64) -> &Value {
    doc["parts"]
        .as_array()
        .unwrap_or_else(|| panic!("no parts in {doc}"))
        .iter()
        .find(|p| p["id"] == json!(id))
        .unwrap_or_else(|| panic!("no part {id} in {doc}"))
}

/// The ids of every part, in order.
pub fn part_ids(doc: &Value) -> Vec<u64> {
    doc["parts"]
        .as_array()
        .unwrap_or_else(|| panic!("no parts in {doc}"))
        .iter()
        .map(|p| p["id"].as_u64().unwrap())
        .collect()
}

/// A part's body: the part itself in a snapshot, its `body` in a stored
/// document (where shape, material and icons live).
fn body(p: &Value) -> &Value {
    if p.get("body").is_some() {
        &p["body"]
    } else {
        p
    }
}

/// The icons of part `id` (snapshot or stored document).
pub fn icons(doc: &Value, id: u64) -> &Vec<Value> {
    body(part(doc, id))["icons"]
        .as_array()
        .unwrap_or_else(|| panic!("no icons on part {id} in {doc}"))
}

/// The material of part `id` (snapshot or stored document).
pub fn material(doc: &Value, id: u64) -> &Value {
    &body(part(doc, id))["material"]
}

/// The surface of part `id`: the protocol's `shape.surface` in a snapshot,
/// the stored `body.surface` in a stored document.
pub fn surface(doc: &Value, id: u64) -> &Value {
    let p = part(doc, id);
    if p.get("body").is_some() {
        &p["body"]["surface"]
    } else {
        &p["shape"]["surface"]
    }
}

/// Icon `icon` of part `id`.
pub fn icon(doc: &Value, id: u64, icon: u64) -> &Value {
    icons(doc, id)
        .iter()
        .find(|i| i["id"] == json!(icon))
        .unwrap_or_else(|| panic!("no icon {icon} on part {id} in {doc}"))
}

/// The first icon of role `kind` on part `id`.
pub fn icon_of_role(doc: &Value, id: u64, kind: &str) -> Value {
    icons(doc, id)
        .iter()
        .find(|i| i["role"]["kind"] == kind)
        .cloned()
        .unwrap_or_else(|| panic!("no {kind} icon on part {id} in {doc}"))
}

/// The demo's load icon (on the top shell): its id and position.
pub fn load_icon(snapshot: &Value) -> (u64, [f64; 3]) {
    let i = icon_of_role(snapshot, SHELL, "load");
    (
        i["id"].as_u64().unwrap(),
        serde_json::from_value(i["xyz"].clone()).unwrap(),
    )
}

/// `msg` naming part `id` (every icon message and `set_material` carry it).
pub fn on_part(mut msg: Value, id: u64) -> Value {
    msg["part"] = json!(id);
    msg
}
