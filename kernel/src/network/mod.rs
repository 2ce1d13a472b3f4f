//! Styling-curve networks filled with n-sided patches (paper 004, §2–3):
//! a net of B-spline curves, its meetings and faces found automatically,
//! cross-boundary ribbons at the corners interpolated along the sides, and
//! one side-based transfinite patch per face, G1 across every shared curve,
//! with tuning handles that reshape the interior only.
//!
//! Choices (paper 004 leaves them open; Gregory's original construction is
//! replaced by its modern side-based successor):
//! * patch: Kato's side-based transfinite patch over a regular n-gon with
//!   Wachspress-based side parameters (Salvi–Várady) — [`patch`];
//! * ribbons: a normal field per edge blended from the vertex normals, with
//!   twist handles, and corner-compatible cross derivatives with scale
//!   handles — [`ribbon`];
//! * faces: a face walk on the graph embedded by local vertex normals —
//!   [`topology`];
//! * the paper's u²v² tuning terms: bubble functions Π d_i² that vanish with
//!   their gradient on the boundary — [`patch`].

pub mod curve_network;
pub mod demo;
pub mod domain;
pub mod error;
pub mod intersect;
pub mod jet;
pub mod patch;
pub mod ribbon;
pub mod sampler;
pub mod topology;

pub use curve_network::{CurveNetwork, NetworkOptions, Update};
pub use domain::Domain;
pub use error::NetworkError;
pub use jet::{Jet, Scalar, V3};
pub use patch::{Patch, PointWeights};
pub use ribbon::{NormalPiece, SideRibbon};
pub use sampler::{DomainMesh, PatchSampler};
pub use topology::{Edge, Face, Side, Topology, Vertex};
