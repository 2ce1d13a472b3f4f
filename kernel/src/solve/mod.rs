//! The constrained solve: the linear problem icons produce ([`Problem`]), the
//! sparse factorisation of the stiffness and the solver that answers full
//! solves and drag frames.

mod error;
mod factor;
mod pin_update;
mod problem;
mod solver;

pub use error::SolveError;
pub use factor::{Factor, Forward};
pub use problem::{Equation, Group, GroupKey, Load, Problem, ScalarRow};
pub use solver::{RESIDUAL_TOLERANCE, ResponseCounts, SolveReport, SolveWarning, Solver};
