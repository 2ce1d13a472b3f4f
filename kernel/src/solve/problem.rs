//! The linear problem that icons hand to the solver.
//!
//! The unknowns are the control points `P` (N points, 3 coordinates). The
//! solver minimises the deformation energy of the displacement `δ = P − P_ref`
//! from a reference shape,
//!
//! ```text
//! E(δ) = δᵀ K δ − 2 δ · b          (K: N×N stiffness shared by x, y and z)
//! ```
//!
//! subject to linear equations on `P`. Every equation and load is built from
//! [`ScalarRow`]s: sparse linear functionals over one coordinate of the
//! control points, e.g. the basis-function values of a surface point
//! `w(u,v) = Σ N_i(u) M_j(v) P_ij` or of one of its derivatives.
//!
//! Equations and loads are grouped by the icon that produced them ([`Group`]),
//! so a drag of one icon can be answered from precomputed columns: a drag sets
//! the group's *drag input* `t ∈ R³`, which shifts every [`Equation::Vector`]
//! target of the group by `t` and adds `drag_gain · t` to every load force of
//! the group. Nothing else changes during a drag, so the factorisation and the
//! Schur complement stay valid.

use glam::DVec3;

/// A sparse linear functional over one coordinate of the control points:
/// `value(P, k) = Σ weights[n] · P[indices[n]][k]`.
///
/// Indices are control-point indices (for a surface `i * nv + j`), unique.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScalarRow {
    /// Control-point indices with a non-zero weight.
    pub indices: Vec<usize>,
    /// The weight of each index.
    pub weights: Vec<f64>,
}

impl ScalarRow {
    /// The functional applied to every coordinate of `points`.
    pub fn apply(&self, points: &[DVec3]) -> DVec3 {
        self.indices
            .iter()
            .zip(&self.weights)
            .map(|(&i, &w)| points[i] * w)
            .sum()
    }
}

/// One constraint equation on the control points.
#[derive(Clone, Debug, PartialEq)]
pub enum Equation {
    /// Three scalar equations, one per coordinate: `row(P, k) = target[k]`.
    /// Position constraints, derivative constraints (R, V, R2, V2, RV) and
    /// samples of curve or region constraints.
    Vector {
        /// The functional (e.g. basis values of `w` or of `w_u` at a point).
        row: ScalarRow,
        /// Its required value.
        target: DVec3,
    },
    /// One scalar equation coupling the coordinates:
    /// `Σ_k direction[k] · row(P, k) = target`. Normal constraints
    /// (`N · w_u = 0`, `N · w_v = 0`).
    Projected {
        /// The functional (e.g. basis values of `w_u` at a point).
        row: ScalarRow,
        /// The direction the row's vector value is projected on.
        direction: DVec3,
        /// The required value of the projection.
        target: f64,
    },
}

/// A concentrated load: adds `row ⊗ force` to the load vector `b`.
/// Distributed loads (curve and region icons) are sums of these, one per
/// quadrature point, with the quadrature weight folded into `force`.
#[derive(Clone, Debug, PartialEq)]
pub struct Load {
    /// Basis values of `w` at the point where the force acts.
    pub row: ScalarRow,
    /// The force (the drag input adds `drag_gain · t` to it).
    pub force: DVec3,
    /// How strongly the group's drag input enters this load's force.
    pub drag_gain: f64,
}

/// Identifies a group across problem rebuilds (the icon id).
pub type GroupKey = u64;

/// The equations and loads of one icon.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Group {
    /// The icon this group comes from.
    pub key: GroupKey,
    /// Its constraint equations (empty for a load icon).
    pub equations: Vec<Equation>,
    /// Its loads (empty for a constraint icon).
    pub loads: Vec<Load>,
}

/// Everything the solver must honour: the groups of every active icon.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Problem {
    /// One group per active (driving or passive) icon.
    pub groups: Vec<Group>,
}
