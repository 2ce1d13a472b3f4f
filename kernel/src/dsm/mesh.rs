//! Meshing S: dual contouring with Hermite data on a uniform grid, visited through
//! an octree whose nodes are culled by interval bounds.
//!
//! 1. The grid spans [`Model::bounds`] with `cells` cells along its longest side
//!    ([`Grid::on_lattice`]: about that many, on a lattice that stays put while the bounds
//!    move a little, for incremental re-meshing during a drag).
//!    An octree over it culls, per node, the primitives whose influence cannot
//!    reach the node's ball, and classifies the node by interval arithmetic
//!    ([`Model::classify`]): a node wholly inside or outside S is skipped.
//! 2. Each undecided leaf (8³ cells) classifies its 2³-cell bricks the same
//!    way and samples membership and Φ only at the corners of undecided
//!    bricks (a narrow band around the boundary): no mixed cell and no
//!    crossing edge lies in a proven brick.
//! 3. Every grid edge whose ends differ in membership gets a Hermite sample: its
//!    crossing, found by the Illinois method on Φ to 1e-10 of a cell, and the
//!    unit normal of the boundary piece there.
//! 4. Every cell with a crossing gets one vertex: the QEF minimiser (sharp edges
//!    and corners of geometric primitives are kept), or the mass point if the
//!    minimiser leaves the cell. A vertex on a smooth patch (QEF rank 1) is then
//!    projected onto the boundary along its normal (a bracketed root of Φ), so it
//!    lies on the level set to ~1e-12 of a cell.
//! 5. Every crossing edge gives a quad of the four cells around it, oriented
//!    outwards and split along its shorter diagonal.
//!
//! Steps 2–4 are per leaf and depend on nothing outside it (a crossing on a
//! leaf face is found by each leaf that has it, with its own active set), so a
//! leaf is kept between edits and only the leaves an edit reaches are meshed
//! again ([`super::incremental`]). Vertices are numbered leaf by leaf in Morton
//! order of the leaves, cell by cell (x fastest) within a leaf.
//!
//! The mesh is closed (every edge in two triangles) because the quads are the dual
//! of the boundary between inside and outside grid corners. Known limit: one vertex
//! per cell, so a cell cut by two separate sheets (features thinner than a cell)
//! joins them at a non-manifold vertex — Manifold Dual Contouring would split it.

use super::error::DsmError;
use super::interval::Tri;
use super::model::{Active, Model};
use super::qef::{Qef, QefSolution};
use glam::{DVec3, IVec3};

/// Leaf size in cells.
pub(crate) const LEAF: i32 = 8;

/// A triangle mesh with unit normals.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Unit outward normals.
    pub normals: Vec<DVec3>,
    /// Triangles (counter-clockwise seen from outside).
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// V − E + F, edges counted once per unordered vertex pair.
    pub fn euler_characteristic(&self) -> i64 {
        let mut edges = std::collections::HashSet::new();
        for t in &self.triangles {
            for i in 0..3 {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                edges.insert((a.min(b), a.max(b)));
            }
        }
        self.positions.len() as i64 - edges.len() as i64 + self.triangles.len() as i64
    }
}

/// What to mesh at which resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshOptions {
    /// Cells along the longest side of the model's bounds (4 ..= 4096).
    pub cells: usize,
}

/// Counters of one meshing run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MeshStats {
    /// Octree leaves sampled.
    pub leaves: usize,
    /// Cells that got a vertex.
    pub vertices: usize,
    /// Vertices projected onto the level set (QEF rank 1).
    pub projected: usize,
    /// Vertices kept at a QEF feature point (rank 2 or 3).
    pub features: usize,
}

/// One sampled and contoured leaf (8³ cells): what the mesher keeps per leaf
/// between edits. Every sample it took is a function of the point and the
/// model alone ([`Model::sample`]), never of other leaves or of its active
/// set, so a leaf the edit cannot reach is reused as it is, and in a leaf the
/// edit reaches only the corners and cells within the edit's reach are sampled
/// again ([`update_leaf`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct LeafMesh {
    /// Grid corner of the leaf's first cell.
    pub(crate) origin: IVec3,
    /// Membership at the (LEAF + 1)³ corners (x fastest).
    inside: Vec<bool>,
    /// Φ at the corners; NaN at a corner not sampled (it lies in proven
    /// bricks only, [`leaf_bricks`]).
    phi: Vec<f64>,
    /// Per cell (x fastest): index into `verts`, or u32::MAX.
    cell_vert: Vec<u32>,
    /// Each mixed cell's vertex, in cell order.
    verts: Vec<CellVertex>,
    /// Crossing edges from the leaf's own corners (0..8 per axis): (cell, axis,
    /// whether the lower end is inside), in the order quads are emitted.
    crossings: Vec<(IVec3, u8, bool)>,
    projected: usize,
    features: usize,
}

