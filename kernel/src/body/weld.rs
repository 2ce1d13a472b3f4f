//! Welding the pieces of a union's boundary into one closed, manifold
//! triangle mesh (issue 13).
//!
//! [`super::union`] clips every body's sampled boundary against the other
//! bodies on its own, so the pieces meet without sharing vertices: a
//! body's faces each have their own vertices along the body's edges,
//! bodies sharing a face meet along its boundary with a copy of each
//! vertex per body, and where two bodies cross, each side is cut at its
//! own points of the same intersection curve. Welding makes one mesh of
//! them, in four steps:
//!
//! 1. **Merge** vertices closer than `tol` (a spatial hash of `tol` cells):
//!    the copies along body edges and shared faces are one vertex again.
//!    Triangles that collapse go; a triangle and its mirror image (a face
//!    left by both bodies, facing both ways) go together; a triangle twice
//!    over is kept once.
//! 2. **Split** the T-junctions of the seams: every vertex at the open
//!    border of one body's piece that lies on an open border edge of
//!    another body's piece (within `tol`, or [`SEAM`] of the edge's length
//!    for a curved seam, whose two sides are different chords of the same
//!    curve) is inserted into that edge, its triangle split in two. Repeated
//!    until nothing is inserted, both sides of a seam then run through the
//!    same vertices and their border edges pair up.
//! 3. **Close** what is still open — where three bodies meet, or where the
//!    chords of a curved seam interleave — by fanning each loop of border
//!    edges left (a triangle or a few slivers as wide as the seam's chord
//!    error).
//! 4. **Compact**: vertices no triangle uses are dropped.
//!
//! The result is then **checked** ([`check_manifold`]: every edge in
//! exactly two triangles with opposite directions, one fan of triangles
//! round every vertex). Where the two sides of a curved seam zigzag about
//! each other more than steps 2–3 can order (coarse samplings), the check
//! fails; the merged pieces are then **zipped** instead ([`zip_seams`]):
//! each border loop is paired with the nearest loop of another body, and
//! the two are stitched by a strip of triangles — an annulus glued along
//! two circles, so the surface is closed, oriented and of the pieces'
//! Euler characteristic by construction. Before either, each body's piece
//! is checked to be a piece of a sphere (χ = 2 − its border loops per
//! connected part). What still fails is an error: the union reports the
//! sampling as too coarse (`BodyError::TooCoarse`), never a broken mesh.
//!
//! No vertex moves (but for snapping), so the welded mesh encloses the same
//! volume as the pieces but for the slivers of steps 2–3 or the strips.

use std::collections::HashMap;

use glam::DVec3;

/// How far from a border edge, relative to its length, another body's
/// border vertex may lie and still be inserted into it (the two sides of a
/// curved seam are chords of the same curve, a chord error apart).
pub const SEAM: f64 = 0.2;

/// Border vertices of different bodies closer than this, relative to the
/// shortest border edge at either, are snapped into one (the first kept,
/// the other moved onto it by less than a chord error): where the two
/// sides of a seam zigzag about each other on a scale finer than their
/// edges, inserting one side's vertices into the other's edges could not
/// keep their order.
pub const SNAP: f64 = 0.25;

/// Rounds of dropping doubled edges' triangles and closing what they
/// leave, at most.
const REPAIRS: usize = 4;

/// Rounds of T-junction splitting at most (each round inserts every vertex
/// that has an edge to go into, one edge per triangle).
const ROUNDS: usize = 32;

/// A triangle mesh whose triangles each remember their body.
#[derive(Clone, Debug, Default)]
pub(super) struct Pieces {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[usize; 3]>,
    pub body: Vec<usize>,
}

/// What welding did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WeldReport {
    /// Vertices merged into another.
    pub merged: usize,
    /// Border vertices snapped onto another body's (see [`SNAP`]).
    pub snapped: usize,
    /// Vertices inserted into another body's border edge.
    pub inserted: usize,
    /// Triangles dropped because an edge ran the same way in another.
    pub dropped: usize,
    /// Loops of border edges closed by a fan.
    pub closed: usize,
    /// Triangles those fans added.
    pub fan_triangles: usize,
}

