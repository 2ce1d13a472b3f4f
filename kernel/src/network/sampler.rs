//! Sampling patches into triangle meshes, fast enough for a curve drag.
//!
//! A [`DomainMesh`] triangulates the regular n-gon: for n = 3 the
//! triangular lattice with m segments per side ((m+1)(m+2)/2 points, m²
//! triangles — the paper's octant is m = 24: 325 points, 576 triangles);
//! otherwise a fan of n such lattices around the centre (shared points
//! merged). A [`PatchSampler`] precomputes, per sample, everything that
//! depends on the domain only — the side parameters s_i, d_i, the blends
//! B_i and the tuning weights — and the boundary curves' basis values at
//! each sample, so re-evaluating after a curve moves is a linear
//! combination of control points per side, the ribbon's frame at fixed
//! (s_i, d_i), and fixed blend weights.

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use super::domain::Domain;
use super::patch::{Patch, PointWeights};
use super::ribbon::SideRibbon;
use crate::bspline::{BasisDerivs, basis_derivs_into};

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
    #[allow(clippy::needless_range_loop)] // lattice indices (i, j)
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

/// A patch's samples with their domain-only weights precomputed, and per
/// side the curve's basis values (and derivatives) at every sample's
/// parameter, kept while the side's parameter range and knots stay the same
/// (a drag moves control points; a side's range changes only when a meeting
/// on it moves along the curve).
///
/// A frame re-evaluates only what changed. A patch point is
/// S = Σ_i B_i R_i(s_i, d_i) + Σ_k φ_k h_k with fixed weights B_i, φ_k, but
/// R_i is not linear in the curve: its cross derivative uses the unit
/// tangent and the normal field's frame at s_i (normalisations, cos/sin of
/// the normal's angle), so there is no fixed matrix from control points to
/// samples. It is local, though: R_i at a sample depends only on the
/// side's parameter range, knots, normal pieces, corner values, scale and
/// the control points whose basis functions are non-zero somewhere on the
/// side. Each side keeps its R_i per sample and the data it was computed
/// from; a side whose data are unchanged (a drag elsewhere on the curve, or
/// on another curve) is not re-evaluated, and the samples are recombined
/// from the kept R_i (a few multiply-adds per sample and side).
#[derive(Clone, Debug)]
pub struct PatchSampler {
    mesh: DomainMesh,
    weights: Vec<PointWeights>,
    sides: usize,
    cache: Vec<SideCache>,
    /// Whether the last `evaluate` re-evaluated each side.
    refreshed: Vec<bool>,
}

/// One side's basis values at every sample, and its ribbon values.
#[derive(Clone, Debug, Default)]
struct SideCache {
    key: Option<(f64, f64, Vec<f64>)>,
    /// First control point index per sample.
    first: Vec<u32>,
    /// 3 (degree + 1) values per sample: N, N′, N″.
    values: Vec<f64>,
    /// The control points used by the samples: `lo..hi`.
    lo: usize,
    hi: usize,
    /// The ribbon `ribbon_values` were computed from.
    ribbon: Option<SideRibbon>,
    /// R(s, d) per sample (zero where the side's blend is zero).
    ribbon_values: Vec<DVec3>,
}

