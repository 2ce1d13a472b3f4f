//! IGES 5.3 exchange of B-spline surfaces (entity 128, "rational B-spline
//! surface"), the format designers' CAD tools read and write.
//!
//! The writer emits a fixed-format ASCII file: Start (S), Global (G),
//! Directory Entry (D, two 80-column records per entity), Parameter Data (P,
//! 64 data columns plus the back-pointer to the entity's D record) and
//! Terminate (T) sections, Hollerith strings (`5Hhello`), weights all 1 and
//! PROP3 = 1 (polynomial). Reals are written in Rust's shortest round-trip
//! form, so a write → read cycle reproduces every knot and control point
//! bit for bit.
//!
//! The reader accepts files from other tools: any parameter/record
//! delimiters declared in the Global section, `D` exponents, short (trimmed)
//! lines, CRLF, other entity types (skipped), an optional transformation
//! matrix (entity 124) applied to the control points, and rational surfaces
//! whose weights are all equal (equivalent to polynomial). Surfaces with
//! non-uniform weights are rejected with [`IgesError::RationalWeights`],
//! because the kernel's surfaces are polynomial.

use glam::DVec3;
use std::collections::HashMap;
use std::fmt::Write;
use thiserror::Error;

/// Why an IGES file could not be read (or a surface written).
#[derive(Debug, Error, PartialEq)]
pub enum IgesError {
    /// The file is not fixed-format ASCII IGES (e.g. binary or compressed).
    #[error("not an ASCII IGES file: {0}")]
    NotIges(String),
    /// A section record is malformed.
    #[error("malformed IGES {section} section at line {line}: {reason}")]
    Malformed {
        /// Section letter.
        section: char,
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A parameter of an entity could not be parsed.
    #[error("entity at D{de}: {reason}")]
    BadParameter {
        /// The entity's directory-entry sequence number.
        de: usize,
        /// What is wrong.
        reason: String,
    },
    /// The file has no B-spline surface (entity 128).
    #[error("the file contains no B-spline surface (entity 128)")]
    NoSurface,
    /// The surface is genuinely rational (weights not all equal).
    #[error(
        "entity at D{de} is a rational surface with non-uniform weights (min {min}, max {max}); only polynomial B-spline surfaces are supported"
    )]
    RationalWeights {
        /// The entity's directory-entry sequence number.
        de: usize,
        /// Smallest weight.
        min: f64,
        /// Largest weight.
        max: f64,
    },
    /// A knot or (transformed) control point is beyond [`MAX_IGES_MAGNITUDE`].
    #[error(
        "entity at D{de}: {what} {value:e} is beyond ±{MAX_IGES_MAGNITUDE:e}, the largest coordinate accepted"
    )]
    TooLarge {
        /// The entity's directory-entry sequence number.
        de: usize,
        /// Which kind of number ("knot" or "control point coordinate").
        what: &'static str,
        /// The offending value (may be infinite after a transformation).
        value: f64,
    },
    /// The surface to write is inconsistent.
    #[error("invalid surface: {0}")]
    InvalidSurface(String),
}

/// Largest magnitude of a knot or control-point coordinate read from IGES:
/// the protocol's limit for any coordinate (`vsculpt_protocol::limits`), so
/// an imported surface can be solved, sent in f32 frames and exported.
pub const MAX_IGES_MAGNITUDE: f64 = vsculpt_protocol::limits::MAX_MAGNITUDE;

/// A polynomial B-spline surface as IGES carries it: degrees, full knot
/// vectors and control points row-major (`i * nv + j`, `i` along u) — the
/// kernel's layout.
#[derive(Clone, Debug, PartialEq)]
pub struct IgesSurface {
    /// Degree in u.
    pub u_degree: usize,
    /// Degree in v.
    pub v_degree: usize,
    /// Knots in u (`nu + u_degree + 1` values).
    pub u_knots: Vec<f64>,
    /// Knots in v (`nv + v_degree + 1` values).
    pub v_knots: Vec<f64>,
    /// Control points along u.
    pub nu: usize,
    /// Control points along v.
    pub nv: usize,
    /// Control points, `points[i * nv + j]`.
    pub points: Vec<DVec3>,
}

