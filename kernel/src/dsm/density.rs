//! Density primitives (paper §2.1, eq. 1): F = D · exp(−a · r), r the distance from
//! the primitive's reference plane, line or point, with positive or negative D —
//! plane-based, pipe-based and sphere-based primitives (the spatial charge
//! models), the blobby primitive, and a plane-based sheet bent onto a cylinder
//! (shape mapping, §4). Each has analytic gradient and Hessian, a rigid placement,
//! an influence range outside which it is considered 0, and optional clipping
//! half-spaces ("part of a pipe", "part of a ball").
//!
//! Choices the paper leaves open, made here:
//! * Sphere- and pipe-based primitives take a reference radius ρ₀ ≥ 0: r = |q| − ρ₀
//!   (pipe: distance from the axis − ρ₀), so ρ₀ = 0 is a point or line charge and
//!   ρ₀ > 0 a ball or tube shell. Inside the shell (r < 0) the primitive is 0 —
//!   the shell is hollow. The pipe is finite, |z| ≤ half_length, cut square.
//! * The plane-based primitive is symmetric about its reference plane: r = |h|.
//!   Its solid is the lens |h| ≤ h(u, v) of eq. (12); it is cut to a (u, v) rectangle.
//!   Its D(u, v) is a [`Distribution`] and its reducing factor a / s(u, v) with the
//!   connecting function s of eq. (13) (s = 1 without one), where s = 0 gives F = 0.
//! * Blobby: Blinn's Gaussian F = D exp(−a |q|²) (the paper names it, not its formula).
//! * Shape mapping onto a cylinder of radius R: (u, v, r) = (R θ, z, |ρ − R|).
//! * Influence range: F is 0 where r > range. `range` is infinite unless set; the
//!   model then culls at τ (r where |D| e^{−a r} = τ D_e), see [`super::model`].

use super::connect::Connecting;
use super::distribution::Distribution;
use super::error::{DsmError, finite, positive};
use super::interval::Interval;
use super::jet::{Jet, Jet2};
use super::placement::Placement;
use glam::{DVec2, DVec3};

/// A half-space n · q ≤ d in the primitive's local frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfSpace {
    /// Unit normal (pointing out of the kept side).
    pub normal: DVec3,
    /// Offset.
    pub offset: f64,
}

impl HalfSpace {
    /// n · q ≤ d with n normalised (n ≠ 0).
    pub fn new(normal: DVec3, offset: f64) -> Result<Self, DsmError> {
        let n = normal.try_normalize().ok_or(DsmError::BadParameter {
            name: "half-space normal",
            value: 0.0,
            why: "must be non-zero",
        })?;
        finite("half-space offset", offset)?;
        Ok(Self {
            normal: n,
            offset: offset / normal.length(),
        })
    }
}

/// A density distribution sheet: D(u, v) over a (u, v) rectangle, with an optional
/// connecting function.
#[derive(Clone, Debug, PartialEq)]
pub struct Sheet {
    /// D(u, v).
    pub distribution: Distribution,
    /// Lower corner of the (u, v) rectangle.
    pub lo: DVec2,
    /// Upper corner.
    pub hi: DVec2,
    /// s(u, v) of eq. (13), if any.
    pub connect: Option<Connecting>,
}

/// The kind of density primitive and its reference geometry.
#[derive(Clone, Debug, PartialEq)]
pub enum DensityShape {
    /// Sphere-based: reference point (radius 0) or ball shell of that radius.
    Sphere {
        /// Reference radius ρ₀ ≥ 0.
        radius: f64,
    },
    /// Pipe-based: reference segment of local z (radius 0) or a tube shell.
    Pipe {
        /// Reference radius ρ₀ ≥ 0.
        radius: f64,
        /// Half length along local z.
        half_length: f64,
    },
    /// Blobby (Gaussian) about the local origin.
    Blobby,
    /// Plane-based on the local z = 0 plane, (u, v) = (x, y).
    Plane(Box<Sheet>),
    /// A plane-based sheet mapped onto the cylinder ρ = radius about local z.
    CylinderMap {
        /// Cylinder radius R.
        radius: f64,
        /// The mapped sheet, u = R θ (θ ∈ (−π, π]), v = z.
        sheet: Box<Sheet>,
    },
}

