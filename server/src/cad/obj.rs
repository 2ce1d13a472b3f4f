//! Wavefront OBJ export of a tessellated surface: `v`, `vn` and `f v//vn`
//! records (1-based indices), readable by Blender, MeshLab and most viewers.
//! [`write_obj_to`] streams into any writer (the server's exports send it
//! chunk by chunk); [`write_obj`] collects it into a string.

use super::mesh::Mesh;
use std::io::{self, Write};

/// Streams `mesh` as OBJ text with one object named `name` into `out`.
pub fn write_obj_to(mesh: &Mesh<'_>, name: &str, out: &mut impl Write) -> io::Result<()> {
    let clean: String = name
        .chars()
        .map(|c| {
            if c.is_whitespace() || c.is_control() {
                '_'
            } else {
                c
            }
        })
        .collect();
    writeln!(out, "# vsculpt OBJ export")?;
    writeln!(
        out,
        "o {}",
        if clean.is_empty() { "surface" } else { &clean }
    )?;
    for p in mesh.positions() {
        writeln!(out, "v {} {} {}", p[0], p[1], p[2])?;
    }
    for n in mesh.normals() {
        writeln!(out, "vn {} {} {}", n[0], n[1], n[2])?;
    }
    for t in mesh.indices().chunks_exact(3) {
        let (a, b, c) = (t[0] + 1, t[1] + 1, t[2] + 1);
        writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}")?;
    }
    Ok(())
}

/// Writes `mesh` as an OBJ text with one object named `name`.
pub fn write_obj(mesh: &Mesh<'_>, name: &str) -> String {
    let mut out = Vec::with_capacity(64 * mesh.positions().len());
    // Writing into a Vec cannot fail, and every byte written is UTF-8.
    let _ = write_obj_to(mesh, name, &mut out);
    String::from_utf8(out).unwrap_or_default()
}
