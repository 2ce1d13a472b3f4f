//! Tessellation of surfaces and curves for clients and exports: positions,
//! unit normals, (u,v), mean and Gaussian curvature per vertex, triangles.
//!
//! A [`Tessellator`] precomputes the basis functions (values, first and
//! second derivatives) at every u sample and every v sample once per knot
//! layout and density; [`Tessellator::fill`] then evaluates separably —
//! for each control row and v sample it contracts v, then for each vertex
//! it contracts u — and refills a [`Tessellation`] in place.

use glam::DVec3;

use super::{Degenerate, curve_curvature, shading_curvature};
use crate::bspline::{BSplineCurve, BSplineSurface, SurfaceDerivs, basis_derivs};

/// A triangle mesh of a surface with per-vertex attributes (f32, ready for
/// a GPU buffer or a mesh file). Vertex (a, b) — a-th u sample, b-th v
/// sample — is at index `a * samples_v + b`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tessellation {
    /// Samples along u.
    pub samples_u: usize,
    /// Samples along v.
    pub samples_v: usize,
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Unit normals (w_u × w_v normalised; a neighbour's where degenerate).
    pub normals: Vec<[f32; 3]>,
    /// Parameters.
    pub uvs: Vec<[f32; 2]>,
    /// Mean curvature (0 where degenerate).
    pub mean: Vec<f32>,
    /// Gaussian curvature (0 where degenerate).
    pub gauss: Vec<f32>,
    /// Triangles, counter-clockwise seen from the normal.
    pub indices: Vec<u32>,
}

impl Tessellation {
    /// The number of triangles.
    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }
}

#[derive(Clone, Debug)]
struct Table {
    first: usize,
    /// (degree+1) values each of N, N', N''.
    w: [Vec<f64>; 3],
}

fn table(kv: &crate::bspline::KnotVector, samples: &[f64]) -> Vec<Table> {
    samples
        .iter()
        .map(|&t| {
            let b = basis_derivs(kv, t, 2);
            Table {
                first: b.first,
                w: [b.row(0).to_vec(), b.row(1).to_vec(), b.row(2).to_vec()],
            }
        })
        .collect()
}

fn uniform(domain: (f64, f64), n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| domain.0 + (domain.1 - domain.0) * k as f64 / (n - 1) as f64)
        .collect()
}

/// Sample counts (u, v) giving about `triangles` triangles on `surface`,
/// shared in proportion to its control grid.
pub fn samples_for(surface: &BSplineSurface, triangles: usize) -> (usize, usize) {
    let aspect = surface.nu() as f64 / surface.nv() as f64;
    let cells = (triangles as f64 / 2.0).max(1.0);
    let su = (cells * aspect).sqrt().round().max(1.0) as usize + 1;
    let sv = (cells / (su - 1) as f64).round().max(1.0) as usize + 1;
    (su, sv)
}

/// Precomputed basis tables for one knot layout and density.
#[derive(Clone, Debug)]
pub struct Tessellator {
    us: Vec<f64>,
    vs: Vec<f64>,
    tu: Vec<Table>,
    tv: Vec<Table>,
    knots: (Vec<f64>, Vec<f64>),
    /// Scratch: v-contracted rows, nu × samples_v × 3.
    rows: Vec<DVec3>,
}

impl Tessellator {
    /// Tables for `surface`'s knots with `samples_u × samples_v` vertices
    /// (each at least 2), uniform in the parameter domain.
    pub fn new(surface: &BSplineSurface, samples_u: usize, samples_v: usize) -> Self {
        let (du, dv) = surface.domain();
        let us = uniform(du, samples_u.max(2));
        let vs = uniform(dv, samples_v.max(2));
        Self {
            tu: table(surface.u_knots(), &us),
            tv: table(surface.v_knots(), &vs),
            us,
            vs,
            knots: (
                surface.u_knots().knots().to_vec(),
                surface.v_knots().knots().to_vec(),
            ),
            rows: Vec::new(),
        }
    }

    /// Whether these tables were made for `surface`'s knot layout.
    pub fn fits(&self, surface: &BSplineSurface) -> bool {
        self.knots.0 == surface.u_knots().knots() && self.knots.1 == surface.v_knots().knots()
    }

