//! Why a network edit or a patch request was refused. Every refused edit
//! leaves the network as it was.

use glam::DVec3;
use thiserror::Error;

/// A network could not be built or changed.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum NetworkError {
    /// The intersection tolerance must be positive and finite.
    #[error("intersection tolerance must be positive and finite, got {0}")]
    BadTolerance(f64),
    /// A curve's end meets no other curve, so the face beside it is open.
    #[error(
        "curve {curve} ends at t = {t} without meeting another curve: the face there is left open"
    )]
    OpenEnd {
        /// The curve.
        curve: usize,
        /// The parameter of its free end.
        t: f64,
    },
    /// A face's boundary walks along a curve piece on both sides (a piece
    /// hanging into the face), so the face is not closed.
    #[error("a face is left open: curve {curve} hangs into it between t = {t0} and t = {t1}")]
    OpenFace {
        /// The curve of the hanging piece.
        curve: usize,
        /// Its parameter range.
        t0: f64,
        /// Its parameter range.
        t1: f64,
    },
    /// A face's boundary passes a vertex twice or crosses itself.
    #[error("face {face} is self-intersecting: its boundary {what}")]
    SelfIntersectingFace {
        /// The face (in the order faces are found).
        face: usize,
        /// What was found.
        what: String,
    },
    /// A curve crosses itself.
    #[error("curve {curve} crosses itself at t = {t0} and t = {t1}")]
    SelfIntersectingCurve {
        /// The curve.
        curve: usize,
        /// One parameter of the crossing.
        t0: f64,
        /// The other parameter.
        t1: f64,
    },
    /// A face has fewer than three sides (two curves meeting twice).
    #[error("face {face} has {sides} sides; a patch needs at least 3")]
    TooFewSides {
        /// The face.
        face: usize,
        /// Its sides.
        sides: usize,
    },
    /// A face has more sides than a patch supports.
    #[error("face {face} has {sides} sides; at most {max} are supported")]
    TooManySides {
        /// The face.
        face: usize,
        /// Its sides.
        sides: usize,
        /// The limit.
        max: usize,
    },
    /// All curves at a vertex are tangent: no tangent plane there.
    #[error("the curves meeting at {point} are all tangent to each other: no tangent plane")]
    DegenerateVertex {
        /// Where.
        point: DVec3,
    },
    /// An edit moved two curves apart that met: their intersection is lost.
    #[error("curves {a} and {b} no longer meet (gap {gap} > tolerance {tolerance})")]
    LostIntersection {
        /// One curve.
        a: usize,
        /// The other.
        b: usize,
        /// Their closest distance near the old intersection.
        gap: f64,
        /// The tolerance.
        tolerance: f64,
    },
    /// No index like that.
    #[error("no {what} {index}")]
    Unknown {
        /// "curve", "face", "edge", "side".
        what: &'static str,
        /// The index asked for.
        index: usize,
    },
    /// A handle value or a point is NaN or infinite, or out of its range.
    #[error("bad value: {0}")]
    BadValue(String),
    /// The curves enclose no face.
    #[error("the curves enclose no face")]
    NoFaces,
}
