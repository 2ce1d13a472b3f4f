//! A product of 10 parts (the paper's five grids, 20×15 … 81×159, two of
//! each), each with the paper's icons (4 point position constraints, a
//! curve constraint, a point load). Measures, in one run:
//!
//! * `alone/drag_frame` — a drag frame of the load on a design alone;
//! * `product/drag_frame` — the same frame on the same design as an
//!   unjoined part of the 10-part product (target: within ±10 % of alone).
//!   The two benches run the same interleaved frames (one alone, one in the
//!   product) and each times one of them; before them the bench prints the
//!   medians of 4000 paired frames and their ratio (`paired medians`),
//!   and likewise for the joined pair against the part alone;
//! * `joined/drag_frame` — the same frame on a part joined G1 to a second
//!   part of the same grid (the pair's joint drag fast path, plus writing
//!   the partner's control points and re-placing its icons);
//! * `bound_curve/drag_frame` — a drag frame of a curve part bound along
//!   u = 0.5 of a part of this grid: the curve's own frame, then a full
//!   solve of the surface with the curve's new control points as targets.
//!
//! Run: `cargo bench -p vsculpt-kernel --bench product`. Figures in
//! BENCHMARKS.md.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use glam::DVec3;
use std::hint::black_box;
use std::time::{Duration, Instant};
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector};
use vsculpt_kernel::curve_design::{CurveDesign, CurveRole};
use vsculpt_kernel::design::Design;
use vsculpt_kernel::energy::{CurveMaterial, SurfaceMaterial};
use vsculpt_kernel::icon::{Anchor, IconId, IconSpec, IconState, Role};
use vsculpt_kernel::product::{
    BindingSpec, Continuity, Edge, IsoLine, JoinSpec, Part, PartId, Product, iso_curve,
};

/// Paper 003's Table 2 grids.
const GRIDS: [(usize, usize); 5] = [(20, 15), (38, 32), (42, 40), (91, 54), (81, 159)];

/// The paper's scene on a `nu × nv` bicubic panel starting at x = `x0`;
/// returns the design (solved) and its load.
fn scene(nu: usize, nv: usize, x0: f64) -> (Design, IconId) {
    let mut s = BSplineSurface::plane(nu as f64 / 10.0, nv as f64 / 10.0, nu, nv, 3).unwrap();
    let (w, h) = (nu as f64 / 10.0, nv as f64 / 10.0);
    for p in s.points_mut() {
        p.z = 0.2
            * w.min(h)
            * (std::f64::consts::PI * p.x / w).sin()
            * (std::f64::consts::PI * p.y / h).sin();
        p.x += x0;
    }
    let mut d = Design::new(s, SurfaceMaterial::default()).unwrap();
    d.set_adaptive_spring(false);
    let point = |u: f64, v: f64, role| IconSpec {
        anchor: Anchor::Point { u, v },
        role,
        state: IconState::Passive,
        target: None,
    };
    for (u, v) in [(0.1, 0.1), (0.9, 0.1), (0.1, 0.9), (0.9, 0.9)] {
        d.add_icon(point(u, v, Role::Position)).unwrap();
    }
    let line = BSplineCurve::new(
        KnotVector::clamped_uniform(1, 2).unwrap(),
        vec![DVec3::new(0.2, 0.25, 0.0), DVec3::new(0.8, 0.25, 0.0)],
    )
    .unwrap();
    d.add_icon(IconSpec {
        anchor: Anchor::Curve(line),
        role: Role::Position,
        state: IconState::Passive,
        target: None,
    })
    .unwrap();
    let load = d.add_icon(point(0.5, 0.6, Role::Load)).unwrap();
    d.solve().unwrap();
    (d, load)
}

