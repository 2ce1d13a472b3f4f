//! The binary body frame (kind 4): what a client draws of one Coons body
//! part (paper 002 §2.1) — its control lattice (the handles), its boundary
//! as a triangle mesh with normals, and isoparametric lines at constant
//! u, v and w on the boundary — at one morph time. One binary WebSocket
//! message per evaluated shape, latest-wins per part, like a geometry frame.
//!
//! All numbers little-endian; every section is a multiple of 4 bytes, so
//! JavaScript views the arrays with `Float32Array` / `Uint32Array` without
//! copying. protocol/README.md gives the layout byte by byte.

use crate::error::{ErrorCode, ProtocolError};
use crate::frame::{check_triangles, write_header};

/// Frame kind: a Coons body.
pub const KIND_BODY: u8 = 4;
/// Size of the body frame's header in bytes.
pub const BODY_HEADER_BYTES: usize = 64;
/// Most lattice points a body frame may carry.
pub const MAX_FRAME_LATTICE: usize = 1 << 16;
/// Most boundary vertices a body frame may carry.
pub const MAX_FRAME_VERTICES: usize = 1 << 20;
/// Most boundary triangles a body frame may carry.
pub const MAX_FRAME_TRIANGLES: usize = 1 << 21;
/// Most isoparametric lines a body frame may carry.
pub const MAX_FRAME_LINES: usize = 4096;
/// Most samples along one isoparametric line.
pub const MAX_LINE_SAMPLES: usize = 1024;
/// Highest degree a body frame's lattice may have along a direction.
pub const MAX_FRAME_DEGREE: u32 = crate::body::MAX_BODY_DEGREE;

/// One evaluated body.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyFrame {
    /// The design.
    pub design: u64,
    /// The part.
    pub part: u64,
    /// The shape revision.
    pub revision: u64,
    /// Bit flags (as a geometry frame's: bit 0 drag, bit 1 snapshot).
    pub flags: u16,
    /// The morph time this shape is at (0 without a morph target).
    pub t: f32,
    /// Lattice size `[nu, nv, nw]`.
    pub counts: [u32; 3],
    /// The lattice points at time `t`, k fastest (`(i * nv + j) * nw + k`).
    pub lattice: Vec<[f32; 3]>,
    /// Boundary vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Boundary vertex unit normals (outward).
    pub normals: Vec<[f32; 3]>,
    /// Boundary triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Samples per isoparametric line.
    pub line_samples: u32,
    /// Per line, the direction held constant: 0 u, 1 v, 2 w.
    pub line_dirs: Vec<u32>,
    /// The lines' points, `line_samples` per line, line after line.
    pub line_points: Vec<[f32; 3]>,
    /// The lattice's degrees along u, v, w.
    pub degrees: [u32; 3],
    /// The lattice's clamped knots along u, v, w: `counts[d] + degrees[d] + 1` each.
    pub knots: [Vec<f32>; 3],
}

fn bad(message: impl Into<String>) -> ProtocolError {
    ProtocolError::new(ErrorCode::Malformed, message)
}

impl BodyFrame {
    /// The encoded length in bytes.
    pub fn byte_len(&self) -> usize {
        BODY_HEADER_BYTES
            + 12 * self.lattice.len()
            + 24 * self.positions.len()
            + 12 * self.triangles.len()
            + 4 * self.line_dirs.len()
            + 12 * self.line_points.len()
            + 12
            + 4 * self.knots.iter().map(Vec::len).sum::<usize>()
    }

