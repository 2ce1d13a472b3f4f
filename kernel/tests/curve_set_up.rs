//! A free-form curve constraint set up without full columns of Z (issue 15):
//! `Solver::set_problem` leaves a curve's hundreds of equation rows pending,
//! S from their forward halves on the elimination-tree reach, and the full
//! solve and the drag response solve combined rows instead of summing
//! columns. On the paper's scene (4 point constraints, a straight curve, a
//! point load) plus the free-form cubic of `server/tests/icon_creation.rs`,
//! on 20 × 15 and 81 × 159, with the load pulling or dragged:
//!
//! * the shape equals the one of the full-column path (the solver before
//!   issue 15, kept behind `Solver::set_eager_columns`) and, on 20 × 15,
//!   an independent dense solve (dense Cholesky of K over all three
//!   coordinates, no pins eliminated, the multipliers from a dense
//!   eigendecomposition of S: the curve's collocation rows outnumber what
//!   the coarse surface carries along it, so S is singular there — 33 of
//!   294 equations dependent — and consistent), to 1e-9 of the shape's
//!   size;
//! * every curve equation holds to 1e-9 at ten times the curve's sample
//!   density (the surface along the curve against its targets).

use glam::DVec3;
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector};
use vsculpt_kernel::design::Design;
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::{Anchor, IconId, IconSpec, IconState, Role};
use vsculpt_kernel::solve::{Equation, Problem, Solver};

/// The benches' wavy sheet (`benches/sculpt.rs`, the paper's Table 2 grids).
fn sheet(nu: usize, nv: usize) -> BSplineSurface {
    let (w, h) = (nu as f64 / 10.0, nv as f64 / 10.0);
    let mut s = BSplineSurface::plane(w, h, nu, nv, 3).unwrap();
    for p in s.points_mut() {
        p.z = 0.2
            * w.min(h)
            * (std::f64::consts::PI * p.x / w).sin()
            * (std::f64::consts::PI * p.y / h).sin();
    }
    s
}

/// The free-form cubic of `server/tests/icon_creation.rs`, across the plate.
fn cubic() -> BSplineCurve {
    let points = [
        (0.1, 0.12),
        (0.3, 0.3),
        (0.5, 0.05),
        (0.7, 0.35),
        (0.92, 0.15),
    ];
    BSplineCurve::new(
        KnotVector::new(3, vec![0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 1.0]).unwrap(),
        points.iter().map(|&(u, v)| DVec3::new(u, v, 0.0)).collect(),
    )
    .unwrap()
}

fn passive(anchor: Anchor, role: Role) -> IconSpec {
    IconSpec {
        anchor,
        role,
        state: IconState::Passive,
        target: None,
    }
}

/// The paper's scene plus the cubic curve constraint: the design, the
/// curve icon and the load icon.
fn scene(nu: usize, nv: usize) -> (Design, IconId, IconId) {
    let mut d = Design::new(sheet(nu, nv), SurfaceMaterial::default()).unwrap();
    d.set_adaptive_spring(false);
    for (u, v) in [(0.1, 0.1), (0.9, 0.1), (0.1, 0.9), (0.9, 0.9)] {
        d.add_icon(passive(Anchor::Point { u, v }, Role::Position))
            .unwrap();
    }
    let line = BSplineCurve::new(
        KnotVector::clamped_uniform(1, 2).unwrap(),
        vec![DVec3::new(0.2, 0.25, 0.0), DVec3::new(0.8, 0.25, 0.0)],
    )
    .unwrap();
    d.add_icon(passive(Anchor::Curve(line), Role::Position))
        .unwrap();
    let load = d
        .add_icon(passive(Anchor::Point { u: 0.5, v: 0.6 }, Role::Load))
        .unwrap();
    let curve = d
        .add_icon(passive(Anchor::Curve(cubic()), Role::Position))
        .unwrap();
    d.solve().unwrap();
    (d, curve, load)
}

/// The design's problem during a grab of the load (its group active),
/// the load pulling by `force`: a solve that moves the shape (the curve
/// crosses the straight one, so it is held where it is).
fn pulled(d: &mut Design, load: IconId, force: DVec3) -> Problem {
    d.drag_start(load).unwrap();
    let mut p = d.problem();
    let mut found = false;
    for g in &mut p.groups {
        if g.key == load.0 {
            for l in &mut g.loads {
                l.force = force;
                found = true;
            }
        }
    }
    assert!(found, "the grabbed load is in the problem");
    p
}

fn stiffness(d: &Design) -> Stiffness {
    let s = d.surface();
    Stiffness::surface(s.u_knots(), s.v_knots(), &d.material()).unwrap()
}

/// The largest coordinate of a shape (at least 1): the scale of 1e-9.
fn size(p: &[DVec3]) -> f64 {
    p.iter().fold(1.0f64, |m, q| m.max(q.abs().max_element()))
}

fn farthest(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (*p - *q).abs().max_element())
        .fold(0.0, f64::max)
}

