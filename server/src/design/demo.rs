//! Starter designs: the demo product created on first start — a computer
//! mouse: a bicubic 16 × 12 top shell (two position constraints, a load and
//! a normal constraint), two side panels joined to it G1 along its long
//! edges, and a feature curve on the top that the shell follows — beside it
//! the paper 002 spool body (a cube that morphs into the spool made from it,
//! figures 7 and 10), and the flat plate new designs begin from.

use super::doc::{
    AnchorDoc, DOC_FORMAT, DesignDoc, IconDoc, IconRoleDoc, IconStateDoc, MaterialDoc, SurfaceDoc,
};
use super::edit::SurfaceQuery;
use super::engine::Engine;
use super::error::{CommandError, ErrorKind};
use super::part::{
    ContinuityDoc, CurveDoc, CurveMaterialDoc, CurvePart, EdgeDoc, IsoLineDoc, PALETTE, PartBody,
    PartDoc, RelationDoc, RelationKind, SurfacePart,
};
use vsculpt_kernel::bspline::{KnotVector, basis_derivs, greville};

fn kernel(e: impl std::fmt::Display) -> CommandError {
    CommandError::new(ErrorKind::InvalidValue, e.to_string())
}

/// A bicubic surface with clamped uniform knots whose control points are
/// `f` at the Greville abscissae (so a smooth `f` gives a smooth surface
/// close to it).
fn surface_from(
    nu: usize,
    nv: usize,
    f: impl Fn(f64, f64) -> [f64; 3],
) -> Result<SurfaceDoc, CommandError> {
    let ku = KnotVector::clamped_uniform(3, nu).map_err(kernel)?;
    let kv = KnotVector::clamped_uniform(3, nv).map_err(kernel)?;
    let (gu, gv) = (greville(&ku), greville(&kv));
    let mut points = Vec::with_capacity(nu * nv);
    for &s in &gu {
        for &t in &gv {
            points.push(f(s, t));
        }
    }
    Ok(SurfaceDoc {
        u_degree: 3,
        v_degree: 3,
        u_knots: ku.knots().to_vec(),
        v_knots: kv.knots().to_vec(),
        nu,
        nv,
        points,
    })
}

/// Checks a new design's name: 1 to 200 bytes after trimming, no control
/// characters (a name is printed in the start banner and in logs, where a
/// line break would forge a line).
pub fn check_name(name: &str) -> Result<(), CommandError> {
    let name = name.trim();
    if name.is_empty() || name.len() > 200 {
        return Err(CommandError::new(
            ErrorKind::InvalidValue,
            "a design name has 1 to 200 bytes",
        ));
    }
    if name.chars().any(char::is_control) {
        return Err(CommandError::new(
            ErrorKind::InvalidValue,
            "a design name may not contain control characters (line breaks, tabs, escapes)",
        ));
    }
    Ok(())
}

/// A flat `nu × nv` bicubic plate part, 100 × 100 (model units: mm), no icons.
pub fn plate_part(nu: usize, nv: usize) -> Result<SurfacePart, CommandError> {
    let surface = surface_from(nu, nv, |s, t| [100.0 * s - 50.0, 100.0 * t - 50.0, 0.0])?;
    Ok(SurfacePart {
        surface,
        material: MaterialDoc::default(),
        icons: Vec::new(),
        kappa: None,
        spring_size: None,
    })
}

/// A design of one flat `nu × nv` bicubic plate (the part is called
/// "plate").
pub fn plate(name: &str, nu: usize, nv: usize) -> Result<DesignDoc, CommandError> {
    Ok(DesignDoc::single(
        name,
        "plate",
        PartBody::Surface(plate_part(nu, nv)?),
    ))
}

/// The mouse's top shell over the unit square (s along its 120 mm length,
/// front to palm; t across): a dome highest over the palm (s ≈ 0.62),
/// rounding down towards the long edges, tapering to 80 % of its width at
/// the front. A polynomial, so smooth everywhere: the earlier dome was
/// clamped to zero outside an ellipse, and interpolating that kink made the
/// rim ripple (visible in zebra and mean curvature).
fn shell_point(s: f64, t: f64) -> [f64; 3] {
    let y = 2.0 * t - 1.0;
    let along = 1.0 - 1.6 * (s - 0.62) * (s - 0.62);
    let across = 1.0 - 0.55 * y * y - 0.25 * y.powi(4);
    [
        120.0 * s - 60.0,
        35.0 * y * (0.8 + 0.2 * s),
        38.0 * along * across,
    ]
}

