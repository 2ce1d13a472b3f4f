//! Property: over random icon sets on a small wavy sheet, a solve either
//! meets every equation of the problem to tolerance (checked here by
//! applying each equation's row to the answer), or reports honestly that
//! it does not (a `Dependent` warning whose residual is the measured one),
//! or is an error — never a silent miss (issue 15).

use glam::DVec3;
use proptest::prelude::*;
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector};
use vsculpt_kernel::design::Design;
use vsculpt_kernel::energy::SurfaceMaterial;
use vsculpt_kernel::icon::{Anchor, Derivative, Edge, IconSpec, IconState, Role};
use vsculpt_kernel::solve::{Equation, RESIDUAL_TOLERANCE};

fn sheet() -> BSplineSurface {
    let mut s = BSplineSurface::plane(1.2, 1.0, 12, 10, 3).unwrap();
    for p in s.points_mut() {
        p.z = 0.15 * (3.0 * p.x).sin() * (2.0 * p.y).cos();
    }
    s
}

/// One random icon: (kind, parameters, target offset).
fn icon() -> impl Strategy<Value = (u8, [f64; 4], [f64; 3])> {
    (
        0u8..8,
        prop::array::uniform4(0.02f64..0.98),
        prop::array::uniform3(-0.1f64..0.1),
    )
}

fn spec(kind: u8, p: [f64; 4]) -> (Anchor, Role) {
    let point = Anchor::Point { u: p[0], v: p[1] };
    match kind {
        0 => (point, Role::Position),
        1 => (point, Role::Derivative(Derivative::R)),
        2 => (point, Role::Normal),
        3 => (
            Anchor::Curve(
                BSplineCurve::new(
                    KnotVector::clamped_uniform(1, 2).unwrap(),
                    vec![DVec3::new(p[0], p[1], 0.0), DVec3::new(p[2], p[3], 0.0)],
                )
                .unwrap(),
            ),
            Role::Position,
        ),
        4 | 5 => (
            Anchor::Region {
                u0: p[0],
                v0: p[1],
                u1: p[2],
                v1: p[3],
                inside: kind == 4,
            },
            Role::Position,
        ),
        6 => (
            Anchor::Edge {
                edge: [Edge::UMin, Edge::UMax, Edge::VMin, Edge::VMax][(p[0] * 4.0) as usize % 4],
                clamped: p[1] > 0.5,
            },
            Role::Position,
        ),
        _ => (point, Role::Load),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]
    #[test]
    fn every_equation_is_met_or_the_answer_says_why(icons in prop::collection::vec(icon(), 1..6)) {
        let mut d = Design::new(sheet(), SurfaceMaterial::default()).unwrap();
        for (kind, p, offset) in &icons {
            let (anchor, role) = spec(*kind, *p);
            let Ok(id) = d.add_icon(IconSpec { anchor, role, state: IconState::Passive, target: None }) else {
                continue; // a degenerate anchor is refused: fine
            };
            // Constraints get a moved target (an outside region cannot move).
            if role != Role::Load {
                let t = d.icon(id).unwrap().target + DVec3::from_array(*offset);
                let _ = d.set_target(id, t);
            }
        }
        let Ok(report) = d.solve() else {
            return Ok(()); // an error is an allowed answer
        };
        // Every equation, measured here.
        let points = d.surface().points();
        let mut worst: f64 = 0.0;
        let mut scale: f64 = points.iter().fold(1.0f64, |m, p| m.max(p.abs().max_element()));
        for g in d.problem().groups {
            for e in &g.equations {
                let r = match e {
                    Equation::Vector { row, target } => {
                        scale = scale.max(target.abs().max_element());
                        (row.apply(points) - *target).abs().max_element()
                    }
                    Equation::Projected { row, direction, target } => {
                        (row.apply(points).dot(*direction) - target).abs()
                    }
                };
                worst = worst.max(r);
            }
        }
        // The report is the truth…
        prop_assert!((report.constraint_residual - worst).abs() <= 1e-12 * scale,
            "reported {} measured {}", report.constraint_residual, worst);
        // …and an answer without a warning meets everything (no load pulls).
        if report.warning.is_none() {
            prop_assert!(worst <= RESIDUAL_TOLERANCE * scale, "missed by {worst:e}: {report:?}");
        }
    }
}
