//! The one error type of the B-spline layer: every constructor and evaluator
//! validates its input and says what is wrong instead of panicking.

use thiserror::Error;

/// What is wrong with a B-spline's data or with a request made of it.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum GeometryError {
    /// The degree must be at least 1.
    #[error("degree must be at least 1, got {0}")]
    BadDegree(usize),
    /// A degree-p B-spline needs at least p+1 control points.
    #[error("degree {degree} needs at least {needed} control points, got {got}")]
    TooFewControlPoints {
        /// The degree asked for.
        degree: usize,
        /// How many control points it needs.
        needed: usize,
        /// How many were given.
        got: usize,
    },
    /// A knot is NaN or infinite.
    #[error("knot {index} is not finite")]
    NonFiniteKnot {
        /// Position of the knot.
        index: usize,
    },
    /// Knots must never decrease.
    #[error("knots decrease at index {index}")]
    DecreasingKnots {
        /// Position of the first knot smaller than its predecessor.
        index: usize,
    },
    /// The knot vector's length does not match degree and control points.
    #[error("expected {expected} knots, got {got}")]
    KnotCount {
        /// num_ctrl + degree + 1.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// The end knots must have multiplicity degree+1 (clamped).
    #[error("knot vector is not clamped: end knots need multiplicity degree+1")]
    NotClamped,
    /// An interior knot of multiplicity above the degree breaks the curve.
    #[error("interior knot {value} has multiplicity {multiplicity} > degree {degree}")]
    InteriorMultiplicity {
        /// The knot value.
        value: f64,
        /// Its multiplicity.
        multiplicity: usize,
        /// The degree.
        degree: usize,
    },
    /// The parameter domain has zero length.
    #[error("the parameter domain is empty")]
    EmptyDomain,
    /// A parameter is NaN, infinite or outside the domain.
    #[error("parameter {value} is outside the domain [{start}, {end}]")]
    OutOfDomain {
        /// The parameter.
        value: f64,
        /// Domain start.
        start: f64,
        /// Domain end.
        end: f64,
    },
    /// A control or data point has a NaN or infinite coordinate.
    #[error("point {index} is not finite")]
    NonFinitePoint {
        /// Position of the point.
        index: usize,
    },
    /// The number of points does not match the grid.
    #[error("expected {expected} points, got {got}")]
    GridSize {
        /// The number the layout asks for.
        expected: usize,
        /// The number given.
        got: usize,
    },
    /// An interpolation or fitting system is singular (e.g. repeated data points).
    #[error("singular system: {0}")]
    Singular(String),
    /// A size parameter is not positive and finite.
    #[error("invalid size: {0}")]
    InvalidSize(String),
}
