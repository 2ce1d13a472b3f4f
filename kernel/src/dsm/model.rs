//! Shape groups, equal density solids and the object (paper eqs. 1–7).
//!
//! For each shape group k, in order:
//! * f_k = Σ_i F_ik — the group's density primitives (eq. 1), culled outside
//!   their influence ranges;
//! * R_k = Σ_j G_jk + Σ_m Q_m — the geometric primitives (±D_e inside, eq. 2) plus the
//!   equal density solids of the earlier groups m it incorporates (eq. 3);
//! * H_k = D_e where R_k ≥ D_e, else 0 (eq. 5);
//! * E_k = f_k + H_k − D_e (eq. 4) and Q_k = D_e where E_k ≥ 0, else 0 (eq. 6).
//!
//! Fusion is limited to a group: density primitives of one group never add to
//! another's f. The object is S = {Σ_t σ_t Π_{k∈t} Q_k / D_e^{|t|−1} ≥ D_e} over its
//! terms t (eq. 7 when every term is one group with σ = +1).
//!
//! Choices the paper leaves open, made here:
//! * Add and subtract of shapes: a term's sign σ = ±1 (a subtracted group removes
//!   its solid wherever no other term covers it twice). Multiply: a term lists
//!   several groups and contributes the product of their indicators — the
//!   intersection.
//! * A group incorporated into another (eq. 3's Q) counts in eq. (7) only if a term
//!   lists it; groups may incorporate only earlier groups (no cycles).
//! * Culling: a density primitive is 0 beyond min(range, r_τ) where
//!   |D| e^{−a r_τ} = τ D_e (sheets: with max |D(u, v)|); the field error this causes is
//!   below n·τ·D_e at any point (n the number of culled primitives there), which moves
//!   a surface with |∇f| ≈ a D_e by at most n·τ/a. τ defaults to 1e-9.

use super::density::{DensityPrimitive, RadialCharge};
use super::error::{DsmError, positive};
use super::geometric::GeometricPrimitive;
use super::interval::{Interval, Tri};
use glam::DVec3;

/// A shape group: geometric and density primitives that fuse, plus earlier
/// groups' equal density solids incorporated into it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Group {
    /// Geometric primitives (eq. 2).
    pub geometric: Vec<GeometricPrimitive>,
    /// Density primitives (eq. 1).
    pub density: Vec<DensityPrimitive>,
    /// Indices of earlier groups whose solids enter R_k (eq. 3).
    pub incorporated: Vec<usize>,
}

/// How a term enters eq. (7).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sign {
    /// + D_e (add).
    Add,
    /// − D_e (subtract).
    Subtract,
}

/// One term of eq. (7): the product (intersection) of groups' solids, with a sign.
#[derive(Clone, Debug, PartialEq)]
pub struct Term {
    /// The groups multiplied.
    pub groups: Vec<usize>,
    /// Add or subtract.
    pub sign: Sign,
}

/// A Density Spatial Model object: groups, eq. (7)'s terms, D_e and the culling τ.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    de: f64,
    tau: f64,
    groups: Vec<Group>,
    terms: Vec<Term>,
    ranges: Vec<Vec<f64>>,
    cuts: Vec<Vec<bool>>,
    scales: Vec<f64>,
    /// Per group: each density primitive as a radial charge, where it is one.
    radial: Vec<Vec<Option<RadialCharge>>>,
    /// Per group: each geometric primitive's bounding ball (centre, radius).
    gballs: Vec<Vec<(DVec3, f64)>>,
    /// Per group: each density primitive's influence ball (centre, radius).
    dballs: Vec<Vec<(DVec3, f64)>>,
}

/// Which primitives may be non-zero in a region: per group, the indices of its
/// geometric and density primitives (the rest are culled there).
#[derive(Clone, Debug, PartialEq)]
pub struct Active {
    /// Per group: geometric primitive indices.
    pub geometric: Vec<Vec<u32>>,
    /// Per group: density primitive indices.
    pub density: Vec<Vec<u32>>,
}

/// The object at a point: inside S or not, and Φ, a continuous signed estimate of
/// the distance to S's boundary (> 0 inside, its zero set ⊇ ∂S).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Whether the point is in S.
    pub inside: bool,
    /// Φ.
    pub phi: f64,
}