/// A mixed cell's vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
struct CellVertex {
    position: DVec3,
    normal: DVec3,
    /// Projected onto the level set (QEF rank ≤ 1), else a feature point.
    projected: bool,
}

fn corner_index(l: IVec3) -> usize {
    let n = (LEAF + 1) as usize;
    (l.z as usize * n + l.y as usize) * n + l.x as usize
}

fn cell_index(l: IVec3) -> usize {
    let n = LEAF as usize;
    (l.z as usize * n + l.y as usize) * n + l.x as usize
}

/// The grid: origin, cell size, dimensions in cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// World position of corner (0, 0, 0).
    pub origin: DVec3,
    /// Cell size.
    pub h: f64,
    /// Cells per axis.
    pub dims: IVec3,
}

impl Grid {
    /// The grid for a model at `cells` cells along its longest side, with
    /// 1.5 cells to spare on every side.
    pub fn for_model(model: &Model, cells: usize) -> Result<Self, DsmError> {
        let (lo, hi, size) = Self::bounds(model, cells)?;
        let h = size / cells as f64;
        let origin = lo - DVec3::splat(1.5 * h);
        let dims = ((hi - lo) / h).ceil().as_ivec3() + IVec3::splat(3);
        Ok(Self { origin, h, dims })
    }

    /// The grid for a model at about `cells` cells along the longest side of
    /// its bounds, on a lattice so that it stays put while an edit moves the
    /// bounds a little (an incremental re-mesh, and a mesh frame quantised on
    /// the grid, need the same grid; the server sends a drag's frames as
    /// deltas):
    /// * the cell size is size / cells rounded up to a power of 2^(1/16)
    ///   (so there are between cells / 1.045 and `cells` cells along the
    ///   longest side);
    /// * the origin is the bounds' low corner rounded down to a multiple of
    ///   the cell size, less two cells, and the grid ends two to three cells
    ///   beyond the high corner: between two and three cells to spare on
    ///   every side.
    ///
    /// A function of the bounds alone, so a part edited step by step and a
    /// part built from its final document get the same grid.
    pub fn on_lattice(model: &Model, cells: usize) -> Result<Self, DsmError> {
        let (lo, hi, size) = Self::bounds(model, cells)?;
        let h = ((16.0 * (size / cells as f64).log2()).ceil() / 16.0).exp2();
        let origin = ((lo / h).floor() - DVec3::splat(2.0)) * h;
        let dims = ((hi - origin) / h).ceil().as_ivec3() + IVec3::splat(2);
        Ok(Self { origin, h, dims })
    }

    /// The model's bounds and their longest side, checked, for a grid of
    /// `cells` cells.
    fn bounds(model: &Model, cells: usize) -> Result<(DVec3, DVec3, f64), DsmError> {
        if !(4..=4096).contains(&cells) {
            return Err(DsmError::BadMeshRequest("cells must be in 4..=4096"));
        }
        let (lo, hi) = model.bounds().ok_or(DsmError::BadMeshRequest(
            "the model has no positive primitive",
        ))?;
        let size = (hi - lo).max_element();
        if !(size > 0.0 && size.is_finite()) {
            return Err(DsmError::BadMeshRequest(
                "the model's bounds are empty or infinite",
            ));
        }
        Ok((lo, hi, size))
    }

    /// The world position of grid corner c.
    pub fn corner(&self, c: IVec3) -> DVec3 {
        self.origin + c.as_dvec3() * self.h
    }

    /// The reach margin of the mesher's samples ([`Model::sample`]): two
    /// cells. Every bracket the mesher searches (a cell edge, a projection of
    /// at most one cell) is shorter than the margin, so within it Φ is the
    /// distance estimate of every boundary piece nearby, unclamped.
    pub fn reach_margin(&self) -> f64 {
        2.0 * self.h
    }
}

