//! Coons bodies (paper 002, Ďurikovič & Czanner): trivariate B-spline
//! solids that shape both a product's outside and its interior.
//!
//! * [`volume`] — tensor-product B-spline volumes: evaluation, derivatives,
//!   Jacobian, isoparametric surfaces, faces.
//! * [`refine`] / [`elevate`] — knot insertion, merging, splitting, degree
//!   elevation (exact changes of basis).
//! * [`invert`] — point inversion x → (u, v, w).
//! * [`space`] — common spline spaces for several curves or surfaces.
//! * [`coons`] — Coons bodies 0, 1, 2 and their exact B-spline volumes.
//! * [`injective`] — det J > 0 proved from its Bernstein form.
//! * [`interior`] — interior distribution (det J), shape-preserving and checked edits.
//! * [`ffd`] — free-form deformation of points, meshes, curves and surfaces.
//! * [`lattice`] — several bodies sharing faces; continuity across them.
//! * [`morph`] — metamorphosis: grid correspondence, paths, the body at t.
//! * [`union`] — union of bodies as a set operation on their boundaries.
//! * `subdivide` — local subdivision where another body crosses a
//!   sampled triangle unseen by its corners.
//! * [`weld`] — the union's pieces welded into one closed, manifold mesh.
//! * [`display`] — boundary and isoparametric surface meshes for viewers.
//! * [`demo`] — the paper's cube, spool, cube-to-spool morph and chair.

pub mod coons;
pub mod demo;
pub mod display;
pub mod elevate;
mod error;
pub mod ffd;
pub mod injective;
pub mod interior;
pub mod invert;
pub mod lattice;
pub mod morph;
pub mod refine;
pub mod space;
mod subdivide;
pub mod union;
pub mod volume;
pub mod weld;

pub use coons::{Body0, Body1, Body2, Edges, coons_patch, trilinear};
pub use error::BodyError;
pub use ffd::{Embedding, Ffd};
pub use injective::{InjectivityCache, InjectivityReport, check_injective};
pub use invert::{Inversion, Inverter};
pub use lattice::{BodyLattice, Continuity, Joint};
pub use morph::{Morph, Path};
pub use volume::{BSplineVolume, Dir, Face, VolumeDerivs, VolumeScratch};