/// A density primitive F = D exp(−a r) placed in space.
#[derive(Clone, Debug, PartialEq)]
pub struct DensityPrimitive {
    /// Kind and reference geometry.
    pub shape: DensityShape,
    /// Placement.
    pub placement: Placement,
    /// D (sheets: a factor on D(u, v)); negative removes density.
    pub density: f64,
    /// Reducing factor a > 0.
    pub reducing: f64,
    /// Influence range in r (F = 0 beyond); infinite = culled by the model's τ.
    pub range: f64,
    /// Kept half-spaces (local); F = 0 outside any.
    pub clip: Vec<HalfSpace>,
}

/// A sphere-based or blobby primitive without clipping, reduced to what its
/// value needs: F depends on |p − centre| alone, so no transform to local
/// coordinates and no support tests beyond the range (the mesher's hot loop,
/// [`super::model::Model::sample`]). Equal to [`DensityPrimitive::value`] to
/// rounding (bit for bit with an identity rotation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RadialCharge {
    centre: DVec3,
    /// Reference radius ρ₀ (0 for blobby).
    radius: f64,
    density: f64,
    reducing: f64,
    /// Blinn's Gaussian e^{−a r²} instead of e^{−a r}.
    gaussian: bool,
}

impl RadialCharge {
    /// F at p with influence range `range`.
    #[inline]
    pub(crate) fn value(&self, p: DVec3, range: f64) -> f64 {
        let r = (p - self.centre).length() - self.radius;
        if !(r >= 0.0 && r <= range) {
            return 0.0;
        }
        // The same operations, in the same order, as `value_at`.
        let x = if self.gaussian {
            -self.reducing * r * r
        } else {
            -self.reducing * r
        };
        self.density * x.exp()
    }

    /// F and its world gradient at p ([`DensityPrimitive::value_grad`] to
    /// rounding).
    #[inline]
    pub(crate) fn value_grad(&self, p: DVec3, range: f64) -> (f64, DVec3) {
        let d = p - self.centre;
        let n = d.length();
        let v = self.value(p, range);
        if v == 0.0 {
            return (0.0, DVec3::ZERO);
        }
        let g = if self.gaussian {
            d * (-2.0 * self.reducing * v)
        } else if n > 0.0 {
            d * (-self.reducing * v / n)
        } else {
            DVec3::ZERO
        };
        (v, g)
    }
}

/// Local distance r, its jet, and whether the point is inside the support.
struct Local {
    q: DVec3,
    r: f64,
}

impl DensityPrimitive {
    /// A primitive with the given shape, density D and reducing factor a.
    pub fn new(
        shape: DensityShape,
        placement: Placement,
        density: f64,
        reducing: f64,
    ) -> Result<Self, DsmError> {
        finite("density", density)?;
        positive("reducing factor", reducing)?;
        match &shape {
            DensityShape::Sphere { radius } => {
                if !(radius.is_finite() && *radius >= 0.0) {
                    return Err(DsmError::BadParameter {
                        name: "reference radius",
                        value: *radius,
                        why: "must be finite and >= 0",
                    });
                }
            }
            DensityShape::Pipe {
                radius,
                half_length,
            } => {
                if !(radius.is_finite() && *radius >= 0.0) {
                    return Err(DsmError::BadParameter {
                        name: "reference radius",
                        value: *radius,
                        why: "must be finite and >= 0",
                    });
                }
                positive("half length", *half_length)?;
            }
            DensityShape::Blobby => {}
            DensityShape::Plane(s) => check_sheet(s)?,
            DensityShape::CylinderMap { radius, sheet } => {
                positive("cylinder radius", *radius)?;
                check_sheet(sheet)?;
                if sheet.lo.x <= -std::f64::consts::PI * radius
                    || sheet.hi.x > std::f64::consts::PI * radius
                {
                    return Err(DsmError::BadParameter {
                        name: "mapped u extent",
                        value: sheet.hi.x,
                        why: "must lie within (−πR, πR]",
                    });
                }
            }
        }
        Ok(Self {
            shape,
            placement,
            density,
            reducing,
            range: f64::INFINITY,
            clip: Vec::new(),
        })
    }

    /// A sphere-based primitive about `centre`.
    pub fn sphere(centre: DVec3, density: f64, reducing: f64) -> Result<Self, DsmError> {
        Self::new(
            DensityShape::Sphere { radius: 0.0 },
            Placement::at(centre),
            density,
            reducing,
        )
    }