/// The field the mesher samples: a model, the primitives active in a leaf and
/// the grid's reach margin.
#[derive(Clone, Copy)]
pub(crate) struct Field<'a> {
    pub(crate) model: &'a Model,
    pub(crate) act: &'a Active,
    pub(crate) margin: f64,
}

impl Field<'_> {
    pub(crate) fn sample(&self, p: DVec3, scratch: &mut Vec<bool>) -> super::model::Sample {
        self.model.sample(p, self.act, self.margin, scratch)
    }

    pub(crate) fn normal(&self, p: DVec3) -> DVec3 {
        self.model.piece_gradient(p, self.act, self.margin)
    }
}

/// Meshes S at the resolution of `opts`.
pub fn mesh(model: &Model, opts: MeshOptions) -> Result<(Mesh, MeshStats), DsmError> {
    let grid = Grid::for_model(model, opts.cells)?;
    Ok(mesh_on(model, &grid))
}

/// Meshes S on a given grid.
pub fn mesh_on(model: &Model, grid: &Grid) -> (Mesh, MeshStats) {
    super::incremental::LeafTree::build(model, grid).assemble()
}

/// The primitives that may reach (with the grid's reach margin) any point
/// the leaf at `origin` samples: its corners and edges, and the projections
/// of its cells' vertices (up to one cell beyond the leaf), with a cell to
/// spare.
fn leaf_active(model: &Model, grid: &Grid, origin: IVec3) -> Active {
    let half = LEAF as f64 * 0.5;
    let c = grid.corner(origin) + DVec3::splat(half * grid.h);
    let r = grid.h * (half * 3f64.sqrt() + 2.0) + grid.reach_margin();
    model.cull(&model.all_active(), c, r)
}

/// Bricks of [`BRICK`]³ cells per leaf axis.
const BRICKS: i32 = LEAF / BRICK;

/// Brick size in cells: the unit of the narrow band within a leaf.
const BRICK: i32 = 2;

/// Membership proven by interval bounds ([`Model::classify`]) over each
/// [`BRICK`]³-cell brick of the leaf at `origin` (x fastest; `Tri::Maybe`:
/// undecided), from the leaf's half-size bricks down. No crossing edge and no
/// mixed cell lies in a proven brick, so only the corners of undecided
/// bricks are sampled (the narrow band around the boundary); a corner of
/// proven bricks alone takes their membership and no Φ. A function of the
/// model, the grid and the leaf (its active set is derived from them), so a
/// fresh leaf and an updated one prove the same bricks.
fn leaf_bricks(model: &Model, act: &Active, grid: &Grid, origin: IVec3) -> Vec<Tri> {
    let nb = BRICKS as usize;
    let mut out = vec![Tri::Maybe; nb * nb * nb];
    let half = LEAF / 2;
    for k in 0..8 {
        let o = IVec3::new(k & 1, (k >> 1) & 1, (k >> 2) & 1) * half;
        let r = 0.5 * half as f64 * grid.h * 3f64.sqrt();
        let c = grid.corner(origin + o) + DVec3::splat(0.5 * half as f64 * grid.h);
        let sub = model.cull(act, c, r);
        let t = model.classify(c, r, &sub);
        let rb = 0.5 * BRICK as f64 * grid.h * 3f64.sqrt();
        for bz in 0..half / BRICK {
            for by in 0..half / BRICK {
                for bx in 0..half / BRICK {
                    let b = o / BRICK + IVec3::new(bx, by, bz);
                    let tb = if t == Tri::Maybe {
                        let cb = grid.corner(origin + b * BRICK)
                            + DVec3::splat(0.5 * BRICK as f64 * grid.h);
                        model.classify(cb, rb, &sub)
                    } else {
                        t
                    };
                    out[((b.z * BRICKS + b.y) * BRICKS + b.x) as usize] = tb;
                }
            }
        }
    }
    out
}

