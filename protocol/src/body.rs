//! A Coons body part on the wire (paper 002): a trivariate B-spline volume
//! given by its control lattice, an optional morph target, the lattice
//! edits a client sends (`body_edit`: one point, a face's points or an
//! edge's points moved by a delta) and the morph time (`body_morph`).
//!
//! Every number is checked here ([`BodyData::validate`],
//! [`BodyEdit::validate`]): finite, within ±[`MAX_MAGNITUDE`], degrees
//! 1..=[`MAX_BODY_DEGREE`], at most [`MAX_BODY_POINTS_PER_DIR`] points
//! along a direction and [`MAX_BODY_POINTS`] in all, knot counts that fit.
//! What needs the kernel (clamped knots, det J > 0) the server checks.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::error::{ErrorCode, ProtocolError};
use crate::limits::MAX_MAGNITUDE;
use crate::types::{Knots, Vec3};

/// Highest degree of a body along any direction.
pub const MAX_BODY_DEGREE: u32 = 5;
/// Most control points along one direction of a body.
pub const MAX_BODY_POINTS_PER_DIR: usize = 32;
/// Most control points of one body.
pub const MAX_BODY_POINTS: usize = 4096;

/// A B-spline volume's control lattice: three clamped knot vectors and
/// `nu · nv · nw` control points with k (along w) fastest:
/// `points[(i * nv + j) * nw + k]`, where `n = knots − degree − 1` per
/// direction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LatticeData {
    /// Degree and knots along u (index i).
    pub u: Knots,
    /// Degree and knots along v (index j).
    pub v: Knots,
    /// Degree and knots along w (index k).
    pub w: Knots,
    /// The control points, k fastest.
    pub points: Vec<Vec3>,
}

/// A body part's shape: its lattice and, optionally, the body it morphs
/// into (paper 002 §4; the lattices need not match: the server refines one
/// to the other).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BodyData {
    /// The body.
    pub lattice: LatticeData,
    /// The body it morphs into, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub morph_target: Option<LatticeData>,
}

/// One of a lattice's six boundary faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BodyFace {
    /// i = 0 (u = start).
    UMin,
    /// i = nu − 1.
    UMax,
    /// j = 0.
    VMin,
    /// j = nv − 1.
    VMax,
    /// k = 0.
    WMin,
    /// k = nw − 1.
    WMax,
}

impl BodyFace {
    /// The direction held constant (0 u, 1 v, 2 w) and whether at the end.
    pub fn dir_end(self) -> (usize, bool) {
        match self {
            BodyFace::UMin => (0, false),
            BodyFace::UMax => (0, true),
            BodyFace::VMin => (1, false),
            BodyFace::VMax => (1, true),
            BodyFace::WMin => (2, false),
            BodyFace::WMax => (2, true),
        }
    }
}

/// Which lattice points an edit moves: `{"point": [i, j, k]}`,
/// `{"face": "u_min"}` or `{"edge": ["u_min", "w_max"]}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum LatticeSelection {
    /// One point `[i, j, k]` (indices along u, v, w).
    Point([u32; 3]),
    /// Every point of a boundary face.
    Face(BodyFace),
    /// Every point of a boundary edge: where two faces of different
    /// directions meet.
    Edge([BodyFace; 2]),
}

/// A lattice edit: the selected points move by `delta`. The server refuses
/// an edit that folds the body (det J ≤ 0 somewhere) and says where.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BodyEdit {
    /// The points.
    pub select: LatticeSelection,
    /// How far they move (model units).
    pub delta: Vec3,
}

fn err(code: ErrorCode, m: impl Into<String>) -> ProtocolError {
    ProtocolError::new(code, m)
}

fn number(name: &str, x: f64) -> Result<(), ProtocolError> {
    if !x.is_finite() {
        return Err(err(ErrorCode::NotFinite, format!("{name} is not finite")));
    }
    if x.abs() > MAX_MAGNITUDE {
        return Err(err(
            ErrorCode::OutOfRange,
            format!("{name} = {x} exceeds ±{MAX_MAGNITUDE}"),
        ));
    }
    Ok(())
}

impl LatticeData {
    /// Control points per direction (knots − degree − 1; 0 when too few knots).
    pub fn counts(&self) -> [usize; 3] {
        [&self.u, &self.v, &self.w].map(|k| k.knots.len().saturating_sub(k.degree as usize + 1))
    }

    /// Sizes, degrees and finiteness (knot order and det J are the server's).
    pub fn validate(&self) -> Result<(), ProtocolError> {
        for (name, k) in [("u", &self.u), ("v", &self.v), ("w", &self.w)] {
            if k.degree < 1 || k.degree > MAX_BODY_DEGREE {
                return Err(err(
                    ErrorCode::OutOfRange,
                    format!("body degree along {name} must be 1..={MAX_BODY_DEGREE}"),
                ));
            }
            if k.knots.len() > MAX_BODY_POINTS_PER_DIR + MAX_BODY_DEGREE as usize + 1 {
                return Err(err(
                    ErrorCode::TooLarge,
                    format!(
                        "body has too many knots along {name} (at most {MAX_BODY_POINTS_PER_DIR} points per direction)"
                    ),
                ));
            }
            let n = k.knots.len().saturating_sub(k.degree as usize + 1);
            if n < k.degree as usize + 1 {
                return Err(err(
                    ErrorCode::OutOfRange,
                    format!("body needs at least degree + 1 points along {name}"),
                ));
            }
            k.knots.iter().try_for_each(|&x| number("knot", x))?;
        }
        let c = self.counts();
        let total = c[0] * c[1] * c[2];
        if total > MAX_BODY_POINTS || self.points.len() > MAX_BODY_POINTS {
            return Err(err(
                ErrorCode::TooLarge,
                format!("a body has at most {MAX_BODY_POINTS} control points"),
            ));
        }
        if self.points.len() != total {
            return Err(err(
                ErrorCode::OutOfRange,
                format!(
                    "body has {} control points; its knots need {}·{}·{} = {total}",
                    self.points.len(),
                    c[0],
                    c[1],
                    c[2]
                ),
            ));
        }
        self.points
            .iter()
            .flatten()
            .try_for_each(|&x| number("control point", x))
    }
}

impl BodyData {
    /// Both lattices' checks.
    pub fn validate(&self) -> Result<(), ProtocolError> {
        self.lattice.validate()?;
        if let Some(t) = &self.morph_target {
            t.validate()?;
        }
        Ok(())
    }
}

impl BodyEdit {
    /// A finite delta within range; an edge's faces of two directions.
    pub fn validate(&self) -> Result<(), ProtocolError> {
        self.delta.iter().try_for_each(|&x| number("delta", x))?;
        if let LatticeSelection::Edge(faces) = &self.select
            && faces[0].dir_end().0 == faces[1].dir_end().0
        {
            return Err(err(
                ErrorCode::OutOfRange,
                "an edge is where faces of two different directions meet",
            ));
        }
        Ok(())
    }
}

/// Checks a morph time: finite, within [0, 1].
pub fn validate_morph_time(t: f64) -> Result<(), ProtocolError> {
    if !t.is_finite() {
        return Err(err(ErrorCode::NotFinite, "t is not finite"));
    }
    if !(0.0..=1.0).contains(&t) {
        return Err(err(
            ErrorCode::OutOfRange,
            format!("t = {t} is not in [0, 1]"),
        ));
    }
    Ok(())
}
