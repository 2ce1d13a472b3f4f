//! Icon and material edits applied to the live kernel design (issue 15,
//! `product_engine::icon_edit`) give what a rebuild of the part from the
//! edited document gives — the server's old path, kept behind
//! `DesignModel::set_edit_in_place(false)` — over random sequences of
//! every edit kind mixed with drags (a dragged constraint leaves the plate
//! bent elastically from its old reference shape; a rebuild takes the
//! shape as it is for its reference, and so must an edit in place).
//!
//! Each step starts both from the same document (the old path rebuilt
//! from the in-place model's document). After it both answer alike (both accept or both refuse)
//! and hold the same document: every control point within 1e-7 of the
//! model's size (the rebuild solves afresh, to the kernel's tolerance of
//! 1e-9 per equation, which on ill-conditioned random sets leaves the
//! shape up to ~1e-8 of its size from the optimum; the semantic slips
//! this test found were 1e-5 to 1e-2), every icon with the same anchor,
//! role, state and sensors and its target within 1e-7; a new icon moves
//! nothing in place
//! (1e-9 of the size). Steps whose constraints contradict each other are
//! counted and not compared (see `compare`). Also: the refactor a pin change defers is
//! left for idle time and settling it moves nothing.

mod common;

use common::random::Lcg;
use glam::DVec3;
use vsculpt_server::design::demo::plate;
use vsculpt_server::design::doc::{
    AnchorDoc, DerivativeDoc, EdgeSideDoc, IconRoleDoc, IconStateDoc, MaterialDoc, UvCurveDoc,
};
use vsculpt_server::design::edit::{Edit, MaterialEdit, PartEdit};
use vsculpt_server::design::model::DesignModel;

fn anchor(r: &mut Lcg) -> AnchorDoc {
    match r.pick(6) {
        0..=2 => AnchorDoc::Point {
            u: r.within(0.05, 0.95),
            v: r.within(0.05, 0.95),
        },
        3 => {
            let v0 = r.within(0.1, 0.9);
            AnchorDoc::Curve {
                curve: UvCurveDoc {
                    degree: 3,
                    knots: vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0],
                    points: (0..4)
                        .map(|k| {
                            [
                                0.1 + 0.25 * k as f64,
                                (v0 + r.within(-0.1, 0.1)).clamp(0.02, 0.98),
                            ]
                        })
                        .collect(),
                },
            }
        }
        4 => {
            let (u0, v0) = (r.within(0.05, 0.7), r.within(0.05, 0.7));
            AnchorDoc::Region {
                u0,
                v0,
                u1: u0 + r.within(0.08, 0.25),
                v1: v0 + r.within(0.08, 0.25),
                inside: r.next() < 0.7,
            }
        }
        _ => AnchorDoc::Edge {
            edge: [
                EdgeSideDoc::UMin,
                EdgeSideDoc::UMax,
                EdgeSideDoc::VMin,
                EdgeSideDoc::VMax,
            ][r.pick(4)],
            clamped: r.next() < 0.5,
        },
    }
}

fn role(r: &mut Lcg) -> IconRoleDoc {
    match r.pick(5) {
        0 => IconRoleDoc::Load,
        1 | 2 => IconRoleDoc::Position,
        3 => IconRoleDoc::Normal,
        _ => IconRoleDoc::Derivative {
            which: [
                DerivativeDoc::R,
                DerivativeDoc::V,
                DerivativeDoc::R2,
                DerivativeDoc::V2,
                DerivativeDoc::RV,
            ][r.pick(5)],
        },
    }
}

/// One step, the same on every model: an edit, or a drag (grab, three
/// frames, release).
enum Step {
    Edit(PartEdit),
    Drag(u64, [f64; 3]),
}

