//! Tessellation alone (tables prebuilt, [`Tessellator::fill`]) of the paper's
//! five bicubic surfaces (paper 003, Table 2: 20×15 … 81×159 control
//! points) at about the paper's polygon counts, with positions, unit
//! normals, (u,v), mean and Gaussian curvature per vertex.
//!
//! Run: `cargo bench -p vsculpt-kernel --bench tessellate`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use vsculpt_kernel::analysis::{Tessellation, Tessellator, samples_for};
use vsculpt_kernel::bspline::BSplineSurface;

/// (nu, nv, triangles) of paper 003's Table 2.
const GRIDS: [(usize, usize, usize); 5] = [
    (20, 15, 1533),
    (38, 32, 2028),
    (42, 40, 3956),
    (91, 54, 13000),
    (81, 159, 48536),
];

/// A smooth bump over a plane of `nu × nv` bicubic control points.
fn bump(nu: usize, nv: usize) -> BSplineSurface {
    let (w, h) = (nu as f64 / 10.0, nv as f64 / 10.0);
    let mut s = BSplineSurface::plane(w, h, nu, nv, 3).expect("valid plane");
    for p in s.points_mut() {
        p.z = 0.2
            * w.min(h)
            * (std::f64::consts::PI * p.x / w).sin()
            * (std::f64::consts::PI * p.y / h).sin();
    }
    s
}

fn tessellate(c: &mut Criterion) {
    let mut group = c.benchmark_group("tessellate_fill");
    for (nu, nv, tris) in GRIDS {
        let s = bump(nu, nv);
        let (su, sv) = samples_for(&s, tris);
        let mut tess = Tessellator::new(&s, su, sv);
        let mut out = Tessellation::default();
        tess.fill(&s, &mut out);
        let id = format!("{nu}x{nv}/{}tri/{}v", out.triangles(), su * sv);
        group.throughput(Throughput::Elements((su * sv) as u64));
        group.bench_function(BenchmarkId::from_parameter(id), |b| {
            b.iter(|| {
                tess.fill(black_box(&s), &mut out);
                black_box(&out.positions);
            })
        });
    }
    group.finish();
}

criterion_group!(benches, tessellate);
criterion_main!(benches);
