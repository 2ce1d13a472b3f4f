//! The constrained solver: minimises δᵀKδ − 2δ·b subject to C(P_ref + δ) = d
//! (see [`super::problem`]) by the Schur complement over a prefactored K.
//!
//! With Y = K⁻¹Cᵀ and S = C K⁻¹ Cᵀ:
//!
//! ```text
//! δ0 = K⁻¹ b,   λ = S⁺ (C δ0 + C P_ref − d),   δ = δ0 − Y λ
//! ```
//!
//! Every load and every equation is built from a [`ScalarRow`] a_c, so all
//! of K⁻¹b and Y are combinations of the columns Z = K⁻¹[a_c], computed in
//! one batched solve when the problem changes and cached by row, so adding
//! one icon solves only for its new rows. S is assembled from the small Gram
//! matrix G = Aᵀ Z. S⁺ is a pseudo-inverse by symmetric eigendecomposition:
//! redundant equations (eigenvalues below 1e-11 of the largest) are dropped
//! and contradictory ones get the least-squares compromise in the S-norm;
//! the residual |C P − d| is reported, never NaN.
//!
//! A drag frame moves one group's input t (targets and forces, see
//! [`super::problem`]); δ is affine in t, δ(t) = δ_base + R t, so the first
//! drag of a group computes R (three N-vectors of DVec3, coupled across
//! coordinates when projected equations exist) and every later frame costs
//! 3N multiply-adds: no sparse solve, no allocation.

use std::collections::HashMap;

use faer::Mat;
use glam::DVec3;

use super::factor::Factor;
use super::{Equation, GroupKey, Problem, ScalarRow, SolveError};
use crate::energy::Stiffness;

/// What a solve achieved.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveReport {
    /// max |C P − d| over all scalar equations (0 when there are none).
    pub constraint_residual: f64,
    /// How many scalar equations were redundant or contradictory (dropped
    /// eigen-directions of S).
    pub rank_deficiency: usize,
    /// The number of scalar equations.
    pub equations: usize,
}

/// One term α · (a_col applied to coordinate k).
#[derive(Clone, Copy, Debug)]
struct Term {
    k: usize,
    col: usize,
    coef: f64,
}

/// One scalar equation.
#[derive(Clone, Debug)]
struct ScalarEq {
    terms: Vec<Term>,
    target: f64,
    group: usize,
    /// The coordinate of the drag input that shifts this equation's target.
    shift: Option<usize>,
}

#[derive(Clone, Debug)]
struct LoadCol {
    col: usize,
    force: DVec3,
    gain: f64,
    group: usize,
}

/// Bit-exact key of a row, for caching its column of Z.
type RowKey = (Vec<usize>, Vec<u64>);

fn row_key(r: &ScalarRow) -> RowKey {
    (
        r.indices.clone(),
        r.weights.iter().map(|w| w.to_bits()).collect(),
    )
}

/// The cached response of one group to its drag input.
#[derive(Debug)]
struct Response {
    group: usize,
    kind: ResponseKind,
}

/// δ(t) − δ(0) = R t. Without projected equations every coordinate answers
/// alone and alike, so R = ρ ⊗ I with one scalar field ρ: a third of the
/// memory traffic per frame.
#[derive(Debug)]
enum ResponseKind {
    Uniform(Vec<f64>),
    Coupled([Vec<DVec3>; 3]),
}

impl ResponseKind {
    fn new(r: [Vec<DVec3>; 3]) -> Self {
        let scale = r
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs().max_element()));
        let tol = 1e-12 * scale.max(1e-300);
        let uniform = (0..r[0].len()).all(|i| {
            let (a, b, c) = (r[0][i], r[1][i], r[2][i]);
            a.y.abs() <= tol
                && a.z.abs() <= tol
                && b.x.abs() <= tol
                && b.z.abs() <= tol
                && c.x.abs() <= tol
                && c.y.abs() <= tol
                && (a.x - b.y).abs() <= tol
                && (a.x - c.z).abs() <= tol
        });
        if uniform {
            ResponseKind::Uniform(r[0].iter().map(|v| v.x).collect())
        } else {
            ResponseKind::Coupled(r)
        }
    }
}

