//! The drag stream: two small binary messages that let a client follow a
//! drag without a whole control net per frame (protocol/README.md, "Drag
//! stream", gives the layout byte by byte).
//!
//! While a drag stays on the kernel's fast path every frame of a part's
//! net is `P = R + ρ·d`: `R` the net of one full geometry frame the client
//! already holds (the *reference*, named by its revision), `ρ` one scalar per
//! control point and `d` a 3-vector. The server sends `ρ` once in a
//! [`DragBasis`] (kind 5), then one [`DragFrame`] (kind 6) per drag frame
//! carrying only `d` and the icon positions — 72 bytes plus 24 per icon. At
//! rest (release, any other edit) a full geometry frame follows, so the shape
//! at rest is the server's to the bit of the full frame. Little-endian.

use crate::error::{ErrorCode, ProtocolError};
use crate::frame::{FrameIcon, ICON_BYTES, MAGIC};
use crate::limits::{MAX_FRAME_ICONS, MAX_GRID};
use crate::version::PROTOCOL_VERSION;

/// Frame kind: a drag basis (ρ of one part).
pub const KIND_DRAG_BASIS: u8 = 5;
/// Frame kind: a drag frame (the displacement `d` of one part's drag).
pub const KIND_DRAG_FRAME: u8 = 6;
/// Size of a drag basis's header in bytes (ρ follows).
pub const BASIS_HEADER_BYTES: usize = 48;
/// Size of a drag frame's header in bytes (the icon records follow).
pub const DRAG_HEADER_BYTES: usize = 72;

fn bad(message: impl Into<String>) -> ProtocolError {
    ProtocolError::new(ErrorCode::Malformed, message)
}

fn too_large() -> ProtocolError {
    ProtocolError::new(ErrorCode::TooLarge, "drag message exceeds the size limits")
}

fn not_finite() -> ProtocolError {
    ProtocolError::new(ErrorCode::NotFinite, "drag message has a non-finite number")
}

/// The shared header checks (see [`crate::frame::check_header`]).
fn check_head(bytes: &[u8], kind: u8, header: usize) -> Result<(), ProtocolError> {
    crate::frame::check_header(bytes, kind, header, "drag message")
}

fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_le_bytes(b[o..o + 4].try_into().unwrap_or([0; 4]))
}
fn u64_at(b: &[u8], o: usize) -> u64 {
    u64::from_le_bytes(b[o..o + 8].try_into().unwrap_or([0; 8]))
}
fn f64_at(b: &[u8], o: usize) -> f64 {
    f64::from_le_bytes(b[o..o + 8].try_into().unwrap_or([0; 8]))
}
fn f32_at(b: &[u8], o: usize) -> f32 {
    f32::from_le_bytes(b[o..o + 4].try_into().unwrap_or([0; 4]))
}

/// ρ of one part's drag: the net of the reference frame moves by `ρ[k]·d`
/// at control point `k` (row-major, as the geometry frame's points).
#[derive(Clone, Debug, PartialEq)]
pub struct DragBasis {
    /// The design.
    pub design: u64,
    /// The part.
    pub part: u64,
    /// Names this basis; drag frames carry it.
    pub basis: u64,
    /// The revision of the full geometry frame whose net is the reference.
    pub reference: u64,
    /// One factor per control point, nu · nv of them.
    pub rho: Vec<f32>,
}

impl DragBasis {
    /// The basis as bytes.
    pub fn encode(&self) -> Result<Vec<u8>, ProtocolError> {
        if self.rho.len() > MAX_GRID * MAX_GRID {
            return Err(too_large());
        }
        if self.rho.iter().any(|r| !r.is_finite()) {
            return Err(not_finite());
        }
        let mut out = Vec::with_capacity(BASIS_HEADER_BYTES + 4 * self.rho.len());
        out.extend_from_slice(&MAGIC);
        out.push(KIND_DRAG_BASIS);
        out.push(PROTOCOL_VERSION as u8);
        out.extend_from_slice(&[0, 0]);
        out.extend_from_slice(&self.design.to_le_bytes());
        out.extend_from_slice(&self.part.to_le_bytes());
        out.extend_from_slice(&self.basis.to_le_bytes());
        out.extend_from_slice(&self.reference.to_le_bytes());
        out.extend_from_slice(&(self.rho.len() as u32).to_le_bytes());
        out.extend_from_slice(&[0; 4]);
        debug_assert_eq!(out.len(), BASIS_HEADER_BYTES);
        for r in &self.rho {
            out.extend_from_slice(&r.to_le_bytes());
        }
        Ok(out)
    }

    /// Parses a basis. Any byte string gives a basis or an error; never a panic.
    pub fn decode(bytes: &[u8]) -> Result<Self, ProtocolError> {
        check_head(bytes, KIND_DRAG_BASIS, BASIS_HEADER_BYTES)?;
        let n = u32_at(bytes, 40) as usize;
        if n > MAX_GRID * MAX_GRID {
            return Err(too_large());
        }
        if bytes.len() != BASIS_HEADER_BYTES + 4 * n {
            return Err(bad(format!(
                "drag basis has {} bytes, its header says {}",
                bytes.len(),
                BASIS_HEADER_BYTES + 4 * n
            )));
        }
        if bytes[6..8] != [0, 0] || bytes[44..48] != [0; 4] {
            return Err(bad(
                "a drag basis's zero bytes (offsets 6, 44) must be zero",
            ));
        }
        let rho: Vec<f32> = (0..n)
            .map(|k| f32_at(bytes, BASIS_HEADER_BYTES + 4 * k))
            .collect();
        if rho.iter().any(|r| !r.is_finite()) {
            return Err(not_finite());
        }
        Ok(Self {
            design: u64_at(bytes, 8),
            part: u64_at(bytes, 16),
            basis: u64_at(bytes, 24),
            reference: u64_at(bytes, 32),
            rho,
        })
    }
}

