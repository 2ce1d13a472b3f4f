//! Lattices of several Coons bodies sharing faces (paper 002 §3: "each cell
//! of the control lattice defines a Coons body"; the spool and the chair).
//!
//! A [`BodyLattice`] holds B-spline volumes and [`Joint`]s: face `a` of one
//! body is face `b` of another. Shared faces share their control points one
//! to one: the two faces must have the same knots in the two tangential
//! directions, which run the same way in both bodies (the joint does not
//! reorient), and [`BodyLattice::set_point`] moves a shared point in both.
//!
//! **Continuity** is parametric, as in B-spline modelling, measured on a
//! sample grid of the shared face ([`BodyLattice::continuity`]): jumps of
//! position and of the first and second derivatives across the face with
//! respect to the bodies' own parameters. Bodies cut from one volume with
//! [`BodyLattice::split`] keep the global parameters, so a knot of
//! multiplicity r in a degree-p volume gives a C^{p−r} joint; multiplicity p
//! (C0) is how a sharp edge or corner is made ("multiple knots").

use glam::DVec3;

use super::{BSplineVolume, BodyError, Dir, Face, VolumeScratch};

/// Face `a.1` of body `a.0` is face `b.1` of body `b.0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Joint {
    /// One side: body index and face.
    pub a: (usize, Face),
    /// The other side.
    pub b: (usize, Face),
}

/// Largest jumps across a shared face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Continuity {
    /// max |x_a − x_b|.
    pub position: f64,
    /// max |∂x_a/∂n − ∂x_b/∂n| (n the cross parameter, oriented from a to b).
    pub first: f64,
    /// max |∂²x_a/∂n² − ∂²x_b/∂n²|.
    pub second: f64,
}

impl Continuity {
    /// The highest k ≤ 2 with all jumps up to order k within `tol`, or None
    /// if even the positions differ.
    pub fn order(&self, tol: f64) -> Option<usize> {
        if self.position > tol {
            None
        } else if self.first > tol {
            Some(0)
        } else if self.second > tol {
            Some(1)
        } else {
            Some(2)
        }
    }
}

/// Several bodies and the faces they share.
#[derive(Clone, Debug, Default)]
pub struct BodyLattice {
    bodies: Vec<BSplineVolume>,
    joints: Vec<Joint>,
}

impl BodyLattice {
    /// Bodies with no joints yet.
    pub fn new(bodies: Vec<BSplineVolume>) -> Self {
        Self {
            bodies,
            joints: Vec::new(),
        }
    }

    /// The bodies.
    pub fn bodies(&self) -> &[BSplineVolume] {
        &self.bodies
    }

    /// The joints.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// Declares that face `fa` of body `a` is face `fb` of body `b`: the
    /// tangential knots must agree and the face control points coincide
    /// within `tolerance` (then `b`'s are set to `a`'s).
    pub fn join(
        &mut self,
        a: usize,
        fa: Face,
        b: usize,
        fb: Face,
        tolerance: f64,
    ) -> Result<(), BodyError> {
        let n = self.bodies.len();
        if a >= n || b >= n || a == b {
            return Err(BodyError::Mismatch(format!("bodies {a} and {b} of {n}")));
        }
        let (va, vb) = (&self.bodies[a], &self.bodies[b]);
        let (a1, a2) = fa.dir.others();
        let (b1, b2) = fb.dir.others();
        if va.knots(a1) != vb.knots(b1) || va.knots(a2) != vb.knots(b2) {
            return Err(BodyError::Mismatch(
                "the shared faces have different knots".into(),
            ));
        }
        let (ia, ib) = (va.face_indices(fa), vb.face_indices(fb));
        let d = ia
            .iter()
            .zip(&ib)
            .map(|(&i, &j)| (va.points()[i] - vb.points()[j]).length())
            .fold(0.0, f64::max);
        if d > tolerance || d.is_nan() {
            return Err(BodyError::Incompatible {
                what: format!("face of body {a} and face of body {b}"),
                distance: d,
                tolerance,
            });
        }
        let pts: Vec<DVec3> = ia.iter().map(|&i| self.bodies[a].points()[i]).collect();
        for (&j, p) in ib.iter().zip(pts) {
            self.bodies[b].set_point(j, p)?;
        }
        self.joints.push(Joint {
            a: (a, fa),
            b: (b, fb),
        });
        Ok(())
    }