    /// A pipe-based primitive on the segment a → b.
    pub fn pipe(a: DVec3, b: DVec3, density: f64, reducing: f64) -> Result<Self, DsmError> {
        let half_length = (b - a).length() * 0.5;
        Self::new(
            DensityShape::Pipe {
                radius: 0.0,
                half_length,
            },
            Placement::with_axis((a + b) * 0.5, b - a)?,
            density,
            reducing,
        )
    }

    /// A blobby primitive about `centre`.
    pub fn blobby(centre: DVec3, density: f64, reducing: f64) -> Result<Self, DsmError> {
        Self::new(
            DensityShape::Blobby,
            Placement::at(centre),
            density,
            reducing,
        )
    }

    /// A plane-based primitive with reference plane z = 0 of `placement`.
    pub fn plane(sheet: Sheet, placement: Placement, reducing: f64) -> Result<Self, DsmError> {
        Self::new(
            DensityShape::Plane(Box::new(sheet)),
            placement,
            1.0,
            reducing,
        )
    }

    /// With an explicit influence range (> 0).
    pub fn with_range(mut self, range: f64) -> Result<Self, DsmError> {
        self.range = positive("influence range", range)?;
        Ok(self)
    }

    /// With one more kept half-space (local frame).
    pub fn clipped(mut self, h: HalfSpace) -> Self {
        self.clip.push(h);
        self
    }

    /// The influence range with the model's culling threshold τ·D_e applied: beyond
    /// it |F| < τ D_e everywhere (for sheets, with s ≤ 1).
    pub fn effective_range(&self, de: f64, tau: f64) -> f64 {
        let dmax = match &self.shape {
            DensityShape::Plane(s) | DensityShape::CylinderMap { sheet: s, .. } => {
                self.density.abs() * s.distribution.max_abs()
            }
            _ => self.density.abs(),
        };
        let l = (dmax / (tau * de)).ln().max(0.0);
        let cull = match self.shape {
            DensityShape::Blobby => (l / self.reducing).sqrt(),
            _ => l / self.reducing,
        };
        cull.min(self.range)
    }

    /// The primitive as a [`RadialCharge`] when it is one (sphere-based or
    /// blobby, no clip half-spaces).
    pub(crate) fn radial_charge(&self) -> Option<RadialCharge> {
        if !self.clip.is_empty() {
            return None;
        }
        let (radius, gaussian) = match self.shape {
            DensityShape::Sphere { radius } => (radius, false),
            DensityShape::Blobby => (0.0, true),
            _ => return None,
        };
        Some(RadialCharge {
            centre: self.placement.translation(),
            radius,
            density: self.density,
            reducing: self.reducing,
            gaussian,
        })
    }

    fn local(&self, p: DVec3) -> Local {
        let q = self.placement.to_local(p);
        let r = match &self.shape {
            DensityShape::Sphere { radius } => q.length() - radius,
            DensityShape::Pipe { radius, .. } => (q.x * q.x + q.y * q.y).sqrt() - radius,
            DensityShape::Blobby => q.length(),
            DensityShape::Plane(_) => q.z.abs(),
            DensityShape::CylinderMap { radius, .. } => {
                ((q.x * q.x + q.y * q.y).sqrt() - radius).abs()
            }
        };
        Local { q, r }
    }

    fn sheet_uv(&self, q: DVec3) -> Option<(&Sheet, DVec2)> {
        match &self.shape {
            DensityShape::Plane(s) => Some((s, DVec2::new(q.x, q.y))),
            DensityShape::CylinderMap { radius, sheet } => {
                Some((sheet, DVec2::new(radius * q.y.atan2(q.x), q.z)))
            }
            _ => None,
        }
    }

    fn in_support(&self, l: &Local, range: f64) -> bool {
        if !(l.r >= 0.0 && l.r <= range) {
            return false;
        }
        if self.clip.iter().any(|h| h.normal.dot(l.q) > h.offset) {
            return false;
        }
        match &self.shape {
            DensityShape::Pipe { half_length, .. } => l.q.z.abs() <= *half_length,
            _ => match self.sheet_uv(l.q) {
                Some((s, uv)) => uv.cmpge(s.lo).all() && uv.cmple(s.hi).all(),
                None => true,
            },
        }
    }

