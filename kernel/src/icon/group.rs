//! Each icon becomes a [`Group`] of the solver's [`Problem`]: constraint
//! equations or loads built from rows of the surface at its samples.
//!
//! * position → `Vector{row of w at sample i, shape_i + (target − handle)}`,
//!   and for a curve `Projected{identity row, axis, its held value}` per
//!   coordinate (translation-free, [`super::Identity`]);
//!   a region or an edge pins its held control points
//!   ([`super::held_points`]) at `shape_i + (target − handle)`; an outside
//!   region holds them as they are;
//! * derivative R/V/R2/V2/RV → `Vector{row of that derivative, target}`
//! * normal → `Projected{row of w_u, N, 0}` and `Projected{row of w_v, N, 0}`
//! * load → one load, `k·(target − handle)` times the consistent-load row of
//!   the anchor ([`super::load_row`]: w at a point, ∫N_i ds along a curve,
//!   ∫N_i dA over a region), with drag gain `k` (the spring stiffness), so a
//!   drag is the solver's fast path.
//!
//! Only what acts contributes ([`Icon::is_active`], paper 003 Table 1): a
//! sleeping icon nothing, a passive load nothing (it carries no force), a
//! passive or driving constraint its equations, a driving load its force.
use glam::DVec3;

use super::{Anchor, Icon, Role, held_points, load_row, surface_row};
use crate::bspline::BSplineSurface;
use crate::solve::{Equation, Group, Load, ScalarRow};

/// The group of `icon` on `surface`, with `base` standing in for its target
/// (the drag origin during a drag) and spring stiffness `k`; `None` when
/// the icon does not act (sleeping, or a load that is not driving).
pub fn icon_group(icon: &Icon, base: DVec3, surface: &BSplineSurface, k: f64) -> Option<Group> {
    if !icon.is_active() {
        return None;
    }
    let mut group = Group {
        key: icon.id.0,
        ..Group::default()
    };
    let (u, v) = icon.handle_uv();
    match icon.role {
        Role::Position => {
            let shift = match icon.anchor {
                Anchor::Region { inside: false, .. } => DVec3::ZERO,
                _ => base - icon.handle,
            };
            match held_points(&icon.anchor, surface) {
                // A region or an edge: its control points pinned (the
                // solver eliminates them: exact, however many).
                Some(points) => {
                    for (&c, p) in points.iter().zip(&icon.shape) {
                        group.equations.push(Equation::Vector {
                            row: ScalarRow {
                                indices: vec![c],
                                weights: vec![1.0],
                            },
                            target: *p + shift,
                        });
                    }
                }
                None => {
                    for (&(su, sv), p) in icon.samples.iter().zip(&icon.shape) {
                        group.equations.push(Equation::Vector {
                            row: surface_row(surface, su, sv, 0, 0),
                            target: *p + shift,
                        });
                    }
                    // A curve's translation-free identity rows: their values
                    // do not move with the shift (the weights sum to zero).
                    let values = icon.shape.iter().skip(icon.samples.len());
                    for (row, value) in icon.identity.iter().zip(values) {
                        for k in 0..3 {
                            group.equations.push(Equation::Projected {
                                row: row.clone(),
                                direction: DVec3::AXES[k],
                                target: value[k],
                            });
                        }
                    }
                }
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
            let pull = base - icon.handle;
            group.loads.push(Load {
                row: load_row(&icon.anchor, surface),
                force: pull * k,
                drag_gain: k,
            });
        }
    }
    Some(group)
}
