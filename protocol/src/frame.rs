//! The binary geometry frame: the solved control net of one part of a
//! design, its knots and the positions of its icons, sent as one binary
//! WebSocket message per solved frame of that part (latest-wins per part). Clients tessellate it themselves, so a frame costs
//! kilobytes where a mesh would cost megabytes (protocol/README.md gives
//! the layout byte by byte and the measured sizes).
//!
//! All integers and floats are little-endian. Knots are f64 (exact knot
//! values matter for evaluation), control points f32 (display precision; the
//! server keeps f64). Sections are aligned so JavaScript can view the arrays
//! with `Float64Array` / `Float32Array` without copying.

use crate::error::{ErrorCode, ProtocolError};
use crate::limits::{MAX_FRAME_ICONS, MAX_GRID};
use crate::version::PROTOCOL_VERSION;

/// The first four bytes of every frame: "VSGF".
pub const MAGIC: [u8; 4] = *b"VSGF";
/// Frame kind: a tensor-product B-spline surface part.
pub const KIND_SURFACE: u8 = 1;
/// Frame kind: a B-spline curve part (`nv` = 1, `degree_v` = 0, no v knots).
pub const KIND_CURVE: u8 = 2;
/// Flag: this frame comes from a drag (more will follow soon).
pub const FLAG_DRAG: u16 = 1;
/// Flag: this frame is the shape of a joining client's `snapshot`, sent
/// before it (the compact join: a hello with `geometry_first`).
pub const FLAG_SNAPSHOT: u16 = 2;
/// Size of the fixed header in bytes.
pub const HEADER_BYTES: usize = 48;
/// Size of one icon record in bytes.
pub const ICON_BYTES: usize = 24;
/// Highest degree a frame may carry.
pub const MAX_DEGREE: u8 = 15;

/// A copy of an encoded frame with `flags` set in addition to its own
/// (bytes 6–7 of the header); bytes that are not a frame are copied as they
/// are. Lets a server re-flag a frame it already encoded, without decoding it.
pub fn with_flags(frame: &[u8], flags: u16) -> Vec<u8> {
    let mut out = frame.to_vec();
    if out.len() >= HEADER_BYTES && out[..4] == MAGIC {
        let old = u16::from_le_bytes([out[6], out[7]]);
        out[6..8].copy_from_slice(&(old | flags).to_le_bytes());
    }
    out
}

/// An icon's id and position in a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameIcon {
    /// The icon id.
    pub id: u64,
    /// Its position on the solved surface.
    pub xyz: [f32; 3],
}

/// One solved frame of one part of a design.
#[derive(Clone, Debug, PartialEq)]
pub struct GeometryFrame {
    /// [`KIND_SURFACE`] or [`KIND_CURVE`].
    pub kind: u8,
    /// The design.
    pub design: u64,
    /// The part.
    pub part: u64,
    /// The shape revision (increases with every change).
    pub revision: u64,
    /// Bit flags ([`FLAG_DRAG`], [`FLAG_SNAPSHOT`]).
    pub flags: u16,
    /// Degree along u.
    pub degree_u: u8,
    /// Degree along v.
    pub degree_v: u8,
    /// Control points along u.
    pub nu: u32,
    /// Control points along v.
    pub nv: u32,
    /// nu + degree_u + 1 knots.
    pub knots_u: Vec<f64>,
    /// nv + degree_v + 1 knots (none for a curve).
    pub knots_v: Vec<f64>,
    /// nu · nv control points, row-major (i * nv + j, i along u).
    pub points: Vec<[f32; 3]>,
    /// Icon positions.
    pub icons: Vec<FrameIcon>,
}

/// Little-endian reads at byte offsets of a frame whose length was checked
/// first (a short read gives 0, never a panic, for the multi-byte widths;
/// `u16` needs its two bytes in range). Shared by every binary decoder.
#[derive(Clone, Copy)]
pub(crate) struct Le<'a>(pub &'a [u8]);

