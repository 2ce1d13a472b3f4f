//! Joined surface parts: G1 and G0 seams held exactly (at 50 points along
//! the seam, between control points and knots) after every drag frame, on
//! the seam and inside either part; joining is the least-energy change
//! (checked against an independent dense KKT solve); unjoining keeps shapes.

mod product_support;

use glam::DVec3;
use product_support::*;
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::Role;
use vsculpt_kernel::product::{ChangedParts, Continuity, Edge, JoinSpec, PartId, Product};

/// A (8 × 7) and B (6 × 7, v over [0, 2]: an affine reparameterisation of
/// A's v knots) side by side with a gap of 0.05 and different slopes at
/// the seam; each pinned at its far corners.
fn pair() -> (Product, PartId, PartId) {
    let mut p = Product::new();
    let a = p.add_part(surface_part(panel(0.0, 8, v_knots(1.0), 0.0, 0.1)));
    let b = p.add_part(surface_part(panel(1.05, 6, v_knots(2.0), 0.12, -0.2)));
    p.edit_surface(a, |d| {
        d.add_icon(point(0.0, 0.0, Role::Position))?;
        d.add_icon(point(0.0, 1.0, Role::Position))
    })
    .unwrap();
    p.edit_surface(b, |d| {
        d.add_icon(point(1.0, 0.0, Role::Position))?;
        d.add_icon(point(1.0, 2.0, Role::Position))
    })
    .unwrap();
    (p, a, b)
}

fn spec(a: PartId, b: PartId, continuity: Continuity) -> JoinSpec {
    JoinSpec {
        a,
        edge_a: Edge::UMax,
        b,
        edge_b: Edge::UMin,
        reversed: false,
        continuity,
        ratio: None,
    }
}

/// (position gap / model size, normal angle) over 50 seam points.
fn seam(p: &Product, a: PartId, b: PartId) -> (f64, f64) {
    let (sa, sb) = (
        p.surface(a).unwrap().surface(),
        p.surface(b).unwrap().surface(),
    );
    let (gap, ang) = seam_gaps(sa, Edge::UMax, sb, Edge::UMin, false, 50);
    (gap / model_size(p), ang)
}

fn moved(before: &[DVec3], after: &[DVec3]) -> f64 {
    before
        .iter()
        .zip(after)
        .map(|(x, y)| (*x - *y).length())
        .fold(0.0, f64::max)
}

/// Drags `icon` of `part` through `frames` frames of `step`, checking the
/// seam after every frame with `check`; releases; returns how far each
/// part moved.
fn drag_frames(
    p: &mut Product,
    part: PartId,
    icon: vsculpt_kernel::icon::IconId,
    step: DVec3,
    frames: usize,
    check: &dyn Fn(&Product, usize),
) -> Vec<f64> {
    let before = all_points(p);
    let start = p.surface(part).unwrap().icon(icon).unwrap().xyz;
    for k in 1..=frames {
        let r = p.drag(part, icon, start + step * k as f64).unwrap();
        assert_eq!(r.changed, p.solved_with(part));
        check(p, k);
    }
    p.release(part, icon).unwrap();
    check(p, frames + 1);
    let after = all_points(p);
    before
        .keys()
        .map(|id| moved(&before[id], &after[id]))
        .collect()
}