/// The mouse's top shell: a 16 × 12 bicubic surface, 120 × 70 mm, whose
/// control points are the shell at the Greville abscissae (Schoenberg's
/// variation-diminishing approximation: it never oscillates about the
/// shape, so the demo is fair from the start), with two position
/// constraints (front and back), a load on the palm rest and a normal
/// constraint on the button area.
pub fn shell_part() -> Result<SurfacePart, CommandError> {
    let surface = surface_from(16, 12, shell_point)?;
    let mut part = SurfacePart {
        surface,
        material: MaterialDoc::default(),
        icons: Vec::new(),
        kappa: None,
        spring_size: None,
    };
    let engine = Engine::build_unsolved(&part)?;
    let icons = [
        (AnchorDoc::Point { u: 0.12, v: 0.5 }, IconRoleDoc::Position),
        (AnchorDoc::Point { u: 0.88, v: 0.5 }, IconRoleDoc::Position),
        (AnchorDoc::Point { u: 0.62, v: 0.5 }, IconRoleDoc::Load),
        (AnchorDoc::Point { u: 0.3, v: 0.35 }, IconRoleDoc::Normal),
    ];
    for (id, (anchor, role)) in (1..).zip(icons) {
        part.icons.push(IconDoc {
            id,
            xyz: engine.point_at(&anchor),
            target: engine.current_target(&anchor, role),
            anchor,
            role,
            state: IconStateDoc::Passive,
            sensors: Vec::new(),
        });
    }
    Ok(part)
}

/// A side panel hanging from the shell's long edge `v_min` (true) or
/// `v_max`: the same u knots and 16 control points along the edge, one
/// cubic span across it. Its first row is the shell's edge row and its
/// second continues the shell's last cross-edge leg (ratio 1), so it meets
/// the shell G1 as built; then it rolls down 22 mm into the skirt.
fn side_part(shell: &SurfaceDoc, v_min: bool) -> SurfacePart {
    let nv = shell.nv;
    let (edge, inner) = if v_min { (0, 1) } else { (nv - 1, nv - 2) };
    let mut points = Vec::with_capacity(shell.nu * 4);
    for i in 0..shell.nu {
        let e = glam::DVec3::from(shell.points[i * nv + edge]);
        let leg = e - glam::DVec3::from(shell.points[i * nv + inner]);
        let out = glam::DVec3::new(0.0, leg.y.signum() * 4.0, 0.0);
        points.push(e.to_array());
        points.push((e + leg).to_array());
        points.push((e + leg + out + glam::DVec3::new(0.0, 0.0, -10.0)).to_array());
        points.push((e + leg + out * 1.5 + glam::DVec3::new(0.0, 0.0, -22.0)).to_array());
    }
    SurfacePart {
        surface: SurfaceDoc {
            u_degree: shell.u_degree,
            v_degree: 3,
            u_knots: shell.u_knots.clone(),
            v_knots: vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0],
            nu: shell.nu,
            nv: 4,
            points,
        },
        material: MaterialDoc::default(),
        icons: Vec::new(),
        kappa: None,
        spring_size: None,
    }
}

/// The shell's parameter line v = `v` as a B-spline curve on the shell's u
/// knots (exact: its control points are Σ_j N_j(v) P_ij), so a curve part
/// made from it starts on the surface.
fn iso_v(shell: &SurfaceDoc, v: f64) -> Result<CurveDoc, CommandError> {
    let kv = KnotVector::new(shell.v_degree, shell.v_knots.clone()).map_err(kernel)?;
    let b = basis_derivs(&kv, v, 0);
    let points = (0..shell.nu)
        .map(|i| {
            (0..=shell.v_degree)
                .map(|k| glam::DVec3::from(shell.points[i * shell.nv + b.first + k]) * b.get(0, k))
                .sum::<glam::DVec3>()
                .to_array()
        })
        .collect();
    Ok(CurveDoc {
        degree: shell.u_degree,
        knots: shell.u_knots.clone(),
        points,
    })
}

