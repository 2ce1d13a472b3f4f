//! The paper's five surfaces (20×15 … 81×159 bicubic control points), each
//! with 4 point position constraints, 1 curve constraint and one dragged
//! point load (paper 003, Table 2). Measures:
//!
//! * `drag_frame` — one drag frame: solve + re-place every icon;
//! * `first_frame` — the first frame of a new drag (a grab after a release):
//!   the drag's base solve and response columns, then the frame;
//! * `constraint_change` — an icon switched (sleeping ↔ passive) and solved
//!   (the switched icon's column is kept while it sleeps; it holds the
//!   surface where it is, so the solver proves the shape unchanged);
//! * `constraint_change_moving` — the same switch woken with a lifted
//!   target, so both directions move the shape (a full, refined solve);
//! * `add_icon` — a position icon added at a new place and solved (its
//!   column is a new sparse solve), then removed outside the timing;
//! * `first_frame_after_add` — the first frame of a grab just after an icon
//!   was added (the drag response recomputed, the pending column solved);
//! * `pin_change` — a small region constraint switched (sleeping ↔
//!   passive): the pinned control points change (answered through the
//!   factor of the old set, `solve::pin_update`, when small enough; else a
//!   numeric refactor);
//! * `pin_add` — the direction that costs: the region switched on and
//!   solved (switched off outside the timing);
//! * `first_frame_after_pin` — the first frame of a grab right after the
//!   region was switched on (its pins not yet settled);
//! * `pin_settle` — the deferred refactor that settles a pin change
//!   (`Design::settle_pins`);
//! * `refactor` — a material change: numeric refactorisation + solve;
//! * `tessellate` — the client tessellation at the paper's polygon count;
//! * `full_frame` — drag frame + tessellation with normals and curvature.
//!
//! And `clamped_plate`: a 128 × 128 plate clamped on its four edges (edge
//! icons) under a dragged distributed load.
//!
//! And `curve_set_up` (issue 15), on 20 × 15 and 81 × 159 with the paper's
//! scene: a free-form cubic curve constraint across the plate (the one of
//! `server/tests/icon_creation.rs`) added and solved — the time from adding
//! the icon to the design being ready for a drag (`curve_set_up`) — and the
//! first frame of a grab right after it (`first_frame_after_curve`).
//!
//! Run: `cargo bench -p vsculpt-kernel --bench sculpt`. Figures in BENCHMARKS.md.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use glam::DVec3;
use std::hint::black_box;
use std::time::Duration;
use vsculpt_kernel::analysis::{Tessellation, Tessellator, samples_for};
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector};
use vsculpt_kernel::design::Design;
use vsculpt_kernel::energy::SurfaceMaterial;
use vsculpt_kernel::icon::{Anchor, Edge, IconId, IconSpec, IconState, Role};
use vsculpt_kernel::solve::SolveReport;

/// (nu, nv, polygons) of paper 003's Table 2.
const GRIDS: [(usize, usize, usize); 5] = [
    (20, 15, 1533),
    (38, 32, 2028),
    (42, 40, 3956),
    (91, 54, 13000),
    (81, 159, 48536),
];

struct Scene {
    design: Design,
    load: IconId,
    switch: IconId,
    start: DVec3,
}

