//! Density Spatial Model parts (paper 001) on the server: the document's
//! [`DsmPart`] (the wire's `DsmData`, validated before the kernel sees it),
//! how a `dsm_edit` changes it ([`apply_edit`]), the kernel model built from
//! it ([`build_model`]), and [`DsmEngine`], which holds every DSM part's
//! current mesh and encodes it as a mesh frame (kind 3).
//!
//! Choices made here:
//! * A net primitive is rebuilt by a fresh inverse transformation (eqs. 8–11)
//!   whenever its part changes: a `drag_node` is one undoable edit, not a
//!   stream of frames, so the kernel's `NetDrag` factorisation update is not
//!   used here. The net is centred on `at` in the plane normal to `axis`.
//! * A group with `op: none` enters no term of eq. (7) (it only feeds later
//!   groups that incorporate it); `add` / `subtract` are one-group terms.
//! * A part with no positive primitive meshes to the empty mesh.
//! * The mesh is rebuilt only when the part's data changed (an unchanged part
//!   keeps its mesh across rebuilds of other parts).
//! * An edit re-meshes incrementally: the part keeps the kernel's
//!   [`IncrementalMesh`] (every sampled leaf), the edited document is built
//!   into a fresh model, and only the leaves within the changed primitives'
//!   influence are sampled again; the kernel re-meshes everything when the
//!   grid (which spans the model's bounds) or the groups' structure changed.
//!   The mesh is the one a part built from the edited document has, vertex
//!   for vertex. A new part, a load and a part whose model is empty mesh from
//!   scratch; an edit that fails changes nothing.

use super::doc::IconDoc;
use super::error::{CommandError, ErrorKind};
use super::model::MeshData;
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use vsculpt_kernel::dsm::{
    DEFAULT_TAU, DensityPrimitive, DensityShape, GeometricPrimitive, GeometricShape, Grid, Group,
    IncrementalMesh, InverseOptions, Mesh, MeshOptions, Model, PassingPointsNet, Placement, Sign,
    inverse_transform, mesh,
};
use vsculpt_protocol::dsm::{DsmData, DsmEdit, DsmGroup, DsmOp, DsmPrimitive, DsmPrimitiveShape};
use vsculpt_protocol::{ErrorCode, ProtocolError, mesh_frame::MeshFrame};

/// A DSM part in the document: its shape data. A DSM part has no icons and
/// no material; `icons` is always empty (it exists so every part kind can
/// lend a list of icons).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DsmPart {
    /// Groups, primitives, D_e and the mesh resolution.
    pub dsm: DsmData,
    /// Always empty.
    #[serde(default, skip_serializing)]
    pub icons: Vec<IconDoc>,
}

fn invalid(msg: impl Into<String>) -> CommandError {
    CommandError::new(ErrorKind::InvalidValue, msg)
}

/// A protocol validation error as a command error (same class).
fn from_protocol(e: ProtocolError) -> CommandError {
    let kind = match e.code {
        ErrorCode::NotFinite => ErrorKind::NotFinite,
        _ => ErrorKind::InvalidValue,
    };
    CommandError::new(kind, e.message)
}

impl DsmPart {
    /// A part of `dsm`.
    pub fn new(dsm: DsmData) -> Self {
        Self {
            dsm,
            icons: Vec::new(),
        }
    }

    /// Checks every number, size, id and group reference (untrusted data
    /// from the network or the store), and that it has no icons.
    pub fn validate(&self) -> Result<(), CommandError> {
        if !self.icons.is_empty() {
            return Err(CommandError::new(
                ErrorKind::Unsupported,
                "a dsm part has no icons",
            ));
        }
        self.dsm.validate().map_err(from_protocol)
    }
}

fn unknown_primitive(id: u64) -> CommandError {
    invalid(format!("no primitive {id} in this dsm part"))
}

fn primitive_mut(data: &mut DsmData, id: u64) -> Result<&mut DsmPrimitive, CommandError> {
    data.groups
        .iter_mut()
        .flat_map(|g| g.primitives.iter_mut())
        .find(|p| p.id == id)
        .ok_or_else(|| unknown_primitive(id))
}

fn group_index(data: &mut DsmData, group: u32) -> Result<usize, CommandError> {
    let k = group as usize;
    if k > data.groups.len() {
        return Err(invalid(format!(
            "no group {group}: the part has {} (give {} to append one)",
            data.groups.len(),
            data.groups.len()
        )));
    }
    if k == data.groups.len() {
        data.groups.push(DsmGroup {
            op: DsmOp::Add,
            incorporated: Vec::new(),
            primitives: Vec::new(),
        });
    }
    Ok(k)
}