    /// F at a world point, with influence range `range` (see [`Self::effective_range`]).
    pub fn value(&self, p: DVec3, range: f64) -> f64 {
        self.value_at(&self.local(p), range)
    }

    /// F and, when `cut`, the distance of [`Self::cut_distance`] (without its
    /// gradient; +∞ when not asked), from one transform of `p` to local
    /// coordinates: what a sample of the mesher needs. Equal, bit for bit, to
    /// the two separate calls.
    pub fn value_and_cut(&self, p: DVec3, range: f64, cut: bool) -> (f64, f64) {
        let l = self.local(p);
        let mut best = f64::INFINITY;
        if cut {
            self.cuts(&l, range, |d, _| best = best.min(d.abs()));
        }
        (self.value_at(&l, range), best)
    }

    /// F at the local point `l`.
    fn value_at(&self, l: &Local, range: f64) -> f64 {
        if !self.in_support(l, range) {
            return 0.0;
        }
        match &self.shape {
            DensityShape::Blobby => self.density * (-self.reducing * l.r * l.r).exp(),
            DensityShape::Plane(_) | DensityShape::CylinderMap { .. } => {
                let (s, uv) = self.sheet_uv(l.q).expect("sheet");
                let sc = s.connect.as_ref().map_or(1.0, |c| c.value(uv));
                if sc <= 0.0 {
                    return 0.0;
                }
                self.density * s.distribution.value(uv) * (-self.reducing * l.r / sc).exp()
            }
            _ => self.density * (-self.reducing * l.r).exp(),
        }
    }

    /// F with its world gradient and Hessian (zero outside the support; the cusp
    /// of exp(−a r) at r = 0 is reported with the one-sided derivatives).
    pub fn jet(&self, p: DVec3, range: f64) -> Jet {
        let l = self.local(p);
        if !self.in_support(&l, range) {
            return Jet::constant(0.0);
        }
        let q = l.q;
        let a = self.reducing;
        let local = match &self.shape {
            DensityShape::Sphere { radius } => Jet::norm(q)
                .add_constant(-radius)
                .scale(a)
                .exp_neg()
                .scale(self.density),
            DensityShape::Pipe { radius, .. } => Jet::radial(q)
                .add_constant(-radius)
                .scale(a)
                .exp_neg()
                .scale(self.density),
            DensityShape::Blobby => {
                let e = Jet {
                    value: a * q.length_squared(),
                    grad: q * (2.0 * a),
                    hess: glam::DMat3::IDENTITY * (2.0 * a),
                };
                e.exp_neg().scale(self.density)
            }
            DensityShape::Plane(s) => {
                let u = Jet::linear(DVec3::X, q.x);
                let v = Jet::linear(DVec3::Y, q.y);
                let r = Jet::linear(DVec3::Z, q.z).abs();
                sheet_jet(s, u, v, r, a, self.density)
            }
            DensityShape::CylinderMap { radius, sheet } => {
                let rho = Jet::radial(q);
                let rr = rho.value;
                // θ = atan2(y, x): ∇θ = (−y, x, 0)/ρ², ∇²θ from differentiating that.
                let (x, y) = (q.x, q.y);
                let r4 = rr.powi(4);
                let theta = Jet {
                    value: y.atan2(x),
                    grad: DVec3::new(-y, x, 0.0) / (rr * rr),
                    hess: glam::DMat3::from_cols(
                        DVec3::new(2.0 * x * y, y * y - x * x, 0.0) / r4,
                        DVec3::new(y * y - x * x, -2.0 * x * y, 0.0) / r4,
                        DVec3::ZERO,
                    ),
                };
                let u = theta.scale(*radius);
                let v = Jet::linear(DVec3::Z, q.z);
                let r = rho.add_constant(-radius).abs();
                sheet_jet(sheet, u, v, r, a, self.density)
            }
        };
        local.rotate(&self.placement.rotation())
    }

