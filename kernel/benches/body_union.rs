//! The union of bodies (paper 002 §3), two methods compared on accuracy
//! and time in one run (issue 13: "a well-kept mesh-boolean library, or an
//! implicit conversion; choose by measurement"):
//!
//! * **boundary** — the kernel's [`union`]: every body's faces sampled
//!   `per_span` times per knot span, clipped against the other bodies
//!   classified exactly (point inversion), the pieces welded closed;
//! * **implicit** — an implicit conversion written here for the
//!   comparison: membership in the union (inside any body, by the same
//!   point inversion) on an n-cell grid over the bodies' box, meshed by
//!   marching tetrahedra (six Kuhn tetrahedra per cell, so the mesh is
//!   closed and manifold by construction) with every crossing found by
//!   bisection of the membership along its grid edge to 2⁻³⁰ of it.
//!
//! Two cases: **boxes** — two crossing boxes (A = [0, 2]×[0, 1]×[0, 1],
//! B = [1, 3]×[0.5, 1.5]×[−1, 0.6]), whose union's volume is exactly 4.9
//! and whose boundary is known in closed form (each box's faces less the
//! other's inside: rectangles), so the distance of every mesh vertex to the
//! exact boundary is computed (its maximum: the one-sided Hausdorff
//! distance, mesh → exact); **spool + bar** — the paper's spool and a bar
//! through its waist (curved seams), its volume against the spool's
//! (quadrature) plus the bar's less their overlap by Monte Carlo (200 000
//! seeded points, σ printed); **spool + turned bar** — a bar turned and
//! tilted so that its edge pokes through spool triangles at 7 and 10
//! samples per span (refused before local subdivision, issue 13 session
//! 10), its volume likewise.
//!
//! Accuracy is printed once per method and resolution (before the timing);
//! criterion times each. Run:
//! `cargo bench -p vsculpt-kernel --bench body_union -- --warm-up-time 1 --measurement-time 3`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use std::collections::HashMap;
use std::hint::black_box;
use std::time::Instant;
use vsculpt_kernel::body::demo::spool;
use vsculpt_kernel::body::interior;
use vsculpt_kernel::body::union::{UnionMesh, union};
use vsculpt_kernel::body::{BSplineVolume, Inverter};

#[path = "../tests/body_support/mod.rs"]
mod body_support;
use body_support::{Rng, cuboid};

/// Membership in a union of bodies by point inversion.
struct Members<'a> {
    bodies: Vec<(Inverter<'a>, f64, DVec3, DVec3)>,
}

impl<'a> Members<'a> {
    fn new(vols: &'a [BSplineVolume]) -> Self {
        Self {
            bodies: vols
                .iter()
                .map(|v| {
                    let (lo, hi) = v
                        .points()
                        .iter()
                        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| {
                            (l.min(*p), h.max(*p))
                        });
                    let tol = 1e-9 * (hi - lo).length();
                    (Inverter::new(v), tol, lo, hi)
                })
                .collect(),
        }
    }

    fn inside(&self, x: DVec3) -> bool {
        self.bodies.iter().any(|(inv, tol, lo, hi)| {
            x.cmpge(*lo).all()
                && x.cmple(*hi).all()
                && inv
                    .invert(x, 1e-3 * tol)
                    .map(|r| r.distance <= *tol)
                    .unwrap_or(false)
        })
    }
}