    /// Checks sizes, numbers and indices (the checks `decode` makes).
    pub fn check(&self) -> Result<(), ProtocolError> {
        let n: usize = self.counts.iter().map(|&c| c as usize).product();
        if n > MAX_FRAME_LATTICE
            || self.positions.len() > MAX_FRAME_VERTICES
            || self.triangles.len() > MAX_FRAME_TRIANGLES
            || self.line_dirs.len() > MAX_FRAME_LINES
            || self.line_samples as usize > MAX_LINE_SAMPLES
        {
            return Err(ProtocolError::new(
                ErrorCode::TooLarge,
                "body frame exceeds the size limits",
            ));
        }
        if self.lattice.len() != n {
            return Err(bad("lattice size does not match its counts"));
        }
        if self.normals.len() != self.positions.len() {
            return Err(bad("positions and normals differ in number"));
        }
        if self.line_points.len() != self.line_dirs.len() * self.line_samples as usize {
            return Err(bad("line points do not match lines × samples"));
        }
        if self.line_dirs.iter().any(|&d| d > 2) {
            return Err(bad("a line direction is not 0, 1 or 2"));
        }
        check_spline(self.counts, self.degrees, &self.knots)?;
        let finite = |p: &[f32; 3]| p.iter().all(|x| x.is_finite());
        if !self.t.is_finite()
            || !self.lattice.iter().all(finite)
            || !self.positions.iter().all(finite)
            || !self.normals.iter().all(finite)
            || !self.line_points.iter().all(finite)
        {
            return Err(ProtocolError::new(
                ErrorCode::NotFinite,
                "body frame has a non-finite number",
            ));
        }
        let v = self.positions.len();
        check_triangles(&self.triangles, v)
    }

    /// The frame as bytes (after [`check`](Self::check)).
    pub fn encode(&self) -> Result<Vec<u8>, ProtocolError> {
        self.check()?;
        let mut out = Vec::with_capacity(self.byte_len());
        write_header(
            &mut out,
            KIND_BODY,
            self.flags,
            (self.design, self.part, self.revision),
        );
        out.extend_from_slice(&self.t.to_le_bytes());
        for c in self.counts {
            out.extend_from_slice(&c.to_le_bytes());
        }
        for n in [
            self.positions.len(),
            self.triangles.len(),
            self.line_dirs.len(),
        ] {
            out.extend_from_slice(&(n as u32).to_le_bytes());
        }
        out.extend_from_slice(&self.line_samples.to_le_bytes());
        debug_assert_eq!(out.len(), BODY_HEADER_BYTES);
        let put3 = |out: &mut Vec<u8>, xs: &[[f32; 3]]| {
            for p in xs {
                p.iter()
                    .for_each(|c| out.extend_from_slice(&c.to_le_bytes()));
            }
        };
        put3(&mut out, &self.lattice);
        put3(&mut out, &self.positions);
        put3(&mut out, &self.normals);
        for t in &self.triangles {
            t.iter()
                .for_each(|i| out.extend_from_slice(&i.to_le_bytes()));
        }
        for d in &self.line_dirs {
            out.extend_from_slice(&d.to_le_bytes());
        }
        put3(&mut out, &self.line_points);
        for d in self.degrees {
            out.extend_from_slice(&d.to_le_bytes());
        }
        for x in self.knots.iter().flatten() {
            out.extend_from_slice(&x.to_le_bytes());
        }
        debug_assert_eq!(out.len(), self.byte_len());
        Ok(out)
    }