/// The solution with every drag input at zero, for one reference shape.
#[derive(Debug)]
struct Base {
    reference: Vec<DVec3>,
    /// reference + δ(0).
    start: Vec<DVec3>,
}

/// Solves the problem icons hand it, fast enough for drag frames.
#[derive(Debug)]
pub struct Solver {
    factor: Factor,
    problem: Problem,
    rows: Vec<ScalarRow>,
    z: Mat<f64>,
    g: Vec<f64>,
    eqs: Vec<ScalarEq>,
    loads: Vec<LoadCol>,
    s_pinv: Vec<f64>,
    rank_deficiency: usize,
    base: Option<Base>,
    response: Option<Response>,
}

impl Solver {
    /// Factors `stiffness` (symbolic and numeric); the problem starts empty.
    pub fn new(stiffness: Stiffness) -> Result<Self, SolveError> {
        let factor = Factor::new(stiffness)?;
        let n = factor.dim();
        Ok(Self {
            factor,
            problem: Problem::default(),
            rows: Vec::new(),
            z: Mat::zeros(n, 0),
            g: Vec::new(),
            eqs: Vec::new(),
            loads: Vec::new(),
            s_pinv: Vec::new(),
            rank_deficiency: 0,
            base: None,
            response: None,
        })
    }

    /// The number of control points.
    pub fn dim(&self) -> usize {
        self.factor.dim()
    }

    /// The factored stiffness.
    pub fn stiffness(&self) -> &Stiffness {
        self.factor.stiffness()
    }

    /// Refactors for a new stiffness (numeric only when the pattern is
    /// unchanged) and recomputes the problem's columns. On error nothing changes.
    pub fn refactor(&mut self, stiffness: Stiffness) -> Result<(), SolveError> {
        if stiffness.dim() != self.dim() {
            let mut fresh = Solver::new(stiffness)?;
            fresh.set_problem(self.problem.clone())?;
            *self = fresh;
            return Ok(());
        }
        // Factor::refactor keeps the old factor when it fails.
        let old = self.factor.stiffness().clone();
        self.factor.refactor(stiffness)?;
        let problem = std::mem::take(&mut self.problem);
        self.rows.clear();
        self.z = Mat::zeros(self.dim(), 0);
        if let Err(e) = self.set_problem(problem.clone()) {
            // Only reachable if the problem was valid before and S fails now:
            // go back to the old stiffness so nothing changes.
            self.factor.refactor(old)?;
            self.set_problem(problem)?;
            return Err(e);
        }
        Ok(())
    }

    /// The current problem.
    pub fn problem(&self) -> &Problem {
        &self.problem
    }

