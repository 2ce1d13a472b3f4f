//! B-spline curves and tensor-product surfaces: knots, basis functions,
//! evaluation with derivatives, interpolation and knot insertion.

mod basis;
mod curve;
mod error;
mod knots;
mod surface;

pub use basis::{BasisDerivs, basis_derivs, basis_derivs_into};
pub use curve::{BSplineCurve, CurveDerivs};
pub use error::GeometryError;
pub use knots::KnotVector;
pub use surface::{BSplineSurface, SurfaceDerivs, greville};