/// Per corner of the leaf: whether an undecided brick holds it (it is
/// sampled), else the membership its proven bricks give.
fn corner_plan(bricks: &[Tri]) -> Vec<Option<bool>> {
    let n = (LEAF + 1) as usize;
    let mut plan = vec![Some(false); n * n * n];
    let mut known = vec![false; n * n * n];
    for bz in 0..BRICKS {
        for by in 0..BRICKS {
            for bx in 0..BRICKS {
                let b = IVec3::new(bx, by, bz);
                let t = bricks[((bz * BRICKS + by) * BRICKS + bx) as usize];
                for z in 0..=BRICK {
                    for y in 0..=BRICK {
                        for x in 0..=BRICK {
                            let i = corner_index(b * BRICK + IVec3::new(x, y, z));
                            match t {
                                Tri::Maybe => {
                                    plan[i] = None;
                                    known[i] = true;
                                }
                                _ if !known[i] => {
                                    plan[i] = Some(t == Tri::Yes);
                                    known[i] = true;
                                }
                                _ => {}
                            }
                        }
                    }
                }
            }
        }
    }
    plan
}

/// Steps 2–4 for the leaf at `origin`: corner samples in the narrow band
/// ([`leaf_bricks`]), Hermite data (per leaf: a crossing on a leaf face is
/// computed by each leaf that has it), one vertex per mixed cell, and the
/// leaf's crossing edges for step 5.
pub(crate) fn mesh_leaf(model: &Model, grid: &Grid, origin: IVec3) -> LeafMesh {
    let act = leaf_active(model, grid, origin);
    let field = Field {
        model,
        act: &act,
        margin: grid.reach_margin(),
    };
    let plan = corner_plan(&leaf_bricks(model, &act, grid, origin));
    let n = (LEAF + 1) as usize;
    let mut scratch = Vec::new();
    let mut inside = Vec::with_capacity(n * n * n);
    let mut phi = Vec::with_capacity(n * n * n);
    for z in 0..=LEAF {
        for y in 0..=LEAF {
            for x in 0..=LEAF {
                let l = IVec3::new(x, y, z);
                match plan[corner_index(l)] {
                    Some(known) => {
                        inside.push(known);
                        phi.push(f64::NAN);
                    }
                    None => {
                        let smp = field.sample(grid.corner(origin + l), &mut scratch);
                        inside.push(smp.inside);
                        phi.push(smp.phi);
                    }
                }
            }
        }
    }
    contour(&field, grid, origin, inside, phi, None).0
}

/// Whether a ball (c, r) meets one of `balls` (the test of [`Model::cull`]).
pub(crate) fn touches(balls: &[(DVec3, f64)], c: DVec3, r: f64) -> bool {
    balls.iter().any(|&(bc, br)| (bc - c).length() <= br + r)
}

/// `leaf` after an edit of the model that changed nothing outside the balls
/// `changed` (see [`super::incremental`]): only the corners inside a ball are
/// sampled again, and only the cells whose samples can reach a ball (the cell
/// and one cell around it, where its crossings, vertex and projection are
/// found) are contoured again; every other corner and cell vertex is kept.
/// Returns the leaf and the number of cells contoured again. Equals
/// [`mesh_leaf`] of the edited model, bit for bit, because every sample is a
/// function of the point and the model alone.
pub(crate) fn update_leaf(
    model: &Model,
    grid: &Grid,
    leaf: &LeafMesh,
    changed: &[(DVec3, f64)],
) -> (LeafMesh, usize) {
    let origin = leaf.origin;
    let act = leaf_active(model, grid, origin);
    let field = Field {
        model,
        act: &act,
        margin: grid.reach_margin(),
    };
    // Rounding slack of the reach tests (the QEF point may leave its cell by
    // 1e-9 of a cell).
    let eps = 1e-6 * grid.h;
    let mut scratch = Vec::new();
    let plan = corner_plan(&leaf_bricks(model, &act, grid, origin));
    let mut inside = leaf.inside.clone();
    let mut phi = leaf.phi.clone();
    for z in 0..=LEAF {
        for y in 0..=LEAF {
            for x in 0..=LEAF {
                let l = IVec3::new(x, y, z);
                let i = corner_index(l);
                match plan[i] {
                    Some(known) => {
                        inside[i] = known;
                        phi[i] = f64::NAN;
                    }
                    // Sampled before (Φ is not NaN) and out of the edit's
                    // reach: the same sample.
                    None if !phi[i].is_nan() && !touches(changed, grid.corner(origin + l), eps) => {
                    }
                    None => {
                        let smp = field.sample(grid.corner(origin + l), &mut scratch);
                        inside[i] = smp.inside;
                        phi[i] = smp.phi;
                    }
                }
            }
        }
    }
    let reach = grid.h * (0.5 * 3f64.sqrt() + 1.0) + eps;
    let redo = |lc: IVec3| {
        let c = grid.corner(origin + lc) + DVec3::splat(0.5 * grid.h);
        touches(changed, c, reach)
    };
    contour(&field, grid, origin, inside, phi, Some((leaf, &redo)))
}

