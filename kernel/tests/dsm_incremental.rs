//! Incremental re-meshing of a DSM model (`IncrementalMesh`) against a mesh of
//! the same model from scratch (`mesh_on`, same grid): after every edit of a
//! random sequence — moves, resizes, density and reducing-factor changes,
//! primitives added and removed, in groups that add, subtract and incorporate
//! — the two meshes have the same triangles and the same vertices to 1e-12.
//! The edits change the surface (checked), so a re-meshed region smaller than
//! an edit's support leaves stale leaves and fails the comparison.

mod dsm_support;

use dsm_support::{Item, Rng, Spec, ball, boxed, charge, handset};
use glam::DVec3;
use vsculpt_kernel::dsm::*;

/// Asserts a and b have the same triangles and vertices (and normals) to 1e-12.
fn assert_same(a: &Mesh, b: &Mesh, what: &str) {
    assert_eq!(a.positions.len(), b.positions.len(), "{what}: vertex count");
    assert_eq!(a.triangles, b.triangles, "{what}: triangles");
    for (i, (p, q)) in a.positions.iter().zip(&b.positions).enumerate() {
        assert!(
            (*p - *q).abs().max_element() <= 1e-12,
            "{what}: vertex {i}: {p} vs {q}"
        );
    }
    for (i, (p, q)) in a.normals.iter().zip(&b.normals).enumerate() {
        assert!(
            (*p - *q).abs().max_element() <= 1e-12,
            "{what}: normal {i}: {p} vs {q}"
        );
    }
}

/// One random edit of `spec`; its name.
fn random_edit(spec: &mut Spec, rng: &mut Rng) -> String {
    let n = spec.len();
    let kind = rng.below(10);
    // Never the body box (primitive 0): the grid spans it.
    let pick = 1 + rng.below(n - 1);
    let (k, i) = spec.locate(pick);
    match kind {
        0..=3 => {
            let d = rng.vec(0.08);
            spec.translate(pick, d);
            format!("move {k}/{i} by {d}")
        }
        4 | 5 => {
            let f = rng.range(0.75, 1.3);
            match &mut spec.groups[k].items[i] {
                Item::Geo(p) => {
                    p.shape = match p.shape {
                        GeometricShape::Box { half } => GeometricShape::Box { half: half * f },
                        GeometricShape::Cylinder {
                            radius,
                            half_height,
                        } => GeometricShape::Cylinder {
                            radius: radius * f,
                            half_height,
                        },
                        GeometricShape::Sphere { radius } => {
                            GeometricShape::Sphere { radius: radius * f }
                        }
                        s => s,
                    };
                    format!("resize {k}/{i} by {f}")
                }
                Item::Den(p) => {
                    p.density *= f;
                    format!("density {k}/{i} × {f}")
                }
            }
        }
        6 => match &mut spec.groups[k].items[i] {
            Item::Den(p) => {
                let f = rng.range(0.85, 1.2);
                p.reducing *= f;
                format!("reducing {k}/{i} × {f}")
            }
            Item::Geo(p) => {
                p.negative = !p.negative;
                format!("negate {k}/{i}")
            }
        },
        7 | 8 => {
            let at = DVec3::new(
                rng.range(-1.3, 1.3),
                rng.range(-0.7, 0.7),
                rng.range(-0.3, 0.3),
            );
            let it = match rng.below(4) {
                0 => ball(at, rng.range(0.05, 0.2), rng.next() < 0.5),
                1 => boxed(at, DVec3::splat(rng.range(0.04, 0.15)), rng.next() < 0.5),
                _ => charge(at, rng.range(0.3, 1.2), rng.range(4.0, 8.0)),
            };
            let g = rng.below(spec.groups.len());
            let j = rng.below(spec.groups[g].items.len() + 1);
            spec.groups[g].items.insert(j, it);
            format!("add to group {g} at {j}")
        }
        _ => {
            if spec.groups[k].items.len() > 1 {
                spec.groups[k].items.remove(i);
                format!("remove {k}/{i}")
            } else {
                spec.translate(pick, DVec3::new(0.03, 0.0, 0.0));
                format!("move {k}/{i} (last of its group)")
            }
        }
    }
}

fn random_sequence(seed: u64, cells: usize, edits: usize) {
    let mut rng = Rng(seed);
    let mut spec = handset();
    let model = spec.model();
    let grid = Grid::for_model(&model, cells).unwrap();
    let mut inc = IncrementalMesh::new(model, grid);
    let (mut last, _) = inc.mesh();
    let (mut incremental, mut changed, mut reused, mut partial) = (0, 0, 0, 0);
    for e in 0..edits {
        let what = random_edit(&mut spec, &mut rng);
        let model = spec.model();
        let grid = Grid::for_model(&model, cells).unwrap();
        let st = inc.update(model.clone(), grid);
        let (got, _) = inc.mesh();
        let (want, _) = mesh_on(&model, &grid);
        assert_same(
            &got,
            &want,
            &format!("seed {seed}, edit {e} ({what}), {st:?}"),
        );
        if !st.full {
            incremental += 1;
            reused += st.leaves - st.recomputed.min(st.leaves);
            // Leaves met by the edit but meshed before: updated in part.
            if st.recomputed > st.fresh_leaves && st.cells < 512 * st.recomputed {
                partial += 1;
            }
        }
        if got != last {
            changed += 1;
        }
        last = got;
    }
    // The sequence exercised the incremental path, and its edits showed.
    assert!(
        incremental * 2 >= edits,
        "{incremental} of {edits} incremental"
    );
    assert!(reused > 0, "no leaf was ever reused");
    assert!(partial > 0, "no leaf was ever updated in part");
    assert!(
        changed * 2 >= edits,
        "only {changed} of {edits} edits changed the mesh"
    );
}