impl IgesSurface {
    fn validate(&self) -> Result<(), IgesError> {
        let bad = |s: String| Err(IgesError::InvalidSurface(s));
        if self.u_degree == 0 || self.v_degree == 0 {
            return bad("degree must be at least 1".into());
        }
        if self.nu <= self.u_degree || self.nv <= self.v_degree {
            return bad("too few control points for the degree".into());
        }
        if self.points.len() != self.nu * self.nv {
            return bad(format!(
                "{} control points for a {}×{} net",
                self.points.len(),
                self.nu,
                self.nv
            ));
        }
        if self.u_knots.len() != self.nu + self.u_degree + 1
            || self.v_knots.len() != self.nv + self.v_degree + 1
        {
            return bad("knot count does not match control points and degree".into());
        }
        let finite = self
            .u_knots
            .iter()
            .chain(&self.v_knots)
            .all(|x| x.is_finite())
            && self.points.iter().all(|p| p.is_finite());
        if !finite {
            return bad("non-finite knot or control point".into());
        }
        Ok(())
    }
}

/// Text for the Global section.
#[derive(Clone, Debug)]
pub struct IgesMeta {
    /// Product / file name.
    pub name: String,
    /// Author.
    pub author: String,
    /// Time of writing as `YYYYMMDD.HHNNSS`.
    pub timestamp: String,
}

impl IgesMeta {
    /// Metadata stamped with the current UTC time.
    pub fn now(name: &str, author: &str) -> Self {
        Self {
            name: name.to_string(),
            author: author.to_string(),
            timestamp: iges_timestamp(std::time::SystemTime::now()),
        }
    }
}