    /// Tessellates `surface` into `out`, reusing its buffers. A surface of
    /// another knot layout gets fresh tables first.
    pub fn fill(&mut self, surface: &BSplineSurface, out: &mut Tessellation) {
        if !self.fits(surface) {
            *self = Self::new(surface, self.us.len(), self.vs.len());
        }
        let (nu, nv) = (surface.nu(), surface.nv());
        let (su, sv) = (self.us.len(), self.vs.len());
        let pts = surface.points();
        let pv = surface.v_knots().degree();
        let pu = surface.u_knots().degree();
        // Contract v: rows[(i * sv + b) * 3 + d] = Σ_j M^(d)_j(v_b) P_ij.
        self.rows.clear();
        self.rows.resize(nu * sv * 3, DVec3::ZERO);
        for i in 0..nu {
            let row = &pts[i * nv..(i + 1) * nv];
            for (b, t) in self.tv.iter().enumerate() {
                let base = (i * sv + b) * 3;
                for d in 0..3 {
                    let mut acc = DVec3::ZERO;
                    for k in 0..=pv {
                        acc += row[t.first + k] * t.w[d][k];
                    }
                    self.rows[base + d] = acc;
                }
            }
        }
        let n = su * sv;
        out.samples_u = su;
        out.samples_v = sv;
        out.positions.resize(n, [0.0; 3]);
        out.normals.resize(n, [0.0; 3]);
        out.uvs.resize(n, [0.0; 2]);
        out.mean.resize(n, 0.0);
        out.gauss.resize(n, 0.0);
        let f3 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
        for (a, t) in self.tu.iter().enumerate() {
            for b in 0..sv {
                let mut d = SurfaceDerivs::default();
                for k in 0..=pu {
                    let base = ((t.first + k) * sv + b) * 3;
                    let (c0, c1, c2) = (self.rows[base], self.rows[base + 1], self.rows[base + 2]);
                    let (n0, n1, n2) = (t.w[0][k], t.w[1][k], t.w[2][k]);
                    d.p += c0 * n0;
                    d.u += c0 * n1;
                    d.v += c1 * n0;
                    d.uu += c0 * n2;
                    d.uv += c1 * n1;
                    d.vv += c2 * n0;
                }
                let idx = a * sv + b;
                out.positions[idx] = f3(d.p);
                out.uvs[idx] = [self.us[a] as f32, self.vs[b] as f32];
                match shading_curvature(&d) {
                    Ok(c) => {
                        out.normals[idx] = f3(c.normal);
                        out.mean[idx] = c.mean as f32;
                        out.gauss[idx] = c.gauss as f32;
                    }
                    Err(Degenerate) => {
                        out.normals[idx] = f3(surface.normal(self.us[a], self.vs[b]));
                        out.mean[idx] = 0.0;
                        out.gauss[idx] = 0.0;
                    }
                }
            }
        }
        let tris = 6 * (su - 1) * (sv - 1);
        if out.indices.len() != tris {
            out.indices.clear();
            for a in 0..su - 1 {
                for b in 0..sv - 1 {
                    let i0 = (a * sv + b) as u32;
                    let i1 = ((a + 1) * sv + b) as u32;
                    let i2 = ((a + 1) * sv + b + 1) as u32;
                    let i3 = (a * sv + b + 1) as u32;
                    out.indices.extend_from_slice(&[i0, i1, i2, i0, i2, i3]);
                }
            }
        }
    }
}

/// A one-shot tessellation of `surface` with `samples_u × samples_v` vertices.
pub fn tessellate(surface: &BSplineSurface, samples_u: usize, samples_v: usize) -> Tessellation {
    let mut t = Tessellation::default();
    Tessellator::new(surface, samples_u, samples_v).fill(surface, &mut t);
    t
}

/// A curve sampled for drawing and curvature combs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CurveTessellation {
    /// Points along the curve.
    pub points: Vec<DVec3>,
    /// Curvature at each point.
    pub curvature: Vec<f64>,
    /// Principal normal at each point (toward the centre of curvature; zero where straight).
    pub normals: Vec<DVec3>,
}

/// `n` (≥ 2) samples of `curve`, uniform in its parameter.
pub fn tessellate_curve(curve: &BSplineCurve, n: usize) -> CurveTessellation {
    let (a, b) = curve.domain();
    let mut out = CurveTessellation::default();
    for t in uniform((a, b), n.max(2)) {
        let d = curve.derivs(t);
        let (k, nrm) = curve_curvature(&d).unwrap_or((0.0, DVec3::ZERO));
        out.points.push(d.p);
        out.curvature.push(k);
        out.normals.push(nrm);
    }
    out
}
