//! What a deflated message (kind 7) costs: DEFLATE-compressing a frame
//! once on the server (shared by every client that asked) and inflating it
//! (the Rust side of what a client does), against the plain encode of the
//! same frame in the same run. Frames: a smooth 81 × 159 surface and a
//! drag basis of the same size.
//!
//! Run: `cargo bench -p vsculpt-protocol --bench deflated`. Figures in
//! BENCHMARKS.md.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use vsculpt_protocol::deflated;
use vsculpt_protocol::drag_frame::DragBasis;
use vsculpt_protocol::frame::{GeometryFrame, KIND_SURFACE};

fn surface() -> GeometryFrame {
    let (nu, nv) = (81usize, 159usize);
    let knots = |n: usize| {
        let spans = n - 3;
        let mut k = vec![0.0; 4];
        k.extend((1..spans).map(|i| i as f64 / spans as f64));
        k.extend([1.0; 4]);
        k
    };
    let mut points = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (x, y) = (i as f32 * 0.1, j as f32 * 0.1);
            points.push([x, y, 1.6 * (x * 0.39).sin() * (y * 0.2).sin()]);
        }
    }
    GeometryFrame {
        kind: KIND_SURFACE,
        design: 1,
        part: 1,
        revision: 7,
        flags: 0,
        degree_u: 3,
        degree_v: 3,
        nu: nu as u32,
        nv: nv as u32,
        knots_u: knots(nu),
        knots_v: knots(nv),
        points,
        icons: Vec::new(),
    }
}

fn benches(c: &mut Criterion) {
    let frame = surface();
    let bytes = frame.encode().unwrap();
    let basis = DragBasis {
        design: 1,
        part: 1,
        basis: 1,
        reference: 7,
        rho: (0..81 * 159)
            .map(|k| {
                let (i, j) = ((k / 159) as f32, (k % 159) as f32);
                (-((i - 40.0).powi(2) + (j - 95.0).powi(2)) / 400.0).exp()
            })
            .collect(),
    }
    .encode()
    .unwrap();
    let small = deflated::deflate(&bytes).unwrap();
    let small_basis = deflated::deflate(&basis).unwrap();
    let mut g = c.benchmark_group("deflated");
    g.bench_function("encode_frame/81x159", |b| {
        b.iter(|| black_box(frame.encode().unwrap()))
    });
    g.bench_function("deflate_frame/81x159", |b| {
        b.iter(|| black_box(deflated::deflate(&bytes).unwrap()))
    });
    g.bench_function("inflate_frame/81x159", |b| {
        b.iter(|| black_box(deflated::inflate(&small).unwrap()))
    });
    g.bench_function("deflate_basis/81x159", |b| {
        b.iter(|| black_box(deflated::deflate(&basis).unwrap()))
    });
    g.bench_function("inflate_basis/81x159", |b| {
        b.iter(|| black_box(deflated::inflate(&small_basis).unwrap()))
    });
    g.finish();
}

criterion_group!(deflated_benches, benches);
criterion_main!(deflated_benches);