fn step(r: &mut Lcg, m: &DesignModel, size: f64) -> Step {
    let icons = m.doc().parts[0].body.icons().to_vec();
    let some = |r: &mut Lcg| icons[r.pick(icons.len())].id;
    let k = if icons.len() < 3 { 0 } else { r.pick(12) };
    Step::Edit(match k {
        0..=2 => PartEdit::AddIcon {
            anchor: anchor(r),
            role: role(r),
            state: [
                IconStateDoc::Passive,
                IconStateDoc::Sleeping,
                IconStateDoc::Driving,
            ][r.pick(3)],
            target: None,
        },
        3 => PartEdit::DeleteIcon { id: some(r) },
        4 => PartEdit::SetState {
            id: some(r),
            state: [
                IconStateDoc::Passive,
                IconStateDoc::Sleeping,
                IconStateDoc::Driving,
            ][r.pick(3)],
        },
        5 => PartEdit::SetRole {
            id: some(r),
            role: role(r),
        },
        6 => {
            let i = &icons[r.pick(icons.len())];
            let at = DVec3::from(i.xyz);
            let xyz = at
                + DVec3::new(
                    r.within(-1.0, 1.0),
                    r.within(-1.0, 1.0),
                    r.within(-1.0, 1.0),
                ) * 0.05
                    * size;
            PartEdit::MoveIcon {
                id: i.id,
                xyz: xyz.to_array(),
            }
        }
        7 => PartEdit::SetAnchor {
            id: some(r),
            anchor: anchor(r),
        },
        8 => PartEdit::BindSensor {
            id: some(r),
            sensor: format!("glove{}", r.pick(2)),
        },
        9 => PartEdit::UnbindSensor {
            id: some(r),
            sensor: format!("glove{}", r.pick(2)),
        },
        10 => {
            let s = r.within(0.5, 2.0);
            PartEdit::SetMaterial(MaterialEdit::Surface(MaterialDoc {
                alpha11: 0.01 * s,
                alpha22: 0.01 * s,
                beta11: r.within(0.5, 2.0),
                ..MaterialDoc::default()
            }))
        }
        _ => {
            let i = &icons[r.pick(icons.len())];
            let by = [r.within(-1.0, 1.0), r.within(-1.0, 1.0), r.within(0.2, 1.0)];
            return Step::Drag(i.id, by.map(|x| x * 0.1 * size));
        }
    })
}

fn run(m: &mut DesignModel, s: &Step) -> Result<(), String> {
    let part = m.doc().parts[0].id;
    match s {
        Step::Edit(e) => m
            .apply(Edit::Part {
                part,
                edit: e.clone(),
            })
            .map(|_| ())
            .map_err(|e| e.message),
        Step::Drag(icon, by) => {
            let at = m
                .icon(*icon)
                .map(|(_, i)| DVec3::from(i.xyz))
                .ok_or("no icon")?;
            m.grab(part, *icon).map_err(|e| e.message)?;
            let mut out = Ok(());
            for f in 1..=3 {
                let to = at + DVec3::from(*by) * (f as f64 / 3.0);
                if let Err(e) = m.drag(part, *icon, to) {
                    out = Err(e.message);
                    break;
                }
            }
            m.release(part, *icon).map_err(|e| e.message)?;
            out
        }
    }
}

fn size(m: &DesignModel) -> f64 {
    let p = &m.doc().parts[0];
    let vsculpt_server::design::part::PartBody::Surface(s) = &p.body else {
        panic!("a surface part");
    };
    let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for q in &s.surface.points {
        lo = lo.min(DVec3::from(*q));
        hi = hi.max(DVec3::from(*q));
    }
    (hi - lo).length()
}

fn points(m: &DesignModel) -> Vec<DVec3> {
    match &m.doc().parts[0].body {
        vsculpt_server::design::part::PartBody::Surface(s) => {
            s.surface.points.iter().map(|p| DVec3::from(*p)).collect()
        }
        _ => panic!("a surface part"),
    }
}