/// Welds `m` (see the module doc), vertices closer than `tol` being one.
/// The result is checked ([`check_manifold`]); when the T-junction welding
/// leaves it broken, the pieces are zipped instead ([`zip_seams`]) and
/// checked again; an error says what is still broken (the caller reports
/// the sampling as too coarse).
pub(super) fn weld(m: &mut Pieces, tol: f64) -> Result<WeldReport, String> {
    let mut report = WeldReport {
        merged: merge(m, tol),
        ..WeldReport::default()
    };
    cancel_duplicates(m);
    check_pieces(m)?;
    let pieces = m.clone();
    let first = junctions(m, tol, &mut report);
    compact(m);
    let first = first.and_then(|()| check_manifold(m));
    if first.is_ok() {
        return Ok(report);
    }
    // The two sides of a seam could not be put in one order: stitch each
    // pair of border loops with a strip instead.
    *m = pieces;
    let mut zipped = WeldReport {
        merged: report.merged,
        ..WeldReport::default()
    };
    let result = zip_seams(m, &mut zipped).and_then(|()| {
        compact(m);
        check_manifold(m)
    });
    match result {
        Ok(()) => Ok(zipped),
        Err(e) => Err(format!(
            "{} (T-junction weld: {})",
            e,
            first.err().unwrap_or_default()
        )),
    }
}

/// Steps 2 and 3 of the module doc: snapping, T-junction splitting, closing
/// what is left, dropping doubled edges' triangles.
fn junctions(m: &mut Pieces, tol: f64, report: &mut WeldReport) -> Result<(), String> {
    report.snapped = snap(m);
    cancel_duplicates(m);
    // Each vertex's body: that of the first triangle using it (a vertex
    // merged from several bodies' copies lies on all of them, and no seam
    // vertex of one body needs inserting into it).
    let mut origin = vec![usize::MAX; m.positions.len()];
    for (t, &b) in m.triangles.iter().zip(&m.body) {
        for &v in t {
            if origin[v] == usize::MAX {
                origin[v] = b;
            }
        }
    }
    for _ in 0..ROUNDS {
        let n = split_seams(m, tol, &origin);
        if n == 0 {
            break;
        }
        report.inserted += n;
    }
    let (closed, fans) = close_loops(m);
    report.closed = closed;
    report.fan_triangles = fans;
    // Where the two sides' vertices could not be put in one order, an edge
    // runs the same way in two triangles: the later triangle goes, and the
    // loop it leaves is fanned shut.
    for _ in 0..REPAIRS {
        let dropped = drop_doubled(m);
        if dropped == 0 {
            break;
        }
        report.dropped += dropped;
        let (closed, fans) = close_loops(m);
        report.closed += closed;
        report.fan_triangles += fans;
    }
    Ok(())
}

