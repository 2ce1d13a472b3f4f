//! Free-form deformation (Sederberg & Parry 1986; the B-spline variant of
//! Griessmair & Purgathofer 1989): geometry embedded in a lattice moves with
//! it.
//!
//! A lattice is a [`BSplineVolume`] at rest and its current state (same
//! knots). A point is *embedded* once: its (u, v, w) in the rest lattice
//! (closed form when the rest lattice is an affine box — a parallelepiped
//! with Greville control points, Sederberg–Parry's setting; Newton inversion
//! otherwise, Coquillart's extended FFD) and then its deformed position is
//! x(u, v, w) of the current lattice. With `count = degree + 1` per direction
//! the lattice is one Bernstein (Bézier) volume, Sederberg–Parry exactly;
//! with more points it is the B-spline variant, and it is local.
//!
//! **Polygon vertices are exact**: a mesh's vertices are mapped exactly (a
//! deformed triangle's interior is not; that is inherent in moving
//! vertices). **Outside rule**: a point outside the rest lattice (by more
//! than `1e-12` in parameter, or farther than the tolerance after
//! inversion) is not deformed: it keeps its position (Sederberg–Parry's
//! convention; the deformation is then only continuous if the lattice's
//! boundary layer stays at rest).
//!
//! **Locality** ([`Ffd::move_point`]): lattice point (a, b, c) influences only
//! knot-span cells with span index a … a+l (and so on); vertices are bucketed
//! by cell at embedding, and a move recomputes only the vertices of the
//! (l+1)(m+1)(n+1) cells around the point, each from scratch (no drift).
//!
//! **B-spline curves and surfaces** are deformed by refitting
//! ([`Ffd::deform_surface`], [`Ffd::deform_curve`]): the deformed shape (a
//! piecewise polynomial of much higher degree) is interpolated at the
//! Greville abscissae of a spline space of degree ≥ 3 starting from the
//! part's own knots; the error is measured at 5 points per span per
//! direction between the interpolation sites, and every span is halved
//! until that error is within the tolerance (at most 6 rounds). The
//! tolerance is met at those samples; it is not a proved bound.

use faer::Mat;
use faer::prelude::Solve;
use glam::{DMat3, DVec3};

use super::elevate::{elevate_curve, elevate_surface};
use super::invert::Inverter;
use super::{BSplineVolume, BodyError, Dir};
use crate::bspline::{
    BSplineCurve, BSplineSurface, BasisDerivs, KnotVector, basis_derivs, basis_derivs_into,
    greville,
};

/// A lattice: the rest state and the current one.
#[derive(Clone, Debug)]
pub struct Ffd {
    rest: BSplineVolume,
    current: BSplineVolume,
    /// (origin, inverse of the axes) when the rest lattice is an affine box.
    affine: Option<(DVec3, DMat3)>,
}

/// Embedded points: each one's basis functions in the rest lattice, and the
/// points bucketed by knot-span cell.
#[derive(Clone, Debug)]
pub struct Embedding {
    /// Rest positions (returned unchanged for points outside).
    rest: Vec<DVec3>,
    /// Parameters (u, v, w) of each point (NaN for points outside).
    params: Vec<[f64; 3]>,
    /// Per inside point: index of its first basis function per direction.
    first: Vec<[u32; 3]>,
    /// Per point: the (l+1) + (m+1) + (n+1) basis values.
    weights: Vec<f64>,
    stride: usize,
    degrees: [usize; 3],
    /// CSR buckets: the points of cell (a, b, c) (first-function indices)
    /// are `cell_points[cell_start[id]..cell_start[id + 1]]`.
    cell_start: Vec<u32>,
    cell_points: Vec<u32>,
    cells: [usize; 3],
    outside: usize,
    /// Per point, added to its deformed position (empty: none); see
    /// [`Embedding::carry_residual`].
    offsets: Vec<DVec3>,
}

impl Embedding {
    /// The number of points.
    pub fn len(&self) -> usize {
        self.rest.len()
    }

    /// Whether no point is embedded.
    pub fn is_empty(&self) -> bool {
        self.rest.is_empty()
    }

    /// How many points lie outside the lattice (and are not deformed).
    pub fn outside(&self) -> usize {
        self.outside
    }

