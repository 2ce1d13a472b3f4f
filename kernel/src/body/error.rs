//! The one error type of the Coons-body layer: every constructor, edit and
//! query validates its input and says what is wrong instead of panicking.

use thiserror::Error;

use crate::bspline::GeometryError;

/// What is wrong with a body's data or with a request made of it.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum BodyError {
    /// The underlying B-spline data is invalid.
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    /// Boundary curves or faces that must meet do not, by more than the
    /// tolerance.
    #[error("boundaries do not meet: {what} off by {distance:e} (tolerance {tolerance:e})")]
    Incompatible {
        /// Which corner, edge or face pair.
        what: String,
        /// The largest distance found.
        distance: f64,
        /// The tolerance it was checked against.
        tolerance: f64,
    },
    /// An edit would fold the body: det J ≤ 0 at (u, v, w).
    #[error("the body folds at (u, v, w) = ({u}, {v}, {w}): det J = {det:e}")]
    Folds {
        /// Parameter u of the fold.
        u: f64,
        /// Parameter v of the fold.
        v: f64,
        /// Parameter w of the fold.
        w: f64,
        /// det J there (≤ 0, or a non-positive Bernstein bound the check
        /// could not resolve within its subdivision budget).
        det: f64,
    },
    /// A control-point index is outside the lattice.
    #[error("control point {index} is outside a lattice of {count}")]
    BadIndex {
        /// The index given.
        index: usize,
        /// The number of control points.
        count: usize,
    },
    /// A point, displacement or parameter is NaN or infinite.
    #[error("{0} is not finite")]
    NonFinite(String),
    /// Two bodies, or a body and a request, do not fit together.
    #[error("mismatch: {0}")]
    Mismatch(String),
    /// A linear system (collocation, inversion) is singular.
    #[error("singular: {0}")]
    Singular(String),
    /// An iterative method did not reach its tolerance.
    #[error("no convergence: {0}")]
    NoConvergence(String),
    /// A union's sampling is too coarse to resolve where the bodies meet:
    /// its pieces could not be welded into one closed, consistently
    /// oriented manifold (sample finer).
    #[error(
        "a union at {per_span} samples per span is too coarse to resolve where the bodies meet: {reason}; sample finer"
    )]
    TooCoarse {
        /// The samples per knot span asked.
        per_span: usize,
        /// What could not be welded.
        reason: String,
    },
}