    /// F with its world gradient, without the Hessian of [`Self::jet`]: what
    /// the mesher's normals need. Sphere-, pipe-based and blobby primitives
    /// differentiate e^{−a r} directly (equal to the jet's value and gradient
    /// to rounding); sheets take the jet's.
    pub fn value_grad(&self, p: DVec3, range: f64) -> (f64, DVec3) {
        let l = self.local(p);
        if !self.in_support(&l, range) {
            return (0.0, DVec3::ZERO);
        }
        let q = l.q;
        let a = self.reducing;
        let (v, g) = match &self.shape {
            DensityShape::Sphere { .. } => {
                let n = q.length();
                let u = if n == 0.0 { DVec3::ZERO } else { q / n };
                let v = self.density * (-a * l.r).exp();
                (v, u * (-a * v))
            }
            DensityShape::Pipe { .. } => {
                let n = (q.x * q.x + q.y * q.y).sqrt();
                let u = if n == 0.0 {
                    DVec3::ZERO
                } else {
                    DVec3::new(q.x / n, q.y / n, 0.0)
                };
                let v = self.density * (-a * l.r).exp();
                (v, u * (-a * v))
            }
            DensityShape::Blobby => {
                let v = self.density * (-a * l.r * l.r).exp();
                (v, q * (-2.0 * a * v))
            }
            _ => {
                let j = self.jet(p, range);
                return (j.value, j.grad);
            }
        };
        (v, self.placement.rotation() * g)
    }

    /// Distance (a 1-Lipschitz lower bound, exact for planes) from `p` to the
    /// nearest boundary of the support (range surface, shell bore, clip planes,
    /// pipe ends, sheet edges) and the unit gradient of that distance function.
    pub fn cut_distance(&self, p: DVec3, range: f64) -> (f64, DVec3) {
        let l = self.local(p);
        let mut best = (f64::INFINITY, DVec3::ZERO);
        self.cuts(&l, range, |d, g| {
            if d.abs() < best.0 {
                let g = g();
                best = (d.abs(), if d < 0.0 { -g } else { g });
            }
        });
        (best.0, self.placement.rotation() * best.1)
    }

    /// Every boundary of the support at the local point `l`: `take(d, g)`
    /// with the signed distance d to it and g, the local gradient of d,
    /// computed only when called.
    fn cuts(&self, l: &Local, range: f64, mut take: impl FnMut(f64, &dyn Fn() -> DVec3)) {
        let q = l.q;
        let rgrad = || match &self.shape {
            DensityShape::Sphere { .. } | DensityShape::Blobby => q.normalize_or_zero(),
            DensityShape::Pipe { .. } => DVec3::new(q.x, q.y, 0.0).normalize_or_zero(),
            DensityShape::Plane(_) => DVec3::new(0.0, 0.0, q.z.signum()),
            DensityShape::CylinderMap { radius, .. } => {
                let rr = (q.x * q.x + q.y * q.y).sqrt();
                DVec3::new(q.x, q.y, 0.0).normalize_or_zero() * (rr - radius).signum()
            }
        };
        if range.is_finite() {
            take(range - l.r, &|| -rgrad());
        }
        if let DensityShape::Sphere { radius } | DensityShape::Pipe { radius, .. } = self.shape
            && radius > 0.0
        {
            take(l.r, &rgrad);
        }
        for h in &self.clip {
            take(h.offset - h.normal.dot(q), &|| -h.normal);
        }
        match &self.shape {
            DensityShape::Pipe { half_length, .. } => take(half_length - q.z.abs(), &|| {
                DVec3::new(0.0, 0.0, -q.z.signum())
            }),
            DensityShape::Plane(s) => {
                take(q.x - s.lo.x, &|| DVec3::X);
                take(s.hi.x - q.x, &|| -DVec3::X);
                take(q.y - s.lo.y, &|| DVec3::Y);
                take(s.hi.y - q.y, &|| -DVec3::Y);
            }
            DensityShape::CylinderMap { radius, sheet } => {
                let rr = (q.x * q.x + q.y * q.y).sqrt();
                let th = q.y.atan2(q.x);
                let t = || DVec3::new(-q.y, q.x, 0.0).normalize_or_zero();
                take((th - sheet.lo.x / radius) * rr, &t);
                take((sheet.hi.x / radius - th) * rr, &|| -t());
                take(q.z - sheet.lo.y, &|| DVec3::Z);
                take(sheet.hi.y - q.z, &|| -DVec3::Z);
            }
            _ => {}
        }
    }

