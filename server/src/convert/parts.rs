//! Parts and relations between the wire (`vsculpt_protocol::parts`) and the
//! design document (`design::part`): decoding `create_part` and `relate`,
//! encoding parts for snapshots and `part_created`, relations for
//! `relation_created`.

use super::{icon_to_wire, material_from_wire, material_to_wire};
use crate::design::body_part::{BodyPart, LatticeDoc, LatticeSelect};
use crate::design::doc::{IconDoc, SurfaceDoc};
use crate::design::dsm_engine::DsmPart;
use crate::design::part::{
    ContinuityDoc, CurveDoc, CurveMaterialDoc, CurvePart, EdgeDoc, IsoLineDoc, PartBody, PartDoc,
    RelationDoc, RelationKind, SurfacePart,
};
use crate::design::{Edit, MaterialEdit};
use std::collections::BTreeMap;
use vsculpt_protocol as wire;

/// A wire surface as a document surface.
pub fn surface_from_wire(s: &wire::SurfaceData) -> SurfaceDoc {
    SurfaceDoc {
        u_degree: s.u.degree as usize,
        v_degree: s.v.degree as usize,
        u_knots: s.u.knots.clone(),
        v_knots: s.v.knots.clone(),
        nu: s.nu as usize,
        nv: s.nv as usize,
        points: s.points.clone(),
    }
}

/// A document surface on the wire (without its control points when
/// `points` is false: the compact join).
pub fn surface_to_wire(s: &SurfaceDoc, points: bool) -> wire::SurfaceData {
    wire::SurfaceData {
        u: wire::Knots {
            degree: s.u_degree as u32,
            knots: s.u_knots.clone(),
        },
        v: wire::Knots {
            degree: s.v_degree as u32,
            knots: s.v_knots.clone(),
        },
        nu: s.nu as u32,
        nv: s.nv as u32,
        points: if points { s.points.clone() } else { Vec::new() },
    }
}

fn curve_to_wire(c: &CurveDoc, points: bool) -> wire::CurveData {
    wire::CurveData {
        knots: wire::Knots {
            degree: c.degree as u32,
            knots: c.knots.clone(),
        },
        points: if points { c.points.clone() } else { Vec::new() },
    }
}

/// A wire lattice as a document lattice.
fn lattice_from_wire(l: &wire::LatticeData) -> LatticeDoc {
    LatticeDoc {
        degrees: [&l.u, &l.v, &l.w].map(|k| k.degree as usize),
        knots: [&l.u, &l.v, &l.w].map(|k| k.knots.clone()),
        points: l.points.clone(),
    }
}

/// A document lattice on the wire (always with its points: the client
/// needs the knots and sizes, and a body is at most 4096 points).
fn lattice_to_wire(l: &LatticeDoc) -> wire::LatticeData {
    let k = |d: usize| wire::Knots {
        degree: l.degrees[d] as u32,
        knots: l.knots[d].clone(),
    };
    wire::LatticeData {
        u: k(0),
        v: k(1),
        w: k(2),
        points: l.points.clone(),
    }
}

/// A `create_part` spec of body part `b` named `name` (the demo presets).
pub fn body_spec(name: &str, b: &BodyPart) -> wire::PartSpec {
    wire::PartSpec {
        name: name.to_string(),
        shape: wire::PartShape::Body {
            body: Box::new(wire::BodyData {
                lattice: lattice_to_wire(&b.lattice),
                morph_target: b.morph_target.as_ref().map(lattice_to_wire),
            }),
        },
        material: None,
        colour: None,
    }
}

/// A wire lattice selection as the document's.
pub fn lattice_select(s: &wire::LatticeSelection) -> LatticeSelect {
    match s {
        wire::LatticeSelection::Point(ijk) => LatticeSelect::Point(ijk.map(|x| x as usize)),
        wire::LatticeSelection::Face(f) => {
            let (d, e) = f.dir_end();
            LatticeSelect::Face(d, e)
        }
        wire::LatticeSelection::Edge([a, b]) => LatticeSelect::Edge([a.dir_end(), b.dir_end()]),
    }
}

