//! Errors of the constrained solve. A failed call leaves the solver as it was.

use thiserror::Error;

use super::GroupKey;
use crate::energy::StiffnessError;

/// Why a solve could not be done.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum SolveError {
    /// The stiffness could not be factored (not positive definite).
    #[error("factorisation failed: {0}")]
    Factor(String),
    /// The stiffness could not be built.
    #[error(transparent)]
    Stiffness(#[from] StiffnessError),
    /// A slice has the wrong length.
    #[error("expected {expected} values, got {got}")]
    Size {
        /// The solver's dimension.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// A number in the problem or the input is NaN or infinite.
    #[error("not finite: {0}")]
    NotFinite(String),
    /// A row refers to a control point that does not exist.
    #[error("control point index {index} out of range (dimension {dim})")]
    IndexOutOfRange {
        /// The index.
        index: usize,
        /// The number of control points.
        dim: usize,
    },
    /// A projected equation has a zero direction.
    #[error("projected equation with a zero direction")]
    ZeroDirection,
    /// Two groups share a key.
    #[error("two groups share the key {0}")]
    DuplicateGroup(GroupKey),
    /// The answer misses an independent equation by more than the
    /// tolerance (see [`super::RESIDUAL_TOLERANCE`]): it is refused rather
    /// than returned as a wrong shape.
    #[error("constraints met only to {residual:e} (tolerance {tolerance:e})")]
    Inexact {
        /// max |C P − d|.
        residual: f64,
        /// The tolerance it exceeds.
        tolerance: f64,
    },
    /// No group with that key in the problem.
    #[error("no group {0} in the problem")]
    UnknownGroup(GroupKey),
}