/// Frames of `a` and `b`, interleaved one by one; prints the median of
/// each and their ratio. Medians of paired frames are robust to the
/// preemption spikes of a shared machine, which dominate criterion's means
/// there.
fn paired_medians(label: &str, mut a: impl FnMut(DVec3), mut b: impl FnMut(DVec3), start: DVec3) {
    const FRAMES: usize = 4000;
    let (mut ta, mut tb) = (Vec::with_capacity(FRAMES), Vec::with_capacity(FRAMES));
    for k in 0..FRAMES {
        let x = start + DVec3::Z * (0.01 + 0.001 * (k % 7) as f64);
        let t = Instant::now();
        a(x);
        ta.push(t.elapsed());
        let t = Instant::now();
        b(x);
        tb.push(t.elapsed());
    }
    ta.sort_unstable();
    tb.sort_unstable();
    let (ma, mb) = (ta[FRAMES / 2], tb[FRAMES / 2]);
    eprintln!(
        "paired medians {label}: {ma:?} against {mb:?}, ratio {:.3}",
        mb.as_secs_f64() / ma.as_secs_f64()
    );
}

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("product");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    // The 10-part product: two parts of each grid; the first is dragged.
    let mut product = Product::new();
    let mut dragged: Vec<(PartId, IconId)> = Vec::new();
    for (nu, nv) in GRIDS {
        let (d, load) = scene(nu, nv, 0.0);
        dragged.push((product.add_part(Part::Surface(d)), load));
        let (d, _) = scene(nu, nv, 0.0);
        product.add_part(Part::Surface(d));
    }
    for (k, (nu, nv)) in GRIDS.into_iter().enumerate() {
        let id = format!("{nu}x{nv}");
        let (mut alone, load) = scene(nu, nv, 0.0);
        let (part, pload) = dragged[k];
        let start = alone.icon(load).unwrap().xyz;
        let mut n = 0u64;
        let mut lift = move || {
            n += 1;
            DVec3::Z * (0.01 + 0.001 * (n % 7) as f64)
        };
        alone.drag(load, start + lift()).unwrap();
        product.drag(part, pload, start + lift()).unwrap();
        paired_medians(
            &format!("{id} alone / in the product"),
            |x| {
                black_box(alone.drag(load, x).unwrap());
            },
            |x| {
                black_box(product.drag(part, pload, x).unwrap());
            },
            start,
        );
        // Both benches run the same interleaved work (one frame alone, one
        // in the product) and time one of the two, so caches and the
        // machine's load treat them alike.
        for timed_alone in [true, false] {
            let name = if timed_alone { "alone" } else { "product" };
            group.bench_function(BenchmarkId::new(format!("{name}/drag_frame"), &id), |b| {
                b.iter_custom(|iters| {
                    let mut spent = Duration::ZERO;
                    for _ in 0..iters {
                        let (xa, xp) = (start + lift(), start + lift());
                        let t = Instant::now();
                        black_box(alone.drag(load, xa).unwrap());
                        let ta = t.elapsed();
                        let t = Instant::now();
                        black_box(product.drag(part, pload, xp).unwrap());
                        let tp = t.elapsed();
                        spent += if timed_alone { ta } else { tp };
                    }
                    spent
                })
            });
        }
        // A joined pair of this grid: B continues A along x, G1.
        let mut pair = Product::new();
        let (da, la) = scene(nu, nv, 0.0);
        let a = pair.add_part(Part::Surface(da));
        let (db, _) = scene(nu, nv, nu as f64 / 10.0);
        let b = pair.add_part(Part::Surface(db));
        pair.join(JoinSpec {
            a,
            edge_a: Edge::UMax,
            b,
            edge_b: Edge::UMin,
            reversed: false,
            continuity: Continuity::G1,
            ratio: None,
        })
        .unwrap();
        let at = pair.surface(a).unwrap().icon(la).unwrap().xyz;
        pair.drag(a, la, at + lift()).unwrap();
        paired_medians(
            &format!("{id} alone / joined pair"),
            |x| {
                black_box(alone.drag(load, x).unwrap());
            },
            |x| {
                black_box(pair.drag(a, la, at - start + x).unwrap());
            },
            start,
        );
        group.bench_function(BenchmarkId::new("joined/drag_frame", &id), |b| {
            b.iter(|| black_box(pair.drag(a, la, at + lift()).unwrap()))
        });
        // A curve bound along u = 0.5 of a part of this grid, dragged.
        let mut bound = Product::new();
        let (ds, _) = scene(nu, nv, 0.0);
        let line = IsoLine::U(0.5);
        let on = iso_curve(ds.surface(), line).unwrap();
        let surface = bound.add_part(Part::Surface(ds));
        let curve = bound.add_part(Part::Curve(
            CurveDesign::new(on, CurveMaterial::default()).unwrap(),
        ));
        bound
            .bind(BindingSpec {
                curve,
                surface,
                line,
                reversed: false,
            })
            .unwrap();
        let ci = bound
            .edit_curve(curve, |c| {
                let (t0, t1) = c.curve().domain();
                c.add_icon(0.5 * (t0 + t1), CurveRole::Position)
            })
            .unwrap()
            .value;
        let cat = bound.curve(curve).unwrap().icon(ci).unwrap().xyz;
        bound.drag(curve, ci, cat + lift()).unwrap();
        group.bench_function(BenchmarkId::new("bound_curve/drag_frame", &id), |b| {
            b.iter(|| black_box(bound.drag(curve, ci, cat + lift()).unwrap()))
        });
    }
    group.finish();
}

criterion_group!(product_benches, benches);
criterion_main!(product_benches);
