//! Union of bodies (paper 002 §3): checked against truths computed here
//! without the union code — boxes' unions counted cell by cell on a grid
//! their faces lie on (volume and exposed area exact, met to the classification's tolerance), and the five-body
//! chair, whose union is the strip it was cut from: the strip's boundary
//! area by Gauss–Legendre quadrature of |x_a × x_b| and its volume.

use glam::DVec3;
use vsculpt_kernel::body::demo::{chair, chair_strip};
use vsculpt_kernel::body::interior;
use vsculpt_kernel::body::union::union;
use vsculpt_kernel::body::{BSplineVolume, BodyError, Dir, Face};

/// An axis-aligned box [lo, hi] as a biquadratic-by-linear lattice (affine
/// lattices reproduce the box exactly at any degree).
fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> BSplineVolume {
    let e = [0, 1, 2].map(|a| hi[a] - lo[a]);
    BSplineVolume::affine(
        DVec3::from_array(lo),
        [DVec3::X * e[0], DVec3::Y * e[1], DVec3::Z * e[2]],
        [2, 2, 1],
        [4, 3, 3],
    )
    .unwrap()
}

/// Volume and surface area of a union of boxes whose coordinates are
/// multiples of `h`, by counting the grid's cells (centre inside a box) and
/// the faces between a filled and an empty cell.
fn counted(boxes: &[([f64; 3], [f64; 3])], h: f64) -> (f64, f64) {
    let lo = boxes
        .iter()
        .fold([f64::MAX; 3], |m, b| [0, 1, 2].map(|a| m[a].min(b.0[a])));
    let hi = boxes
        .iter()
        .fold([f64::MIN; 3], |m, b| [0, 1, 2].map(|a| m[a].max(b.1[a])));
    let n = [0, 1, 2].map(|a| ((hi[a] - lo[a]) / h).round() as i64);
    let filled = |c: [i64; 3]| {
        (0..3).all(|a| c[a] >= 0 && c[a] < n[a]) && {
            let x = [0, 1, 2].map(|a| lo[a] + (c[a] as f64 + 0.5) * h);
            boxes
                .iter()
                .any(|(l, u)| (0..3).all(|a| x[a] > l[a] && x[a] < u[a]))
        }
    };
    let (mut cells, mut faces) = (0usize, 0usize);
    for i in 0..n[0] {
        for j in 0..n[1] {
            for k in 0..n[2] {
                if !filled([i, j, k]) {
                    continue;
                }
                cells += 1;
                for a in 0..3 {
                    for s in [-1, 1] {
                        let mut c = [i, j, k];
                        c[a] += s;
                        if !filled(c) {
                            faces += 1;
                        }
                    }
                }
            }
        }
    }
    (cells as f64 * h * h * h, faces as f64 * h * h)
}

#[test]
fn overlapping_boxes_unite_to_the_counted_volume_and_area() {
    // Every coordinate but z = 0.6 is a multiple of 0.5, and every face's
    // sample grid (2 per span) has all multiples of 0.5: the planes z = 0.6
    // (B's top) and z = 0 and 0.5 on B's faces (whose z-grid steps by 0.4)
    // cut triangles, each along one straight line, so the union is exact;
    // B's and C's faces at y = 0.5 lie on each other inside A.
    let boxes = [
        ([0.0, 0.0, 0.0], [2.0, 1.0, 1.0]),
        ([1.0, 0.5, -1.0], [3.0, 1.5, 0.6]),
        ([0.5, 0.5, 0.5], [1.5, 1.5, 1.5]),
    ];
    let bodies: Vec<_> = boxes.iter().map(|(l, h)| cuboid(*l, *h)).collect();
    let (volume, area) = counted(&boxes, 0.1);
    let mesh = union(&bodies, 2).unwrap();
    // Exact but for slivers as wide as the classification's tolerance
    // (1e-9 of a body's size, ≤ 3.4e-9 here) along the seams (< 30 long).
    assert!(
        (mesh.enclosed_volume() - volume).abs() < 1e-7 && (mesh.area() - area).abs() < 1e-7,
        "volume {} against {volume}, area {} against {area}",
        mesh.enclosed_volume(),
        mesh.area()
    );
    // Every body keeps some of its boundary, and nothing is left inside.
    for b in 0..3 {
        assert!(mesh.body.contains(&b), "body {b} has no part in the union");
    }
}

#[test]
fn two_boxes_crossing_unite_to_the_counted_volume_and_area() {
    // B crosses A's faces x = 2 and y = 1 and its bottom z = 0; the plane
    // z = 0.6 cuts A's triangles, z = 0 B's, each along one straight line.
    let boxes = [
        ([0.0, 0.0, 0.0], [2.0, 1.0, 1.0]),
        ([1.0, 0.5, -1.0], [3.0, 1.5, 0.6]),
    ];
    let bodies: Vec<_> = boxes.iter().map(|(l, h)| cuboid(*l, *h)).collect();
    let (volume, area) = counted(&boxes, 0.1);
    let mesh = union(&bodies, 2).unwrap();
    // Exact but for slivers as wide as the classification's tolerance
    // (1e-9 of a body's size, ≤ 3.4e-9 here) along the seams (< 30 long).
    assert!(
        (mesh.enclosed_volume() - volume).abs() < 1e-7 && (mesh.area() - area).abs() < 1e-7,
        "volume {} against {volume}, area {} against {area}",
        mesh.enclosed_volume(),
        mesh.area()
    );
}