/// Whether `new` gives the same R(s, d) as `old` at every sample whose
/// curve basis uses only control points `lo..hi`.
fn same_ribbon(old: &SideRibbon, new: &SideRibbon, lo: usize, hi: usize) -> bool {
    old.t_start == new.t_start
        && old.t_end == new.t_end
        && old.a == new.a
        && old.b == new.b
        && old.scale == new.scale
        && old.pieces == new.pieces
        && old.curve.knots() == new.curve.knots()
        && old.curve.points().len() == new.curve.points().len()
        && hi <= old.curve.points().len()
        && old.curve.points()[lo..hi] == new.curve.points()[lo..hi]
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
            cache: vec![SideCache::default(); patch.sides()],
            refreshed: vec![false; patch.sides()],
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

    /// Forgets the kept ribbon values, so the next [`Self::evaluate`]
    /// re-evaluates every side (the basis values are kept).
    pub fn invalidate(&mut self) {
        for c in &mut self.cache {
            c.ribbon = None;
        }
    }

    /// Which sides the last [`Self::evaluate`] re-evaluated (the others'
    /// ribbon values were unchanged and reused).
    pub fn refreshed(&self) -> &[bool] {
        &self.refreshed
    }

    /// The patch at every sample, into `out` (resized). `patch` must have
    /// the number of sides the sampler was made for (else nothing is
    /// written and `false` is returned).
    pub fn evaluate(&mut self, patch: &Patch, out: &mut Vec<DVec3>) -> bool {
        if patch.sides() != self.sides {
            return false;
        }
        let mut scratch = BasisDerivs::default();
        for (k, side) in patch.ribbons().iter().enumerate() {
            let key = (
                side.t_start,
                side.t_end,
                side.curve.knots().knots().to_vec(),
            );
            let cache = &mut self.cache[k];
            if cache.key.as_ref() == Some(&key) {
                continue;
            }
            let w = side.curve.degree() + 1;
            cache.first.clear();
            cache.values.clear();
            let (mut lo, mut hi) = (usize::MAX, 0);
            for pw in &self.weights {
                let s = if pw.corner.is_some() { 0.0 } else { pw.s[k] };
                let t = side.t_start + s * (side.t_end - side.t_start);
                basis_derivs_into(side.curve.knots(), t, 2, &mut scratch);
                cache.first.push(scratch.first as u32);
                lo = lo.min(scratch.first);
                hi = hi.max(scratch.first + w);
                for d in 0..3 {
                    cache.values.extend((0..w).map(|j| scratch.get(d, j)));
                }
            }
            cache.lo = lo.min(hi);
            cache.hi = hi;
            cache.key = Some(key);
            cache.ribbon = None;
        }
        for (k, side) in patch.ribbons().iter().enumerate() {
            let cache = &mut self.cache[k];
            let fresh = cache
                .ribbon
                .as_ref()
                .is_some_and(|old| same_ribbon(old, side, cache.lo, cache.hi));
            self.refreshed[k] = !fresh;
            if fresh {
                continue;
            }
            let w = side.curve.degree() + 1;
            cache.ribbon_values.clear();
            cache.ribbon_values.reserve(self.weights.len());
            for (idx, pw) in self.weights.iter().enumerate() {
                if pw.corner.is_some() || pw.blend[k] == 0.0 {
                    cache.ribbon_values.push(DVec3::ZERO);
                    continue;
                }
                let first = cache.first[idx] as usize;
                let vals = &cache.values[idx * 3 * w..(idx + 1) * 3 * w];
                let pts = &side.curve.points()[first..first + w];
                let mut derivs = [DVec3::ZERO; 3];
                for (d, out_d) in derivs.iter_mut().enumerate() {
                    for (j, p) in pts.iter().enumerate() {
                        *out_d += *p * vals[d * w + j];
                    }
                }
                cache
                    .ribbon_values
                    .push(side.eval_from(pw.s[k], pw.d[k], derivs).val());
            }
            cache.ribbon = Some(side.clone());
        }
        out.clear();
        out.reserve(self.weights.len());
        for (idx, pw) in self.weights.iter().enumerate() {
            if let Some(c) = pw.corner {
                out.push(patch.ribbons()[c].point(0.0));
                continue;
            }
            let mut acc = DVec3::ZERO;
            for (k, cache) in self.cache.iter().enumerate() {
                let b = pw.blend[k];
                if b == 0.0 {
                    continue;
                }
                acc += cache.ribbon_values[idx] * b;
            }
            for (h, t) in patch.tuning().iter().zip(&pw.tuning) {
                acc += *h * *t;
            }
            out.push(acc);
        }
        true
    }
}
