//! Reading the sections of a fixed-format IGES file: the Global section's
//! delimiters, the Directory Entry records, and each entity's Parameter Data
//! split into fields (Hollerith strings honoured), with the numeric parsing
//! every entity reader shares.

use super::IgesError;
use std::collections::{BTreeMap, HashMap};

/// One directory entry as far as the reader needs it.
#[derive(Clone, Debug)]
pub(super) struct DirEntry {
    /// Entity type number (field 1).
    pub entity: i64,
    /// First parameter-data line (field 2).
    pub param_start: usize,
    /// Transformation matrix pointer (field 7), 0 if none.
    pub transform: usize,
    /// Status number (field 9), the eight digits as written (may be blank).
    pub status: String,
    /// Parameter-data line count (field 14).
    pub param_lines: usize,
    /// Form number (field 15).
    pub form: i64,
    /// Entity label (field 18), trimmed; empty if none.
    pub label: String,
    /// Entity subscript (field 19), if written.
    pub subscript: Option<i64>,
}

impl DirEntry {
    /// The subordinate entity switch (status digits 3–4): 0 independent,
    /// 1 physically dependent, 2 logically dependent, 3 both. Blank or
    /// unreadable digits count as 0, as IGES defaults blank fields.
    pub fn subordinate(&self) -> u8 {
        self.status_digits(2)
    }

    /// The entity use flag (status digits 5–6): 5 is "2D parametric", a
    /// curve in a surface's parameter space rather than in model space.
    pub fn use_flag(&self) -> u8 {
        self.status_digits(4)
    }

    fn status_digits(&self, from: usize) -> u8 {
        // The field is right-justified in 8 columns: pad to 8 on the left.
        let s = format!("{:0>8}", self.status.replace(' ', "0"));
        s.get(from..from + 2)
            .and_then(|d| d.parse().ok())
            .unwrap_or(0)
    }

    /// The name the label and subscript give, as OpenCASCADE forms it:
    /// `label(subscript)` when a subscript is written, else the label.
    pub fn label_name(&self) -> Option<String> {
        if self.label.is_empty() {
            return None;
        }
        Some(match self.subscript {
            Some(n) => format!("{}({n})", self.label),
            None => self.label.clone(),
        })
    }
}

/// The parsed sections of a file.
pub(super) struct IgesFile {
    /// Directory entries by the sequence number of their first record.
    pub entries: BTreeMap<usize, DirEntry>,
    /// Parameter-data lines by sequence number: the 64 data columns and the
    /// directory back-pointer.
    plines: HashMap<usize, (String, usize)>,
    /// Parameter delimiter.
    pd: char,
    /// Record delimiter.
    rd: char,
    /// Millimetres per model unit (Global fields 14–15).
    pub unit_mm: f64,
}

impl IgesFile {
    /// Splits `text` into its sections.
    pub fn parse(text: &str) -> Result<Self, IgesError> {
        let mut global = String::new();
        let mut dlines: Vec<(usize, String)> = Vec::new();
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
                'D' => dlines.push((n + 1, body.to_string())),
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
        let unit_mm = unit_mm(&global, pd, rd);
        if !dlines.len().is_multiple_of(2) {
            return Err(IgesError::Malformed {
                section: 'D',
                line: dlines.last().map_or(0, |d| d.0),
                reason: "odd number of directory records".into(),
            });
        }
        let field = |rec: &str, k: usize| -> String {
            rec.get(8 * k..8 * k + 8).unwrap_or("").trim().to_string()
        };
        let mut entries = BTreeMap::new();
        for (k, pair) in dlines.chunks_exact(2).enumerate() {
            let de = 2 * k + 1;
            let line = pair[0].0;
            let bad = |reason: String| IgesError::Malformed {
                section: 'D',
                line,
                reason,
            };
            let int = |s: String| -> Result<i64, IgesError> {
                if s.is_empty() {
                    return Ok(0);
                }
                s.parse::<i64>()
                    .map_err(|_| bad(format!("'{s}' is not an integer")))
            };
            let num = |s: String| int(s).map(|v| v.max(0) as usize);
            let (r1, r2) = (&pair[0].1, &pair[1].1);
            let entity = field(r1, 0)
                .parse::<i64>()
                .map_err(|_| bad("bad entity type".into()))?;
            let sub = field(r2, 8);
            entries.insert(
                de,
                DirEntry {
                    entity,
                    param_start: num(field(r1, 1))?,
                    transform: num(field(r1, 6))?,
                    status: r1.get(64..72).unwrap_or("").to_string(),
                    param_lines: num(field(r2, 3))?,
                    form: int(field(r2, 4))?,
                    label: field(r2, 7),
                    subscript: if sub.is_empty() {
                        None
                    } else {
                        Some(int(sub)?)
                    },
                },
            );
        }
        Ok(Self {
            entries,
            plines,
            pd,
            rd,
            unit_mm,
        })
    }

    /// The directory entry at `de`, or an error naming the entity `from`
    /// whose pointer led there.
    pub fn entry(&self, from: usize, de: usize) -> Result<&DirEntry, IgesError> {
        self.entries
            .get(&de)
            .ok_or_else(|| IgesError::BadParameter {
                de: from,
                reason: format!("pointer to D{de}, which is not a directory entry"),
            })
    }

