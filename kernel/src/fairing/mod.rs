//! Fairing of point meshes sampled from patches (paper 004 §3–8): local
//! axes by plane fitting, pseudo-centroids, curvature by local quadric
//! fits, fairness measures, goals given or interpolated from the boundary,
//! the iterative improvement (boundary points never move) and a B-spline
//! surface refitted to the result.
//!
//! Choices the paper leaves open (stated here and tested):
//! * curvature signs: positive where the surface bends away from its normal
//!   (a unit sphere with outward normals has H = 1, K = 1);
//! * the curvature estimator: a cubic jet through the point fitted to its
//!   2-ring in the local axes (chosen by measurement against the 1-ring
//!   quadric on irregular meshes); the fairing step fits the 1-ring with a
//!   quadric (cheap, and the goal constraint removes one unknown);
//! * goals are in mean or Gaussian curvature; a Gaussian goal K is met by
//!   the mean-curvature fit with H = √(K + δ²), δ that fit's own
//!   anisotropy ([`gaussian_goal`]); principal-curvature goals are refused;
//! * the scheme: [`fair`] point by point as the paper, [`fair_implicit`] the
//!   same equations solved per sweep for all points at once, its sweeps
//!   stepped by Anderson acceleration (same fixed point, fewer sweeps);
//! * boundary goals: measured at the boundary points, spread harmonically;
//! * convergence: the largest move of a sweep below 1e-10 of the mesh size.

pub mod anderson;
pub mod eigen3;
pub mod error;
pub mod gaussian_goal;
pub mod goals;
pub mod implicit;
pub mod iterate;
pub mod local_axes;
pub mod measures;
pub mod mesh;
pub mod quadric;
pub mod refit;
pub mod sparse;
pub mod sweep_solver;

pub use anderson::Acceleration;
pub use error::FairingError;
pub use goals::{Goals, resolve};
pub use implicit::{fair_implicit, fair_implicit_with, fair_sweeps, laplacian_implicit};
pub use iterate::{Control, FairingOptions, FairingReport, Progress, fair, laplacian_smooth};
pub use measures::{Fairness, Neighbourhood, estimate, fairness, variation};
pub use mesh::PointMesh;
pub use quadric::{Curvatures, Measure};
pub use refit::{Refit, RefitOptions, refit};
pub use sweep_solver::SweepSolve;
