//! The Density Spatial Model (paper 001, Sakita & Igoshi): implicit product shapes
//! built from geometric primitives of uniform density and density primitives
//! F = D exp(−a r), fused within shape groups into equal density solids, shaped by
//! passing-points nets (the inverse transformation) and meshed for display.
//!
//! * [`jet`] — value/gradient/Hessian arithmetic every field is built from.
//! * [`placement`] — rigid placement of a primitive.
//! * [`geometric`] — box, cylinder, sphere, ellipsoid, hyperboloid (eq. 2).
//! * [`density`] — plane-, pipe-, sphere-based, blobby and cylinder-mapped primitives (eq. 1).
//! * [`distribution`] — D(u, v) of a plane-based primitive: point charges (eq. 11).
//! * [`connect`] — the surface connecting function s(u, v) (eq. 13).
//! * [`model`] — groups, equal density solids and the object (eqs. 3–7), culling.
//! * [`inverse`] — passing-points nets and the inverse transformation (eqs. 8–11).
//! * [`net_drag`] — a node drag re-solved from the drag's first factorisation.
//! * [`surface`] — the explicit equal density surface h(u, v) (eqs. 12–13) and its curvature.
//! * [`mesh`], [`qef`] — dual contouring of the object.
//! * [`adaptive`] — dual contouring on an octree of leaves as coarse as a
//!   stated tolerance allows (1 to `max_leaf` cells).
//! * [`incremental`] — the mesher's leaves kept between edits, re-meshed only
//!   within an edit's support.
//! * [`shape_ops`] — round corners, shape mapping onto a box face or a cylinder (§4).
//! * [`interval`] — interval bounds used to cull and to skip empty space.
//!
//! Every choice the paper leaves open is stated in the module that makes it and
//! collected in `kernel/README.md` ("Density Spatial Model").

pub mod adaptive;
pub mod connect;
mod corner_cache;
pub mod density;
pub mod distribution;
pub mod error;
pub mod geometric;
pub mod incremental;
pub mod interval;
pub mod inverse;
pub mod jet;
pub mod mesh;
pub mod model;
pub mod net_drag;
pub mod placement;
pub mod qef;
pub mod shape_ops;
pub mod surface;

pub use adaptive::{AdaptiveOptions, AdaptiveStats, mesh_adaptive, mesh_adaptive_on};
pub use connect::{Connecting, Profile};
pub use density::{DensityPrimitive, DensityShape, HalfSpace, Sheet};
pub use distribution::{Charge, Distribution};
pub use error::DsmError;
pub use geometric::{GeometricPrimitive, GeometricShape};
pub use incremental::{IncrementalMesh, UpdateStats, edit_support};
pub use inverse::{InverseOptions, InverseReport, PassingPointsNet, inverse_transform};
pub use jet::{Jet, Jet2};
pub use mesh::{Grid, Mesh, MeshOptions, MeshStats, mesh, mesh_on};
pub use model::{Active, DEFAULT_TAU, Group, Model, Sample, Sign, Term};
pub use net_drag::{DragStep, NetDrag};
pub use placement::Placement;
pub use surface::{Curvature, EqualDensitySurface, graph_curvature};
