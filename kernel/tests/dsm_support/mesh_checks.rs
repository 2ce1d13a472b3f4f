//! Checks of a mesh's topology and triangle shape shared by the mesh tests.

use glam::DVec3;
use std::collections::HashMap;
use vsculpt_kernel::dsm::{GeometricPrimitive, Mesh};

/// Every undirected edge is used by exactly two triangles, once in each direction
/// (closed, oriented), and every vertex's triangles form one fan (vertex-manifold).
pub fn assert_closed_manifold(m: &Mesh) {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &m.triangles {
        assert!(
            t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
            "repeated vertex in {t:?}"
        );
        for i in 0..3 {
            *directed.entry((t[i], t[(i + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "directed edge {a}->{b} used {n} times");
        assert_eq!(
            directed.get(&(b, a)),
            Some(&1),
            "edge {a}-{b} is a border or non-manifold"
        );
    }
    // Vertex fans: the link of each vertex is one cycle.
    let mut next: HashMap<u32, HashMap<u32, u32>> = HashMap::new();
    for t in &m.triangles {
        for i in 0..3 {
            next.entry(t[i])
                .or_default()
                .insert(t[(i + 1) % 3], t[(i + 2) % 3]);
        }
    }
    for (v, link) in &next {
        let start = *link.keys().next().unwrap();
        let mut cur = start;
        let mut steps = 0;
        loop {
            cur = link[&cur];
            steps += 1;
            if cur == start {
                break;
            }
            assert!(steps <= link.len(), "vertex {v}: link is not a cycle");
        }
        assert_eq!(
            steps,
            link.len(),
            "vertex {v}: link has {} edges in more than one cycle",
            link.len()
        );
    }
}

/// The smallest triangle quality 4√3 · area / Σ edge² (1 equilateral, 0 degenerate).
pub fn min_triangle_quality(m: &Mesh) -> f64 {
    // 4√3 · area / Σ edge² : 1 for equilateral, 0 for degenerate.
    m.triangles
        .iter()
        .map(|t| {
            let (a, b, c) = (
                m.positions[t[0] as usize],
                m.positions[t[1] as usize],
                m.positions[t[2] as usize],
            );
            let area = 0.5 * (b - a).cross(c - a).length();
            4.0 * 3f64.sqrt() * area
                / ((b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared())
        })
        .fold(f64::INFINITY, f64::min)
}

/// Every vertex lies on the surface of box `b` (centre `at`, half extents
/// `half`) to 1e-9, and its 8 corners are vertices (sharp features kept).
pub fn assert_box_reproduced(mesh: &Mesh, b: &GeometricPrimitive, at: DVec3, half: DVec3) {
    for v in &mesh.positions {
        assert!(
            b.value(*v).abs() < 1e-9,
            "vertex off the box: {}",
            b.value(*v)
        );
    }
    for s in 0..8 {
        let sign = |bit: i32| if s & bit == 0 { -1.0 } else { 1.0 };
        let corner = at + half * DVec3::new(sign(1), sign(2), sign(4));
        let nearest = mesh
            .positions
            .iter()
            .map(|v| (*v - corner).length())
            .fold(f64::INFINITY, f64::min);
        assert!(nearest < 1e-9, "corner {corner} missed by {nearest}");
    }
}
