//! Injectivity of a B-spline volume: det J > 0 everywhere, proved (not
//! sampled) from the Bernstein form of det J.
//!
//! On every knot-span cell det J = x_u · (x_v × x_w) is one trivariate
//! polynomial of degree (3l − 1, 3m − 1, 3n − 1) (x_u has degree l − 1 in u,
//! x_v and x_w degree l). Its Bernstein coefficients on the cell are found
//! exactly (to rounding) by evaluating det J at (degree + 1)³ Chebyshev
//! points strictly inside the cell and solving the tensor-product Bernstein
//! collocation system (one small LU per direction). Bernstein polynomials
//! are a non-negative partition of unity, so det J lies between the smallest
//! and largest coefficient:
//!
//! * all coefficients > 0 ⇒ det J > 0 on the whole cell (proved);
//! * a corner coefficient ≤ 0 is det J at that corner ⇒ a fold, found;
//! * otherwise the cell is split in half (de Casteljau, exact) along the
//!   direction cycling with depth, up to [`MAX_DEPTH`] levels; what is still
//!   undecided then is refused conservatively at the parameter of its
//!   smallest coefficient.
//!
//! The collocation's rounding error was measured at ~1e-10 of the largest
//! coefficient (degree 8 per direction for a tricubic body), so coefficients
//! within `1e-8 · max |coefficient|` of zero count as ≤ 0: rounding cannot
//! prove a fold away, and a body that merely touches det J = 0 is refused. det J > 0 everywhere with an injective
//! boundary makes the map injective; the check is the local condition the
//! paper's "interior density" needs (no folded material).
//!
//! [`InjectivityCache`] keeps every cell's proof between checks: a lattice
//! that differs from the last one proved in a few control points is proved
//! again only on the cells those points reach (B-spline locality), with the
//! verdict and fold of a fresh proof.

use faer::Mat;
use faer::prelude::Solve;

use glam::DVec3;

use super::{BSplineVolume, BodyError, Dir, VolumeScratch};
use crate::bspline::basis_derivs;

/// Subdivision levels before an undecided cell is refused.
pub const MAX_DEPTH: usize = 12;

/// Coefficients below `MARGIN · max |coefficient|` count as non-positive.
pub const MARGIN: f64 = 1e-8;

/// What the check proved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InjectivityReport {
    /// A proved lower bound of det J over the whole domain (> 0).
    pub lower_bound: f64,
    /// The smallest det J seen at a cell corner (an upper bound of the min).
    pub min_seen: f64,
    /// Cells (knot-span boxes) checked.
    pub cells: usize,
    /// Sub-cells created by subdivision.
    pub subdivisions: usize,
}

