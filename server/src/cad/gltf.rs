//! glTF 2.0 export of a tessellated surface as one self-contained `.gltf`
//! JSON file: a single buffer (positions, normals, u32 indices) embedded as a
//! base64 data URI, three accessors, one mesh, one node, one scene.
//! [`write_gltf_to`] streams the buffer through a base64 encoder into any
//! writer, so the binary buffer is never held whole; [`write_gltf`] collects.

use super::mesh::Mesh;
use base64::write::EncoderWriter;
use serde_json::json;
use std::io::{self, Write};

/// glTF `ARRAY_BUFFER` target.
const ARRAY_BUFFER: u32 = 34962;
/// glTF `ELEMENT_ARRAY_BUFFER` target.
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
/// glTF component type FLOAT.
const FLOAT: u32 = 5126;
/// glTF component type UNSIGNED_INT.
const UNSIGNED_INT: u32 = 5125;

/// Streams `mesh` as a glTF 2.0 JSON document with an embedded buffer.
pub fn write_gltf_to(mesh: &Mesh<'_>, name: &str, out: &mut impl Write) -> io::Result<()> {
    let n = mesh.positions().len();
    let m = mesh.indices().len();
    let byte_length = 24 * n + 4 * m;
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for p in mesh.positions() {
        for k in 0..3 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    if n == 0 {
        min = [0.0; 3];
        max = [0.0; 3];
    }
    let rest = json!({
        "asset": { "version": "2.0", "generator": "vsculpt-server" },
        "scene": 0,
        "scenes": [ { "nodes": [0] } ],
        "nodes": [ { "mesh": 0, "name": name } ],
        "meshes": [ {
            "name": name,
            "primitives": [ {
                "attributes": { "POSITION": 0, "NORMAL": 1 },
                "indices": 2,
                "mode": 4
            } ]
        } ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 12 * n, "target": ARRAY_BUFFER },
            { "buffer": 0, "byteOffset": 12 * n, "byteLength": 12 * n, "target": ARRAY_BUFFER },
            { "buffer": 0, "byteOffset": 24 * n, "byteLength": 4 * m, "target": ELEMENT_ARRAY_BUFFER }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": FLOAT, "count": n, "type": "VEC3", "min": min, "max": max },
            { "bufferView": 1, "componentType": FLOAT, "count": n, "type": "VEC3" },
            { "bufferView": 2, "componentType": UNSIGNED_INT, "count": m, "type": "SCALAR" }
        ]
    })
    .to_string();
    // `rest` is a non-empty JSON object: "{…}". The buffer member goes
    // first, its base64 text streamed, then the other members.
    write!(
        out,
        "{{\"buffers\":[{{\"byteLength\":{byte_length},\"uri\":\"data:application/octet-stream;base64,"
    )?;
    {
        let mut enc = EncoderWriter::new(&mut *out, &base64::engine::general_purpose::STANDARD);
        for p in mesh.positions().iter().chain(mesh.normals()) {
            for x in p {
                enc.write_all(&x.to_le_bytes())?;
            }
        }
        for i in mesh.indices() {
            enc.write_all(&i.to_le_bytes())?;
        }
        enc.finish()?;
    }
    write!(out, "\"}}],{}", &rest[1..])
}

/// Writes `mesh` as a glTF 2.0 JSON document with an embedded buffer.
pub fn write_gltf(mesh: &Mesh<'_>, name: &str) -> String {
    let mut out = Vec::new();
    // Writing into a Vec cannot fail, and every byte written is UTF-8.
    let _ = write_gltf_to(mesh, name, &mut out);
    String::from_utf8(out).unwrap_or_default()
}