#[test]
fn a_g1_seam_holds_normals_and_positions_after_every_drag_frame() {
    let (mut p, a, b) = pair();
    let (gap0, ang0) = seam(&p, a, b);
    assert!(
        gap0 > 1e-2 && ang0 > 1e-2,
        "the panels start apart: {gap0} {ang0}"
    );
    let (_, changed) = p.join(spec(a, b, Continuity::G1)).unwrap();
    assert_eq!(changed, ChangedParts::from_ids([a, b]));
    let check = |p: &Product, frame: usize| {
        let (gap, ang) = seam(p, a, b);
        assert!(gap < 1e-9, "frame {frame}: seam gap {gap:e} of the size");
        assert!(ang < 1e-9, "frame {frame}: normals differ by {ang:e} rad");
    };
    check(&p, 0);
    // The seam itself: a position icon on A's edge.
    let seam_icon = p
        .edit_surface(a, |d| d.add_icon(point(1.0, 0.4, Role::Position)))
        .unwrap()
        .value;
    let m = drag_frames(&mut p, a, seam_icon, DVec3::new(0.0, 0.01, 0.03), 8, &check);
    assert!(
        m.iter().all(|&x| x > 0.05),
        "both panels follow the seam: {m:?}"
    );
    // A load inside A, then a position icon inside B: both panels move.
    let load = p
        .edit_surface(a, |d| d.add_icon(point(0.55, 0.6, Role::Load)))
        .unwrap()
        .value;
    let m = drag_frames(&mut p, a, load, DVec3::new(0.0, 0.0, -0.04), 6, &check);
    assert!(
        m.iter().all(|&x| x > 1e-3),
        "a pull inside A moves both: {m:?}"
    );
    let inner = p
        .edit_surface(b, |d| d.add_icon(point(0.45, 1.3, Role::Position)))
        .unwrap()
        .value;
    let m = drag_frames(&mut p, b, inner, DVec3::new(0.02, 0.0, 0.05), 6, &check);
    assert!(
        m.iter().all(|&x| x > 1e-3),
        "a pull inside B moves both: {m:?}"
    );
    // An edit on one part re-solves the pair and keeps the seam.
    let c = p
        .edit_surface(b, |d| d.set_target(inner, DVec3::new(1.5, 0.65, 0.4)))
        .unwrap();
    assert_eq!(c.changed, ChangedParts::from_ids([a, b]));
    check(&p, 99);
}

#[test]
fn a_g0_seam_holds_positions_after_every_drag_frame_and_leaves_the_normals_free() {
    let (mut p, a, b) = pair();
    p.join(spec(a, b, Continuity::G0)).unwrap();
    let check = |p: &Product, frame: usize| {
        let (gap, _) = seam(p, a, b);
        assert!(gap < 1e-9, "frame {frame}: seam gap {gap:e} of the size");
    };
    check(&p, 0);
    let seam_icon = p
        .edit_surface(a, |d| d.add_icon(point(1.0, 0.7, Role::Position)))
        .unwrap()
        .value;
    drag_frames(&mut p, a, seam_icon, DVec3::new(0.0, 0.0, 0.04), 5, &check);
    let inner = p
        .edit_surface(b, |d| d.add_icon(point(0.5, 1.0, Role::Load)))
        .unwrap()
        .value;
    let m = drag_frames(&mut p, b, inner, DVec3::new(0.0, 0.0, 0.05), 5, &check);
    assert!(m.iter().all(|&x| x > 1e-3), "{m:?}");
    // Only positions are held: the panels still meet at an angle.
    let (_, ang) = seam(&p, a, b);
    assert!(ang > 1e-3, "G0 leaves a crease: {ang}");
}

#[test]
fn joining_is_the_least_energy_change_that_meets_the_edges() {
    for continuity in [Continuity::G0, Continuity::G1] {
        // No icons: the joint shape is the KKT point of the two energies
        // under the join equations alone, written here from the module's
        // definition (E^a = E^b; E − I^a = ρ (I^b − E)).
        let mut p = Product::new();
        let sa = panel(0.0, 8, v_knots(1.0), 0.0, 0.1);
        let sb = panel(1.05, 6, v_knots(2.0), 0.12, -0.2);
        let a = p.add_part(surface_part(sa.clone()));
        let b = p.add_part(surface_part(sb.clone()));
        let (jid, _) = p.join(spec(a, b, continuity)).unwrap();
        let rho = p.join_of(jid).unwrap().ratio;
        let m = SurfaceMaterial::default();
        let ka = dense(&Stiffness::surface(sa.u_knots(), sa.v_knots(), &m).unwrap());
        let kb = dense(&Stiffness::surface(sb.u_knots(), sb.v_knots(), &m).unwrap());
        let (na, nb) = (ka.len(), kb.len());
        let mut k = vec![vec![0.0; na + nb]; na + nb];
        for i in 0..na {
            k[i][..na].copy_from_slice(&ka[i]);
        }
        for i in 0..nb {
            k[na + i][na..].copy_from_slice(&kb[i]);
        }
        let nv = 7;
        let mut rows = Vec::new();
        for j in 0..nv {
            let ea = 7 * nv + j; // A: i = nu − 1 = 7
            let ia = 6 * nv + j;
            let eb = na + j; // B: i = 0
            let ib = na + nv + j;
            rows.push((vec![(ea, 1.0), (eb, -1.0)], 0.0));
            if continuity == Continuity::G1 {
                rows.push((vec![(ea, 1.0), (eb, rho), (ia, -1.0), (ib, -rho)], 0.0));
            }
        }
        let reference: Vec<DVec3> = sa.points().iter().chain(sb.points()).copied().collect();
        let got: Vec<DVec3> = p
            .control_points(a)
            .unwrap()
            .iter()
            .chain(p.control_points(b).unwrap())
            .copied()
            .collect();
        for c in 0..3 {
            let r: Vec<f64> = reference.iter().map(|q| q[c]).collect();
            let want = dense_kkt(&k, &rows, &r);
            for (i, w) in want.iter().enumerate() {
                assert!(
                    (got[i][c] - w).abs() < 1e-8,
                    "{continuity:?} coordinate {c} point {i}: {} vs {w}",
                    got[i][c]
                );
            }
        }
        // The shape moved (the panels did not meet before).
        assert!(moved(sa.points(), p.control_points(a).unwrap()) > 1e-3);
    }
}