/// The demo product, a computer mouse: the top shell, a left and a right
/// side panel joined G1 to its long edges, and a feature line along the
/// shell's parameter line v = 0.75 that the shell follows (a binding); and
/// beside it (clear of it) the paper 002 body, the cube whose morph target
/// is the spool made from it (`body_demo`), shown as the cube until its
/// metamorphosis is played. The parts and relations are all made the way a
/// designer would make them.
pub fn demo() -> Result<DesignDoc, CommandError> {
    let shell = shell_part()?;
    let left = side_part(&shell.surface, true);
    let right = side_part(&shell.surface, false);
    let line = iso_v(&shell.surface, 0.75)?;
    let part = |id: u64, name: &str, colour: usize, body: PartBody| PartDoc {
        id,
        name: name.to_string(),
        visible: true,
        locked: false,
        colour: PALETTE[colour].to_string(),
        body,
    };
    let doc = DesignDoc {
        format: DOC_FORMAT,
        name: "demo".into(),
        parts: vec![
            part(1, "top shell", 0, PartBody::Surface(shell)),
            part(2, "left side", 1, PartBody::Surface(left)),
            part(3, "right side", 1, PartBody::Surface(right)),
            part(
                4,
                "feature line",
                2,
                PartBody::Curve(CurvePart {
                    curve: line,
                    material: CurveMaterialDoc::default(),
                    icons: Vec::new(),
                    kappa: None,
                }),
            ),
            part(
                5,
                "spool",
                3,
                PartBody::Body(super::body_demo::spool_part_at(
                    super::body_demo::DEMO_SPOOL_AT,
                )?),
            ),
        ],
        relations: vec![
            RelationDoc {
                id: 1,
                kind: RelationKind::Join {
                    a: 1,
                    edge_a: EdgeDoc::VMin,
                    b: 2,
                    edge_b: EdgeDoc::VMin,
                    continuity: ContinuityDoc::G1,
                    reversed: false,
                    ratio: 1.0,
                },
            },
            RelationDoc {
                id: 2,
                kind: RelationKind::Join {
                    a: 1,
                    edge_a: EdgeDoc::VMax,
                    b: 3,
                    edge_b: EdgeDoc::VMin,
                    continuity: ContinuityDoc::G1,
                    reversed: false,
                    ratio: 1.0,
                },
            },
            RelationDoc {
                id: 3,
                kind: RelationKind::Binding {
                    curve: 4,
                    surface: 1,
                    line: IsoLineDoc::V(0.75),
                    reversed: false,
                },
            },
        ],
        next_icon: 5,
        next_part: 6,
        next_relation: 4,
    };
    doc.validate()?;
    Ok(doc)
}

/// The DSM demo shape (paper 001, a handset-like product concept): a flat
/// box body whose ends are rounded by two fused sphere-based density
/// primitives, a free-form top shaped by a 5 × 4 passing-points net on the
/// body's top face (the inverse transformation puts the surface through the
/// interior nodes), and a lanyard hole through it subtracted by a second
/// group.
pub fn handset_dsm() -> vsculpt_protocol::DsmData {
    use vsculpt_protocol::dsm::{DsmData, DsmGroup, DsmOp, DsmPrimitive, DsmPrimitiveShape};
    let prim = |id: u64, at: [f64; 3], shape: DsmPrimitiveShape| DsmPrimitive {
        id,
        at,
        axis: None,
        shape,
    };
    let heights = vec![
        0.08, 0.10, 0.10, 0.10, 0.08, //
        0.10, 0.22, 0.26, 0.22, 0.10, //
        0.10, 0.22, 0.26, 0.22, 0.10, //
        0.08, 0.10, 0.10, 0.10, 0.08,
    ];
    DsmData {
        de: 1.0,
        cells: 40,
        groups: vec![
            DsmGroup {
                op: DsmOp::Add,
                incorporated: Vec::new(),
                primitives: vec![
                    prim(
                        1,
                        [0.0, 0.0, 0.0],
                        DsmPrimitiveShape::Box {
                            half: [1.6, 0.8, 0.3],
                            negative: false,
                        },
                    ),
                    prim(
                        2,
                        [1.5, 0.0, 0.0],
                        DsmPrimitiveShape::DensitySphere {
                            density: 3.0,
                            reducing: 3.0,
                        },
                    ),
                    prim(
                        3,
                        [-1.5, 0.0, 0.0],
                        DsmPrimitiveShape::DensitySphere {
                            density: 3.0,
                            reducing: 3.0,
                        },
                    ),
                    prim(
                        4,
                        [0.0, 0.0, 0.3],
                        DsmPrimitiveShape::Net {
                            nu: 5,
                            nv: 4,
                            spacing: [0.7, 0.45],
                            heights,
                            reducing: 3.0,
                        },
                    ),
                ],
            },
            DsmGroup {
                op: DsmOp::Subtract,
                incorporated: Vec::new(),
                primitives: vec![prim(
                    5,
                    [1.15, 0.0, 0.0],
                    DsmPrimitiveShape::Cylinder {
                        radius: 0.15,
                        half_height: 1.5,
                        negative: false,
                    },
                )],
            },
        ],
    }
}

/// The DSM demo design: one part, the handset concept of [`handset_dsm`].
pub fn handset() -> Result<DesignDoc, CommandError> {
    let doc = DesignDoc::single(
        "handset concept",
        "handset",
        PartBody::Dsm(super::dsm_engine::DsmPart::new(handset_dsm())),
    );
    doc.validate()?;
    Ok(doc)
}
