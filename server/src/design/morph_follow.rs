//! Parts bound to a body (the `ffd` relation, `ffd_binding`) follow the
//! body's metamorphosis as it plays (paper 002 §4 with §2.3's FFD).
//!
//! The morph time is not stored (a `body_morph` is a view, not an edit), so
//! neither is this deformation: the document keeps the bound parts as the
//! body's lattice left them, and only what viewers are sent moves. At time
//! t > 0 the body shown is B_t on the morph's common lattice, B₀ the body on
//! that lattice (the same map as the stored body); a point x of a bound part
//! is shown at B_t(B₀⁻¹(x)) (`body_engine::BodyEngine::follow`), exactly x
//! at t = 0, affine when the morph is, local as B-splines are.
//!
//! * **Surface and curve parts**: their control points (and icon positions)
//!   are carried when their frame is encoded — a handful of points, inverted
//!   on the fly (closed form for an affine box, Newton otherwise). A control
//!   point outside the body keeps its place (Sederberg–Parry's convention).
//!   A drag of such a part sends full frames (no drag stream) while the
//!   body is morphed.
//! * **DSM parts**: the mesh shown (already deformed by the body's lattice)
//!   is embedded once per mesh and body state ([`MorphMeshes`]) and every
//!   frame of the morph recomputes the vertices from that embedding, with
//!   area-weighted normals; vertices outside keep their places.

use super::body_engine::BodyEngines;
use super::doc::DesignDoc;
use super::error::{CommandError, ErrorKind};
use super::part::{PartBody, RelationKind};
use glam::DVec3;
use std::collections::BTreeMap;
use vsculpt_kernel::body::{BSplineVolume, Embedding, Ffd};
use vsculpt_kernel::dsm::Mesh;

/// How far from the body a point may be after inversion and still count as
/// inside, relative to the diagonal of the lattice's bounding box (as
/// `ffd_binding::INSIDE_TOLERANCE`).
pub const INSIDE_TOLERANCE: f64 = 1e-9;

/// The absolute inside tolerance of `vol`.
pub fn tolerance(vol: &BSplineVolume) -> f64 {
    let (lo, hi) = vol
        .points()
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| {
            (l.min(*p), h.max(*p))
        });
    INSIDE_TOLERANCE * (hi - lo).length().max(1e-300)
}

/// The body part that part `part` is bound to in `doc`, if any.
pub fn body_of(doc: &DesignDoc, part: u64) -> Option<u64> {
    doc.relations.iter().find_map(|r| match &r.kind {
        RelationKind::Ffd { body, part: p, .. } if *p == part => Some(*body),
        _ => None,
    })
}

/// The parts bound to body `body` in `doc`.
pub fn bound_parts(doc: &DesignDoc, body: u64) -> Vec<u64> {
    doc.relations
        .iter()
        .filter_map(|r| match &r.kind {
            RelationKind::Ffd { body: b, part, .. } if *b == body => Some(*part),
            _ => None,
        })
        .collect()
}

/// `points` carried by the morph deformation `follow` (points outside the
/// body keep their places).
pub fn carry(follow: &Ffd, points: &[DVec3]) -> Vec<DVec3> {
    let tol = tolerance(follow.rest());
    points
        .iter()
        .map(|&x| follow.deform_point(x, tol))
        .collect()
}

/// One bound DSM part's mesh as the morph shows it.
struct MorphMesh {
    body: u64,
    /// The mesh it was embedded from (the part's mesh before the morph).
    base: Vec<DVec3>,
    /// The body's lattice at embedding (the morph's source).
    rest: Vec<DVec3>,
    emb: Embedding,
    mesh: Mesh,
}

/// The morphed meshes of the DSM parts bound to bodies shown at t > 0.
#[derive(Default)]
pub struct MorphMeshes {
    parts: BTreeMap<u64, MorphMesh>,
}

impl MorphMeshes {
    /// Brings the morphed meshes in step with `doc`'s `ffd` relations of
    /// DSM parts, the bodies' morph times (`bodies`) and the meshes the
    /// parts show before the morph (`mesh_of`). Returns the parts whose
    /// morphed mesh appeared, changed or went away. On an error nothing is
    /// kept (the next update rebuilds).
    pub fn update<'a>(
        &mut self,
        doc: &DesignDoc,
        bodies: &BodyEngines,
        mesh_of: impl Fn(u64) -> Option<&'a Mesh>,
    ) -> Result<Vec<u64>, CommandError> {
        let kernel = |e: vsculpt_kernel::body::BodyError| {
            CommandError::new(ErrorKind::InvalidValue, format!("morph ffd: {e}"))
        };
        let mut old = std::mem::take(&mut self.parts);
        let mut changed = Vec::new();
        for r in &doc.relations {
            let RelationKind::Ffd { body, part, .. } = &r.kind else {
                continue;
            };
            let (Some(PartBody::Dsm(_)), Some(follow), Some(mesh)) = (
                doc.part(*part).map(|p| &p.body),
                bodies.follow(*body),
                mesh_of(*part),
            ) else {
                continue;
            };
            let reuse = old.remove(part).filter(|e| {
                e.body == *body && e.base == mesh.positions && e.rest == follow.rest().points()
            });
            let mut e = match reuse {
                Some(e) => e,
                None => {
                    // Embedding uses the rest lattice only; the residual is
                    // taken against it too.
                    let mut emb = follow
                        .embed(&mesh.positions, tolerance(follow.rest()))
                        .map_err(kernel)?;
                    emb.carry_residual(follow).map_err(kernel)?;
                    MorphMesh {
                        body: *body,
                        base: mesh.positions.clone(),
                        rest: follow.rest().points().to_vec(),
                        emb,
                        mesh: mesh.clone(),
                    }
                }
            };
            follow
                .deform_all(&e.emb, &mut e.mesh.positions)
                .map_err(kernel)?;
            super::ffd_binding::renormal(&mut e.mesh);
            changed.push(*part);
            self.parts.insert(*part, e);
        }
        changed.extend(old.into_keys().filter(|k| doc.part(*k).is_some()));
        changed.sort_unstable();
        changed.dedup();
        Ok(changed)
    }

    /// Part `id`'s morphed mesh, if it is a DSM part bound to a body shown
    /// at t > 0.
    pub fn mesh(&self, id: u64) -> Option<&Mesh> {
        self.parts.get(&id).map(|e| &e.mesh)
    }
}
