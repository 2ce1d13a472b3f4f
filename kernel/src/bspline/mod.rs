//! B-spline curves and tensor-product surfaces: knots, basis functions, evaluation with derivatives, interpolation and knot insertion.
