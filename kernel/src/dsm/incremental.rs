//! Incremental re-meshing: the mesher's octree of sampled leaves kept between
//! edits, and re-sampled only where an edit can change it.
//!
//! What a leaf holds ([`super::mesh`] steps 2–4: corner membership and Φ, the
//! cell vertices and the crossing edges) is made of samples taken at points
//! within one cell of the leaf, and each sample ([`Model::sample`],
//! [`Model::piece_gradient`]) is a function of the point and of the primitives
//! that *reach* it (those whose ball, grown by the grid's reach margin of two
//! cells, holds it, in model order), D_e, τ, the groups' incorporations, the
//! terms of eq. (7) and each group's Φ scale (its largest reducing factor) —
//! not of the leaf's culled active set. An edit's support is therefore grown
//! by the same margin.
//!
//! The support of an edit, derived from the density functions:
//! * A geometric primitive (eq. 2) contributes ±D_e inside itself and exactly 0
//!   outside: its support is its bounding ball.
//! * A density primitive F = D e^{−a r} never reaches 0, so it can move a vertex
//!   wherever it is evaluated: a contribution δ shifts a surface with
//!   |∇f| ≈ a D_e by δ / (a D_e), and any δ > 0 flips a sample whose field is
//!   within δ of D_e. The only place its contribution is *exactly* 0 — the
//!   only support for which an incremental mesh can equal a fresh one to 1e-12
//!   — is beyond its culling range r_τ = ln(|D| / (τ D_e)) / a (sheets: with
//!   max |D(u, v)|; blobby: the square root), i.e. its influence ball
//!   ([`super::density::DensityPrimitive::influence_ball`]). With the default
//!   τ = 1e-9 that is 20.7 / a beyond the primitive's core; a coarser τ (a model
//!   parameter) shrinks it as ln(1/τ).
//! * Groups do not widen it: eqs. (1)–(7) — fusion within a group,
//!   incorporation of earlier groups' solids (eq. 3), add, subtract and multiply
//!   of terms (eq. 7) — combine the primitives' values *at the same point*, so a
//!   point outside every changed primitive's ball sees the same values and the
//!   same S. Φ (the mesher's signed distance estimate) is pointwise too, except
//!   for each group's scale: when an edit changes a group's largest reducing
//!   factor, every density primitive of that group counts as changed.
//! * Anything structural (D_e, τ, the number of groups, an incorporation, a
//!   term) or a change of grid (the grid spans the model's bounds) re-meshes
//!   everything.
//!
//! An edit's changed primitives are found by comparing the old and new models
//! group by group: the common leading and trailing runs of equal primitives
//! are unchanged (their relative order, and so every sum, is kept); the rest,
//! old and new, is changed. The octree is then walked again from the root, and
//! only a node whose ball meets a changed primitive's old or new ball — the
//! same test [`Model::cull`] uses — is re-culled, re-classified and, at a leaf,
//! re-sampled and re-contoured. Every other node that the previous walk reached
//! keeps its subtree as it was (its active set and classification cannot have
//! changed); a node reached for the first time is walked afresh. The mesh is
//! then assembled from every leaf in Morton order, exactly as a fresh mesh of
//! the same model on the same grid ([`super::mesh_on`], which is this walk
//! from an empty tree): the same vertices, bit for bit, and the same triangles.
//! In a leaf the walk reaches that was meshed before, only the corners inside
//! a changed ball are sampled again and only the cells within one cell of a
//! changed ball contoured again ([`super::mesh`]'s `update_leaf`): samples being
//! pointwise, every other corner and cell vertex is what a fresh leaf computes.

use super::interval::Tri;
use super::mesh::{
    Grid, LEAF, LeafMesh, Mesh, MeshStats, assemble, mesh_leaf, touches, update_leaf,
};
use super::model::{Active, Model};
use glam::{DVec3, IVec3};
use std::collections::{BTreeMap, BTreeSet};

/// A ball (centre, radius) of world space.
pub type Ball = (DVec3, f64);

/// The leaves of one octree walk over a grid, keyed by the Morton code of
/// their leaf coordinates, with the internal nodes the walk expanded.
#[derive(Clone, Debug)]
pub(crate) struct LeafTree {
    grid: Grid,
    size: i32,
    leaves: BTreeMap<u64, LeafMesh>,
    expanded: BTreeSet<(u64, i32)>,
}

/// The Morton code of leaf coordinates (21 bits each).
fn morton(l: IVec3) -> u64 {
    let mut m = 0u64;
    for b in 0..21 {
        for (axis, v) in [l.x, l.y, l.z].into_iter().enumerate() {
            m |= (((v as u64) >> b) & 1) << (3 * b + axis);
        }
    }
    m
}

