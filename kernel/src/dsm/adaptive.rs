//! Adaptive meshing of S: dual contouring on an octree whose leaves are as
//! coarse as a stated tolerance allows (Ju, Losasso, Schaefer & Warren,
//! "Dual contouring of Hermite data", 2002, with the leaves chosen top-down).
//!
//! The finest leaf is one cell of the uniform mesher's grid ([`Grid::for_model`]
//! at `cells`); a leaf is at most `max_leaf` cells. Top-down, from a
//! power-of-two cube over the grid:
//! 1. A node's active set is culled to the primitives that may be non-zero
//!    within reach of its samples (ball test, then each density primitive's
//!    interval bound: one bounded by exactly 0 there is dropped). A node whose
//!    ball interval bounds prove wholly inside or outside S
//!    ([`Model::classify`]) is a leaf without surface; a node larger than
//!    `max_leaf` is split.
//! 2. Any other node of s ≥ 2 cells is sampled on its *check lattice* of
//!    spacing q = s/2 cells (its 3³ grid corners: membership and Φ) and kept
//!    as one leaf only if all of these hold, else it is split:
//!    * every lattice line (along x, y or z) changes membership at most once,
//!      so each of the node's edges and faces is crossed at most as its corners
//!      say: a face whose 4 corners agree holds no lattice crossing, and the
//!      node's 8 corners are not all alike while the lattice has a crossing
//!      (the coarse cell's sign pattern holds the fine topology, as in Ju et
//!      al.'s topology-safe simplification);
//!    * the inside and the outside corners of the node are each connected along
//!      its edges (a pattern one vertex represents as a manifold);
//!    * the QEF of the Hermite samples of every crossing lattice edge (rooted
//!      to 1e-3 cell) has rank 1 (a smooth sheet; sharp edges and corners are
//!      left to finer leaves);
//!    * its vertex — the QEF minimiser (the mass point if that leaves the node)
//!      projected onto the level set along the mean normal — and the exact
//!      unit normal n there fit the samples: every crossing p_i lies within
//!      tol / 2 of the vertex's tangent plane, every sample normal within 30°
//!      of n, and every lattice corner farther than tol from that plane is on
//!      the side the plane gives it (inside below, outside above).
//!
//!    A node whose lattice has no crossing at all is a leaf without surface.
//!    A one-cell node is always a leaf, meshed as the uniform mesher meshes a
//!    cell (QEF vertex, sharp features kept, projected when smooth).
//!    A node whose parent failed the tangent-plane test by a factor k is
//!    predicted to fail it by k / 4 (a smooth sheet's deviation from a tangent
//!    plane grows as the square of the size): it is split without sampling
//!    while the prediction exceeds 2.
//! 3. Quads: Ju et al.'s cell / face / edge procedures walk every edge shared by
//!    four leaves; the *minimal* edge (the smallest leaf's) gives a quad of the
//!    four leaves' vertices when its ends differ in membership, oriented
//!    outwards and split along its shorter diagonal as in [`super::mesh`].
//!    Signs live on grid corners and a sample is a function of the point
//!    alone, so every leaf sees the same sign at a shared corner: the quads
//!    are the dual of the boundary between inside and outside minimal edges,
//!    closed across leaves of any sizes (no crack, no balancing needed).
//!    A leaf a quad names without a vertex of its own (its lattice saw no
//!    crossing where a smaller neighbour's edge did) gets one from the
//!    Hermite samples of those edges.
//!
//! Tolerance. Every vertex is on the level set (projected, or a QEF feature
//! point of a one-cell leaf as in the uniform mesher); within a coarse leaf the
//! sampled surface is within tol / 2 of the vertex's tangent plane, so a
//! triangle joining neighbouring vertices stays within about tol of the
//! surface: `tests/dsm_adaptive.rs` measures it by Newton projection of
//! points inside every triangle (at tol ¼ cell, at most 0.19 cell on the
//! rounded box and 0.12 on the blobby shape from 64 to 256 cells; with the
//! test at tol itself instead of tol / 2 it reached 1.8 tol).
//!
//! Samples: every corner and Hermite sample is taken once per run (a sparse
//! corner grid, [`super::corner_cache`], and a hash map of edges), and a
//! corner's membership is a function of the point alone ([`Model::sample`]
//! with any active set that holds the primitives reaching it), so leaves of
//! different sizes agree on it. The caches are kept per thread between runs.
//! With `max_leaf` = 1 every leaf is a cell and the quads are exactly the
//! uniform mesher's (tested).
//!
//! Known limits, stated: the checks see the surface at the check lattice's
//! spacing q only — a feature that crosses no lattice edge of a coarse leaf
//! (thinner than q ≤ `max_leaf` / 2 cells, e.g. 8 cells of a 256-cell grid
//! at the default `max_leaf` of 16) is not meshed, where the uniform mesher
//! sees features down to one cell; and the interval bounds prove only
//! empty and full nodes, not the absence of such thin features in a node
//! that holds a sheet. One vertex per leaf, so a one-cell leaf cut by two
//! sheets is non-manifold as in the uniform mesher. Not incremental: an edit
//! re-meshes everything (the uniform mesher's [`super::IncrementalMesh`] is
//! what the server uses for drags).