/// Default culling threshold τ (relative to D_e).
pub const DEFAULT_TAU: f64 = 1e-9;

impl Model {
    /// An empty model with presentation density D_e and culling threshold τ ∈ (0, 1).
    pub fn new(de: f64, tau: f64) -> Result<Self, DsmError> {
        positive("D_e", de)?;
        if !(tau > 0.0 && tau < 1.0) {
            return Err(DsmError::BadParameter {
                name: "tau",
                value: tau,
                why: "must be in (0, 1)",
            });
        }
        Ok(Self {
            de,
            tau,
            groups: Vec::new(),
            terms: Vec::new(),
            ranges: Vec::new(),
            cuts: Vec::new(),
            scales: Vec::new(),
            radial: Vec::new(),
            gballs: Vec::new(),
            dballs: Vec::new(),
        })
    }

    /// D_e.
    pub fn de(&self) -> f64 {
        self.de
    }

    /// The culling threshold τ.
    pub fn tau(&self) -> f64 {
        self.tau
    }

    /// The groups.
    pub fn groups(&self) -> &[Group] {
        &self.groups
    }

    /// The terms of eq. (7).
    pub fn terms(&self) -> &[Term] {
        &self.terms
    }

    /// Appends a group (its incorporated groups must be earlier) and returns its index.
    pub fn add_group(&mut self, group: Group) -> Result<usize, DsmError> {
        let k = self.groups.len();
        check_group(k, &group)?;
        self.groups.push(group);
        self.ranges.push(Vec::new());
        self.cuts.push(Vec::new());
        self.scales.push(0.0);
        self.radial.push(Vec::new());
        self.gballs.push(Vec::new());
        self.dballs.push(Vec::new());
        self.refresh(k);
        Ok(k)
    }

    /// Replaces group k (same rules as [`Self::add_group`]); on error nothing changes.
    pub fn set_group(&mut self, k: usize, group: Group) -> Result<(), DsmError> {
        if k >= self.groups.len() {
            return Err(DsmError::BadGroup { group: k, other: k });
        }
        check_group(k, &group)?;
        self.groups[k] = group;
        self.refresh(k);
        Ok(())
    }

    /// Moves density primitive i of group k to `prim` (a drag); on error nothing changes.
    pub fn set_density(
        &mut self,
        k: usize,
        i: usize,
        prim: DensityPrimitive,
    ) -> Result<(), DsmError> {
        if k >= self.groups.len() || i >= self.groups[k].density.len() {
            return Err(DsmError::BadGroup { group: k, other: i });
        }
        self.groups[k].density[i] = prim;
        self.refresh(k);
        Ok(())
    }

    /// Adds a term of eq. (7).
    pub fn add_term(&mut self, groups: Vec<usize>, sign: Sign) -> Result<(), DsmError> {
        if groups.is_empty() {
            return Err(DsmError::BadParameter {
                name: "term groups",
                value: 0.0,
                why: "a term needs a group",
            });
        }
        for &g in &groups {
            if g >= self.groups.len() {
                return Err(DsmError::BadGroup {
                    group: self.terms.len(),
                    other: g,
                });
            }
        }
        self.terms.push(Term { groups, sign });
        Ok(())
    }

    /// Adds a group and a term adding its solid to the object.
    pub fn add(&mut self, group: Group) -> Result<usize, DsmError> {
        let k = self.add_group(group)?;
        self.add_term(vec![k], Sign::Add)?;
        Ok(k)
    }

    fn refresh(&mut self, k: usize) {
        let g = &self.groups[k];
        self.ranges[k] = g
            .density
            .iter()
            .map(|d| d.effective_range(self.de, self.tau))
            .collect();
        self.cuts[k] = g.density.iter().map(|d| d.has_cuts()).collect();
        self.scales[k] = g.density.iter().map(|d| d.reducing).fold(0.0, f64::max);
        self.radial[k] = g.density.iter().map(|d| d.radial_charge()).collect();
        self.gballs[k] = g.geometric.iter().map(|gp| gp.bounds()).collect();
        self.dballs[k] = g
            .density
            .iter()
            .zip(&self.ranges[k])
            .map(|(d, &r)| d.influence_ball(r))
            .collect();
    }