#[test]
fn a_reversed_edge_joins_its_mirror_and_holds_the_tangent_plane() {
    let mut p = Product::new();
    let sa = panel(0.0, 8, v_knots(1.0), 0.0, 0.1);
    // B's v runs backwards (y = 1 − t) over [0, 3]; its knots mirrored.
    let k = v_knots(1.0);
    let mirrored: Vec<f64> = k.knots().iter().rev().map(|t| 3.0 * (1.0 - t)).collect();
    let vb = vsculpt_kernel::bspline::KnotVector::new(3, mirrored).unwrap();
    let mut sb = panel(1.02, 6, vb, 0.05, -0.1);
    let nv = 7;
    let pts = sb.points().to_vec();
    for (idx, q) in sb.points_mut().iter_mut().enumerate() {
        let (i, j) = (idx / nv, idx % nv);
        *q = DVec3::new(pts[idx].x, pts[i * nv + (nv - 1 - j)].y, pts[idx].z);
        let _ = q;
    }
    let a = p.add_part(surface_part(sa));
    let b = p.add_part(surface_part(sb));
    let spec_r = JoinSpec {
        reversed: true,
        ..spec(a, b, Continuity::G1)
    };
    p.join(spec_r).unwrap();
    let (sa, sb) = (
        p.surface(a).unwrap().surface(),
        p.surface(b).unwrap().surface(),
    );
    let (gap, ang) = seam_gaps(sa, Edge::UMax, sb, Edge::UMin, true, 50);
    // B's orientation is flipped: its normal is the opposite one.
    let plane = ang.min(std::f64::consts::PI - ang);
    assert!(gap < 1e-9 * model_size(&p), "{gap}");
    assert!(plane < 1e-9, "{plane}");
}

#[test]
fn unjoining_keeps_the_shapes_and_the_parts_move_alone_again() {
    let (mut p, a, b) = pair();
    let (j, _) = p.join(spec(a, b, Continuity::G1)).unwrap();
    let icon = p
        .edit_surface(a, |d| d.add_icon(point(1.0, 0.5, Role::Position)))
        .unwrap()
        .value;
    p.drag(a, icon, DVec3::new(1.0, 0.5, 0.3)).unwrap();
    p.release(a, icon).unwrap();
    let before = all_points(&p);
    let changed = p.unjoin(j).unwrap();
    assert_eq!(changed, ChangedParts::from_ids([a, b]));
    assert_eq!(p.joins().count(), 0);
    // Nothing springs back: a solve of each part alone keeps its shape.
    for id in [a, b] {
        assert_eq!(p.solve(id).unwrap(), ChangedParts::one(id));
        assert!(moved(&before[&id], p.control_points(id).unwrap()) < 1e-9);
    }
    // Now a drag on A leaves B alone.
    let r = p.drag(a, icon, DVec3::new(1.0, 0.5, 0.5)).unwrap();
    assert_eq!(r.changed, ChangedParts::one(a));
    assert_eq!(p.control_points(b).unwrap(), &before[&b][..]);
    assert!(moved(&before[&a], p.control_points(a).unwrap()) > 0.1);
}