use super::corner_cache::CornerCache;
use super::error::DsmError;
use super::interval::Tri;
use super::mesh::{Field, Grid, Mesh, cell_vertex, hermite, project, root};
use super::model::{Active, Model, Sample};
use super::qef::Qef;
use glam::{DVec3, IVec3};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// What to mesh adaptively: the finest cell, the tolerance and the largest leaf.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveOptions {
    /// Finest cells along the longest side of the model's bounds (4 ..= 4096),
    /// as [`super::MeshOptions::cells`].
    pub cells: usize,
    /// The largest distance of the surface from a coarse leaf's vertex plane,
    /// in finest cells (> 0): the mesh stays within about this of S.
    pub tolerance: f64,
    /// The largest leaf, in finest cells (a power of two, 1 ..= 64; 1 gives
    /// the uniform grid's cells).
    pub max_leaf: usize,
}

impl AdaptiveOptions {
    /// `cells` with a tolerance of ¼ cell and leaves of up to 16 cells.
    pub fn new(cells: usize) -> Self {
        Self {
            cells,
            tolerance: 0.25,
            max_leaf: 16,
        }
    }
}

/// Counters of one adaptive meshing run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AdaptiveStats {
    /// Leaves of the octree.
    pub leaves: usize,
    /// Leaves larger than one cell that hold a sheet.
    pub coarse_surface_leaves: usize,
    /// One-cell leaves with a crossing.
    pub fine_surface_leaves: usize,
    /// Largest leaf holding a sheet, in cells.
    pub largest_surface_leaf: usize,
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Φ samples at grid corners (each corner once).
    pub corner_samples: usize,
    /// Hermite samples (each edge once).
    pub hermite_samples: usize,
}

/// Meshes S adaptively ([`self`]).
pub fn mesh_adaptive(
    model: &Model,
    opts: AdaptiveOptions,
) -> Result<(Mesh, AdaptiveStats), DsmError> {
    if !(opts.tolerance > 0.0 && opts.tolerance.is_finite()) {
        return Err(DsmError::BadMeshRequest("tolerance must be positive"));
    }
    if !(1..=64).contains(&opts.max_leaf) || !opts.max_leaf.is_power_of_two() {
        return Err(DsmError::BadMeshRequest(
            "max_leaf must be a power of two in 1..=64",
        ));
    }
    let grid = Grid::for_model(model, opts.cells)?;
    Ok(mesh_adaptive_on(
        model,
        &grid,
        opts.tolerance,
        opts.max_leaf as i32,
    ))
}

/// Meshes S adaptively on a given grid (its cells are the finest leaves);
/// `tolerance` in cells, `max_leaf` a power of two.
pub fn mesh_adaptive_on(
    model: &Model,
    grid: &Grid,
    tolerance: f64,
    max_leaf: i32,
) -> (Mesh, AdaptiveStats) {
    let mut size = 1;
    while size < grid.dims.max_element() {
        size *= 2;
    }
    let mut store = STORE.with(|s| std::mem::take(&mut *s.borrow_mut()));
    let mut samples = store
        .samples
        .take()
        .unwrap_or_else(|| CornerCache::new(IVec3::ZERO));
    samples.reset(IVec3::splat(size));
    store.edges.clear();
    store.nodes.clear();
    store.leaves.clear();
    let mut b = Builder {
        model,
        grid: *grid,
        margin: grid.reach_margin(),
        tol: tolerance * grid.h,
        max_leaf,
        nodes: store.nodes,
        leaves: store.leaves,
        samples,
        edges: store.edges,
        positions: Vec::new(),
        normals: Vec::new(),
        scratch: Vec::new(),
        stats: AdaptiveStats::default(),
    };
    let all = model.all_active();
    let root = b.build(IVec3::ZERO, size, &all, 0.0);
    let mut quads = Vec::new();
    b.cell_proc(root, &mut quads);
    let (mesh, stats, store) = b.finish(quads, &all);
    STORE.with(|s| *s.borrow_mut() = store);
    (mesh, stats)
}

