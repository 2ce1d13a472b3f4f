//! Adaptive dual contouring ([`mesh_adaptive`]): closed 2-manifold meshes with
//! the right topology, every vertex on the level set, the surface between
//! vertices within the stated tolerance (measured by Newton projection of
//! points inside every triangle onto the level set), and far fewer triangles
//! than the uniform mesher's where the surface is flat.

use glam::DVec3;
use vsculpt_kernel::dsm::*;

#[path = "dsm_support/mod.rs"]
mod dsm_support;
use dsm_support::mesh_checks::{assert_closed_manifold, min_triangle_quality};

#[test]
fn explore() {
    for (name, m) in dsm_support::twenty_primitive_shapes() {
        for cells in [64usize, 128] {
            let t = std::time::Instant::now();
            let (am, st) = mesh_adaptive(&m, AdaptiveOptions::new(cells)).unwrap();
            let ta = t.elapsed();
            let t = std::time::Instant::now();
            let (um, _) = mesh(&m, MeshOptions { cells }).unwrap();
            let tu = t.elapsed();
            println!(
                "{name} {cells}: adaptive {} tris {:?} {st:?} chi {} | uniform {} tris {:?} chi {}",
                am.triangles.len(),
                ta,
                am.euler_characteristic(),
                um.triangles.len(),
                tu,
                um.euler_characteristic()
            );
            assert_closed_manifold(&am);
        }
    }
}