/// The implicit union: marching tetrahedra on an `n`-cell grid (longest
/// side) over the bodies' box.
fn implicit_union(vols: &[BSplineVolume], n: usize) -> UnionMesh {
    let m = Members::new(vols);
    let (lo, hi) = m.bodies.iter().fold(
        (DVec3::INFINITY, DVec3::NEG_INFINITY),
        |(l, h), (_, _, a, b)| (l.min(*a), h.max(*b)),
    );
    let ext = hi - lo;
    let h = ext.max_element() / n as f64;
    // One empty layer around the box so the surface closes.
    let base = lo - DVec3::splat(h);
    let dims = ((ext / h).ceil().as_uvec3() + 3)
        .to_array()
        .map(|d| d as usize);
    let id = |i: usize, j: usize, k: usize| (i * dims[1] + j) * dims[2] + k;
    let corner = |c: usize| {
        let (i, j, k) = (
            c / (dims[1] * dims[2]),
            (c / dims[2]) % dims[1],
            c % dims[2],
        );
        base + DVec3::new(i as f64, j as f64, k as f64) * h
    };
    let mut inside = vec![false; dims[0] * dims[1] * dims[2]];
    for i in 1..dims[0] - 1 {
        for j in 1..dims[1] - 1 {
            for k in 1..dims[2] - 1 {
                inside[id(i, j, k)] = m.inside(corner(id(i, j, k)));
            }
        }
    }
    let mut mesh = UnionMesh::default();
    let mut on_edge: HashMap<(usize, usize), usize> = HashMap::new();
    let mut crossing = |a: usize, b: usize, mesh: &mut UnionMesh| -> usize {
        let key = (a.min(b), a.max(b));
        if let Some(&v) = on_edge.get(&key) {
            return v;
        }
        // a inside, b outside: bisection of membership.
        let (inn, out) = if inside[a] { (a, b) } else { (b, a) };
        let (p, q) = (corner(inn), corner(out));
        let (mut s0, mut s1) = (0.0f64, 1.0f64);
        for _ in 0..30 {
            let s = 0.5 * (s0 + s1);
            if m.inside(p.lerp(q, s)) {
                s0 = s;
            } else {
                s1 = s;
            }
        }
        mesh.positions.push(p.lerp(q, 0.5 * (s0 + s1)));
        on_edge.insert(key, mesh.positions.len() - 1);
        mesh.positions.len() - 1
    };
    const PERMS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    for i in 0..dims[0] - 1 {
        for j in 0..dims[1] - 1 {
            for k in 0..dims[2] - 1 {
                let at = |o: [usize; 3]| id(i + o[0], j + o[1], k + o[2]);
                for perm in PERMS {
                    let mut o = [0usize; 3];
                    let mut tet = [at(o); 4];
                    for (s, &axis) in perm.iter().enumerate() {
                        o[axis] = 1;
                        tet[s + 1] = at(o);
                    }
                    let ins: Vec<usize> = tet.iter().copied().filter(|&c| inside[c]).collect();
                    let outs: Vec<usize> = tet.iter().copied().filter(|&c| !inside[c]).collect();
                    if ins.is_empty() || outs.is_empty() {
                        continue;
                    }
                    let dir = outs.iter().map(|&c| corner(c)).sum::<DVec3>() / outs.len() as f64
                        - ins.iter().map(|&c| corner(c)).sum::<DVec3>() / ins.len() as f64;
                    let emit = |t: [usize; 3], mesh: &mut UnionMesh| {
                        let [a, b, c] = t.map(|v| mesh.positions[v]);
                        let t = if (b - a).cross(c - a).dot(dir) >= 0.0 {
                            t
                        } else {
                            [t[0], t[2], t[1]]
                        };
                        mesh.triangles.push(t);
                    };
                    match (ins.len(), outs.len()) {
                        (1, 3) | (3, 1) => {
                            let (lone, others) = if ins.len() == 1 {
                                (ins[0], &outs)
                            } else {
                                (outs[0], &ins)
                            };
                            let t = [0, 1, 2].map(|s| crossing(lone, others[s], &mut mesh));
                            emit(t, &mut mesh);
                        }
                        _ => {
                            // Two in, two out: a quad.
                            let a = crossing(ins[0], outs[0], &mut mesh);
                            let b = crossing(ins[0], outs[1], &mut mesh);
                            let c = crossing(ins[1], outs[1], &mut mesh);
                            let d = crossing(ins[1], outs[0], &mut mesh);
                            emit([a, b, c], &mut mesh);
                            emit([a, c, d], &mut mesh);
                        }
                    }
                }
            }
        }
    }
    mesh.body = vec![0; mesh.triangles.len()];
    mesh
}

/// A closed axis-aligned rectangle: the axis it is normal to, its place on
/// that axis, and its extent in all three coordinates (flat along `axis`).
#[derive(Clone, Copy)]
struct Rect {
    lo: DVec3,
    hi: DVec3,
}

impl Rect {
    fn distance(&self, p: DVec3) -> f64 {
        p.clamp(self.lo, self.hi).distance(p)
    }
}