/// Checks that every body's piece is a piece of a sphere (a body's
/// boundary is one): each connected part of it (triangles of one body
/// joined by edges) has Euler characteristic 2 − its border loops. A part
/// that does not — a body crossing a triangle without containing one of
/// its vertices leaves a handle or a pinch — cannot be welded right.
fn check_pieces(m: &Pieces) -> Result<(), String> {
    let n = m.triangles.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    // Undirected edges of each body, with the triangles holding them.
    let mut edges: HashMap<(usize, usize, usize), Vec<usize>> = HashMap::new();
    for (i, t) in m.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges
                .entry((m.body[i], a.min(b), a.max(b)))
                .or_default()
                .push(i);
        }
    }
    for ts in edges.values() {
        for w in ts.windows(2) {
            let (a, b) = (root(&mut parent, w[0]), root(&mut parent, w[1]));
            parent[a] = b;
        }
    }
    // Per part: vertices, edges, faces, and its border edges' vertices
    // joined into loops.
    #[derive(Default)]
    struct Part {
        vertices: std::collections::HashSet<usize>,
        edges: usize,
        faces: usize,
        border: Vec<(usize, usize)>,
    }
    let mut parts: HashMap<usize, Part> = HashMap::new();
    for (i, t) in m.triangles.iter().enumerate() {
        let p = parts.entry(root(&mut parent, i)).or_default();
        p.faces += 1;
        p.vertices.extend(t.iter().copied());
    }
    for (&(_, a, b), ts) in &edges {
        let p = parts.entry(root(&mut parent, ts[0])).or_default();
        p.edges += 1;
        if ts.len() == 1 {
            p.border.push((a, b));
        }
    }
    for p in parts.values() {
        let mut up: HashMap<usize, usize> = HashMap::new();
        fn find(up: &mut HashMap<usize, usize>, v: usize) -> usize {
            let mut r = v;
            while let Some(&u) = up.get(&r).filter(|&&u| u != r) {
                r = u;
            }
            r
        }
        let mut loops = 0i64;
        let mut seen = std::collections::HashSet::new();
        for &(a, b) in &p.border {
            for v in [a, b] {
                if seen.insert(v) {
                    up.insert(v, v);
                    loops += 1;
                }
            }
            let (ra, rb) = (find(&mut up, a), find(&mut up, b));
            if ra != rb {
                up.insert(ra, rb);
                loops -= 1;
            }
        }
        let chi = p.vertices.len() as i64 - p.edges as i64 + p.faces as i64;
        if chi != 2 - loops {
            let at = m.positions[*p.vertices.iter().next().unwrap_or(&0)];
            return Err(format!(
                "a body's piece near {at:?} is not a piece of its boundary (χ = {chi} with {loops} border loops): another body crosses a triangle without containing any of its vertices"
            ));
        }
    }
    Ok(())
}

/// Whether `m` is a closed, consistently oriented 2-manifold: no triangle
/// repeats a vertex, every directed edge occurs once and its reverse once,
/// and the triangles around every vertex form one fan (a vertex where two
/// fans touch is a pinch). Says what is wrong, and where, otherwise.
pub(super) fn check_manifold(m: &Pieces) -> Result<(), String> {
    let mut next: HashMap<(usize, usize), usize> = HashMap::new();
    for t in &m.triangles {
        if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
            return Err(format!("a triangle repeats a vertex: {t:?}"));
        }
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            if next.insert((a, b), c).is_some() {
                return Err(format!(
                    "the edge {:?} → {:?} runs the same way in two triangles",
                    m.positions[a], m.positions[b]
                ));
            }
        }
    }
    if let Some((a, b)) = next.keys().find(|(a, b)| !next.contains_key(&(*b, *a))) {
        return Err(format!(
            "the edge {:?} → {:?} is open (in one triangle)",
            m.positions[*a], m.positions[*b]
        ));
    }
    // Around vertex a, triangle (a, b, c) is followed by the one holding
    // (a, c): one cycle through all of a's triangles.
    let mut around: HashMap<usize, Vec<usize>> = HashMap::new();
    for &(a, b) in next.keys() {
        around.entry(a).or_default().push(b);
    }
    for (&a, firsts) in &around {
        let mut b = firsts[0];
        let mut steps = 0;
        loop {
            b = next[&(a, b)];
            steps += 1;
            if b == firsts[0] || steps > firsts.len() {
                break;
            }
        }
        if steps != firsts.len() {
            return Err(format!(
                "the surface pinches at {:?} ({} triangles there, one fan of {steps})",
                m.positions[a],
                firsts.len()
            ));
        }
    }
    Ok(())
}

