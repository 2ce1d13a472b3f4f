//! Interior modelling: det J > 0 proved or a fold found where det J ≤ 0
//! (checked by independent evaluation), the solid's volume by quadrature
//! against the analytic value, and figure 4's edit (edge points slid along
//! a cube's edges): the outer shape and the volume stay, the interior
//! changes; folding and shape-changing moves are refused.

use glam::DVec3;
use vsculpt_kernel::body::interior::{det_grid, det_on_plane, edit, move_keeping_shape, volume};
use vsculpt_kernel::body::{
    BSplineVolume, Body1, BodyError, Dir, Edges, InjectivityCache, check_injective,
};
use vsculpt_kernel::bspline::{BSplineCurve, KnotVector, greville};
mod body_support;
use body_support::Rng;

fn box_volume() -> BSplineVolume {
    BSplineVolume::affine(
        DVec3::new(-1.0, -1.0, -1.0),
        [DVec3::X * 2.0, DVec3::Y * 2.0, DVec3::Z * 2.0],
        [3, 3, 3],
        [5, 5, 5],
    )
    .unwrap()
}

#[test]
fn affine_box_is_injective_with_the_exact_bound_and_volume() {
    let v = box_volume();
    let r = check_injective(&v).unwrap();
    // det J = 8 everywhere: every Bernstein coefficient is 8.
    assert!((r.lower_bound - 8.0).abs() < 1e-7, "{r:?}");
    assert_eq!(r.subdivisions, 0);
    assert!((volume(&v) - 8.0).abs() < 1e-12);
    assert!(det_grid(&v, 5).iter().all(|d| (d - 8.0).abs() < 1e-12));
}

#[test]
fn a_folding_edit_is_refused_where_det_j_is_not_positive() {
    let v = box_volume();
    // Push an inner point through the opposite face: the body folds.
    let idx = v.index(2, 2, 1);
    let target = v.points()[idx] + DVec3::new(0.0, 0.0, 8.0);
    match edit(&v, &[(idx, target)]) {
        Err(BodyError::Folds { u, v: vv, w, det }) => {
            assert!(det <= 0.0);
            // Independent check at the reported place, on the edited lattice.
            let mut e = v.clone();
            e.set_point(idx, target).unwrap();
            let d = e.derivs(u, vv, w).det();
            assert!(d <= 1e-9, "det J at the reported fold is {d}");
        }
        other => panic!("{other:?}"),
    }
    // A mild edit passes, and every sample agrees det J > 0.
    let (ok, rep) = edit(&v, &[(idx, v.points()[idx] + DVec3::new(0.1, 0.0, 0.2))]).unwrap();
    assert!(rep.lower_bound > 0.0);
    assert!(
        det_grid(&ok, 9)
            .iter()
            .all(|&d| d >= rep.lower_bound - 1e-9)
    );
}

#[test]
fn a_fold_between_samples_is_found() {
    // A cubic in u whose inner control points cross over slightly:
    // x(u) = Bézier(0, 1.002, −0.002, 1), x'(u) < 0 only on (0.484, 0.516).
    let mut v = BSplineVolume::affine(
        DVec3::ZERO,
        [DVec3::X, DVec3::Y, DVec3::Z],
        [3, 1, 1],
        [4, 2, 2],
    )
    .unwrap();
    for j in 0..2 {
        for k in 0..2 {
            for (i, x) in [(1, 1.002), (2, -0.002)] {
                let idx = v.index(i, j, k);
                let p = v.points()[idx];
                v.set_point(idx, DVec3::new(x, p.y, p.z)).unwrap();
            }
        }
    }
    // A 26-point grid (step 0.04: u = 0.48, 0.52) sees nothing.
    assert!(det_grid(&v, 26).iter().all(|&d| d > 0.0));
    match check_injective(&v) {
        Err(BodyError::Folds { u, det, .. }) => {
            assert!((0.484..=0.516).contains(&u), "{u}");
            assert!(det <= 0.0);
            assert!(v.derivs(u, 0.5, 0.5).det() < 0.0);
        }
        other => panic!("{other:?}"),
    }
}

