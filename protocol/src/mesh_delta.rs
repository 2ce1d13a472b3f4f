//! The binary mesh delta (kind 8): a mesh frame (kind 3) of one part given
//! as the changes from an earlier mesh frame of the same part that the
//! client holds (its *base*, named by revision), for clients that ask for it
//! (`/ws?mesh_delta=1`).
//!
//! A DSM part's mesher re-meshes only the region an edit reaches and numbers
//! vertices leaf by leaf, and its frames are quantised on a cube that stays
//! put while an edit keeps the model's bounds; so most of a new frame's
//! vertices and triangles are runs of the base's, with the base's vertices
//! renumbered. A delta lists the new vertices as runs — copied from the base
//! or taken from its own literal vertices — and the new triangles likewise,
//! a copied triangle's indices mapped from the base's numbering to the new
//! one. Applying a delta to its base gives the new frame exactly
//! ([`MeshDelta::apply`]; the same bytes once encoded). protocol/README.md,
//! "Binary mesh delta (kind 8)", gives the layout byte by byte.

use crate::error::{ErrorCode, ProtocolError};
use crate::frame::{check_triangles, write_header};
use crate::mesh_frame::{
    MAX_MESH_TRIANGLES, MAX_MESH_VERTICES, MeshFrame, index_bytes, read_records, write_cube,
    write_records,
};
use std::collections::HashMap;
use std::hash::Hash;

/// Frame kind: a mesh frame given as changes from an earlier one.
pub const KIND_MESH_DELTA: u8 = 8;
/// Size of the mesh delta's header in bytes.
pub const DELTA_HEADER_BYTES: usize = 88;
/// A run's `source` meaning "the next `count` literal records of the delta".
pub const LITERAL: u32 = u32::MAX;
/// Shortest run the encoder copies from the base: a shorter one costs more
/// as a run between two literal runs (8 bytes of run, 8 more to split the
/// literals) than its records would as literals.
const MIN_COPY: usize = 4;

/// A run of the new mesh's vertices or triangles: `count` records copied
/// from the base from record `source` on, or, with `source` = [`LITERAL`],
/// the delta's next `count` literal records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Run {
    /// First record of the base, or [`LITERAL`].
    pub source: u32,
    /// Records in the run (≥ 1).
    pub count: u32,
}

/// A mesh frame of one part as the changes from its base frame.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshDelta {
    /// The design.
    pub design: u64,
    /// The part.
    pub part: u64,
    /// The revision of the frame this delta stands for.
    pub revision: u64,
    /// The revision of the base frame it applies to.
    pub base: u64,
    /// Bit flags of the frame it stands for (as a geometry frame's).
    pub flags: u16,
    /// The quantisation cube's origin: the base's and the new frame's.
    pub origin: [f32; 3],
    /// The quantisation step: the base's and the new frame's.
    pub step: f32,
    /// The new vertices, run after run.
    pub vertex_runs: Vec<Run>,
    /// The new triangles, run after run.
    pub triangle_runs: Vec<Run>,
    /// Literal vertices' quantised positions, in the order literal runs take them.
    pub positions: Vec<[u16; 3]>,
    /// Literal vertices' normals (i16 snorm).
    pub normals: Vec<[i16; 3]>,
    /// Literal triangles, with indices of the new mesh's numbering.
    pub triangles: Vec<[u32; 3]>,
}

fn bad(message: impl Into<String>) -> ProtocolError {
    ProtocolError::new(ErrorCode::Malformed, message)
}

