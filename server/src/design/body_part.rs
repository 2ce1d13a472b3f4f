//! A Coons body part in the design document (paper 002): the control
//! lattice of a B-spline volume and an optional morph target, as plain
//! serde data; the validation of untrusted lattices (sizes, finiteness,
//! clamped knots, det J > 0 proved by the kernel) and the lattice edits
//! (one point, a face's or an edge's points moved by a delta), refused
//! with the place where they would fold the body.

use super::doc::{IconDoc, SurfaceDoc};
use super::error::{CommandError, ErrorKind};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use vsculpt_kernel::body::{BSplineVolume, BodyError, Dir, Face, Morph, Path};
use vsculpt_kernel::bspline::KnotVector;

/// Highest degree along any direction.
pub const MAX_BODY_DEGREE: usize = 5;
/// Most control points along one direction.
pub const MAX_BODY_POINTS_PER_DIR: usize = 32;
/// Most control points of one body.
pub const MAX_BODY_POINTS: usize = 4096;
/// Largest coordinate accepted (as the protocol's limit).
pub const MAX_BODY_MAGNITUDE: f64 = 1e9;

fn invalid(msg: impl Into<String>) -> CommandError {
    CommandError::new(ErrorKind::InvalidValue, msg)
}

/// A B-spline volume's lattice: degree and knots per direction (u, v, w),
/// control points with k fastest (`(i * nv + j) * nw + k`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LatticeDoc {
    /// Degrees along u, v, w.
    pub degrees: [usize; 3],
    /// Knots along u, v, w.
    pub knots: [Vec<f64>; 3],
    /// Control points, k fastest.
    pub points: Vec<[f64; 3]>,
}

/// A body part: its lattice and the body it morphs into, if any. It has no
/// material; `icons` stays empty (kept so every part kind has icons).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyPart {
    /// The body.
    pub lattice: LatticeDoc,
    /// The body it morphs into.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub morph_target: Option<LatticeDoc>,
    /// Always empty: a body is shaped by its lattice, not by icons.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub icons: Vec<IconDoc>,
}

/// Which lattice points an edit moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LatticeSelect {
    /// One point (i, j, k).
    Point([usize; 3]),
    /// A boundary face: the direction held constant (0 u, 1 v, 2 w) and
    /// whether at its last index.
    Face(usize, bool),
    /// A boundary edge: two faces of different directions.
    Edge([(usize, bool); 2]),
}

/// The message of a fold: where (parameters and model point) and det J.
pub fn fold_error(e: BodyError, vol: &BSplineVolume) -> CommandError {
    match e {
        BodyError::Folds { u, v, w, det } => {
            let x = vol.point(u, v, w);
            invalid(format!(
                "the edit folds the body at (u, v, w) = ({u:.4}, {v:.4}, {w:.4}) — x = ({:.4}, {:.4}, {:.4}): det J = {det:.3e}",
                x.x, x.y, x.z
            ))
        }
        other => invalid(format!("body: {other}")),
    }
}

impl LatticeDoc {
    /// Control points per direction.
    pub fn counts(&self) -> [usize; 3] {
        [0, 1, 2].map(|d| self.knots[d].len().saturating_sub(self.degrees[d] + 1))
    }

    /// The kernel volume after the structural checks (degrees, sizes,
    /// finiteness, clamped knots: the kernel's `KnotVector::new`). Not yet
    /// checked for folds.
    pub fn volume(&self) -> Result<BSplineVolume, CommandError> {
        for d in 0..3 {
            let p = self.degrees[d];
            if p == 0 || p > MAX_BODY_DEGREE {
                return Err(invalid(format!(
                    "body degrees must be between 1 and {MAX_BODY_DEGREE}"
                )));
            }
            let n = self.knots[d].len().saturating_sub(p + 1);
            if n < p + 1 || n > MAX_BODY_POINTS_PER_DIR {
                return Err(invalid(format!(
                    "a body has degree + 1 to {MAX_BODY_POINTS_PER_DIR} control points per direction"
                )));
            }
        }
        let c = self.counts();
        let total = c[0] * c[1] * c[2];
        if total > MAX_BODY_POINTS {
            return Err(invalid(format!(
                "a body has at most {MAX_BODY_POINTS} control points"
            )));
        }
        if self.points.len() != total {
            return Err(invalid(format!(
                "the body has {} control points; its knots need {total}",
                self.points.len()
            )));
        }
        let finite = self.knots.iter().flatten().all(|x| x.is_finite())
            && self
                .points
                .iter()
                .flatten()
                .all(|x| x.is_finite() && x.abs() <= MAX_BODY_MAGNITUDE);
        if !finite {
            return Err(CommandError::new(
                ErrorKind::NotFinite,
                format!(
                    "body knots and control points must be finite and within ±{MAX_BODY_MAGNITUDE}"
                ),
            ));
        }
        let kv = |d: usize| {
            KnotVector::new(self.degrees[d], self.knots[d].clone())
                .map_err(|e| invalid(format!("body knots along {}: {e}", ["u", "v", "w"][d])))
        };
        let (u, v, w) = (kv(0)?, kv(1)?, kv(2)?);
        BSplineVolume::new(
            u,
            v,
            w,
            self.points.iter().map(|p| DVec3::from(*p)).collect(),
        )
        .map_err(|e| invalid(format!("body: {e}")))
    }

