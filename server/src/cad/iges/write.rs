//! Writing surfaces and curves as a fixed-format IGES 5.3 file: Start,
//! Global, Directory Entry, Parameter Data and Terminate sections, with a
//! Name property (406 form 15) for every named part.

use super::format::{hollerith, iges_text, pack, real, with_delims};
use super::{IgesEntity, IgesError, IgesMeta, IgesPart, IgesSurface};
use std::fmt::Write;

/// One entity to write: its type and form, parameters (no delimiters), DE
/// label and status (blank, subordinate, use, hierarchy: `00000000` for an
/// independent entity).
struct Item {
    entity: u32,
    form: u32,
    params: Vec<String>,
    label: String,
    status: &'static str,
}

/// Status of an entity another one is made of (physically dependent).
const DEPENDENT: &str = "00010000";
/// Status of a curve in a surface's parameter space (physically
/// dependent, use flag 5: 2D parametric).
const DEPENDENT_PARAMETRIC: &str = "00010500";

/// Writes one surface as an IGES 5.3 file (millimetres), unnamed.
pub fn write_iges(surface: &IgesSurface, meta: &IgesMeta) -> Result<String, IgesError> {
    surface.validate()?;
    let max = surface
        .points
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0, f64::max);
    let item = Item {
        entity: 128,
        form: 0,
        params: surface.params(),
        label: String::new(),
        status: "00000000",
    };
    Ok(write_items(vec![item], max, meta, "entity 128"))
}

/// Writes every part as an IGES 5.3 file (millimetres): one entity 128 per
/// surface and one entity 126 per curve, in the order given, each
/// independent (status 00000000), and a trimmed surface as an entity 144
/// followed by what it is made of (its 128, the 126 of its trimming polygon
/// and the 142 that puts it on the surface; see [`super::IgesTrimmed`]);
/// everything polynomial with weights 1 and its knots
/// and control points exact. A named part also gets a Name property (406
/// form 15) that its parameter data points to — `..., 0, 1, <406 DE>;`,
/// no associativities and one property — and the name's first 8
/// characters as its label, as OpenCASCADE's writer does. Names (and the
/// Global section's texts) are written as printable ASCII: every other
/// character becomes `_`.
///
/// Errors: [`IgesError::NoParts`] for an empty list; the first invalid part's
/// [`IgesError::InvalidSurface`] or [`IgesError::InvalidCurve`].
pub fn write_iges_parts(parts: &[IgesPart], meta: &IgesMeta) -> Result<String, IgesError> {
    if parts.is_empty() {
        return Err(IgesError::NoParts);
    }
    let mut max: f64 = 0.0;
    let mut items = Vec::with_capacity(2 * parts.len());
    for part in parts {
        // This entity's DE (its parts' follow it).
        let de = 2 * items.len() + 1;
        let mut dependents = Vec::new();
        let (entity, mut params) = match &part.entity {
            IgesEntity::Surface(s) => {
                s.validate()?;
                max = s
                    .points
                    .iter()
                    .map(|p| p.abs().max_element())
                    .fold(max, f64::max);
                (128, s.params())
            }
            IgesEntity::Curve(c) => {
                c.validate()?;
                max = c
                    .points
                    .iter()
                    .flatten()
                    .map(|x| x.abs())
                    .fold(max, f64::max);
                (126, c.params())
            }
            IgesEntity::Trimmed(t) => {
                t.validate()?;
                max = t
                    .surface
                    .points
                    .iter()
                    .map(|p| p.abs().max_element())
                    .fold(max, f64::max);
                let (surface, outline, on_surface) = (de + 2, de + 4, de + 6);
                dependents = vec![
                    Item {
                        entity: 128,
                        form: 0,
                        params: t.surface.params(),
                        label: String::new(),
                        status: DEPENDENT,
                    },
                    Item {
                        entity: 126,
                        form: 0,
                        params: t.loop_params(),
                        label: String::new(),
                        status: DEPENDENT_PARAMETRIC,
                    },
                    Item {
                        entity: 142,
                        form: 0,
                        params: vec![
                            "142".into(),
                            "0".into(),
                            surface.to_string(),
                            outline.to_string(),
                            "0".into(),
                            "1".into(),
                        ],
                        label: String::new(),
                        status: DEPENDENT,
                    },
                ];
                let params = vec![
                    "144".into(),
                    surface.to_string(),
                    "1".into(),
                    "0".into(),
                    on_surface.to_string(),
                ];
                (144, params)
            }
        };
        let name = part.name.as_deref().map(iges_text);
        let Some(name) = name.filter(|n| !n.trim().is_empty()) else {
            items.push(Item {
                entity,
                form: 0,
                params,
                label: String::new(),
                status: "00000000",
            });
            items.extend(dependents);
            continue;
        };
        // The name follows the entity and its parts.
        let name_de = de + 2 * (dependents.len() + 1);
        params.extend(["0".to_string(), "1".into(), name_de.to_string()]);
        items.push(Item {
            entity,
            form: 0,
            params,
            label: name.chars().take(8).collect(),
            status: "00000000",
        });
        items.extend(dependents);
        items.push(Item {
            entity: 406,
            form: 15,
            params: vec!["406".into(), "1".into(), hollerith(&name)],
            label: String::new(),
            status: "00000000",
        });
    }
    Ok(write_items(items, max, meta, "entities 126/128/144"))
}