    /// The parameter fields of the entity at `de` (the first is its type).
    pub fn params(&self, de: usize) -> Result<Vec<String>, IgesError> {
        let e = self.entry(de, de)?;
        let mut text = String::new();
        let count = e.param_lines.max(1);
        for s in e.param_start..e.param_start.saturating_add(count) {
            match self.plines.get(&s) {
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
        split_params(&text, self.pd, self.rd)
            .map_err(|reason| IgesError::BadParameter { de, reason })
    }
}

/// Typed access to one entity's parameter fields, with errors naming it.
pub(super) struct Fields<'a> {
    /// The entity's directory-entry sequence number.
    pub de: usize,
    /// The fields, the entity type first.
    pub f: &'a [String],
}

impl Fields<'_> {
    /// An error about this entity.
    pub fn bad(&self, reason: String) -> IgesError {
        IgesError::BadParameter {
            de: self.de,
            reason,
        }
    }

    fn get(&self, k: usize) -> Result<&str, IgesError> {
        self.f
            .get(k)
            .map(String::as_str)
            .ok_or_else(|| self.bad(format!("missing parameter {k}")))
    }

    /// Field `k` as an integer.
    pub fn int(&self, k: usize) -> Result<i64, IgesError> {
        parse_int(self.get(k)?).map_err(|r| self.bad(r))
    }

    /// Field `k` as a finite real.
    pub fn real(&self, k: usize) -> Result<f64, IgesError> {
        parse_real(self.get(k)?).map_err(|r| self.bad(r))
    }

    /// Field `k` as text (a Hollerith string's content).
    pub fn text(&self, k: usize) -> Result<&str, IgesError> {
        self.get(k)
    }

    /// `n` reals from field `*k` on, advancing `*k`.
    pub fn reals(&self, k: &mut usize, n: usize) -> Result<Vec<f64>, IgesError> {
        if self.f.len() < k.saturating_add(n) {
            return Err(self.bad(format!(
                "{} parameters where at least {} are needed",
                self.f.len(),
                k.saturating_add(n)
            )));
        }
        let v = (*k..*k + n)
            .map(|i| self.real(i))
            .collect::<Result<Vec<_>, _>>()?;
        *k += n;
        Ok(v)
    }

    /// A directory pointer in field `k`: a positive odd sequence number of
    /// an existing entry (0 means "none" and gives `None`).
    pub fn pointer(&self, file: &IgesFile, k: usize) -> Result<Option<usize>, IgesError> {
        let v = self.int(k)?;
        if v == 0 {
            return Ok(None);
        }
        let de = usize::try_from(v)
            .ok()
            .filter(|d| d % 2 == 1)
            .ok_or_else(|| self.bad(format!("field {k} = {v} is not a directory pointer")))?;
        file.entry(self.de, de)?;
        Ok(Some(de))
    }

    /// The properties listed after the entity's own `own` fields: IGES
    /// follows them with a count and pointers of associativities, then a
    /// count and pointers of properties (both groups optional).
    pub fn properties(&self, file: &IgesFile, own: usize) -> Result<Vec<usize>, IgesError> {
        let mut k = own;
        let mut groups = Vec::new();
        for _ in 0..2 {
            if k >= self.f.len() || self.f[k].is_empty() && k + 1 == self.f.len() {
                groups.push(Vec::new());
                continue;
            }
            let n = self.int(k)?;
            let n = usize::try_from(n)
                .ok()
                .filter(|&n| n < self.f.len() - k)
                .ok_or_else(|| self.bad(format!("pointer count {n} at field {k}")))?;
            let ptrs = (k + 1..k + 1 + n)
                .map(|i| self.pointer(file, i))
                .collect::<Result<Vec<_>, _>>()?;
            groups.push(ptrs.into_iter().flatten().collect());
            k += 1 + n;
        }
        Ok(groups.pop().unwrap_or_default())
    }
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
            if n > chars.len() || k + 1 + n > chars.len() {
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

/// A real field (`D` exponents accepted; blank is 0); never NaN or infinite.
pub(super) fn parse_real(s: &str) -> Result<f64, String> {
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

/// An integer field (blank is 0; a real with no fraction is accepted).
pub(super) fn parse_int(s: &str) -> Result<i64, String> {
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

/// Millimetres per model unit from the Global section: the units flag
/// (field 14) and units name (field 15), converted only when they agree
/// (or the flag is 3, "name given", with a known name). Otherwise — fields
/// missing, blank, unknown or contradicting each other, as when a Hollerith
/// count earlier in the section is wrong — the numbers are taken as
/// millimetres, what vsculpt and most tools write.
fn unit_mm(global: &str, pd: char, rd: char) -> f64 {
    let Ok(fields) = split_params(global, pd, rd) else {
        return 1.0;
    };
    let flag = fields.get(13).and_then(|s| parse_int(s).ok());
    let name = fields.get(14).map(|s| s.trim().to_ascii_uppercase());
    let by_name = match name.as_deref() {
        Some("IN" | "INCH") => Some((1, 25.4)),
        Some("MM") => Some((2, 1.0)),
        Some("FT") => Some((4, 304.8)),
        Some("MI") => Some((5, 1_609_344.0)),
        Some("M") => Some((6, 1000.0)),
        Some("KM") => Some((7, 1e6)),
        Some("MIL") => Some((8, 0.0254)),
        Some("UM") => Some((9, 1e-3)),
        Some("CM") => Some((10, 10.0)),
        Some("UIN") => Some((11, 2.54e-5)),
        _ => None,
    };
    match (flag, by_name) {
        (Some(f), Some((g, mm))) if f == g || f == 3 => mm,
        _ => 1.0,
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
