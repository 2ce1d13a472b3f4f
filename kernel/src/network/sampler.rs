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
    /// The domain corner each sample is at, if any.
    corner: Vec<Option<usize>>,
    /// Per side, its parameters and blend at every sample (contiguous per
    /// side: a side's pass reads them in order).
    side_weights: Vec<SideWeights>,
    /// Per tuning handle, its weight at every sample.
    tuning: Vec<Vec<f64>>,
    sides: usize,
    cache: Vec<SideCache>,
    /// Whether the last `evaluate` re-evaluated each side.
    refreshed: Vec<bool>,
}

/// One side's s_i, d_i and B_i at every sample.
#[derive(Clone, Debug, Default)]
struct SideWeights {
    s: Vec<f64>,
    d: Vec<f64>,
    blend: Vec<f64>,
}

/// One side's basis values at every sample, and its ribbon values.
#[derive(Clone, Debug, Default)]
struct SideCache {
    key: Option<(f64, f64, Vec<f64>)>,
    /// First control point index per sample.
    first: Vec<u32>,
    /// 2 (degree + 1) values per sample: N, N′ (the values need no c″: it
    /// only carries the exact derivatives of the `Jet` evaluation).
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
        let n = patch.sides();
        let mut corner = Vec::with_capacity(mesh.points.len());
        let mut side_weights = vec![SideWeights::default(); n];
        let mut tuning = vec![Vec::with_capacity(mesh.points.len()); n + 1];
        for p in &mesh.points {
            let w: PointWeights = patch.weights(*p);
            corner.push(w.corner);
            for (k, sw) in side_weights.iter_mut().enumerate() {
                sw.s.push(w.s[k]);
                sw.d.push(w.d[k]);
                sw.blend.push(w.blend[k]);
            }
            for (h, t) in tuning.iter_mut().zip(&w.tuning) {
                h.push(*t);
            }
        }
        Self {
            mesh,
            corner,
            side_weights,
            tuning,
            sides: n,
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
        self.corner.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.corner.is_empty()
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
            // A corner's weights are all zero (s = 0).
            for &s in &self.side_weights[k].s {
                let t = side.t_start + s * (side.t_end - side.t_start);
                basis_derivs_into(side.curve.knots(), t, 1, &mut scratch);
                cache.first.push(scratch.first as u32);
                lo = lo.min(scratch.first);
                hi = hi.max(scratch.first + w);
                for d in 0..2 {
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
            let sw = &self.side_weights[k];
            cache.ribbon_values.clear();
            cache.ribbon_values.reserve(sw.s.len());
            for (idx, corner) in self.corner.iter().enumerate() {
                if corner.is_some() || sw.blend[idx] == 0.0 {
                    cache.ribbon_values.push(DVec3::ZERO);
                    continue;
                }
                let first = cache.first[idx] as usize;
                let vals = &cache.values[idx * 2 * w..(idx + 1) * 2 * w];
                let pts = &side.curve.points()[first..first + w];
                // c and c′; c″ (zero here) enters only derivatives, which
                // the f64 evaluation does not carry.
                let mut derivs = [DVec3::ZERO; 3];
                for (j, p) in pts.iter().enumerate() {
                    derivs[0] += *p * vals[j];
                    derivs[1] += *p * vals[w + j];
                }
                cache
                    .ribbon_values
                    .push(side.eval_from(sw.s[idx], sw.d[idx], derivs).val());
            }
            cache.ribbon = Some(side.clone());
        }
        // Σ_i B_i R_i, side by side over all samples, then the tuning
        // terms, then the corners (where the blends are 0/0).
        out.clear();
        out.resize(self.corner.len(), DVec3::ZERO);
        for (cache, sw) in self.cache.iter().zip(&self.side_weights) {
            for ((o, r), b) in out.iter_mut().zip(&cache.ribbon_values).zip(&sw.blend) {
                if *b != 0.0 {
                    *o += *r * *b;
                }
            }
        }
        for (h, weights) in patch.tuning().iter().zip(&self.tuning) {
            if *h == DVec3::ZERO {
                continue;
            }
            for (o, t) in out.iter_mut().zip(weights) {
                *o += *h * *t;
            }
        }
        for (o, c) in out.iter_mut().zip(&self.corner) {
            if let Some(c) = c {
                *o = patch.ribbons()[*c].point(0.0);
            }
        }
        true
    }
}