impl Le<'_> {
    pub(crate) fn u16(self, o: usize) -> u16 {
        u16::from_le_bytes([self.0[o], self.0[o + 1]])
    }
    pub(crate) fn u32(self, o: usize) -> u32 {
        u32::from_le_bytes(self.bytes(o))
    }
    pub(crate) fn u64(self, o: usize) -> u64 {
        u64::from_le_bytes(self.bytes(o))
    }
    pub(crate) fn f32(self, o: usize) -> f32 {
        f32::from_le_bytes(self.bytes(o))
    }
    pub(crate) fn f64(self, o: usize) -> f64 {
        f64::from_le_bytes(self.bytes(o))
    }
    fn bytes<const N: usize>(self, o: usize) -> [u8; N] {
        self.0
            .get(o..o + N)
            .and_then(|b| b.try_into().ok())
            .unwrap_or([0; N])
    }
}

fn bad(message: impl Into<String>) -> ProtocolError {
    ProtocolError::new(ErrorCode::Malformed, message)
}

/// The checks every binary message of one `kind` shares: at least `header`
/// bytes, the magic, the kind and the protocol version (`what` names the
/// message in the errors, e.g. "mesh frame").
pub(crate) fn check_header(
    bytes: &[u8],
    kind: u8,
    header: usize,
    what: &str,
) -> Result<(), ProtocolError> {
    if bytes.len() < header {
        return Err(bad(format!(
            "{what} of {} bytes is shorter than its header ({header})",
            bytes.len()
        )));
    }
    if bytes[0..4] != MAGIC {
        return Err(bad("not a geometry frame (bad magic)"));
    }
    if bytes[4] != kind {
        return Err(bad(format!(
            "frame kind {} is not {kind}: not a {what}",
            bytes[4]
        )));
    }
    if bytes[5] as u32 != PROTOCOL_VERSION {
        return Err(ProtocolError::new(
            ErrorCode::BadVersion,
            format!("frame version {} is not {PROTOCOL_VERSION}", bytes[5]),
        ));
    }
    Ok(())
}

/// Writes the 32-byte header every geometry frame with a revision shares:
/// magic, `kind`, version, flags, design, part, revision (little-endian).
pub(crate) fn write_header(
    out: &mut Vec<u8>,
    kind: u8,
    flags: u16,
    (design, part, revision): (u64, u64, u64),
) {
    out.extend_from_slice(&MAGIC);
    out.push(kind);
    out.push(PROTOCOL_VERSION as u8);
    out.extend_from_slice(&flags.to_le_bytes());
    out.extend_from_slice(&design.to_le_bytes());
    out.extend_from_slice(&part.to_le_bytes());
    out.extend_from_slice(&revision.to_le_bytes());
}

/// Every triangle names one of the `v` vertices sent.
pub(crate) fn check_triangles(triangles: &[[u32; 3]], v: usize) -> Result<(), ProtocolError> {
    match triangles
        .iter()
        .find(|t| t.iter().any(|&i| i as usize >= v))
    {
        Some(t) => Err(bad(format!(
            "triangle {t:?} names a vertex beyond the {v} sent"
        ))),
        None => Ok(()),
    }
}

fn pad8(n: usize) -> usize {
    n.div_ceil(8) * 8
}

/// Byte offsets of the sections of a frame with the given sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Offset of the u knots (f64).
    pub knots_u: usize,
    /// Offset of the v knots (f64).
    pub knots_v: usize,
    /// Offset of the control points (f32 × 3 each).
    pub points: usize,
    /// Offset of the icon records.
    pub icons: usize,
    /// Total length.
    pub total: usize,
}

