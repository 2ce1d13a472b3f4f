//! A styling-curve network part on the wire (paper 004): B-spline curves,
//! the meetings and faces the server finds between them, the faces it has
//! faired, and the edits a client sends (`network_edit`): move a control
//! point, drag a point of a curve, add or remove a curve, fair a face, set
//! a side's ribbon handles (scale, twist).
//! A fair runs as a job off the design's thread: its progress
//! ([`FairingProgress`]) and how it ended ([`FairingOutcome`]) go to every
//! client; an editor may cancel it (`cancel_fairing`).
//!
//! The filled patches travel as mesh frames (kind 3, [`crate::mesh_frame`]):
//! one mesh of every face of the part, faces one after another in face
//! order. Every number is checked here ([`NetworkData::validate`],
//! [`NetworkEdit::validate`]); what needs the part (curve and face indices,
//! whether the curves still meet and enclose faces) the server checks.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::error::{ErrorCode, ProtocolError};
use crate::limits::{MAX_KNOTS, MAX_MAGNITUDE};
use crate::parts::CurveData;
use crate::types::Vec3;

/// Most curves in one network part.
pub const MAX_NETWORK_CURVES: usize = 64;
/// Most sweeps a fairing request may ask for.
pub const MAX_FAIRING_ITERATIONS: u32 = 100_000;
/// Most a side's ribbon scale may be; the least is its inverse (1/10).
pub const MAX_RIBBON_SCALE: f64 = 10.0;
/// Most tuning handles a `set_tuning` may carry (a face of 64 sides).
pub const MAX_TUNING_HANDLES: usize = MAX_NETWORK_CURVES + 1;

/// A network part's shape: its curves and what the server found of them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NetworkData {
    /// The styling curves (clamped B-splines), indexed from 0.
    pub curves: Vec<CurveData>,
    /// Curves closer than this meet (model units, > 0).
    pub tolerance: f64,
    /// The side the patches' normals face (non-zero).
    pub up: Vec3,
    /// Where curves meet (found by the server; ignored in `create_part`).
    #[serde(default)]
    pub meetings: Vec<Meeting>,
    /// The faces the curves enclose (found by the server; ignored in
    /// `create_part`).
    #[serde(default)]
    pub faces: Vec<NetworkFace>,
    /// The faces whose patch was replaced by a faired point mesh, by face
    /// index (set by the server; ignored in `create_part`).
    #[serde(default)]
    pub faired: Vec<u32>,
    /// Per face, per side, its ribbon handles (set by the server; ignored
    /// in `create_part`; left out when there are no faces).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ribbons: Vec<Vec<RibbonHandles>>,
    /// Per face, its tuning handles (paper 004's u²v² terms): n + 1
    /// offsets for a face of n sides — the centre's, then one per corner
    /// (corner k where side k starts) — added to the patch with weights
    /// that vanish with their gradient on the whole boundary, so they
    /// reshape the interior only (set by the server; ignored in
    /// `create_part`; left out when there are no faces).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tuning: Vec<Vec<Vec3>>,
}

/// A side's ribbon handles (paper 004 §5): how the patch leaves the side.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RibbonHandles {
    /// The cross-boundary derivative's length is multiplied by
    /// 1 + (scale − 1)·sin(πs) along the side (1: the ribbon the corners
    /// give; in [1/10, 10]).
    pub scale: f64,
    /// The tangent plane along the side turned about its curve by
    /// twist·sin(πu) radians on each of its edges (0: none; |twist| < π/2).
    /// Shared with the face across the side, so the join stays G1.
    pub twist: f64,
}

/// A point where two or more curves meet.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Meeting {
    /// Where.
    pub point: Vec3,
    /// The curves there with their parameter: `[curve, t]` pairs.
    pub curves: Vec<(u32, f64)>,
}

/// A face: its sides in order around it, each a stretch of one curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NetworkFace {
    /// The sides (3 or more).
    pub sides: Vec<FaceSide>,
}

/// One side of a face: curve `curve` from `t_start` to `t_end`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FaceSide {
    /// The curve.
    pub curve: u32,
    /// Where the side starts on it.
    pub t_start: f64,
    /// Where it ends.
    pub t_end: f64,
}

/// The curvature measure fairness goals are given in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum FairnessMeasure {
    /// H = (k1 + k2)/2.
    Mean,
    /// K = k1 k2 (bending away from the normal where K ≥ 0).
    Gaussian,
    /// The larger principal curvature (refused by the kernel).
    MaxPrincipal,
    /// The smaller principal curvature (refused by the kernel).
    MinPrincipal,
}

