//! Why a fairing request was refused.

use thiserror::Error;

/// A point mesh, goal or fit request is invalid or could not be solved.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum FairingError {
    /// The mesh is malformed.
    #[error("bad mesh: {0}")]
    BadMesh(String),
    /// A value (goal, tolerance, parameter) is NaN, infinite or out of range.
    #[error("bad value: {0}")]
    BadValue(String),
    /// A point has too few neighbours for a quadric fit.
    #[error("point {point} has {neighbours} neighbours; a quadric fit needs {needed}")]
    TooFewNeighbours {
        /// The point.
        point: usize,
        /// Its neighbours.
        neighbours: usize,
        /// How many the fit needs.
        needed: usize,
    },
    /// A sparse solve failed (singular system).
    #[error("sparse solve: {0}")]
    Solve(String),
    /// The refit surface misses the points by more than the tolerance.
    #[error(
        "refit misses the points by {deviation} (> tolerance {tolerance}) at {nu} × {nv} control points"
    )]
    RefitTolerance {
        /// The largest distance from a point to the fitted surface.
        deviation: f64,
        /// The tolerance asked for.
        tolerance: f64,
        /// Control points in u of the finest fit tried.
        nu: usize,
        /// Control points in v.
        nv: usize,
    },
    /// The run was cancelled by its progress callback.
    #[error("fairing cancelled after {iterations} iterations")]
    Cancelled {
        /// Iterations done (the mesh is left as it was before the run).
        iterations: usize,
    },
}