    /// The parameters (u, v, w) of point `i` in the lattice (NaN outside).
    pub fn params(&self, i: usize) -> [f64; 3] {
        self.params[i]
    }

    /// Makes the rest lattice of `ffd` give back the embedded points (to
    /// rounding, not only to the inversion's tolerance): each inside point
    /// carries its inversion residual x − B_rest(u, v, w), added to its
    /// deformed position from then on. The map stays exactly as local and
    /// affine moves stay affine; a point is then B(u, v, w) plus a constant
    /// residual (zero for an affine-box lattice, ≤ the inversion tolerance
    /// otherwise).
    pub fn carry_residual(&mut self, ffd: &Ffd) -> Result<(), BodyError> {
        self.offsets.clear();
        let mut at_rest = ffd.clone();
        at_rest.current = ffd.rest.clone();
        let mut out = vec![DVec3::ZERO; self.len()];
        at_rest.deform_all(self, &mut out)?;
        self.offsets = self.rest.iter().zip(&out).map(|(x, b)| *x - *b).collect();
        Ok(())
    }
}

fn affine_frame(v: &BSplineVolume) -> Option<(DVec3, DMat3)> {
    let c = v.counts();
    let p = v.points();
    let o = p[v.index(0, 0, 0)];
    let ax = [
        p[v.index(c[0] - 1, 0, 0)] - o,
        p[v.index(0, c[1] - 1, 0)] - o,
        p[v.index(0, 0, c[2] - 1)] - o,
    ];
    let m = DMat3::from_cols(ax[0], ax[1], ax[2]);
    if m.determinant().abs() < 1e-14 * ax.iter().map(|a| a.length()).product::<f64>() {
        return None;
    }
    let dom = v.domain();
    let g = Dir::ALL.map(|d| {
        let (a, b) = dom[d.index()];
        greville(v.knots(d))
            .into_iter()
            .map(|x| (x - a) / (b - a))
            .collect::<Vec<_>>()
    });
    let size = ax.iter().map(|a| a.length()).fold(0.0, f64::max);
    for i in 0..c[0] {
        for j in 0..c[1] {
            for k in 0..c[2] {
                let want = o + ax[0] * g[0][i] + ax[1] * g[1][j] + ax[2] * g[2][k];
                if (p[v.index(i, j, k)] - want).length() > 1e-12 * size {
                    return None;
                }
            }
        }
    }
    Some((o, m.inverse()))
}

impl Ffd {
    /// A lattice at rest in `rest` (any B-spline volume; an affine box gets
    /// closed-form embedding).
    pub fn new(rest: BSplineVolume) -> Self {
        let affine = affine_frame(&rest);
        Self {
            current: rest.clone(),
            rest,
            affine,
        }
    }

    /// The lattice at rest.
    pub fn rest(&self) -> &BSplineVolume {
        &self.rest
    }

    /// The current lattice.
    pub fn lattice(&self) -> &BSplineVolume {
        &self.current
    }

    /// The rest parameters of `x`, or None if `x` is outside the lattice.
    fn locate(&self, x: DVec3, inverter: Option<&Inverter>, tol: f64) -> Option<[f64; 3]> {
        let dom = self.rest.domain();
        if let Some((o, inv)) = self.affine {
            let s = inv * (x - o);
            let s = [s.x, s.y, s.z];
            if s.iter().any(|&t| !(-1e-12..=1.0 + 1e-12).contains(&t)) {
                return None;
            }
            Some([0, 1, 2].map(|d| dom[d].0 + (dom[d].1 - dom[d].0) * s[d].clamp(0.0, 1.0)))
        } else {
            let r = inverter?.invert(x, tol * 1e-3).ok()?;
            (r.distance <= tol).then_some(r.uvw)
        }
    }