/// `data` with `edit` applied, fully validated; on error `data` is left as
/// it was.
pub fn apply_edit(data: &DsmData, edit: &DsmEdit) -> Result<DsmData, CommandError> {
    edit.validate().map_err(from_protocol)?;
    let mut d = data.clone();
    match edit {
        DsmEdit::AddPrimitive { group, primitive } => {
            if d.primitive(primitive.id).is_some() {
                return Err(CommandError::new(
                    ErrorKind::Conflict,
                    format!("primitive id {} is already in this dsm part", primitive.id),
                ));
            }
            let k = group_index(&mut d, *group)?;
            d.groups[k].primitives.push(primitive.clone());
        }
        DsmEdit::RemovePrimitive { id } => {
            let (k, _) = d.primitive(*id).ok_or_else(|| unknown_primitive(*id))?;
            d.groups[k].primitives.retain(|p| p.id != *id);
        }
        DsmEdit::MovePrimitive { id, at } => primitive_mut(&mut d, *id)?.at = *at,
        DsmEdit::ResizePrimitive { id, shape } => {
            let p = primitive_mut(&mut d, *id)?;
            if p.shape.type_name() != shape.type_name() {
                return Err(invalid(format!(
                    "primitive {id} is a {}: a resize may not make it a {}",
                    p.shape.type_name(),
                    shape.type_name()
                )));
            }
            p.shape = shape.clone();
        }
        DsmEdit::SetDensity {
            id,
            density,
            reducing,
        } => match &mut primitive_mut(&mut d, *id)?.shape {
            DsmPrimitiveShape::DensitySphere {
                density: dd,
                reducing: a,
            }
            | DsmPrimitiveShape::DensityPipe {
                density: dd,
                reducing: a,
                ..
            } => {
                *dd = *density;
                *a = *reducing;
            }
            other => {
                return Err(CommandError::new(
                    ErrorKind::Incompatible,
                    format!(
                        "primitive {id} is a {}: set_density applies to density_sphere and density_pipe",
                        other.type_name()
                    ),
                ));
            }
        },
        DsmEdit::ChangeGroup { id, group } => {
            let (from, _) = d.primitive(*id).ok_or_else(|| unknown_primitive(*id))?;
            let k = group_index(&mut d, *group)?;
            let i = d.groups[from]
                .primitives
                .iter()
                .position(|p| p.id == *id)
                .ok_or_else(|| unknown_primitive(*id))?;
            let p = d.groups[from].primitives.remove(i);
            d.groups[k].primitives.push(p);
        }
        DsmEdit::DragNode { id, node, height } => match &mut primitive_mut(&mut d, *id)?.shape {
            DsmPrimitiveShape::Net { heights, .. } => {
                let n = heights.len();
                let h = heights.get_mut(*node as usize).ok_or_else(|| {
                    invalid(format!("net {id} has {n} nodes: there is no node {node}"))
                })?;
                *h = *height;
            }
            other => {
                return Err(CommandError::new(
                    ErrorKind::Incompatible,
                    format!(
                        "primitive {id} is a {}: only a net has nodes to drag",
                        other.type_name()
                    ),
                ));
            }
        },
    }
    d.validate().map_err(from_protocol)?;
    Ok(d)
}

fn kernel(id: u64, e: impl std::fmt::Display) -> CommandError {
    invalid(format!("dsm primitive {id}: {e}"))
}

fn placement(p: &DsmPrimitive) -> Result<Placement, CommandError> {
    let at = DVec3::from(p.at);
    match p.axis {
        Some(a) => Placement::with_axis(at, DVec3::from(a)).map_err(|e| kernel(p.id, e)),
        None => Ok(Placement::at(at)),
    }
}

