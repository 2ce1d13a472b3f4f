//! The written form of IGES values: printable-ASCII text, Hollerith strings,
//! reals that round-trip, timestamps, and parameters packed into the fixed
//! columns of a record.

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
pub(super) fn hollerith(s: &str) -> String {
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

/// A real in the shortest form that reads back bit for bit, always with a
/// decimal point and an exponent (`1.5E0`), as IGES reals are written.
pub(super) fn real(x: f64) -> String {
    let s = format!("{x:E}");
    match s.find('E') {
        Some(e) if !s[..e].contains('.') => format!("{}.0{}", &s[..e], &s[e..]),
        _ => s,
    }
}

/// Packs parameter tokens (each already carrying its delimiter) into lines
/// of at most `width` columns without splitting a token, except a token
/// longer than a line, which is split (only Hollerith strings can be).
pub(super) fn pack(tokens: &[String], width: usize) -> Vec<String> {
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

/// Parameters followed by their delimiters: `,` between, `;` after the last.
pub(super) fn with_delims(params: Vec<String>) -> Vec<String> {
    let n = params.len();
    params
        .into_iter()
        .enumerate()
        .map(|(k, p)| format!("{p}{}", if k + 1 == n { ';' } else { ',' }))
        .collect()
}

/// A knot vector is usable: finite, non-decreasing, and the span between
/// `knots[degree]` and `knots[count]` is not empty.
pub(super) fn knots_ok(knots: &[f64], degree: usize, count: usize) -> Result<(), String> {
    if knots.iter().any(|k| !k.is_finite()) {
        return Err("non-finite knot".into());
    }
    if knots.windows(2).any(|w| w[1] < w[0]) {
        return Err("knots are not non-decreasing".into());
    }
    match (knots.get(degree), knots.get(count)) {
        (Some(a), Some(b)) if a < b => Ok(()),
        _ => Err("the knot vector spans an empty parameter range".into()),
    }
}