/// The knot spans of a clamped uniform direction with `n` points of
/// degree `p` that point `i` reaches (its basis function's support):
/// spans s = p … n − 1 with s − p ≤ i ≤ s.
fn spans_reached(n: usize, p: usize, i: usize) -> usize {
    (p..n).filter(|&s| s - p <= i && i <= s).count()
}

#[test]
fn kept_proofs_give_a_fresh_proof_s_verdict_and_fold() {
    // A tricubic 6³ box whose points wander one at a time, some far enough
    // to fold it: at every step the kept proofs' verdict and fold are
    // those of a proof from scratch, the bound they report is below det J
    // wherever it is sampled, and only the cells the moved point reaches
    // are proved again.
    let base = BSplineVolume::affine(
        DVec3::ZERO,
        [DVec3::X, DVec3::Y, DVec3::Z],
        [3, 3, 3],
        [6, 6, 6],
    )
    .unwrap();
    let mut cache = InjectivityCache::default();
    cache.check(&base).unwrap();
    let mut current = base.clone();
    let mut rng = Rng(0x5eed_1234);
    let (mut folds, mut proofs) = (0, 0);
    for step in 0..40 {
        let ijk = [0, 1, 2].map(|_| (rng.next() * 6.0) as usize);
        let idx = current.index(ijk[0], ijk[1], ijk[2]);
        // Every fourth move is large (likely to fold), the others small.
        let size = if step % 4 == 3 { 1.2 } else { 0.08 };
        let mut next = current.clone();
        next.set_point(idx, current.points()[idx] + rng.vec(size))
            .unwrap();
        let reached: usize = (0..3).map(|d| spans_reached(6, 3, ijk[d])).product();
        assert_eq!(cache.changed_cells(&next), reached, "point {ijk:?}");
        let fresh = check_injective(&next);
        let kept = cache.check(&next);
        match (&fresh, &kept) {
            (Ok(_), Ok(r)) => {
                proofs += 1;
                assert!(r.lower_bound > 0.0);
                let low = det_grid(&next, 7).into_iter().fold(f64::INFINITY, f64::min);
                assert!(low >= r.lower_bound * (1.0 - 1e-9), "{low} < {r:?}");
                current = next;
            }
            (Err(a), Err(b)) => {
                folds += 1;
                assert_eq!(a, b);
                // A refused lattice leaves the kept proofs as they were.
                assert_eq!(cache.last(), Some(&current));
            }
            _ => panic!("step {step}: fresh {fresh:?}, kept {kept:?}"),
        }
    }
    assert!(folds > 0 && proofs > 0, "{folds} folds, {proofs} proofs");
    // The unchanged lattice is proved again without proving any cell.
    assert_eq!(cache.changed_cells(&current), 0);
    // Another knot vector is a new space: every cell is proved.
    let other = BSplineVolume::affine(
        DVec3::ZERO,
        [DVec3::X, DVec3::Y, DVec3::Z],
        [3, 3, 3],
        [6, 6, 7],
    )
    .unwrap();
    assert_eq!(cache.changed_cells(&other), 3 * 3 * 4);
}

/// A straight cubic edge with its control points at Greville spacing.
fn line(a: DVec3, b: DVec3) -> BSplineCurve {
    let kv = KnotVector::clamped_uniform(3, 5).unwrap();
    let g = greville(&kv);
    BSplineCurve::new(kv, g.iter().map(|&t| a + (b - a) * t).collect()).unwrap()
}

