//! The thin-plate deformation energy of paper 003: exact Gram matrices,
//! materials and the stiffness matrix shared by x, y and z.

mod gram;
mod material;
mod stiffness;

pub use gram::Gram;
pub use material::{CurveMaterial, MaterialError, SurfaceMaterial};
pub use stiffness::{Stiffness, StiffnessError};