/// The faces of box `a` less the inside of box `b`: rectangles.
fn faces_outside(a: ([f64; 3], [f64; 3]), b: ([f64; 3], [f64; 3])) -> Vec<Rect> {
    let mut out = Vec::new();
    for axis in 0..3 {
        for end in [a.0[axis], a.1[axis]] {
            let (mut lo, mut hi) = (DVec3::from_array(a.0), DVec3::from_array(a.1));
            lo[axis] = end;
            hi[axis] = end;
            // B's open inside meets this plane in an open rectangle.
            let cuts = end > b.0[axis] && end < b.1[axis];
            let (p, q) = ((axis + 1) % 3, (axis + 2) % 3);
            let s_lo = DVec3::from_array(b.0).max(lo);
            let s_hi = DVec3::from_array(b.1).min(hi);
            if !cuts || s_lo[p] >= s_hi[p] || s_lo[q] >= s_hi[q] {
                out.push(Rect { lo, hi });
                continue;
            }
            // The face less the hole: up to four rectangles.
            let mut push = |plo: f64, phi: f64, qlo: f64, qhi: f64| {
                if phi > plo && qhi > qlo {
                    let (mut l, mut h) = (lo, hi);
                    l[p] = plo;
                    h[p] = phi;
                    l[q] = qlo;
                    h[q] = qhi;
                    out.push(Rect { lo: l, hi: h });
                }
            };
            push(lo[p], s_lo[p], lo[q], hi[q]);
            push(s_hi[p], hi[p], lo[q], hi[q]);
            push(s_lo[p], s_hi[p], lo[q], s_lo[q]);
            push(s_lo[p], s_hi[p], s_hi[q], hi[q]);
        }
    }
    out
}

const A: ([f64; 3], [f64; 3]) = ([0.0, 0.0, 0.0], [2.0, 1.0, 1.0]);
const B: ([f64; 3], [f64; 3]) = ([1.0, 0.5, -1.0], [3.0, 1.5, 0.6]);
/// |A ∪ B| = 2 + 3.2 − |[1, 2] × [0.5, 1] × [0, 0.6]|.
const BOXES_VOLUME: f64 = 2.0 + 3.2 - 0.3;

