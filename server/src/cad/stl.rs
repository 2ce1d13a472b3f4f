//! Binary STL export of a tessellated surface: an 80-byte header, a
//! little-endian u32 triangle count, then per triangle a facet normal, three
//! vertices (12 f32) and a zero u16 attribute — 50 bytes per triangle.
//! [`write_stl_to`] streams into any writer; [`write_stl`] collects.

use super::mesh::Mesh;
use std::io::{self, Write};

/// Size of the binary STL header.
pub const STL_HEADER_LEN: usize = 80;
/// Size of one triangle record.
pub const STL_TRIANGLE_LEN: usize = 50;

/// Streams `mesh` as binary STL into `out`. Facet normals are the unit
/// right-hand normals of the triangles (zero for degenerate triangles, as
/// the format allows).
pub fn write_stl_to(mesh: &Mesh<'_>, name: &str, out: &mut impl Write) -> io::Result<()> {
    let count = mesh.triangle_count();
    let mut header = [b' '; STL_HEADER_LEN];
    // A header must not start with "solid" or readers take it for ASCII STL.
    let title = format!("vsculpt binary STL: {name}");
    for (h, b) in header.iter_mut().zip(title.bytes()) {
        *h = b;
    }
    out.write_all(&header)?;
    out.write_all(&(count as u32).to_le_bytes())?;
    let mut record = [0u8; STL_TRIANGLE_LEN];
    for t in 0..count {
        let [a, b, c] = mesh.triangle(t);
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let n = if len > 0.0 {
            [n[0] / len, n[1] / len, n[2] / len]
        } else {
            [0.0; 3]
        };
        for (k, x) in [n, a, b, c].iter().flatten().enumerate() {
            record[4 * k..4 * k + 4].copy_from_slice(&x.to_le_bytes());
        }
        out.write_all(&record)?;
    }
    Ok(())
}

/// Writes `mesh` as binary STL.
pub fn write_stl(mesh: &Mesh<'_>, name: &str) -> Vec<u8> {
    let mut out = Vec::with_capacity(STL_HEADER_LEN + 4 + STL_TRIANGLE_LEN * mesh.triangle_count());
    // Writing into a Vec cannot fail.
    let _ = write_stl_to(mesh, name, &mut out);
    out
}