    /// The volume, proved injective (det J > 0), or the place it folds
    /// (proofs of unchanged cells are kept between checks: `body_proof`).
    pub fn checked_volume(&self) -> Result<BSplineVolume, CommandError> {
        let vol = self.volume()?;
        super::body_proof::prove(&vol).map_err(|e| fold_error(e, &vol))?;
        Ok(vol)
    }

    /// The lattice of a kernel volume.
    pub fn from_volume(vol: &BSplineVolume) -> Self {
        Self {
            degrees: vol.degrees(),
            knots: Dir::ALL.map(|d| vol.knots(d).knots().to_vec()),
            points: vol.points().iter().map(|p| p.to_array()).collect(),
        }
    }

    /// The storage indices `sel` names, or an error for an index outside
    /// the lattice or an edge of two faces of one direction.
    pub fn indices(&self, sel: LatticeSelect) -> Result<Vec<usize>, CommandError> {
        let c = self.counts();
        let at = |ijk: [usize; 3]| (ijk[0] * c[1] + ijk[1]) * c[2] + ijk[2];
        let fixed = |d: usize, end: bool| if end { c[d] - 1 } else { 0 };
        let all =
            (0..c[0]).flat_map(|i| (0..c[1]).flat_map(move |j| (0..c[2]).map(move |k| [i, j, k])));
        Ok(match sel {
            LatticeSelect::Point(ijk) => {
                if (0..3).any(|d| ijk[d] >= c[d]) {
                    return Err(invalid(format!(
                        "lattice point {ijk:?} is outside a {}×{}×{} lattice",
                        c[0], c[1], c[2]
                    )));
                }
                vec![at(ijk)]
            }
            LatticeSelect::Face(d, end) => {
                if d > 2 {
                    return Err(invalid("a face's direction is u, v or w"));
                }
                all.filter(|ijk| ijk[d] == fixed(d, end)).map(at).collect()
            }
            LatticeSelect::Edge([(d1, e1), (d2, e2)]) => {
                if d1 > 2 || d2 > 2 || d1 == d2 {
                    return Err(invalid(
                        "an edge is where faces of two different directions meet",
                    ));
                }
                all.filter(|ijk| ijk[d1] == fixed(d1, e1) && ijk[d2] == fixed(d2, e2))
                    .map(at)
                    .collect()
            }
        })
    }

    /// The boundary faces as B-spline surfaces oriented outward (for a body
    /// with det J > 0), in the kernel's face order (u = start, u = end, v …):
    /// a face whose natural normal points inward has its first parameter
    /// reversed, which is exact.
    pub fn faces(&self) -> Result<Vec<(Face, SurfaceDoc)>, CommandError> {
        let vol = self.volume()?;
        Ok(Face::ALL
            .iter()
            .map(|&face| {
                let s = vol.face(face);
                let (nu, nv) = (s.u_knots().num_ctrl(), s.v_knots().num_ctrl());
                let mut doc = SurfaceDoc {
                    u_degree: s.u_knots().degree(),
                    v_degree: s.v_knots().degree(),
                    u_knots: s.u_knots().knots().to_vec(),
                    v_knots: s.v_knots().knots().to_vec(),
                    nu,
                    nv,
                    points: s.points().iter().map(|p| p.to_array()).collect(),
                };
                let inward = match face.dir {
                    Dir::U | Dir::W => !face.end,
                    Dir::V => face.end,
                };
                if inward {
                    let (a, b) = (doc.u_knots[0], doc.u_knots[doc.u_knots.len() - 1]);
                    doc.u_knots = doc.u_knots.iter().rev().map(|k| a + b - k).collect();
                    let old = std::mem::take(&mut doc.points);
                    doc.points = (0..nu)
                        .flat_map(|i| (0..nv).map(move |j| (nu - 1 - i) * nv + j))
                        .map(|idx| old[idx])
                        .collect();
                }
                (face, doc)
            })
            .collect())
    }
}

impl BodyPart {
    /// Full validation of untrusted content: both lattices build and are
    /// injective; the two bodies correspond (one lattice refines to the
    /// other's).
    pub fn validate(&self) -> Result<(), CommandError> {
        if !self.icons.is_empty() {
            return Err(invalid("a body part has no icons"));
        }
        let a = self.lattice.checked_volume()?;
        if let Some(t) = &self.morph_target {
            let b = t
                .checked_volume()
                .map_err(|e| CommandError::new(e.kind, format!("morph target: {}", e.message)))?;
            Morph::new(&a, &b, Path::Eased)
                .map_err(|e| invalid(format!("the morph target does not correspond: {e}")))?;
        }
        Ok(())
    }

    /// Moves the points `sel` names by `delta`; refused (the part unchanged)
    /// when `delta` is not finite or the result folds, with where.
    pub fn move_points(&mut self, sel: LatticeSelect, delta: [f64; 3]) -> Result<(), CommandError> {
        if !delta.iter().all(|x| x.is_finite()) {
            return Err(CommandError::new(
                ErrorKind::NotFinite,
                "delta must be finite (no NaN or ∞)",
            ));
        }
        let idx = self.lattice.indices(sel)?;
        let mut next = self.lattice.clone();
        for i in idx {
            let p = &mut next.points[i];
            for a in 0..3 {
                p[a] += delta[a];
            }
        }
        next.checked_volume()?;
        self.lattice = next;
        Ok(())
    }
}