fn scene(nu: usize, nv: usize) -> Scene {
    let mut s = BSplineSurface::plane(nu as f64 / 10.0, nv as f64 / 10.0, nu, nv, 3).unwrap();
    let (w, h) = (nu as f64 / 10.0, nv as f64 / 10.0);
    for p in s.points_mut() {
        p.z = 0.2
            * w.min(h)
            * (std::f64::consts::PI * p.x / w).sin()
            * (std::f64::consts::PI * p.y / h).sin();
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
    let switch = d.add_icon(point(0.3, 0.7, Role::Position)).unwrap();
    d.set_state(switch, IconState::Sleeping).unwrap();
    let load = d.add_icon(point(0.5, 0.6, Role::Load)).unwrap();
    d.solve().unwrap();
    let start = d.icon(load).unwrap().xyz;
    d.drag_start(load).unwrap();
    d.drag(load, start + DVec3::Z * 0.01).unwrap();
    Scene {
        design: d,
        load,
        switch,
        start,
    }
}

/// A passive position icon on `anchor`.
fn held(anchor: Anchor) -> IconSpec {
    IconSpec {
        anchor,
        role: Role::Position,
        state: IconState::Passive,
        target: None,
    }
}

/// `iters` times: an icon `spec()` added and solved (timed), then removed
/// and the removal solved (not timed).
fn time_add(sc: &mut Scene, iters: u64, spec: &mut impl FnMut() -> IconSpec) -> Duration {
    let mut spent = Duration::ZERO;
    for _ in 0..iters {
        let spec = spec();
        let start = std::time::Instant::now();
        let icon = sc.design.add_icon(spec).unwrap();
        black_box(sc.design.solve().unwrap());
        spent += start.elapsed();
        sc.design.remove_icon(icon).unwrap();
        sc.design.solve().unwrap();
    }
    spent
}

/// The first frame of a grab of the load, `lift` above where it is (timed:
/// drag start and one frame); the load is released after, untimed.
fn timed_grab(sc: &mut Scene, lift: DVec3) -> Duration {
    let at = sc.design.icon(sc.load).unwrap().xyz;
    let start = std::time::Instant::now();
    sc.design.drag_start(sc.load).unwrap();
    black_box(sc.design.drag(sc.load, at + lift).unwrap());
    let spent = start.elapsed();
    sc.design.release(sc.load).unwrap();
    spent
}

/// `iters` times: an icon `spec()` added and solved, then the first frame
/// of a grab of the load (timed: drag start and one frame), then the load
/// released and the icon removed.
fn time_first_frame_after_add(
    sc: &mut Scene,
    iters: u64,
    spec: &mut impl FnMut() -> IconSpec,
) -> Duration {
    let mut spent = Duration::ZERO;
    for _ in 0..iters {
        let icon = sc.design.add_icon(spec()).unwrap();
        sc.design.solve().unwrap();
        spent += timed_grab(sc, DVec3::Z * 0.001);
        sc.design.remove_icon(icon).unwrap();
        sc.design.solve().unwrap();
    }
    spent
}

/// Switches `icon` passive (even `k`) or sleeping (odd `k`) and solves.
fn switch_and_solve(design: &mut Design, icon: IconId, k: u64) -> SolveReport {
    let state = if k.is_multiple_of(2) {
        IconState::Passive
    } else {
        IconState::Sleeping
    };
    design.set_state(icon, state).unwrap();
    design.solve().unwrap()
}

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("sculpt");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    for (nu, nv, polygons) in GRIDS {
        let id = format!("{nu}x{nv}");
        let mut sc = scene(nu, nv);
        let mut k = 0u64;
        group.bench_function(BenchmarkId::new("drag_frame", &id), |b| {
            b.iter(|| {
                k += 1;
                let lift = 0.01 + 0.001 * (k % 7) as f64;
                black_box(sc.design.drag(sc.load, sc.start + DVec3::Z * lift).unwrap())
            })
        });
        let (su, sv) = samples_for(sc.design.surface(), polygons);
        let mut tess = Tessellator::new(sc.design.surface(), su, sv);
        let mut out = Tessellation::default();
        group.bench_function(BenchmarkId::new("tessellate", &id), |b| {
            b.iter(|| {
                tess.fill(sc.design.surface(), &mut out);
                black_box(out.positions.len())
            })
        });
        group.bench_function(BenchmarkId::new("full_frame", &id), |b| {
            b.iter(|| {
                k += 1;
                let lift = 0.01 + 0.001 * (k % 7) as f64;
                sc.design.drag(sc.load, sc.start + DVec3::Z * lift).unwrap();
                tess.fill(sc.design.surface(), &mut out);
                black_box(out.positions.len())
            })
        });
        sc.design.release(sc.load).unwrap();
        // A grab: the first frame of a new drag (after a release baked the
        // shape) computes the drag's base and its response columns.
        group.bench_function(BenchmarkId::new("first_frame", &id), |b| {
            b.iter_custom(|iters| {
                let mut spent = Duration::ZERO;
                for _ in 0..iters {
                    k += 1;
                    spent += timed_grab(&mut sc, DVec3::Z * 0.001 * (1 + k % 3) as f64);
                }
                spent
            })
        });
        group.bench_function(BenchmarkId::new("constraint_change", &id), |b| {
            b.iter(|| {
                k += 1;
                black_box(switch_and_solve(&mut sc.design, sc.switch, k))
            })
        });
        // The same switch, but woken with a lifted target: the shape moves
        // both ways (woken: pulled up; asleep: it relaxes), a full solve.
        let lift = DVec3::Z * 0.01 * (nu.min(nv) as f64 / 10.0);
        group.bench_function(BenchmarkId::new("constraint_change_moving", &id), |b| {
            b.iter(|| {
                k += 1;
                if k.is_multiple_of(2) {
                    sc.design.set_state(sc.switch, IconState::Passive).unwrap();
                    let at = sc.design.icon(sc.switch).unwrap().target;
                    sc.design.set_target(sc.switch, at + lift).unwrap();
                } else {
                    sc.design.set_state(sc.switch, IconState::Sleeping).unwrap();
                }
                black_box(sc.design.solve().unwrap())
            })
        });
        // A position icon at a parameter never used before: its column is
        // not cached.
        let mut fresh = 0u64;
        let mut point = move || {
            fresh += 1;
            let u = 0.2 + 0.6 * ((fresh as f64 * 0.618_033_988_75) % 1.0);
            let v = 0.4 + 0.2 * ((fresh as f64 * 0.414_213_562_37) % 1.0);
            held(Anchor::Point { u, v })
        };
        group.bench_function(BenchmarkId::new("add_icon", &id), |b| {
            b.iter_custom(|iters| time_add(&mut sc, iters, &mut point))
        });
        // The first frame of a grab right after the icon set changed (an
        // icon added and solved, outside the timing): the drag's response
        // is recomputed and the new icon's pending column solved.
        group.bench_function(BenchmarkId::new("first_frame_after_add", &id), |b| {
            b.iter_custom(|iters| time_first_frame_after_add(&mut sc, iters, &mut point))
        });
        // A region constraint switched (sleeping ↔ passive): the control
        // points its rectangle holds are pinned or freed, so the pin set
        // changes (a numeric refactor of the stiffness each way).
        let region = sc
            .design
            .add_icon(IconSpec {
                anchor: Anchor::Region {
                    u0: 0.6,
                    v0: 0.3,
                    u1: 0.65,
                    v1: 0.35,
                    inside: true,
                },
                role: Role::Position,
                state: IconState::Sleeping,
                target: None,
            })
            .unwrap();
        sc.design.solve().unwrap();
        group.bench_function(BenchmarkId::new("pin_change", &id), |b| {
            b.iter(|| {
                k += 1;
                black_box(switch_and_solve(&mut sc.design, region, k))
            })
        });
        // The direction that costs: the region switched on (its ~100
        // control points pinned) and solved; switched off outside the timing.
        group.bench_function(BenchmarkId::new("pin_add", &id), |b| {
            b.iter_custom(|iters| {
                let mut spent = Duration::ZERO;
                for _ in 0..iters {
                    let start = std::time::Instant::now();
                    black_box(switch_and_solve(&mut sc.design, region, 0));
                    spent += start.elapsed();
                    switch_and_solve(&mut sc.design, region, 1);
                }
                spent
            })
        });
        // The first frame of a grab right after the region was switched on
        // (its pins answered through the old factor, not yet settled), and
        // the deferred refactor that settles them.
        group.bench_function(BenchmarkId::new("first_frame_after_pin", &id), |b| {
            b.iter_custom(|iters| {
                let mut spent = Duration::ZERO;
                for _ in 0..iters {
                    sc.design.set_state(region, IconState::Passive).unwrap();
                    sc.design.solve().unwrap();
                    spent += timed_grab(&mut sc, DVec3::Z * 0.001);
                    sc.design.set_state(region, IconState::Sleeping).unwrap();
                    sc.design.solve().unwrap();
                    // Back to a factor without the region's pins.
                    sc.design.settle_pins().unwrap();
                }
                spent
            })
        });
        group.bench_function(BenchmarkId::new("pin_settle", &id), |b| {
            b.iter_custom(|iters| {
                let mut spent = Duration::ZERO;
                for k in 0..iters {
                    switch_and_solve(&mut sc.design, region, k);
                    let start = std::time::Instant::now();
                    black_box(sc.design.settle_pins().unwrap());
                    spent += start.elapsed();
                }
                spent
            })
        });
        sc.design.remove_icon(region).unwrap();
        sc.design.solve().unwrap();
        group.bench_function(BenchmarkId::new("refactor", &id), |b| {
            b.iter(|| {
                k += 1;
                let m = SurfaceMaterial {
                    beta11: 1.0 + 0.1 * (k % 2) as f64,
                    ..Default::default()
                };
                sc.design.set_material(m).unwrap();
                black_box(sc.design.solve().unwrap())
            })
        });
        println!("{id}: {} triangles", out.triangles());
    }
    group.finish();
}