    /// Parses a body frame. Any byte string gives a frame or an error; never a panic.
    pub fn decode(bytes: &[u8]) -> Result<Self, ProtocolError> {
        crate::frame::check_header(bytes, KIND_BODY, BODY_HEADER_BYTES, "body frame")?;
        let le = crate::frame::Le(bytes);
        let counts = [le.u32(36), le.u32(40), le.u32(44)];
        let (v, t, l, s) = (
            le.u32(48) as usize,
            le.u32(52) as usize,
            le.u32(56) as usize,
            le.u32(60) as usize,
        );
        let n = counts
            .iter()
            .try_fold(1usize, |a, &c| a.checked_mul(c as usize))
            .unwrap_or(usize::MAX);
        if n > MAX_FRAME_LATTICE
            || v > MAX_FRAME_VERTICES
            || t > MAX_FRAME_TRIANGLES
            || l > MAX_FRAME_LINES
            || s > MAX_LINE_SAMPLES
        {
            return Err(ProtocolError::new(
                ErrorCode::TooLarge,
                "body frame exceeds the size limits",
            ));
        }
        // The spline section follows the lines: 3 degrees, then the knots.
        let spline = BODY_HEADER_BYTES + 12 * n + 24 * v + 12 * t + 4 * l + 12 * l * s;
        if bytes.len() < spline + 12 {
            return Err(bad(format!(
                "body frame has {} bytes, too few for its header's sizes and the degrees",
                bytes.len()
            )));
        }
        let degrees = [0, 1, 2].map(|d| le.u32(spline + 4 * d));
        if degrees.iter().any(|&p| p == 0 || p > MAX_FRAME_DEGREE) {
            return Err(bad(format!(
                "a body frame's degrees must be 1..={MAX_FRAME_DEGREE}"
            )));
        }
        let lens = [0, 1, 2].map(|d| counts[d] as usize + degrees[d] as usize + 1);
        let total = spline + 12 + 4 * lens.iter().sum::<usize>();
        if bytes.len() != total {
            return Err(bad(format!(
                "body frame has {} bytes, its header says {total}",
                bytes.len()
            )));
        }
        let vec3s = |at: usize, count: usize| -> Vec<[f32; 3]> {
            (0..count)
                .map(|k| [0, 1, 2].map(|a| le.f32(at + 12 * k + 4 * a)))
                .collect()
        };
        let lat = BODY_HEADER_BYTES;
        let pos = lat + 12 * n;
        let nor = pos + 12 * v;
        let tri = nor + 12 * v;
        let dirs = tri + 12 * t;
        let pts = dirs + 4 * l;
        let frame = Self {
            design: le.u64(8),
            part: le.u64(16),
            revision: le.u64(24),
            flags: u16::from_le_bytes([bytes[6], bytes[7]]),
            t: le.f32(32),
            counts,
            lattice: vec3s(lat, n),
            positions: vec3s(pos, v),
            normals: vec3s(nor, v),
            triangles: (0..t)
                .map(|k| [0, 1, 2].map(|a| le.u32(tri + 12 * k + 4 * a)))
                .collect(),
            line_samples: s as u32,
            line_dirs: (0..l).map(|k| le.u32(dirs + 4 * k)).collect(),
            line_points: vec3s(pts, l * s),
            degrees,
            knots: {
                let mut at = spline + 12;
                lens.map(|len| {
                    let k = (0..len).map(|i| le.f32(at + 4 * i)).collect();
                    at += 4 * len;
                    k
                })
            },
        };
        frame.check()?;
        Ok(frame)
    }
}

/// A lattice's degrees and knots agree with its counts: degrees
/// 1..=[`MAX_FRAME_DEGREE`], at least degree + 1 points, `counts + degree
/// + 1` finite, non-decreasing knots per direction.
fn check_spline(
    counts: [u32; 3],
    degrees: [u32; 3],
    knots: &[Vec<f32>; 3],
) -> Result<(), ProtocolError> {
    for d in 0..3 {
        let (n, p) = (counts[d] as usize, degrees[d] as usize);
        if p == 0 || p > MAX_FRAME_DEGREE as usize {
            return Err(bad(format!(
                "a body frame's degrees must be 1..={MAX_FRAME_DEGREE}"
            )));
        }
        if n < p + 1 {
            return Err(bad(
                "a body frame's lattice has fewer than degree + 1 points along a direction",
            ));
        }
        if knots[d].len() != n + p + 1 {
            return Err(bad(
                "a body frame's knots do not match its counts and degrees",
            ));
        }
        if !knots[d].iter().all(|x| x.is_finite()) {
            return Err(ProtocolError::new(
                ErrorCode::NotFinite,
                "body frame has a non-finite knot",
            ));
        }
        if knots[d].windows(2).any(|w| w[1] < w[0]) {
            return Err(bad("a body frame's knots decrease"));
        }
    }
    Ok(())
}