/// Zips the seams of `m` (pieces merged, not yet welded): every loop of
/// border edges is paired with the nearest loop of the other side running
/// the other way, and the two are stitched by a strip of triangles (from
/// the nearest pair of vertices on, each step advancing the loop whose
/// next diagonal is shorter). Each strip is an annulus glued along two
/// circles, so the Euler characteristic is the pieces'. Fails when a
/// border vertex has several border edges out or in (the pieces pinch), or
/// a loop has no partner (three bodies meet on it).
fn zip_seams(m: &mut Pieces, report: &mut WeldReport) -> Result<(), String> {
    let border = borders(m);
    let mut out: HashMap<usize, (usize, usize)> = HashMap::new();
    let mut ins: HashMap<usize, usize> = HashMap::new();
    for &(a, b, t) in &border {
        if out.insert(a, (b, t)).is_some() || ins.insert(b, a).is_some() {
            return Err(format!(
                "the pieces pinch at {:?} (two seams through it)",
                m.positions[if out.contains_key(&a) { a } else { b }]
            ));
        }
    }
    let mut seen = std::collections::HashSet::new();
    let mut loops: Vec<(Vec<usize>, usize)> = Vec::new();
    for &(a, _, t) in &border {
        if seen.contains(&a) {
            continue;
        }
        let mut lp = Vec::new();
        let mut v = a;
        while seen.insert(v) {
            lp.push(v);
            v = out[&v].0;
        }
        loops.push((lp, m.body[t]));
    }
    // How far loop p's vertices lie from loop q's, on average.
    let gap = |p: &[usize], q: &[usize]| {
        p.iter()
            .map(|&i| {
                q.iter()
                    .map(|&j| m.positions[i].distance(m.positions[j]))
                    .fold(f64::INFINITY, f64::min)
            })
            .sum::<f64>()
            / p.len() as f64
    };
    let best = |k: usize| {
        (0..loops.len())
            .filter(|&l| l != k && loops[l].1 != loops[k].1)
            .min_by(|&x, &y| {
                gap(&loops[k].0, &loops[x].0).total_cmp(&gap(&loops[k].0, &loops[y].0))
            })
    };
    let partner: Vec<Option<usize>> = (0..loops.len()).map(best).collect();
    for k in 0..loops.len() {
        let Some(l) = partner[k].filter(|&l| partner[l] == Some(k)) else {
            let at = m.positions[loops[k].0[0]];
            return Err(format!("a seam at {at:?} has no partner on another body"));
        };
        if l < k {
            continue;
        }
        let body = loops[k].1;
        let p = &loops[k].0;
        // The partner backwards, from its vertex nearest p[0]: it then runs
        // along p.
        let q = &loops[l].0;
        let start = (0..q.len())
            .min_by(|&x, &y| {
                let d = |j: usize| m.positions[q[j]].distance(m.positions[p[0]]);
                d(x).total_cmp(&d(y))
            })
            .unwrap_or(0);
        let r: Vec<usize> = (0..q.len())
            .map(|j| q[(start + q.len() - j) % q.len()])
            .collect();
        let (n, s) = (p.len(), r.len());
        let (mut i, mut j) = (0, 0);
        while i < n || j < s {
            let d = |a: usize, b: usize| m.positions[a].distance(m.positions[b]);
            let advance_p =
                j == s || (i < n && d(p[(i + 1) % n], r[j % s]) <= d(r[(j + 1) % s], p[i % n]));
            let t = if advance_p {
                i += 1;
                [p[i % n], p[(i - 1) % n], r[j % s]]
            } else {
                j += 1;
                [r[(j - 1) % s], r[j % s], p[i % n]]
            };
            if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
                return Err(format!(
                    "two seams share the vertex {:?}",
                    m.positions[t[2]]
                ));
            }
            m.triangles.push(t);
            m.body.push(body);
            report.fan_triangles += 1;
        }
        report.closed += 1;
    }
    Ok(())
}

type Cell = (i64, i64, i64);

fn cell_of(p: DVec3, size: f64) -> Cell {
    let c = (p / size).floor();
    (c.x as i64, c.y as i64, c.z as i64)
}