impl Layout {
    /// The layout of a frame of `kind`, or `None` if the sizes overflow.
    pub fn new(kind: u8, nu: usize, nv: usize, du: usize, dv: usize, icons: usize) -> Option<Self> {
        let knots_u = HEADER_BYTES;
        let knots_v = knots_u.checked_add(nu.checked_add(du + 1)?.checked_mul(8)?)?;
        let v_knots = if kind == KIND_CURVE {
            0
        } else {
            nv.checked_add(dv + 1)?
        };
        let points = knots_v.checked_add(v_knots.checked_mul(8)?)?;
        let point_bytes = nu.checked_mul(nv)?.checked_mul(12)?;
        let icons_at = pad8(points.checked_add(point_bytes)?);
        let total = icons_at.checked_add(icons.checked_mul(ICON_BYTES)?)?;
        Some(Self {
            knots_u,
            knots_v,
            points,
            icons: icons_at,
            total,
        })
    }
}

impl GeometryFrame {
    fn layout(&self) -> Result<Layout, ProtocolError> {
        Layout::new(
            self.kind,
            self.nu as usize,
            self.nv as usize,
            self.degree_u as usize,
            self.degree_v as usize,
            self.icons.len(),
        )
        .ok_or_else(|| ProtocolError::new(ErrorCode::TooLarge, "frame sizes overflow"))
    }

    /// Checks the sizes, knots and numbers (the same checks `decode` makes).
    pub fn check(&self) -> Result<(), ProtocolError> {
        let (nu, nv) = (self.nu as usize, self.nv as usize);
        if nu > MAX_GRID || nv > MAX_GRID || self.icons.len() > MAX_FRAME_ICONS {
            return Err(ProtocolError::new(
                ErrorCode::TooLarge,
                "frame exceeds the size limits",
            ));
        }
        let curve = match self.kind {
            KIND_SURFACE => false,
            KIND_CURVE => true,
            k => return Err(bad(format!("unknown frame kind {k}"))),
        };
        if curve && (nv != 1 || self.degree_v != 0) {
            return Err(bad("a curve frame has nv = 1 and degree_v = 0"));
        }
        let dirs: &[(u8, usize)] = if curve {
            &[(self.degree_u, nu)]
        } else {
            &[(self.degree_u, nu), (self.degree_v, nv)]
        };
        for &(d, n) in dirs {
            if d == 0 || d > MAX_DEGREE || n < d as usize + 1 {
                return Err(bad(format!("degree {d} with {n} control points")));
            }
        }
        let v_knots = if curve {
            0
        } else {
            nv + self.degree_v as usize + 1
        };
        if self.knots_u.len() != nu + self.degree_u as usize + 1 || self.knots_v.len() != v_knots {
            return Err(bad("knot count does not match degree and control points"));
        }
        for k in [&self.knots_u, &self.knots_v] {
            if k.iter().any(|x| !x.is_finite()) || k.windows(2).any(|w| w[1] < w[0]) {
                return Err(bad("knots must be finite and non-decreasing"));
            }
        }
        if self.points.len() != nu * nv {
            return Err(bad("control point count does not match nu · nv"));
        }
        let finite = |p: &[f32; 3]| p.iter().all(|x| x.is_finite());
        if !self.points.iter().all(finite) || !self.icons.iter().all(|i| finite(&i.xyz)) {
            return Err(ProtocolError::new(
                ErrorCode::NotFinite,
                "frame has a non-finite coordinate",
            ));
        }
        Ok(())
    }

