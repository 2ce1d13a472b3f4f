//! Density Spatial Model (paper 001) at interactive rates:
//! * `dsm_net_drag`: a node of a 20 × 20 passing-points net dragged → inverse
//!   transformation (eqs. 8–11, 324 charges) → height-field mesh of h(u, v) (eq. 12) at
//!   4 samples per net spacing (77 × 77 vertices); and the same drag meshed in 3-D by
//!   dual contouring at 64 cells; `drag_update_and_height_mesh_20x20`: the same drag
//!   solved by updating the drag's first factorisation ([`NetDrag`]).
//! * `dsm_shape_remesh`: a 20-density-primitive shape (a box rounded by 12 sector-shell
//!   pipes and 8 octant ball shells) and a 20-primitive blobby shape, dual-contoured at
//!   64, 128 and 256 cells along their size; `adaptive_*`: the same shapes by
//!   [`mesh_adaptive`] (finest cell as the uniform grid's, tolerance ¼ and ½
//!   cell, leaves up to 16 cells).
//!
//! * `dsm_compare`: the same fields meshed by `fast-surface-nets` (naive surface
//!   nets, a well-kept implicit mesher) on the same grid, with Φ sampled densely at
//!   every corner (it has no culling of its own): the baseline of the same run.
//!
//! * `dsm_incremental`: the 20-primitive handset concept of
//!   `tests/dsm_support` with one side button moved a small step (0.01, back and
//!   forth) per frame, re-meshed from scratch (`full`) and by [`IncrementalMesh`]
//!   (`incremental`), at the 40 cells the server's demo part uses and at 128;
//!   both include building the model and its grid, as the server does. And the
//!   thumb-rest charge (a sphere-based density primitive, a = 6) moved the same
//!   step: its support (20.7 / a at τ = 1e-9) covers the whole part.
//!
//! Every time is the benchmark thread's **CPU time** (`CLOCK_THREAD_CPUTIME_ID`),
//! not wall time: on the shared, loaded machine these benches run on, wall
//! time mostly measures how long the thread waited for a core. CPU time still
//! shares caches and memory bandwidth with the other processes, so it is an
//! upper bound of a quiet core's time, far closer than wall time.
//!
//! Run: `cargo bench -p vsculpt-kernel --bench dsm -- --warm-up-time 1 --measurement-time 3`.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use glam::{DVec2, DVec3};
use std::hint::black_box;
use std::time::{Duration, Instant};
use vsculpt_kernel::dsm::*;

#[path = "../tests/dsm_support/mod.rs"]
mod dsm_support;

/// `struct timespec` of 64-bit Linux.
#[repr(C)]
struct Timespec {
    tv_sec: i64,
    tv_nsec: i64,
}

unsafe extern "C" {
    /// POSIX clock_gettime (from the C library std links).
    fn clock_gettime(clock: i32, ts: *mut Timespec) -> i32;
}

/// Linux's CLOCK_THREAD_CPUTIME_ID.
const CLOCK_THREAD_CPUTIME_ID: i32 = 3;

/// The CPU time this thread has run, if the system reports it.
fn thread_cpu() -> Option<Duration> {
    let mut ts = Timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec for the call.
    let ok = unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut ts) } == 0;
    (ok && cfg!(all(target_os = "linux", target_pointer_width = "64")))
        .then(|| Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32))
}

/// Runs `f` `iters` times and returns the thread's CPU time for them (the
/// wall time where the system reports none).
fn cpu_timed<O>(iters: u64, mut f: impl FnMut() -> O) -> Duration {
    let (cpu0, wall0) = (thread_cpu(), Instant::now());
    for _ in 0..iters {
        black_box(f());
    }
    match (cpu0, thread_cpu()) {
        (Some(a), Some(b)) => b.saturating_sub(a),
        _ => wall0.elapsed(),
    }
}

fn net() -> PassingPointsNet {
    let n = 20;
    let heights: Vec<f64> = (0..n * n)
        .map(|k| 1.0 + 0.4 * (0.5 * (k % n) as f64).sin() * (0.3 * (k / n) as f64).cos())
        .collect();
    PassingPointsNet::regular(DVec2::ZERO, DVec2::splat(0.25), n, n, &heights).unwrap()
}