/// A clamped square plate of 128 × 128 control points (its four edges held
/// by edge-clamp icons: two rows pinned each, 1 512 points, eliminated from
/// the unknowns) under a distributed load over the whole plate, dragged.
/// `clamp_change` switches one edge clamp off and on (the pin set changes:
/// a numeric refactor each way).
fn clamped_plate(c: &mut Criterion) {
    let mut group = c.benchmark_group("clamped_plate");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    let n = 128;
    let s = BSplineSurface::plane(1.0, 1.0, n, n, 3).unwrap();
    let mut d = Design::new(s, SurfaceMaterial::default()).unwrap();
    d.set_adaptive_spring(false);
    let mut clamps = Vec::new();
    for edge in [Edge::UMin, Edge::UMax, Edge::VMin, Edge::VMax] {
        clamps.push(
            d.add_icon(IconSpec {
                anchor: Anchor::Edge {
                    edge,
                    clamped: true,
                },
                role: Role::Position,
                state: IconState::Passive,
                target: None,
            })
            .unwrap(),
        );
    }
    let load = d
        .add_icon(IconSpec {
            anchor: Anchor::Region {
                u0: 0.0,
                v0: 0.0,
                u1: 1.0,
                v1: 1.0,
                inside: true,
            },
            role: Role::Load,
            state: IconState::Passive,
            target: None,
        })
        .unwrap();
    d.solve().unwrap();
    let start = d.icon(load).unwrap().xyz;
    d.drag_start(load).unwrap();
    d.drag(load, start + DVec3::Z * 0.01).unwrap();
    let id = format!("{n}x{n}");
    let mut k = 0u64;
    group.bench_function(BenchmarkId::new("drag_frame", &id), |b| {
        b.iter(|| {
            k += 1;
            let lift = 0.01 + 0.001 * (k % 7) as f64;
            black_box(d.drag(load, start + DVec3::Z * lift).unwrap())
        })
    });
    d.release(load).unwrap();
    group.bench_function(BenchmarkId::new("first_frame", &id), |b| {
        b.iter_custom(|iters| {
            let mut spent = Duration::ZERO;
            for _ in 0..iters {
                k += 1;
                let at = d.icon(load).unwrap().xyz;
                let lift = DVec3::Z * 0.001 * (1 + k % 3) as f64;
                let t = std::time::Instant::now();
                d.drag_start(load).unwrap();
                black_box(d.drag(load, at + lift).unwrap());
                spent += t.elapsed();
                d.release(load).unwrap();
            }
            spent
        })
    });
    group.bench_function(BenchmarkId::new("clamp_change", &id), |b| {
        b.iter(|| {
            k += 1;
            black_box(switch_and_solve(&mut d, clamps[0], k))
        })
    });
    group.finish();
}