/// The largest difference between the two models' documents, as a
/// fraction of the model's size; panics on a structural difference.
fn difference(a: &DesignModel, b: &DesignModel, what: &str) -> (f64, String) {
    let size = size(a);
    let mut worst = points(a)
        .iter()
        .zip(points(b))
        .map(|(p, q)| (*p - q).length())
        .fold(0.0, f64::max);
    let mut at = "control points".to_string();
    let (ia, ib) = (a.doc().parts[0].body.icons(), b.doc().parts[0].body.icons());
    assert_eq!(ia.len(), ib.len(), "{what}: icon count");
    for (x, y) in ia.iter().zip(ib) {
        assert_eq!(x.id, y.id, "{what}");
        assert_eq!(x.anchor, y.anchor, "{what}: icon {}", x.id);
        assert_eq!(x.role, y.role, "{what}: icon {}", x.id);
        assert_eq!(x.state, y.state, "{what}: icon {} state", x.id);
        assert_eq!(x.sensors, y.sensors, "{what}: icon {} sensors", x.id);
        let scale = if x.role == IconRoleDoc::Position || x.role == IconRoleDoc::Load {
            1.0
        } else {
            size.recip()
        };
        let t = (DVec3::from(x.target) - DVec3::from(y.target)).length() * scale;
        let p = (DVec3::from(x.xyz) - DVec3::from(y.xyz)).length();
        if t.max(p) > worst {
            worst = t.max(p);
            at = format!("icon {}: target {:?} vs {:?}", x.id, x.target, y.target);
        }
    }
    (worst / size, at)
}

fn compare(seed: u64, nu: usize, nv: usize, steps: usize) {
    let doc = plate("plate", nu, nv).unwrap();
    let mut live = DesignModel::load(&doc).unwrap();
    let mut r = Lcg(seed);
    let (mut accepted, mut refused, mut pins_left, mut contradictions) = (0, 0, 0, 0);
    let mut after_contradiction = false;
    for k in 0..steps {
        let size = size(&live);
        let s = step(&mut r, &live, size);
        let what = match &s {
            Step::Edit(e) => format!("seed {seed} step {k}: {e:?}"),
            Step::Drag(i, by) => format!("seed {seed} step {k}: drag {i} by {by:?}"),
        };
        // The old path from the same document: each step compared alone.
        let mut rebuilt = DesignModel::load(live.doc()).unwrap();
        rebuilt.set_edit_in_place(false);
        let was_live = points(&live);
        let a = run(&mut live, &s);
        let b = run(&mut rebuilt, &s);
        assert_eq!(
            a.is_ok(),
            b.is_ok(),
            "{what}: in place {a:?}, rebuilt {b:?}"
        );
        if a.is_ok() {
            accepted += 1;
        } else {
            refused += 1;
        }
        if live.edit_warning().is_some() || rebuilt.edit_warning().is_some() {
            // Contradictory constraints: the shape is a least-squares
            // compromise, and a rebuild captures the curves and regions
            // where that compromise left them (their old targets are not in
            // the document), so the two may differ from here. Both start
            // again from the in-place document.
            contradictions += 1;
            live = DesignModel::load(live.doc()).unwrap();
            // The stored compromise is not the optimum of the next set of
            // constraints: the next step's solve may move it.
            after_contradiction = true;
            continue;
        }
        let reloaded = std::mem::take(&mut after_contradiction);
        if let Step::Edit(PartEdit::AddIcon { .. }) = &s
            && !reloaded
        {
            // A new icon holds the shape where it is (a load starts with
            // no force): nothing moves in place (the old answer is proved
            // optimal). The rebuild's fresh solve is not checked here: it
            // meets every equation to 1e-9 but, on these ill-conditioned
            // sets, may land ~1e-8 of the size away (see `difference`).
            let moved = was_live
                .iter()
                .zip(&points(&live))
                .map(|(p, q)| (*p - *q).length())
                .fold(0.0, f64::max);
            assert!(
                moved <= 1e-9 * size,
                "{what}: the edit in place moved the shape by {:e} of its size",
                moved / size
            );
        }
        let (d, at) = difference(&live, &rebuilt, &what);
        assert!(
            d <= 1e-7,
            "{what}: the documents differ by {d:e} of the size ({at})"
        );
        if live.idle_work() {
            // Settling the deferred refactor moves nothing.
            pins_left += 1;
            let before = points(&live);
            assert!(live.settle_idle().unwrap(), "{what}");
            assert!(!live.idle_work());
            assert_eq!(
                before,
                points(&live),
                "{what}: the idle settle moved the shape"
            );
        }
    }
    assert!(
        accepted >= steps / 2,
        "seed {seed}: only {accepted} steps accepted"
    );
    assert!(
        contradictions <= steps / 4,
        "seed {seed}: {contradictions} steps contradicted"
    );
    eprintln!(
        "seed {seed}: {accepted} accepted, {refused} refused, {pins_left} settled when idle, {contradictions} contradictory"
    );
}

