//! Shape evaluation for clients and designers: curvature and tessellation.