/// Merges vertices within `tol` of a kept one; returns how many merged.
fn merge(m: &mut Pieces, tol: f64) -> usize {
    let mut grid: HashMap<Cell, Vec<usize>> = HashMap::new();
    let mut rep = vec![0usize; m.positions.len()];
    let mut merged = 0;
    for (i, &p) in m.positions.iter().enumerate() {
        let (x, y, z) = cell_of(p, tol);
        let mut found = None;
        'search: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&(x + dx, y + dy, z + dz))
                        && let Some(&j) = list.iter().find(|&&j| m.positions[j].distance(p) <= tol)
                    {
                        found = Some(j);
                        break 'search;
                    }
                }
            }
        }
        rep[i] = match found {
            Some(j) => {
                merged += 1;
                j
            }
            None => {
                grid.entry((x, y, z)).or_default().push(i);
                i
            }
        };
    }
    let (tris, body) = (
        std::mem::take(&mut m.triangles),
        std::mem::take(&mut m.body),
    );
    for (t, b) in tris.into_iter().zip(body) {
        let t = t.map(|i| rep[i]);
        if t[0] != t[1] && t[1] != t[2] && t[2] != t[0] {
            m.triangles.push(t);
            m.body.push(b);
        }
    }
    merged
}

/// `t` rotated so that its smallest index comes first (same orientation).
fn rotated(t: [usize; 3]) -> [usize; 3] {
    let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
}

/// Drops a triangle together with its mirror image, and repeats of a
/// triangle.
fn cancel_duplicates(m: &mut Pieces) {
    let mut seen: HashMap<[usize; 3], usize> = HashMap::new();
    let mut keep = vec![true; m.triangles.len()];
    for (i, &t) in m.triangles.iter().enumerate() {
        let r = rotated(t);
        let mirror = rotated([t[0], t[2], t[1]]);
        if seen.contains_key(&r) {
            keep[i] = false;
        } else if let Some(j) = seen.remove(&mirror) {
            keep[i] = false;
            keep[j] = false;
        } else {
            seen.insert(r, i);
        }
    }
    retain(m, &keep);
}

fn retain(m: &mut Pieces, keep: &[bool]) {
    let (tris, body) = (
        std::mem::take(&mut m.triangles),
        std::mem::take(&mut m.body),
    );
    for ((t, b), k) in tris.into_iter().zip(body).zip(keep) {
        if *k {
            m.triangles.push(t);
            m.body.push(b);
        }
    }
}

/// The border half-edges (a → b in a triangle, b → a in none), with their
/// triangle.
fn borders(m: &Pieces) -> Vec<(usize, usize, usize)> {
    let mut directed: HashMap<(usize, usize), usize> = HashMap::new();
    for (i, t) in m.triangles.iter().enumerate() {
        for k in 0..3 {
            directed.entry((t[k], t[(k + 1) % 3])).or_insert(i);
        }
    }
    let mut out: Vec<(usize, usize, usize)> = directed
        .iter()
        .filter(|((a, b), _)| !directed.contains_key(&(*b, *a)))
        .map(|(&(a, b), &t)| (a, b, t))
        .collect();
    out.sort_unstable();
    out
}

