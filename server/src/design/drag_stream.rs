//! The drag stream of a design (protocol/README.md, "Drag stream"): while a
//! part's drag stays on the kernel's fast path, its net is `R + ρ·d` with
//! `R` the net of a full geometry frame already published (the reference),
//! `ρ` the kernel's uniform response (one scalar per control point) and `d`
//! a 3-vector. A client that asks for the stream gets `ρ` once (a drag
//! basis, kind 5) and then 72 + 24·icons bytes per frame (kind 6) instead of
//! the whole net.
//!
//! Nothing here trusts the kernel's cache blindly: every frame is checked
//! against the solved net, computing `R + ρ·d` from the f32 numbers exactly
//! as a client does, and a frame that is not within [`TOLERANCE`] of the
//! model size goes out as a full frame (a full solve, a coupled response, a
//! joint solve with other parts, an adaptive-spring step the basis does not
//! cover). At rest every part gets a full frame, so the shape at rest is the
//! full frame's, bit for bit.

use axum::body::Bytes;
use glam::DVec3;
use std::collections::BTreeMap;
use std::sync::Arc;
use vsculpt_protocol as wire;
use wire::drag_frame::{DragBasis, DragFrame};
use wire::frame::{FrameIcon, GeometryFrame};

/// Largest distance, per coordinate and as a fraction of the model size (the
/// diagonal of the net's bounding box), between a client's `R + ρ·d` and the
/// server's net that a drag frame may carry. The requirement is 1e-6; the
/// margin covers the client storing its sum in f32.
pub const TOLERANCE: f64 = 2.5e-7;

/// One basis as clients receive it.
#[derive(Debug)]
pub struct StreamBasis {
    /// Names the basis (unique within the design's actor).
    pub id: u64,
    /// The revision of the reference frame.
    pub reference: u64,
    /// The reference frame (a full geometry frame), for a client that does
    /// not hold it.
    pub reference_frame: Bytes,
    /// The encoded [`DragBasis`].
    pub frame: Bytes,
    /// `frame` deflated, for the clients that asked (`deflate=1`).
    pub deflated: super::deflated_frame::DeflatedFrame,
    /// `reference_frame` deflated, for the clients that asked.
    pub reference_deflated: super::deflated_frame::DeflatedFrame,
}

/// One drag frame of one part as the stream carries it.
#[derive(Clone, Debug)]
pub struct StreamFrame {
    /// The basis it applies.
    pub basis: Arc<StreamBasis>,
    /// The encoded [`DragFrame`].
    pub frame: Bytes,
}

/// A part's running stream.
struct PartStream {
    basis: Arc<StreamBasis>,
    /// The kernel's basis it was made from (a new kernel basis starts a new
    /// stream).
    start: Vec<DVec3>,
    rho: Vec<f64>,
    /// What clients hold: the reference net and ρ, in f32.
    reference: Vec<[f32; 3]>,
    rho32: Vec<f32>,
    /// The control point with the largest |ρ| (where `d` is read).
    pivot: usize,
}

impl PartStream {
    /// `d` with `reference + ρ·d` within [`TOLERANCE`] of `points`, if any.
    fn fit(&self, points: &[DVec3]) -> Option<[f64; 3]> {
        if points.len() != self.reference.len() {
            return None;
        }
        let k = self.pivot;
        let r = self.rho32[k] as f64;
        if r == 0.0 {
            return None;
        }
        let d = [0, 1, 2].map(|c| (points[k][c] - self.reference[k][c] as f64) / r);
        if !d.iter().all(|x| x.is_finite()) {
            return None;
        }
        let tol = TOLERANCE * model_size(points);
        let fits = self
            .reference
            .iter()
            .zip(&self.rho32)
            .zip(points)
            .all(|((q, &r), p)| {
                let r = r as f64;
                (0..3).all(|c| (q[c] as f64 + r * d[c] - p[c]).abs() <= tol)
            });
        fits.then_some(d)
    }
}

/// The diagonal of the bounding box of `points` (at least 1e-300).
pub fn model_size(points: &[DVec3]) -> f64 {
    let (lo, hi) = points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    (hi - lo).length().max(1e-300)
}

/// The running streams of one design's parts.
#[derive(Default)]
pub struct DragStreams {
    parts: BTreeMap<u64, PartStream>,
    next_id: u64,
}

