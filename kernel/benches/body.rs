//! Coons bodies (paper 002), in one run:
//!
//! * `ffd/move_point` — FFD of a 100 000-vertex mesh (a dense triangulated
//!   sphere shell of 100 000 vertices inside a tricubic 8 × 8 × 8 lattice)
//!   when one lattice point moves: only the vertices in the moved point's
//!   support are recomputed ([`Ffd::move_point`]);
//! * `ffd/recompute_all` — the baseline in the same run: every vertex
//!   recomputed for the same lattice ([`Ffd::deform_all`]);
//! * `ffd/bernstein_move_point` — the same move on Sederberg–Parry's
//!   4 × 4 × 4 Bernstein lattice (one span: every vertex depends on every
//!   point, so no locality);
//! * `chair/display` — evaluation for display of the five-body chair (the
//!   cantilever strip of `body::demo::chair`, C1/C0/C2/C1 joints): six
//!   boundary faces and 3 isoparametric surfaces per direction per body,
//!   17 × 17 vertices each (75 surfaces, 21 675 vertices with normals and
//!   curvature);
//! * `morph/frame` — one frame of the cube → spool metamorphosis: the body
//!   at t and its display (six faces + 3 iso-surfaces per direction,
//!   17 × 17 each); `morph/body_at_t` the body alone.
//!
//! * `injective/fresh` — the proof that det J > 0 of the tricubic 8³
//!   lattice with one point moved, every cell proved ([`check_injective`]);
//!   `injective/kept` — the same proof with the proofs of the last lattice
//!   kept ([`InjectivityCache`]): only the cells the moved point reaches
//!   are proved again.
//!
//! Run: `cargo bench -p vsculpt-kernel --bench body -- --warm-up-time 1
//! --measurement-time 3`. Figures in BENCHMARKS.md.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use std::hint::black_box;
use vsculpt_kernel::body::demo::{chair, cube_to_spool};
use vsculpt_kernel::body::display::BodyDisplay;
use vsculpt_kernel::body::{BSplineVolume, Ffd, InjectivityCache, check_injective};

/// 100 000 vertices on a sphere shell of radius 0.45 around (0.5, 0.5, 0.5)
/// (a latitude–longitude grid, 250 × 400).
fn mesh() -> Vec<DVec3> {
    let (nt, np) = (250, 400);
    let mut out = Vec::with_capacity(nt * np);
    for a in 0..nt {
        let theta = std::f64::consts::PI * (a as f64 + 0.5) / nt as f64;
        for b in 0..np {
            let phi = 2.0 * std::f64::consts::PI * b as f64 / np as f64;
            out.push(
                DVec3::splat(0.5)
                    + DVec3::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    ) * 0.45,
            );
        }
    }
    out
}

fn unit_lattice(degree: usize, count: usize) -> BSplineVolume {
    BSplineVolume::affine(
        DVec3::ZERO,
        [DVec3::X, DVec3::Y, DVec3::Z],
        [degree; 3],
        [count; 3],
    )
    .unwrap()
}

fn ffd(c: &mut Criterion) {
    let pts = mesh();
    assert_eq!(pts.len(), 100_000);
    let mut g = c.benchmark_group("ffd");
    for (name, degree, count) in [("move_point", 3, 8), ("bernstein_move_point", 3, 4)] {
        let lat = unit_lattice(degree, count);
        let mut f = Ffd::new(lat.clone());
        let emb = f.embed(&pts, 1e-9).unwrap();
        let mut out = vec![DVec3::ZERO; pts.len()];
        f.deform_all(&emb, &mut out).unwrap();
        // A point on the sphere's equator side of the lattice.
        let idx = lat.index(count - 2, count / 2, count / 2);
        let rest = lat.points()[idx];
        let touched = f.move_point(idx, rest, &emb, &mut out).unwrap();
        println!(
            "{name}: {touched} of {} vertices in the moved point's support",
            pts.len()
        );
        let mut k = 0u32;
        g.bench_function(name, |b| {
            b.iter(|| {
                k += 1;
                let p = rest + DVec3::new(0.05 * ((k % 7) as f64), 0.02, 0.0);
                black_box(f.move_point(idx, p, &emb, &mut out).unwrap())
            })
        });
        if count == 8 {
            g.bench_function("recompute_all", |b| {
                b.iter(|| {
                    f.deform_all(&emb, &mut out).unwrap();
                    black_box(out[0])
                })
            });
        }
    }
    g.finish();
}

fn display(c: &mut Criterion) {
    let lattice = chair().unwrap();
    let mut displays: Vec<BodyDisplay> = (0..5).map(|_| BodyDisplay::new(3, 17)).collect();
    c.bench_function("chair/display", |b| {
        b.iter(|| {
            for (d, v) in displays.iter_mut().zip(lattice.bodies()) {
                d.update(v);
            }
            black_box(displays[0].faces[0].positions[0])
        })
    });
    let m = cube_to_spool().unwrap();
    let mut body = m.source().clone();
    let mut disp = BodyDisplay::new(3, 17);
    let mut k = 0u32;
    c.bench_function("morph/frame", |b| {
        b.iter(|| {
            k = (k + 1) % 60;
            m.at_into(k as f64 / 59.0, &mut body);
            disp.update(&body);
            black_box(disp.faces[0].positions[0])
        })
    });
    c.bench_function("morph/body_at_t", |b| {
        b.iter(|| {
            k = (k + 1) % 60;
            m.at_into(k as f64 / 59.0, &mut body);
            black_box(body.points()[0])
        })
    });
}

fn injective(c: &mut Criterion) {
    let lat = unit_lattice(3, 8);
    let idx = lat.index(6, 4, 4);
    let rest = lat.points()[idx];
    let mut g = c.benchmark_group("injective");
    // The point wanders on a small loop: no lattice repeats.
    let moved = |k: u32| {
        let a = 0.05 * k as f64;
        let mut v = lat.clone();
        v.set_point(idx, rest + 0.04 * DVec3::new(a.cos(), a.sin(), 0.0))
            .unwrap();
        v
    };
    let mut cache = InjectivityCache::default();
    cache.check(&lat).unwrap();
    println!(
        "injective: {} of {} cells reached by point (6, 4, 4)",
        cache.changed_cells(&moved(1)),
        check_injective(&lat).unwrap().cells
    );
    let mut k = 0u32;
    g.bench_function("fresh", |b| {
        b.iter(|| {
            k += 1;
            black_box(check_injective(&moved(k)).unwrap().lower_bound)
        })
    });
    g.bench_function("kept", |b| {
        b.iter(|| {
            k += 1;
            black_box(cache.check(&moved(k)).unwrap().lower_bound)
        })
    });
    g.finish();
}

criterion_group!(benches, ffd, display, injective);
criterion_main!(benches);
