//! A DSM part bound to a body (FFD) under lattice moves, as a mesh-delta
//! client sees it: its mesh frame is kept encoded and patched where a move
//! moved vertices (`server/src/design/ffd_frame.rs`), and each frame comes
//! with the delta from the frame before. After every move the whole frame
//! equals a fresh encoding of the model's deformed mesh on the frame's cube
//! (an encoder that does not patch), a viewer that applies each delta to
//! the frame it holds holds exactly those bytes, and a viewer that missed
//! revisions cannot use the delta (its base is not what it holds) and takes
//! the whole frame. A move that carries the mesh out of the frame's cube,
//! and a DSM edit (a new mesh), give whole frames and no delta.

use glam::DVec3;
use vsculpt_kernel::body::BSplineVolume;
use vsculpt_protocol::MeshFrame;
use vsculpt_protocol::dsm::{DsmData, DsmEdit, DsmGroup, DsmOp, DsmPrimitive, DsmPrimitiveShape};
use vsculpt_protocol::mesh_delta::MeshDelta;
use vsculpt_server::design::body_part::{BodyPart, LatticeDoc, LatticeSelect};
use vsculpt_server::design::doc::DesignDoc;
use vsculpt_server::design::dsm_engine::DsmPart;
use vsculpt_server::design::edit::{Edit, PartEdit};
use vsculpt_server::design::model::DesignModel;
use vsculpt_server::design::part::{PartBody, RelationKind};