    /// Embeds `points` in the rest lattice (`tolerance`: how far from the
    /// lattice a point may be after inversion to count as inside; unused for
    /// an affine box).
    pub fn embed(&self, points: &[DVec3], tolerance: f64) -> Result<Embedding, BodyError> {
        if let Some(i) = points.iter().position(|p| !p.is_finite()) {
            return Err(BodyError::NonFinite(format!("point {i}")));
        }
        let inverter = self.affine.is_none().then(|| Inverter::new(&self.rest));
        let degrees = self.rest.degrees();
        let stride = degrees.iter().map(|p| p + 1).sum::<usize>();
        let counts = self.rest.counts();
        let cells = [0, 1, 2].map(|d| counts[d] - degrees[d]);
        let mut params = Vec::with_capacity(points.len());
        let mut first = Vec::with_capacity(points.len());
        let mut weights = Vec::with_capacity(points.len() * stride);
        let mut b: [BasisDerivs; 3] = Default::default();
        let mut outside = 0;
        for &x in points {
            match self.locate(x, inverter.as_ref(), tolerance) {
                Some(t) => {
                    let mut f = [0u32; 3];
                    for d in 0..3 {
                        basis_derivs_into(self.rest.knots(Dir::ALL[d]), t[d], 0, &mut b[d]);
                        f[d] = b[d].first as u32;
                        weights.extend_from_slice(b[d].row(0));
                    }
                    params.push(t);
                    first.push(f);
                }
                None => {
                    outside += 1;
                    params.push([f64::NAN; 3]);
                    first.push([u32::MAX; 3]);
                    weights.extend(std::iter::repeat_n(0.0, stride));
                }
            }
        }
        // Bucket inside points by cell (first-function index per direction).
        let n_cells = cells[0] * cells[1] * cells[2];
        let cell_of =
            |f: &[u32; 3]| (f[0] as usize * cells[1] + f[1] as usize) * cells[2] + f[2] as usize;
        let mut count = vec![0u32; n_cells + 1];
        for f in first.iter().filter(|f| f[0] != u32::MAX) {
            count[cell_of(f) + 1] += 1;
        }
        for c in 0..n_cells {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        let mut cell_points = vec![0u32; points.len() - outside];
        for (i, f) in first.iter().enumerate() {
            if f[0] != u32::MAX {
                let c = cell_of(f);
                cell_points[fill[c] as usize] = i as u32;
                fill[c] += 1;
            }
        }
        Ok(Embedding {
            rest: points.to_vec(),
            params,
            first,
            weights,
            stride,
            degrees,
            cell_start: count,
            cell_points,
            cells,
            outside,
            offsets: Vec::new(),
        })
    }

    fn check(&self, emb: &Embedding, out: &[DVec3]) -> Result<(), BodyError> {
        if emb.degrees != self.rest.degrees()
            || emb.cells != [0, 1, 2].map(|d| self.rest.counts()[d] - emb.degrees[d])
        {
            return Err(BodyError::Mismatch("embedding of another lattice".into()));
        }
        if out.len() != emb.len() {
            return Err(BodyError::Mismatch(format!(
                "{} outputs for {} points",
                out.len(),
                emb.len()
            )));
        }
        Ok(())
    }

    #[inline]
    fn deform_one(&self, emb: &Embedding, i: usize) -> DVec3 {
        let f = emb.first[i];
        if f[0] == u32::MAX {
            return emb.rest[i];
        }
        let [l, m, n] = emb.degrees;
        let w = &emb.weights[i * emb.stride..(i + 1) * emb.stride];
        let (wu, rest) = w.split_at(l + 1);
        let (wv, ww) = rest.split_at(m + 1);
        let [_, nv, nw] = self.current.counts();
        let pts = self.current.points();
        let mut acc = DVec3::ZERO;
        for (a, &na) in wu.iter().enumerate() {
            for (bb, &nb) in wv.iter().enumerate() {
                let base = ((f[0] as usize + a) * nv + f[1] as usize + bb) * nw + f[2] as usize;
                let mut s = DVec3::ZERO;
                for (c, &nc) in ww.iter().enumerate() {
                    s += pts[base + c] * nc;
                }
                acc += s * (na * nb);
            }
        }
        let _ = n;
        match emb.offsets.get(i) {
            Some(o) => acc + *o,
            None => acc,
        }
    }

    /// Deformed positions of all embedded points into `out` (the baseline:
    /// every point recomputed).
    pub fn deform_all(&self, emb: &Embedding, out: &mut [DVec3]) -> Result<(), BodyError> {
        self.check(emb, out)?;
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.deform_one(emb, i);
        }
        Ok(())
    }

    /// The deformed position of one point (embedding it on the fly; outside
    /// points are returned unchanged).
    pub fn deform_point(&self, x: DVec3, tolerance: f64) -> DVec3 {
        let inverter = self.affine.is_none().then(|| Inverter::new(&self.rest));
        match self.locate(x, inverter.as_ref(), tolerance) {
            Some(t) => self.current.point(t[0], t[1], t[2]),
            None => x,
        }
    }