/// One round of T-junction splitting; returns the vertices inserted.
fn split_seams(m: &mut Pieces, tol: f64, origin: &[usize]) -> usize {
    let border = borders(m);
    if border.is_empty() {
        return 0;
    }
    let mut verts: Vec<usize> = border.iter().flat_map(|&(a, b, _)| [a, b]).collect();
    verts.sort_unstable();
    verts.dedup();
    // A grid of border edges, cells as large as the median edge.
    let mut lengths: Vec<f64> = border
        .iter()
        .map(|&(a, b, _)| m.positions[a].distance(m.positions[b]))
        .collect();
    lengths.sort_by(f64::total_cmp);
    let h = (2.0 * lengths[lengths.len() / 2]).max(tol);
    let mut grid: HashMap<Cell, Vec<usize>> = HashMap::new();
    for (e, &(a, b, _)) in border.iter().enumerate() {
        let (p, q) = (m.positions[a], m.positions[b]);
        let reach = (SEAM * p.distance(q)).max(tol);
        let lo = cell_of(p.min(q) - DVec3::splat(reach), h);
        let hi = cell_of(p.max(q) + DVec3::splat(reach), h);
        for x in lo.0..=hi.0 {
            for y in lo.1..=hi.1 {
                for z in lo.2..=hi.2 {
                    grid.entry((x, y, z)).or_default().push(e);
                }
            }
        }
    }
    // Each border vertex's nearest other-body border edge it lies on.
    let mut wanted: HashMap<usize, Vec<(f64, usize)>> = HashMap::new();
    for &v in &verts {
        let x = m.positions[v];
        let Some(list) = grid.get(&cell_of(x, h)) else {
            continue;
        };
        let mut best: Option<(f64, usize, f64)> = None;
        for &e in list {
            let (a, b, t) = border[e];
            if m.triangles[t].contains(&v) || m.body[t] == origin[v] {
                continue;
            }
            let (p, q) = (m.positions[a], m.positions[b]);
            let d = q - p;
            let len2 = d.length_squared();
            if len2 == 0.0 {
                continue;
            }
            let s = (x - p).dot(d) / len2;
            if s <= 0.0 || s >= 1.0 {
                continue;
            }
            let dist = (p + d * s).distance(x);
            let len = len2.sqrt();
            // Not at an end (that is a merge's work, or a shorter edge's).
            if dist > (SEAM * len).max(tol) || s * len <= tol || (1.0 - s) * len <= tol {
                continue;
            }
            if best.is_none_or(|(bd, _, _)| dist < bd) {
                best = Some((dist, e, s));
            }
        }
        if let Some((_, e, s)) = best {
            wanted.entry(e).or_default().push((s, v));
        }
    }
    // One edge per triangle per round.
    let mut done_tri = vec![false; m.triangles.len()];
    let mut edges: Vec<usize> = wanted.keys().copied().collect();
    edges.sort_unstable();
    let mut inserted = 0;
    for e in edges {
        let (a, b, t) = border[e];
        if done_tri[t] {
            continue;
        }
        done_tri[t] = true;
        let mut vs = wanted.remove(&e).unwrap_or_default();
        vs.sort_by(|p, q| p.0.total_cmp(&q.0));
        vs.dedup_by_key(|p| p.1);
        let tri = m.triangles[t];
        let k = (0..3)
            .find(|&k| tri[k] == a && tri[(k + 1) % 3] == b)
            .expect("a border edge is in its triangle");
        let z = tri[(k + 2) % 3];
        let mut chain = vec![a];
        chain.extend(vs.iter().map(|p| p.1));
        chain.push(b);
        inserted += vs.len();
        m.triangles[t] = [chain[0], chain[1], z];
        for w in chain.windows(2).skip(1) {
            m.triangles.push([w[0], w[1], z]);
            m.body.push(m.body[t]);
        }
    }
    inserted
}

/// Fans every loop of border edges left; returns (loops, triangles added).
fn close_loops(m: &mut Pieces) -> (usize, usize) {
    let border = borders(m);
    let mut out: HashMap<usize, Vec<(usize, usize)>> = HashMap::new();
    for (e, &(a, b, _)) in border.iter().enumerate() {
        out.entry(a).or_default().push((b, e));
    }
    let mut used = vec![false; border.len()];
    let mut loops: Vec<(Vec<usize>, usize)> = Vec::new();
    for start in 0..border.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let (a, b, t) = border[start];
        let body = m.body[t];
        let mut path = vec![a];
        let mut at: HashMap<usize, usize> = HashMap::from([(a, 0)]);
        let mut cur = b;
        loop {
            if let Some(&j) = at.get(&cur) {
                // A loop closes at `cur`: cut it off the path.
                loops.push((path[j..].to_vec(), body));
                for v in path.drain(j + 1..) {
                    at.remove(&v);
                }
            } else {
                at.insert(cur, path.len());
                path.push(cur);
            }
            let next = out
                .get(&cur)
                .and_then(|l| l.iter().find(|(_, e)| !used[*e]));
            match next {
                Some(&(n, e)) => {
                    used[e] = true;
                    cur = n;
                }
                None => break,
            }
        }
    }
    let mut fans = 0;
    let mut closed = 0;
    let mut edges: std::collections::HashSet<(usize, usize)> = m
        .triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
        .collect();
    for (lp, body) in loops {
        let n = lp.len();
        if n < 3 {
            continue;
        }
        closed += 1;
        // The fan's apex: the first loop vertex whose fan adds no edge the
        // mesh has already (else the first).
        let fan = |r: usize| -> Vec<[usize; 3]> {
            (1..n - 1)
                .map(|i| [lp[r], lp[(r + i + 1) % n], lp[(r + i) % n]])
                .collect()
        };
        let apex = (0..n)
            .find(|&r| {
                fan(r).iter().all(|t| {
                    (0..3).all(|k| {
                        let e = (t[k], t[(k + 1) % 3]);
                        // The loop's own reversed border edges are wanted.
                        !edges.contains(&e)
                    })
                })
            })
            .unwrap_or(0);
        for t in fan(apex) {
            for k in 0..3 {
                edges.insert((t[k], t[(k + 1) % 3]));
            }
            m.triangles.push(t);
            m.body.push(body);
            fans += 1;
        }
    }
    (closed, fans)
}