    /// Takes a new problem: validates it, reuses the columns of rows seen
    /// before, solves for the new ones in one batch, assembles S and its
    /// pseudo-inverse. On error nothing changes.
    pub fn set_problem(&mut self, problem: Problem) -> Result<(), SolveError> {
        let n = self.dim();
        validate(&problem, n)?;
        // Columns: one per equation row and per load row, deduplicated.
        let mut rows: Vec<ScalarRow> = Vec::new();
        let mut index: HashMap<RowKey, usize> = HashMap::new();
        let mut col_of = |r: &ScalarRow, rows: &mut Vec<ScalarRow>| -> usize {
            *index.entry(row_key(r)).or_insert_with(|| {
                rows.push(r.clone());
                rows.len() - 1
            })
        };
        let mut eqs = Vec::new();
        let mut loads = Vec::new();
        for (gi, group) in problem.groups.iter().enumerate() {
            for eq in &group.equations {
                match eq {
                    Equation::Vector { row, target } => {
                        let col = col_of(row, &mut rows);
                        for k in 0..3 {
                            eqs.push(ScalarEq {
                                terms: vec![Term { k, col, coef: 1.0 }],
                                target: target[k],
                                group: gi,
                                shift: Some(k),
                            });
                        }
                    }
                    Equation::Projected {
                        row,
                        direction,
                        target,
                    } => {
                        let col = col_of(row, &mut rows);
                        eqs.push(ScalarEq {
                            terms: (0..3)
                                .filter(|&k| direction[k] != 0.0)
                                .map(|k| Term {
                                    k,
                                    col,
                                    coef: direction[k],
                                })
                                .collect(),
                            target: *target,
                            group: gi,
                            shift: None,
                        });
                    }
                }
            }
            for load in &group.loads {
                let col = col_of(&load.row, &mut rows);
                loads.push(LoadCol {
                    col,
                    force: load.force,
                    gain: load.drag_gain,
                    group: gi,
                });
            }
        }
        // Z: reuse cached columns, solve for the rest in one batch.
        let old: HashMap<RowKey, usize> = self
            .rows
            .iter()
            .enumerate()
            .map(|(c, r)| (row_key(r), c))
            .collect();
        let mut z = Mat::<f64>::zeros(n, rows.len());
        let missing: Vec<usize> = (0..rows.len())
            .filter(|c| !old.contains_key(&row_key(&rows[*c])))
            .collect();
        if !missing.is_empty() {
            let mut rhs = Mat::<f64>::zeros(n, missing.len());
            for (m, &c) in missing.iter().enumerate() {
                for (&i, &w) in rows[c].indices.iter().zip(&rows[c].weights) {
                    rhs[(i, m)] += w;
                }
            }
            self.factor.solve_in_place(rhs.as_mut());
            for (m, &c) in missing.iter().enumerate() {
                z.col_mut(c).copy_from(rhs.col(m));
            }
        }
        for (c, r) in rows.iter().enumerate() {
            if let Some(&oc) = old.get(&row_key(r)) {
                z.col_mut(c).copy_from(self.z.col(oc));
            }
        }
        // G = Aᵀ Z.
        let nc = rows.len();
        let mut g = vec![0.0; nc * nc];
        for (a, row) in rows.iter().enumerate() {
            for b in 0..nc {
                let zb = z.col_as_slice(b);
                g[a * nc + b] = row
                    .indices
                    .iter()
                    .zip(&row.weights)
                    .map(|(&i, &w)| w * zb[i])
                    .sum();
            }
        }
        // S = C K⁻¹ Cᵀ and its pseudo-inverse.
        let m = eqs.len();
        let mut s = Mat::<f64>::zeros(m, m);
        for (e, ee) in eqs.iter().enumerate() {
            for (f, ff) in eqs.iter().enumerate().skip(e) {
                let mut v = 0.0;
                for t in &ee.terms {
                    for u in ff.terms.iter().filter(|u| u.k == t.k) {
                        v += t.coef * u.coef * g[t.col * nc + u.col];
                    }
                }
                s[(e, f)] = v;
                s[(f, e)] = v;
            }
        }
        let (s_pinv, rank_deficiency) = pseudo_inverse(&s)?;
        self.problem = problem;
        self.rows = rows;
        self.z = z;
        self.g = g;
        self.eqs = eqs;
        self.loads = loads;
        self.s_pinv = s_pinv;
        self.rank_deficiency = rank_deficiency;
        self.base = None;
        self.response = None;
        Ok(())
    }

    /// Solves with the problem's targets and forces (every drag input zero):
    /// `out = reference + δ`.
    pub fn solve(
        &mut self,
        reference: &[DVec3],
        out: &mut [DVec3],
    ) -> Result<SolveReport, SolveError> {
        self.check_io(reference, out)?;
        let cx = self.c_times(reference);
        let delta = self.refined_delta(&self.inputs(None, DVec3::ZERO), &cx);
        for ((o, r), d) in out.iter_mut().zip(reference).zip(&delta) {
            *o = *r + *d;
        }
        self.base = Some(Base {
            reference: reference.to_vec(),
            start: out.to_vec(),
        });
        Ok(self.report(out, None, DVec3::ZERO))
    }