    /// Moves control point `index` of body `body` to `p`, and its twins in
    /// every body sharing it through joints. Returns the (body, index) pairs
    /// moved.
    pub fn set_point(
        &mut self,
        body: usize,
        index: usize,
        p: DVec3,
    ) -> Result<Vec<(usize, usize)>, BodyError> {
        if body >= self.bodies.len() {
            return Err(BodyError::Mismatch(format!("no body {body}")));
        }
        let mut moved = vec![(body, index)];
        let mut k = 0;
        while k < moved.len() {
            let (bi, ii) = moved[k];
            for j in &self.joints {
                for (this, other) in [(j.a, j.b), (j.b, j.a)] {
                    if this.0 != bi {
                        continue;
                    }
                    let fi = self.bodies[bi].face_indices(this.1);
                    if let Some(pos) = fi.iter().position(|&x| x == ii) {
                        let twin = (other.0, self.bodies[other.0].face_indices(other.1)[pos]);
                        if !moved.contains(&twin) {
                            moved.push(twin);
                        }
                    }
                }
            }
            k += 1;
        }
        for &(bi, ii) in &moved {
            self.bodies[bi].set_point(ii, p)?;
        }
        Ok(moved)
    }

    /// Jumps across joint `joint` measured on an `n × n` grid of the shared
    /// face (the two tangential parameters over their domain).
    pub fn continuity(&self, joint: usize, n: usize) -> Result<Continuity, BodyError> {
        let j = self
            .joints
            .get(joint)
            .ok_or_else(|| BodyError::Mismatch(format!("no joint {joint}")))?;
        let (va, vb) = (&self.bodies[j.a.0], &self.bodies[j.b.0]);
        let (fa, fb) = (j.a.1, j.b.1);
        // Cross derivative sign: from a into b. Leaving a at its end and
        // entering b at its start, both parameters increase from a to b.
        let sa = if fa.end { 1.0 } else { -1.0 };
        let sb = if fb.end { -1.0 } else { 1.0 };
        let (a1, a2) = fa.dir.others();
        let (b1, b2) = fb.dir.others();
        let da = va.domain();
        let db = vb.domain();
        let n = n.max(2);
        let mut out = Continuity {
            position: 0.0,
            first: 0.0,
            second: 0.0,
        };
        let mut s = VolumeScratch::default();
        for p in 0..n {
            for q in 0..n {
                let (fp, fq) = (p as f64 / (n - 1) as f64, q as f64 / (n - 1) as f64);
                let mut ta = [0.0; 3];
                let mut tb = [0.0; 3];
                let (l1, h1) = da[a1.index()];
                let (l2, h2) = da[a2.index()];
                ta[a1.index()] = l1 + (h1 - l1) * fp;
                ta[a2.index()] = l2 + (h2 - l2) * fq;
                ta[fa.dir.index()] = if fa.end {
                    da[fa.dir.index()].1
                } else {
                    da[fa.dir.index()].0
                };
                let (l1, h1) = db[b1.index()];
                let (l2, h2) = db[b2.index()];
                tb[b1.index()] = l1 + (h1 - l1) * fp;
                tb[b2.index()] = l2 + (h2 - l2) * fq;
                tb[fb.dir.index()] = if fb.end {
                    db[fb.dir.index()].1
                } else {
                    db[fb.dir.index()].0
                };
                let x = va.eval(&mut s, ta, 2);
                let y = vb.eval(&mut s, tb, 2);
                let (ca, cb) = (fa.dir.index(), fb.dir.index());
                out.position = out.position.max((x.p - y.p).length());
                out.first = out.first.max((x.d[ca] * sa - y.d[cb] * sb).length());
                out.second = out.second.max((x.dd[ca][ca] - y.dd[cb][cb]).length());
            }
        }
        Ok(out)
    }

    /// Cuts `volume` at the parameters `cuts` (increasing, inside the domain)
    /// in direction `dir` into bodies that keep the global parameters, joined
    /// face to face.
    pub fn split(volume: &BSplineVolume, dir: Dir, cuts: &[f64]) -> Result<Self, BodyError> {
        if cuts.windows(2).any(|w| w[1] <= w[0]) {
            return Err(BodyError::Mismatch("cuts must increase".into()));
        }
        let mut bodies = Vec::with_capacity(cuts.len() + 1);
        let mut rest = volume.clone();
        for &t in cuts {
            let (l, r) = rest.split(dir, t)?;
            bodies.push(l);
            rest = r;
        }
        bodies.push(rest);
        let mut lattice = Self::new(bodies);
        for i in 0..cuts.len() {
            lattice.join(
                i,
                Face { dir, end: true },
                i + 1,
                Face { dir, end: false },
                0.0,
            )?;
        }
        Ok(lattice)
    }
}