/// Adds primitive `p` to kernel group `g`.
fn add_primitive(g: &mut Group, p: &DsmPrimitive, de: f64) -> Result<(), CommandError> {
    let pl = placement(p)?;
    let geometric = |shape, negative: bool| -> Result<GeometricPrimitive, CommandError> {
        let gp = GeometricPrimitive::new(shape, pl).map_err(|e| kernel(p.id, e))?;
        Ok(if negative { gp.negated() } else { gp })
    };
    match &p.shape {
        DsmPrimitiveShape::Box { half, negative } => g.geometric.push(geometric(
            GeometricShape::Box {
                half: DVec3::from(*half),
            },
            *negative,
        )?),
        DsmPrimitiveShape::Cylinder {
            radius,
            half_height,
            negative,
        } => g.geometric.push(geometric(
            GeometricShape::Cylinder {
                radius: *radius,
                half_height: *half_height,
            },
            *negative,
        )?),
        DsmPrimitiveShape::Sphere { radius, negative } => g.geometric.push(geometric(
            GeometricShape::Sphere { radius: *radius },
            *negative,
        )?),
        DsmPrimitiveShape::DensitySphere { density, reducing } => g.density.push(
            DensityPrimitive::new(
                DensityShape::Sphere { radius: 0.0 },
                pl,
                *density,
                *reducing,
            )
            .map_err(|e| kernel(p.id, e))?,
        ),
        DsmPrimitiveShape::DensityPipe {
            length,
            density,
            reducing,
        } => g.density.push(
            DensityPrimitive::new(
                DensityShape::Pipe {
                    radius: 0.0,
                    half_length: 0.5 * length,
                },
                pl,
                *density,
                *reducing,
            )
            .map_err(|e| kernel(p.id, e))?,
        ),
        DsmPrimitiveShape::Net {
            nu,
            nv,
            spacing,
            heights,
            reducing,
        } => {
            let spacing = DVec2::from(*spacing);
            let half = spacing * DVec2::new((*nu - 1) as f64, (*nv - 1) as f64) * 0.5;
            let net =
                PassingPointsNet::regular(-half, spacing, *nu as usize, *nv as usize, heights)
                    .map_err(|e| kernel(p.id, e))?;
            let mut opts = InverseOptions::for_net(&net, *reducing);
            opts.de = de;
            let (surface, _) = inverse_transform(&net, &opts).map_err(|e| kernel(p.id, e))?;
            let (lo, hi) = net.uv_box();
            g.density
                .push(surface.primitive(lo, hi, pl).map_err(|e| kernel(p.id, e))?);
        }
    }
    Ok(())
}

/// The kernel model of `data` (validated first).
pub fn build_model(data: &DsmData) -> Result<Model, CommandError> {
    data.validate().map_err(from_protocol)?;
    let mut model = Model::new(data.de, DEFAULT_TAU).map_err(|e| invalid(e.to_string()))?;
    for (k, g) in data.groups.iter().enumerate() {
        let mut group = Group {
            incorporated: g.incorporated.iter().map(|&m| m as usize).collect(),
            ..Group::default()
        };
        for p in &g.primitives {
            add_primitive(&mut group, p, data.de)?;
        }
        let k2 = model
            .add_group(group)
            .map_err(|e| invalid(format!("dsm group {k}: {e}")))?;
        let sign = match g.op {
            DsmOp::Add => Some(Sign::Add),
            DsmOp::Subtract => Some(Sign::Subtract),
            DsmOp::None => None,
        };
        if let Some(sign) = sign {
            model
                .add_term(vec![k2], sign)
                .map_err(|e| invalid(format!("dsm group {k}: {e}")))?;
        }
    }
    Ok(model)
}

/// The mesh of `data` at `cells` cells along the longest side of its bounds
/// (the empty mesh when nothing is positive).
pub fn mesh_at(data: &DsmData, cells: u32) -> Result<Mesh, CommandError> {
    let model = build_model(data)?;
    if model.bounds().is_none() {
        return Ok(Mesh::default());
    }
    let (m, _) = mesh(
        &model,
        MeshOptions {
            cells: cells as usize,
        },
    )
    .map_err(|e| invalid(format!("dsm mesh: {e}")))?;
    Ok(m)
}

/// `m` as an export tessellation (f32).
/// `m` in the export's f32 form.
pub fn mesh_data(m: &Mesh) -> MeshData {
    MeshData {
        positions: m.positions.iter().map(|p| p.as_vec3().to_array()).collect(),
        normals: m.normals.iter().map(|n| n.as_vec3().to_array()).collect(),
        indices: m.triangles.iter().flatten().copied().collect(),
    }
}

/// The mesh of `data` for an export with at most `max_vertices` vertices:
/// at the part's own resolution, or coarser (down to 8 cells) until it fits;
/// a clear error if even that is over the budget.
pub fn export_mesh(data: &DsmData, max_vertices: usize) -> Result<MeshData, CommandError> {
    export_kernel_mesh(data, max_vertices).map(|m| mesh_data(&m))
}

/// [`export_mesh`] before the conversion to f32 (for a bound part, which is
/// deformed in f64 first: `ffd_binding::deform_export`).
pub fn export_kernel_mesh(data: &DsmData, max_vertices: usize) -> Result<Mesh, CommandError> {
    let mut cells = data.cells;
    loop {
        let m = mesh_at(data, cells)?;
        let n = m.positions.len();
        if n <= max_vertices {
            return Ok(m);
        }
        if cells <= 8 {
            return Err(invalid(format!(
                "the dsm mesh has {n} vertices even at 8 cells; the export budget is {max_vertices}"
            )));
        }
        // Vertices grow as cells²: aim just under the budget.
        let f = (max_vertices as f64 / n as f64).sqrt() * 0.95;
        cells = ((cells as f64 * f).floor() as u32).clamp(8, cells - 1);
    }
}