impl LeafTree {
    /// A fresh walk of `model` over `grid`.
    pub(crate) fn build(model: &Model, grid: &Grid) -> Self {
        let mut size = LEAF;
        while size < grid.dims.max_element() {
            size *= 2;
        }
        let mut tree = Self {
            grid: *grid,
            size,
            leaves: BTreeMap::new(),
            expanded: BTreeSet::new(),
        };
        let mut n = Redone::default();
        tree.visit(
            model,
            IVec3::ZERO,
            size,
            &model.all_active(),
            &[],
            true,
            &mut n,
        );
        tree
    }

    /// The mesh of every leaf.
    pub(crate) fn assemble(&self) -> (Mesh, MeshStats) {
        assemble(&self.grid, self.leaves.values())
    }

    /// Re-walks the tree for `model`, which differs from the model of the
    /// previous walk only inside `changed`; returns the leaves reached and the
    /// cells contoured again.
    fn update(&mut self, model: &Model, changed: &[Ball]) -> Redone {
        let mut n = Redone::default();
        let act = model.all_active();
        self.visit(model, IVec3::ZERO, self.size, &act, changed, false, &mut n);
        n
    }

    /// Forgets everything under node (key, s) (the node included).
    fn remove_subtree(&mut self, key: u64, s: i32) {
        let n = ((s / LEAF) as u64).pow(3);
        let leaves: Vec<u64> = self.leaves.range(key..key + n).map(|(k, _)| *k).collect();
        for k in leaves {
            self.leaves.remove(&k);
        }
        let nodes: Vec<(u64, i32)> = self
            .expanded
            .range((key, 0)..(key + n, 0))
            .copied()
            .collect();
        for k in nodes {
            self.expanded.remove(&k);
        }
    }

    /// Walks node (o, s) whose parent's active set is `parent`. `fresh`: the
    /// previous walk never reached this node (nothing is kept under it).
    #[allow(clippy::too_many_arguments)]
    fn visit(
        &mut self,
        model: &Model,
        o: IVec3,
        s: i32,
        parent: &Active,
        changed: &[Ball],
        fresh: bool,
        redone: &mut Redone,
    ) {
        let grid = self.grid;
        if o.cmpge(grid.dims).any() {
            return;
        }
        let c = grid.origin + (o.as_dvec3() + DVec3::splat(s as f64 * 0.5)) * grid.h;
        let r = s as f64 * grid.h * 0.5 * 3f64.sqrt();
        // A leaf samples up to one cell beyond itself (a border cell's
        // projection), so an edit within (½√3 + 1) cells of a cell reaches it:
        // a node is walked again if the edit comes within two cells of its ball.
        if !fresh && !touches(changed, c, r + 2.0 * grid.h) {
            return;
        }
        let key = morton(o / LEAF);
        let was_expanded = !fresh && self.expanded.contains(&(key, s));
        let act = model.cull(parent, c, r);
        if model.classify(c, r, &act) != Tri::Maybe {
            if !fresh {
                self.remove_subtree(key, s);
            }
            return;
        }
        if s > LEAF {
            self.expanded.insert((key, s));
            let hs = s / 2;
            for k in 0..8 {
                let d = IVec3::new(k & 1, (k >> 1) & 1, (k >> 2) & 1) * hs;
                self.visit(
                    model,
                    o + d,
                    hs,
                    &act,
                    changed,
                    fresh || !was_expanded,
                    redone,
                );
            }
            return;
        }
        redone.leaves += 1;
        let leaf = match self.leaves.get(&key) {
            Some(old) if !fresh => {
                let (leaf, cells) = update_leaf(model, &grid, old, changed);
                redone.cells += cells;
                leaf
            }
            _ => {
                redone.fresh += 1;
                mesh_leaf(model, &grid, o)
            }
        };
        self.leaves.insert(key, leaf);
    }
}

/// What one re-walk did.
#[derive(Clone, Copy, Debug, Default)]
struct Redone {
    /// Leaves reached (sampled afresh or in part).
    leaves: usize,
    /// Of those, leaves sampled afresh (new to the tree).
    fresh: usize,
    /// Mixed cells contoured again in the leaves updated in part.
    cells: usize,
}

/// What one [`IncrementalMesh::update`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UpdateStats {
    /// Everything was re-meshed (a structural change or a new grid).
    pub full: bool,
    /// Primitives found changed (old and new counted apart).
    pub changed: usize,
    /// Leaves reached by the edit: sampled afresh, or, when the leaf was
    /// meshed before, sampled again only within the edit's reach.
    pub recomputed: usize,
    /// Of those, leaves new to the tree (sampled and contoured whole).
    pub fresh_leaves: usize,
    /// Mixed cells contoured again in the leaves updated in part.
    pub cells: usize,
    /// Leaves in the tree after the update.
    pub leaves: usize,
}

/// A model's mesh on a grid with everything the mesher sampled, re-meshed
/// incrementally as the model is edited (see the module doc).
#[derive(Clone, Debug)]
pub struct IncrementalMesh {
    model: Model,
    tree: LeafTree,
}

