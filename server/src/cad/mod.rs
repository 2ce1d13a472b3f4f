//! CAD exchange: IGES surfaces (entity 128) and curves (entity 126) in and
//! out, named parts included, and mesh exports (OBJ, binary STL, glTF 2.0)
//! of a tessellation for review tools, and hexahedral VTK grids (`.vtu`)
//! of a body's interior for simulation.

pub mod gltf;
pub mod iges;
pub mod mesh;
pub mod obj;
pub mod stl;
pub mod vtu;

pub use gltf::{write_gltf, write_gltf_to};
pub use iges::{
    IgesCurve, IgesEntity, IgesError, IgesMeta, IgesPart, IgesSurface, IgesTrimmed, iges_text,
    read_iges, read_iges_parts, write_iges, write_iges_parts,
};
pub use mesh::{Mesh, MeshError};
pub use obj::{write_obj, write_obj_to};
pub use stl::{write_stl, write_stl_to};
pub use vtu::{HexGrid, VtuError, write_vtu_to};
