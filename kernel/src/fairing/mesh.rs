//! A triangulated point mesh: points, triangles, which points are on the
//! boundary (never moved by fairing), and each point's rings of neighbours.

use glam::DVec3;

use super::error::FairingError;
use crate::network::{Patch, PatchSampler};

/// Points of a surface with their triangulation.
#[derive(Clone, Debug, PartialEq)]
pub struct PointMesh {
    /// The points.
    pub points: Vec<DVec3>,
    /// Triangles (indices into `points`).
    pub triangles: Vec<[u32; 3]>,
    /// Whether each point is a boundary point.
    pub boundary: Vec<bool>,
    ring1: Vec<Vec<u32>>,
    ring2: Vec<Vec<u32>>,
}

impl PointMesh {
    /// A mesh from points, triangles and boundary flags.
    pub fn new(
        points: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
        boundary: Vec<bool>,
    ) -> Result<Self, FairingError> {
        let n = points.len();
        if boundary.len() != n {
            return Err(FairingError::BadMesh(format!(
                "{} boundary flags for {n} points",
                boundary.len()
            )));
        }
        if let Some(i) = points.iter().position(|p| !p.is_finite()) {
            return Err(FairingError::BadMesh(format!("point {i} is not finite")));
        }
        let mut ring1: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (t, tri) in triangles.iter().enumerate() {
            if tri.iter().any(|&i| i as usize >= n)
                || tri[0] == tri[1]
                || tri[1] == tri[2]
                || tri[0] == tri[2]
            {
                return Err(FairingError::BadMesh(format!("triangle {t} is invalid")));
            }
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if !ring1[a as usize].contains(&b) {
                    ring1[a as usize].push(b);
                }
                if !ring1[b as usize].contains(&a) {
                    ring1[b as usize].push(a);
                }
            }
        }
        let ring2 = (0..n)
            .map(|i| {
                let mut r = ring1[i].clone();
                for &j in &ring1[i] {
                    for &k in &ring1[j as usize] {
                        if k as usize != i && !r.contains(&k) {
                            r.push(k);
                        }
                    }
                }
                r
            })
            .collect();
        Ok(Self {
            points,
            triangles,
            boundary,
            ring1,
            ring2,
        })
    }

    /// The mesh of `patch` sampled at lattice resolution `m` (see
    /// [`crate::network::DomainMesh`]).
    pub fn from_patch(patch: &Patch, m: usize) -> Result<Self, FairingError> {
        let mut sampler = PatchSampler::new(patch, m);
        let mut pts = Vec::new();
        sampler.evaluate(patch, &mut pts);
        let dm = sampler.mesh();
        Self::new(pts, dm.triangles.clone(), dm.boundary.clone())
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the mesh has no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The points sharing an edge with point `i`.
    pub fn ring1(&self, i: usize) -> &[u32] {
        &self.ring1[i]
    }

    /// The points within two edges of point `i` (not `i` itself).
    pub fn ring2(&self, i: usize) -> &[u32] {
        &self.ring2[i]
    }

    /// The area-weighted normal of the triangles around point `i` (their
    /// orientation decides the side).
    pub fn triangle_normal(&self, i: usize) -> DVec3 {
        // Built on demand: fairing keeps its own per-point normals.
        let mut n = DVec3::ZERO;
        for tri in &self.triangles {
            if tri.contains(&(i as u32)) {
                let [a, b, c] = tri.map(|k| self.points[k as usize]);
                n += (b - a).cross(c - a);
            }
        }
        n.normalize_or_zero()
    }

    /// Area-weighted normals of every point from its triangles.
    pub fn triangle_normals(&self) -> Vec<DVec3> {
        let mut n = vec![DVec3::ZERO; self.len()];
        for tri in &self.triangles {
            let [a, b, c] = tri.map(|k| self.points[k as usize]);
            let f = (b - a).cross(c - a);
            for k in tri {
                n[*k as usize] += f;
            }
        }
        n.into_iter().map(|v| v.normalize_or_zero()).collect()
    }
}
