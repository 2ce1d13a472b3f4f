//! Reading surfaces, curves and whole parts (with their names) out of an
//! IGES file, applying each entity's transformation matrix (entity 124).

use super::curve::parse_curve;
use super::format::iges_text;
use super::parse::{DirEntry, Fields, IgesFile};
use super::surface::parse_surface;
use super::{IgesEntity, IgesError, IgesPart, IgesSurface};
use glam::{DMat3, DVec3};
use std::collections::{HashMap, HashSet};

/// Longest part name kept (longer names are cut): the protocol's limit for
/// any string, so an imported name can be sent and stored as it is.
const MAX_NAME: usize = vsculpt_protocol::limits::MAX_STRING_BYTES;

/// Reads every B-spline surface (entity 128) of an IGES file, whatever its
/// role in the file, in file order. Control points are in millimetres: the
/// entity's transformation (entity 124) is applied, then the file's units
/// (Global fields 14–15) are converted.
pub fn read_iges(text: &str) -> Result<Vec<IgesSurface>, IgesError> {
    let file = IgesFile::parse(text)?;
    let mut surfaces = Vec::new();
    for (&de, e) in &file.entries {
        if e.entity != 128 {
            continue;
        }
        let f = file.params(de)?;
        let (mut s, _) = parse_surface(&Fields { de, f: &f })?;
        let m = transform(&file, de, e.transform)?;
        for p in &mut s.points {
            *p = m(*p) * file.unit_mm;
        }
        s.check_magnitudes(de)?;
        surfaces.push(s);
    }
    if surfaces.is_empty() {
        return Err(IgesError::NoSurface);
    }
    Ok(surfaces)
}

/// The entity a physically dependent surface belongs to: a trimmed (144)
/// or bounded (143) surface, or a B-rep face (510).
struct Owner {
    /// The owner's directory entry.
    de: usize,
    /// The number of the owner's own parameter fields.
    own: usize,
}

/// Membership of a 402 group: the group's entry, the member's 1-based
/// position and the member count.
struct Membership {
    group: usize,
    own: usize,
    position: usize,
    count: usize,
}