    /// Whether the support has boundaries of its own (an explicit range, clip planes,
    /// a shell bore, pipe ends, sheet edges). Without them the only cut is the
    /// culling range, where F jumps by less than τ·D_e — not a boundary of S.
    pub fn has_cuts(&self) -> bool {
        self.range.is_finite()
            || !self.clip.is_empty()
            || match &self.shape {
                DensityShape::Sphere { radius } => *radius > 0.0,
                DensityShape::Blobby => false,
                _ => true,
            }
    }

    /// A ball (centre, radius) outside which F = 0 for influence range `range`.
    pub fn influence_ball(&self, range: f64) -> (DVec3, f64) {
        let c = self.placement.translation();
        let r = match &self.shape {
            DensityShape::Sphere { radius } => radius + range,
            DensityShape::Blobby => range,
            DensityShape::Pipe {
                radius,
                half_length,
            } => (radius + range).hypot(*half_length),
            DensityShape::Plane(s) => {
                let m = s.lo.abs().max(s.hi.abs());
                m.length().hypot(range)
            }
            DensityShape::CylinderMap { radius, sheet } => {
                (radius + range).hypot(sheet.lo.y.abs().max(sheet.hi.y.abs()))
            }
        };
        (c, r)
    }

    /// Bounds of F over the ball (centre, radius) of world space.
    pub fn bound(&self, centre: DVec3, radius: f64, range: f64) -> Interval {
        let l = self.local(centre);
        let q = l.q;
        let (rlo, rhi) = (l.r - radius, l.r + radius);
        // Support status over the ball.
        let mut out = rlo > range || rhi < 0.0;
        let mut partial = rhi > range || rlo < 0.0;
        for h in &self.clip {
            let s = h.normal.dot(q) - h.offset;
            out |= s > radius;
            partial |= s > -radius;
        }
        let mut d_bound = Interval::point(self.density);
        let mut s_lo = 1.0;
        match &self.shape {
            DensityShape::Pipe { half_length, .. } => {
                out |= q.z.abs() - radius > *half_length;
                partial |= q.z.abs() + radius > *half_length;
            }
            DensityShape::Plane(_) | DensityShape::CylinderMap { .. } => {
                let (s, uv) = self.sheet_uv(q).expect("sheet");
                // (u, v) moves by at most `ru` within the ball.
                let ru = match &self.shape {
                    DensityShape::CylinderMap { radius: cr, .. } => {
                        let rr = (q.x * q.x + q.y * q.y).sqrt();
                        if rr - radius > 0.1 * cr {
                            radius * cr / (rr - radius)
                        } else {
                            f64::INFINITY
                        }
                    }
                    _ => radius,
                };
                if ru.is_finite() {
                    out |= uv.x + ru < s.lo.x
                        || uv.x - ru > s.hi.x
                        || uv.y + ru < s.lo.y
                        || uv.y - ru > s.hi.y;
                    partial |= uv.x - ru < s.lo.x
                        || uv.x + ru > s.hi.x
                        || uv.y - ru < s.lo.y
                        || uv.y + ru > s.hi.y;
                    d_bound = s
                        .distribution
                        .bound(uv, ru * std::f64::consts::SQRT_2)
                        .scale(self.density);
                    if let Some(c) = &s.connect {
                        let sb = c.bound(uv, ru);
                        s_lo = sb.lo;
                        if sb.hi <= 0.0 {
                            out = true;
                        }
                    }
                } else {
                    partial = true;
                    let m = self.density.abs() * s.distribution.max_abs();
                    d_bound = Interval::new(-m, m);
                    s_lo = 0.0;
                }
            }
            _ => {}
        }
        if out {
            return Interval::point(0.0);
        }
        let (elo, ehi) = match self.shape {
            DensityShape::Blobby => {
                let lo = rlo.max(0.0);
                (self.reducing * lo * lo, self.reducing * rhi * rhi)
            }
            _ => {
                let lo = rlo.max(0.0);
                let hi = if s_lo > 0.0 {
                    rhi / s_lo
                } else {
                    f64::INFINITY
                };
                (self.reducing * lo, self.reducing * hi)
            }
        };
        let e = Interval::new((-ehi).exp(), (-elo).exp());
        let f = d_bound.mul_nonneg(e);
        if partial { f.with_zero() } else { f }
    }
}