/// The sample caches and the octree of one thread's runs, kept between
/// them (their memory stays mapped: a re-mesh at interactive rates takes no
/// page faults).
#[derive(Default)]
struct Store {
    samples: Option<CornerCache>,
    edges: HashMap<u64, (DVec3, DVec3), Fast>,
    nodes: Vec<Node>,
    leaves: Vec<Leaf>,
}

thread_local! {
    static STORE: std::cell::RefCell<Store> = std::cell::RefCell::new(Store::default());
}

/// A hash for the integer keys of the Hermite cache: the keys are mixed
/// with splitmix64's finaliser, so the low bits a hash table indexes by
/// depend on every bit of the key.
#[derive(Default)]
struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &x in bytes {
            self.write_u64(x as u64);
        }
    }

    fn write_u64(&mut self, n: u64) {
        let mut z = (self.0 ^ n).wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        self.0 = z ^ (z >> 31);
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

type Fast = BuildHasherDefault<KeyHasher>;

/// A grid corner (non-negative, below 2¹³: grids of up to 4096 cells and
/// their margins) as one integer below 2³⁹.
fn key(c: IVec3) -> u64 {
    (c.x as u64) | ((c.y as u64) << 13) | ((c.z as u64) << 26)
}

/// A node of the octree: children (x fastest) or a leaf.
enum Node {
    Inner([u32; 8]),
    Leaf(u32),
}

/// An octree leaf: its cube, the membership of its 8 corners (bit
/// x + 2y + 4z) and its vertex (index into the builder's vertices).
struct Leaf {
    origin: IVec3,
    size: i32,
    corners: u8,
    vertex: u32,
    /// Hermite samples of the minimal edges naming a leaf without a vertex.
    fallback: Qef,
}

const NONE: u32 = u32::MAX;

/// The four cells around an edge along axis d, in the order of
/// [`super::mesh`]'s quads: (low, low), (high, low), (high, high), (low, high)
/// on the axes (d + 1) % 3 and (d + 2) % 3.
const RING: [(i32, i32); 4] = [(0, 0), (1, 0), (1, 1), (0, 1)];

/// cos 30°: the widest angle between a coarse leaf's sample normals and its
/// vertex normal.
const COS_MAX: f64 = 0.866_025_403_784_438_6;

struct Builder<'a> {
    model: &'a Model,
    grid: Grid,
    margin: f64,
    tol: f64,
    max_leaf: i32,
    nodes: Vec<Node>,
    leaves: Vec<Leaf>,
    samples: CornerCache,
    edges: HashMap<u64, (DVec3, DVec3), Fast>,
    positions: Vec<DVec3>,
    normals: Vec<DVec3>,
    scratch: Vec<bool>,
    stats: AdaptiveStats,
}

/// Corner bit index of local corner offsets (0 or 1 each).
fn bit(x: i32, y: i32, z: i32) -> u32 {
    (x | (y << 1) | (z << 2)) as u32
}

/// Whether the corners in `set` (bits of a cube's 8 corners) are connected
/// along the cube's edges (true for an empty set).
fn connected(set: u8) -> bool {
    if set == 0 {
        return true;
    }
    let start = set.trailing_zeros();
    let mut seen = 1u8 << start;
    let mut stack = vec![start];
    while let Some(c) = stack.pop() {
        for a in 0..3 {
            let n = c ^ (1 << a);
            if set & (1 << n) != 0 && seen & (1 << n) == 0 {
                seen |= 1 << n;
                stack.push(n);
            }
        }
    }
    seen == set
}