/// Steps 3–4 on sampled corners; with `old`, a cell that `redo` does not name
/// keeps its vertex from the old leaf. Returns the leaf and the number of
/// mixed cells contoured.
fn contour(
    field: &Field,
    grid: &Grid,
    origin: IVec3,
    inside: Vec<bool>,
    phi: Vec<f64>,
    old: Option<(&LeafMesh, &dyn Fn(IVec3) -> bool)>,
) -> (LeafMesh, usize) {
    let mut leaf = LeafMesh {
        origin,
        inside,
        phi,
        cell_vert: vec![u32::MAX; (LEAF * LEAF * LEAF) as usize],
        verts: Vec::new(),
        crossings: Vec::new(),
        projected: 0,
        features: 0,
    };
    let (inside, phi) = (&leaf.inside, &leaf.phi);
    let mut verts = Vec::new();
    let mut contoured = 0;
    // Hermite samples of the leaf's edges, shared by the (up to 4) cells
    // around each: per (corner, axis), 1 + an index into `hermites`, or 0.
    let mut edge_slot = vec![0u32; 3 * corner_index(IVec3::splat(LEAF)) + 3];
    let mut hermites: Vec<(DVec3, DVec3)> = Vec::new();
    for z in 0..LEAF {
        for y in 0..LEAF {
            for x in 0..LEAF {
                let lc = IVec3::new(x, y, z);
                let mut mask = 0u8;
                for k in 0..8 {
                    let d = IVec3::new(k & 1, (k >> 1) & 1, (k >> 2) & 1);
                    if inside[corner_index(lc + d)] {
                        mask |= 1 << k;
                    }
                }
                if mask == 0 || mask == 255 {
                    continue;
                }
                if let Some((old, redo)) = old {
                    let v = old.cell_vert[cell_index(lc)];
                    if v != u32::MAX && !redo(lc) {
                        leaf.cell_vert[cell_index(lc)] = verts.len() as u32;
                        verts.push(old.verts[v as usize]);
                        continue;
                    }
                }
                contoured += 1;
                let mut qef = Qef::default();
                for axis in 0..3u8 {
                    let e = [IVec3::X, IVec3::Y, IVec3::Z][axis as usize];
                    let (b, c) = (
                        [IVec3::Y, IVec3::Z, IVec3::X][axis as usize],
                        [IVec3::Z, IVec3::X, IVec3::Y][axis as usize],
                    );
                    for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let a0 = lc + b * i + c * j;
                        let a1 = a0 + e;
                        let (i0, i1) = (inside[corner_index(a0)], inside[corner_index(a1)]);
                        if i0 == i1 {
                            continue;
                        }
                        let slot = &mut edge_slot[3 * corner_index(a0) + axis as usize];
                        if *slot == 0 {
                            hermites.push(hermite(
                                field,
                                grid,
                                origin + a0,
                                e,
                                phi[corner_index(a0)],
                                phi[corner_index(a1)],
                                i0,
                            ));
                            *slot = hermites.len() as u32;
                        }
                        let (p, n) = hermites[*slot as usize - 1];
                        qef.add(p, n);
                    }
                }
                let sol = qef.solve().expect("a mixed cell has a crossing");
                let (v, normal, projected) =
                    cell_vertex(field, grid.h, grid.corner(origin + lc), &sol);
                leaf.cell_vert[cell_index(lc)] = verts.len() as u32;
                verts.push(CellVertex {
                    position: v,
                    normal,
                    projected,
                });
            }
        }
    }
    let mut crossings = Vec::new();
    for z in 0..LEAF {
        for y in 0..LEAF {
            for x in 0..LEAF {
                let lc = IVec3::new(x, y, z);
                let i0 = inside[corner_index(lc)];
                for axis in 0..3u8 {
                    let e = [IVec3::X, IVec3::Y, IVec3::Z][axis as usize];
                    if i0 != inside[corner_index(lc + e)] {
                        crossings.push((lc, axis, i0));
                    }
                }
            }
        }
    }
    leaf.projected = verts.iter().filter(|v| v.projected).count();
    leaf.features = verts.len() - leaf.projected;
    leaf.verts = verts;
    leaf.crossings = crossings;
    (leaf, contoured)
}