/// What a drag frame of one part needs to be streamed.
pub struct DragInput<'a> {
    /// The design.
    pub design: u64,
    /// The part.
    pub part: u64,
    /// The revision of this frame.
    pub revision: u64,
    /// The kernel's basis `(start, ρ)` of the part, if it has one.
    pub basis: Option<(&'a [DVec3], &'a [f64])>,
    /// The solved net.
    pub points: &'a [DVec3],
    /// The icon positions of this frame.
    pub icons: &'a [(u64, DVec3)],
    /// The part's frame published before this one (its revision and bytes).
    pub previous: Option<(u64, &'a Bytes)>,
    /// This frame as a full geometry frame.
    pub full: &'a Bytes,
}

impl DragStreams {
    /// Forgets every stream (the design changed as a whole).
    pub fn clear(&mut self) {
        self.parts.clear();
    }

    /// Forgets `part`'s stream (it changed other than by a drag).
    pub fn forget(&mut self, part: u64) {
        self.parts.remove(&part);
    }

    /// `[part]` when `part` has a running stream (its drag ended: it needs
    /// a full frame at rest, even if the release moved nothing), else none.
    pub fn at_rest(&self, part: u64) -> Vec<u64> {
        if self.parts.contains_key(&part) {
            vec![part]
        } else {
            Vec::new()
        }
    }

    /// The stream frame of a drag frame, or `None` when it goes out as a
    /// full frame only (the stream then may start from this frame).
    pub fn frame(&mut self, input: DragInput<'_>) -> Option<StreamFrame> {
        let Some((start, rho)) = input.basis else {
            self.forget(input.part);
            return None;
        };
        if rho.len() != input.points.len() || start.len() != input.points.len() {
            self.forget(input.part);
            return None;
        }
        if let Some(s) = self.parts.get(&input.part)
            && s.start == start
            && s.rho == rho
            && let Some(d) = s.fit(input.points)
        {
            let basis = s.basis.clone();
            return encode(&input, basis, d);
        }
        // A new kernel basis, or the old one no longer fits: try the frame
        // clients already hold as the reference, else this one.
        if let Some((rev, bytes)) = input.previous
            && let Some(s) = self.make(&input, start, rho, rev, bytes)
            && let Some(d) = s.fit(input.points)
        {
            let basis = s.basis.clone();
            self.parts.insert(input.part, s);
            return encode(&input, basis, d);
        }
        match self.make(&input, start, rho, input.revision, input.full) {
            Some(s) => {
                self.parts.insert(input.part, s);
            }
            None => self.forget(input.part),
        }
        None
    }

    /// A stream with reference frame `bytes` (revision `rev`).
    fn make(
        &mut self,
        input: &DragInput<'_>,
        start: &[DVec3],
        rho: &[f64],
        rev: u64,
        bytes: &Bytes,
    ) -> Option<PartStream> {
        let f = GeometryFrame::decode(bytes).ok()?;
        if f.kind != wire::frame::KIND_SURFACE || f.points.len() != rho.len() {
            return None;
        }
        let rho32: Vec<f32> = rho.iter().map(|&r| r as f32).collect();
        let pivot = rho32
            .iter()
            .enumerate()
            .fold((0, 0.0f32), |(bi, bv), (i, &r)| {
                if r.abs() > bv { (i, r.abs()) } else { (bi, bv) }
            })
            .0;
        self.next_id += 1;
        let frame = DragBasis {
            design: input.design,
            part: input.part,
            basis: self.next_id,
            reference: rev,
            rho: rho32.clone(),
        }
        .encode()
        .ok()?;
        Some(PartStream {
            basis: Arc::new(StreamBasis {
                id: self.next_id,
                reference: rev,
                reference_frame: bytes.clone(),
                frame: Bytes::from(frame),
                deflated: Default::default(),
                reference_deflated: Default::default(),
            }),
            start: start.to_vec(),
            rho: rho.to_vec(),
            reference: f.points,
            rho32,
            pivot,
        })
    }
}

