//! A mesh frame (kind 3) kept encoded and patched in place where vertices
//! move, with each patch offered as a mesh delta (kind 8).
//!
//! For a mesh whose triangles stay and whose vertices move in place — a DSM
//! part deformed by the body it is bound to (FFD): a lattice edit moves only
//! the vertices in the moved points' support — encoding the whole frame at
//! every change costs far more than the change. [`PatchedMeshFrame`] holds the
//! whole frame's bytes and its quantised records; [`set_vertex`] re-quantises
//! one vertex on the frame's fixed cube and overwrites its records in the
//! bytes where they changed, noting the vertex; [`take`] stamps the revision
//! and flags into the header and gives the delta from the revision taken
//! before: the noted vertices as literal vertices, the triangles touching one
//! as literal triangles, everything else copied from the base. The bytes are
//! at every take exactly the whole frame's (`MeshFrame::encode` of the same
//! vertices; `protocol/tests/mesh_patch.rs` compares), and the delta applied to
//! the base gives them.
//!
//! [`set_vertex`]: PatchedMeshFrame::set_vertex
//! [`take`]: PatchedMeshFrame::take

use crate::error::ProtocolError;
use crate::mesh_delta::{LITERAL, MeshDelta, Run};
use crate::mesh_frame::{MESH_HEADER_BYTES, MeshFrame, quantise_normal, quantise_position};

/// The whole mesh frame, encoded, with the vertices changed since the last
/// [`take`](Self::take).
#[derive(Clone, Debug)]
pub struct PatchedMeshFrame {
    /// The quantised frame (its revision and flags those of the last take).
    frame: MeshFrame,
    /// `frame` encoded, kept equal to `frame.encode()`.
    bytes: Vec<u8>,
    /// Vertices whose records changed since the last take, and a mark per
    /// vertex.
    dirty: Vec<u32>,
    marked: Vec<bool>,
    /// The revision of the last take, when its bytes are what was handed
    /// out at that revision (a delta may start from it).
    base: Option<u64>,
    /// The newest revision taken.
    last: Option<u64>,
}

/// One take: the whole frame and, when there is a base, the delta from it.
#[derive(Clone, Debug)]
pub struct Take<'a> {
    /// The whole mesh frame (kind 3) at the revision taken.
    pub frame: &'a [u8],
    /// The encoded mesh delta (kind 8) from revision `base` to this frame,
    /// if one is shorter than the frame.
    pub delta: Option<(u64, Vec<u8>)>,
}

impl PatchedMeshFrame {
    /// The frame of a mesh quantised on the fixed cube (`origin`, `extent`)
    /// (as [`MeshFrame::quantise_in`]: a position more than a step outside
    /// is `out_of_range`), at revision `ids.2`. No delta starts from it until
    /// it is [taken](Self::take).
    pub fn new(
        ids: (u64, u64, u64),
        flags: u16,
        cube: ([f64; 3], f64),
        positions: &[[f64; 3]],
        normals: &[[f64; 3]],
        triangles: &[[u32; 3]],
    ) -> Result<Self, ProtocolError> {
        let frame = MeshFrame::quantise_in(ids, flags, cube, positions, normals, triangles)?;
        let bytes = frame.encode()?;
        let n = frame.positions.len();
        Ok(Self {
            frame,
            bytes,
            dirty: Vec::new(),
            marked: vec![false; n],
            base: None,
            last: None,
        })
    }

    /// Vertices of the mesh.
    pub fn len(&self) -> usize {
        self.frame.positions.len()
    }

    /// Whether the mesh has no vertices.
    pub fn is_empty(&self) -> bool {
        self.frame.positions.is_empty()
    }

    /// The quantised frame as it stands (revision and flags of the last take).
    pub fn frame(&self) -> &MeshFrame {
        &self.frame
    }