/// Reads every part of an IGES file: each B-spline surface (entity 128) and
/// B-spline curve (entity 126) that stands for itself, in file order.
///
/// Which entities are parts is decided by the Directory Entry's subordinate
/// entity switch (status digits 3–4), the standard's own marker:
/// - an independent (00) or only logically dependent (02, e.g. a member of
///   a group) 126 or 128 is a part, except a 126 whose use flag (status
///   digits 5–6) is 05, "2D parametric": a curve in a surface's parameter
///   space, not in model space;
/// - a physically dependent (01, 03) 126 is a piece of something else — a
///   trimmed surface's boundary (142/144), a composite curve (102), a B-rep
///   edge — and is skipped. So is a 126 that such an entity uses whatever
///   its own status says (some writers leave the field blank): one pointed
///   to by a composite curve (102), a curve on a surface (142, its
///   parameter-space and model-space curves), a boundary (141), an edge
///   list (504) or a loop (508, its parameter-space curves);
/// - a physically dependent 128 is a part when it is the base surface of an
///   independent trimmed (144) or bounded (143) surface, or the surface of a
///   B-rep face (510): that is how most CAD systems write their surfaces.
///   The trimming itself is not kept (the kernel's surfaces are untrimmed);
///   the owner's transformation matrix is applied after the surface's own.
///   Any other physically dependent 128 (say, inside a subfigure
///   definition, 308) is skipped.
///
/// Control points are in millimetres, after the transformations, as in
/// [`read_iges`]; knots are as written.
///
/// A part's name is, as in OpenCASCADE's reader, its Name property (entity
/// 406 form 15, referenced from the property pointers after the entity's
/// parameters) or else its label (DE field 18) with its subscript (field
/// 19) as `label(subscript)`. A surface with neither takes the name of its
/// trimmed surface or face; failing that, a part that is a member of a
/// named group (associativity 402, forms 1, 7, 14, 15) is named after the
/// group, with its 1-based position when the group has several members.
/// Names are printable ASCII, trimmed, and at most 1024 characters.
///
/// Errors: anything [`read_iges`] refuses, for any entity that is read (a
/// part, its owner, its name property or group); an unreadable pointer or a
/// pointer to a missing entry; a rational part with non-uniform weights
/// ([`IgesError::RationalWeights`], [`IgesError::RationalCurve`]); no part
/// at all ([`IgesError::NoParts`]).
pub fn read_iges_parts(text: &str) -> Result<Vec<IgesPart>, IgesError> {
    let file = IgesFile::parse(text)?;
    let mut owners: HashMap<usize, Owner> = HashMap::new();
    let mut groups: HashMap<usize, Membership> = HashMap::new();
    for (&de, e) in &file.entries {
        // The field pointing to the surface, and whether the owner must be
        // independent itself (a B-rep face never is).
        let (surface_field, must_be_independent) = match e.entity {
            144 => (1, true),
            143 => (2, true),
            510 => (1, false),
            402 if [1, 7, 14, 15].contains(&e.form) => {
                let p = file.params(de)?;
                let f = Fields { de, f: &p };
                let n = count(&f, 1)?;
                for k in 0..n {
                    if let Some(m) = f.pointer(&file, 2 + k)? {
                        groups.entry(m).or_insert(Membership {
                            group: de,
                            own: 2 + n,
                            position: k + 1,
                            count: n,
                        });
                    }
                }
                continue;
            }
            _ => continue,
        };
        if must_be_independent && !matches!(e.subordinate(), 0 | 2) {
            continue;
        }
        let p = file.params(de)?;
        let f = Fields { de, f: &p };
        let own = match e.entity {
            144 => 5 + count(&f, 3)?,
            _ => 4 + count(&f, 3 - usize::from(e.entity == 510))?,
        };
        if let Some(s) = f.pointer(&file, surface_field)?
            && file.entries[&s].entity == 128
        {
            owners.entry(s).or_insert(Owner { de, own });
        }
    }

    let pieces = pieces(&file);
    let mut parts = Vec::new();
    for (&de, e) in &file.entries {
        let independent = matches!(e.subordinate(), 0 | 2);
        let owner = owners.get(&de);
        let take = match e.entity {
            126 => independent && e.use_flag() != 5 && !pieces.contains(&de),
            128 => independent || owner.is_some(),
            _ => false,
        };
        if !take {
            continue;
        }
        let p = file.params(de)?;
        let f = Fields { de, f: &p };
        let m = transform(&file, de, e.transform)?;
        let outer = match owner {
            Some(o) => Some(transform(&file, o.de, file.entries[&o.de].transform)?),
            None => None,
        };
        let map = |p: DVec3| outer.as_ref().map_or(m(p), |o| o(m(p))) * file.unit_mm;
        let (entity, own) = if e.entity == 128 {
            let (mut s, own) = parse_surface(&f)?;
            for p in &mut s.points {
                *p = map(*p);
            }
            s.check_magnitudes(de)?;
            (IgesEntity::Surface(s), own)
        } else {
            let (mut c, own) = parse_curve(&f)?;
            for p in &mut c.points {
                *p = map(DVec3::from_array(*p)).to_array();
            }
            c.check_magnitudes(de)?;
            (IgesEntity::Curve(c), own)
        };
        let name = part_name(&file, e, &f, own, owner, groups.get(&de))?;
        parts.push(IgesPart { name, entity });
    }
    if parts.is_empty() {
        return Err(IgesError::NoParts);
    }
    Ok(parts)
}

/// The entries that composite curves (102), boundaries (141), curves on
/// surfaces (142), edge lists (504) and loops (508) use as their curves.
/// These carriers are not parts themselves, so one that cannot be read is
/// passed over rather than refusing the file.
fn pieces(file: &IgesFile) -> HashSet<usize> {
    let mut set = HashSet::new();
    for (&de, e) in &file.entries {
        if ![102, 141, 142, 504, 508].contains(&e.entity) {
            continue;
        }
        let Ok(p) = file.params(de) else { continue };
        let f = Fields { de, f: &p };
        let int = |k: usize| {
            f.int(k)
                .ok()
                .and_then(|v| usize::try_from(v).ok())
                .filter(|&v| v < p.len())
        };
        let mut fields = Vec::new();
        match e.entity {
            102 => fields.extend((0..int(1).unwrap_or(0)).map(|k| 2 + k)),
            142 => fields.extend([3, 4]),
            // 141: TYPE, PREF, SPTR, N, then per curve CRVPT, SENSE, K and
            // K parameter-space curves.
            141 => {
                let mut at = 5;
                for _ in 0..int(4).unwrap_or(0) {
                    let Some(k) = int(at + 2) else { break };
                    fields.push(at);
                    fields.extend(at + 3..at + 3 + k);
                    at += 3 + k;
                }
            }
            // 504: N, then per edge CURV, SVP, SV, TVP, TV.
            504 => fields.extend((0..int(1).unwrap_or(0)).map(|k| 2 + 5 * k)),
            // 508: N, then per edge TYPE, EDGE, NDX, OF, K and K pairs
            // (ISOP, CURV) of parameter-space curves.
            _ => {
                let mut at = 2;
                for _ in 0..int(1).unwrap_or(0) {
                    let Some(k) = int(at + 4) else { break };
                    fields.extend((0..k).map(|j| at + 6 + 2 * j));
                    at += 5 + 2 * k;
                }
            }
        }
        set.extend(
            fields
                .into_iter()
                .filter_map(|k| f.pointer(file, k).ok().flatten()),
        );
    }
    set
}