/// The runs that make `new` from `old` (records of the base, None where a
/// record cannot be copied) and literal records; with `once`, no base record
/// is copied twice. Greedy: a run continues while the base's next record is
/// the next new one, else a new run starts at the base's first record equal
/// to it; copies shorter than [`MIN_COPY`] become literals.
fn runs<T: Hash + Eq + Copy>(old: &[Option<T>], new: &[T], once: bool) -> (Vec<Run>, Vec<T>) {
    let mut first: HashMap<T, u32> = HashMap::with_capacity(old.len());
    for (i, r) in old.iter().enumerate() {
        if let Some(r) = r {
            first.entry(*r).or_insert(i as u32);
        }
    }
    let mut used = vec![false; if once { old.len() } else { 0 }];
    // Raw copy runs (source, start in new, count).
    let mut copies: Vec<(u32, usize, usize)> = Vec::new();
    let mut j = 0;
    while j < new.len() {
        let Some(&i) = first.get(&new[j]) else {
            j += 1;
            continue;
        };
        let (i, start) = (i as usize, j);
        let mut n = 0;
        while start + n < new.len()
            && i + n < old.len()
            && old[i + n] == Some(new[start + n])
            && !(once && used[i + n])
        {
            n += 1;
        }
        if n >= MIN_COPY {
            if once {
                used[i..i + n].fill(true);
            }
            copies.push((i as u32, start, n));
            j += n;
        } else {
            j += 1;
        }
    }
    let mut out = Vec::new();
    let mut literal = Vec::new();
    let mut at = 0;
    let mut push_literal = |out: &mut Vec<Run>, from: usize, to: usize| {
        if to > from {
            out.push(Run {
                source: LITERAL,
                count: (to - from) as u32,
            });
            literal.extend_from_slice(&new[from..to]);
        }
    };
    for (source, start, count) in copies {
        push_literal(&mut out, at, start);
        out.push(Run {
            source,
            count: count as u32,
        });
        at = start + count;
    }
    push_literal(&mut out, at, new.len());
    (out, literal)
}

/// Σ counts of `runs` and of its literal runs, refusing an empty run and a
/// sum over `max`.
fn totals(runs: &[Run], max: usize, what: &str) -> Result<(usize, usize), ProtocolError> {
    let (mut all, mut literal) = (0usize, 0usize);
    for r in runs {
        if r.count == 0 {
            return Err(bad(format!("mesh delta has an empty {what} run")));
        }
        all += r.count as usize;
        if r.source == LITERAL {
            literal += r.count as usize;
        }
        if all > max {
            return Err(ProtocolError::new(
                ErrorCode::TooLarge,
                "mesh delta exceeds the size limits",
            ));
        }
    }
    Ok((all, literal))
}

impl MeshDelta {
    /// `next` as a delta from `base` (both of the same design and part and
    /// quantised on the same cube), or None when they differ in that, or
    /// when the delta would not be shorter than `next` itself.
    pub fn between(base: &MeshFrame, next: &MeshFrame) -> Option<Self> {
        if (base.design, base.part) != (next.design, next.part)
            || base.origin.map(f32::to_bits) != next.origin.map(f32::to_bits)
            || base.step.to_bits() != next.step.to_bits()
        {
            return None;
        }
        let vertex = |p: &[[u16; 3]], n: &[[i16; 3]], i: usize| (p[i], n[i]);
        let old: Vec<Option<_>> = (0..base.positions.len())
            .map(|i| Some(vertex(&base.positions, &base.normals, i)))
            .collect();
        let new: Vec<_> = (0..next.positions.len())
            .map(|i| vertex(&next.positions, &next.normals, i))
            .collect();
        let (vertex_runs, literal) = runs(&old, &new, true);
        // Where each base vertex goes in the new numbering.
        let mut map = vec![u32::MAX; base.positions.len()];
        let mut at = 0u32;
        for r in &vertex_runs {
            if r.source != LITERAL {
                for k in 0..r.count {
                    map[(r.source + k) as usize] = at + k;
                }
            }
            at += r.count;
        }
        let old_t: Vec<Option<[u32; 3]>> = base
            .triangles
            .iter()
            .map(|t| {
                let m = t.map(|i| map[i as usize]);
                (!m.contains(&u32::MAX)).then_some(m)
            })
            .collect();
        let (triangle_runs, triangles) = runs(&old_t, &next.triangles, false);
        let delta = Self {
            design: next.design,
            part: next.part,
            revision: next.revision,
            base: base.revision,
            flags: next.flags,
            origin: next.origin,
            step: next.step,
            vertex_runs,
            triangle_runs,
            positions: literal.iter().map(|v| v.0).collect(),
            normals: literal.iter().map(|v| v.1).collect(),
            triangles,
        };
        (delta.check().is_ok() && delta.byte_len() < next.byte_len()).then_some(delta)
    }

    /// The new frame's vertex and triangle counts (after [`check`](Self::check)).
    pub fn counts(&self) -> (usize, usize) {
        let sum = |runs: &[Run]| runs.iter().map(|r| r.count as usize).sum();
        (sum(&self.vertex_runs), sum(&self.triangle_runs))
    }

