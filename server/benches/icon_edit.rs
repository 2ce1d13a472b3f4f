//! Icon edits on the server's design model (issue 15), on the paper's
//! 81 × 159 flat plate set up as the paper does (four point constraints, a
//! held straight curve, a point load pulled up by a fifth of the plate and
//! released), each edit as the design actor runs it (`DesignModel::apply`:
//! the document edited and validated, the kernel updated and solved, the
//! document synchronised):
//!
//! * `icon_edit/add_delete_point/{in_place,rebuild}` — a point constraint
//!   created at the next of 16 places and deleted again (two edits);
//! * `icon_edit/sleep_wake/…` — a point constraint put to sleep and woken
//!   (two edits);
//! * `icon_edit/add_delete_region/…` — an inside region constraint (it pins
//!   the control points under it) created and deleted (two edits);
//! * `icon_edit/first_frame_after_region/…` — a region created, then the
//!   load grabbed and dragged one frame (timed: the grab and that frame,
//!   as a client waits for it), released; the region deleted. `idle`
//!   settles the deferred refactor between the edit and the grab, as the
//!   design actor does when no request waits (not timed).
//!
//! * `icon_edit/undo_then_first_frame/{alone,taken}` — a point constraint
//!   created, then undone (the model built from the stored document) and
//!   the load grabbed and dragged one frame (timed: the undo, the grab and
//!   the frame): `alone` builds the kernel designs afresh (the server
//!   before: a factorisation and every column at the grab), `taken` takes
//!   the replaced model's solvers (`DesignModel::load_replacing`).
//!
//! `in_place` is the server since issue 15's in-place edits
//! (`product_engine::icon_edit`); `rebuild` rebuilds the part from its
//! edited document at every edit (`DesignModel::set_edit_in_place(false)`),
//! the server before.
//!
//! Run: `cargo bench -p vsculpt-server --bench icon_edit`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use std::hint::black_box;
use std::time::{Duration, Instant};
use vsculpt_server::design::demo::plate;
use vsculpt_server::design::doc::UvCurveDoc;
use vsculpt_server::design::doc::{AnchorDoc, IconRoleDoc, IconStateDoc};
use vsculpt_server::design::edit::{Edit, PartEdit};
use vsculpt_server::design::model::DesignModel;

/// The model, its part, the load's id.
fn scene() -> (DesignModel, u64, u64) {
    let doc = plate("paper 81x159", 81, 159).unwrap();
    let mut m = DesignModel::load(&doc).unwrap();
    let part = m.doc().parts[0].id;
    let add = |m: &mut DesignModel, anchor: AnchorDoc, role: IconRoleDoc| {
        m.apply(Edit::Part {
            part,
            edit: PartEdit::AddIcon {
                anchor,
                role,
                state: IconStateDoc::Passive,
                target: None,
            },
        })
        .unwrap()
        .0
        .icon
        .unwrap()
    };
    for (u, v) in [(0.2, 0.2), (0.8, 0.2), (0.2, 0.8), (0.8, 0.8)] {
        add(&mut m, AnchorDoc::Point { u, v }, IconRoleDoc::Position);
    }
    let curve = UvCurveDoc {
        degree: 1,
        knots: vec![0.0, 0.0, 1.0, 1.0],
        points: vec![[0.1, 0.1], [0.9, 0.1]],
    };
    add(&mut m, AnchorDoc::Curve { curve }, IconRoleDoc::Position);
    let load = add(
        &mut m,
        AnchorDoc::Point { u: 0.5, v: 0.6 },
        IconRoleDoc::Load,
    );
    let at = m.icon(load).map(|(_, i)| DVec3::from(i.xyz)).unwrap();
    m.grab(part, load).unwrap();
    m.drag(part, load, at + DVec3::new(0.0, 0.0, 20.0)).unwrap();
    m.release(part, load).unwrap();
    (m, part, load)
}

fn edit(m: &mut DesignModel, part: u64, edit: PartEdit) -> Option<u64> {
    m.apply(Edit::Part { part, edit }).unwrap().0.icon
}