/// A part's name: its own (see [`own_name`]), else its owner's, else its
/// group's with its position when the group has several members.
fn part_name(
    file: &IgesFile,
    e: &DirEntry,
    f: &Fields<'_>,
    own: usize,
    owner: Option<&Owner>,
    group: Option<&Membership>,
) -> Result<Option<String>, IgesError> {
    if let Some(name) = own_name(file, e, f, own)? {
        return Ok(Some(name));
    }
    if let Some(o) = owner {
        let p = file.params(o.de)?;
        let of = Fields { de: o.de, f: &p };
        if let Some(name) = own_name(file, &file.entries[&o.de], &of, o.own)? {
            return Ok(Some(name));
        }
    }
    let Some(g) = group else { return Ok(None) };
    let p = file.params(g.group)?;
    let gf = Fields { de: g.group, f: &p };
    let name = own_name(file, &file.entries[&g.group], &gf, g.own)?;
    Ok(name.map(|n| {
        if g.count > 1 {
            format!("{n} {}", g.position)
        } else {
            n
        }
    }))
}

/// A count in field `k` that fits in the fields after it.
fn count(f: &Fields<'_>, k: usize) -> Result<usize, IgesError> {
    let n = f.int(k)?;
    usize::try_from(n)
        .ok()
        .filter(|&n| n < f.f.len())
        .ok_or_else(|| {
            f.bad(format!(
                "count {n} in field {k} does not fit the parameters"
            ))
        })
}

/// An entity's own name: its Name property (406 form 15), else its label
/// and subscript.
fn own_name(
    file: &IgesFile,
    e: &DirEntry,
    f: &Fields<'_>,
    own: usize,
) -> Result<Option<String>, IgesError> {
    for p in f.properties(file, own)? {
        let pe = &file.entries[&p];
        if pe.entity != 406 || pe.form != 15 {
            continue;
        }
        let params = file.params(p)?;
        let pf = Fields { de: p, f: &params };
        if let Some(name) = clean_name(pf.text(2)?) {
            return Ok(Some(name));
        }
    }
    Ok(e.label_name().and_then(|n| clean_name(&n)))
}

/// A name made printable ASCII, trimmed and cut to [`MAX_NAME`]; `None` if
/// nothing is left.
fn clean_name(raw: &str) -> Option<String> {
    let mut s = iges_text(raw.trim()).trim().to_string();
    s.truncate(MAX_NAME);
    (!s.is_empty()).then_some(s)
}

/// The transformation (entity 124, possibly chained) at `t` as a point map;
/// the identity when `t` is 0. `de` is the entity that points to it.
fn transform(
    file: &IgesFile,
    de: usize,
    t: usize,
) -> Result<impl Fn(DVec3) -> DVec3 + use<>, IgesError> {
    let mut chain: Vec<(DMat3, DVec3)> = Vec::new();
    let mut cur = t;
    while cur != 0 {
        let e = file.entry(de, cur)?;
        if e.entity != 124 || chain.len() > 16 {
            return Err(IgesError::BadParameter {
                de: cur,
                reason: "transformation pointer is not an entity 124 chain".into(),
            });
        }
        let p = file.params(cur)?;
        let f = Fields { de: cur, f: &p };
        if p.len() < 13 {
            return Err(f.bad("entity 124 needs 12 parameters".into()));
        }
        let r = |k: usize| f.real(k);
        let m = DMat3::from_cols(
            DVec3::new(r(1)?, r(5)?, r(9)?),
            DVec3::new(r(2)?, r(6)?, r(10)?),
            DVec3::new(r(3)?, r(7)?, r(11)?),
        );
        let t = DVec3::new(r(4)?, r(8)?, r(12)?);
        chain.push((m, t));
        cur = e.transform;
    }
    Ok(move |p: DVec3| chain.iter().fold(p, |p, (m, t)| *m * p + *t))
}
