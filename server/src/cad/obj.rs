//! Wavefront OBJ export of a tessellated surface: `v`, `vn` and `f v//vn`
//! records (1-based indices), readable by Blender, MeshLab and most viewers.

use super::mesh::Mesh;
use std::fmt::Write;

/// Writes `mesh` as an OBJ text with one object named `name`.
pub fn write_obj(mesh: &Mesh<'_>, name: &str) -> String {
    let mut out = String::with_capacity(64 * mesh.positions().len());
    let clean: String = name
        .chars()
        .map(|c| if c.is_whitespace() { '_' } else { c })
        .collect();
    let _ = writeln!(out, "# vsculpt OBJ export");
    let _ = writeln!(
        out,
        "o {}",
        if clean.is_empty() { "surface" } else { &clean }
    );
    for p in mesh.positions() {
        let _ = writeln!(out, "v {} {} {}", p[0], p[1], p[2]);
    }
    for n in mesh.normals() {
        let _ = writeln!(out, "vn {} {} {}", n[0], n[1], n[2]);
    }
    for t in mesh.indices().chunks_exact(3) {
        let (a, b, c) = (t[0] + 1, t[1] + 1, t[2] + 1);
        let _ = writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    out
}
