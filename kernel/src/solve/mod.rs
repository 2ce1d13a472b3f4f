//! The constrained solve: the linear problem icons produce ([`Problem`]) and
//! the solver that answers it.

mod problem;

pub use problem::{Equation, Group, GroupKey, Load, Problem, ScalarRow};