/// A part's material on the wire.
pub fn part_material_to_wire(m: &MaterialEdit) -> wire::PartMaterial {
    match m {
        MaterialEdit::Surface(m) => wire::PartMaterial::Surface(material_to_wire(m)),
        MaterialEdit::Curve(c) => wire::PartMaterial::Curve(wire::CurveMaterial {
            alpha: c.alpha,
            beta: c.beta,
        }),
    }
}

/// A wire material as a material edit.
pub fn part_material_from_wire(m: &wire::PartMaterial) -> MaterialEdit {
    match m {
        wire::PartMaterial::Surface(m) => MaterialEdit::Surface(material_from_wire(m)),
        wire::PartMaterial::Curve(c) => MaterialEdit::Curve(CurveMaterialDoc {
            alpha: c.alpha,
            beta: c.beta,
        }),
    }
}

/// A part body's material.
pub fn body_material(b: &PartBody) -> MaterialEdit {
    match b {
        PartBody::Surface(s) => MaterialEdit::Surface(s.material),
        PartBody::Curve(c) => MaterialEdit::Curve(c.material),
        // Network and DSM parts have no material; the wire's `material`
        // field gets the curve default as a placeholder (set_material on
        // them is refused).
        PartBody::Network(_) | PartBody::Dsm(_) => MaterialEdit::Curve(CurveMaterialDoc::default()),
        // A body has no material: the wire's `material` field carries the
        // surface default, and `set_material` on a body is refused.
        PartBody::Body(_) => MaterialEdit::Surface(Default::default()),
    }
}

/// `create_part` as an edit: the shape with the given material (or the
/// kind's default; a material of the other kind is refused by validation
/// in the protocol crate).
pub fn create_part(spec: &wire::PartSpec) -> Edit {
    let body = match &spec.shape {
        wire::PartShape::Surface { surface } => PartBody::Surface(SurfacePart {
            surface: surface_from_wire(surface),
            material: match &spec.material {
                Some(wire::PartMaterial::Surface(m)) => material_from_wire(m),
                _ => Default::default(),
            },
            icons: Vec::new(),
            kappa: None,
            spring_size: None,
        }),
        wire::PartShape::Curve { curve } => PartBody::Curve(CurvePart {
            curve: CurveDoc {
                degree: curve.knots.degree as usize,
                knots: curve.knots.knots.clone(),
                points: curve.points.clone(),
            },
            material: match &spec.material {
                Some(wire::PartMaterial::Curve(c)) => CurveMaterialDoc {
                    alpha: c.alpha,
                    beta: c.beta,
                },
                _ => Default::default(),
            },
            icons: Vec::new(),
            kappa: None,
        }),
        wire::PartShape::Dsm { dsm } => PartBody::Dsm(DsmPart::new(dsm.clone())),
        wire::PartShape::Network { network } => {
            PartBody::Network(super::network::network_from_wire(network))
        }
        wire::PartShape::Body { body } => PartBody::Body(BodyPart {
            lattice: lattice_from_wire(&body.lattice),
            morph_target: body.morph_target.as_ref().map(lattice_from_wire),
            icons: Vec::new(),
        }),
    };
    Edit::CreatePart {
        name: spec.name.clone(),
        body: Box::new(body),
        colour: spec.colour.clone(),
    }
}