    /// Whether geometric primitive j of group k reaches p with reach margin
    /// `margin` (p in its bounding ball grown by `margin`): outside the ball
    /// it is not inside, and beyond the margin it is no piece of Φ.
    fn geometric_reaches(&self, k: usize, j: usize, p: DVec3, margin: f64) -> bool {
        within(self.gballs[k][j], p, margin)
    }

    /// Whether density primitive i of group k reaches p with reach margin
    /// `margin` (p in its influence ball grown by `margin`): outside the
    /// ball F = 0, and beyond the margin its cuts are no pieces of Φ.
    fn density_reaches(&self, k: usize, i: usize, p: DVec3, margin: f64) -> bool {
        within(self.dballs[k][i], p, margin)
    }

    /// Group k's largest reducing factor: the scale of Φ's density-sum terms
    /// ([`Self::sample`]), so a change of it changes Φ wherever the group's
    /// density primitives reach.
    pub fn scale(&self, k: usize) -> f64 {
        self.scales[k]
    }

    /// The effective influence range of density primitive i of group k.
    pub fn range(&self, k: usize, i: usize) -> f64 {
        self.ranges[k][i]
    }

    /// Every primitive active.
    pub fn all_active(&self) -> Active {
        Active {
            geometric: self
                .groups
                .iter()
                .map(|g| (0..g.geometric.len() as u32).collect())
                .collect(),
            density: self
                .groups
                .iter()
                .map(|g| (0..g.density.len() as u32).collect())
                .collect(),
        }
    }

    /// The primitives of `parent` that may be non-zero in the ball (c, r).
    pub fn cull(&self, parent: &Active, c: DVec3, r: f64) -> Active {
        let mut out = Active {
            geometric: Vec::with_capacity(self.groups.len()),
            density: Vec::with_capacity(self.groups.len()),
        };
        for (k, g) in self.groups.iter().enumerate() {
            out.geometric.push(
                parent.geometric[k]
                    .iter()
                    .copied()
                    .filter(|&j| {
                        let (bc, br) = g.geometric[j as usize].bounds();
                        (bc - c).length() <= br + r
                    })
                    .collect(),
            );
            out.density.push(
                parent.density[k]
                    .iter()
                    .copied()
                    .filter(|&i| {
                        let (bc, br) =
                            g.density[i as usize].influence_ball(self.ranges[k][i as usize]);
                        (bc - c).length() <= br + r
                    })
                    .collect(),
            );
        }
        out
    }

    /// Group k's density sum f_k at p (all its primitives, culled by range).
    pub fn density_sum(&self, k: usize, p: DVec3) -> f64 {
        self.groups[k]
            .density
            .iter()
            .enumerate()
            .map(|(i, d)| d.value(p, self.ranges[k][i]))
            .sum()
    }

    /// Group k's density sum with gradient and Hessian.
    pub fn density_jet(&self, k: usize, p: DVec3) -> super::jet::Jet {
        let mut j = super::jet::Jet::constant(0.0);
        for (i, d) in self.groups[k].density.iter().enumerate() {
            j = j.plus(d.jet(p, self.ranges[k][i]));
        }
        j
    }

    /// Q_k / D_e for every group at p (eqs. 3–6), all primitives.
    pub fn solids(&self, p: DVec3) -> Vec<bool> {
        let mut q = Vec::with_capacity(self.groups.len());
        let act = self.all_active();
        for k in 0..self.groups.len() {
            let (e, _, _) = self.group_eval(k, p, &act, &q, f64::INFINITY, None);
            q.push(e >= 0.0);
        }
        q
    }

    /// E_k of eq. (4) at p, all primitives.
    pub fn group_field(&self, k: usize, p: DVec3) -> f64 {
        let act = self.all_active();
        let mut q = Vec::with_capacity(k + 1);
        let mut e = 0.0;
        for m in 0..=k {
            let (em, _, _) = self.group_eval(m, p, &act, &q, f64::INFINITY, None);
            q.push(em >= 0.0);
            e = em;
        }
        e
    }

    /// Whether p is in S (eq. 7).
    pub fn contains(&self, p: DVec3) -> bool {
        self.object(&self.solids(p))
    }

    fn object(&self, q: &[bool]) -> bool {
        let mut total = 0i32;
        for t in &self.terms {
            if t.groups.iter().all(|&g| q[g]) {
                total += match t.sign {
                    Sign::Add => 1,
                    Sign::Subtract => -1,
                };
            }
        }
        total >= 1
    }