/// The largest distance of a vertex to the exact boundary of A ∪ B.
fn boxes_hausdorff(mesh: &[DVec3]) -> f64 {
    let mut faces = faces_outside(A, B);
    faces.extend(faces_outside(B, A));
    mesh.iter()
        .map(|&p| {
            faces
                .iter()
                .map(|f| f.distance(p))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

/// The spool and a bar through its waist; the union's volume by the
/// spool's quadrature, the bar's, and their overlap by Monte Carlo (value,
/// σ).
fn spool_bar() -> (Vec<BSplineVolume>, f64, f64) {
    let s = spool().unwrap();
    let (lo, hi) = ([-0.25, -2.0, -0.4], [0.25, 2.0, 0.4]);
    let bar = cuboid(lo, hi);
    let bar_volume = 0.5 * 4.0 * 0.8;
    let m = Members::new(std::slice::from_ref(&s));
    let mut rng = Rng(0x0b0d_1e55);
    let mut next = || rng.next();
    let n = 200_000;
    let hits = (0..n)
        .filter(|_| {
            let x = DVec3::new(
                lo[0] + (hi[0] - lo[0]) * next(),
                lo[1] + (hi[1] - lo[1]) * next(),
                lo[2] + (hi[2] - lo[2]) * next(),
            );
            m.inside(x)
        })
        .count();
    let f = hits as f64 / n as f64;
    let volume = interior::volume(&s) + bar_volume * (1.0 - f);
    let sigma = bar_volume * (f * (1.0 - f) / n as f64).sqrt();
    (vec![s, bar], volume, sigma)
}

/// A turned bar through the spool's waist whose edge pokes through spool
/// triangles at 7 and 10 samples per span (the sweep's first seeded bar in
/// `tests/body_union.rs`: refused before local subdivision); the union's
/// volume as in [`spool_bar`].
fn spool_turned_bar() -> (Vec<BSplineVolume>, f64, f64) {
    let s = spool().unwrap();
    let (centre, sides) = (
        DVec3::new(
            -0.08156764929497817,
            0.07535978342807813,
            0.06689757967541334,
        ),
        [0.39866003186865, 4.0, 0.5395271794439412],
    );
    let (angle, tilt) = (0.31281404519106487, 0.09733979950158274);
    let turn = glam::DMat3::from_rotation_x(tilt) * glam::DMat3::from_rotation_z(angle);
    let axes = [DVec3::X, DVec3::Y, DVec3::Z].map(|a| turn * a);
    let axes = [0, 1, 2].map(|k| axes[k] * sides[k]);
    let origin = centre - (axes[0] + axes[1] + axes[2]) / 2.0;
    let bar = BSplineVolume::affine(origin, axes, [1, 1, 1], [2, 2, 2]).unwrap();
    let bar_volume = sides[0] * sides[1] * sides[2];
    let m = Members::new(std::slice::from_ref(&s));
    let mut rng = Rng(0x0b0d_1e55);
    let n = 200_000;
    let hits = (0..n)
        .filter(|_| m.inside(bar.point(rng.next(), rng.next(), rng.next())))
        .count();
    let f = hits as f64 / n as f64;
    let volume = interior::volume(&s) + bar_volume * (1.0 - f);
    let sigma = bar_volume * (f * (1.0 - f) / n as f64).sqrt();
    (vec![s, bar], volume, sigma)
}

fn compare(c: &mut Criterion) {
    let boxes = vec![cuboid(A.0, A.1), cuboid(B.0, B.1)];
    let (curved, curved_volume, sigma) = spool_bar();
    println!("spool + bar: volume {curved_volume:.6} ± {sigma:.6} (Monte Carlo σ)");
    let mut g = c.benchmark_group("union");
    g.sample_size(10);
    for per_span in [2, 4, 8] {
        let t = Instant::now();
        let m = union(&boxes, per_span).unwrap();
        let dt = t.elapsed();
        println!(
            "boundary boxes per_span {per_span}: {} triangles, volume error {:.2e}, Hausdorff {:.2e}, {dt:?}, weld {:?}",
            m.triangles.len(),
            (m.enclosed_volume() - BOXES_VOLUME).abs(),
            boxes_hausdorff(&m.positions),
            m.weld
        );
        g.bench_function(format!("boundary/boxes/{per_span}"), |b| {
            b.iter(|| black_box(union(&boxes, per_span).unwrap().triangles.len()))
        });
        let t = Instant::now();
        let m = union(&curved, per_span).unwrap();
        let dt = t.elapsed();
        println!(
            "boundary spool+bar per_span {per_span}: {} triangles, volume error {:.2e}, {dt:?}, weld {:?}",
            m.triangles.len(),
            (m.enclosed_volume() - curved_volume).abs(),
            m.weld
        );
        g.bench_function(format!("boundary/spool_bar/{per_span}"), |b| {
            b.iter(|| black_box(union(&curved, per_span).unwrap().triangles.len()))
        });
    }
    let (turned, turned_volume, turned_sigma) = spool_turned_bar();
    println!("spool + turned bar: volume {turned_volume:.6} ± {turned_sigma:.6} (Monte Carlo σ)");
    for per_span in [7, 10] {
        let t = Instant::now();
        match union(&turned, per_span) {
            Ok(m) => {
                let dt = t.elapsed();
                println!(
                    "boundary spool+turned bar per_span {per_span}: {} triangles, volume error {:.2e}, {dt:?}, weld {:?}",
                    m.triangles.len(),
                    (m.enclosed_volume() - turned_volume).abs(),
                    m.weld
                );
                g.bench_function(format!("boundary/spool_turned_bar/{per_span}"), |b| {
                    b.iter(|| black_box(union(&turned, per_span).map(|m| m.triangles.len())))
                });
            }
            Err(e) => println!("boundary spool+turned bar per_span {per_span}: {e}"),
        }
    }
    for n in [16, 32, 64] {
        let t = Instant::now();
        let m = implicit_union(&boxes, n);
        let dt = t.elapsed();
        println!(
            "implicit boxes n {n}: {} triangles, volume error {:.2e}, Hausdorff {:.2e}, {dt:?}",
            m.triangles.len(),
            (m.enclosed_volume() - BOXES_VOLUME).abs(),
            boxes_hausdorff(&m.positions)
        );
        let t = Instant::now();
        let mc = implicit_union(&curved, n);
        let dt2 = t.elapsed();
        println!(
            "implicit spool+bar n {n}: {} triangles, volume error {:.2e}, {dt2:?}",
            mc.triangles.len(),
            (mc.enclosed_volume() - curved_volume).abs()
        );
        if n <= 32 {
            g.bench_function(format!("implicit/boxes/{n}"), |b| {
                b.iter(|| black_box(implicit_union(&boxes, n).triangles.len()))
            });
            g.bench_function(format!("implicit/spool_bar/{n}"), |b| {
                b.iter(|| black_box(implicit_union(&curved, n).triangles.len()))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, compare);
criterion_main!(benches);