    /// Moves lattice point `index` to `p` and recomputes in `out` only the
    /// embedded points whose position depends on it (those in the knot-span
    /// cells of its support). `out` must hold the deformed positions for the
    /// lattice before the move. Returns how many points were recomputed.
    pub fn move_point(
        &mut self,
        index: usize,
        p: DVec3,
        emb: &Embedding,
        out: &mut [DVec3],
    ) -> Result<usize, BodyError> {
        self.move_support(index, p, emb, out, None)
    }

    /// [`Ffd::move_point`], appending the indices of the points it
    /// recomputed to `listed` (each once per call): what a caller must
    /// update after the move (normals around them, say) — no other point
    /// changed.
    pub fn move_point_listed(
        &mut self,
        index: usize,
        p: DVec3,
        emb: &Embedding,
        out: &mut [DVec3],
        listed: &mut Vec<u32>,
    ) -> Result<usize, BodyError> {
        self.move_support(index, p, emb, out, Some(listed))
    }

    fn move_support(
        &mut self,
        index: usize,
        p: DVec3,
        emb: &Embedding,
        out: &mut [DVec3],
        mut listed: Option<&mut Vec<u32>>,
    ) -> Result<usize, BodyError> {
        self.check(emb, out)?;
        self.current.set_point(index, p)?;
        let ijk = self.current.ijk(index);
        let mut range = [(0usize, 0usize); 3];
        for d in 0..3 {
            // Cells (first-function index f) with f ≤ ijk ≤ f + p.
            let lo = ijk[d].saturating_sub(emb.degrees[d]);
            let hi = ijk[d].min(emb.cells[d] - 1);
            range[d] = (lo, hi);
        }
        let mut n = 0;
        for a in range[0].0..=range[0].1 {
            for b in range[1].0..=range[1].1 {
                for c in range[2].0..=range[2].1 {
                    let id = (a * emb.cells[1] + b) * emb.cells[2] + c;
                    let (s, e) = (emb.cell_start[id] as usize, emb.cell_start[id + 1] as usize);
                    let cell = &emb.cell_points[s..e];
                    for &v in cell {
                        out[v as usize] = self.deform_one(emb, v as usize);
                    }
                    if let Some(l) = listed.as_deref_mut() {
                        l.extend_from_slice(cell);
                    }
                    n += e - s;
                }
            }
        }
        Ok(n)
    }

    /// Sets the whole current lattice (same size as the rest lattice).
    pub fn set_lattice(&mut self, points: Vec<DVec3>) -> Result<(), BodyError> {
        self.current.set_points(points)
    }

    /// The B-spline surface `s` deformed by the lattice, refitted within
    /// `tolerance` (see the module doc). Returns the surface and the largest
    /// error measured.
    pub fn deform_surface(
        &self,
        s: &BSplineSurface,
        tolerance: f64,
    ) -> Result<(BSplineSurface, f64), BodyError> {
        let inverter = self.affine.is_none().then(|| Inverter::new(&self.rest));
        let map = |x: DVec3| match self.locate(x, inverter.as_ref(), tolerance) {
            Some(t) => self.current.point(t[0], t[1], t[2]),
            None => x,
        };
        let mut space = elevate_surface(
            s,
            3usize.saturating_sub(s.u_knots().degree()),
            3usize.saturating_sub(s.v_knots().degree()),
        )?;
        let mut last_err = f64::INFINITY;
        for _ in 0..6 {
            let (ku, kv) = (space.u_knots().clone(), space.v_knots().clone());
            let (gu, gv) = (greville(&ku), greville(&kv));
            let mut values = Vec::with_capacity(gu.len() * gv.len());
            for &a in &gu {
                for &b in &gv {
                    values.push(map(s.point(a, b)));
                }
            }
            let pts = collocate_grid(&ku, &kv, &gu, &gv, values)?;
            let fit = BSplineSurface::new(ku.clone(), kv.clone(), pts)?;
            let mut err: f64 = 0.0;
            for (_, a0, a1) in ku.spans() {
                for (_, b0, b1) in kv.spans() {
                    for r in 0..5 {
                        for q in 0..5 {
                            let a = a0 + (a1 - a0) * (r as f64 + 0.5) / 5.0;
                            let b = b0 + (b1 - b0) * (q as f64 + 0.5) / 5.0;
                            err = err.max((fit.point(a, b) - map(s.point(a, b))).length());
                        }
                    }
                }
            }
            last_err = err;
            if err <= tolerance {
                return Ok((fit, err));
            }
            space = space.refine_uniform()?;
        }
        Err(BodyError::NoConvergence(format!(
            "surface refit error {last_err:e} above {tolerance:e} after 6 refinements"
        )))
    }

