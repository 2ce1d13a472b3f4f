//! Metamorphosis of two bodies (paper 002 §4): grid-point correspondence and
//! a path per grid point.
//!
//! **Correspondence.** Both bodies are brought onto one spline space per
//! direction — knots normalised to [0, 1], degree raised to the larger,
//! knots merged and inserted — all exact changes of basis, so each body
//! keeps its shape and its parametrisation, and then grid point (i, j, k) of
//! one corresponds to grid point (i, j, k) of the other: the points at the
//! same place of the common parametrisation. (The paper leaves the matching
//! open; this one is the natural one for bodies modelled from the same
//! cube, like the spool.)
//!
//! **Paths** ([`Path`]), with A the source and B the target grid point:
//! * `Linear`: (1 − t) A + t B;
//! * `Eased`: the straight path with the smoothstep timing s = 3t² − 2t³
//!   (starts and stops at rest, C1 in time);
//! * `Hermite`: per grid point a cubic Hermite curve with given end
//!   velocities (e.g. to swing points around an obstacle).
//!
//! t = 0 and t = 1 give A and B exactly (the blend weights are exactly 0 and
//! 1 there). [`Morph::check_injective`] proves det J > 0 for the body at a
//! set of times (the check is per frame: in between, injectivity follows
//! only from continuity of det J in t, not from a proof).

use glam::DVec3;

use super::injective::{InjectivityReport, check_injective};
use super::space::common_knots;
use super::{BSplineVolume, BodyError, Dir};

/// How each grid point travels.
#[derive(Clone, Debug, PartialEq)]
pub enum Path {
    /// Straight, constant speed.
    Linear,
    /// Straight, smoothstep timing.
    Eased,
    /// Cubic Hermite per grid point with velocities (per unit t) at the
    /// start and at the end, one per grid point of the common lattice.
    Hermite {
        /// dP/dt at t = 0.
        start: Vec<DVec3>,
        /// dP/dt at t = 1.
        end: Vec<DVec3>,
    },
}

/// Two corresponding bodies and the paths between them.
#[derive(Clone, Debug)]
pub struct Morph {
    a: BSplineVolume,
    b: BSplineVolume,
    path: Path,
}

/// `a` and `b` on one common spline space per direction (see the module doc).
pub fn correspond(
    a: &BSplineVolume,
    b: &BSplineVolume,
) -> Result<(BSplineVolume, BSplineVolume), BodyError> {
    let (mut a, mut b) = (a.normalized(), b.normalized());
    for d in Dir::ALL {
        let k = common_knots(&[a.knots(d), b.knots(d)])?;
        for v in [&mut a, &mut b] {
            let up = k.degree() - v.knots(d).degree();
            *v = v.elevate(d, up)?;
            *v = v.refine(d, &k)?;
        }
    }
    if Dir::ALL.iter().any(|&d| a.knots(d) != b.knots(d)) {
        return Err(BodyError::Mismatch("no common lattice".into()));
    }
    Ok((a, b))
}

impl Morph {
    /// The metamorphosis from `a` to `b` along `path` (a `Hermite` path's
    /// velocities are per grid point of the *common* lattice: build it with
    /// [`correspond`] first to know the count).
    pub fn new(a: &BSplineVolume, b: &BSplineVolume, path: Path) -> Result<Self, BodyError> {
        let (a, b) = correspond(a, b)?;
        if let Path::Hermite { start, end } = &path {
            let n = a.points().len();
            if start.len() != n || end.len() != n {
                return Err(BodyError::Mismatch(format!(
                    "Hermite path needs {n} velocities at each end"
                )));
            }
            if start.iter().chain(end).any(|v| !v.is_finite()) {
                return Err(BodyError::NonFinite("Hermite velocity".into()));
            }
        }
        Ok(Self { a, b, path })
    }

    /// The source on the common lattice.
    pub fn source(&self) -> &BSplineVolume {
        &self.a
    }

    /// The target on the common lattice.
    pub fn target(&self) -> &BSplineVolume {
        &self.b
    }

    /// The body at time `t` (clamped to [0, 1]; NaN counts as 0).
    pub fn at(&self, t: f64) -> BSplineVolume {
        let mut out = self.a.clone();
        self.at_into(t, &mut out);
        out
    }

    /// The body at time `t` written into `out`, which must be a body of the
    /// common lattice (e.g. from [`Morph::source`]); allocation-free, for
    /// streaming frames. A body of another size is replaced.
    pub fn at_into(&self, t: f64, out: &mut BSplineVolume) {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        if out.points().len() != self.a.points().len() || out.counts() != self.a.counts() {
            *out = self.a.clone();
        }
        let (pa, pb) = (self.a.points(), self.b.points());
        let pts = out.points_mut_crate();
        match &self.path {
            Path::Linear | Path::Eased => {
                let s = if matches!(self.path, Path::Eased) {
                    t * t * (3.0 - 2.0 * t)
                } else {
                    t
                };
                for ((o, a), b) in pts.iter_mut().zip(pa).zip(pb) {
                    *o = *a * (1.0 - s) + *b * s;
                }
            }
            Path::Hermite { start, end } => {
                let (t2, t3) = (t * t, t * t * t);
                let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
                let h10 = t3 - 2.0 * t2 + t;
                let h01 = -2.0 * t3 + 3.0 * t2;
                let h11 = t3 - t2;
                for (r, o) in pts.iter_mut().enumerate() {
                    *o = pa[r] * h00 + start[r] * h10 + pb[r] * h01 + end[r] * h11;
                }
            }
        }
    }

    /// Proves det J > 0 for the bodies at t = k / steps, k = 0 … steps; the
    /// first failure is returned as [`BodyError::Folds`] with its time.
    pub fn check_injective(
        &self,
        steps: usize,
    ) -> Result<Vec<(f64, InjectivityReport)>, (f64, BodyError)> {
        let steps = steps.max(1);
        let mut out = Vec::with_capacity(steps + 1);
        let mut body = self.a.clone();
        for k in 0..=steps {
            let t = k as f64 / steps as f64;
            self.at_into(t, &mut body);
            match check_injective(&body) {
                Ok(r) => out.push((t, r)),
                Err(e) => return Err((t, e)),
            }
        }
        Ok(out)
    }
}
