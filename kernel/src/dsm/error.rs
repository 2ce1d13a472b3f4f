//! Errors of the Density Spatial Model: bad input is refused with a reason and
//! changes nothing.

use thiserror::Error;

/// Why a DSM input was refused.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum DsmError {
    /// A rotation that is not orthonormal with determinant +1, or a non-finite placement.
    #[error("placement is not a rigid transform (orthonormal rotation, finite translation)")]
    BadPlacement,
    /// A size, density or reducing factor out of its domain.
    #[error("bad parameter {name} = {value}: {why}")]
    BadParameter {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The rule it breaks.
        why: &'static str,
    },
    /// A group index that does not exist or is not earlier than the group using it.
    #[error(
        "group {group} cannot use group {other}: only existing, earlier groups can be incorporated or combined"
    )]
    BadGroup {
        /// The group (or term) that refers.
        group: usize,
        /// The group referred to.
        other: usize,
    },
    /// A passing-points net node with a height h ≤ 0 (or not finite): eq. (8) takes log h.
    #[error("passing-points net node {node} has height {height}; heights must be finite and > 0")]
    NonPositiveHeight {
        /// Node index.
        node: usize,
        /// Its height.
        height: f64,
    },
    /// Two nodes at the same (u, v) (within 1e-9 of the net size): C is singular.
    #[error("passing-points net nodes {a} and {b} coincide in (u, v) (distance {distance:e})")]
    CoincidentNodes {
        /// First node.
        a: usize,
        /// Second node.
        b: usize,
        /// Their (u, v) distance.
        distance: f64,
    },
    /// A net without enough nodes or without an interior node to carry a charge.
    #[error("passing-points net is degenerate: {0}")]
    DegenerateNet(&'static str),
    /// The system of eq. (9) is numerically singular.
    #[error("the inverse transformation's system is singular (condition estimate {condition:e})")]
    Singular {
        /// 1-norm condition estimate of C.
        condition: f64,
    },
    /// A mesh request the mesher cannot honour.
    #[error("mesh request refused: {0}")]
    BadMeshRequest(&'static str),
}

/// Checks that `value` is finite and > 0.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64, DsmError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(DsmError::BadParameter {
            name,
            value,
            why: "must be finite and > 0",
        })
    }
}

/// Checks that `value` is finite.
pub(crate) fn finite(name: &'static str, value: f64) -> Result<f64, DsmError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(DsmError::BadParameter {
            name,
            value,
            why: "must be finite",
        })
    }
}
