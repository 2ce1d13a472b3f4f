//! Bounded, streamed exports: a mesh export tessellates with at most a
//! vertex budget ([`DEFAULT_MAX_EXPORT_VERTICES`] unless the operator raises
//! it with `--export-max-vertices`), on a blocking thread, and the file goes
//! out in 64 KiB chunks through a small bounded channel — the body is never
//! held whole, a client that stops reading stalls only its own export, and
//! one that disconnects stops it. IGES is written on a blocking thread too.
//!
//! Density: 8 samples per knot span when that fits the budget, else the
//! largest whole number of samples per span that fits, else (more spans
//! than the budget allows at one sample each) uniform samples scaled to it.

use crate::cad::{self, IgesMeta, Mesh};
use crate::design::DesignDoc;
use axum::body::{Body, Bytes};
use std::io::{self, Write};
use std::sync::Arc;
use tokio::sync::{mpsc, oneshot};
use vsculpt_kernel::analysis::tessellate;
use vsculpt_kernel::bspline::{BSplineSurface, KnotVector};

/// The default vertex budget of one mesh export.
pub const DEFAULT_MAX_EXPORT_VERTICES: usize = 1_000_000;
/// Samples per knot span when the budget allows.
pub const SAMPLES_PER_SPAN: usize = 8;
/// Size of one body chunk.
pub const CHUNK_BYTES: usize = 64 * 1024;
/// Chunks buffered between the writer thread and the connection.
const CHUNKS_IN_FLIGHT: usize = 4;

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ.
    Obj,
    /// Binary STL.
    Stl,
    /// glTF 2.0 with an embedded buffer.
    Gltf,
}