    /// The B-spline curve `c` deformed by the lattice, refitted within
    /// `tolerance` (as [`Ffd::deform_surface`]).
    pub fn deform_curve(
        &self,
        c: &BSplineCurve,
        tolerance: f64,
    ) -> Result<(BSplineCurve, f64), BodyError> {
        let inverter = self.affine.is_none().then(|| Inverter::new(&self.rest));
        let map = |x: DVec3| match self.locate(x, inverter.as_ref(), tolerance) {
            Some(t) => self.current.point(t[0], t[1], t[2]),
            None => x,
        };
        let mut space = elevate_curve(c, 3usize.saturating_sub(c.degree()))?;
        let mut last_err = f64::INFINITY;
        for _ in 0..6 {
            let kv = space.knots().clone();
            let g = greville(&kv);
            let (sites, lu) = collocation(&kv, &g);
            let rhs = Mat::<f64>::from_fn(sites, 3, |r, d| map(c.point(g[r]))[d]);
            let x = lu.solve(&rhs);
            let pts: Vec<DVec3> = (0..sites)
                .map(|r| DVec3::new(x[(r, 0)], x[(r, 1)], x[(r, 2)]))
                .collect();
            let fit = BSplineCurve::new(kv.clone(), pts)?;
            let mut err: f64 = 0.0;
            for (_, a0, a1) in kv.spans() {
                for r in 0..5 {
                    let t = a0 + (a1 - a0) * (r as f64 + 0.5) / 5.0;
                    err = err.max((fit.point(t) - map(c.point(t))).length());
                }
            }
            last_err = err;
            if err <= tolerance {
                return Ok((fit, err));
            }
            let mut next = space.clone();
            for (_, a, b) in kv.spans() {
                next = next.insert_knot(0.5 * (a + b))?;
            }
            space = next;
        }
        Err(BodyError::NoConvergence(format!(
            "curve refit error {last_err:e} above {tolerance:e} after 6 refinements"
        )))
    }
}

fn collocation(
    kv: &KnotVector,
    sites: &[f64],
) -> (usize, faer::linalg::solvers::PartialPivLu<f64>) {
    let n = sites.len();
    let mut a = Mat::<f64>::zeros(n, n);
    for (r, &t) in sites.iter().enumerate() {
        let b = basis_derivs(kv, t, 0);
        for (c, &v) in b.row(0).iter().enumerate() {
            a[(r, b.first + c)] = v;
        }
    }
    (n, a.partial_piv_lu())
}

/// Control points interpolating `values` (row-major, u slowest) at the
/// sites `gu × gv`.
fn collocate_grid(
    ku: &KnotVector,
    kv: &KnotVector,
    gu: &[f64],
    gv: &[f64],
    values: Vec<DVec3>,
) -> Result<Vec<DVec3>, BodyError> {
    let (nu, nv) = (gu.len(), gv.len());
    let (_, lu_u) = collocation(ku, gu);
    let (_, lu_v) = collocation(kv, gv);
    // Along u: columns are (j, coordinate).
    let rhs = Mat::<f64>::from_fn(nu, nv * 3, |i, c| values[i * nv + c / 3][c % 3]);
    let x = lu_u.solve(&rhs);
    // Along v: columns are (i, coordinate).
    let rhs = Mat::<f64>::from_fn(nv, nu * 3, |j, c| x[(c / 3, j * 3 + c % 3)]);
    let y = lu_v.solve(&rhs);
    let mut pts = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            pts.push(DVec3::new(
                y[(j, i * 3)],
                y[(j, i * 3 + 1)],
                y[(j, i * 3 + 2)],
            ));
        }
    }
    if pts.iter().any(|p| !p.is_finite()) {
        return Err(BodyError::Singular("surface collocation".into()));
    }
    Ok(pts)
}