fn check_sheet(s: &Sheet) -> Result<(), DsmError> {
    if !(s.lo.is_finite() && s.hi.is_finite() && s.lo.x < s.hi.x && s.lo.y < s.hi.y) {
        return Err(DsmError::BadParameter {
            name: "sheet extent",
            value: s.hi.x - s.lo.x,
            why: "lo must be below hi, finite",
        });
    }
    Ok(())
}

/// D(u, v) · exp(−a r / s(u, v)) with derivatives through the (u, v, r) maps.
fn sheet_jet(s: &Sheet, u: Jet, v: Jet, r: Jet, a: f64, density: f64) -> Jet {
    let uv = DVec2::new(u.value, v.value);
    let d = Jet::compose(s.distribution.jet(uv), u, v);
    let e = match &s.connect {
        None => r.scale(a),
        Some(c) => {
            let sj: Jet2 = c.jet(uv);
            if sj.value <= 0.0 {
                return Jet::constant(0.0);
            }
            r.times(Jet::compose(sj, u, v).recip()).scale(a)
        }
    };
    d.times(e.exp_neg()).scale(density)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A radial charge's value and gradient against the primitive's own
    /// (through its local frame): the value bit for bit at an axis-aligned
    /// placement, both to rounding when
    /// rotated; 0 inside a shell's bore and beyond the range; clipped
    /// primitives and other shapes are not radial charges.
    #[test]
    fn radial_charges_have_the_primitives_values() {
        let rot = glam::DMat3::from_axis_angle(DVec3::new(1.0, -2.0, 0.5).normalize(), 0.9);
        let placed = [
            Placement::at(DVec3::new(0.3, -0.2, 0.1)),
            Placement::new(rot, DVec3::new(-0.4, 0.7, 0.2)).unwrap(),
        ];
        for (k, pl) in placed.into_iter().enumerate() {
            let prims = [
                DensityPrimitive::new(DensityShape::Sphere { radius: 0.0 }, pl, 1.6, 1.5).unwrap(),
                DensityPrimitive::new(DensityShape::Sphere { radius: 0.5 }, pl, -0.7, 2.5).unwrap(),
                DensityPrimitive::new(DensityShape::Blobby, pl, 2.0, 0.8).unwrap(),
            ];
            for d in &prims {
                let rc = d.radial_charge().expect("radial");
                for i in 0..200 {
                    let t = i as f64 * 0.37;
                    let p = pl.translation()
                        + DVec3::new(t.sin(), (1.3 * t).cos(), (0.7 * t).sin()) * (0.02 * i as f64);
                    for range in [1.0, 3.5] {
                        let (a, b) = (rc.value(p, range), d.value(p, range));
                        if k == 0 {
                            assert_eq!(a.to_bits(), b.to_bits(), "{d:?} at {p}");
                        } else {
                            // |p − c| to rounding, which exp(−a r) scales by a r.
                            assert!((a - b).abs() <= 1e-13 * b.abs(), "{a} vs {b}");
                        }
                        let (v, g) = rc.value_grad(p, range);
                        let (w, h) = d.value_grad(p, range);
                        assert_eq!(v, a);
                        assert!((v - w).abs() <= 1e-13 * w.abs(), "{v} vs {w}");
                        assert!((g - h).length() <= 1e-12 * (1.0 + h.length()), "{g} vs {h}");
                        if (p - pl.translation()).length() > range + 0.6 {
                            assert_eq!(a, 0.0);
                        }
                    }
                }
            }
        }
        let bore = DensityPrimitive::sphere(DVec3::ZERO, 1.0, 1.0).unwrap();
        assert!(bore.radial_charge().is_some());
        let clipped = bore.clone().clipped(HalfSpace::new(DVec3::X, 0.0).unwrap());
        assert!(clipped.radial_charge().is_none());
        let pipe = DensityPrimitive::pipe(DVec3::ZERO, DVec3::X, 1.0, 1.0).unwrap();
        assert!(pipe.radial_charge().is_none());
        let shell = DensityPrimitive::new(
            DensityShape::Sphere { radius: 0.5 },
            Placement::IDENTITY,
            1.0,
            1.0,
        )
        .unwrap()
        .radial_charge()
        .unwrap();
        assert_eq!(shell.value(DVec3::new(0.2, 0.0, 0.0), 9.0), 0.0);
    }
}