    /// The encoded length in bytes.
    pub fn byte_len(&self) -> usize {
        let (v, _) = self.counts();
        DELTA_HEADER_BYTES
            + 8 * (self.vertex_runs.len() + self.triangle_runs.len())
            + 12 * self.positions.len()
            + 3 * index_bytes(v) * self.triangles.len()
    }

    /// Checks sizes, numbers and the literal triangles' indices (the checks
    /// `decode` makes; what needs the base is checked by [`apply`](Self::apply)).
    pub fn check(&self) -> Result<(), ProtocolError> {
        let (v, lv) = totals(&self.vertex_runs, MAX_MESH_VERTICES, "vertex")?;
        let (_, lt) = totals(&self.triangle_runs, MAX_MESH_TRIANGLES, "triangle")?;
        if self.positions.len() != lv || self.normals.len() != lv {
            return Err(bad(format!(
                "mesh delta's literal runs take {lv} vertices, it has {} positions and {} normals",
                self.positions.len(),
                self.normals.len()
            )));
        }
        if self.triangles.len() != lt {
            return Err(bad(format!(
                "mesh delta's literal runs take {lt} triangles, it has {}",
                self.triangles.len()
            )));
        }
        if !(self.origin.iter().all(|x| x.is_finite()) && self.step.is_finite()) {
            return Err(ProtocolError::new(
                ErrorCode::NotFinite,
                "mesh delta has a non-finite origin or step",
            ));
        }
        if self.step < 0.0 {
            return Err(bad("mesh delta step is negative"));
        }
        check_triangles(&self.triangles, v)
    }

    /// The frame this delta stands for, made from `base`, which must be the
    /// frame of revision [`base`](Self::base) of the same design and part,
    /// on the same cube. A copy run beyond the base, a base vertex copied
    /// twice, or a copied triangle naming a base vertex that is not copied
    /// is refused (`malformed`); a wrong base is `conflict`.
    pub fn apply(&self, base: &MeshFrame) -> Result<MeshFrame, ProtocolError> {
        self.check()?;
        if (base.design, base.part, base.revision) != (self.design, self.part, self.base) {
            return Err(ProtocolError::new(
                ErrorCode::Conflict,
                format!(
                    "mesh delta of part {} applies to revision {}; the frame given is part {} revision {}",
                    self.part, self.base, base.part, base.revision
                ),
            ));
        }
        if base.origin.map(f32::to_bits) != self.origin.map(f32::to_bits)
            || base.step.to_bits() != self.step.to_bits()
        {
            return Err(ProtocolError::new(
                ErrorCode::Conflict,
                "mesh delta's cube is not its base's",
            ));
        }
        let (v, t) = self.counts();
        let bv = base.positions.len();
        let mut map = vec![u32::MAX; bv];
        let mut positions = Vec::with_capacity(v);
        let mut normals = Vec::with_capacity(v);
        let mut lit = 0;
        for r in &self.vertex_runs {
            let n = r.count as usize;
            if r.source == LITERAL {
                positions.extend_from_slice(&self.positions[lit..lit + n]);
                normals.extend_from_slice(&self.normals[lit..lit + n]);
                lit += n;
                continue;
            }
            let s = r.source as usize;
            if s + n > bv {
                return Err(bad(format!(
                    "mesh delta copies vertices {s}..{} of a base of {bv}",
                    s + n
                )));
            }
            for (k, slot) in map.iter_mut().enumerate().skip(s).take(n) {
                if *slot != u32::MAX {
                    return Err(bad(format!("mesh delta copies base vertex {k} twice")));
                }
                *slot = positions.len() as u32;
                positions.push(base.positions[k]);
                normals.push(base.normals[k]);
            }
        }
        let mut triangles = Vec::with_capacity(t);
        let mut lit = 0;
        for r in &self.triangle_runs {
            let n = r.count as usize;
            if r.source == LITERAL {
                triangles.extend_from_slice(&self.triangles[lit..lit + n]);
                lit += n;
                continue;
            }
            let s = r.source as usize;
            let Some(copied) = base.triangles.get(s..s + n) else {
                return Err(bad(format!(
                    "mesh delta copies triangles {s}..{} of a base of {}",
                    s + n,
                    base.triangles.len()
                )));
            };
            for tri in copied {
                let m = tri.map(|i| map.get(i as usize).copied().unwrap_or(u32::MAX));
                if m.contains(&u32::MAX) {
                    return Err(bad(format!(
                        "mesh delta copies base triangle {tri:?}, which names a vertex it does not keep"
                    )));
                }
                triangles.push(m);
            }
        }
        let frame = MeshFrame {
            design: self.design,
            part: self.part,
            revision: self.revision,
            flags: self.flags,
            origin: self.origin,
            step: self.step,
            positions,
            normals,
            triangles,
        };
        frame.check()?;
        Ok(frame)
    }