fn encode(input: &DragInput<'_>, basis: Arc<StreamBasis>, d: [f64; 3]) -> Option<StreamFrame> {
    let frame = DragFrame {
        design: input.design,
        part: input.part,
        revision: input.revision,
        basis: basis.id,
        d,
        icons: input
            .icons
            .iter()
            .map(|(id, p)| FrameIcon {
                id: *id,
                xyz: p.as_vec3().to_array(),
            })
            .collect(),
    }
    .encode()
    .ok()?;
    Some(StreamFrame {
        basis,
        frame: Bytes::from(frame),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 × 4 cubic surface frame of `points` at `revision`.
    fn full(revision: u64, points: &[DVec3]) -> Bytes {
        let knots = vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        Bytes::from(
            GeometryFrame {
                kind: wire::frame::KIND_SURFACE,
                design: 1,
                part: 2,
                revision,
                flags: 0,
                degree_u: 3,
                degree_v: 3,
                nu: 4,
                nv: 4,
                knots_u: knots.clone(),
                knots_v: knots,
                points: points.iter().map(|p| p.as_vec3().to_array()).collect(),
                icons: Vec::new(),
            }
            .encode()
            .unwrap(),
        )
    }

    fn grid() -> (Vec<DVec3>, Vec<f64>) {
        let start: Vec<DVec3> = (0..16)
            .map(|k| DVec3::new((k / 4) as f64 * 10.0, (k % 4) as f64 * 10.0, 0.0))
            .collect();
        let rho: Vec<f64> = (0..16).map(|k| 1.0 / (1.0 + k as f64)).collect();
        (start, rho)
    }

    fn input<'a>(
        revision: u64,
        basis: (&'a [DVec3], &'a [f64]),
        points: &'a [DVec3],
        previous: Option<(u64, &'a Bytes)>,
        full: &'a Bytes,
    ) -> DragInput<'a> {
        DragInput {
            design: 1,
            part: 2,
            revision,
            basis: Some(basis),
            points,
            icons: &[],
            previous,
            full,
        }
    }

    #[test]
    fn a_drag_on_the_basis_streams_and_one_off_it_goes_full() {
        let (start, rho) = grid();
        let rest = full(1, &start);
        let mut streams = DragStreams::default();
        let t = DVec3::new(0.5, -2.0, 3.0);
        let moved: Vec<DVec3> = start.iter().zip(&rho).map(|(s, r)| *s + t * *r).collect();
        let f = full(2, &moved);
        let s = streams
            .frame(input(2, (&start, &rho), &moved, Some((1, &rest)), &f))
            .expect("on the basis: a stream frame");
        assert_eq!(s.basis.reference, 1);
        let d = DragFrame::decode(&s.frame).unwrap();
        let b = DragBasis::decode(&s.basis.frame).unwrap();
        let reference = GeometryFrame::decode(&rest).unwrap().points;
        let net = d.apply(&reference, &b.rho).unwrap();
        let tol = 1e-6 * model_size(&moved);
        for (a, p) in net.iter().zip(&moved) {
            for c in 0..3 {
                assert!((a[c] - p[c]).abs() <= tol, "{a:?} vs {p:?}");
            }
        }
        // One control point 1e-5 of the size off the basis: a full frame.
        let mut off = moved.clone();
        off[7].z += 1e-5 * model_size(&moved);
        let f3 = full(3, &off);
        assert!(
            streams
                .frame(input(3, (&start, &rho), &off, Some((2, &f)), &f3))
                .is_none()
        );
        // No kernel basis: a full frame, and the stream is gone.
        let f4 = full(4, &moved);
        let mut none = input(4, (&start, &rho), &moved, Some((3, &f3)), &f4);
        none.basis = None;
        assert!(streams.frame(none).is_none());
        assert!(streams.at_rest(2).is_empty());
    }

    #[test]
    fn a_shape_not_at_rest_on_the_basis_starts_the_stream_at_this_frame() {
        // The reference clients hold is not start + ρ·t for any t: the first
        // frame goes full and becomes the reference of the next.
        let (start, rho) = grid();
        let mut bent = start.clone();
        bent[5].z += 4.0;
        let rest = full(1, &bent);
        let mut streams = DragStreams::default();
        let at =
            |t: DVec3| -> Vec<DVec3> { start.iter().zip(&rho).map(|(s, r)| *s + t * *r).collect() };
        let p2 = at(DVec3::new(0.0, 0.0, 1.0));
        let f2 = full(2, &p2);
        assert!(
            streams
                .frame(input(2, (&start, &rho), &p2, Some((1, &rest)), &f2))
                .is_none()
        );
        let p3 = at(DVec3::new(0.0, 0.0, 2.0));
        let f3 = full(3, &p3);
        let s = streams
            .frame(input(3, (&start, &rho), &p3, Some((2, &f2)), &f3))
            .expect("the second frame streams");
        assert_eq!(s.basis.reference, 2);
        assert_eq!(streams.at_rest(2), vec![2]);
    }
}