#[test]
fn random_edit_sequences_mesh_as_from_scratch() {
    for seed in [0x9e37_79b9_7f4a_7c15, 0x2545_f491_4f6c_dd1d, 7] {
        random_sequence(seed, 24, 30);
    }
}

#[test]
fn a_random_sequence_at_a_finer_grid_meshes_as_from_scratch() {
    random_sequence(0xdead_beef_cafe_f00d, 48, 12);
}

#[test]
fn a_small_step_of_a_button_re_meshes_only_near_it() {
    let mut spec = handset();
    let model = spec.model();
    let grid = Grid::for_model(&model, 40).unwrap();
    let mut inc = IncrementalMesh::new(model, grid);
    // Primitive 4: the first side button, 0.24 × 0.08 × 0.12.
    spec.translate(4, DVec3::new(0.02, 0.0, 0.0));
    let model = spec.model();
    assert_eq!(Grid::for_model(&model, 40).unwrap(), grid);
    let st = inc.update(model.clone(), grid);
    assert!(!st.full);
    assert_eq!(st.changed, 2, "the button's old and new balls");
    // Its bounding ball (radius 0.15) meets a few of the leaves (8 cells of 0.11).
    assert!(
        st.recomputed >= 1 && st.recomputed * 4 <= st.leaves,
        "{st:?}"
    );
    assert_same(&inc.mesh().0, &mesh_on(&model, &grid).0, "button step");
}

#[test]
fn the_support_of_an_edit_is_the_changed_primitives_balls() {
    let spec = handset();
    let old = spec.model();
    // Nothing changed: nothing to re-mesh.
    assert_eq!(edit_support(&old, &spec.model()), Some(vec![]));
    // A geometric move: its old and new bounding balls.
    let mut moved = spec.clone();
    moved.translate(12, DVec3::new(0.0, 0.1, 0.0));
    let Item::Geo(g0) = &spec.groups[0].items[12] else {
        panic!()
    };
    let Item::Geo(g1) = &moved.groups[0].items[12] else {
        panic!()
    };
    assert_eq!(
        edit_support(&old, &moved.model()),
        Some(vec![g0.bounds(), g1.bounds()])
    );
    // A density change: the primitive's influence ball, old range and new.
    let mut denser = spec.clone();
    let Item::Den(d) = &mut denser.groups[0].items[3] else {
        panic!()
    };
    d.density *= 2.0;
    let new = denser.model();
    let balls = edit_support(&old, &new).unwrap();
    assert_eq!(balls.len(), 2);
    assert!(balls[1].1 > balls[0].1);
    // r_τ = ln(D / (τ D_e)) / a beyond the centre.
    assert!((balls[1].1 - (1.8f64 / DEFAULT_TAU).ln() / 4.0).abs() < 1e-12);
    // Raising a group's largest reducing factor changes Φ's scale: the whole group.
    let mut sharper = spec.clone();
    let Item::Den(d) = &mut sharper.groups[0].items[3] else {
        panic!()
    };
    d.reducing = 9.0;
    assert_eq!(edit_support(&old, &sharper.model()).unwrap().len(), 2 * 4);
    // Structure: a term or an incorporation changed re-meshes everything.
    let mut s = spec.clone();
    s.groups[1].sign = Some(Sign::Add);
    assert_eq!(edit_support(&old, &s.model()), None);
    let mut s = spec.clone();
    s.groups[3].incorporated.clear();
    assert_eq!(edit_support(&old, &s.model()), None);
}

#[test]
fn a_new_grid_or_structure_re_meshes_everything() {
    let spec = handset();
    let model = spec.model();
    let grid = Grid::for_model(&model, 24).unwrap();
    let mut inc = IncrementalMesh::new(model.clone(), grid);
    let finer = Grid::for_model(&model, 32).unwrap();
    let st = inc.update(model.clone(), finer);
    assert!(st.full);
    assert_same(&inc.mesh().0, &mesh_on(&model, &finer).0, "finer grid");
    let mut s = spec.clone();
    s.groups[2].sign = Some(Sign::Add);
    let m2 = s.model();
    let st = inc.update(m2.clone(), finer);
    assert!(st.full);
    assert_same(
        &inc.mesh().0,
        &mesh_on(&m2, &finer).0,
        "grip added as a term",
    );
}