/// The balls outside which `new` classifies exactly as `old` and, grown by
/// a sample's reach margin, samples exactly as `old` (see the module doc), or
/// None when everything may differ.
pub fn edit_support(old: &Model, new: &Model) -> Option<Vec<Ball>> {
    if old.de() != new.de()
        || old.tau() != new.tau()
        || old.terms() != new.terms()
        || old.groups().len() != new.groups().len()
    {
        return None;
    }
    let mut balls = Vec::new();
    for (k, (go, gn)) in old.groups().iter().zip(new.groups()).enumerate() {
        if go.incorporated != gn.incorporated {
            return None;
        }
        let (ro, rn) = unmatched(&go.geometric, &gn.geometric);
        balls.extend(go.geometric[ro].iter().map(|g| g.bounds()));
        balls.extend(gn.geometric[rn].iter().map(|g| g.bounds()));
        let (ro, rn) = if old.scale(k) == new.scale(k) {
            unmatched(&go.density, &gn.density)
        } else {
            (0..go.density.len(), 0..gn.density.len())
        };
        balls.extend(ro.map(|i| go.density[i].influence_ball(old.range(k, i))));
        balls.extend(rn.map(|i| gn.density[i].influence_ball(new.range(k, i))));
    }
    Some(balls)
}

/// The ranges of `a` and `b` outside their common leading and trailing runs.
fn unmatched<T: PartialEq>(a: &[T], b: &[T]) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let lead = a.iter().zip(b).take_while(|(x, y)| x == y).count();
    let room = a.len().min(b.len()) - lead;
    let trail = a
        .iter()
        .rev()
        .zip(b.iter().rev())
        .take(room)
        .take_while(|(x, y)| x == y)
        .count();
    (lead..a.len() - trail, lead..b.len() - trail)
}

impl IncrementalMesh {
    /// Samples and contours `model` on `grid` from scratch.
    pub fn new(model: Model, grid: Grid) -> Self {
        let tree = LeafTree::build(&model, &grid);
        Self { model, tree }
    }

    /// The model meshed.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The grid.
    pub fn grid(&self) -> &Grid {
        &self.tree.grid
    }

    /// Re-meshes for `model` on `grid`: only the leaves within the edit's
    /// support when the grid and the model's structure are unchanged,
    /// everything otherwise. The result equals [`super::mesh_on`]`(model, grid)`.
    pub fn update(&mut self, model: Model, grid: Grid) -> UpdateStats {
        // The mesher's samples reach the grid's margin beyond a primitive's
        // ball (`Grid::reach_margin`): so does an edit's support.
        let support = if grid == self.tree.grid {
            edit_support(&self.model, &model).map(|balls| {
                let m = grid.reach_margin();
                balls
                    .into_iter()
                    .map(|(c, r)| (c, r + m))
                    .collect::<Vec<Ball>>()
            })
        } else {
            None
        };
        let stats = match support {
            Some(balls) => {
                let redone = self.tree.update(&model, &balls);
                UpdateStats {
                    full: false,
                    changed: balls.len(),
                    recomputed: redone.leaves,
                    fresh_leaves: redone.fresh,
                    cells: redone.cells,
                    leaves: self.tree.leaves.len(),
                }
            }
            None => {
                self.tree = LeafTree::build(&model, &grid);
                UpdateStats {
                    full: true,
                    changed: 0,
                    recomputed: self.tree.leaves.len(),
                    fresh_leaves: self.tree.leaves.len(),
                    cells: 0,
                    leaves: self.tree.leaves.len(),
                }
            }
        };
        self.model = model;
        stats
    }

    /// The mesh (assembled from every leaf) and its counters.
    pub fn mesh(&self) -> (Mesh, MeshStats) {
        self.tree.assemble()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_codes_of_a_block_are_contiguous() {
        // The 8 children of a node of 4³ leaves at (4, 0, 4) fill [m, m + 64).
        let base = morton(IVec3::new(4, 0, 4));
        let mut codes: Vec<u64> = (0..64)
            .map(|i| morton(IVec3::new(4 + (i & 3), (i >> 2) & 3, 4 + (i >> 4))))
            .collect();
        codes.sort_unstable();
        assert_eq!(codes, (base..base + 64).collect::<Vec<_>>());
    }

    #[test]
    fn unmatched_runs_are_what_an_edit_touched() {
        assert_eq!(unmatched(&[1, 2, 3], &[1, 9, 3]), (1..2, 1..2));
        assert_eq!(unmatched(&[1, 2, 3], &[1, 3]), (1..2, 1..1));
        assert_eq!(unmatched(&[1, 2], &[1, 2, 3]), (2..2, 2..3));
        assert_eq!(unmatched(&[1, 1], &[1]), (1..2, 1..1));
        assert_eq!(unmatched::<i32>(&[], &[]), (0..0, 0..0));
    }
}
