//! CAD exchange: IGES entity 128 surfaces in and out, and mesh exports
//! (OBJ, binary STL, glTF 2.0) of a tessellation for review tools.

pub mod gltf;
pub mod iges;
pub mod mesh;
pub mod obj;
pub mod stl;

pub use gltf::{write_gltf, write_gltf_to};
pub use iges::{IgesError, IgesMeta, IgesSurface, iges_text, read_iges, write_iges};
pub use mesh::{Mesh, MeshError};
pub use obj::{write_obj, write_obj_to};
pub use stl::{write_stl, write_stl_to};