/// The free-form cubic of `server/tests/icon_creation.rs`, across the plate,
/// its control points shifted by `shift` along v (a fresh curve per
/// iteration: no cached column of an earlier one applies).
fn cubic(shift: f64) -> Anchor {
    let points = [
        (0.1, 0.12),
        (0.3, 0.3),
        (0.5, 0.05),
        (0.7, 0.35),
        (0.92, 0.15),
    ];
    let curve = BSplineCurve::new(
        KnotVector::new(3, vec![0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 1.0]).unwrap(),
        points
            .iter()
            .map(|&(u, v)| DVec3::new(u, v + shift, 0.0))
            .collect(),
    )
    .unwrap();
    Anchor::Curve(curve)
}

/// A free-form curve constraint added to the paper's scene (issue 15).
fn curve_set_up(c: &mut Criterion) {
    let mut group = c.benchmark_group("sculpt");
    group
        .sample_size(10)
        .sampling_mode(criterion::SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(100))
        .measurement_time(Duration::from_secs(2));
    for (nu, nv) in [(20, 15), (81, 159)] {
        let id = format!("{nu}x{nv}");
        let mut sc = scene(nu, nv);
        sc.design.release(sc.load).unwrap();
        let mut fresh = 0u64;
        let mut spec = move || {
            fresh += 1;
            held(cubic(0.02 * ((fresh as f64 * 0.618_033_988_75) % 1.0)))
        };
        // Added and solved: the design is then ready for a drag.
        group.bench_function(BenchmarkId::new("curve_set_up", &id), |b| {
            b.iter_custom(|iters| time_add(&mut sc, iters, &mut spec))
        });
        // The first frame of a grab of the load right after the curve was
        // added and solved (outside the timing).
        group.bench_function(BenchmarkId::new("first_frame_after_curve", &id), |b| {
            b.iter_custom(|iters| time_first_frame_after_add(&mut sc, iters, &mut spec))
        });
    }
    group.finish();
}

criterion_group!(sculpt, benches, clamped_plate, curve_set_up);
criterion_main!(sculpt);