#[test]
fn in_place_edits_equal_rebuilds_on_a_20x15_plate() {
    for seed in [1, 2, 3] {
        compare(seed, 20, 15, 60);
    }
}

#[test]
fn in_place_edits_equal_rebuilds_on_a_42x40_plate() {
    compare(7, 42, 40, 40);
}

/// Creates a passive icon on `part`; its id.
fn add(m: &mut DesignModel, part: u64, anchor: AnchorDoc, role: IconRoleDoc) -> u64 {
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
}

#[test]
fn a_region_defers_its_refactor_to_idle_time_and_settling_moves_nothing() {
    let doc = plate("plate", 42, 40).unwrap();
    let mut m = DesignModel::load(&doc).unwrap();
    let part = m.doc().parts[0].id;
    let add =
        |m: &mut DesignModel, anchor: AnchorDoc, role: IconRoleDoc| add(m, part, anchor, role);
    let load = add(
        &mut m,
        AnchorDoc::Point { u: 0.5, v: 0.6 },
        IconRoleDoc::Load,
    );
    add(
        &mut m,
        AnchorDoc::Point { u: 0.2, v: 0.2 },
        IconRoleDoc::Position,
    );
    assert!(!m.idle_work(), "a point constraint pins nothing");
    // The first pins refactor at once (R would be as ill-conditioned as
    // the plate's soft modes with nothing pinned: `pin_update`); later
    // ones are answered through the old factor.
    add(
        &mut m,
        AnchorDoc::Edge {
            edge: EdgeSideDoc::UMin,
            clamped: true,
        },
        IconRoleDoc::Position,
    );
    assert!(!m.idle_work());
    let region = AnchorDoc::Region {
        u0: 0.3,
        v0: 0.3,
        u1: 0.4,
        v1: 0.45,
        inside: true,
    };
    let before = points(&m);
    add(&mut m, region, IconRoleDoc::Position);
    assert_eq!(before, points(&m), "a new region moved the shape");
    assert!(m.idle_work(), "the region's refactor was not deferred");
    assert!(m.settle_idle().unwrap());
    assert!(!m.idle_work());
    assert_eq!(before, points(&m), "settling moved the shape");
    // Another region, not settled: the grab settles it.
    add(
        &mut m,
        AnchorDoc::Region {
            u0: 0.6,
            v0: 0.6,
            u1: 0.7,
            v1: 0.7,
            inside: true,
        },
        IconRoleDoc::Position,
    );
    assert!(m.idle_work());
    assert_eq!(before, points(&m), "the second region moved the shape");
    // The grab settles what is pending; the load still pulls.
    let at = m.icon(load).map(|(_, i)| DVec3::from(i.xyz)).unwrap();
    m.grab(part, load).unwrap();
    let (reached, _, _) = m.drag(part, load, at + DVec3::new(0.0, 0.0, 10.0)).unwrap();
    assert!(!m.idle_work(), "the grab left the refactor pending");
    assert!(reached.z > at.z + 1.0, "the load did not pull: {reached:?}");
}