/// Why an export could not start.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The document's surface does not build (a bug: stored documents are valid).
    #[error("surface: {0}")]
    Surface(String),
    /// The tessellation is not a valid mesh (non-finite points).
    #[error("mesh: {0}")]
    Mesh(#[from] cad::MeshError),
    /// IGES writing failed.
    #[error("IGES: {0}")]
    Iges(#[from] cad::IgesError),
    /// The blocking task died.
    #[error("export task failed")]
    Task,
    /// The part asked for is not there or has no such export.
    #[error("{0}")]
    Part(String),
}

/// Samples along u and v for a surface of `spans_u` × `spans_v` knot spans
/// so that `samples_u · samples_v ≤ budget` (budget at least 4).
pub fn samples(spans_u: usize, spans_v: usize, budget: usize) -> (usize, usize) {
    let budget = budget.max(4);
    let (su, sv) = (spans_u.max(1), spans_v.max(1));
    for d in (1..=SAMPLES_PER_SPAN).rev() {
        let (nu, nv) = (su * d + 1, sv * d + 1);
        if nu.saturating_mul(nv) <= budget {
            return (nu, nv);
        }
    }
    // Even one sample per span is too many: scale both directions alike.
    let (nu, nv) = ((su + 1) as f64, (sv + 1) as f64);
    let f = (budget as f64 / (nu * nv)).sqrt();
    let mut a = ((nu * f).floor() as usize).max(2);
    let mut b = ((nv * f).floor() as usize).max(2);
    while a * b > budget {
        if a >= b { a -= 1 } else { b -= 1 }
    }
    (a, b)
}

fn kernel_surface(s: &crate::design::doc::SurfaceDoc) -> Result<BSplineSurface, ExportError> {
    let bad = |e: &dyn std::fmt::Display| ExportError::Surface(e.to_string());
    let u = KnotVector::new(s.u_degree, s.u_knots.clone()).map_err(|e| bad(&e))?;
    let v = KnotVector::new(s.v_degree, s.v_knots.clone()).map_err(|e| bad(&e))?;
    BSplineSurface::new(u, v, s.dpoints()).map_err(|e| bad(&e))
}

/// The surfaces an export covers: of `part` alone (an error if it is not
/// a surface or body part of `doc`), or of every visible surface and body
/// part — a body gives its six boundary faces, oriented outward.
pub fn export_surfaces(
    doc: &DesignDoc,
    part: Option<u64>,
) -> Result<Vec<(String, crate::design::doc::SurfaceDoc)>, ExportError> {
    use crate::design::part::PartBody;
    // A body part's mesh is its boundary: six faces, oriented outward.
    let pick = |p: &crate::design::part::PartDoc| match &p.body {
        PartBody::Surface(s) => Ok(Some(vec![(p.name.clone(), s.surface.clone())])),
        PartBody::Body(b) => b
            .lattice
            .faces()
            .map(|f| Some(f.into_iter().map(|(_, s)| (p.name.clone(), s)).collect()))
            .map_err(|e| ExportError::Surface(e.message)),
        _ => Ok(None),
    };
    match part {
        Some(id) => {
            let p = doc
                .part(id)
                .ok_or_else(|| ExportError::Part(format!("no part {id}")))?;
            pick(p)?.ok_or_else(|| {
                ExportError::Part(format!(
                    "part {id} is not a surface or a body: it has no mesh"
                ))
            })
        }
        None => {
            let mut out = Vec::new();
            for p in doc.parts.iter().filter(|p| p.visible) {
                out.extend(pick(p)?.unwrap_or_default());
            }
            Ok(out)
        }
    }
}

/// The network parts a mesh export covers: `part` if it is one, or every
/// visible network part when `part` is `None`.
pub fn export_networks(
    doc: &DesignDoc,
    part: Option<u64>,
) -> Vec<crate::design::part::NetworkPart> {
    use crate::design::part::PartBody;
    doc.parts
        .iter()
        .filter(|p| match part {
            Some(id) => p.id == id,
            None => p.visible,
        })
        .filter_map(|p| match &p.body {
            PartBody::Network(n) => Some(n.clone()),
            _ => None,
        })
        .collect()
}

/// Sends what it is given to the HTTP body in [`CHUNK_BYTES`] pieces,
/// blocking while the connection is behind; fails once the client is gone.
struct ChunkWriter {
    buf: Vec<u8>,
    tx: mpsc::Sender<io::Result<Bytes>>,
}

impl ChunkWriter {
    fn send(&mut self) -> io::Result<()> {
        if self.buf.is_empty() {
            return Ok(());
        }
        let chunk = std::mem::replace(&mut self.buf, Vec::with_capacity(CHUNK_BYTES));
        self.tx
            .blocking_send(Ok(Bytes::from(chunk)))
            .map_err(|_| io::Error::new(io::ErrorKind::BrokenPipe, "the client went away"))
    }
}

impl Write for ChunkWriter {
    fn write(&mut self, data: &[u8]) -> io::Result<usize> {
        self.buf.extend_from_slice(data);
        if self.buf.len() >= CHUNK_BYTES {
            self.send()?;
        }
        Ok(data.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        self.send()
    }
}

/// Runs `prepare` on a blocking thread; when it succeeds, answers with a
/// body that `write` fills chunk by chunk on that same thread.
async fn stream<T, P, W>(prepare: P, write: W) -> Result<Body, ExportError>
where
    T: Send + 'static,
    P: FnOnce() -> Result<T, ExportError> + Send + 'static,
    W: FnOnce(&T, &mut dyn Write) -> io::Result<()> + Send + 'static,
{
    let (ready_tx, ready_rx) = oneshot::channel();
    let (tx, mut rx) = mpsc::channel::<io::Result<Bytes>>(CHUNKS_IN_FLIGHT);
    tokio::task::spawn_blocking(move || {
        let prepared = match prepare() {
            Ok(p) => p,
            Err(e) => {
                let _ = ready_tx.send(Err(e));
                return;
            }
        };
        if ready_tx.send(Ok(())).is_err() {
            return;
        }
        let mut w = ChunkWriter {
            buf: Vec::with_capacity(CHUNK_BYTES),
            tx: tx.clone(),
        };
        let done = write(&prepared, &mut w).and_then(|()| w.flush());
        drop(prepared);
        if let Err(e) = done
            && e.kind() != io::ErrorKind::BrokenPipe
        {
            tracing::warn!("export failed while streaming: {e}");
            let _ = tx.blocking_send(Err(e));
        }
    });
    ready_rx.await.map_err(|_| ExportError::Task)??;
    let body = futures_util::stream::poll_fn(move |cx| rx.poll_recv(cx));
    Ok(Body::from_stream(body))
}

/// A mesh export of `doc` — one part, or every visible surface and network
/// part (a network's patches as the engine samples them) — with
/// at most `max_vertices` vertices in all (shared among the parts by their
/// number of knot spans), streamed.
pub async fn mesh(
    doc: Arc<DesignDoc>,
    part: Option<u64>,
    format: MeshFormat,
    max_vertices: usize,
) -> Result<Body, ExportError> {
    let name = match part.and_then(|id| doc.part(id)) {
        Some(p) => format!("{} - {}", doc.name, p.name),
        None => doc.name.clone(),
    };
    if let Some(p) = part.and_then(|id| doc.part(id))
        && let crate::design::part::PartBody::Dsm(d) = &p.body
    {
        // A DSM part: its implicit surface meshed within the vertex budget,
        // deformed by the body it is bound to, if any.
        let data = d.dsm.clone();
        let deform = crate::design::ffd_binding::export_deformation(&doc, p.id);
        drop(doc);
        return stream(
            move || {
                use crate::design::{dsm_engine, ffd_binding};
                let part = |e: crate::design::CommandError| ExportError::Part(e.message);
                let mut m = dsm_engine::export_kernel_mesh(&data, max_vertices).map_err(part)?;
                if let Some((rest, current)) = &deform {
                    ffd_binding::deform_export(rest, current, &mut m).map_err(part)?;
                }
                let t = dsm_engine::mesh_data(&m);
                Mesh::new(&t.positions, &t.normals, &t.indices)?;
                Ok(t)
            },
            move |t, out| write_mesh(&t.positions, &t.normals, &t.indices, format, &name, out),
        )
        .await;
    }
    let networks = export_networks(&doc, part);
    let surfaces = if networks.is_empty() || part.is_none() {
        export_surfaces(&doc, part)?
    } else {
        Vec::new()
    };
    drop(doc);
    stream(
        move || {
            let surfaces = surfaces
                .iter()
                .map(|(_, s)| kernel_surface(s))
                .collect::<Result<Vec<_>, _>>()?;
            let spans: Vec<usize> = surfaces
                .iter()
                .map(|s| s.u_knots().spans().len() * s.v_knots().spans().len())
                .collect();
            let total = spans.iter().sum::<usize>().max(1);
            let mut t = vsculpt_kernel::analysis::Tessellation::default();
            for (surface, n) in surfaces.iter().zip(&spans) {
                let (su, sv) = samples(
                    surface.u_knots().spans().len(),
                    surface.v_knots().spans().len(),
                    max_vertices * n / total,
                );
                let one = tessellate(surface, su, sv);
                let base = t.positions.len() as u32;
                t.positions.extend(one.positions);
                t.normals.extend(one.normals);
                t.indices.extend(one.indices.iter().map(|i| i + base));
            }
            // Network parts: their patches' meshes (the engine's resolution).
            for n in &networks {
                let one = crate::design::network_engine::NetworkEngine::build(n)
                    .map_err(|e| ExportError::Part(e.message))?
                    .mesh();
                let base = t.positions.len() as u32;
                t.positions.extend(one.positions);
                t.normals.extend(one.normals);
                t.indices.extend(one.indices.iter().map(|i| i + base));
            }
            Mesh::new(&t.positions, &t.normals, &t.indices)?;
            Ok(t)
        },
        move |t, out| write_mesh(&t.positions, &t.normals, &t.indices, format, &name, out),
    )
    .await
}

/// Writes a mesh validated in `prepare` (so it cannot fail validation again).
fn write_mesh(
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    indices: &[u32],
    format: MeshFormat,
    name: &str,
    mut out: &mut dyn Write,
) -> io::Result<()> {
    let mesh = Mesh::new(positions, normals, indices)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e))?;
    match format {
        MeshFormat::Obj => cad::write_obj_to(&mesh, name, &mut out),
        MeshFormat::Stl => cad::write_stl_to(&mesh, name, &mut out),
        MeshFormat::Gltf => cad::write_gltf_to(&mesh, name, &mut out),
    }
}