/// Where the goal values come from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum FairingGoal {
    /// The same value at every interior point: `{"constant": 1.0}`.
    Constant(f64),
    /// The measure at the boundary points spread harmonically inside:
    /// `"from_boundary"`.
    FromBoundary,
}

/// A fairing run on one face, as the kernel takes it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FairingRequest {
    /// The face (index into `faces`).
    pub face: u32,
    /// The measure of the goals.
    pub measure: FairnessMeasure,
    /// The goals.
    pub goal: FairingGoal,
    /// Relaxation ω in (0, 2); 1 when omitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relaxation: Option<f64>,
    /// Convergence: the largest move of a sweep relative to the mesh size
    /// (> 0); 1e-10 when omitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// Sweeps at most (1 ..= 100 000); 200 when omitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_iterations: Option<u32>,
}

/// One edit of a network part. Each is one undoable step; a refused edit
/// changes nothing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub enum NetworkEdit {
    /// Move control point `index` of curve `curve` to `xyz`.
    MovePoint {
        /// The curve.
        curve: u32,
        /// The control point.
        index: u32,
        /// Where to.
        xyz: Vec3,
    },
    /// Drag the point at parameter `t` of curve `curve` to `xyz`: the
    /// smallest change of the curve's control points that takes c(t) to
    /// `xyz` and keeps every meeting of the curve where it is.
    DragPoint {
        /// The curve.
        curve: u32,
        /// The parameter of the dragged point.
        t: f64,
        /// Where it goes.
        xyz: Vec3,
    },
    /// Add a curve (it must meet the others so that every face closes).
    AddCurve {
        /// The curve.
        curve: CurveData,
    },
    /// Remove curve `curve` (later curves' indices drop by one).
    RemoveCurve {
        /// The curve.
        curve: u32,
    },
    /// Fair one face's point mesh toward curvature goals (paper 004 §8);
    /// the faired mesh replaces the face's patch until its curves change.
    Fair(FairingRequest),
    /// Set side `side` of face `face`'s ribbon handles (at least one of
    /// `scale`, `twist`; an omitted one keeps its value): the patches
    /// update and a mesh frame follows.
    SetRibbon {
        /// The face.
        face: u32,
        /// The side (index into the face's `sides`).
        side: u32,
        /// The new scale, in [1/10, 10].
        #[serde(default, skip_serializing_if = "Option::is_none")]
        scale: Option<f64>,
        /// The new twist in radians, |twist| < π/2.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        twist: Option<f64>,
    },
    /// Set face `face`'s tuning handles (see [`NetworkData::tuning`]): all
    /// n + 1 of them (zero vectors for none); the face's interior moves,
    /// its boundary and the tangent planes along it stay.
    SetTuning {
        /// The face.
        face: u32,
        /// The centre's offset, then each corner's (n + 1 for n sides).
        handles: Vec<Vec3>,
    },
}

/// How a fairing job ended (`fairing_ended`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum FairingOutcome {
    /// The faired mesh replaced the face's patch: one undoable edit
    /// (`network_changed` and a mesh frame follow or came just before).
    Applied,
    /// An editor cancelled it (or its part was deleted): nothing changed.
    Cancelled,
    /// The face changed while it ran (a curve of the face moved, an undo):
    /// the result fits a mesh that is gone, so nothing changed.
    Discarded,
    /// The kernel refused the run (no fit at a point, divergence): nothing
    /// changed.
    Failed,
}

/// A fairing job's state after a sweep (`fairing_progress`, at most ten a
/// second per job; iteration 0 when it starts).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FairingProgress {
    /// The network part.
    pub part: u64,
    /// The face being faired.
    pub face: u32,
    /// The client that asked for it.
    pub client: u64,
    /// Sweeps done.
    pub iteration: u32,
    /// Sweeps at most.
    pub max_iterations: u32,
    /// The largest move of the last sweep (model units; 0 before the first).
    pub max_move: f64,
    /// The move below which the run has converged (model units).
    pub threshold: f64,
    /// An estimate of the fraction done in [0, 1]: the larger of the
    /// sweeps' fraction and how far the largest move has come down (on a
    /// log scale) from the first sweep's toward the threshold.
    pub fraction: f64,
}

fn bad(code: ErrorCode, message: impl Into<String>) -> ProtocolError {
    ProtocolError::new(code, message)
}

fn number(name: &str, x: f64) -> Result<(), ProtocolError> {
    if !x.is_finite() {
        return Err(bad(ErrorCode::NotFinite, format!("{name} is not finite")));
    }
    if x.abs() > MAX_MAGNITUDE {
        return Err(bad(
            ErrorCode::OutOfRange,
            format!("{name} = {x} exceeds ±{MAX_MAGNITUDE}"),
        ));
    }
    Ok(())
}