    /// A drag frame: group `key`'s drag input set to `t`, everything else as
    /// in the problem. The first call for a group (or after the reference
    /// changed) costs one dense pass over Z; later calls cost 3N
    /// multiply-adds.
    pub fn drag(
        &mut self,
        key: GroupKey,
        t: DVec3,
        reference: &[DVec3],
        out: &mut [DVec3],
    ) -> Result<SolveReport, SolveError> {
        let cached = self.base.as_ref().is_some_and(|b| b.reference == reference);
        if cached {
            // Same reference as the cached base: already checked.
            if out.len() != reference.len() {
                return Err(SolveError::Size {
                    expected: reference.len(),
                    got: out.len(),
                });
            }
        } else {
            self.check_io(reference, out)?;
        }
        if !t.is_finite() {
            return Err(SolveError::NotFinite("drag input".into()));
        }
        let group = self
            .problem
            .groups
            .iter()
            .position(|g| g.key == key)
            .ok_or(SolveError::UnknownGroup(key))?;
        if !cached {
            let cx = self.c_times(reference);
            let delta = self.refined_delta(&self.inputs(None, DVec3::ZERO), &cx);
            let start = reference.iter().zip(&delta).map(|(r, d)| *r + *d).collect();
            self.base = Some(Base {
                reference: reference.to_vec(),
                start,
            });
        }
        if self.response.as_ref().is_none_or(|r| r.group != group) {
            let zero = vec![0.0; self.eqs.len()];
            let r = [DVec3::X, DVec3::Y, DVec3::Z].map(|e| {
                let inputs = self.unit_inputs(group, e);
                self.refined_delta(&inputs, &zero)
            });
            self.response = Some(Response {
                group,
                kind: ResponseKind::new(r),
            });
        }
        let (Some(base), Some(resp)) = (&self.base, &self.response) else {
            return Err(SolveError::Factor("drag caches missing".into()));
        };
        match &resp.kind {
            ResponseKind::Uniform(rho) => {
                for ((o, s), r) in out.iter_mut().zip(&base.start).zip(rho) {
                    *o = *s + t * *r;
                }
            }
            ResponseKind::Coupled([r0, r1, r2]) => {
                for i in 0..out.len() {
                    out[i] = base.start[i] + r0[i] * t.x + r1[i] * t.y + r2[i] * t.z;
                }
            }
        }
        Ok(self.report(out, Some(group), t))
    }

    fn check_io(&self, reference: &[DVec3], out: &[DVec3]) -> Result<(), SolveError> {
        let n = self.dim();
        for len in [reference.len(), out.len()] {
            if len != n {
                return Err(SolveError::Size {
                    expected: n,
                    got: len,
                });
            }
        }
        if reference.iter().any(|p| !p.is_finite()) {
            return Err(SolveError::NotFinite("reference shape".into()));
        }
        Ok(())
    }

    /// (C P)_e for every scalar equation.
    fn c_times(&self, p: &[DVec3]) -> Vec<f64> {
        let applied: Vec<DVec3> = self.rows.iter().map(|r| r.apply(p)).collect();
        self.eqs
            .iter()
            .map(|e| e.terms.iter().map(|t| t.coef * applied[t.col][t.k]).sum())
            .collect()
    }

    /// Targets and forces with group `shifted`'s drag input at `t`.
    fn inputs(&self, shifted: Option<usize>, t: DVec3) -> Inputs {
        Inputs {
            targets: self
                .eqs
                .iter()
                .map(|e| match (e.shift, shifted) {
                    (Some(k), Some(g)) if e.group == g => e.target + t[k],
                    _ => e.target,
                })
                .collect(),
            forces: self
                .loads
                .iter()
                .map(|l| {
                    if Some(l.group) == shifted {
                        l.force + t * l.gain
                    } else {
                        l.force
                    }
                })
                .collect(),
        }
    }

