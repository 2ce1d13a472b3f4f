//! Coons bodies (paper 002, Ďurikovič & Czanner): trivariate B-spline
//! solids that shape both a product's outside and its interior.
//!
//! * [`volume`] — tensor-product B-spline volumes: evaluation, derivatives,
//!   Jacobian, isoparametric surfaces, faces.
//! * [`refine`] / [`elevate`] — knot insertion, merging, splitting, degree
//!   elevation (exact changes of basis).
//! * [`invert`] — point inversion x → (u, v, w).

pub mod elevate;
mod error;
pub mod invert;
pub mod refine;
pub mod volume;

pub use error::BodyError;
pub use invert::{Inversion, Inverter};
pub use volume::{BSplineVolume, Dir, Face, VolumeDerivs, VolumeScratch};
