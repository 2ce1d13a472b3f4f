//! The binary mesh frame (kind 3): an indexed triangle mesh of one part whose
//! shape the client cannot evaluate itself (a DSM part's implicit surface),
//! sent like a geometry frame: one binary WebSocket message per re-meshed
//! shape, latest-wins per part.
//!
//! Compact: positions quantised to u16 on the mesh's bounding cube (origin +
//! q·step), unit normals as i16 snorm (q / 32767), indices u16 when the mesh
//! has at most 65 535 vertices, else u32 — 12 bytes a vertex and 6 (or 12) a
//! triangle, against 24 + 12 for f32 positions and normals with u32 indices.
//! protocol/README.md gives the layout byte by byte.

use crate::error::{ErrorCode, ProtocolError};
use crate::frame::{check_triangles, write_header};

/// Frame kind: an indexed, quantised triangle mesh.
pub const KIND_MESH: u8 = 3;
/// Size of the mesh frame's header in bytes.
pub const MESH_HEADER_BYTES: usize = 64;
/// Most vertices a mesh frame may carry.
pub const MAX_MESH_VERTICES: usize = 4 << 20;
/// Most triangles a mesh frame may carry.
pub const MAX_MESH_TRIANGLES: usize = 8 << 20;

/// One mesh of one part, quantised as it travels.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshFrame {
    /// The design.
    pub design: u64,
    /// The part.
    pub part: u64,
    /// The shape revision (increases with every change).
    pub revision: u64,
    /// Bit flags (as a geometry frame's: bit 0 drag, bit 1 snapshot).
    pub flags: u16,
    /// World position of quantised (0, 0, 0).
    pub origin: [f32; 3],
    /// World size of one quantum (≥ 0).
    pub step: f32,
    /// Quantised positions: origin + q·step.
    pub positions: Vec<[u16; 3]>,
    /// Unit normals, i16 snorm (q / 32767).
    pub normals: Vec<[i16; 3]>,
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

fn bad(message: impl Into<String>) -> ProtocolError {
    ProtocolError::new(ErrorCode::Malformed, message)
}

/// Bytes of an index for a mesh of `vertices` vertices: 2 up to 65 535, else 4.
pub(crate) fn index_bytes(vertices: usize) -> usize {
    if vertices <= u16::MAX as usize { 2 } else { 4 }
}

/// Writes a cube (origin, step) and an index width `ib`, then zeros up to
/// `header` bytes (the tail of a mesh frame's or a mesh delta's header).
pub(crate) fn write_cube(out: &mut Vec<u8>, origin: [f32; 3], step: f32, ib: usize, header: usize) {
    for c in origin {
        out.extend_from_slice(&c.to_le_bytes());
    }
    out.extend_from_slice(&step.to_le_bytes());
    out.push(ib as u8);
    out.resize(header, 0);
}

/// Writes vertex records (every quantised position, then every normal) and
/// triangles with `ib` bytes an index.
pub(crate) fn write_records(
    out: &mut Vec<u8>,
    (positions, normals): (&[[u16; 3]], &[[i16; 3]]),
    triangles: &[[u32; 3]],
    ib: usize,
) {
    for p in positions {
        p.iter()
            .for_each(|c| out.extend_from_slice(&c.to_le_bytes()));
    }
    for n in normals {
        n.iter()
            .for_each(|c| out.extend_from_slice(&c.to_le_bytes()));
    }
    for t in triangles {
        for &i in t {
            if ib == 2 {
                out.extend_from_slice(&(i as u16).to_le_bytes());
            } else {
                out.extend_from_slice(&i.to_le_bytes());
            }
        }
    }
}

/// Quantised positions, normals and triangles as [`read_records`] reads them.
pub(crate) type Records = (Vec<[u16; 3]>, Vec<[i16; 3]>, Vec<[u32; 3]>);

/// Reads `v` vertex records and `t` triangles of `ib`-byte indices written
/// by [`write_records`] from byte `at` (the caller checked the length).
pub(crate) fn read_records(bytes: &[u8], at: usize, (v, t): (usize, usize), ib: usize) -> Records {
    let le = crate::frame::Le(bytes);
    let (nn, tn) = (at + 6 * v, at + 12 * v);
    (
        (0..v)
            .map(|k| [0, 1, 2].map(|a| le.u16(at + 6 * k + 2 * a)))
            .collect(),
        (0..v)
            .map(|k| [0, 1, 2].map(|a| le.u16(nn + 6 * k + 2 * a) as i16))
            .collect(),
        (0..t)
            .map(|k| {
                [0, 1, 2].map(|a| {
                    let o = tn + ib * (3 * k + a);
                    if ib == 2 { le.u16(o) as u32 } else { le.u32(o) }
                })
            })
            .collect(),
    )
}

