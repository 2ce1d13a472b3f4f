//! vsculpt-kernel: the geometry and solver at the heart of vsculpt. Pure Rust,
//! no I/O, no async; used by the server, the device bridge and the benches.
//!
//! # Layout
//!
//! Data flows one way: input (icons) → constraints and loads (a [`solve::Problem`])
//! → solve → evaluate → output (tessellation, curvature).
//!
//! * [`bspline`] — knot vectors, basis functions, curves and tensor-product
//!   surfaces with derivatives, interpolation, knot insertion.
//! * [`energy`] — the thin-plate deformation energy: Gauss quadrature, the exact
//!   Galerkin stiffness of curves and surfaces, materials.
//! * [`quadrature`] — Gauss–Legendre rules, exact for B-spline products per span.
//! * [`solve`] — the linear problem icons hand to the solver and the solver
//!   itself: sparse Cholesky of the stiffness, constraints by Schur complement,
//!   drag frames answered from precomputed columns.
//! * [`icon`] — icon entities (point, curve, region × constraint or load) and
//!   how each becomes constraint equations or loads.
//! * [`spring`] — the spring model that maps a drag to a force.
//! * [`analysis`] — curvature and tessellation for clients.
//! * [`curve_design`] — the same icons sculpting a deformable curve.
//! * [`design`] — a design (surface, icons, material) as a value: edit, solve,
//!   snapshot, restore.
//! * [`product`] — a design of many parts (surfaces, curves), joins between
//!   surfaces and curves bound to them, solved jointly where related.
//! * [`dsm`] — the Density Spatial Model (paper 001): implicit shapes from primitives,
//!   shape groups and passing-points nets, meshed by dual contouring.
//! * [`body`] — Coons bodies (paper 002): B-spline volumes, Coons bodies 0/1/2,
//!   lattices, interior modelling, free-form deformation, metamorphosis.
//! * [`network`] — styling-curve networks (paper 004): meetings and faces found
//!   automatically, cross-boundary ribbons, G1 n-sided patches with tuning handles.
//! * [`fairing`] — point meshes sampled from patches, curvature fairness measures
//!   by local quadric fits, iterative fairing toward goals, B-spline refit.

pub mod analysis;
pub mod body;
pub mod bspline;
pub mod curve_design;
pub mod design;
pub mod dsm;
pub mod energy;
pub mod fairing;
pub mod icon;
pub mod network;
pub mod product;
pub mod quadrature;
pub mod solve;
pub mod spring;
