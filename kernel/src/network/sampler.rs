//! Sampling patches into triangle meshes, fast enough for a curve drag.
//!
//! A [`DomainMesh`] triangulates the regular n-gon: for n = 3 the
//! triangular lattice with m segments per side ((m+1)(m+2)/2 points, m²
//! triangles — the paper's octant is m = 24: 325 points, 576 triangles);
//! otherwise a fan of n such lattices around the centre (shared points
//! merged). A [`PatchSampler`] precomputes, per sample, everything that
//! depends on the domain only — the side parameters s_i, d_i, the blends
//! B_i and the tuning weights — so re-evaluating after a curve moves is
//! only the ribbons at fixed (s_i, d_i) combined with fixed weights.

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use super::domain::Domain;
use super::patch::{Patch, PointWeights};
use crate::bspline::BasisDerivs;

/// A triangulated patch domain.
#[derive(Clone, Debug, PartialEq)]
pub struct DomainMesh {
    /// Domain points.
    pub points: Vec<DVec2>,
    /// Triangles (counter-clockwise in the domain).
    pub triangles: Vec<[u32; 3]>,
    /// Whether each point lies on the domain boundary.
    pub boundary: Vec<bool>,
}

impl DomainMesh {
    /// The mesh of `domain` with `m ≥ 1` segments per lattice side.
    pub fn new(domain: &Domain, m: usize) -> Self {
        let m = m.max(1);
        let v = domain.vertices();
        let n = v.len();
        let tris: Vec<[DVec2; 3]> = if n == 3 {
            vec![[v[0], v[1], v[2]]]
        } else {
            (0..n)
                .map(|k| [DVec2::ZERO, v[k], v[(k + 1) % n]])
                .collect()
        };
        let mut index: HashMap<(i64, i64), u32> = HashMap::new();
        let mut points = Vec::new();
        let mut triangles = Vec::new();
        let mut id = |p: DVec2, points: &mut Vec<DVec2>| -> u32 {
            let key = ((p.x * 1e9).round() as i64, (p.y * 1e9).round() as i64);
            *index.entry(key).or_insert_with(|| {
                points.push(p);
                (points.len() - 1) as u32
            })
        };
        for [a, b, c] in tris {
            let mut grid = vec![vec![0u32; m + 1]; m + 1];
            for i in 0..=m {
                for j in 0..=m - i {
                    let p = a + (b - a) * (i as f64 / m as f64) + (c - a) * (j as f64 / m as f64);
                    grid[i][j] = id(p, &mut points);
                }
            }
            for i in 0..m {
                for j in 0..m - i {
                    triangles.push([grid[i][j], grid[i + 1][j], grid[i][j + 1]]);
                    if i + j + 1 < m {
                        triangles.push([grid[i + 1][j], grid[i + 1][j + 1], grid[i][j + 1]]);
                    }
                }
            }
        }
        let boundary = points
            .iter()
            .map(|p| {
                (0..n).any(|k| {
                    let (a, b) = (v[k], v[(k + 1) % n]);
                    ((b - a).perp_dot(*p - a) / (b - a).length()).abs() < 1e-9
                })
            })
            .collect();
        Self {
            points,
            triangles,
            boundary,
        }
    }
}

/// A patch's samples with their domain-only weights precomputed.
#[derive(Clone, Debug)]
pub struct PatchSampler {
    mesh: DomainMesh,
    weights: Vec<PointWeights>,
    sides: usize,
}

impl PatchSampler {
    /// Samples for an n-sided patch at lattice resolution `m`.
    pub fn new(patch: &Patch, m: usize) -> Self {
        let mesh = DomainMesh::new(patch.domain(), m);
        let weights = mesh.points.iter().map(|p| patch.weights(*p)).collect();
        Self {
            mesh,
            weights,
            sides: patch.sides(),
        }
    }

    /// The domain mesh.
    pub fn mesh(&self) -> &DomainMesh {
        &self.mesh
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// The patch at every sample, into `out` (resized). `patch` must have
    /// the number of sides the sampler was made for (else nothing is
    /// written and `false` is returned).
    pub fn evaluate(&self, patch: &Patch, out: &mut Vec<DVec3>) -> bool {
        if patch.sides() != self.sides {
            return false;
        }
        out.clear();
        let mut scratch = BasisDerivs::default();
        out.extend(
            self.weights
                .iter()
                .map(|w| patch.eval_weights(w, &mut scratch)),
        );
        true
    }
}