    /// (E_k, f_k, whether any density primitive is non-zero) with the given active set
    /// and the earlier groups' solids `q`; the pieces of Φ at p of the
    /// primitives that reach p with reach margin `margin` folded into `d`
    /// when it is given.
    fn group_eval(
        &self,
        k: usize,
        p: DVec3,
        act: &Active,
        q: &[bool],
        margin: f64,
        mut d: Option<&mut f64>,
    ) -> (f64, f64, bool) {
        let g = &self.groups[k];
        let mut f = 0.0;
        let mut any = false;
        for &i in &act.density[k] {
            let i = i as usize;
            if !self.density_reaches(k, i, p, margin) {
                continue;
            }
            // Without cuts of its own (`has_cuts`) the only cut is the
            // culling range, where F jumps by less than τ D_e: no boundary of
            // S and no piece of Φ (as in `piece_gradient`).
            let cut = d.is_some() && self.cuts[k][i];
            let (v, cd) = match self.radial[k][i] {
                Some(rc) if !cut => (rc.value(p, self.ranges[k][i]), f64::INFINITY),
                _ => g.density[i].value_and_cut(p, self.ranges[k][i], cut),
            };
            if v != 0.0 {
                any = true;
                f += v;
            }
            if let Some(d) = d.as_deref_mut()
                && cut
            {
                *d = d.min(cd);
            }
        }
        let mut count = 0i32;
        for &j in &act.geometric[k] {
            let j = j as usize;
            if !self.geometric_reaches(k, j, p, margin) {
                continue;
            }
            let gp = &g.geometric[j];
            let v = gp.value(p);
            if v >= 0.0 {
                count += if gp.negative { -1 } else { 1 };
            }
            if let Some(d) = d.as_deref_mut() {
                *d = d.min(v.abs());
            }
        }
        for &m in &g.incorporated {
            if q[m] {
                count += 1;
            }
        }
        let h = if count >= 1 { self.de } else { 0.0 };
        (f + h - self.de, f, any)
    }

    /// Membership and Φ at p with the active set `act` and reach margin
    /// `margin` (> 0); `q` is scratch.
    ///
    /// Only the primitives that reach p enter: p lies in a geometric
    /// primitive's bounding ball, or in a density primitive's influence ball,
    /// grown by `margin`. The sample is then the same for every active set
    /// that holds them: a function of p, the model and the margin alone, which
    /// [`super::incremental`] relies on. Φ is clamped to ±`margin`, so it is
    /// continuous: a piece that ends at its primitive's grown ball is at least
    /// `margin` there (the pieces are 1-Lipschitz and no closer to p than the
    /// primitive's ball). Every boundary piece within `margin` of p is in Φ.
    /// A margin of `f64::INFINITY` gives the unclamped Φ of every primitive
    /// in `act`.
    pub fn sample(&self, p: DVec3, act: &Active, margin: f64, q: &mut Vec<bool>) -> Sample {
        q.clear();
        let mut d = margin;
        for k in 0..self.groups.len() {
            let (e, f, any) = self.group_eval(k, p, act, q, margin, Some(&mut d));
            q.push(e >= 0.0);
            if any {
                let s = 1.0 / (self.scales[k] * self.de);
                d = d.min(f.abs() * s).min((f - self.de).abs() * s);
            }
        }
        let inside = self.object(q);
        if !d.is_finite() {
            d = 1e30;
        }
        Sample {
            inside,
            phi: if inside { d } else { -d },
        }
    }