    /// Vertex `i` moved to `position` with `normal`: re-quantised on the
    /// frame's cube, its records overwritten where they changed. Returns
    /// whether they changed. A non-finite value is `not_finite`, a position
    /// more than a step outside the cube `out_of_range`, an index beyond the
    /// mesh `malformed`; then nothing changes (the caller makes a new frame).
    pub fn set_vertex(
        &mut self,
        i: usize,
        position: [f64; 3],
        normal: [f64; 3],
    ) -> Result<bool, ProtocolError> {
        let n = self.len();
        if i >= n {
            return Err(ProtocolError::new(
                crate::error::ErrorCode::Malformed,
                format!("vertex {i} of a mesh of {n}"),
            ));
        }
        if !(position.iter().all(|x| x.is_finite()) && normal.iter().all(|x| x.is_finite())) {
            return Err(ProtocolError::new(
                crate::error::ErrorCode::NotFinite,
                "mesh has a non-finite coordinate",
            ));
        }
        let q = quantise_position(self.frame.origin, self.frame.step, position, true)?;
        let m = quantise_normal(normal);
        if q == self.frame.positions[i] && m == self.frame.normals[i] {
            return Ok(false);
        }
        self.frame.positions[i] = q;
        self.frame.normals[i] = m;
        let at = MESH_HEADER_BYTES + 6 * i;
        let na = MESH_HEADER_BYTES + 6 * n + 6 * i;
        for a in 0..3 {
            self.bytes[at + 2 * a..at + 2 * a + 2].copy_from_slice(&q[a].to_le_bytes());
            self.bytes[na + 2 * a..na + 2 * a + 2].copy_from_slice(&m[a].to_le_bytes());
        }
        if !self.marked[i] {
            self.marked[i] = true;
            self.dirty.push(i as u32);
        }
        Ok(true)
    }

    /// The frame at `revision` with `flags`: its bytes, and the delta from
    /// the revision taken before when that one is older and its bytes were
    /// the frame then. Taking a revision again after changes (or an older
    /// one) gives no delta now or at the next take: a client may hold other
    /// bytes under that number.
    pub fn take(&mut self, revision: u64, flags: u16) -> Take<'_> {
        let changed = !self.dirty.is_empty() || flags != self.frame.flags;
        let delta = match self.base {
            Some(base) if revision > base => self.delta(base, revision, flags),
            _ => None,
        };
        // A delta may start from these bytes next time only if no client
        // can hold other bytes under this revision.
        self.base = match self.last {
            Some(l) if revision < l => None,
            Some(l) if revision == l => self.base.filter(|&b| b == l && !changed),
            _ => Some(revision),
        };
        self.last = Some(self.last.map_or(revision, |l| l.max(revision)));
        self.frame.revision = revision;
        self.frame.flags = flags;
        self.bytes[6..8].copy_from_slice(&flags.to_le_bytes());
        self.bytes[24..32].copy_from_slice(&revision.to_le_bytes());
        for &v in &self.dirty {
            self.marked[v as usize] = false;
        }
        self.dirty.clear();
        Take {
            frame: &self.bytes,
            delta,
        }
    }

    /// The delta from `base` to the frame as it stands, at `revision` with
    /// `flags`, encoded; None when it is not shorter than the frame.
    fn delta(&self, base: u64, revision: u64, flags: u16) -> Option<(u64, Vec<u8>)> {
        let f = &self.frame;
        let mut vertex_runs = Vec::new();
        let (mut positions, mut normals) = (Vec::new(), Vec::new());
        let push = |runs: &mut Vec<Run>, literal: bool, at: usize, count: usize| {
            if count > 0 {
                runs.push(Run {
                    source: if literal { LITERAL } else { at as u32 },
                    count: count as u32,
                });
            }
        };
        // Runs of equal marks: copied where unmarked, literal where marked.
        let mut start = 0;
        for i in 1..=f.positions.len() {
            if i == f.positions.len() || self.marked[i] != self.marked[start] {
                push(&mut vertex_runs, self.marked[start], start, i - start);
                if self.marked[start] {
                    positions.extend_from_slice(&f.positions[start..i]);
                    normals.extend_from_slice(&f.normals[start..i]);
                }
                start = i;
            }
        }
        // A triangle naming a changed vertex cannot be copied (the base's
        // copy of that vertex is not kept): literal.
        let literal = |t: &[u32; 3]| t.iter().any(|&i| self.marked[i as usize]);
        let mut triangle_runs = Vec::new();
        let mut triangles = Vec::new();
        let mut start = 0;
        for k in 1..=f.triangles.len() {
            if k == f.triangles.len() || literal(&f.triangles[k]) != literal(&f.triangles[start]) {
                let lit = literal(&f.triangles[start]);
                push(&mut triangle_runs, lit, start, k - start);
                if lit {
                    triangles.extend_from_slice(&f.triangles[start..k]);
                }
                start = k;
            }
        }
        let delta = MeshDelta {
            design: f.design,
            part: f.part,
            revision,
            base,
            flags,
            origin: f.origin,
            step: f.step,
            vertex_runs,
            triangle_runs,
            positions,
            normals,
            triangles,
        };
        if delta.byte_len() >= self.bytes.len() {
            return None;
        }
        delta.encode().ok().map(|b| (base, b))
    }
}