/// One DSM part as the engine holds it: its data, its mesh and what the
/// mesher sampled (None when the model is empty).
struct Shape {
    data: DsmData,
    mesh: Mesh,
    sampled: Option<IncrementalMesh>,
}

/// The kernel model of `data` and its grid at the part's resolution (None:
/// nothing is positive, the mesh is empty).
fn model_and_grid(data: &DsmData) -> Result<Option<(Model, Grid)>, CommandError> {
    let model = build_model(data)?;
    if model.bounds().is_none() {
        return Ok(None);
    }
    let grid = Grid::on_lattice(&model, data.cells as usize)
        .map_err(|e| invalid(format!("dsm mesh: {e}")))?;
    Ok(Some((model, grid)))
}

/// The DSM parts of a design with their meshes.
#[derive(Default)]
pub struct DsmEngine {
    parts: BTreeMap<u64, Shape>,
}

impl DsmEngine {
    /// Builds and meshes part `id` from `part` (kept as it is when its data
    /// did not change; re-meshed incrementally when the part was meshed
    /// before). On error nothing changes.
    pub fn insert(&mut self, id: u64, part: &DsmPart) -> Result<(), CommandError> {
        part.validate()?;
        if self.parts.get(&id).is_some_and(|s| s.data == part.dsm) {
            return Ok(());
        }
        let built = model_and_grid(&part.dsm)?;
        let previous = self.parts.remove(&id).and_then(|s| s.sampled);
        let sampled = built.map(|(model, grid)| match previous {
            Some(mut inc) => {
                inc.update(model, grid);
                inc
            }
            None => IncrementalMesh::new(model, grid),
        });
        let mesh = sampled
            .as_ref()
            .map_or_else(Mesh::default, |inc| inc.mesh().0);
        self.parts.insert(
            id,
            Shape {
                data: part.dsm.clone(),
                mesh,
                sampled,
            },
        );
        Ok(())
    }

    /// Forgets part `id`; whether it was a DSM part.
    pub fn remove(&mut self, id: u64) -> bool {
        self.parts.remove(&id).is_some()
    }

    /// Whether part `id` is a DSM part here.
    pub fn contains(&self, id: u64) -> bool {
        self.parts.contains_key(&id)
    }

    /// Part `id`'s mesh.
    pub fn mesh(&self, id: u64) -> Option<&Mesh> {
        self.parts.get(&id).map(|s| &s.mesh)
    }

    /// Part `id`'s mesh as an export tessellation.
    pub fn mesh_data(&self, id: u64) -> Option<MeshData> {
        self.mesh(id).map(mesh_data)
    }

    /// Part `id`'s mesh frame (kind 3) at revision `rev` of `design`,
    /// quantised on the part's meshing grid ([`grid_cube`]).
    pub fn frame(&self, design: u64, id: u64, rev: u64, drag: bool) -> Option<axum::body::Bytes> {
        let shape = self.parts.get(&id)?;
        let cube = shape.sampled.as_ref().map(|inc| grid_cube(inc.grid()));
        mesh_frame(&shape.mesh, design, id, rev, drag, cube)
    }
}

/// The cube (origin, extent) a DSM part's mesh frame is quantised on: its
/// meshing grid's, which holds every vertex (the grid spans the model's
/// bounds with two to three cells to spare). The grid is on a lattice
/// (`Grid::on_lattice`) and stays put while a drag moves the model's bounds
/// less than a cell, so a vertex the mesher kept keeps its quantised
/// position and the frame goes as a delta ([`super::dsm_delta`]).
pub fn grid_cube(grid: &Grid) -> ([f64; 3], f64) {
    (
        grid.origin.to_array(),
        grid.dims.max_element() as f64 * grid.h,
    )
}