#[test]
fn an_edit_of_one_part_keeps_the_partners_running_drag() {
    let (mut p, a, b) = pair();
    p.join(spec(a, b, Continuity::G1)).unwrap();
    let icon = p
        .edit_surface(a, |d| d.add_icon(point(0.9, 0.5, Role::Position)))
        .unwrap()
        .value;
    let to = p.surface(a).unwrap().icon(icon).unwrap().xyz + DVec3::new(0.0, 0.0, 0.2);
    p.drag(a, icon, to).unwrap();
    assert!((p.surface(a).unwrap().icon(icon).unwrap().xyz - to).length() < 1e-9);
    // B is edited mid-drag: the pair is re-solved with A's drag still at `to`.
    let c = p
        .edit_surface(b, |d| d.add_icon(point(0.5, 0.5, Role::Position)))
        .unwrap();
    assert_eq!(c.changed, ChangedParts::from_ids([a, b]));
    let at = p.surface(a).unwrap().icon(icon).unwrap().xyz;
    assert!((at - to).length() < 1e-9, "{at} vs {to}");
    assert_eq!(p.surface(a).unwrap().dragging(), Some(icon));
    // The drag goes on from there, seam held.
    p.drag(a, icon, to + DVec3::Y * 0.05).unwrap();
    let (gap, ang) = seam(&p, a, b);
    assert!(gap < 1e-9 && ang < 1e-9, "{gap} {ang}");
}

#[test]
fn a_part_joined_to_itself_closes_into_a_tube() {
    // A panel's v = min and v = max edges (both along u, 8 points) joined
    // G1: the panel rolls into a closed tube with a smooth seam.
    let mut p = Product::new();
    let a = p.add_part(surface_part(panel(0.0, 8, v_knots(1.0), 0.0, 0.1)));
    let (_, changed) = p
        .join(JoinSpec {
            a,
            edge_a: Edge::VMax,
            b: a,
            edge_b: Edge::VMin,
            reversed: false,
            continuity: Continuity::G1,
            ratio: None,
        })
        .unwrap();
    assert_eq!(changed, ChangedParts::one(a));
    let s = p.surface(a).unwrap().surface();
    let (gap, ang) = seam_gaps(s, Edge::VMax, s, Edge::VMin, false, 50);
    assert!(gap < 1e-9 * model_size(&p) && ang < 1e-9, "{gap} {ang}");
    let icon = p
        .edit_surface(a, |d| d.add_icon(point(0.5, 0.0, Role::Position)))
        .unwrap()
        .value;
    let at = p.surface(a).unwrap().icon(icon).unwrap().xyz;
    for k in 1..=4 {
        p.drag(a, icon, at + DVec3::Z * 0.05 * k as f64).unwrap();
        let s = p.surface(a).unwrap().surface();
        let (gap, ang) = seam_gaps(s, Edge::VMax, s, Edge::VMin, false, 50);
        assert!(
            gap < 1e-9 * model_size(&p) && ang < 1e-9,
            "frame {k}: {gap} {ang}"
        );
    }
}

#[test]
fn a_load_released_by_its_last_sensor_keeps_both_joined_shapes() {
    use vsculpt_kernel::icon::SensorId;
    let (mut p, a, b) = pair();
    p.join(spec(a, b, Continuity::G1)).unwrap();
    let load = p
        .edit_surface(a, |d| d.add_icon(point(0.8, 0.5, Role::Load)))
        .unwrap()
        .value;
    let sensor = SensorId("glove".into());
    p.edit_surface(a, |d| d.bind_sensor(load, sensor.clone()))
        .unwrap();
    let at = p.surface(a).unwrap().icon(load).unwrap().xyz;
    for k in 1..=4 {
        p.drag(a, load, at + DVec3::Z * 0.05 * k as f64).unwrap();
    }
    let dragged = all_points(&p);
    // The last sensor leaves: the load is released (its pull kept as shape).
    let c = p
        .edit_surface(a, |d| d.unbind_sensor(load, &sensor))
        .unwrap();
    assert_eq!(c.changed, ChangedParts::from_ids([a, b]));
    for id in [a, b] {
        let m = moved(&dragged[&id], p.control_points(id).unwrap());
        assert!(m < 1e-9, "{id:?} sprang back by {m:e}");
    }
    let (gap, ang) = seam(&p, a, b);
    assert!(gap < 1e-9 && ang < 1e-9);
    // A closure failing half-way leaves nothing behind.
    let icons = p.surface(a).unwrap().icons().count();
    let shape = p.control_points(a).unwrap().to_vec();
    assert!(
        p.edit_surface(a, |d| {
            d.add_icon(point(0.5, 0.5, Role::Position))?;
            d.add_icon(point(2.0, 0.5, Role::Position))
        })
        .is_err()
    );
    assert_eq!(p.surface(a).unwrap().icons().count(), icons);
    assert_eq!(p.control_points(a).unwrap(), &shape[..]);
}
