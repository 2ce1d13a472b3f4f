//! The thin-plate deformation energy: quadrature, stiffness matrices, materials.