fn curve(c: &CurveData) -> Result<(), ProtocolError> {
    if c.points.len() > MAX_KNOTS || c.knots.knots.len() > MAX_KNOTS {
        return Err(bad(ErrorCode::TooLarge, "too many control points or knots"));
    }
    c.knots.knots.iter().try_for_each(|k| number("knot", *k))?;
    c.points
        .iter()
        .flatten()
        .try_for_each(|x| number("control point", *x))
}

impl NetworkData {
    /// Counts and numbers (the server checks the geometry).
    pub fn validate(&self) -> Result<(), ProtocolError> {
        if self.curves.len() > MAX_NETWORK_CURVES {
            return Err(bad(
                ErrorCode::TooLarge,
                format!(
                    "{} curves; a network has at most {MAX_NETWORK_CURVES}",
                    self.curves.len()
                ),
            ));
        }
        self.curves.iter().try_for_each(curve)?;
        number("tolerance", self.tolerance)?;
        if self.tolerance <= 0.0 {
            return Err(bad(ErrorCode::OutOfRange, "tolerance must be > 0"));
        }
        self.up.iter().try_for_each(|x| number("up", *x))?;
        if self.up.iter().all(|x| *x == 0.0) {
            return Err(bad(ErrorCode::OutOfRange, "up must not be zero"));
        }
        Ok(())
    }
}

impl NetworkEdit {
    /// Numbers and ranges (indices are checked by the server).
    pub fn validate(&self) -> Result<(), ProtocolError> {
        match self {
            NetworkEdit::MovePoint { xyz, .. } => xyz.iter().try_for_each(|x| number("xyz", *x)),
            NetworkEdit::DragPoint { t, xyz, .. } => {
                number("t", *t)?;
                xyz.iter().try_for_each(|x| number("xyz", *x))
            }
            NetworkEdit::AddCurve { curve: c } => curve(c),
            NetworkEdit::RemoveCurve { .. } => Ok(()),
            NetworkEdit::SetRibbon { scale, twist, .. } => {
                if scale.is_none() && twist.is_none() {
                    return Err(bad(
                        ErrorCode::Malformed,
                        "set_ribbon needs a scale or a twist",
                    ));
                }
                if let Some(x) = *scale {
                    number("scale", x)?;
                    if !(1.0 / MAX_RIBBON_SCALE..=MAX_RIBBON_SCALE).contains(&x) {
                        return Err(bad(
                            ErrorCode::OutOfRange,
                            format!("scale {x} must be in [0.1, {MAX_RIBBON_SCALE}]"),
                        ));
                    }
                }
                if let Some(t) = *twist {
                    number("twist", t)?;
                    if t.abs() >= std::f64::consts::FRAC_PI_2 {
                        return Err(bad(
                            ErrorCode::OutOfRange,
                            format!("twist {t} must have |twist| < π/2"),
                        ));
                    }
                }
                Ok(())
            }
            NetworkEdit::SetTuning { handles, .. } => {
                if !(4..=MAX_TUNING_HANDLES).contains(&handles.len()) {
                    return Err(bad(
                        ErrorCode::OutOfRange,
                        format!(
                            "{} tuning handles: a face of n sides has n + 1 (4 ..= {MAX_TUNING_HANDLES})",
                            handles.len()
                        ),
                    ));
                }
                handles
                    .iter()
                    .flatten()
                    .try_for_each(|x| number("handles", *x))
            }
            NetworkEdit::Fair(f) => {
                if let FairingGoal::Constant(g) = f.goal {
                    number("goal", g)?;
                }
                if let Some(w) = f.relaxation {
                    number("relaxation", w)?;
                    if !(w > 0.0 && w < 2.0) {
                        return Err(bad(ErrorCode::OutOfRange, "relaxation must be in (0, 2)"));
                    }
                }
                if let Some(t) = f.tolerance {
                    number("tolerance", t)?;
                    if t <= 0.0 {
                        return Err(bad(ErrorCode::OutOfRange, "tolerance must be > 0"));
                    }
                }
                if let Some(n) = f.max_iterations
                    && !(1..=MAX_FAIRING_ITERATIONS).contains(&n)
                {
                    return Err(bad(
                        ErrorCode::OutOfRange,
                        format!("max_iterations must be 1 ..= {MAX_FAIRING_ITERATIONS}"),
                    ));
                }
                Ok(())
            }
        }
    }
}