/// Step 5 over `leaves` of a walk over `grid` (in the order their vertices
/// are numbered): the vertices, then one quad per crossing edge owned by a
/// leaf, oriented outwards and split along its shorter diagonal.
pub(crate) fn assemble<'a>(
    grid: &Grid,
    leaves: impl Iterator<Item = &'a LeafMesh>,
) -> (Mesh, MeshStats) {
    let mut stats = MeshStats::default();
    let mut mesh = Mesh::default();
    // Leaf slot → (index in `list`, first vertex), dense over the leaf grid.
    let nl = (grid.dims + IVec3::splat(LEAF - 1)) / LEAF;
    let slot = |l: IVec3| -> Option<usize> {
        (l.cmpge(IVec3::ZERO).all() && l.cmplt(nl).all())
            .then(|| ((l.z * nl.y + l.y) * nl.x + l.x) as usize)
    };
    let mut index: Vec<(u32, u32)> = vec![(u32::MAX, 0); (nl.x * nl.y * nl.z) as usize];
    let mut list: Vec<&LeafMesh> = Vec::new();
    for leaf in leaves {
        let base = mesh.positions.len() as u32;
        if let Some(sl) = slot(leaf.origin / LEAF) {
            index[sl] = (list.len() as u32, base);
        }
        list.push(leaf);
        mesh.positions.extend(leaf.verts.iter().map(|v| v.position));
        mesh.normals.extend(leaf.verts.iter().map(|v| v.normal));
        stats.leaves += 1;
        stats.projected += leaf.projected;
        stats.features += leaf.features;
    }
    stats.vertices = mesh.positions.len();
    let vertex_of = |cell: IVec3| -> Option<u32> {
        let lk = IVec3::new(
            cell.x.div_euclid(LEAF),
            cell.y.div_euclid(LEAF),
            cell.z.div_euclid(LEAF),
        );
        let (li, base) = index[slot(lk)?];
        let leaf = list.get(li as usize)?;
        let v = leaf.cell_vert[cell_index(cell - leaf.origin)];
        (v != u32::MAX).then(|| base + v)
    };
    mesh.triangles
        .reserve(list.iter().map(|l| 2 * l.crossings.len()).sum());
    for leaf in &list {
        for &(lc, axis, i0) in &leaf.crossings {
            let axis = axis as usize;
            let (b, c) = (
                [IVec3::Y, IVec3::Z, IVec3::X][axis],
                [IVec3::Z, IVec3::X, IVec3::Y][axis],
            );
            let g = leaf.origin + lc;
            let cells = [g - b - c, g - c, g, g - b];
            let mut q = [0u32; 4];
            let mut ok = true;
            for (k, cell) in cells.iter().enumerate() {
                match vertex_of(*cell) {
                    Some(v) => q[k] = v,
                    None => ok = false,
                }
            }
            if !ok {
                continue;
            }
            // Counter-clockwise seen from +axis; outward is +axis when the lower end is inside.
            if !i0 {
                q.reverse();
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
    }
    (mesh, stats)
}

/// The Hermite sample of the grid edge from corner `a` along `e`: the crossing and
/// the outward unit normal there.
pub(crate) fn hermite(
    field: &Field,
    grid: &Grid,
    a: IVec3,
    e: IVec3,
    phi0: f64,
    phi1: f64,
    inside0: bool,
) -> (DVec3, DVec3) {
    let p0 = grid.corner(a);
    let d = e.as_dvec3() * grid.h;
    let t = root(field, p0, d, (phi0, phi1), inside0, 1e-10);
    let p = p0 + d * t;
    let g = field.normal(p);
    // Outward: from the inside end to the outside end.
    let out = if inside0 { d } else { -d };
    let n = if g.dot(out) < 0.0 { -g } else { g };
    (p, if n == DVec3::ZERO { out.normalize() } else { n })
}

/// The parameter t ∈ [0, 1] where membership along p0 + t d changes (Illinois
/// method on Φ with a bisection guard), to `tol` in t; `f` is Φ at the ends
/// and `ina` the membership of p0 (given, not read from Φ's sign: Φ is +0 or
/// −0 on the boundary itself, and a p0 there would take the wrong side).
///
/// The bracket is kept by membership, so the result is within `tol` of the
/// boundary whatever Φ's shape; Φ only chooses where to sample. A secant
/// estimate closer than `tol` / 2 to an end of the bracket is moved to
/// `tol` / 2 from it: once the estimate is on the root (Φ is near linear over
/// a cell, so after one or two steps), the next sample then lands just past
/// it and closes the bracket, instead of bisecting the far side down to `tol`
/// (about 33 samples a root). Bisection is kept for a step that follows two
/// steps which together did not halve the bracket.
pub(crate) fn root(field: &Field, p0: DVec3, d: DVec3, f: (f64, f64), ina: bool, tol: f64) -> f64 {
    let mut scratch = Vec::new();
    let (mut a, mut b) = (0.0, 1.0);
    let (mut fa, mut fb) = f;
    let mut side = 0i8;
    // Bracket widths before the last two steps.
    let mut widths = [f64::INFINITY; 2];
    for _ in 0..80 {
        let w = b - a;
        if w <= tol {
            break;
        }
        let stalled = w > 0.5 * widths[0];
        widths = [widths[1], w];
        let mut t = if fa != fb && !stalled {
            (a * fb - b * fa) / (fb - fa)
        } else {
            0.5 * (a + b)
        };
        if !(t >= a && t <= b) {
            t = 0.5 * (a + b);
        }
        t = t.clamp(a + 0.5 * tol, b - 0.5 * tol);
        let s = field.sample(p0 + d * t, &mut scratch);
        let ft = s.phi;
        if s.inside == ina {
            a = t;
            fa = ft;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        } else {
            b = t;
            fb = ft;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
    }
    0.5 * (a + b)
}

/// The vertex of one cell of side `h` whose low corner is `cmin`, from its
/// QEF solution `sol`: the minimiser if it stays in the cell (to 1e-9 h),
/// else the mass point; on a smooth patch (rank ≤ 1) projected onto the
/// level set along the summed Hermite normal, with the field's normal there
/// oriented like them. Returns the position, the unit normal and whether it
/// was projected (a smooth vertex, not a feature).
pub(crate) fn cell_vertex(
    field: &Field,
    h: f64,
    cmin: DVec3,
    sol: &QefSolution,
) -> (DVec3, DVec3, bool) {
    let tol = 1e-9 * h;
    let cmax = cmin + DVec3::splat(h);
    let in_cell = |p: DVec3| p.cmpge(cmin - tol).all() && p.cmple(cmax + tol).all();
    let mut v = if in_cell(sol.point) {
        sol.point
    } else {
        sol.mass_point
    };
    let nsum = sol.normal_sum.normalize_or_zero();
    let mut normal = nsum;
    let projected = sol.rank <= 1;
    if projected {
        if let Some(pv) = project(field, h, v, nsum) {
            v = pv;
        }
        let g = field.normal(v);
        normal = if g.dot(nsum) < 0.0 { -g } else { g };
    }
    (v, normal, projected)
}

/// Moves v along ±n onto the boundary (bracketed within `reach`: steps of
/// ¼, ½ and 1 × `reach`); None if no sign change is found.
pub(crate) fn project(field: &Field, reach: f64, v: DVec3, n: DVec3) -> Option<DVec3> {
    if n == DVec3::ZERO {
        return None;
    }
    let mut scratch = Vec::new();
    let s0 = field.sample(v, &mut scratch);
    let dir = if s0.inside { n } else { -n };
    for step in [0.25, 0.5, 1.0] {
        let p1 = v + dir * (step * reach);
        let s1 = field.sample(p1, &mut scratch);
        if s1.inside != s0.inside {
            let t = root(field, v, p1 - v, (s0.phi, s1.phi), s0.inside, 1e-12);
            return Some(v + (p1 - v) * t);
        }
    }
    None
}