fn net_drag(c: &mut Criterion) {
    let mut g = c.benchmark_group("dsm_net_drag");
    g.sample_size(20);
    let mut n = net();
    let opts = InverseOptions::for_net(&n, 1.0);
    let (lo, hi) = n.uv_box();
    let node = 9 * 20 + 9;
    let mut t = 0u32;
    g.bench_function("inverse_only_20x20", |b| {
        b.iter_custom(|iters| {
            cpu_timed(iters, || {
                t = t.wrapping_add(1);
                n.set_height(node, 1.2 + 0.01 * (t % 50) as f64).unwrap();
                black_box(inverse_transform(&n, &opts).unwrap())
            })
        })
    });
    g.bench_function("inverse_and_height_mesh_20x20", |b| {
        b.iter_custom(|iters| {
            cpu_timed(iters, || {
                t = t.wrapping_add(1);
                n.set_height(node, 1.2 + 0.01 * (t % 50) as f64).unwrap();
                let (s, _) = inverse_transform(&n, &opts).unwrap();
                black_box(s.mesh(lo, hi, 76, 76).unwrap())
            })
        })
    });
    let (mut drag, _) = NetDrag::start(net(), opts, node).unwrap();
    g.bench_function("drag_update_and_height_mesh_20x20", |b| {
        b.iter_custom(|iters| {
            cpu_timed(iters, || {
                t = t.wrapping_add(1);
                let (s, _) = drag.set_height(1.2 + 0.01 * (t % 50) as f64).unwrap();
                black_box(s.mesh(lo, hi, 76, 76).unwrap())
            })
        })
    });
    g.bench_function("inverse_and_dc_mesh_64_20x20", |b| {
        b.iter_custom(|iters| {
            cpu_timed(iters, || {
                t = t.wrapping_add(1);
                n.set_height(node, 1.2 + 0.01 * (t % 50) as f64).unwrap();
                let (s, _) = inverse_transform(&n, &opts).unwrap();
                let mut m = Model::new(1.0, DEFAULT_TAU).unwrap();
                m.add(Group {
                    density: vec![s.primitive(lo, hi, Placement::IDENTITY).unwrap()],
                    ..Default::default()
                })
                .unwrap();
                black_box(mesh(&m, MeshOptions { cells: 64 }).unwrap())
            })
        })
    });
    g.finish();
}

/// The rounded box and the blobby shape (the handset is not a bench shape here).
fn shapes() -> Vec<(&'static str, Model)> {
    let mut all = dsm_support::twenty_primitive_shapes();
    all.truncate(2);
    all
}

fn shape_remesh(c: &mut Criterion) {
    let mut g = c.benchmark_group("dsm_shape_remesh");
    g.sample_size(10);
    for (name, m) in shapes() {
        for cells in [64usize, 128, 256] {
            g.bench_with_input(BenchmarkId::new(name, cells), &cells, |b, &cells| {
                b.iter_custom(|iters| cpu_timed(iters, || mesh(&m, MeshOptions { cells }).unwrap()))
            });
            let (um, _) = mesh(&m, MeshOptions { cells }).unwrap();
            for tol in [0.25, 0.5] {
                let opts = AdaptiveOptions {
                    tolerance: tol,
                    ..AdaptiveOptions::new(cells)
                };
                let (am, st) = mesh_adaptive(&m, opts).unwrap();
                // What the adaptive mesh is made of (printed once).
                eprintln!(
                    "dsm_shape_remesh/adaptive_tol{tol}_{name}/{cells}: {} triangles \
                     (uniform {}), {st:?}",
                    am.triangles.len(),
                    um.triangles.len()
                );
                g.bench_with_input(
                    BenchmarkId::new(format!("adaptive_tol{tol}_{name}"), cells),
                    &cells,
                    |b, _| {
                        b.iter_custom(|iters| cpu_timed(iters, || mesh_adaptive(&m, opts).unwrap()))
                    },
                );
            }
        }
    }
    g.finish();
}