    /// The unit gradient of the boundary piece nearest to p (the Hermite normal up
    /// to orientation; the caller orients it from inside to outside); like
    /// [`Self::sample`], only the primitives that reach p with reach margin
    /// `margin` enter.
    pub fn piece_gradient(&self, p: DVec3, act: &Active, margin: f64) -> DVec3 {
        let mut best = (f64::INFINITY, DVec3::ZERO);
        let mut take = |v: f64, g: DVec3| {
            if v.abs() < best.0 {
                best = (v.abs(), g);
            }
        };
        for (k, g) in self.groups.iter().enumerate() {
            for &j in &act.geometric[k] {
                if !self.geometric_reaches(k, j as usize, p, margin) {
                    continue;
                }
                let jet = g.geometric[j as usize].jet(p);
                take(jet.value, jet.grad);
            }
            let (mut f, mut fg) = (0.0, DVec3::ZERO);
            let mut any = false;
            for &i in &act.density[k] {
                if !self.density_reaches(k, i as usize, p, margin) {
                    continue;
                }
                let dp = &g.density[i as usize];
                let r = self.ranges[k][i as usize];
                if self.cuts[k][i as usize] {
                    let (cd, cg) = dp.cut_distance(p, r);
                    take(cd, cg);
                }
                let (v, vg) = match self.radial[k][i as usize] {
                    Some(rc) => rc.value_grad(p, r),
                    None => dp.value_grad(p, r),
                };
                if v != 0.0 {
                    any = true;
                    f += v;
                    fg += vg;
                }
            }
            if any {
                let s = 1.0 / (self.scales[k] * self.de);
                take(f * s, fg * s);
                take((f - self.de) * s, fg * s);
            }
        }
        best.1.normalize_or_zero()
    }

    /// Three-valued membership of S over the ball (c, r).
    pub fn classify(&self, c: DVec3, r: f64, act: &Active) -> Tri {
        let mut q: Vec<Tri> = Vec::with_capacity(self.groups.len());
        for (k, g) in self.groups.iter().enumerate() {
            let mut f = Interval::point(0.0);
            for &i in &act.density[k] {
                f = f.plus(g.density[i as usize].bound(c, r, self.ranges[k][i as usize]));
            }
            let mut count = Interval::point(0.0);
            for &j in &act.geometric[k] {
                let gp = &g.geometric[j as usize];
                let v = gp.value(c);
                let t = if v - r >= 0.0 {
                    Tri::Yes
                } else if v + r < 0.0 {
                    Tri::No
                } else {
                    Tri::Maybe
                };
                let ind = t.indicator();
                count = count.plus(if gp.negative { ind.scale(-1.0) } else { ind });
            }
            for &m in &g.incorporated {
                count = count.plus(q[m].indicator());
            }
            let h = count.at_least(1.0).indicator().scale(self.de);
            let e = f.plus(h).plus(Interval::point(-self.de));
            q.push(e.at_least(0.0));
        }
        let mut total = Interval::point(0.0);
        for t in &self.terms {
            let mut prod = Interval::point(1.0);
            for &g in &t.groups {
                prod = prod.mul_nonneg(q[g].indicator());
            }
            total = total.plus(match t.sign {
                Sign::Add => prod,
                Sign::Subtract => prod.scale(-1.0),
            });
        }
        total.at_least(1.0)
    }

    /// An axis-aligned box (lo, hi) containing S: every positive geometric primitive's
    /// ball and, for a positive density primitive in a group of n of them, the ball
    /// where it alone exceeds D_e / n (outside all of them f < D_e).
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let mut grow = |c: DVec3, r: f64| {
            lo = lo.min(c - r);
            hi = hi.max(c + r);
        };
        for (k, g) in self.groups.iter().enumerate() {
            for gp in g.geometric.iter().filter(|gp| !gp.negative) {
                let (c, r) = gp.bounds();
                grow(c, r);
            }
            let n = g.density.iter().filter(|d| d.density > 0.0).count().max(1) as f64;
            for (i, d) in g.density.iter().enumerate() {
                if d.density <= 0.0 {
                    continue;
                }
                let reach = d
                    .effective_range(self.de / n, 1.0 - 1e-12)
                    .min(self.ranges[k][i]);
                let (c, r) = d.influence_ball(reach);
                grow(c, r);
            }
        }
        if lo.is_finite() && hi.is_finite() {
            Some((lo, hi))
        } else {
            None
        }
    }
}

/// Whether p lies in the ball (c, r) grown by `margin` (∞: everywhere).
fn within((c, r): (DVec3, f64), p: DVec3, margin: f64) -> bool {
    let r = r + margin;
    (p - c).length_squared() <= r * r
}

fn check_group(k: usize, g: &Group) -> Result<(), DsmError> {
    for &m in &g.incorporated {
        if m >= k {
            return Err(DsmError::BadGroup { group: k, other: m });
        }
    }
    Ok(())
}