/// Formats a time as IGES's `YYYYMMDD.HHNNSS` (UTC).
pub fn iges_timestamp(t: std::time::SystemTime) -> String {
    let secs = t
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    let days = secs.div_euclid(86_400);
    let rem = secs.rem_euclid(86_400);
    // Civil-from-days (proleptic Gregorian), after H. Hinnant's algorithm.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}{m:02}{d:02}.{:02}{:02}{:02}",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// `s` as IGES may carry it: printable ASCII only (a fixed-format file is
/// 80 ASCII columns per record). Every other character — non-ASCII letters,
/// line breaks, tabs, other control characters — becomes `_`, so a name
/// can neither split a record nor shift the columns after it.
pub fn iges_text(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c == ' ' || c.is_ascii_graphic() {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// A Hollerith string (`nHtext`) of `s` made IGES-safe; the count is in
/// bytes, which for the printable ASCII of [`iges_text`] is also characters.
fn hollerith(s: &str) -> String {
    let clean = iges_text(s);
    format!("{}H{}", clean.len(), clean)
}

/// The longest prefix of `s` of at most `width` bytes that ends on a
/// character boundary (at least one character, so splitting progresses).
fn split_at_most(s: &str, width: usize) -> (&str, &str) {
    let mut cut = width.min(s.len());
    while cut > 0 && !s.is_char_boundary(cut) {
        cut -= 1;
    }
    if cut == 0 {
        cut = s.chars().next().map_or(0, char::len_utf8);
    }
    s.split_at(cut)
}

fn real(x: f64) -> String {
    let s = format!("{x:E}");
    match s.find('E') {
        Some(e) if !s[..e].contains('.') => format!("{}.0{}", &s[..e], &s[e..]),
        _ => s,
    }
}

/// Packs parameter tokens (each already carrying its delimiter) into lines
/// of at most `width` columns without splitting a token, except a token
/// longer than a line, which is split (only Hollerith strings can be).
fn pack(tokens: &[String], width: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut cur = String::new();
    for t in tokens {
        if cur.len() + t.len() > width && !cur.is_empty() {
            lines.push(std::mem::take(&mut cur));
        }
        let mut t = t.as_str();
        while t.len() > width {
            let (head, tail) = split_at_most(t, width);
            lines.push(head.to_string());
            t = tail;
        }
        cur.push_str(t);
    }
    if !cur.is_empty() {
        lines.push(cur);
    }
    lines
}

fn with_delims(params: Vec<String>) -> Vec<String> {
    let n = params.len();
    params
        .into_iter()
        .enumerate()
        .map(|(k, p)| format!("{p}{}", if k + 1 == n { ';' } else { ',' }))
        .collect()
}

/// Writes one surface as an IGES 5.3 file (millimetres).
pub fn write_iges(surface: &IgesSurface, meta: &IgesMeta) -> Result<String, IgesError> {
    surface.validate()?;
    let mut out = String::new();
    let seq = |out: &mut String, body: &str, section: char, n: usize| {
        let _ = writeln!(out, "{body:<72}{section}{n:>7}");
    };

    // Start section.
    let start = format!(
        "vsculpt surface \"{}\" exported as IGES entity 128",
        iges_text(&meta.name)
    );
    let start_lines = pack(&[start], 72);
    for (k, l) in start_lines.iter().enumerate() {
        seq(&mut out, l, 'S', k + 1);
    }

    // Global section.
    let max_coord = surface
        .points
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0, f64::max);
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

    // Parameter data of the one entity.
    let (nu, nv) = (surface.nu, surface.nv);
    let mut params = vec![
        "128".to_string(),
        (nu - 1).to_string(),
        (nv - 1).to_string(),
        surface.u_degree.to_string(),
        surface.v_degree.to_string(),
        "0".into(),
        "0".into(),
        "1".into(),
        "0".into(),
        "0".into(),
    ];
    params.extend(surface.u_knots.iter().map(|&x| real(x)));
    params.extend(surface.v_knots.iter().map(|&x| real(x)));
    params.extend(std::iter::repeat_n(real(1.0), nu * nv));
    for j in 0..nv {
        for i in 0..nu {
            let p = surface.points[i * nv + j];
            params.extend([real(p.x), real(p.y), real(p.z)]);
        }
    }
    let u0 = surface.u_knots[surface.u_degree];
    let u1 = surface.u_knots[nu];
    let v0 = surface.v_knots[surface.v_degree];
    let v1 = surface.v_knots[nv];
    params.extend([real(u0), real(u1), real(v0), real(v1)]);
    let p_lines = pack(&with_delims(params), 64);

    // Directory entry: two records.
    let de = 1;
    let d1 = format!(
        "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}",
        128, 1, 0, 0, 0, 0, 0, 0, "00000000"
    );
    let d2 = format!(
        "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}",
        128,
        0,
        0,
        p_lines.len(),
        0,
        "",
        "",
        "SURFACE",
        0
    );
    seq(&mut out, &d1, 'D', 1);
    seq(&mut out, &d2, 'D', 2);
    for (k, l) in p_lines.iter().enumerate() {
        let body = format!("{l:<64} {de:>7}");
        seq(&mut out, &body, 'P', k + 1);
    }
    let t = format!(
        "S{:>7}G{:>7}D{:>7}P{:>7}",
        start_lines.len(),
        g_lines.len(),
        2,
        p_lines.len()
    );
    seq(&mut out, &t, 'T', 1);
    Ok(out)
}

/// One directory entry as far as the reader needs it.
#[derive(Clone, Debug)]
struct DirEntry {
    entity: i64,
    param_start: usize,
    transform: usize,
    param_lines: usize,
}

/// Splits parameter text into fields, honouring Hollerith strings.
fn split_params(text: &str, pdelim: char, rdelim: char) -> Result<Vec<String>, String> {
    let chars: Vec<char> = text.chars().collect();
    let mut fields = Vec::new();
    let mut cur = String::new();
    let mut k = 0;
    while k < chars.len() {
        let c = chars[k];
        if c == pdelim || c == rdelim {
            fields.push(cur.trim().to_string());
            cur.clear();
            if c == rdelim {
                return Ok(fields);
            }
            k += 1;
            continue;
        }
        if (c == 'H' || c == 'h')
            && !cur.trim().is_empty()
            && cur.trim().chars().all(|d| d.is_ascii_digit())
        {
            let n: usize = cur.trim().parse().map_err(|_| "bad Hollerith count")?;
            if k + 1 + n > chars.len() {
                return Err("Hollerith string runs past the end".into());
            }
            let s: String = chars[k + 1..k + 1 + n].iter().collect();
            cur = s;
            k += 1 + n;
            continue;
        }
        cur.push(c);
        k += 1;
    }
    if !cur.trim().is_empty() {
        fields.push(cur.trim().to_string());
    }
    Ok(fields)
}

fn parse_real(s: &str) -> Result<f64, String> {
    if s.is_empty() {
        return Ok(0.0);
    }
    let t = s.replace(['D', 'd'], "E");
    let v: f64 = t.parse().map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("'{s}' is not finite"))
    }
}