impl Builder<'_> {
    fn sample(&mut self, c: IVec3, act: &Active) -> Sample {
        if let Some(s) = self.samples.get(c) {
            return s;
        }
        let s = self
            .model
            .sample(self.grid.corner(c), act, self.margin, &mut self.scratch);
        self.samples.set(c, s);
        s
    }

    /// The Hermite sample of the edge of `len` cells from corner `a` along
    /// `axis` (its ends differ in membership), once per edge and precision.
    /// `exact` (a one-cell leaf's edges, whose crossings place feature
    /// vertices, and the minimal edges of leaves without a vertex): rooted to
    /// 1e-10 of the edge as in the uniform mesher; else (a check lattice
    /// edge: its crossing only tests the tolerance, and seeds a vertex that
    /// is then projected onto the level set) to 1e-3 of a cell.
    fn edge(
        &mut self,
        a: IVec3,
        axis: usize,
        len: i32,
        exact: bool,
        act: &Active,
    ) -> (DVec3, DVec3) {
        let k = key(a)
            | (axis as u64) << 39
            | (len.trailing_zeros() as u64) << 41
            | (exact as u64) << 45;
        if let Some(h) = self.edges.get(&k) {
            return *h;
        }
        let e = IVec3::AXES[axis] * len;
        let (s0, s1) = (self.sample(a, act), self.sample(a + e, act));
        let field = Field {
            model: self.model,
            act,
            margin: self.margin,
        };
        let h = if exact {
            hermite(&field, &self.grid, a, e, s0.phi, s1.phi, s0.inside)
        } else {
            let p0 = self.grid.corner(a);
            let d = e.as_dvec3() * self.grid.h;
            let p = p0 + d * self.lattice_root(&field, p0, d, (s0, s1));
            let g = field.normal(p);
            let out = if s0.inside { d } else { -d };
            let n = if g.dot(out) < 0.0 { -g } else { g };
            (p, if n == DVec3::ZERO { out.normalize() } else { n })
        };
        self.edges.insert(k, h);
        h
    }

    /// The crossing on a check lattice edge p0 + t d, t ∈ [0, 1], whose ends
    /// `ends` differ in membership, to 1e-3 of a cell: secant steps on Φ (a
    /// distance estimate, so a step whose |Φ| is below 1e-3 cell is on the
    /// boundary to that), the bracket kept by membership; after two steps the
    /// Illinois search of the uniform mesher ([`root`]) on what is left.
    fn lattice_root(&mut self, field: &Field, p0: DVec3, d: DVec3, ends: (Sample, Sample)) -> f64 {
        let eps = 1e-3 * self.grid.h;
        let ina = ends.0.inside;
        let (mut a, mut b) = (0.0, 1.0);
        let (mut fa, mut fb) = (ends.0.phi, ends.1.phi);
        for _ in 0..2 {
            let mut t = if fa != fb {
                (a * fb - b * fa) / (fb - fa)
            } else {
                0.5 * (a + b)
            };
            if !(t > a && t < b) {
                t = 0.5 * (a + b);
            }
            let s = field.sample(p0 + d * t, &mut self.scratch);
            if s.phi.abs() <= eps {
                return t;
            }
            if s.inside == ina {
                (a, fa) = (t, s.phi);
            } else {
                (b, fb) = (t, s.phi);
            }
        }
        let cells = d.length() / self.grid.h * (b - a);
        let t = root(field, p0 + d * a, d * (b - a), (fa, fb), ina, 1e-3 / cells);
        a + (b - a) * t
    }

    fn push_leaf(&mut self, origin: IVec3, size: i32, corners: u8, vertex: u32) -> u32 {
        self.leaves.push(Leaf {
            origin,
            size,
            corners,
            vertex,
            fallback: Qef::default(),
        });
        self.nodes.push(Node::Leaf(self.leaves.len() as u32 - 1));
        self.nodes.len() as u32 - 1
    }

    fn push_vertex(&mut self, p: DVec3, n: DVec3) -> u32 {
        self.positions.push(p);
        self.normals.push(n);
        self.positions.len() as u32 - 1
    }

    /// Step 1 and 2 for node (o, s) whose parent's active set is `parent`;
    /// `predicted`: the deviation from its vertex plane that the parent's
    /// samples predict for this node, relative to the tolerance (a node whose
    /// prediction exceeds 2 is split without sampling its check lattice).
    fn build(&mut self, o: IVec3, s: i32, parent: &Active, predicted: f64) -> u32 {
        let grid = self.grid;
        if o.cmpge(grid.dims + IVec3::ONE).any() {
            return self.push_leaf(o, s, 0, NONE);
        }
        let r = s as f64 * grid.h * 0.5 * 3f64.sqrt();
        let c = grid.corner(o) + DVec3::splat(0.5 * s as f64 * grid.h);
        // Samples at the node's corners and edges, projections of its vertex
        // (within a lattice step), each with the reach margin.
        let reach = r + s as f64 * grid.h + self.margin;
        let mut act = self.model.cull(parent, c, reach);
        // A density primitive whose interval bound over the reach is exactly
        // 0 (beyond its range, or on the clipped side of a sector shell)
        // changes no membership there; dropping it saves its evaluation in
        // every sample (Φ may lose a cut piece of it, which only steers the
        // root finding).
        for (k, list) in act.density.iter_mut().enumerate() {
            let g = &self.model.groups()[k];
            list.retain(|&i| {
                let b = g.density[i as usize].bound(c, reach, self.model.range(k, i as usize));
                b.lo != 0.0 || b.hi != 0.0
            });
        }
        match self.model.classify(c, r, &act) {
            Tri::Yes => return self.push_leaf(o, s, 255, NONE),
            Tri::No => return self.push_leaf(o, s, 0, NONE),
            Tri::Maybe => {}
        }
        if s == 1 {
            return self.cell_leaf(o, &act);
        }
        // A smooth sheet's deviation from a tangent plane falls as the square
        // of the leaf's size.
        let next = if s <= self.max_leaf && predicted <= 2.0 {
            match self.coarse_leaf(o, s, &act) {
                Ok(n) => return n,
                Err(dev) => 0.25 * dev,
            }
        } else {
            0.25 * predicted
        };
        let id = self.nodes.len();
        self.nodes.push(Node::Inner([NONE; 8]));
        let hs = s / 2;
        let mut ch = [NONE; 8];
        for (k, slot) in ch.iter_mut().enumerate() {
            let k = k as i32;
            let d = IVec3::new(k & 1, (k >> 1) & 1, (k >> 2) & 1) * hs;
            *slot = self.build(o + d, hs, &act, next);
        }
        self.nodes[id] = Node::Inner(ch);
        id as u32
    }

    /// A one-cell leaf: the uniform mesher's cell (QEF vertex, feature point
    /// kept, projected when smooth).
    fn cell_leaf(&mut self, o: IVec3, act: &Active) -> u32 {
        let mut corners = 0u8;
        for k in 0..8 {
            let d = IVec3::new(k & 1, (k >> 1) & 1, (k >> 2) & 1);
            if self.sample(o + d, act).inside {
                corners |= 1 << k;
            }
        }
        if corners == 0 || corners == 255 {
            return self.push_leaf(o, 1, corners, NONE);
        }
        let mut qef = Qef::default();
        for axis in 0..3 {
            let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
            for (i, j) in RING {
                let mut l = [0; 3];
                l[b] = i;
                l[c] = j;
                let (k0, k1) = (bit(l[0], l[1], l[2]), bit(l[0], l[1], l[2]) | (1 << axis));
                if (corners >> k0) & 1 != (corners >> k1) & 1 {
                    let (p, n) = self.edge(o + IVec3::from_array(l), axis, 1, true, act);
                    qef.add(p, n);
                }
            }
        }
        let sol = qef.solve().expect("a mixed cell has a crossing");
        let field = Field {
            model: self.model,
            act,
            margin: self.margin,
        };
        let (v, normal, _) = cell_vertex(&field, self.grid.h, self.grid.corner(o), &sol);
        self.stats.fine_surface_leaves += 1;
        let vi = self.push_vertex(v, normal);
        self.push_leaf(o, 1, corners, vi)
    }

    /// The node (o, s) as one leaf if its check lattice passes the tests of
    /// step 2 (module doc); else the largest deviation of a sample from the
    /// vertex plane relative to the tolerance (0 when the node failed before
    /// a plane was fitted).
    fn coarse_leaf(&mut self, o: IVec3, s: i32, act: &Active) -> Result<u32, f64> {
        let q = s / 2;
        let n = (s / q + 1) as usize;
        let idx = |x: usize, y: usize, z: usize| (z * n + y) * n + x;
        let mut inside = [false; 27];
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let c = o + IVec3::new(x as i32, y as i32, z as i32) * q;
                    inside[idx(x, y, z)] = self.sample(c, act).inside;
                }
            }
        }
        // Lattice lines: at most one change each.
        let mut any = false;
        for axis in 0..3 {
            for j in 0..n {
                for i in 0..n {
                    let mut changes = 0;
                    for t in 0..n - 1 {
                        let at = |t: usize| {
                            let mut l = [0; 3];
                            l[axis] = t;
                            l[(axis + 1) % 3] = i;
                            l[(axis + 2) % 3] = j;
                            inside[idx(l[0], l[1], l[2])]
                        };
                        if at(t) != at(t + 1) {
                            changes += 1;
                        }
                    }
                    if changes > 1 {
                        return Err(0.0);
                    }
                    any |= changes > 0;
                }
            }
        }
        let m = n - 1;
        let mut corners = 0u8;
        for k in 0..8 {
            let (x, y, z) = (k & 1, (k >> 1) & 1, (k >> 2) & 1);
            if inside[idx(x * m, y * m, z * m)] {
                corners |= 1 << k;
            }
        }
        if !any {
            return Ok(self.push_leaf(o, s, corners, NONE));
        }
        if corners == 0 || corners == 255 || !connected(corners) || !connected(!corners) {
            return Err(0.0);
        }
        // Faces whose corners agree hold no lattice crossing.
        for axis in 0..3 {
            for side in [0, m] {
                let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
                let at = |i: usize, j: usize| {
                    let mut l = [0; 3];
                    l[axis] = side;
                    l[b] = i;
                    l[c] = j;
                    inside[idx(l[0], l[1], l[2])]
                };
                let first = at(0, 0);
                if at(m, 0) == first && at(0, m) == first && at(m, m) == first {
                    for j in 0..n {
                        for i in 0..n {
                            if at(i, j) != first {
                                return Err(0.0);
                            }
                        }
                    }
                }
            }
        }
        // Hermite samples of every crossing lattice edge.
        let mut qef = Qef::default();
        let mut samples = Vec::new();
        for axis in 0..3 {
            for z in 0..n {
                for y in 0..n {
                    for x in 0..n {
                        let l = [x, y, z];
                        if l[axis] == m {
                            continue;
                        }
                        let mut l1 = l;
                        l1[axis] += 1;
                        if inside[idx(x, y, z)] != inside[idx(l1[0], l1[1], l1[2])] {
                            let a = o + IVec3::new(x as i32, y as i32, z as i32) * q;
                            let h = self.edge(a, axis, q, false, act);
                            qef.add(h.0, h.1);
                            samples.push(h);
                        }
                    }
                }
            }
        }
        let sol = qef.solve().ok_or(0.0)?;
        if sol.rank > 1 {
            return Err(0.0);
        }
        let h = self.grid.h;
        let lo = self.grid.corner(o);
        let hi = lo + DVec3::splat(s as f64 * h);
        let slack = DVec3::splat(1e-9 * h);
        let v0 = if sol.point.cmpge(lo - slack).all() && sol.point.cmple(hi + slack).all() {
            sol.point
        } else {
            sol.mass_point
        };
        let nsum = sol.normal_sum.normalize_or_zero();
        let field = Field {
            model: self.model,
            act,
            margin: self.margin,
        };
        let v = self
            .onto_level_set(&field, v0, nsum, q as f64 * h)
            .ok_or(0.0)?;
        let reach = DVec3::splat(q as f64 * h);
        if !(v.cmpge(lo - reach).all() && v.cmple(hi + reach).all()) {
            return Err(0.0);
        }
        let g = field.normal(v);
        let nv = if g.dot(nsum) < 0.0 { -g } else { g };
        if nv == DVec3::ZERO {
            return Err(0.0);
        }
        let mut dev: f64 = 0.0;
        let mut bent = false;
        for &(p, pn) in &samples {
            dev = dev.max(nv.dot(p - v).abs());
            bent |= pn.dot(nv) < COS_MAX;
        }
        if bent || dev > 0.5 * self.tol {
            return Err(2.0 * dev / self.tol);
        }
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let p = self
                        .grid
                        .corner(o + IVec3::new(x as i32, y as i32, z as i32) * q);
                    let d = nv.dot(p - v);
                    let ins = inside[idx(x, y, z)];
                    if (ins && d > self.tol) || (!ins && d < -self.tol) {
                        return Err(0.0);
                    }
                }
            }
        }
        self.stats.coarse_surface_leaves += 1;
        self.stats.largest_surface_leaf = self.stats.largest_surface_leaf.max(s as usize);
        let vi = self.push_vertex(v, nv);
        Ok(self.push_leaf(o, s, corners, vi))
    }

    /// Moves v along ±n onto the boundary: first within 1.5 |Φ(v)| (Φ is a
    /// distance estimate, so the bracket is tight and short), else within
    /// `reach` ([`project`]); rooted to 1e-9 of the bracket (the vertex is on
    /// the level set to ~1e-9 of a cell).
    fn onto_level_set(&mut self, field: &Field, v: DVec3, n: DVec3, reach: f64) -> Option<DVec3> {
        if n == DVec3::ZERO {
            return None;
        }
        let s0 = field.sample(v, &mut self.scratch);
        let dir = if s0.inside { n } else { -n };
        let step = 1.5 * s0.phi.abs() + 1e-6 * self.grid.h;
        if step < reach {
            let p1 = v + dir * step;
            let s1 = field.sample(p1, &mut self.scratch);
            if s1.inside != s0.inside {
                let t = root(field, v, p1 - v, (s0.phi, s1.phi), s0.inside, 1e-9);
                return Some(v + (p1 - v) * t);
            }
        }
        project(field, reach, v, n)
    }

    /// Node `id`'s child at corner bits `k`, or the node itself if it is a leaf.
    fn child(&self, id: u32, k: u32) -> u32 {
        match &self.nodes[id as usize] {
            Node::Inner(ch) => ch[k as usize],
            Node::Leaf(_) => id,
        }
    }

    fn is_leaf(&self, id: u32) -> bool {
        matches!(self.nodes[id as usize], Node::Leaf(_))
    }

    fn cell_proc(&mut self, id: u32, quads: &mut Vec<([u32; 4], bool)>) {
        let ch = match &self.nodes[id as usize] {
            Node::Inner(ch) => *ch,
            Node::Leaf(_) => return,
        };
        for &c in &ch {
            self.cell_proc(c, quads);
        }
        for a in 0..3 {
            for k in 0..8u32 {
                if k & (1 << a) == 0 {
                    self.face_proc([ch[k as usize], ch[(k | (1 << a)) as usize]], a, quads);
                }
            }
        }
        for d in 0..3 {
            for t in 0..2 {
                let ring = RING.map(|(bb, cc)| {
                    let mut l = [0; 3];
                    l[d] = t;
                    l[(d + 1) % 3] = bb;
                    l[(d + 2) % 3] = cc;
                    ch[bit(l[0], l[1], l[2]) as usize]
                });
                self.edge_proc(ring, d, quads);
            }
        }
    }

    /// The face between n[0] (low side along axis a) and n[1].
    fn face_proc(&mut self, n: [u32; 2], a: usize, quads: &mut Vec<([u32; 4], bool)>) {
        if self.is_leaf(n[0]) && self.is_leaf(n[1]) {
            return;
        }
        // The 2×2×2 block of cells at the face: side bit a picks the node,
        // which gives its child on the face (bit a flipped).
        let v = |b: &Self, k: u32| b.child(n[((k >> a) & 1) as usize], k ^ (1 << a));
        for k in 0..8u32 {
            if k & (1 << a) == 0 {
                let pair = [v(self, k), v(self, k | (1 << a))];
                self.face_proc(pair, a, quads);
            }
        }
        for d in [(a + 1) % 3, (a + 2) % 3] {
            for t in 0..2 {
                let ring = RING.map(|(bb, cc)| {
                    let mut l = [0; 3];
                    l[d] = t;
                    l[(d + 1) % 3] = bb;
                    l[(d + 2) % 3] = cc;
                    v(self, bit(l[0], l[1], l[2]))
                });
                self.edge_proc(ring, d, quads);
            }
        }
    }

    /// The edge along axis d shared by the four nodes `n` (in [`RING`] order).
    fn edge_proc(&mut self, n: [u32; 4], d: usize, quads: &mut Vec<([u32; 4], bool)>) {
        if n.iter().all(|&id| self.is_leaf(id)) {
            self.edge_quad(n, d, quads);
            return;
        }
        let (b, c) = ((d + 1) % 3, (d + 2) % 3);
        for t in 0..2 {
            let ring: [u32; 4] = std::array::from_fn(|r| {
                let (bb, cc) = RING[r];
                // Node r touches the edge with its child on the far side.
                let mut l = [0; 3];
                l[d] = t;
                l[b] = 1 - bb;
                l[c] = 1 - cc;
                self.child(n[r], bit(l[0], l[1], l[2]))
            });
            self.edge_proc(ring, d, quads);
        }
    }

    /// The quad of four leaves around an edge along axis d, if their minimal
    /// edge (the smallest leaf's) changes membership.
    fn edge_quad(&mut self, n: [u32; 4], d: usize, quads: &mut Vec<([u32; 4], bool)>) {
        let leaf = |id: u32| match self.nodes[id as usize] {
            Node::Leaf(l) => l,
            Node::Inner(_) => unreachable!("edge_quad on leaves"),
        };
        let ls = n.map(leaf);
        let r = (0..4)
            .min_by_key(|&r| self.leaves[ls[r] as usize].size)
            .expect("four leaves");
        let (bb, cc) = RING[r];
        let mut l = [0; 3];
        l[(d + 1) % 3] = 1 - bb;
        l[(d + 2) % 3] = 1 - cc;
        let k0 = bit(l[0], l[1], l[2]);
        let k1 = k0 | (1 << d);
        let small = &self.leaves[ls[r] as usize];
        let (i0, i1) = ((small.corners >> k0) & 1, (small.corners >> k1) & 1);
        if i0 == i1 {
            return;
        }
        if ls.iter().any(|&li| self.leaves[li as usize].vertex == NONE) {
            let a = small.origin + IVec3::from_array(l) * small.size;
            let len = small.size;
            let all = self.model.all_active();
            let (p, nn) = self.edge(a, d, len, true, &all);
            for &li in &ls {
                let leaf = &mut self.leaves[li as usize];
                if leaf.vertex == NONE {
                    leaf.fallback.add(p, nn);
                }
            }
        }
        quads.push((ls, i0 == 1));
    }

    /// Vertices for leaves named without one, then the triangles (only
    /// vertices a triangle uses are kept, in first-use order).
    fn finish(
        mut self,
        quads: Vec<([u32; 4], bool)>,
        all: &Active,
    ) -> (Mesh, AdaptiveStats, Store) {
        let field = Field {
            model: self.model,
            act: all,
            margin: self.margin,
        };
        for li in 0..self.leaves.len() {
            let leaf = &self.leaves[li];
            if leaf.vertex != NONE {
                continue;
            }
            let Some(sol) = leaf.fallback.solve() else {
                continue;
            };
            let nsum = sol.normal_sum.normalize_or_zero();
            let reach = leaf.size as f64 * self.grid.h;
            let v = project(&field, reach, sol.mass_point, nsum).unwrap_or(sol.mass_point);
            let g = field.normal(v);
            let nv = if g.dot(nsum) < 0.0 { -g } else { g };
            let vi = self.push_vertex(v, nv);
            self.leaves[li].vertex = vi;
        }
        let mut mesh = Mesh::default();
        let mut remap = vec![NONE; self.positions.len()];
        let mut take = |v: u32, mesh: &mut Mesh| {
            if remap[v as usize] == NONE {
                remap[v as usize] = mesh.positions.len() as u32;
                mesh.positions.push(self.positions[v as usize]);
                mesh.normals.push(self.normals[v as usize]);
            }
            remap[v as usize]
        };
        mesh.triangles.reserve(2 * quads.len());
        for (ls, lower_inside) in quads {
            let mut q = ls.map(|li| take(self.leaves[li as usize].vertex, &mut mesh));
            // Counter-clockwise seen from +axis; outward is +axis when the
            // lower end is inside.
            if !lower_inside {
                q.reverse();
            }
            // A leaf on both sides of a minimal edge inside its face (Ju et
            // al.'s face procedure passes it twice, next to itself): a triangle.
            if let Some(i) = (0..4).find(|&i| q[i] == q[(i + 1) % 4]) {
                let t = [q[(i + 1) % 4], q[(i + 2) % 4], q[(i + 3) % 4]];
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    mesh.triangles.push(t);
                }
                continue;
            }
            let p = |i: usize| mesh.positions[q[i] as usize];
            if (p(0) - p(2)).length_squared() <= (p(1) - p(3)).length_squared() {
                mesh.triangles.push([q[0], q[1], q[2]]);
                mesh.triangles.push([q[0], q[2], q[3]]);
            } else {
                mesh.triangles.push([q[0], q[1], q[3]]);
                mesh.triangles.push([q[1], q[2], q[3]]);
            }
        }
        self.stats.leaves = self.leaves.len();
        self.stats.vertices = mesh.positions.len();
        self.stats.corner_samples = self.samples.len();
        self.stats.hermite_samples = self.edges.len();
        let store = Store {
            samples: Some(self.samples),
            edges: self.edges,
            nodes: self.nodes,
            leaves: self.leaves,
        };
        (mesh, self.stats, store)
    }
}