/// Solves `problem` from `reference` with a fresh solver, the new path or
/// the full-column one (`eager`).
fn solve(k: &Stiffness, problem: &Problem, reference: &[DVec3], eager: bool) -> Vec<DVec3> {
    let mut solver = Solver::new(k.clone()).unwrap();
    solver.set_eager_columns(eager);
    solver.set_problem(problem.clone()).unwrap();
    let mut out = vec![DVec3::ZERO; reference.len()];
    let report = solver.solve(reference, &mut out).unwrap();
    assert_eq!(report.warning, None);
    out
}

/// The control points with the curve's surface along it at ten times its
/// sample density (its equations' count): how far the surface along the
/// curve is from `moved` (the start shape's curve moved by `lift`).
fn curve_error(
    surface: &BSplineSurface,
    start: &BSplineSurface,
    points: &[DVec3],
    lift: DVec3,
    samples: usize,
) -> f64 {
    let mut s = surface.clone();
    s.points_mut().copy_from_slice(points);
    let c = cubic();
    let (a, b) = c.domain();
    let n = 10 * samples;
    (0..=n)
        .map(|i| {
            let q = c.point(a + (b - a) * i as f64 / n as f64);
            (s.point(q.x, q.y) - start.point(q.x, q.y) - lift)
                .abs()
                .max_element()
        })
        .fold(0.0, f64::max)
}

/// How many vector equations the curve icon holds the surface with.
fn curve_rows(problem: &Problem, curve: IconId) -> usize {
    problem
        .groups
        .iter()
        .find(|g| g.key == curve.0)
        .map_or(0, |g| g.equations.len())
}

fn check_grid(nu: usize, nv: usize, dense: bool) {
    let (mut d, curve, load) = scene(nu, nv);
    let k = stiffness(&d);
    let reference = d.reference().to_vec();
    let scale = size(&reference);
    let force = DVec3::new(0.3, -0.2, 1.0) * scale;
    let lift = DVec3::ZERO;
    let problem = pulled(&mut d, load, force);
    let rows = curve_rows(&problem, curve);
    assert!(
        rows > 8,
        "the curve brings more rows than the old lazy path took ({rows})"
    );
    let new = solve(&k, &problem, &reference, false);
    let old = solve(&k, &problem, &reference, true);
    let moved = farthest(&new, &reference);
    assert!(moved > 1e-3 * scale, "the pull moves the shape ({moved})");
    let gap = farthest(&new, &old);
    assert!(
        gap <= 1e-9 * size(&new),
        "{nu}x{nv}: new path vs full columns {gap:e} (moved {moved:e})"
    );
    let surface = d.surface();
    let err = curve_error(surface, surface, &new, lift, rows);
    assert!(
        err <= 1e-9 * size(&new),
        "{nu}x{nv}: curve off by {err:e} at 10x its samples"
    );
    if dense {
        let (feasible, stationary) = kkt_certificate(&k, &problem, &reference, &new);
        assert!(
            feasible <= 1e-9 * size(&new),
            "{nu}x{nv}: an equation off by {feasible:e}"
        );
        assert!(
            stationary <= 1e-9,
            "{nu}x{nv}: not stationary ({stationary:e} of its terms)"
        );
        // The certificate tells: one free control point moved by 1e-6 of
        // the shape's size fails it.
        let mut off = new.clone();
        let free = off.len() / 2 + 3;
        off[free].z += 1e-6 * size(&new);
        let (f, st) = kkt_certificate(&k, &problem, &reference, &off);
        assert!(f > 1e-9 * size(&new) || st > 1e-9, "{f:e} {st:e}");
    }
}