/// Φ at every corner of the model's grid at `cells` (x fastest), then naive
/// surface nets on it.
fn surface_nets_dense(m: &Model, cells: usize) -> usize {
    use fast_surface_nets::ndshape::{RuntimeShape, Shape};
    use fast_surface_nets::{SurfaceNetsBuffer, surface_nets};
    let grid = Grid::for_model(m, cells).unwrap();
    let d = (grid.dims + glam::IVec3::ONE).as_uvec3();
    let shape = RuntimeShape::<u32, 3>::new([d.x, d.y, d.z]);
    let act = m.all_active();
    let mut scratch = Vec::new();
    let mut sdf = vec![0f32; shape.usize()];
    for (i, v) in sdf.iter_mut().enumerate() {
        let [x, y, z] = shape.delinearize(i as u32);
        let c = glam::IVec3::new(x as i32, y as i32, z as i32);
        // surface nets wants negative inside.
        *v = -(m
            .sample(grid.corner(c), &act, grid.reach_margin(), &mut scratch)
            .phi as f32);
    }
    let mut buf = SurfaceNetsBuffer::default();
    surface_nets(&sdf, &shape, [0; 3], [d.x - 1, d.y - 1, d.z - 1], &mut buf);
    buf.indices.len() / 3
}

fn compare(c: &mut Criterion) {
    let mut g = c.benchmark_group("dsm_compare");
    g.sample_size(10);
    for (name, m) in shapes() {
        for cells in [64usize, 128] {
            g.bench_with_input(
                BenchmarkId::new(format!("fast_surface_nets_dense_{name}"), cells),
                &cells,
                |b, &cells| {
                    b.iter_custom(|iters| cpu_timed(iters, || surface_nets_dense(&m, cells)))
                },
            );
        }
    }
    g.finish();
}

/// The handset with primitive `n` stepped back and forth along x, one step per call.
fn stepper(n: usize) -> impl FnMut() -> Model {
    let mut spec = dsm_support::handset();
    let mut t = 0u32;
    move || {
        t = t.wrapping_add(1);
        let d = if t.is_multiple_of(2) { -0.01 } else { 0.01 };
        spec.translate(n, DVec3::new(d, 0.0, 0.0));
        spec.model()
    }
}

fn incremental(c: &mut Criterion) {
    let mut g = c.benchmark_group("dsm_incremental");
    g.sample_size(10);
    // Primitive 4: the first side button; 19: the thumb-rest charge (group 3).
    for (what, n) in [("button", 4usize), ("charge", 19)] {
        for cells in [40usize, 128] {
            if what == "charge" && cells == 128 {
                continue;
            }
            let mut step = stepper(n);
            g.bench_function(format!("full_{what}/{cells}"), |b| {
                b.iter_custom(|iters| {
                    cpu_timed(iters, || {
                        let m = step();
                        black_box(mesh(&m, MeshOptions { cells }).unwrap())
                    })
                })
            });
            let mut step = stepper(n);
            let m = step();
            let grid = Grid::for_model(&m, cells).unwrap();
            let mut inc = IncrementalMesh::new(m, grid);
            // What one step re-does (printed once: the work behind the time).
            let m = step();
            let grid = Grid::for_model(&m, cells).unwrap();
            let st = inc.update(m, grid);
            eprintln!(
                "dsm_incremental/{what}/{cells}: a step re-walks {} of {} leaves ({} new), \
                 contours {} cells again",
                st.recomputed, st.leaves, st.fresh_leaves, st.cells
            );
            g.bench_function(format!("incremental_{what}/{cells}"), |b| {
                b.iter_custom(|iters| {
                    cpu_timed(iters, || {
                        let m = step();
                        let grid = Grid::for_model(&m, cells).unwrap();
                        let st = inc.update(m, grid);
                        assert!(!st.full);
                        black_box(inc.mesh())
                    })
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, net_drag, shape_remesh, compare, incremental);
criterion_main!(benches);