/// A part as clients see it; icons carry their holders; control points
/// are left out when `points` is false (the compact join).
pub fn part_to_wire(p: &PartDoc, holders: &BTreeMap<u64, u64>, points: bool) -> wire::Part {
    let icons = |icons: &[IconDoc]| {
        icons
            .iter()
            .map(|i| icon_to_wire(i, holders.get(&i.id).copied()))
            .collect()
    };
    wire::Part {
        id: p.id,
        name: p.name.clone(),
        visible: p.visible,
        locked: p.locked,
        colour: p.colour.clone(),
        material: part_material_to_wire(&body_material(&p.body)),
        icons: icons(p.body.icons()),
        shape: match &p.body {
            PartBody::Surface(s) => wire::PartShape::Surface {
                surface: surface_to_wire(&s.surface, points),
            },
            PartBody::Curve(c) => wire::PartShape::Curve {
                curve: curve_to_wire(&c.curve, points),
            },
            PartBody::Network(n) => wire::PartShape::Network {
                network: super::network::network_to_wire(
                    &crate::design::network_engine::NetworkView::of(n),
                ),
            },
            PartBody::Dsm(d) => wire::PartShape::Dsm { dsm: d.dsm.clone() },
            PartBody::Body(b) => wire::PartShape::Body {
                body: Box::new(wire::BodyData {
                    lattice: lattice_to_wire(&b.lattice),
                    morph_target: b.morph_target.as_ref().map(lattice_to_wire),
                }),
            },
        },
    }
}

fn edge_from_wire(e: wire::Edge) -> EdgeDoc {
    match e {
        wire::Edge::UMin => EdgeDoc::UMin,
        wire::Edge::UMax => EdgeDoc::UMax,
        wire::Edge::VMin => EdgeDoc::VMin,
        wire::Edge::VMax => EdgeDoc::VMax,
    }
}

fn edge_to_wire(e: EdgeDoc) -> wire::Edge {
    match e {
        EdgeDoc::UMin => wire::Edge::UMin,
        EdgeDoc::UMax => wire::Edge::UMax,
        EdgeDoc::VMin => wire::Edge::VMin,
        EdgeDoc::VMax => wire::Edge::VMax,
    }
}

/// `relate` as a relation (a join's ratio is measured by the model).
pub fn relation_from_wire(r: &wire::RelationSpec) -> RelationKind {
    match r {
        wire::RelationSpec::Join {
            a,
            b,
            continuity,
            reversed,
        } => RelationKind::Join {
            a: a.part,
            edge_a: edge_from_wire(a.edge),
            b: b.part,
            edge_b: edge_from_wire(b.edge),
            continuity: match continuity {
                wire::Continuity::G0 => ContinuityDoc::G0,
                wire::Continuity::G1 => ContinuityDoc::G1,
            },
            reversed: *reversed,
            ratio: 1.0,
        },
        wire::RelationSpec::Binding {
            curve,
            surface,
            line,
            reversed,
        } => RelationKind::Binding {
            curve: *curve,
            surface: *surface,
            line: match line {
                wire::IsoLine::U(x) => IsoLineDoc::U(*x),
                wire::IsoLine::V(x) => IsoLineDoc::V(*x),
            },
            reversed: *reversed,
        },
        wire::RelationSpec::Ffd { body, part } => RelationKind::Ffd {
            body: *body,
            part: *part,
            rest: None,
        },
    }
}

/// A relation as clients see it.
pub fn relation_to_wire(r: &RelationDoc) -> wire::Relation {
    let spec = match &r.kind {
        RelationKind::Join {
            a,
            edge_a,
            b,
            edge_b,
            continuity,
            reversed,
            ..
        } => wire::RelationSpec::Join {
            a: wire::EdgeRef {
                part: *a,
                edge: edge_to_wire(*edge_a),
            },
            b: wire::EdgeRef {
                part: *b,
                edge: edge_to_wire(*edge_b),
            },
            continuity: match continuity {
                ContinuityDoc::G0 => wire::Continuity::G0,
                ContinuityDoc::G1 => wire::Continuity::G1,
            },
            reversed: *reversed,
        },
        RelationKind::Binding {
            curve,
            surface,
            line,
            reversed,
        } => wire::RelationSpec::Binding {
            curve: *curve,
            surface: *surface,
            line: match line {
                IsoLineDoc::U(x) => wire::IsoLine::U(*x),
                IsoLineDoc::V(x) => wire::IsoLine::V(*x),
            },
            reversed: *reversed,
        },
        RelationKind::Ffd { body, part, .. } => wire::RelationSpec::Ffd {
            body: *body,
            part: *part,
        },
    };
    wire::Relation { id: r.id, spec }
}