/// How far `out` is from meeting the optimality (KKT) conditions of
/// min δᵀKδ − 2δ·b subject to C(P_ref + δ) = d over all three coordinates,
/// checked densely and independently of the solver (no factor, no pins
/// eliminated, no Schur complement): (feasibility) max |C P − d|, and
/// (stationarity) the part of b − Kδ outside the range of Cᵀ, by a dense
/// SVD of Cᵀ (singular values below 1e-10 of the largest are its null
/// space: the curve's collocation rows outnumber what the coarse surface
/// carries along it), relative to max(|b|, |K||δ|). K is positive definite,
/// so both near zero make δ the one minimiser.
fn kkt_certificate(
    k: &Stiffness,
    problem: &Problem,
    reference: &[DVec3],
    out: &[DVec3],
) -> (f64, f64) {
    let n = k.dim();
    let delta: Vec<f64> = out
        .iter()
        .zip(reference)
        .flat_map(|(o, r)| (*o - *r).to_array())
        .collect();
    // C's rows (dense over the 3n unknowns, point-major) and C P − d.
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut feasibility = 0.0f64;
    let mut b = vec![0.0; 3 * n];
    for g in &problem.groups {
        for eq in &g.equations {
            match eq {
                Equation::Vector { row, target } => {
                    for x in 0..3 {
                        let mut r = vec![0.0; 3 * n];
                        for (&i, &w) in row.indices.iter().zip(&row.weights) {
                            r[3 * i + x] += w;
                        }
                        rows.push(r);
                    }
                    feasibility = feasibility.max((row.apply(out) - *target).abs().max_element());
                }
                Equation::Projected {
                    row,
                    direction,
                    target,
                } => {
                    let mut r = vec![0.0; 3 * n];
                    for (&i, &w) in row.indices.iter().zip(&row.weights) {
                        for x in 0..3 {
                            r[3 * i + x] += w * direction[x];
                        }
                    }
                    rows.push(r);
                    feasibility = feasibility.max((row.apply(out).dot(*direction) - target).abs());
                }
            }
        }
        for l in &g.loads {
            for (&i, &w) in l.row.indices.iter().zip(&l.row.weights) {
                for x in 0..3 {
                    b[3 * i + x] += w * l.force[x];
                }
            }
        }
    }
    // g = b − Kδ and the size of its terms.
    let mut g = b.clone();
    let mut terms: f64 = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let lower = k.lower();
    let (cp, ri, v) = (
        lower.symbolic().col_ptr(),
        lower.symbolic().row_idx(),
        lower.val(),
    );
    let mut kabs = vec![0.0; 3 * n];
    for c in 0..n {
        for e in cp[c]..cp[c + 1] {
            let r = ri[e];
            for x in 0..3 {
                g[3 * r + x] -= v[e] * delta[3 * c + x];
                kabs[3 * r + x] += (v[e] * delta[3 * c + x]).abs();
                if r != c {
                    g[3 * c + x] -= v[e] * delta[3 * r + x];
                    kabs[3 * c + x] += (v[e] * delta[3 * r + x]).abs();
                }
            }
        }
    }
    terms = kabs.iter().fold(terms, |m, v| m.max(*v));
    let m = rows.len();
    let ct = faer::Mat::<f64>::from_fn(3 * n, m, |i, e| rows[e][i]);
    let svd = ct.thin_svd().unwrap();
    let (u, sigma) = (svd.U(), svd.S());
    let top = (0..m).fold(0.0f64, |a, i| a.max(sigma[i]));
    let mut perp = g.clone();
    for j in 0..m {
        if sigma[j] <= 1e-10 * top {
            continue;
        }
        let c: f64 = (0..3 * n).map(|i| u[(i, j)] * g[i]).sum();
        for (i, p) in perp.iter_mut().enumerate() {
            *p -= c * u[(i, j)];
        }
    }
    let stationarity = perp.iter().fold(0.0f64, |a, v| a.max(v.abs())) / terms.max(1e-300);
    (feasibility, stationarity)
}

#[test]
fn a_pulled_curve_solves_like_the_full_columns_and_meets_the_kkt_conditions_on_20x15() {
    check_grid(20, 15, true);
}

#[test]
fn a_pulled_curve_solves_like_the_full_columns_on_81x159() {
    check_grid(81, 159, false);
}

/// A grab of the load right after the curve was added: the drag response
/// through pending columns (combined-row solves) equals the full-column
/// path's frame by frame, and the curve holds at 10× its samples.
#[test]
fn a_drag_after_the_curve_frames_like_the_full_columns() {
    for (nu, nv) in [(20, 15), (81, 159)] {
        let (mut d, curve, load) = scene(nu, nv);
        let k = stiffness(&d);
        let reference = d.reference().to_vec();
        let scale = size(&reference);
        let problem = pulled(&mut d, load, DVec3::ZERO);
        let rows = curve_rows(&problem, curve);
        let mut solvers: Vec<Solver> = [false, true]
            .iter()
            .map(|&eager| {
                let mut s = Solver::new(k.clone()).unwrap();
                s.set_eager_columns(eager);
                s.set_problem(problem.clone()).unwrap();
                s
            })
            .collect();
        for step in 1..=3 {
            let t = DVec3::new(0.1, -0.05, 0.2) * scale * step as f64;
            let frames: Vec<Vec<DVec3>> = solvers
                .iter_mut()
                .map(|s| {
                    let mut out = vec![DVec3::ZERO; reference.len()];
                    s.drag(load.0, t, &reference, &mut out).unwrap();
                    out
                })
                .collect();
            let moved = farthest(&frames[0], &reference);
            assert!(moved > 1e-4 * scale, "the drag moves the shape ({moved})");
            let gap = farthest(&frames[0], &frames[1]);
            assert!(
                gap <= 1e-9 * size(&frames[0]),
                "{nu}x{nv} step {step}: drag frame vs full columns {gap:e}"
            );
            let err = curve_error(d.surface(), d.surface(), &frames[0], DVec3::ZERO, rows);
            assert!(
                err <= 1e-9 * size(&frames[0]),
                "{nu}x{nv} step {step}: curve off by {err:e} at 10x its samples"
            );
        }
    }
}