#[test]
fn faces_shared_by_boxes_are_interior_or_kept_once() {
    // D and E share a face with opposite normals (interior: both go); F
    // lies in D and shares four of D's faces with the same normals (kept
    // once), its fifth face lying on the face D shares with E.
    let boxes = [
        ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
        ([1.0, 0.0, 0.0], [2.0, 1.0, 1.0]),
        ([0.0, 0.0, 0.5], [1.0, 1.0, 1.0]),
    ];
    let bodies: Vec<_> = boxes.iter().map(|(l, h)| cuboid(*l, *h)).collect();
    let (volume, area) = counted(&boxes, 0.25);
    assert_eq!((volume, area), (2.0, 10.0));
    for per_span in [1, 2, 5] {
        let mesh = union(&bodies, per_span).unwrap();
        // The classification's tolerance (1e-9 of a body's size) bounds
        // slivers where faces meet at an edge.
        assert!(
            (mesh.enclosed_volume() - volume).abs() < 1e-8,
            "{per_span}: volume {}",
            mesh.enclosed_volume()
        );
        assert!(
            (mesh.area() - area).abs() < 1e-8,
            "{per_span}: area {} (an interior or doubled face left)",
            mesh.area()
        );
        // The third box adds nothing of its own.
        assert!(!mesh.body.contains(&2));
    }
}

/// Gauss–Legendre nodes and weights on [−1, 1], 5 points (Abramowitz &
/// Stegun table 25.4).
const GL5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

/// The area of `vol`'s six faces: ∫∫ |x_a × x_b| by 5-point Gauss–Legendre
/// on every knot span, each cut into `sub` × `sub` pieces.
fn boundary_area(vol: &BSplineVolume, sub: usize) -> f64 {
    let pieces = |d: Dir| {
        let mut out = Vec::new();
        for (_, a, b) in vol.knots(d).spans() {
            for s in 0..sub {
                out.push((
                    a + (b - a) * s as f64 / sub as f64,
                    a + (b - a) * (s + 1) as f64 / sub as f64,
                ));
            }
        }
        out
    };
    let mut total = 0.0;
    for face in Face::ALL {
        let (da, db) = face.dir.others();
        let dom = vol.domain()[face.dir.index()];
        let fixed = if face.end { dom.1 } else { dom.0 };
        for (a0, a1) in pieces(da) {
            for (b0, b1) in pieces(db) {
                for (xa, wa) in GL5 {
                    for (xb, wb) in GL5 {
                        let mut t = [0.0; 3];
                        t[face.dir.index()] = fixed;
                        t[da.index()] = (a0 + a1) / 2.0 + (a1 - a0) / 2.0 * xa;
                        t[db.index()] = (b0 + b1) / 2.0 + (b1 - b0) / 2.0 * xb;
                        let j = vol.derivs(t[0], t[1], t[2]);
                        let n = j.d[da.index()].cross(j.d[db.index()]);
                        total += wa * wb * n.length() * (a1 - a0) * (b1 - b0) / 4.0;
                    }
                }
            }
        }
    }
    total
}

#[test]
fn the_chair_s_five_bodies_unite_to_the_strip_they_were_cut_from() {
    let strip = chair_strip().unwrap();
    let lattice = chair().unwrap();
    let bodies = lattice.bodies().to_vec();
    let area = boundary_area(&strip, 4);
    let volume = interior::volume(&strip);
    // The faces where the bodies meet are interior: what is left is the
    // strip's boundary (area 8 · 0.04 · 0.5 = 0.16 more if they stayed).
    let mut last = f64::INFINITY;
    for per_span in [4, 8] {
        let mesh = union(&bodies, per_span).unwrap();
        let gap = (mesh.area() - area).abs() / area;
        // Inscribed triangles: the chord error falls as h², 4× per halving.
        assert!(
            gap < 2e-3 && gap < last / 3.0,
            "{per_span}: area {} against {area} ({gap:e})",
            mesh.area()
        );
        last = gap;
        let vgap = (mesh.enclosed_volume() - volume).abs() / volume;
        assert!(
            vgap < 5e-3,
            "{per_span}: volume {} against {volume}",
            mesh.enclosed_volume()
        );
        // Every body keeps its outside.
        for b in 0..bodies.len() {
            assert!(mesh.body.contains(&b));
        }
    }
}

#[test]
fn a_body_inside_another_adds_nothing_and_bad_input_is_refused() {
    let outer = cuboid([0.0; 3], [2.0; 3]);
    let inner = cuboid([0.5; 3], [1.5; 3]);
    let mesh = union(&[inner.clone(), outer.clone()], 2).unwrap();
    assert!(!mesh.body.contains(&0));
    assert!((mesh.area() - 24.0).abs() < 1e-12);
    assert!((mesh.enclosed_volume() - 8.0).abs() < 1e-12);
    assert!(matches!(
        union(std::slice::from_ref(&outer), 0),
        Err(BodyError::Mismatch(_))
    ));
    assert_eq!(union(&[], 3).unwrap().triangles.len(), 0);
}