fn parse_int(s: &str) -> Result<i64, String> {
    if s.is_empty() {
        return Ok(0);
    }
    if let Ok(v) = s.parse::<i64>() {
        return Ok(v);
    }
    let r = parse_real(s)?;
    if r.fract() == 0.0 && r.abs() < 1e15 {
        Ok(r as i64)
    } else {
        Err(format!("'{s}' is not an integer"))
    }
}

/// Reads the global section's parameter and record delimiters.
fn delimiters(global: &str) -> (char, char) {
    let mut chars = global.chars();
    let mut pd = ',';
    let rest: String;
    if global.starts_with("1H") || global.starts_with("1h") {
        let _ = chars.next();
        let _ = chars.next();
        pd = chars.next().unwrap_or(',');
        let _ = chars.next(); // the delimiter after field 1
        rest = chars.collect();
    } else {
        // Field 1 defaulted: the text starts with the delimiter itself.
        let _ = chars.next();
        rest = chars.collect();
    }
    let rd = if rest.starts_with("1H") || rest.starts_with("1h") {
        rest.chars().nth(2).unwrap_or(';')
    } else {
        ';'
    };
    (pd, rd)
}

/// Reads every B-spline surface (entity 128) of an IGES file.
pub fn read_iges(text: &str) -> Result<Vec<IgesSurface>, IgesError> {
    let mut global = String::new();
    let mut dlines: Vec<String> = Vec::new();
    let mut plines: HashMap<usize, (String, usize)> = HashMap::new();
    let mut saw_start = false;
    for (n, raw) in text.lines().enumerate() {
        let line = raw.trim_end_matches(['\r', '\n']);
        if line.trim().is_empty() {
            continue;
        }
        if !line.is_ascii() {
            return Err(IgesError::NotIges(format!("line {} is not ASCII", n + 1)));
        }
        if line.len() < 73 {
            return Err(IgesError::NotIges(format!(
                "line {} has {} columns; fixed-format IGES needs 80",
                n + 1,
                line.len()
            )));
        }
        let section = line.as_bytes()[72] as char;
        let body = &line[..72];
        let seq_no = line[73..].trim().parse::<usize>().ok();
        match section {
            'S' => saw_start = true,
            'G' => global.push_str(body),
            'D' => dlines.push(body.to_string()),
            'P' => {
                let seq_no = seq_no.ok_or_else(|| IgesError::Malformed {
                    section: 'P',
                    line: n + 1,
                    reason: "missing sequence number".into(),
                })?;
                let back =
                    body[64..]
                        .trim()
                        .parse::<usize>()
                        .map_err(|_| IgesError::Malformed {
                            section: 'P',
                            line: n + 1,
                            reason: "missing directory back-pointer".into(),
                        })?;
                plines.insert(seq_no, (body[..64].to_string(), back));
            }
            'T' => {}
            'C' => {
                return Err(IgesError::NotIges(
                    "compressed IGES is not supported".into(),
                ));
            }
            'B' => return Err(IgesError::NotIges("binary IGES is not supported".into())),
            other => {
                return Err(IgesError::Malformed {
                    section: other,
                    line: n + 1,
                    reason: "unknown section letter".into(),
                });
            }
        }
    }
    if !saw_start && global.is_empty() {
        return Err(IgesError::NotIges("no Start or Global section".into()));
    }
    let (pd, rd) = delimiters(&global);
    if !dlines.len().is_multiple_of(2) {
        return Err(IgesError::Malformed {
            section: 'D',
            line: 0,
            reason: "odd number of directory records".into(),
        });
    }
    let field = |rec: &str, k: usize| -> String {
        rec.get(8 * k..8 * k + 8).unwrap_or("").trim().to_string()
    };
    let mut entries: HashMap<usize, DirEntry> = HashMap::new();
    for (k, pair) in dlines.chunks_exact(2).enumerate() {
        let de = 2 * k + 1;
        let num = |s: String| -> Result<usize, IgesError> {
            if s.is_empty() {
                return Ok(0);
            }
            s.parse::<i64>()
                .map(|v| v.max(0) as usize)
                .map_err(|_| IgesError::Malformed {
                    section: 'D',
                    line: de,
                    reason: format!("'{s}' is not an integer"),
                })
        };
        let entity = field(&pair[0], 0)
            .parse::<i64>()
            .map_err(|_| IgesError::Malformed {
                section: 'D',
                line: de,
                reason: "bad entity type".into(),
            })?;
        entries.insert(
            de,
            DirEntry {
                entity,
                param_start: num(field(&pair[0], 1))?,
                transform: num(field(&pair[0], 6))?,
                param_lines: num(field(&pair[1], 3))?,
            },
        );
    }
    let params_of = |de: usize| -> Result<Vec<String>, IgesError> {
        let e = &entries[&de];
        let mut text = String::new();
        let count = e.param_lines.max(1);
        for s in e.param_start..e.param_start + count {
            match plines.get(&s) {
                Some((body, back)) if *back == de => text.push_str(body),
                Some(_) if e.param_lines == 0 => break,
                Some((_, back)) => {
                    return Err(IgesError::BadParameter {
                        de,
                        reason: format!("parameter line P{s} points back to D{back}"),
                    });
                }
                None => {
                    return Err(IgesError::BadParameter {
                        de,
                        reason: format!("parameter line P{s} is missing"),
                    });
                }
            }
        }
        split_params(&text, pd, rd).map_err(|reason| IgesError::BadParameter { de, reason })
    };
    let mut des: Vec<usize> = entries
        .iter()
        .filter(|(_, e)| e.entity == 128)
        .map(|(&de, _)| de)
        .collect();
    des.sort_unstable();
    let mut surfaces = Vec::new();
    for de in des {
        let f = params_of(de)?;
        let mut s = parse_surface(de, &f)?;
        let t = entries[&de].transform;
        if t != 0 {
            let m = transform(t, &entries, &params_of)?;
            for p in &mut s.points {
                *p = m(*p);
            }
        }
        check_magnitudes(de, &s)?;
        surfaces.push(s);
    }
    if surfaces.is_empty() {
        return Err(IgesError::NoSurface);
    }
    Ok(surfaces)
}