    /// The frame as bytes (after [`check`](Self::check)).
    pub fn encode(&self) -> Result<Vec<u8>, ProtocolError> {
        self.check()?;
        let layout = self.layout()?;
        let mut out = Vec::with_capacity(layout.total);
        write_header(
            &mut out,
            self.kind,
            self.flags,
            (self.design, self.part, self.revision),
        );
        out.extend_from_slice(&self.nu.to_le_bytes());
        out.extend_from_slice(&self.nv.to_le_bytes());
        out.push(self.degree_u);
        out.push(self.degree_v);
        out.extend_from_slice(&[0, 0]);
        out.extend_from_slice(&(self.icons.len() as u32).to_le_bytes());
        debug_assert_eq!(out.len(), HEADER_BYTES);
        for k in self.knots_u.iter().chain(&self.knots_v) {
            out.extend_from_slice(&k.to_le_bytes());
        }
        for p in &self.points {
            for c in p {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out.resize(layout.icons, 0);
        for icon in &self.icons {
            out.extend_from_slice(&icon.id.to_le_bytes());
            for c in icon.xyz {
                out.extend_from_slice(&c.to_le_bytes());
            }
            out.extend_from_slice(&[0; 4]);
        }
        debug_assert_eq!(out.len(), layout.total);
        Ok(out)
    }

    /// Parses a frame. Any byte string gives a frame or an error; never a panic.
    pub fn decode(bytes: &[u8]) -> Result<Self, ProtocolError> {
        if bytes.len() < HEADER_BYTES {
            return Err(bad(format!(
                "frame of {} bytes is shorter than its header",
                bytes.len()
            )));
        }
        if bytes[0..4] != MAGIC {
            return Err(bad("not a geometry frame (bad magic)"));
        }
        let kind = bytes[4];
        if kind != KIND_SURFACE && kind != KIND_CURVE {
            return Err(bad(format!("unknown frame kind {}", bytes[4])));
        }
        if bytes[5] as u32 != PROTOCOL_VERSION {
            return Err(ProtocolError::new(
                ErrorCode::BadVersion,
                format!("frame version {} is not {PROTOCOL_VERSION}", bytes[5]),
            ));
        }
        let le = crate::frame::Le(bytes);
        let (nu, nv) = (le.u32(32), le.u32(36));
        let (degree_u, degree_v) = (bytes[40], bytes[41]);
        let n_icons = le.u32(44) as usize;
        if nu as usize > MAX_GRID || nv as usize > MAX_GRID || n_icons > MAX_FRAME_ICONS {
            return Err(ProtocolError::new(
                ErrorCode::TooLarge,
                "frame exceeds the size limits",
            ));
        }
        let layout = Layout::new(
            kind,
            nu as usize,
            nv as usize,
            degree_u as usize,
            degree_v as usize,
            n_icons,
        )
        .ok_or_else(|| bad("frame sizes overflow"))?;
        if bytes.len() != layout.total {
            return Err(bad(format!(
                "frame has {} bytes, its header says {}",
                bytes.len(),
                layout.total
            )));
        }
        // The zero bytes (header 42..44, the padding before the icons, each
        // icon's last four) are zero: a frame has one encoding, and a
        // future use of them is not silently misread.
        let points_end = layout.points + 12 * nu as usize * nv as usize;
        let zeros = bytes[42..44]
            .iter()
            .chain(&bytes[points_end..layout.icons])
            .chain((0..n_icons).flat_map(|k| {
                let o = layout.icons + ICON_BYTES * k + 20;
                &bytes[o..o + 4]
            }));
        if zeros.copied().any(|b| b != 0) {
            return Err(bad(
                "a frame's zero bytes (header offset 42, padding, icon records' last four) must be zero",
            ));
        }
        let nku = nu as usize + degree_u as usize + 1;
        let nkv = if kind == KIND_CURVE {
            0
        } else {
            nv as usize + degree_v as usize + 1
        };
        let frame = Self {
            kind,
            design: le.u64(8),
            part: le.u64(16),
            revision: le.u64(24),
            flags: le.u16(6),
            degree_u,
            degree_v,
            nu,
            nv,
            knots_u: (0..nku).map(|k| le.f64(layout.knots_u + 8 * k)).collect(),
            knots_v: (0..nkv).map(|k| le.f64(layout.knots_v + 8 * k)).collect(),
            points: (0..nu as usize * nv as usize)
                .map(|k| {
                    let o = layout.points + 12 * k;
                    [le.f32(o), le.f32(o + 4), le.f32(o + 8)]
                })
                .collect(),
            icons: (0..n_icons)
                .map(|k| {
                    let o = layout.icons + ICON_BYTES * k;
                    FrameIcon {
                        id: le.u64(o),
                        xyz: [le.f32(o + 8), le.f32(o + 12), le.f32(o + 16)],
                    }
                })
                .collect(),
        };
        frame.check()?;
        Ok(frame)
    }
}