    /// The delta as bytes (after [`check`](Self::check)).
    pub fn encode(&self) -> Result<Vec<u8>, ProtocolError> {
        self.check()?;
        let (v, t) = self.counts();
        let ib = index_bytes(v);
        let mut out = Vec::with_capacity(self.byte_len());
        write_header(
            &mut out,
            KIND_MESH_DELTA,
            self.flags,
            (self.design, self.part, self.revision),
        );
        out.extend_from_slice(&self.base.to_le_bytes());
        for n in [
            v,
            t,
            self.vertex_runs.len(),
            self.triangle_runs.len(),
            self.positions.len(),
            self.triangles.len(),
        ] {
            out.extend_from_slice(&(n as u32).to_le_bytes());
        }
        write_cube(&mut out, self.origin, self.step, ib, DELTA_HEADER_BYTES);
        for r in self.vertex_runs.iter().chain(&self.triangle_runs) {
            out.extend_from_slice(&r.source.to_le_bytes());
            out.extend_from_slice(&r.count.to_le_bytes());
        }
        write_records(
            &mut out,
            (&self.positions, &self.normals),
            &self.triangles,
            ib,
        );
        debug_assert_eq!(out.len(), self.byte_len());
        Ok(out)
    }

    /// Parses a mesh delta. Any byte string gives a delta or an error; never a panic.
    pub fn decode(bytes: &[u8]) -> Result<Self, ProtocolError> {
        crate::frame::check_header(bytes, KIND_MESH_DELTA, DELTA_HEADER_BYTES, "mesh delta")?;
        let le = crate::frame::Le(bytes);
        let [v, t, rv, rt, lv, lt] = [40, 44, 48, 52, 56, 60].map(|o| le.u32(o) as usize);
        if v > MAX_MESH_VERTICES || t > MAX_MESH_TRIANGLES || rv > v || rt > t || lv > v || lt > t {
            return Err(ProtocolError::new(
                ErrorCode::TooLarge,
                "mesh delta's counts exceed the size limits or the new mesh",
            ));
        }
        let ib = bytes[80] as usize;
        if ib != index_bytes(v) {
            return Err(bad(format!(
                "index width {ib} does not fit {v} vertices (want {})",
                index_bytes(v)
            )));
        }
        if bytes[81..DELTA_HEADER_BYTES].iter().any(|&b| b != 0) {
            return Err(bad("mesh delta header padding is not zero"));
        }
        let total = DELTA_HEADER_BYTES + 8 * (rv + rt) + 12 * lv + 3 * ib * lt;
        if bytes.len() != total {
            return Err(bad(format!(
                "mesh delta has {} bytes, its header says {total}",
                bytes.len()
            )));
        }
        let run = |k: usize| Run {
            source: le.u32(DELTA_HEADER_BYTES + 8 * k),
            count: le.u32(DELTA_HEADER_BYTES + 8 * k + 4),
        };
        let (positions, normals, triangles) =
            read_records(bytes, DELTA_HEADER_BYTES + 8 * (rv + rt), (lv, lt), ib);
        let delta = Self {
            design: le.u64(8),
            part: le.u64(16),
            revision: le.u64(24),
            base: le.u64(32),
            flags: le.u16(6),
            origin: [le.f32(64), le.f32(68), le.f32(72)],
            step: le.f32(76),
            vertex_runs: (0..rv).map(run).collect(),
            triangle_runs: (rv..rv + rt).map(run).collect(),
            positions,
            normals,
            triangles,
        };
        delta.check()?;
        if delta.counts() != (v, t) {
            return Err(bad(format!(
                "mesh delta's runs make {:?} vertices and triangles, its header says ({v}, {t})",
                delta.counts()
            )));
        }
        Ok(delta)
    }
}
