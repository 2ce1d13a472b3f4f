//! B-spline curves and tensor-product surfaces: knots, basis functions,
//! evaluation with derivatives, interpolation and knot insertion.

mod basis;
mod curve;
mod error;
mod fit;
mod knots;
mod refine;
mod surface;

pub use basis::{BasisDerivs, basis_derivs, basis_derivs_into};
pub use curve::{BSplineCurve, CurveDerivs};
pub use error::GeometryError;
pub use fit::{interpolate_curve, interpolate_surface};
pub use knots::KnotVector;
pub use surface::{BSplineSurface, SurfaceDerivs, greville};
