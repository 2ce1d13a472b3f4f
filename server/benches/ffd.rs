//! FFD of a bound DSM part's mesh on the server path (issue 13): a DSM
//! sphere meshed to ≥ 100 000 vertices, bound to a tricubic 8³ body (the
//! kernel bench's lattice, `kernel/benches/body.rs`), one lattice point
//! moving each iteration:
//!
//! * `ffd_server/dsm_sync` — what the design model does for the DSM part
//!   after a lattice edit (`DsmFfds::sync`): find the moved lattice point,
//!   recompute only the vertices of its support (`Ffd::move_point`), then
//!   the normals of the deformed mesh;
//! * `ffd_server/dsm_sync_and_frame` — the same plus the mesh frame (kind 3)
//!   every viewer receives (quantised and encoded);
//! * `lattice_move/after` — the whole server path of a `body_edit` moving
//!   one lattice point, as the design actor runs it: `DesignModel::apply`
//!   (the edit validated: the body proved injective, with the proofs of
//!   the cells the point does not reach kept from the last edit; the
//!   body's display re-evaluated; the bound mesh's vertices in the point's
//!   support recomputed with the normals around them; the document
//!   synchronised), then `DesignModel::geometry` of every part it moved
//!   (the body frame and the DSM part's mesh frame, kept encoded and
//!   patched at the moved vertices, with the mesh delta a `mesh_delta=1`
//!   client gets: `server/src/design/ffd_frame.rs`);
//! * `lattice_move/whole_frame` — the same with the DSM mesh frame encoded
//!   afresh at every move and compared with the one before for a delta (the
//!   server before the frame was kept);
//! * `lattice_move/before` — every vertex and normal recomputed
//!   (`set_ffd_full_recompute`, which also drops the kept frame: a whole
//!   encoding) and every proof made afresh (`body_proof::forget`): the
//!   server as it was before locality.
//!
//! Each variant prints the bytes a delta client gets per move.
//!
//! Run: `cargo bench -p vsculpt-server --bench ffd`.

use axum::body::Bytes;
use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use std::hint::black_box;
use vsculpt_kernel::body::BSplineVolume;
use vsculpt_protocol::dsm::{DsmData, DsmGroup, DsmOp, DsmPrimitive, DsmPrimitiveShape};
use vsculpt_server::design::body_part::{BodyPart, LatticeDoc, LatticeSelect};
use vsculpt_server::design::body_proof;
use vsculpt_server::design::doc::DesignDoc;
use vsculpt_server::design::dsm_delta::mesh_delta;
use vsculpt_server::design::dsm_engine::{DsmEngine, DsmPart, mesh_frame};
use vsculpt_server::design::edit::{Edit, PartEdit};
use vsculpt_server::design::ffd_binding::DsmFfds;
use vsculpt_server::design::model::DesignModel;
use vsculpt_server::design::part::{PartBody, RelationKind};

/// How a bench variant publishes the moved parts.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Every vertex and proof afresh, the whole frame encoded.
    Before,
    /// Locality, the whole frame encoded afresh and compared for a delta.
    WholeFrame,
    /// Locality, the frame kept encoded and patched, the delta sent.
    After,
}

/// Cells of the DSM sphere's mesh (≥ 100 000 vertices: the grid step is snapped to 2^(k/16), so 146 gives 96 494 since issue 12's lattice grid).
const CELLS: u32 = 153;

fn sphere() -> DsmPart {
    DsmPart::new(DsmData {
        de: 1.0,
        cells: CELLS,
        groups: vec![DsmGroup {
            op: DsmOp::Add,
            incorporated: Vec::new(),
            primitives: vec![DsmPrimitive {
                id: 1,
                at: [0.5, 0.5, 0.5],
                axis: None,
                shape: DsmPrimitiveShape::Sphere {
                    radius: 0.45,
                    negative: false,
                },
            }],
        }],
    })
}

fn lattice() -> LatticeDoc {
    let v =
        BSplineVolume::affine(DVec3::ZERO, [DVec3::X, DVec3::Y, DVec3::Z], [3; 3], [8; 3]).unwrap();
    LatticeDoc::from_volume(&v)
}

/// Body part 1, DSM part 2, bound.
fn model() -> DesignModel {
    let body = PartBody::Body(BodyPart {
        lattice: lattice(),
        morph_target: None,
        icons: Vec::new(),
    });
    let mut m = DesignModel::load(&DesignDoc::single("ffd bench", "cage", body)).unwrap();
    m.apply(Edit::CreatePart {
        name: "blob".into(),
        body: Box::new(PartBody::Dsm(sphere())),
        colour: None,
    })
    .unwrap();
    m.apply(Edit::Relate(RelationKind::Ffd {
        body: 1,
        part: 2,
        rest: None,
    }))
    .unwrap();
    m
}