/// Snaps border vertices of different bodies onto each other (see
/// [`SNAP`]); returns how many moved.
fn snap(m: &mut Pieces) -> usize {
    let border = borders(m);
    if border.is_empty() {
        return 0;
    }
    // Per border vertex: its body and its shortest border edge.
    let mut info: HashMap<usize, (usize, f64)> = HashMap::new();
    for &(a, b, t) in &border {
        let len = m.positions[a].distance(m.positions[b]);
        for v in [a, b] {
            let e = info.entry(v).or_insert((m.body[t], f64::INFINITY));
            e.1 = e.1.min(len);
        }
    }
    let mut verts: Vec<usize> = info.keys().copied().collect();
    verts.sort_unstable();
    let h = verts
        .iter()
        .map(|v| info[v].1)
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut grid: HashMap<Cell, Vec<usize>> = HashMap::new();
    let mut rep: HashMap<usize, usize> = HashMap::new();
    for &v in &verts {
        let p = m.positions[v];
        let (x, y, z) = cell_of(p, h);
        let (body, len) = info[&v];
        let mut found = None;
        'search: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = grid.get(&(x + dx, y + dy, z + dz)) else {
                        continue;
                    };
                    for &w in list {
                        let (wb, wl) = info[&w];
                        if wb != body && m.positions[w].distance(p) <= SNAP * len.min(wl) {
                            found = Some(w);
                            break 'search;
                        }
                    }
                }
            }
        }
        match found {
            Some(w) => {
                rep.insert(v, w);
            }
            None => grid.entry((x, y, z)).or_default().push(v),
        }
    }
    let moved = rep.len();
    let keep: Vec<bool> = m
        .triangles
        .iter_mut()
        .map(|t| {
            for i in t.iter_mut() {
                if let Some(&w) = rep.get(i) {
                    *i = w;
                }
            }
            t[0] != t[1] && t[1] != t[2] && t[2] != t[0]
        })
        .collect();
    retain(m, &keep);
    moved
}

/// Drops every triangle that has a directed edge an earlier triangle has;
/// returns how many.
fn drop_doubled(m: &mut Pieces) -> usize {
    let mut first: HashMap<(usize, usize), usize> = HashMap::new();
    let mut keep = vec![true; m.triangles.len()];
    for (i, t) in m.triangles.iter().enumerate() {
        for k in 0..3 {
            let e = (t[k], t[(k + 1) % 3]);
            match first.get(&e) {
                Some(&j) if j != i => keep[i] = false,
                _ => {
                    first.insert(e, i);
                }
            }
        }
    }
    let dropped = keep.iter().filter(|k| !**k).count();
    retain(m, &keep);
    dropped
}

/// Drops the vertices no triangle uses.
fn compact(m: &mut Pieces) {
    let mut map = vec![usize::MAX; m.positions.len()];
    let mut positions = Vec::new();
    for t in &mut m.triangles {
        for i in t.iter_mut() {
            if map[*i] == usize::MAX {
                map[*i] = positions.len();
                positions.push(m.positions[*i]);
            }
            *i = map[*i];
        }
    }
    m.positions = positions;
}