/// Position `p` quantised on the cube of `origin` and `step` (as a frame
/// stores them: the f32 origin and step): round((p − origin) / step) per
/// axis, clamped to 0 … 65 535. With `strict`, a position more than a step
/// outside the cube is refused (`out_of_range`) instead of clamped.
pub fn quantise_position(
    origin: [f32; 3],
    step: f32,
    p: [f64; 3],
    strict: bool,
) -> Result<[u16; 3], ProtocolError> {
    let mut q = [0u16; 3];
    if step == 0.0 {
        return Ok(q);
    }
    for a in 0..3 {
        let t = (p[a] - origin[a] as f64) / step as f64;
        if strict && !(-1.0..=65536.0).contains(&t) {
            return Err(ProtocolError::new(
                ErrorCode::OutOfRange,
                "mesh position outside the frame's cube",
            ));
        }
        q[a] = t.round().clamp(0.0, 65535.0) as u16;
    }
    Ok(q)
}

/// Normal `n` as i16 snorm of its unit vector (zero stays zero).
pub fn quantise_normal(n: [f64; 3]) -> [i16; 3] {
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let s = if l > 0.0 { 32767.0 / l } else { 0.0 };
    n.map(|c| (c * s).round().clamp(-32767.0, 32767.0) as i16)
}

/// As many normals as positions, all finite.
fn check_vertices(positions: &[[f64; 3]], normals: &[[f64; 3]]) -> Result<(), ProtocolError> {
    if positions.len() != normals.len() {
        return Err(bad("positions and normals differ in number"));
    }
    let finite = |p: &[f64; 3]| p.iter().all(|x| x.is_finite());
    if !positions.iter().all(finite) || !normals.iter().all(finite) {
        return Err(ProtocolError::new(
            ErrorCode::NotFinite,
            "mesh has a non-finite coordinate",
        ));
    }
    Ok(())
}