fn cube_body1() -> BSplineVolume {
    let c =
        |i: usize, j: usize, k: usize| DVec3::new(i as f64, j as f64, k as f64) * 2.0 - DVec3::ONE;
    let e = Edges {
        u: [
            [line(c(0, 0, 0), c(1, 0, 0)), line(c(0, 0, 1), c(1, 0, 1))],
            [line(c(0, 1, 0), c(1, 1, 0)), line(c(0, 1, 1), c(1, 1, 1))],
        ],
        v: [
            [line(c(0, 0, 0), c(0, 1, 0)), line(c(0, 0, 1), c(0, 1, 1))],
            [line(c(1, 0, 0), c(1, 1, 0)), line(c(1, 0, 1), c(1, 1, 1))],
        ],
        w: [
            [line(c(0, 0, 0), c(0, 0, 1)), line(c(0, 1, 0), c(0, 1, 1))],
            [line(c(1, 0, 0), c(1, 0, 1)), line(c(1, 1, 0), c(1, 1, 1))],
        ],
    };
    Body1::new(e, 1e-12).unwrap().to_volume().unwrap()
}

fn on_cube(p: DVec3) -> bool {
    let m = p.x.abs().max(p.y.abs()).max(p.z.abs());
    (m - 1.0).abs() < 1e-12
}

#[test]
fn figure_4_edge_points_slide_the_interior_and_keep_the_shape() {
    let v = cube_body1();
    assert!((volume(&v) - 8.0).abs() < 1e-12);
    let near_before = v.point(0.1, 0.1, 0.2);
    // Slide the second control point of the w-edges at u = 0 toward the
    // bottom, and the u-edge's at v = w = 0 toward its start (figure 4: the
    // interior crowds toward a corner).
    let mut cur = v.clone();
    for (i, j, k, target) in [
        (0, 0, 1, DVec3::new(-1.0, -1.0, -1.0)),
        (0, 4, 1, DVec3::new(-1.0, 1.0, -1.0)),
        (1, 0, 0, DVec3::new(-1.0, -1.0, -1.0)),
        (0, 0, 3, DVec3::new(-1.0, -1.0, 0.0)),
    ] {
        let idx = cur.index(i, j, k);
        let before = cur.points()[idx];
        // Aim partly off the edge: the move is projected onto the edge line.
        let aim = before + (target - before) * 0.6 + DVec3::new(0.3, 0.2, 0.0);
        let (next, at) = move_keeping_shape(&cur, idx, aim).unwrap();
        assert!(on_cube(at));
        cur = next;
    }
    // The outer shape stays: boundary samples on the cube, the same volume.
    let mut rng = Rng(1);
    for _ in 0..500 {
        let (a, b) = (rng.next(), rng.next());
        for p in [
            cur.point(0.0, a, b),
            cur.point(1.0, a, b),
            cur.point(a, 0.0, b),
            cur.point(a, b, 1.0),
        ] {
            assert!(on_cube(p), "{p}");
        }
    }
    assert!((volume(&cur) - 8.0).abs() < 1e-11, "{}", volume(&cur));
    // The interior changed: the centre parameter maps elsewhere and det J
    // is no longer uniform.
    assert!((cur.point(0.1, 0.1, 0.2) - near_before).length() > 1e-3);
    let d = det_grid(&cur, 7);
    let (lo, hi) = d
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), &x| (l.min(x), h.max(x)));
    assert!(hi / lo > 1.5, "{lo} {hi}");
    // The cutting plane reports det J with positions.
    let plane = det_on_plane(&cur, Dir::W, 0.5, 5);
    assert_eq!(plane.len(), 25);
    assert!(
        plane
            .iter()
            .all(|(p, d)| p.z.abs() <= 1.0 + 1e-12 && *d > 0.0)
    );
}

