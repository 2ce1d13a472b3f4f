//! Each icon becomes a [`Group`] of the solver's [`Problem`]: constraint
//! equations or loads built from rows of the surface at its samples.
//!
//! * position → `Vector{row of w at sample i, shape_i + (target − centroid(shape))}`
//! * derivative R/V/R2/V2/RV → `Vector{row of that derivative, target}`
//! * normal → `Projected{row of w_u, N, 0}` and `Projected{row of w_v, N, 0}`
//! * load → at every sample a load `k·wᵢ·(target − centroid(shape))` with
//!   drag gain `k·wᵢ` (wᵢ the sample weights, summing to one; k the spring
//!   stiffness), so a drag is the solver's fast path.
//!
//! A sleeping icon contributes nothing; a passive or driving one everything.

use glam::DVec3;

use super::{Icon, IconState, Role, surface_row};
use crate::bspline::BSplineSurface;
use crate::solve::{Equation, Group, Load};

/// The group of `icon` on `surface`, with `base` standing in for its target
/// (the drag origin during a drag) and spring stiffness `k`; `None` when
/// sleeping.
pub fn icon_group(icon: &Icon, base: DVec3, surface: &BSplineSurface, k: f64) -> Option<Group> {
    if icon.state == IconState::Sleeping {
        return None;
    }
    let mut group = Group {
        key: icon.id.0,
        ..Group::default()
    };
    let (u, v) = icon.handle_uv();
    match icon.role {
        Role::Position => {
            let shift = base - icon.shape_centroid();
            for (&(su, sv), p) in icon.samples.iter().zip(&icon.shape) {
                group.equations.push(Equation::Vector {
                    row: surface_row(surface, su, sv, 0, 0),
                    target: *p + shift,
                });
            }
        }
        Role::Derivative(d) => {
            let (du, dv) = d.orders();
            group.equations.push(Equation::Vector {
                row: surface_row(surface, u, v, du, dv),
                target: base,
            });
        }
        Role::Normal => {
            let n = base.normalize_or(DVec3::Z);
            for (du, dv) in [(1, 0), (0, 1)] {
                group.equations.push(Equation::Projected {
                    row: surface_row(surface, u, v, du, dv),
                    direction: n,
                    target: 0.0,
                });
            }
        }
        Role::Load => {
            let pull = base - icon.shape_centroid();
            let w = 1.0 / icon.samples.len() as f64;
            for &(su, sv) in &icon.samples {
                group.loads.push(Load {
                    row: surface_row(surface, su, sv, 0, 0),
                    force: pull * (k * w),
                    drag_gain: k * w,
                });
            }
        }
    }
    Some(group)
}