impl MeshFrame {
    /// Quantises a mesh: positions on its bounding cube at 65 535 steps along
    /// the longest side (the error is at most half a step), normals to i16.
    /// Non-finite input is refused (`not_finite`).
    pub fn quantise(
        ids: (u64, u64, u64),
        flags: u16,
        positions: &[[f64; 3]],
        normals: &[[f64; 3]],
        triangles: &[[u32; 3]],
    ) -> Result<Self, ProtocolError> {
        check_vertices(positions, normals)?;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in positions {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        if positions.is_empty() {
            lo = [0.0; 3];
            hi = [0.0; 3];
        }
        let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
        Self::on_cube(
            ids,
            flags,
            (lo, extent),
            false,
            (positions, normals, triangles),
        )
    }

    /// Quantises a mesh on a given cube (`origin`, `extent`): 65 535 steps of
    /// extent / 65 535 along each axis from the origin, normals to i16. With
    /// a cube fixed per part (a DSM part's meshing grid), a vertex that did
    /// not move keeps its quantised position from one frame to the next. A
    /// position more than a step outside the cube is refused
    /// (`out_of_range`), non-finite input too (`not_finite`).
    pub fn quantise_in(
        ids: (u64, u64, u64),
        flags: u16,
        (origin, extent): ([f64; 3], f64),
        positions: &[[f64; 3]],
        normals: &[[f64; 3]],
        triangles: &[[u32; 3]],
    ) -> Result<Self, ProtocolError> {
        check_vertices(positions, normals)?;
        Self::on_cube(
            ids,
            flags,
            (origin, extent),
            true,
            (positions, normals, triangles),
        )
    }

    /// The frame of checked vertices on the cube; `strict`: refuse a
    /// position more than a step outside it, else clamp it.
    #[allow(clippy::type_complexity)]
    fn on_cube(
        ids: (u64, u64, u64),
        flags: u16,
        (origin, extent): ([f64; 3], f64),
        strict: bool,
        (positions, normals, triangles): (&[[f64; 3]], &[[f64; 3]], &[[u32; 3]]),
    ) -> Result<Self, ProtocolError> {
        if !(origin.iter().all(|x| x.is_finite()) && extent.is_finite()) {
            return Err(ProtocolError::new(
                ErrorCode::NotFinite,
                "mesh cube is not finite",
            ));
        }
        if extent < 0.0 {
            return Err(bad("mesh cube extent is negative"));
        }
        let origin = origin.map(|x| x as f32);
        let step = (extent / 65535.0) as f32;
        let quantised = positions
            .iter()
            .map(|p| quantise_position(origin, step, *p, strict))
            .collect::<Result<Vec<_>, _>>()?;
        let frame = Self {
            design: ids.0,
            part: ids.1,
            revision: ids.2,
            flags,
            origin,
            step,
            positions: quantised,
            normals: normals.iter().map(|n| quantise_normal(*n)).collect(),
            triangles: triangles.to_vec(),
        };
        frame.check()?;
        Ok(frame)
    }

    /// The world position of vertex i.
    pub fn position(&self, i: usize) -> [f64; 3] {
        let q = self.positions[i];
        [0, 1, 2].map(|a| self.origin[a] as f64 + q[a] as f64 * self.step as f64)
    }

    /// The unit normal of vertex i (as sent, to 1/32767).
    pub fn normal(&self, i: usize) -> [f64; 3] {
        self.normals[i].map(|c| c as f64 / 32767.0)
    }

    /// The encoded length in bytes.
    pub fn byte_len(&self) -> usize {
        let v = self.positions.len();
        MESH_HEADER_BYTES + 12 * v + 3 * index_bytes(v) * self.triangles.len()
    }

    /// Checks sizes, numbers and indices (the checks `decode` makes).
    pub fn check(&self) -> Result<(), ProtocolError> {
        let v = self.positions.len();
        if v > MAX_MESH_VERTICES || self.triangles.len() > MAX_MESH_TRIANGLES {
            return Err(ProtocolError::new(
                ErrorCode::TooLarge,
                "mesh frame exceeds the size limits",
            ));
        }
        if self.normals.len() != v {
            return Err(bad("positions and normals differ in number"));
        }
        if !(self.origin.iter().all(|x| x.is_finite()) && self.step.is_finite()) {
            return Err(ProtocolError::new(
                ErrorCode::NotFinite,
                "mesh frame has a non-finite origin or step",
            ));
        }
        if self.step < 0.0 {
            return Err(bad("mesh frame step is negative"));
        }
        check_triangles(&self.triangles, v)
    }

    /// The frame as bytes (after [`check`](Self::check)).
    pub fn encode(&self) -> Result<Vec<u8>, ProtocolError> {
        self.check()?;
        let v = self.positions.len();
        let ib = index_bytes(v);
        let mut out = Vec::with_capacity(self.byte_len());
        write_header(
            &mut out,
            KIND_MESH,
            self.flags,
            (self.design, self.part, self.revision),
        );
        out.extend_from_slice(&(v as u32).to_le_bytes());
        out.extend_from_slice(&(self.triangles.len() as u32).to_le_bytes());
        write_cube(&mut out, self.origin, self.step, ib, MESH_HEADER_BYTES);
        write_records(
            &mut out,
            (&self.positions, &self.normals),
            &self.triangles,
            ib,
        );
        debug_assert_eq!(out.len(), self.byte_len());
        Ok(out)
    }

    /// Parses a mesh frame. Any byte string gives a frame or an error; never a panic.
    pub fn decode(bytes: &[u8]) -> Result<Self, ProtocolError> {
        crate::frame::check_header(bytes, KIND_MESH, MESH_HEADER_BYTES, "mesh frame")?;
        let le = crate::frame::Le(bytes);
        let (v, t) = (le.u32(32) as usize, le.u32(36) as usize);
        if v > MAX_MESH_VERTICES || t > MAX_MESH_TRIANGLES {
            return Err(ProtocolError::new(
                ErrorCode::TooLarge,
                "mesh frame exceeds the size limits",
            ));
        }
        let ib = bytes[56] as usize;
        if ib != index_bytes(v) {
            return Err(bad(format!(
                "index width {ib} does not fit {v} vertices (want {})",
                index_bytes(v)
            )));
        }
        if bytes[57..MESH_HEADER_BYTES].iter().any(|&b| b != 0) {
            return Err(bad("mesh frame header padding is not zero"));
        }
        let total = MESH_HEADER_BYTES + 12 * v + 3 * ib * t;
        if bytes.len() != total {
            return Err(bad(format!(
                "mesh frame has {} bytes, its header says {total}",
                bytes.len()
            )));
        }
        let (positions, normals, triangles) = read_records(bytes, MESH_HEADER_BYTES, (v, t), ib);
        let frame = Self {
            design: le.u64(8),
            part: le.u64(16),
            revision: le.u64(24),
            flags: le.u16(6),
            origin: [le.f32(40), le.f32(44), le.f32(48)],
            step: le.f32(52),
            positions,
            normals,
            triangles,
        };
        frame.check()?;
        Ok(frame)
    }
}
