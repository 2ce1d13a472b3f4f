//! A curve drag on the bottle network (6 faces, one five-sided) sampled at
//! ≈ 20 000 points: every frame replaces a curve (meetings re-tracked,
//! faces re-checked), rebuilds the patches and re-evaluates every sample.
//! `precomputed`: the samplers' domain weights (s_i, d_i, blends, tuning
//! weights) are computed once, a frame re-evaluates the ribbons of the sides
//! whose data changed (here the bottom side of the label face: the dragged
//! control point's support) and recombines every sample;
//! `all_sides`: the same samplers made to re-evaluate every side's ribbon
//! at every sample (the worst case: a drag that changes every side, and
//! the previous implementation);
//! `baseline`: every sample evaluated from its domain point (Wachspress
//! coordinates and blends recomputed). Target: ≥ 60 frames/s on one core.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DVec2, DVec3};
use vsculpt_kernel::network::demo::bottle;
use vsculpt_kernel::network::{DomainMesh, PatchSampler};

fn bench(c: &mut Criterion) {
    let mut net = bottle().unwrap();
    let patches = net.patches();
    // The lattice resolution giving ≈ 20 000 samples over the six faces.
    let mut m = 8;
    let count = |m: usize| {
        patches
            .iter()
            .map(|p| DomainMesh::new(p.domain(), m).points.len())
            .sum::<usize>()
    };
    while count(m) < 20_000 {
        m += 1;
    }
    let mut samplers: Vec<PatchSampler> = patches.iter().map(|p| PatchSampler::new(p, m)).collect();
    let domains: Vec<Vec<DVec2>> = samplers.iter().map(|s| s.mesh().points.clone()).collect();
    let total: usize = samplers.iter().map(|s| s.len()).sum();
    println!("bottle: {} faces, m = {m}, {total} samples", patches.len());
    let ring = net.curves()[0].clone();
    let mut out: Vec<Vec<DVec3>> = vec![Vec::new(); samplers.len()];
    let mut frame = 0u64;
    let mut group = c.benchmark_group("network_drag_20k");
    group.bench_function("precomputed", |b| {
        b.iter(|| {
            frame += 1;
            let mut moved = ring.clone();
            moved.points_mut()[18] += DVec3::new(0.02 * ((frame % 7) as f64), 0.0, 0.0);
            net.set_curve(0, moved).unwrap();
            for (k, s) in samplers.iter_mut().enumerate() {
                let p = net.patch(k).unwrap();
                s.evaluate(&p, &mut out[k]);
            }
            out[0][0]
        })
    });
    group.bench_function("all_sides", |b| {
        b.iter(|| {
            frame += 1;
            let mut moved = ring.clone();
            moved.points_mut()[18] += DVec3::new(0.02 * ((frame % 7) as f64), 0.0, 0.0);
            net.set_curve(0, moved).unwrap();
            for (k, s) in samplers.iter_mut().enumerate() {
                let p = net.patch(k).unwrap();
                s.invalidate();
                s.evaluate(&p, &mut out[k]);
            }
            out[0][0]
        })
    });
    group.bench_function("baseline", |b| {
        b.iter(|| {
            frame += 1;
            let mut moved = ring.clone();
            moved.points_mut()[18] += DVec3::new(0.02 * ((frame % 7) as f64), 0.0, 0.0);
            net.set_curve(0, moved).unwrap();
            for (k, d) in domains.iter().enumerate() {
                let p = net.patch(k).unwrap();
                out[k].clear();
                out[k].extend(d.iter().map(|q| p.point(*q)));
            }
            out[0][0]
        })
    });
    group.bench_function("edit_only", |b| {
        b.iter(|| {
            frame += 1;
            let mut moved = ring.clone();
            moved.points_mut()[18] += DVec3::new(0.02 * ((frame % 7) as f64), 0.0, 0.0);
            net.set_curve(0, moved).unwrap();
            net.patches().len()
        })
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