    /// The derivative of the inputs with respect to group `group`'s drag input along `e`.
    fn unit_inputs(&self, group: usize, e: DVec3) -> Inputs {
        Inputs {
            targets: self
                .eqs
                .iter()
                .map(|q| match q.shift {
                    Some(k) if q.group == group => e[k],
                    _ => 0.0,
                })
                .collect(),
            forces: self
                .loads
                .iter()
                .map(|l| {
                    if l.group == group {
                        e * l.gain
                    } else {
                        DVec3::ZERO
                    }
                })
                .collect(),
        }
    }

    /// δ = Z w for the given targets/forces and C·P_ref, and the Lagrange
    /// multipliers λ.
    fn delta_lambda(&self, inputs: &Inputs, cx: &[f64]) -> (Vec<DVec3>, Vec<f64>) {
        let nc = self.rows.len();
        let mut w = vec![DVec3::ZERO; nc];
        for (l, f) in self.loads.iter().zip(&inputs.forces) {
            w[l.col] += *f;
        }
        // r = C δ0 + C P_ref − d, with C δ0 from G.
        let r: Vec<f64> = self
            .eqs
            .iter()
            .enumerate()
            .map(|(e, eq)| {
                let cd0: f64 = eq
                    .terms
                    .iter()
                    .map(|t| {
                        t.coef
                            * self
                                .loads
                                .iter()
                                .zip(&inputs.forces)
                                .map(|(l, f)| self.g[t.col * nc + l.col] * f[t.k])
                                .sum::<f64>()
                    })
                    .sum();
                cd0 + cx[e] - inputs.targets[e]
            })
            .collect();
        let m = self.eqs.len();
        let mut lambdas = vec![0.0; m];
        for (e, eq) in self.eqs.iter().enumerate() {
            let lambda: f64 = (0..m).map(|f| self.s_pinv[e * m + f] * r[f]).sum();
            lambdas[e] = lambda;
            for t in &eq.terms {
                w[t.col][t.k] -= t.coef * lambda;
            }
        }
        let mut delta = vec![DVec3::ZERO; self.dim()];
        for (c, wc) in w.iter().enumerate() {
            if *wc == DVec3::ZERO {
                continue;
            }
            let zc = self.z.col_as_slice(c);
            for (d, &zi) in delta.iter_mut().zip(zc) {
                *d += *wc * zi;
            }
        }
        (delta, lambdas)
    }

