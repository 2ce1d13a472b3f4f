//! Binary STL export of a tessellated surface: an 80-byte header, a
//! little-endian u32 triangle count, then per triangle a facet normal, three
//! vertices (12 f32) and a zero u16 attribute — 50 bytes per triangle.

use super::mesh::Mesh;

/// Size of the binary STL header.
pub const STL_HEADER_LEN: usize = 80;
/// Size of one triangle record.
pub const STL_TRIANGLE_LEN: usize = 50;

/// Writes `mesh` as binary STL. Facet normals are the unit right-hand normals
/// of the triangles (zero for degenerate triangles, as the format allows).
pub fn write_stl(mesh: &Mesh<'_>, name: &str) -> Vec<u8> {
    let count = mesh.triangle_count();
    let mut out = Vec::with_capacity(STL_HEADER_LEN + 4 + STL_TRIANGLE_LEN * count);
    let mut header = [b' '; STL_HEADER_LEN];
    // A header must not start with "solid" or readers take it for ASCII STL.
    let title = format!("vsculpt binary STL: {name}");
    for (h, b) in header.iter_mut().zip(title.bytes()) {
        *h = b;
    }
    out.extend_from_slice(&header);
    out.extend_from_slice(&(count as u32).to_le_bytes());
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
        for v in [n, a, b, c] {
            for x in v {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        out.extend_from_slice(&0u16.to_le_bytes());
    }
    out
}