/// Undo, redo and restore build the model afresh from a stored document
/// (`DesignModel::load_replacing`) and take the replaced model's kernel
/// solvers: the next solves must be those of a model loaded alone. Random
/// edits, each undone and redone at random, each followed by a drag on the
/// model that took the solvers and on one loaded alone from the same
/// document: the same shape to 1e-9 of the size, and the stored shape
/// taken bit for bit.
#[test]
fn a_model_that_takes_the_replaced_ones_solvers_solves_as_one_loaded_alone() {
    let doc = plate("plate", 42, 40).unwrap();
    let mut m = DesignModel::load(&doc).unwrap();
    let mut r = Lcg(11);
    let mut history: Vec<vsculpt_server::design::doc::DesignDoc> = Vec::new();
    let (mut compared, mut undone) = (0, 0);
    for k in 0..30 {
        let size = size(&m);
        let s = step(&mut r, &m, size);
        let before = m.doc().clone();
        if run(&mut m, &s).is_err() || m.edit_warning().is_some() {
            m = DesignModel::load(m.doc()).unwrap();
            continue;
        }
        history.push(before);
        // Undo to a random earlier state now and then.
        let target = if r.next() < 0.4 {
            undone += 1;
            history[r.pick(history.len())].clone()
        } else {
            m.doc().clone()
        };
        let mut taken = DesignModel::load_replacing(&target, &mut m).unwrap();
        let mut alone = DesignModel::load(&target).unwrap();
        assert_eq!(points(&taken), points(&alone), "step {k}: the stored shape");
        // A drag of some icon on both.
        let icons = taken.doc().parts[0].body.icons().to_vec();
        if icons.is_empty() {
            m = taken;
            continue;
        }
        let icon = icons[r.pick(icons.len())].id;
        let by =
            [r.within(-1.0, 1.0), r.within(-1.0, 1.0), r.within(0.2, 1.0)].map(|x| x * 0.1 * size);
        let a = run(&mut taken, &Step::Drag(icon, by));
        let b = run(&mut alone, &Step::Drag(icon, by));
        assert_eq!(a.is_ok(), b.is_ok(), "step {k}: {a:?} vs {b:?}");
        if a.is_ok() && taken.edit_warning().is_none() {
            let (d, at) = difference(&taken, &alone, &format!("step {k}"));
            assert!(
                d <= 1e-9,
                "step {k}: the drags differ by {d:e} of the size ({at})"
            );
            compared += 1;
        }
        m = taken;
    }
    assert!(compared >= 10, "only {compared} drags compared");
    assert!(undone >= 5, "only {undone} undos");

    // Undoing a material change: the stiffness differs, so the solver must
    // not be taken (a drag through the old factor would bend the plate as
    // the other material does).
    let mut m = DesignModel::load(&doc).unwrap();
    let part = m.doc().parts[0].id;
    for (anchor, role) in [
        (AnchorDoc::Point { u: 0.2, v: 0.3 }, IconRoleDoc::Position),
        (AnchorDoc::Point { u: 0.6, v: 0.5 }, IconRoleDoc::Load),
    ] {
        add(&mut m, part, anchor, role);
    }
    let before = m.doc().clone();
    let stiffer = MaterialDoc {
        beta11: 5.0,
        beta22: 5.0,
        ..MaterialDoc::default()
    };
    m.apply(Edit::Part {
        part,
        edit: PartEdit::SetMaterial(MaterialEdit::Surface(stiffer)),
    })
    .unwrap();
    let icon = m.doc().parts[0].body.icons()[1].id;
    let lift = 0.05 * size(&m);
    run(&mut m, &Step::Drag(icon, [0.0, 0.0, lift])).unwrap();
    let mut taken = DesignModel::load_replacing(&before, &mut m).unwrap();
    let mut alone = DesignModel::load(&before).unwrap();
    let by = [0.0, 0.0, 0.1 * size(&alone)];
    let a = run(&mut taken, &Step::Drag(icon, by));
    let b = run(&mut alone, &Step::Drag(icon, by));
    assert_eq!(a.is_ok(), b.is_ok());
    let (d, at) = difference(&taken, &alone, "material undone");
    assert!(
        d <= 1e-9,
        "after a material undo the drags differ by {d:e} ({at})"
    );
}