    /// δ with one step of iterative refinement on the optimality conditions
    /// K δ + Cᵀλ = b, C δ = d − C P_ref: the correction costs one 3-column
    /// sparse solve and recovers the digits lost to cancellation in δ0 − Yλ
    /// when the mass term is small (K is then ill-conditioned in its affine
    /// modes).
    fn refined_delta(&mut self, inputs: &Inputs, cx: &[f64]) -> Vec<DVec3> {
        let (mut delta, lambda) = self.delta_lambda(inputs, cx);
        if self.eqs.is_empty() && self.loads.is_empty() {
            return delta;
        }
        let n = self.dim();
        // ρ = b − K δ − Cᵀ λ, per coordinate.
        let mut rho = Mat::<f64>::zeros(n, 3);
        for (l, f) in self.loads.iter().zip(&inputs.forces) {
            let row = &self.rows[l.col];
            for (&i, &w) in row.indices.iter().zip(&row.weights) {
                for k in 0..3 {
                    rho[(i, k)] += w * f[k];
                }
            }
        }
        for (eq, lam) in self.eqs.iter().zip(&lambda) {
            for t in &eq.terms {
                let row = &self.rows[t.col];
                for (&i, &w) in row.indices.iter().zip(&row.weights) {
                    rho[(i, t.k)] -= t.coef * lam * w;
                }
            }
        }
        let max_abs = |m: &Mat<f64>| {
            (0..m.ncols())
                .flat_map(|k| m.col_as_slice(k).iter())
                .fold(0.0f64, |a, &b| a.max(b.abs()))
        };
        let mut scale = max_abs(&rho);
        for k in 0..3 {
            let x: Vec<f64> = delta.iter().map(|d| d[k]).collect();
            for (i, v) in self.stiffness().mul(&x).into_iter().enumerate() {
                scale = scale.max(v.abs());
                rho[(i, k)] -= v;
            }
        }
        // Already accurate (the usual case when the mass term is not tiny):
        // skip the extra sparse solve.
        let worst = max_abs(&rho);
        let cd: Vec<f64> = {
            let applied: Vec<DVec3> = self.rows.iter().map(|r| r.apply(&delta)).collect();
            self.eqs
                .iter()
                .map(|eq| eq.terms.iter().map(|t| t.coef * applied[t.col][t.k]).sum())
                .collect()
        };
        let target_scale = inputs
            .targets
            .iter()
            .chain(cx)
            .fold(1.0f64, |m, x| m.max(x.abs()));
        let constraint_error = self
            .eqs
            .iter()
            .enumerate()
            .map(|(e, _)| (cd[e] + cx[e] - inputs.targets[e]).abs())
            .fold(0.0f64, f64::max);
        if worst <= 1e-13 * scale.max(1e-300) && constraint_error <= 1e-12 * target_scale {
            return delta;
        }
        // y = K⁻¹ ρ, then project onto the constraints as in `delta`.
        self.factor.solve_in_place(rho.as_mut());
        let y: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new(rho[(i, 0)], rho[(i, 1)], rho[(i, 2)]))
            .collect();
        let applied: Vec<DVec3> = self.rows.iter().map(|r| r.apply(&delta)).collect();
        let applied_y: Vec<DVec3> = self.rows.iter().map(|r| r.apply(&y)).collect();
        let m = self.eqs.len();
        let r: Vec<f64> = self
            .eqs
            .iter()
            .enumerate()
            .map(|(e, eq)| {
                let c = |a: &[DVec3]| eq.terms.iter().map(|t| t.coef * a[t.col][t.k]).sum::<f64>();
                // r' = C y − σ with σ = d − C P_ref − C δ.
                c(&applied_y) - (inputs.targets[e] - cx[e] - c(&applied))
            })
            .collect();
        let mut w = vec![DVec3::ZERO; self.rows.len()];
        for (e, eq) in self.eqs.iter().enumerate() {
            let lam: f64 = (0..m).map(|f| self.s_pinv[e * m + f] * r[f]).sum();
            for t in &eq.terms {
                w[t.col][t.k] -= t.coef * lam;
            }
        }
        for (d, yi) in delta.iter_mut().zip(&y) {
            *d += *yi;
        }
        for (c, wc) in w.iter().enumerate() {
            if *wc == DVec3::ZERO {
                continue;
            }
            for (d, &zi) in delta.iter_mut().zip(self.z.col_as_slice(c)) {
                *d += *wc * zi;
            }
        }
        delta
    }

    /// The report of `out` with group `shifted`'s drag input at `t`.
    /// Allocation-free: it runs on every drag frame.
    fn report(&self, out: &[DVec3], shifted: Option<usize>, t: DVec3) -> SolveReport {
        let residual = self
            .eqs
            .iter()
            .map(|e| {
                let value: f64 = e
                    .terms
                    .iter()
                    .map(|term| term.coef * self.rows[term.col].apply(out)[term.k])
                    .sum();
                let target = match (e.shift, shifted) {
                    (Some(k), Some(g)) if e.group == g => e.target + t[k],
                    _ => e.target,
                };
                (value - target).abs()
            })
            .fold(0.0, f64::max);
        SolveReport {
            constraint_residual: residual,
            rank_deficiency: self.rank_deficiency,
            equations: self.eqs.len(),
        }
    }
}

