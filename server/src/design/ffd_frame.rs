//! The mesh frame of a DSM part bound to a body (issue 13), kept encoded and
//! patched where a lattice edit moved vertices, so that a lattice move costs
//! the vertices it moved rather than an encoding of the whole mesh.
//!
//! A bound mesh keeps its triangles; a lattice edit moves only the vertices
//! in the moved points' support ([`super::ffd_binding`]) and the normals
//! around them. The frame is quantised on a cube fixed while the mesh stays
//! in it ([`cube`]: the mesh's box grown by a margin), so a vertex that did
//! not move keeps its bytes; [`FfdFrame::moved`] re-quantises the vertices an
//! update touched into the kept bytes
//! ([`vsculpt_protocol::mesh_patch::PatchedMeshFrame`]), and
//! [`FfdFrame::frame`] hands out the whole frame with the mesh delta (kind 8)
//! from the frame handed out before. The whole frame is the bytes a fresh
//! encoding on that cube gives (checked in debug builds at every frame, and
//! by `server/tests/ffd_delta.rs` against a fresh encode after every move);
//! a vertex leaving the cube makes a new cube and a whole frame.

use super::dsm_delta::MeshDeltaFrame;
use axum::body::Bytes;
use std::sync::Mutex;
use vsculpt_kernel::dsm::Mesh;
use vsculpt_protocol::mesh_patch::PatchedMeshFrame;

/// The margin of the cube around the mesh's box, as a fraction of its
/// longest side on each end: lattice moves of up to this much keep the
/// cube (and deltas); the quantisation step grows by 1 + 2·MARGIN.
pub const MARGIN: f64 = 0.125;

/// The cube a bound mesh's frame is quantised on: its box's longest side
/// grown by [`MARGIN`] at both ends, centred on the box.
pub fn cube(m: &Mesh) -> ([f64; 3], f64) {
    let (lo, hi) =
        m.positions
            .iter()
            .fold(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]), |(l, h), p| {
                let p = p.to_array();
                (
                    [0, 1, 2].map(|a| l[a].min(p[a])),
                    [0, 1, 2].map(|a| h[a].max(p[a])),
                )
            });
    if m.positions.is_empty() {
        return ([0.0; 3], 0.0);
    }
    let side = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    let extent = side * (1.0 + 2.0 * MARGIN);
    (
        [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]) - 0.5 * extent),
        extent,
    )
}

/// A bound mesh's frame, kept encoded (built at the first frame asked).
#[derive(Debug, Default)]
pub struct FfdFrame {
    /// The kept frame and the design it is of.
    kept: Mutex<Option<(u64, PatchedMeshFrame)>>,
}

impl FfdFrame {
    /// The vertices `moved` of `m` changed (position or normal): their
    /// records are re-quantised into the kept frame. A vertex outside the
    /// cube drops the frame (the next one is made whole on a new cube).
    pub fn moved(&mut self, m: &Mesh, moved: impl IntoIterator<Item = u32>) {
        let kept = self.kept.get_mut().unwrap_or_else(|e| e.into_inner());
        let Some((_, frame)) = kept else {
            return;
        };
        for v in moved {
            let i = v as usize;
            let (Some(p), Some(n)) = (m.positions.get(i), m.normals.get(i)) else {
                *kept = None;
                return;
            };
            if frame.set_vertex(i, p.to_array(), n.to_array()).is_err() {
                *kept = None;
                return;
            }
        }
    }

    /// Drops the kept frame: the mesh changed in more than vertex places
    /// (re-meshed, or every vertex recomputed).
    pub fn forget(&mut self) {
        *self.kept.get_mut().unwrap_or_else(|e| e.into_inner()) = None;
    }

    /// The frame of `m` (part `part` of `design`, revision `rev`, flagged
    /// as a drag frame if `drag`) and, when the frame handed out before is
    /// older and was the whole frame then, the delta from it. None when the
    /// mesh cannot be quantised (non-finite).
    pub fn frame(
        &self,
        m: &Mesh,
        design: u64,
        part: u64,
        rev: u64,
        drag: bool,
    ) -> Option<(Bytes, Option<MeshDeltaFrame>)> {
        let flags = if drag {
            vsculpt_protocol::frame::FLAG_DRAG
        } else {
            0
        };
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        let fits = matches!(&*kept, Some((d, f)) if *d == design && f.frame().part == part && f.len() == m.positions.len());
        if !fits {
            let positions: Vec<[f64; 3]> = m.positions.iter().map(|p| p.to_array()).collect();
            let normals: Vec<[f64; 3]> = m.normals.iter().map(|n| n.to_array()).collect();
            let f = PatchedMeshFrame::new(
                (design, part, rev),
                flags,
                cube(m),
                &positions,
                &normals,
                &m.triangles,
            )
            .ok()?;
            *kept = Some((design, f));
        }
        let (_, f) = kept.as_mut()?;
        #[cfg(debug_assertions)]
        let on = cube_of(f.frame());
        let take = f.take(rev, flags);
        let whole = Bytes::copy_from_slice(take.frame);
        #[cfg(debug_assertions)]
        {
            let positions: Vec<[f64; 3]> = m.positions.iter().map(|p| p.to_array()).collect();
            let normals: Vec<[f64; 3]> = m.normals.iter().map(|n| n.to_array()).collect();
            let fresh = vsculpt_protocol::MeshFrame::quantise_in(
                (design, part, rev),
                flags,
                on,
                &positions,
                &normals,
                &m.triangles,
            )
            .and_then(|x| x.encode());
            debug_assert!(
                fresh.as_deref() == Ok(&whole[..]),
                "a patched mesh frame differs from a fresh encoding"
            );
        }
        let delta = take.delta.map(|(base, bytes)| MeshDeltaFrame {
            base,
            frame: Bytes::from(bytes),
            deflated: Default::default(),
        });
        Some((whole, delta))
    }
}

/// The cube (origin, extent) a frame was quantised on, as f64 (its f32
/// origin and step: quantising on it again gives the same origin and step).
#[cfg(debug_assertions)]
fn cube_of(f: &vsculpt_protocol::MeshFrame) -> ([f64; 3], f64) {
    (f.origin.map(f64::from), f.step as f64 * 65535.0)
}