/// Body part 1 (a tricubic 6³ lattice on the unit cube), DSM sphere part 2
/// inside it, bound.
fn model() -> DesignModel {
    let v =
        BSplineVolume::affine(DVec3::ZERO, [DVec3::X, DVec3::Y, DVec3::Z], [3; 3], [6; 3]).unwrap();
    let body = PartBody::Body(BodyPart {
        lattice: LatticeDoc::from_volume(&v),
        morph_target: None,
        icons: Vec::new(),
    });
    let mut m = DesignModel::load(&DesignDoc::single("ffd delta", "cage", body)).unwrap();
    let sphere = DsmData {
        de: 1.0,
        cells: 20,
        groups: vec![DsmGroup {
            op: DsmOp::Add,
            incorporated: Vec::new(),
            primitives: vec![DsmPrimitive {
                id: 1,
                at: [0.5, 0.5, 0.5],
                axis: None,
                shape: DsmPrimitiveShape::Sphere {
                    radius: 0.4,
                    negative: false,
                },
            }],
        }],
    };
    m.apply(Edit::CreatePart {
        name: "blob".into(),
        body: Box::new(PartBody::Dsm(DsmPart::new(sphere))),
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

/// The model's mesh of part 2 encoded afresh at `rev` on the cube of `like`.
fn fresh(m: &DesignModel, rev: u64, like: &MeshFrame) -> Vec<u8> {
    let mesh = m.dsm_mesh(2).unwrap();
    let p: Vec<[f64; 3]> = mesh.positions.iter().map(|x| x.to_array()).collect();
    let n: Vec<[f64; 3]> = mesh.normals.iter().map(|x| x.to_array()).collect();
    let cube = (like.origin.map(f64::from), like.step as f64 * 65535.0);
    MeshFrame::quantise_in((1, 2, rev), 0, cube, &p, &n, &mesh.triangles)
        .unwrap()
        .encode()
        .unwrap()
}

/// A viewer's frame of part 2: (revision, bytes).
type Held = (u64, Vec<u8>);

/// What a viewer holding `held` makes of the frame `whole` with `delta`
/// (base, bytes): the delta applied when its base is what it holds, else the
/// whole frame. Returns whether it used the delta.
fn receive(held: &mut Held, rev: u64, whole: &[u8], delta: Option<(u64, &[u8])>) -> bool {
    if let Some((base, bytes)) = delta
        && base == held.0
    {
        let d = MeshDelta::decode(bytes).unwrap();
        let made = d.apply(&MeshFrame::decode(&held.1).unwrap()).unwrap();
        *held = (rev, made.encode().unwrap());
        return true;
    }
    *held = (rev, whole.to_vec());
    false
}

fn lattice_move(m: &mut DesignModel, ijk: [usize; 3], delta: [f64; 3]) {
    let (_, parts) = m
        .apply(Edit::Part {
            part: 1,
            edit: PartEdit::MoveLattice {
                select: LatticeSelect::Point(ijk),
                delta,
            },
        })
        .unwrap();
    assert!(parts.contains(&2), "{parts:?}");
}

#[test]
fn a_delta_viewer_of_a_bound_dsm_part_holds_the_whole_frame_after_every_lattice_move() {
    let mut m = model();
    let first = m.geometry(1, 2, 1, false).unwrap();
    assert!(first.mesh_delta.is_none(), "nothing to be a delta from");
    let mut viewer: Held = (1, first.frame.to_vec());
    // Looks at every third frame only (a paced or slow client).
    let mut slow: Held = viewer.clone();
    let (mut deltas, mut delta_bytes, mut whole_bytes) = (0, 0, 0);
    // A seeded walk of lattice points (inner ones reach the sphere).
    let mut seed = 0x5eed_f00d_u64;
    let mut next = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 33) as f64 / (1u64 << 31) as f64
    };
    for rev in 2..=25u64 {
        let ijk = [0, 1, 2].map(|_| 1 + (next() * 4.0) as usize);
        let step = [0, 1, 2].map(|_| 0.01 * (next() - 0.5));
        lattice_move(&mut m, ijk, step);
        let g = m.geometry(1, 2, rev, false).unwrap();
        let frame = MeshFrame::decode(&g.frame).unwrap();
        assert_eq!(frame.revision, rev);
        assert_eq!(
            g.frame.to_vec(),
            fresh(&m, rev, &frame),
            "rev {rev}: the kept frame is not a fresh encoding of the mesh"
        );
        let delta = g.mesh_delta.as_ref().map(|d| (d.base, &d.frame[..]));
        if let Some((base, bytes)) = delta {
            assert_eq!(base, rev - 1, "a delta from the frame handed out before");
            assert!(bytes.len() < g.frame.len());
            deltas += 1;
            delta_bytes += bytes.len();
            whole_bytes += g.frame.len();
        }
        receive(&mut viewer, rev, &g.frame, delta);
        assert_eq!(viewer.1, g.frame.to_vec(), "rev {rev}: the delta viewer");
        if rev % 3 == 0 {
            // It holds an older revision: the delta is not for it.
            let used = receive(&mut slow, rev, &g.frame, delta);
            assert!(!used, "rev {rev}: a delta from {:?}", delta.map(|d| d.0));
            assert_eq!(slow.1, g.frame.to_vec());
        }
    }
    assert!(deltas >= 20, "{deltas} deltas in 24 moves");
    println!(
        "{deltas} deltas, {} bytes each against a whole frame of {}",
        delta_bytes / deltas,
        whole_bytes / deltas
    );

    // Points above the sphere's top raised step by step carry the mesh out
    // of the frame's cube: then a new cube, a whole frame, no delta.
    let mut rev = 25;
    let renewed = (0..8).any(|_| {
        for k in [5, 4] {
            lattice_move(&mut m, [2, 3, k], [0.0, 0.0, 0.1]);
        }
        rev += 1;
        let g = m.geometry(1, 2, rev, false).unwrap();
        let before = MeshFrame::decode(&viewer.1).unwrap();
        let frame = MeshFrame::decode(&g.frame).unwrap();
        assert_eq!(g.frame.to_vec(), fresh(&m, rev, &frame));
        let delta = g.mesh_delta.as_ref().map(|d| (d.base, &d.frame[..]));
        receive(&mut viewer, rev, &g.frame, delta);
        assert_eq!(viewer.1, g.frame.to_vec());
        let new_cube = frame.origin != before.origin || frame.step != before.step;
        assert!(!new_cube || delta.is_none(), "no delta across cubes");
        new_cube
    });
    assert!(renewed, "the mesh never left its cube");

    // The next move is a delta again, on the new cube.
    lattice_move(&mut m, [2, 3, 2], [0.004, 0.0, 0.0]);
    let g = m.geometry(1, 2, rev + 1, false).unwrap();
    let frame = MeshFrame::decode(&g.frame).unwrap();
    assert_eq!(g.frame.to_vec(), fresh(&m, rev + 1, &frame));
    let delta = g.mesh_delta.as_ref().map(|d| (d.base, &d.frame[..]));
    assert!(receive(&mut viewer, rev + 1, &g.frame, delta));
    assert_eq!(viewer.1, g.frame.to_vec());

    // A DSM edit re-meshes: the whole frame of the new mesh.
    m.apply(Edit::Dsm {
        part: 2,
        edit: DsmEdit::MovePrimitive {
            id: 1,
            at: [0.5, 0.52, 0.5],
        },
    })
    .unwrap();
    let g = m.geometry(1, 2, rev + 2, false).unwrap();
    let frame = MeshFrame::decode(&g.frame).unwrap();
    assert_eq!(g.frame.to_vec(), fresh(&m, rev + 2, &frame));
    let delta = g.mesh_delta.as_ref().map(|d| (d.base, &d.frame[..]));
    receive(&mut viewer, rev + 2, &g.frame, delta);
    assert_eq!(viewer.1, g.frame.to_vec());

    // The same revision asked again gives the same bytes and no delta.
    let again = m.geometry(1, 2, rev + 2, false).unwrap();
    assert_eq!(again.frame, g.frame);
    assert!(again.mesh_delta.is_none());
}