struct Inputs {
    targets: Vec<f64>,
    forces: Vec<DVec3>,
}

fn validate(problem: &Problem, n: usize) -> Result<(), SolveError> {
    let row_ok = |r: &ScalarRow| -> Result<(), SolveError> {
        if r.indices.len() != r.weights.len() {
            return Err(SolveError::Size {
                expected: r.indices.len(),
                got: r.weights.len(),
            });
        }
        if let Some(&index) = r.indices.iter().find(|&&i| i >= n) {
            return Err(SolveError::IndexOutOfRange { index, dim: n });
        }
        if r.weights.iter().any(|w| !w.is_finite()) {
            return Err(SolveError::NotFinite("row weight".into()));
        }
        Ok(())
    };
    let mut keys = std::collections::HashSet::new();
    for g in &problem.groups {
        if !keys.insert(g.key) {
            return Err(SolveError::DuplicateGroup(g.key));
        }
        for eq in &g.equations {
            match eq {
                Equation::Vector { row, target } => {
                    row_ok(row)?;
                    if !target.is_finite() {
                        return Err(SolveError::NotFinite("equation target".into()));
                    }
                }
                Equation::Projected {
                    row,
                    direction,
                    target,
                } => {
                    row_ok(row)?;
                    if !direction.is_finite() || !target.is_finite() {
                        return Err(SolveError::NotFinite("projected equation".into()));
                    }
                    if *direction == DVec3::ZERO {
                        return Err(SolveError::ZeroDirection);
                    }
                }
            }
        }
        for l in &g.loads {
            row_ok(&l.row)?;
            if !l.force.is_finite() || !l.drag_gain.is_finite() {
                return Err(SolveError::NotFinite("load".into()));
            }
        }
    }
    Ok(())
}

/// The pseudo-inverse of the symmetric positive semi-definite `s` (row-major
/// result) and the number of dropped eigen-directions.
///
/// S is first equilibrated, Ŝ = D^-½ S D^-½ with D = diag(S), so that the
/// cut-off (1e-12 of the largest eigenvalue of Ŝ) measures linear dependence
/// between equations rather than their scale: exactly redundant equations
/// give eigenvalues at round-off level and are dropped; independent ones,
/// however differently scaled, are kept. S⁺ = D^-½ Ŝ⁺ D^-½.
fn pseudo_inverse(s: &Mat<f64>) -> Result<(Vec<f64>, usize), SolveError> {
    let m = s.nrows();
    if m == 0 {
        return Ok((Vec::new(), 0));
    }
    let scale: Vec<f64> = (0..m)
        .map(|i| {
            if s[(i, i)] > 0.0 && s[(i, i)].is_finite() {
                1.0 / s[(i, i)].sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let scaled = Mat::<f64>::from_fn(m, m, |i, j| s[(i, j)] * scale[i] * scale[j]);
    let evd = scaled
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| SolveError::Factor(format!("eigendecomposition of S: {e:?}")))?;
    let u = evd.U();
    let lam = evd.S();
    let lam: Vec<f64> = (0..m).map(|i| lam[i]).collect();
    let max = lam.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let cut = max * 1e-12;
    let mut out = vec![0.0; m * m];
    let mut dropped = 0;
    for (k, &l) in lam.iter().enumerate() {
        if l <= cut || !l.is_finite() {
            dropped += 1;
            continue;
        }
        let inv = 1.0 / l;
        for i in 0..m {
            let a = u[(i, k)] * inv * scale[i];
            if a == 0.0 {
                continue;
            }
            for j in 0..m {
                out[i * m + j] += a * u[(j, k)] * scale[j];
            }
        }
    }
    Ok((out, dropped))
}