/// The file of `items`, each entity's directory entry at `2k + 1`.
fn write_items(items: Vec<Item>, max_coord: f64, meta: &IgesMeta, what: &str) -> String {
    let mut out = String::new();
    let seq = |out: &mut String, body: &str, section: char, n: usize| {
        let _ = writeln!(out, "{body:<72}{section}{n:>7}");
    };

    // Start section.
    let start = format!(
        "vsculpt design \"{}\" exported as IGES {what}",
        iges_text(&meta.name)
    );
    let start_lines = pack(&[start], 72);
    for (k, l) in start_lines.iter().enumerate() {
        seq(&mut out, l, 'S', k + 1);
    }

    // Global section.
    let global = vec![
        "1H,".to_string(),
        "1H;".to_string(),
        hollerith(&meta.name),
        hollerith(&format!("{}.igs", meta.name)),
        hollerith("vsculpt"),
        hollerith(env!("CARGO_PKG_VERSION")),
        "32".into(),
        "38".into(),
        "6".into(),
        "308".into(),
        "15".into(),
        hollerith(&meta.name),
        real(1.0),
        "2".into(),
        hollerith("MM"),
        "1".into(),
        real(1.0),
        hollerith(&meta.timestamp),
        real(1e-6),
        real(max_coord),
        hollerith(&meta.author),
        hollerith("vsculpt"),
        "11".into(),
        "0".into(),
        hollerith(&meta.timestamp),
    ];
    let g_lines = pack(&with_delims(global), 72);
    for (k, l) in g_lines.iter().enumerate() {
        seq(&mut out, l, 'G', k + 1);
    }

    // Parameter data first (the directory needs each entity's first line
    // and line count), then the directory, then the data.
    let mut p_out = String::new();
    let mut p_seq = 0;
    for (k, item) in items.iter().enumerate() {
        let de = 2 * k + 1;
        let lines = pack(&with_delims(item.params.clone()), 64);
        let first = p_seq + 1;
        for l in &lines {
            p_seq += 1;
            let body = format!("{l:<64} {de:>7}");
            seq(&mut p_out, &body, 'P', p_seq);
        }
        let d1 = format!(
            "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}",
            item.entity, first, 0, 0, 0, 0, 0, 0, item.status
        );
        let d2 = format!(
            "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}",
            item.entity,
            0,
            0,
            lines.len(),
            item.form,
            "",
            "",
            item.label,
            ""
        );
        seq(&mut out, &d1, 'D', de);
        seq(&mut out, &d2, 'D', de + 1);
    }
    out.push_str(&p_out);
    let t = format!(
        "S{:>7}G{:>7}D{:>7}P{:>7}",
        start_lines.len(),
        g_lines.len(),
        2 * items.len(),
        p_seq
    );
    seq(&mut out, &t, 'T', 1);
    out
}
