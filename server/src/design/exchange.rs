//! CAD exchange of a whole product: the parts of a design to IGES parts
//! (every surface as an entity 128, every curve — and each curve of a
//! network part — as a 126, each face of a network part as its refit
//! trimmed to the face (144), each named) and
//! IGES parts into a design as new parts (names from the file, made unique;
//! unnamed entities numbered). The byte-level IGES work is `crate::cad`'s.

use super::doc::{DesignDoc, SurfaceDoc};
use super::error::{CommandError, ErrorKind};
use super::part::{CurveDoc, CurvePart, MAX_PARTS, PALETTE, PartBody, PartDoc, SurfacePart};
use crate::cad::{IgesCurve, IgesEntity, IgesPart, IgesSurface, IgesTrimmed};

/// The IGES parts of `doc`: part `only`, or every part (hidden ones too:
/// the exchange file is the whole product), named by their part names.
pub fn to_iges_parts(doc: &DesignDoc, only: Option<u64>) -> Result<Vec<IgesPart>, CommandError> {
    let parts: Vec<&PartDoc> =
        match only {
            Some(id) => vec![doc.part(id).ok_or_else(|| {
                CommandError::new(ErrorKind::UnknownPart, format!("no part {id}"))
            })?],
            None => doc.parts.iter().collect(),
        };
    if let (Some(id), [p]) = (only, parts.as_slice())
        && let PartBody::Dsm(_) = p.body
    {
        return Err(CommandError::new(
            ErrorKind::Unsupported,
            format!(
                "part {id} is a dsm part: it has no exact IGES form; export it as STL, OBJ or glTF"
            ),
        ));
    }
    let curve = |c: &CurveDoc| {
        IgesEntity::Curve(IgesCurve {
            degree: c.degree,
            knots: c.knots.clone(),
            points: c.points.clone(),
        })
    };
    // A whole-product exchange file leaves the dsm parts out (mesh formats
    // carry them).
    let mut out = Vec::new();
    for p in parts {
        let named = |name: String, entity| IgesPart {
            name: Some(name),
            entity,
        };
        match &p.body {
            PartBody::Surface(s) => out.push(named(
                p.name.clone(),
                IgesEntity::Surface(s.surface.to_iges()),
            )),
            PartBody::Curve(c) => out.push(named(p.name.clone(), curve(&c.curve))),
            // A network's styling curves, one entity 126 each, named
            // "<part> curve <k>", and each face's refit trimmed to its
            // domain polygon (entity 144), named "<part> face <k>".
            PartBody::Network(n) => {
                for (k, c) in n.curves.iter().enumerate() {
                    out.push(named(format!("{} curve {k}", p.name), curve(c)));
                }
                let engine = super::network_engine::NetworkEngine::build(n)?;
                for (k, (fit, outer)) in engine.refits()?.into_iter().enumerate() {
                    let s = &fit.surface;
                    let surface = IgesSurface {
                        u_degree: s.u_knots().degree(),
                        v_degree: s.v_knots().degree(),
                        u_knots: s.u_knots().knots().to_vec(),
                        v_knots: s.v_knots().knots().to_vec(),
                        nu: s.nu(),
                        nv: s.nv(),
                        points: s.points().to_vec(),
                    };
                    out.push(named(
                        format!("{} face {k}", p.name),
                        IgesEntity::Trimmed(IgesTrimmed { surface, outer }),
                    ));
                }
            }
            // A body's boundary: its six faces, outward, named by face.
            PartBody::Body(b) => {
                for (face, s) in b.lattice.faces()? {
                    let name = format!("{} {}", p.name, super::body_engine::face_name(face));
                    out.push(named(name, IgesEntity::Surface(s.to_iges())));
                }
            }
            PartBody::Dsm(_) => {}
        }
    }
    Ok(out)
}

/// A name not used in `doc` (nor in `taken`): `name`, else `name (2)`, …
fn unique_name(doc: &DesignDoc, taken: &[String], name: &str) -> String {
    let used = |n: &str| doc.parts.iter().any(|p| p.name == n) || taken.iter().any(|t| t == n);
    if !used(name) {
        return name.to_string();
    }
    (2..)
        .map(|k| format!("{name} ({k})"))
        .find(|n| !used(n))
        .unwrap_or_else(|| name.to_string())
}

/// `doc` with every IGES part added as a new part (bare: no icons), and the
/// new part ids. Parts beyond the design's limit are refused, as is any part
/// the validator refuses (nothing is added then).
pub fn with_iges_parts(
    doc: &DesignDoc,
    parts: &[IgesPart],
) -> Result<(DesignDoc, Vec<u64>), CommandError> {
    if doc.parts.len() + parts.len() > MAX_PARTS {
        return Err(CommandError::new(
            ErrorKind::InvalidValue,
            format!(
                "the file has {} parts; a design holds at most {MAX_PARTS} ({} now)",
                parts.len(),
                doc.parts.len()
            ),
        ));
    }
    let mut out = doc.clone();
    let mut names = Vec::new();
    let mut ids = Vec::new();
    for (k, p) in parts.iter().enumerate() {
        let (kind, body) = match &p.entity {
            // (The reader gives a trimmed surface's surface as a surface.)
            IgesEntity::Surface(s) | IgesEntity::Trimmed(IgesTrimmed { surface: s, .. }) => (
                "surface",
                PartBody::Surface(SurfacePart {
                    surface: SurfaceDoc::from_iges(s),
                    material: Default::default(),
                    icons: Vec::new(),
                    kappa: None,
                    spring_size: None,
                }),
            ),
            IgesEntity::Curve(c) => (
                "curve",
                PartBody::Curve(CurvePart {
                    curve: CurveDoc {
                        degree: c.degree,
                        knots: c.knots.clone(),
                        points: c.points.clone(),
                    },
                    material: Default::default(),
                    icons: Vec::new(),
                    kappa: None,
                }),
            ),
        };
        body.validate()?;
        let base = p
            .name
            .as_deref()
            .map(str::trim)
            .filter(|n| !n.is_empty() && !n.chars().any(char::is_control))
            .map(|n| n.chars().take(200).collect::<String>())
            .unwrap_or_else(|| format!("imported {kind} {}", k + 1));
        let name = unique_name(&out, &names, &base);
        names.push(name.clone());
        let id = out.next_part;
        out.next_part += 1;
        out.parts.push(PartDoc {
            id,
            name,
            visible: true,
            locked: false,
            colour: PALETTE[out.parts.len() % PALETTE.len()].to_string(),
            body,
        });
        ids.push(id);
    }
    out.validate()?;
    Ok((out, ids))
}