/// The lattice point moved: (6, 4, 4), on the sphere's side (as the kernel bench).
const IJK: [usize; 3] = [6, 4, 4];

fn bench(c: &mut Criterion) {
    let m = model();
    let n = m.dsm_mesh(2).unwrap().positions.len();
    println!("dsm mesh: {n} vertices");
    assert!(n >= 100_000, "{n} vertices");
    let mut g = c.benchmark_group("ffd_server");

    // Two documents whose body differs in the one point: sync alternates.
    let doc = m.doc().clone();
    let mut moved = doc.clone();
    if let Some(p) = moved.part_mut(1)
        && let PartBody::Body(b) = &mut p.body
    {
        b.move_points(LatticeSelect::Point(IJK), [0.05, 0.02, 0.0])
            .unwrap();
    }
    let mut dsm = DsmEngine::default();
    dsm.insert(2, &sphere()).unwrap();
    let mut ffds = DsmFfds::default();
    ffds.sync(&doc, &dsm).unwrap();
    let mut k = 0u64;
    g.bench_function("dsm_sync", |b| {
        b.iter(|| {
            k += 1;
            let d = if k.is_multiple_of(2) { &doc } else { &moved };
            black_box(ffds.sync(d, &dsm).unwrap())
        })
    });
    g.bench_function("dsm_sync_and_frame", |b| {
        b.iter(|| {
            k += 1;
            let d = if k.is_multiple_of(2) { &doc } else { &moved };
            ffds.sync(d, &dsm).unwrap();
            black_box(ffds.frame(1, 2, k, true).unwrap().0.len())
        })
    });
    g.finish();

    // The whole server path of a lattice point's move, as the design actor
    // runs it for a `body_edit` (`DesignModel::apply`) and then for its
    // publication (`DesignModel::geometry` of every part it moved: the
    // body frame and the DSM part's mesh frame). The point wanders on a
    // small loop so no lattice repeats (a repeated lattice would find its
    // proof kept whole).
    let mut g = c.benchmark_group("lattice_move");
    g.sample_size(10);
    for (name, mode) in [
        ("before", Mode::Before),
        ("whole_frame", Mode::WholeFrame),
        ("after", Mode::After),
    ] {
        let mut m = model();
        m.set_ffd_full_recompute(mode == Mode::Before);
        let mut k = 0u64;
        let mut previous: Option<Bytes> = None;
        let (mut sent, mut whole, mut moves) = (0usize, 0usize, 0usize);
        g.bench_function(name, |b| {
            b.iter(|| {
                k += 1;
                if mode == Mode::Before {
                    body_proof::forget();
                }
                let a = 0.05 * k as f64;
                let (_, parts) = m
                    .apply(Edit::Part {
                        part: 1,
                        edit: PartEdit::MoveLattice {
                            select: LatticeSelect::Point(IJK),
                            delta: [0.002 * a.cos(), 0.002 * a.sin(), 0.0],
                        },
                    })
                    .unwrap();
                assert!(parts.contains(&1) && parts.contains(&2));
                let body = m.geometry(1, 1, k, false).unwrap().frame.len();
                let mesh = if mode == Mode::WholeFrame {
                    // As the server did before the frame was kept: the whole
                    // frame encoded afresh (on the mesh's box), then compared
                    // with the one before for a delta.
                    let frame = mesh_frame(m.dsm_mesh(2).unwrap(), 1, 2, k, false, None).unwrap();
                    let delta = previous.as_ref().and_then(|p| mesh_delta(k - 1, p, &frame));
                    let n = delta.map_or(frame.len(), |d| d.frame.len());
                    whole += frame.len();
                    previous = Some(frame);
                    n
                } else {
                    // What a delta client gets: the delta when there is one.
                    let g = m.geometry(1, 2, k, false).unwrap();
                    whole += g.frame.len();
                    g.mesh_delta.map_or(g.frame.len(), |d| d.frame.len())
                };
                sent += body + mesh;
                moves += 1;
                black_box(body + mesh)
            })
        });
        println!(
            "{name}: {:.0} kB to a delta client per move (whole mesh frame {:.0} kB)",
            sent as f64 / moves.max(1) as f64 / 1e3,
            whole as f64 / moves.max(1) as f64 / 1e3
        );
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