/// One drag frame of one part: its net is the reference's plus `ρ·d`.
#[derive(Clone, Debug, PartialEq)]
pub struct DragFrame {
    /// The design.
    pub design: u64,
    /// The part.
    pub part: u64,
    /// The shape revision (as a geometry frame's).
    pub revision: u64,
    /// The [`DragBasis`] this frame applies.
    pub basis: u64,
    /// The displacement `d`.
    pub d: [f64; 3],
    /// Icon positions (as a geometry frame's icon records).
    pub icons: Vec<FrameIcon>,
}

impl DragFrame {
    /// The frame as bytes.
    pub fn encode(&self) -> Result<Vec<u8>, ProtocolError> {
        if self.icons.len() > MAX_FRAME_ICONS {
            return Err(too_large());
        }
        if self.d.iter().any(|x| !x.is_finite())
            || self
                .icons
                .iter()
                .any(|i| i.xyz.iter().any(|x| !x.is_finite()))
        {
            return Err(not_finite());
        }
        let mut out = Vec::with_capacity(DRAG_HEADER_BYTES + ICON_BYTES * self.icons.len());
        out.extend_from_slice(&MAGIC);
        out.push(KIND_DRAG_FRAME);
        out.push(PROTOCOL_VERSION as u8);
        out.extend_from_slice(&crate::frame::FLAG_DRAG.to_le_bytes());
        out.extend_from_slice(&self.design.to_le_bytes());
        out.extend_from_slice(&self.part.to_le_bytes());
        out.extend_from_slice(&self.revision.to_le_bytes());
        out.extend_from_slice(&self.basis.to_le_bytes());
        for c in self.d {
            out.extend_from_slice(&c.to_le_bytes());
        }
        out.extend_from_slice(&(self.icons.len() as u32).to_le_bytes());
        out.extend_from_slice(&[0; 4]);
        debug_assert_eq!(out.len(), DRAG_HEADER_BYTES);
        for icon in &self.icons {
            out.extend_from_slice(&icon.id.to_le_bytes());
            for c in icon.xyz {
                out.extend_from_slice(&c.to_le_bytes());
            }
            out.extend_from_slice(&[0; 4]);
        }
        Ok(out)
    }

    /// Parses a drag frame. Any byte string gives a frame or an error; never a panic.
    pub fn decode(bytes: &[u8]) -> Result<Self, ProtocolError> {
        check_head(bytes, KIND_DRAG_FRAME, DRAG_HEADER_BYTES)?;
        let m = u32_at(bytes, 64) as usize;
        if m > MAX_FRAME_ICONS {
            return Err(too_large());
        }
        let total = DRAG_HEADER_BYTES + ICON_BYTES * m;
        if bytes.len() != total {
            return Err(bad(format!(
                "drag frame has {} bytes, its header says {total}",
                bytes.len()
            )));
        }
        let zeros = bytes[68..72].iter().chain((0..m).flat_map(|k| {
            let o = DRAG_HEADER_BYTES + ICON_BYTES * k + 20;
            &bytes[o..o + 4]
        }));
        if zeros.copied().any(|b| b != 0) {
            return Err(bad(
                "a drag frame's zero bytes (offset 68, icon records' last four) must be zero",
            ));
        }
        let frame = Self {
            design: u64_at(bytes, 8),
            part: u64_at(bytes, 16),
            revision: u64_at(bytes, 24),
            basis: u64_at(bytes, 32),
            d: [f64_at(bytes, 40), f64_at(bytes, 48), f64_at(bytes, 56)],
            icons: (0..m)
                .map(|k| {
                    let o = DRAG_HEADER_BYTES + ICON_BYTES * k;
                    FrameIcon {
                        id: u64_at(bytes, o),
                        xyz: [
                            f32_at(bytes, o + 8),
                            f32_at(bytes, o + 12),
                            f32_at(bytes, o + 16),
                        ],
                    }
                })
                .collect(),
        };
        if frame.d.iter().any(|x| !x.is_finite())
            || frame
                .icons
                .iter()
                .any(|i| i.xyz.iter().any(|x| !x.is_finite()))
        {
            return Err(not_finite());
        }
        Ok(frame)
    }

    /// The net this frame stands for: `reference[k] + rho[k]·d`, computed
    /// in f64 from the f32 inputs as a client computes it.
    pub fn apply(&self, reference: &[[f32; 3]], rho: &[f32]) -> Option<Vec<[f64; 3]>> {
        if reference.len() != rho.len() {
            return None;
        }
        Some(
            reference
                .iter()
                .zip(rho)
                .map(|(p, &r)| {
                    let r = r as f64;
                    [
                        p[0] as f64 + r * self.d[0],
                        p[1] as f64 + r * self.d[1],
                        p[2] as f64 + r * self.d[2],
                    ]
                })
                .collect(),
        )
    }
}