/// Every knot and control-point coordinate finite and within
/// ±[`MAX_IGES_MAGNITUDE`] (checked after any transformation).
fn check_magnitudes(de: usize, s: &IgesSurface) -> Result<(), IgesError> {
    let bad = |x: f64| !x.is_finite() || x.abs() > MAX_IGES_MAGNITUDE;
    if let Some(&value) = s.u_knots.iter().chain(&s.v_knots).find(|&&x| bad(x)) {
        return Err(IgesError::TooLarge {
            de,
            what: "knot",
            value,
        });
    }
    if let Some(value) = s.points.iter().flat_map(|p| p.to_array()).find(|&x| bad(x)) {
        return Err(IgesError::TooLarge {
            de,
            what: "control point coordinate",
            value,
        });
    }
    Ok(())
}

type Params<'a> = dyn Fn(usize) -> Result<Vec<String>, IgesError> + 'a;

/// The transformation (entity 124, possibly chained) as a point map.
fn transform(
    de: usize,
    entries: &HashMap<usize, DirEntry>,
    params_of: &Params<'_>,
) -> Result<impl Fn(DVec3) -> DVec3 + use<>, IgesError> {
    let mut chain: Vec<(glam::DMat3, DVec3)> = Vec::new();
    let mut cur = de;
    while cur != 0 {
        let e = entries.get(&cur).ok_or_else(|| IgesError::BadParameter {
            de,
            reason: format!("transformation D{cur} does not exist"),
        })?;
        if e.entity != 124 || chain.len() > 16 {
            return Err(IgesError::BadParameter {
                de: cur,
                reason: "transformation pointer is not an entity 124 chain".into(),
            });
        }
        let f = params_of(cur)?;
        if f.len() < 13 {
            return Err(IgesError::BadParameter {
                de: cur,
                reason: "entity 124 needs 12 parameters".into(),
            });
        }
        let r = |k: usize| {
            parse_real(&f[k]).map_err(|reason| IgesError::BadParameter { de: cur, reason })
        };
        let m = glam::DMat3::from_cols(
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

fn parse_surface(de: usize, f: &[String]) -> Result<IgesSurface, IgesError> {
    let bad = |reason: String| IgesError::BadParameter { de, reason };
    let int = |k: usize| -> Result<i64, IgesError> {
        f.get(k)
            .ok_or_else(|| bad(format!("missing parameter {k}")))
            .and_then(|s| parse_int(s).map_err(bad))
    };
    let re = |k: usize| -> Result<f64, IgesError> {
        f.get(k)
            .ok_or_else(|| bad(format!("missing parameter {k}")))
            .and_then(|s| parse_real(s).map_err(bad))
    };
    if int(0)? != 128 {
        return Err(bad("parameter data does not start with 128".into()));
    }
    let (k1, k2, m1, m2) = (int(1)?, int(2)?, int(3)?, int(4)?);
    if k1 < 1 || k2 < 1 || m1 < 1 || m2 < 1 || k1 > 100_000 || k2 > 100_000 || m1 > 30 || m2 > 30 {
        return Err(bad(format!(
            "unsupported sizes K1={k1} K2={k2} M1={m1} M2={m2}"
        )));
    }
    let (nu, nv, du, dv) = (k1 as usize + 1, k2 as usize + 1, m1 as usize, m2 as usize);
    if nu * nv > 1_000_000 {
        return Err(bad("control net too large".into()));
    }
    let polynomial = int(7)? == 1;
    let mut k = 10;
    let mut take = |n: usize| -> Result<Vec<f64>, IgesError> {
        let v = (k..k + n).map(&re).collect::<Result<Vec<_>, _>>()?;
        k += n;
        Ok(v)
    };
    let u_knots = take(nu + du + 1)?;
    let v_knots = take(nv + dv + 1)?;
    let weights = take(nu * nv)?;
    let coords = take(3 * nu * nv)?;
    if !polynomial {
        let min = weights.iter().copied().fold(f64::INFINITY, f64::min);
        let max = weights.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if min <= 0.0 || (max - min) > 1e-12 * max.abs() {
            return Err(IgesError::RationalWeights { de, min, max });
        }
    }
    let mut points = vec![DVec3::ZERO; nu * nv];
    for j in 0..nv {
        for i in 0..nu {
            let c = 3 * (j * nu + i);
            points[i * nv + j] = DVec3::new(coords[c], coords[c + 1], coords[c + 2]);
        }
    }
    let s = IgesSurface {
        u_degree: du,
        v_degree: dv,
        u_knots,
        v_knots,
        nu,
        nv,
        points,
    };
    s.validate().map_err(|e| bad(e.to_string()))?;
    Ok(s)
}