/// The interior of `doc`'s body parts — `part` alone (an error if it is
/// not a body part), or every visible body part — as one hexahedral VTK
/// grid (`.vtu`) with det J per point, written on a blocking thread and
/// streamed.
pub async fn vtu(doc: Arc<DesignDoc>, part: Option<u64>) -> Result<Body, ExportError> {
    use crate::design::part::PartBody;
    let lattices: Vec<_> = match part {
        Some(id) => match doc.part(id).map(|p| &p.body) {
            None => return Err(ExportError::Part(format!("no part {id}"))),
            Some(PartBody::Body(b)) => vec![b.lattice.clone()],
            Some(_) => {
                return Err(ExportError::Part(format!(
                    "part {id} is not a body: it has no interior"
                )));
            }
        },
        None => doc
            .parts
            .iter()
            .filter(|p| p.visible)
            .filter_map(|p| match &p.body {
                PartBody::Body(b) => Some(b.lattice.clone()),
                _ => None,
            })
            .collect(),
    };
    drop(doc);
    stream(
        move || {
            let mut grid = cad::HexGrid {
                scalar_name: "det_J".into(),
                ..Default::default()
            };
            for l in &lattices {
                let vol = l.volume().map_err(|e| ExportError::Surface(e.message))?;
                grid.append(&crate::design::body_engine::hex_grid(&vol));
            }
            grid.check()
                .map_err(|e| ExportError::Surface(e.to_string()))?;
            Ok(grid)
        },
        |grid, out| {
            let mut out = out;
            cad::write_vtu_to(grid, &mut out)
        },
    )
    .await
}

/// The IGES export of `doc` — one part, or every part (surfaces as entity
/// 128, curves as 126, a network's faces as trimmed refits, 144, each
/// named) — made and written on a blocking thread and streamed.
pub async fn iges(doc: Arc<DesignDoc>, part: Option<u64>) -> Result<Body, ExportError> {
    stream(
        move || {
            // On the blocking thread: a network part's faces are refitted.
            let parts = crate::design::exchange::to_iges_parts(&doc, part)
                .map_err(|e| ExportError::Part(e.message))?;
            let meta = IgesMeta::now(&doc.name, "vsculpt");
            Ok(cad::write_iges_parts(&parts, &meta)?)
        },
        |text, out| out.write_all(text.as_bytes()),
    )
    .await
}