#[test]
fn shape_changing_and_folding_moves_are_refused() {
    let v = cube_body1();
    // A corner.
    let corner = v.index(0, 0, 0);
    assert!(matches!(
        move_keeping_shape(&v, corner, DVec3::ZERO),
        Err(BodyError::Mismatch(_))
    ));
    // Past the edge's end: the edge folds back on itself.
    let idx = v.index(0, 0, 1);
    assert!(matches!(
        move_keeping_shape(&v, idx, DVec3::new(-1.0, -1.0, 1.5)),
        Err(BodyError::Folds { .. })
    ));
    // A face of a bent body is curved: its points cannot move.
    let mut bent = v.clone();
    let mid = bent.index(2, 2, 4);
    bent.set_point(mid, bent.points()[mid] + DVec3::Z * 0.5)
        .unwrap();
    let face_pt = bent.index(1, 2, 4);
    assert!(matches!(
        move_keeping_shape(&bent, face_pt, DVec3::new(0.0, 0.0, 1.0)),
        Err(BodyError::Mismatch(_))
    ));
    // Inner points move freely.
    let inner = v.index(2, 2, 2);
    let (moved, at) = move_keeping_shape(&v, inner, DVec3::new(0.3, 0.2, 0.1)).unwrap();
    assert_eq!(at, DVec3::new(0.3, 0.2, 0.1));
    assert!((volume(&moved) - 8.0).abs() < 1e-11);
    assert!(move_keeping_shape(&v, 10_000, DVec3::ZERO).is_err());
}

/// A straight cubic edge from a to b with its inner control points at the
/// given fractions.
fn line_at(a: DVec3, b: DVec3, f: [f64; 3]) -> BSplineCurve {
    let kv = KnotVector::clamped_uniform(3, 5).unwrap();
    let t = [0.0, f[0], f[1], f[2], 1.0];
    BSplineCurve::new(kv, t.iter().map(|&s| a + (b - a) * s).collect()).unwrap()
}

#[test]
fn figure_4_at_the_coons_level_moves_the_whole_interior() {
    let c =
        |i: usize, j: usize, k: usize| DVec3::new(i as f64, j as f64, k as f64) * 2.0 - DVec3::ONE;
    let g = [1.0 / 6.0, 0.5, 5.0 / 6.0];
    // The four w-edges' de Boor points crowd toward w = 0.
    let crowd = [0.05, 0.15, 0.4];
    let e = Edges {
        u: [
            [
                line_at(c(0, 0, 0), c(1, 0, 0), g),
                line_at(c(0, 0, 1), c(1, 0, 1), g),
            ],
            [
                line_at(c(0, 1, 0), c(1, 1, 0), g),
                line_at(c(0, 1, 1), c(1, 1, 1), g),
            ],
        ],
        v: [
            [
                line_at(c(0, 0, 0), c(0, 1, 0), g),
                line_at(c(0, 0, 1), c(0, 1, 1), g),
            ],
            [
                line_at(c(1, 0, 0), c(1, 1, 0), g),
                line_at(c(1, 0, 1), c(1, 1, 1), g),
            ],
        ],
        w: [
            [
                line_at(c(0, 0, 0), c(0, 0, 1), crowd),
                line_at(c(0, 1, 0), c(0, 1, 1), crowd),
            ],
            [
                line_at(c(1, 0, 0), c(1, 0, 1), crowd),
                line_at(c(1, 1, 0), c(1, 1, 1), crowd),
            ],
        ],
    };
    let before = cube_body1();
    let after = Body1::new(e, 1e-12).unwrap().to_volume().unwrap();
    check_injective(&after).unwrap();
    assert!((volume(&after) - 8.0).abs() < 1e-11);
    let mut rng = Rng(2);
    for _ in 0..500 {
        let (a, b) = (rng.next(), rng.next());
        for p in [
            after.point(0.0, a, b),
            after.point(a, 1.0, b),
            after.point(a, b, 0.0),
            after.point(a, b, 1.0),
        ] {
            assert!(on_cube(p), "{p}");
        }
    }
    // The centre's iso-surface w = 0.5 sinks toward the bottom: z < 0.
    let mid_before = before.point(0.5, 0.5, 0.5);
    let mid_after = after.point(0.5, 0.5, 0.5);
    assert!(mid_before.z.abs() < 1e-12);
    assert!(mid_after.z < -0.2, "{mid_after}");
}
