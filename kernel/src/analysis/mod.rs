//! Shape evaluation for designers and clients: curvature (mean, Gaussian,
//! principal) and tessellation with per-vertex normals and curvature.

mod curvature;
mod tessellate;

pub use curvature::{
    Degenerate, ShadingCurvature, SurfaceCurvature, curve_curvature, shading_curvature,
    surface_curvature,
};
pub use tessellate::{
    CurveTessellation, Tessellation, Tessellator, samples_for, tessellate, tessellate_curve,
};