fn benches(c: &mut Criterion) {
    let mut g = c.benchmark_group("icon_edit");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(8));
    for (name, in_place) in [("in_place", true), ("rebuild", false)] {
        let (mut m, part, load) = scene();
        m.set_edit_in_place(in_place);
        let mut k = 0usize;
        g.bench_function(format!("add_delete_point/{name}"), |b| {
            b.iter(|| {
                k += 1;
                let (u, v) = (0.3 + 0.1 * (k % 4) as f64, 0.3 + 0.1 * (k / 4 % 4) as f64);
                let id = edit(
                    &mut m,
                    part,
                    PartEdit::AddIcon {
                        anchor: AnchorDoc::Point { u, v },
                        role: IconRoleDoc::Position,
                        state: IconStateDoc::Passive,
                        target: None,
                    },
                )
                .unwrap();
                edit(&mut m, part, PartEdit::DeleteIcon { id });
            })
        });
        let pin = m.doc().parts[0].body.icons()[0].id;
        g.bench_function(format!("sleep_wake/{name}"), |b| {
            b.iter(|| {
                for state in [IconStateDoc::Sleeping, IconStateDoc::Passive] {
                    edit(&mut m, part, PartEdit::SetState { id: pin, state });
                }
            })
        });
        let region = AnchorDoc::Region {
            u0: 0.35,
            v0: 0.3,
            u1: 0.45,
            v1: 0.4,
            inside: true,
        };
        let add_region = |m: &mut DesignModel| {
            edit(
                m,
                part,
                PartEdit::AddIcon {
                    anchor: region.clone(),
                    role: IconRoleDoc::Position,
                    state: IconStateDoc::Passive,
                    target: None,
                },
            )
            .unwrap()
        };
        g.bench_function(format!("add_delete_region/{name}"), |b| {
            b.iter(|| {
                let id = add_region(&mut m);
                edit(&mut m, part, PartEdit::DeleteIcon { id });
            })
        });
        for idle in [false, true] {
            let label = if idle { "idle" } else { "at_once" };
            g.bench_function(format!("first_frame_after_region/{name}/{label}"), |b| {
                b.iter_custom(|iters| {
                    let mut total = Duration::ZERO;
                    for _ in 0..iters {
                        let id = add_region(&mut m);
                        if idle {
                            m.settle_idle().unwrap();
                        }
                        let at = m.icon(load).map(|(_, i)| DVec3::from(i.xyz)).unwrap();
                        let t = Instant::now();
                        m.grab(part, load).unwrap();
                        black_box(m.drag(part, load, at + DVec3::new(0.0, 0.0, 1.0)).unwrap());
                        total += t.elapsed();
                        m.drag(part, load, at).unwrap();
                        m.release(part, load).unwrap();
                        edit(&mut m, part, PartEdit::DeleteIcon { id });
                        if idle {
                            m.settle_idle().unwrap();
                        }
                    }
                    total
                })
            });
        }
    }
    // Undo of a point constraint's creation, then a grab of the load: the
    // model built afresh from the stored document alone (the server before)
    // or taking the replaced model's solvers (`DesignModel::load_replacing`).
    let (mut m, part, load) = scene();
    for (name, take) in [("alone", false), ("taken", true)] {
        g.bench_function(format!("undo_then_first_frame/{name}"), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let before = m.doc().clone();
                    edit(
                        &mut m,
                        part,
                        PartEdit::AddIcon {
                            anchor: AnchorDoc::Point { u: 0.35, v: 0.45 },
                            role: IconRoleDoc::Position,
                            state: IconStateDoc::Passive,
                            target: None,
                        },
                    );
                    let t = Instant::now();
                    let mut undone = if take {
                        DesignModel::load_replacing(&before, &mut m).unwrap()
                    } else {
                        DesignModel::load(&before).unwrap()
                    };
                    let at = undone.icon(load).map(|(_, i)| DVec3::from(i.xyz)).unwrap();
                    undone.grab(part, load).unwrap();
                    black_box(
                        undone
                            .drag(part, load, at + DVec3::new(0.0, 0.0, 1.0))
                            .unwrap(),
                    );
                    total += t.elapsed();
                    undone.drag(part, load, at).unwrap();
                    undone.release(part, load).unwrap();
                    m = undone;
                }
                total
            })
        });
    }
    g.finish();
}

criterion_group!(icon_edit, benches);
criterion_main!(icon_edit);