/// `m` as the mesh frame (kind 3) of part `id` at revision `rev` of
/// `design` (flagged as a drag frame if `drag`), quantised on `cube` when
/// given ([`grid_cube`]), else on the mesh's bounding cube. The kernel's
/// meshes are finite and in their grid, so quantising cannot fail; if it
/// ever did, the part would send no frame rather than a bad one.
pub fn mesh_frame(
    m: &Mesh,
    design: u64,
    id: u64,
    rev: u64,
    drag: bool,
    cube: Option<([f64; 3], f64)>,
) -> Option<axum::body::Bytes> {
    let positions: Vec<[f64; 3]> = m.positions.iter().map(|p| p.to_array()).collect();
    let normals: Vec<[f64; 3]> = m.normals.iter().map(|n| n.to_array()).collect();
    let flags = if drag {
        vsculpt_protocol::frame::FLAG_DRAG
    } else {
        0
    };
    let ids = (design, id, rev);
    let frame = match cube {
        Some(cube) => {
            MeshFrame::quantise_in(ids, flags, cube, &positions, &normals, &m.triangles).ok()?
        }
        None => MeshFrame::quantise(ids, flags, &positions, &normals, &m.triangles).ok()?,
    };
    frame.encode().ok().map(axum::body::Bytes::from)
}

#[cfg(test)]
mod tests {
    use super::*;
    use vsculpt_protocol::dsm::DsmGroup;

    fn sphere(id: u64, at: [f64; 3], radius: f64) -> DsmPrimitive {
        DsmPrimitive {
            id,
            at,
            axis: None,
            shape: DsmPrimitiveShape::Sphere {
                radius,
                negative: false,
            },
        }
    }

    fn one_sphere() -> DsmData {
        DsmData {
            de: 1.0,
            cells: 16,
            groups: vec![DsmGroup {
                op: DsmOp::Add,
                incorporated: Vec::new(),
                primitives: vec![sphere(1, [0.0, 0.0, 0.0], 1.0)],
            }],
        }
    }

    #[test]
    fn the_demo_handset_meshes_closed_and_inside_its_body() {
        let m = mesh_at(&super::super::demo::handset_dsm(), 40).unwrap();
        assert!(m.triangles.len() > 1000, "{} triangles", m.triangles.len());
        // Closed, of genus 1: the lanyard hole goes through.
        assert_eq!(m.euler_characteristic(), 0);
        // The subtracted cylinder shows: vertices on its wall, halfway up.
        let h = 3.8 / 40.0;
        let wall = m.positions.iter().filter(|p| {
            let r = ((p.x - 1.15).powi(2) + p.y * p.y).sqrt();
            (r - 0.15).abs() < h && p.z.abs() < 0.2
        });
        assert!(wall.count() >= 4);
        for p in &m.positions {
            // Within the box grown by the end caps' radius ln(3)/3 and the net's top.
            assert!(p.x.abs() <= 1.5 + 3f64.ln() / 3.0 + h, "{p}");
            assert!(p.z.abs() <= 1.0, "{p}");
            // Nothing inside the hole.
            assert!(((p.x - 1.15).powi(2) + p.y * p.y).sqrt() >= 0.15 - h, "{p}");
        }
    }

    #[test]
    fn edits_change_only_what_they_name_and_refusals_change_nothing() {
        let d = one_sphere();
        let moved = apply_edit(
            &d,
            &DsmEdit::MovePrimitive {
                id: 1,
                at: [0.5, 0.0, 0.0],
            },
        )
        .unwrap();
        assert_eq!(moved.groups[0].primitives[0].at, [0.5, 0.0, 0.0]);
        let bad = [
            DsmEdit::MovePrimitive {
                id: 9,
                at: [0.0; 3],
            },
            DsmEdit::MovePrimitive {
                id: 1,
                at: [f64::NAN, 0.0, 0.0],
            },
            DsmEdit::ChangeGroup { id: 1, group: 7 },
            DsmEdit::DragNode {
                id: 1,
                node: 0,
                height: 1.0,
            },
            DsmEdit::ResizePrimitive {
                id: 1,
                shape: DsmPrimitiveShape::DensitySphere {
                    density: 2.0,
                    reducing: 1.0,
                },
            },
            DsmEdit::AddPrimitive {
                group: 0,
                primitive: sphere(1, [0.0; 3], 1.0),
            },
        ];
        for e in bad {
            assert!(apply_edit(&d, &e).is_err(), "{e:?} accepted");
        }
        let grown = apply_edit(&d, &DsmEdit::ChangeGroup { id: 1, group: 1 }).unwrap();
        assert_eq!(grown.groups.len(), 2);
        assert!(grown.groups[0].primitives.is_empty());
    }

    #[test]
    fn an_export_over_budget_is_meshed_coarser_to_fit() {
        let mut d = one_sphere();
        d.cells = 64;
        let full = mesh_at(&d, 64).unwrap().positions.len();
        let m = export_mesh(&d, full / 3).unwrap();
        assert!(m.positions.len() <= full / 3 && m.positions.len() > full / 20);
        assert!(export_mesh(&d, 10).is_err());
    }
}