fn binom(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

fn bernstein(n: usize, k: usize, t: f64) -> f64 {
    binom(n, k) * t.powi(k as i32) * (1.0 - t).powi((n - k) as i32)
}

/// Chebyshev points in (0, 1) and the inverse map from values there to
/// Bernstein coefficients of degree `d`.
struct Collocation {
    nodes: Vec<f64>,
    lu: faer::linalg::solvers::PartialPivLu<f64>,
}

impl Collocation {
    fn new(d: usize) -> Self {
        let n = d + 1;
        let nodes: Vec<f64> = (0..n)
            .map(|r| 0.5 - 0.5 * ((2 * r + 1) as f64 * std::f64::consts::PI / (2 * n) as f64).cos())
            .collect();
        let a = Mat::<f64>::from_fn(n, n, |r, s| bernstein(d, s, nodes[r]));
        Self {
            nodes,
            lu: a.partial_piv_lu(),
        }
    }

    /// Applies the inverse along axis `axis` of an n0 × n1 × n2 tensor.
    fn apply(&self, data: &mut [f64], dims: [usize; 3], axis: usize) {
        let n = dims[axis];
        let stride = match axis {
            0 => dims[1] * dims[2],
            1 => dims[2],
            _ => 1,
        };
        let lines: Vec<usize> = (0..data.len()).filter(|&i| (i / stride) % n == 0).collect();
        let rhs = Mat::<f64>::from_fn(n, lines.len(), |r, c| data[lines[c] + r * stride]);
        let x = self.lu.solve(&rhs);
        for (c, &start) in lines.iter().enumerate() {
            for r in 0..n {
                data[start + r * stride] = x[(r, c)];
            }
        }
    }
}

/// A Bernstein tensor over a parameter box.
struct Patch {
    coef: Vec<f64>,
    dims: [usize; 3],
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Patch {
    fn at(&self, i: usize, j: usize, k: usize) -> f64 {
        self.coef[(i * self.dims[1] + j) * self.dims[2] + k]
    }

    /// The two halves along `axis` (de Casteljau at ½).
    fn split(&self, axis: usize) -> (Patch, Patch) {
        let n = self.dims[axis];
        let stride = match axis {
            0 => self.dims[1] * self.dims[2],
            1 => self.dims[2],
            _ => 1,
        };
        let mut left = self.coef.clone();
        let mut right = self.coef.clone();
        let mut tmp = vec![0.0; n];
        for start in (0..self.coef.len()).filter(|&i| (i / stride) % n == 0) {
            for (r, t) in tmp.iter_mut().enumerate() {
                *t = self.coef[start + r * stride];
            }
            // de Casteljau: left[r] = tmp after r steps at index 0, right[n-1-r] at the end.
            for r in 0..n {
                left[start + r * stride] = tmp[0];
                right[start + (n - 1 - r) * stride] = tmp[n - 1 - r];
                for q in 0..n - 1 - r {
                    tmp[q] = 0.5 * (tmp[q] + tmp[q + 1]);
                }
            }
        }
        let mid = 0.5 * (self.lo[axis] + self.hi[axis]);
        let mut lhi = self.hi;
        lhi[axis] = mid;
        let mut rlo = self.lo;
        rlo[axis] = mid;
        (
            Patch {
                coef: left,
                dims: self.dims,
                lo: self.lo,
                hi: lhi,
            },
            Patch {
                coef: right,
                dims: self.dims,
                lo: rlo,
                hi: self.hi,
            },
        )
    }
}

/// One knot-span cell: its parameter box and the (i, j, k) of the first
/// control point of its (l+1)(m+1)(n+1) block.
#[derive(Clone, Copy, Debug)]
struct Cell {
    lo: [f64; 3],
    hi: [f64; 3],
    first: [usize; 3],
}

/// The knot-span cells of `vol`, u slowest.
fn cells(vol: &BSplineVolume) -> Vec<Cell> {
    let spans = Dir::ALL.map(|d| vol.knots(d).spans());
    let p = vol.degrees();
    let mut out = Vec::new();
    for &(i, a0, a1) in &spans[0] {
        for &(j, b0, b1) in &spans[1] {
            for &(k, c0, c1) in &spans[2] {
                out.push(Cell {
                    lo: [a0, b0, c0],
                    hi: [a1, b1, c1],
                    first: [i - p[0], j - p[1], k - p[2]],
                });
            }
        }
    }
    out
}

/// The Bernstein coefficients of det J on the cell [lo, hi] whose control
/// points start at `first`: det J at the collocation nodes by sum
/// factorisation over the cell's (l+1)(m+1)(n+1) control points (the basis
/// functions and their first derivatives once per direction and node, the
/// points contracted along w, then v, then u), then the collocation solves.
fn cell_patch(vol: &BSplineVolume, colloc: &[Collocation], cell: &Cell) -> Patch {
    let (lo, hi) = (cell.lo, cell.hi);
    let dims = [0, 1, 2].map(|a| colloc[a].nodes.len());
    let deg = vol.degrees();
    // Per direction and node: the p + 1 values and first derivatives.
    let basis: Vec<Vec<(Vec<f64>, Vec<f64>)>> = Dir::ALL
        .iter()
        .map(|&d| {
            let a = d.index();
            colloc[a]
                .nodes
                .iter()
                .map(|&s| {
                    let b = basis_derivs(vol.knots(d), lo[a] + (hi[a] - lo[a]) * s, 1);
                    debug_assert_eq!(b.first, cell.first[a]);
                    (
                        (0..=deg[a]).map(|k| b.get(0, k)).collect(),
                        (0..=deg[a]).map(|k| b.get(1, k)).collect(),
                    )
                })
                .collect()
        })
        .collect();
    let [pu, pv, pw] = deg.map(|p| p + 1);
    let pts = vol.points();
    let f = cell.first;
    // Along w: w0[(a, b, r)] = Σ_c N(w_r)_c P_abc, w1 with N'.
    let mut w0 = vec![DVec3::ZERO; pu * pv * dims[2]];
    let mut w1 = w0.clone();
    for a in 0..pu {
        for b in 0..pv {
            for (r, (n, dn)) in basis[2].iter().enumerate() {
                let (mut x, mut y) = (DVec3::ZERO, DVec3::ZERO);
                for c in 0..pw {
                    let p = pts[vol.index(f[0] + a, f[1] + b, f[2] + c)];
                    x += p * n[c];
                    y += p * dn[c];
                }
                w0[(a * pv + b) * dims[2] + r] = x;
                w1[(a * pv + b) * dims[2] + r] = y;
            }
        }
    }
    // Along v: v00 = Σ_b N w0, v10 = Σ_b N' w0, v01 = Σ_b N w1.
    let size = pu * dims[1] * dims[2];
    let (mut v00, mut v10, mut v01) = (
        vec![DVec3::ZERO; size],
        vec![DVec3::ZERO; size],
        vec![DVec3::ZERO; size],
    );
    for a in 0..pu {
        for (t, (n, dn)) in basis[1].iter().enumerate() {
            for r in 0..dims[2] {
                let at = (a * dims[1] + t) * dims[2] + r;
                for b in 0..pv {
                    let i = (a * pv + b) * dims[2] + r;
                    v00[at] += w0[i] * n[b];
                    v10[at] += w0[i] * dn[b];
                    v01[at] += w1[i] * n[b];
                }
            }
        }
    }
    // Along u: the three first derivatives, and det J.
    let mut coef = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
    for (n, dn) in &basis[0] {
        for t in 0..dims[1] {
            for r in 0..dims[2] {
                let (mut xu, mut xv, mut xw) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
                for a in 0..pu {
                    let i = (a * dims[1] + t) * dims[2] + r;
                    xu += v00[i] * dn[a];
                    xv += v10[i] * n[a];
                    xw += v01[i] * n[a];
                }
                coef.push(xu.dot(xv.cross(xw)));
            }
        }
    }
    for (axis, c) in colloc.iter().enumerate() {
        c.apply(&mut coef, dims, axis);
    }
    Patch { coef, dims, lo, hi }
}

/// The collocations of det J's degrees for `vol`.
fn collocations(vol: &BSplineVolume) -> Vec<Collocation> {
    vol.degrees()
        .iter()
        .map(|&p| Collocation::new(3 * p - 1))
        .collect()
}

/// The largest |coefficient| of a patch.
fn patch_scale(p: &Patch) -> f64 {
    p.coef.iter().fold(0.0f64, |m, c| m.max(c.abs()))
}

/// What one cell's proof found: the smallest leaf coefficient (a lower
/// bound of det J on the cell), the smallest corner value seen, the
/// sub-cells made, and the cell's largest |coefficient|.
#[derive(Clone, Copy, Debug, PartialEq)]
struct CellProof {
    lower: f64,
    min_seen: f64,
    subdivisions: usize,
    scale: f64,
}

/// Proves det J > `eps` on one cell's patch by subdivision (depth first,
/// the right half first), or returns the fold found.
fn prove_cell(
    vol: &BSplineVolume,
    patch: Patch,
    eps: f64,
    scratch: &mut VolumeScratch,
) -> Result<CellProof, BodyError> {
    let mut proof = CellProof {
        lower: f64::INFINITY,
        min_seen: f64::INFINITY,
        subdivisions: 0,
        scale: patch_scale(&patch),
    };
    let mut stack: Vec<(Patch, usize)> = vec![(patch, 0)];
    while let Some((p, depth)) = stack.pop() {
        let [n0, n1, n2] = p.dims;
        for (i, j, k) in [
            (0, 0, 0),
            (n0 - 1, 0, 0),
            (0, n1 - 1, 0),
            (0, 0, n2 - 1),
            (n0 - 1, n1 - 1, 0),
            (n0 - 1, 0, n2 - 1),
            (0, n1 - 1, n2 - 1),
            (n0 - 1, n1 - 1, n2 - 1),
        ] {
            let c = p.at(i, j, k);
            proof.min_seen = proof.min_seen.min(c);
            if c <= eps {
                let t = [
                    if i == 0 { p.lo[0] } else { p.hi[0] },
                    if j == 0 { p.lo[1] } else { p.hi[1] },
                    if k == 0 { p.lo[2] } else { p.hi[2] },
                ];
                return Err(BodyError::Folds {
                    u: t[0],
                    v: t[1],
                    w: t[2],
                    det: c,
                });
            }
        }
        let (imin, &cmin) = p
            .coef
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .expect("non-empty");
        if cmin > eps {
            proof.lower = proof.lower.min(cmin);
            continue;
        }
        if depth >= MAX_DEPTH {
            // Undecided: refuse at the smallest coefficient's parameter.
            let idx = [imin / (n1 * n2), (imin / n2) % n1, imin % n2];
            let t: Vec<f64> = (0..3)
                .map(|a| p.lo[a] + (p.hi[a] - p.lo[a]) * idx[a] as f64 / (p.dims[a] - 1) as f64)
                .collect();
            let det = vol.eval(scratch, [t[0], t[1], t[2]], 1).det();
            return Err(BodyError::Folds {
                u: t[0],
                v: t[1],
                w: t[2],
                det: det.min(cmin),
            });
        }
        let (l, r) = p.split(depth % 3);
        proof.subdivisions += 2;
        stack.push((l, depth + 1));
        stack.push((r, depth + 1));
    }
    Ok(proof)
}

/// Proves det J > 0 on the whole domain of `vol`, or returns
/// [`BodyError::Folds`] with the (u, v, w) where it fails.
pub fn check_injective(vol: &BSplineVolume) -> Result<InjectivityReport, BodyError> {
    InjectivityCache::default().check(vol)
}

/// Injectivity proofs kept per knot-span cell between checks, so that a
/// lattice differing from the last one proved in a few control points is
/// proved again only on the cells those points reach (B-spline locality:
/// a cell's det J depends on its (l+1)(m+1)(n+1) control points only).
///
/// A kept cell counts as proved again when its kept lower bound (its
/// smallest leaf coefficient) still exceeds the margin of the new lattice
/// (`MARGIN` · the largest |coefficient| over all cells, which moves with
/// the changed cells); otherwise it is proved again from scratch. Every
/// leaf of the kept proof then lies above the new margin, so a fresh proof
/// would accept the cell too: the verdict, and the fold reported (the
/// changed cells are proved in the same order as [`check_injective`]'s),
/// are those of a fresh check. The report's figures for kept cells (lower
/// bound, subdivisions) are those of the proof kept.
#[derive(Clone, Debug, Default)]
pub struct InjectivityCache {
    /// The last volume proved injective.
    proved: Option<BSplineVolume>,
    /// Its cells' proofs, in [`cells`] order.
    cells: Vec<CellProof>,
}

impl InjectivityCache {
    /// The volume last proved injective, if any.
    pub fn last(&self) -> Option<&BSplineVolume> {
        self.proved.as_ref()
    }

    /// How many of `vol`'s cells differ from the volume last proved (all of
    /// them when the degrees or knots differ, or nothing was proved).
    pub fn changed_cells(&self, vol: &BSplineVolume) -> usize {
        self.dirty(vol, &cells(vol)).iter().filter(|d| **d).count()
    }

    /// Per cell of `vol`, whether its control points differ from the last
    /// volume proved.
    fn dirty(&self, vol: &BSplineVolume, cells: &[Cell]) -> Vec<bool> {
        let Some(old) = &self.proved else {
            return vec![true; cells.len()];
        };
        let same_space = old.degrees() == vol.degrees()
            && Dir::ALL
                .iter()
                .all(|&d| old.knots(d).knots() == vol.knots(d).knots())
            && self.cells.len() == cells.len();
        if !same_space {
            return vec![true; cells.len()];
        }
        let p = vol.degrees();
        let (a, b) = (old.points(), vol.points());
        cells
            .iter()
            .map(|cell| {
                let first = cell.first;
                (0..=p[0]).any(|i| {
                    (0..=p[1]).any(|j| {
                        (0..=p[2]).any(|k| {
                            let at = vol.index(first[0] + i, first[1] + j, first[2] + k);
                            a[at] != b[at]
                        })
                    })
                })
            })
            .collect()
    }

    /// Proves det J > 0 on the whole domain of `vol` (as
    /// [`check_injective`]), reusing the proofs of cells unchanged since
    /// the last volume proved; keeps `vol`'s proofs when it succeeds (on a
    /// fold the cache is unchanged).
    pub fn check(&mut self, vol: &BSplineVolume) -> Result<InjectivityReport, BodyError> {
        let cells = cells(vol);
        let dirty = self.dirty(vol, &cells);
        let colloc = collocations(vol);
        let mut scratch = VolumeScratch::default();
        // Fresh patches of the changed cells; the kept scale of the others.
        let mut patches: Vec<Option<Patch>> = Vec::with_capacity(cells.len());
        let mut scale = 0.0f64;
        for (c, cell) in cells.iter().enumerate() {
            if dirty[c] {
                let p = cell_patch(vol, &colloc, cell);
                scale = scale.max(patch_scale(&p));
                patches.push(Some(p));
            } else {
                scale = scale.max(self.cells[c].scale);
                patches.push(None);
            }
        }
        let eps = MARGIN * scale;
        // A kept proof whose lower bound no longer clears the margin is
        // made again.
        for (c, cell) in cells.iter().enumerate() {
            if patches[c].is_none() && self.cells[c].lower <= eps {
                patches[c] = Some(cell_patch(vol, &colloc, cell));
            }
        }
        let mut proofs = vec![
            CellProof {
                lower: f64::INFINITY,
                min_seen: f64::INFINITY,
                subdivisions: 0,
                scale: 0.0,
            };
            cells.len()
        ];
        // The last cell first (as a stack of all cells pops them).
        for c in (0..cells.len()).rev() {
            proofs[c] = match patches[c].take() {
                Some(p) => prove_cell(vol, p, eps, &mut scratch)?,
                None => self.cells[c],
            };
        }
        let report = InjectivityReport {
            lower_bound: proofs.iter().fold(f64::INFINITY, |m, p| m.min(p.lower)),
            min_seen: proofs.iter().fold(f64::INFINITY, |m, p| m.min(p.min_seen)),
            cells: cells.len(),
            subdivisions: proofs.iter().map(|p| p.subdivisions).sum(),
        };
        self.proved = Some(vol.clone());
        self.cells = proofs;
        Ok(report)
    }
}
