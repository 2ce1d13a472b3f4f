//! Geometric primitives (paper §2.1, eq. 2): solids of uniform density D_e inside
//! and 0 outside — rectangular solid, cylinder, sphere, ellipsoid and one-sheet
//! hyperboloid of revolution — each with a sign (a negative primitive carries −D_e
//! and removes what it covers in eq. (3)'s sum) and a rigid placement.
//!
//! Each shape is described by a boundary function g(q) of its local coordinates,
//! g ≥ 0 inside, with analytic gradient and Hessian. Every g is 1-Lipschitz (an exact
//! signed distance for box, cylinder and sphere; scaled for ellipsoid and
//! hyperboloid), so |g| never exceeds the distance to the boundary — the mesher's
//! interval bounds rely on this.

use super::error::{DsmError, positive};
use super::jet::Jet;
use super::placement::Placement;
use glam::{DMat3, DVec3};

/// The shape of a geometric primitive, in its local frame (centred at the origin,
/// axis of revolution along local z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GeometricShape {
    /// Rectangular solid with half extents along local x, y, z.
    Box {
        /// Half extents (all > 0).
        half: DVec3,
    },
    /// Capped circular cylinder.
    Cylinder {
        /// Radius.
        radius: f64,
        /// Half height along local z.
        half_height: f64,
    },
    /// Sphere.
    Sphere {
        /// Radius.
        radius: f64,
    },
    /// Ellipsoid with semi-axes along local x, y, z.
    Ellipsoid {
        /// Semi-axes (all > 0).
        semi: DVec3,
    },
    /// One-sheet hyperboloid of revolution ρ² / a² − z² / c² ≤ 1, cut at |z| ≤ half_height.
    Hyperboloid {
        /// Waist radius a.
        waist: f64,
        /// Shape parameter c (the asymptotes' slope is a / c).
        c: f64,
        /// Half height of the cut.
        half_height: f64,
    },
}

/// A geometric primitive: a shape, a placement and a sign.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeometricPrimitive {
    /// The shape.
    pub shape: GeometricShape,
    /// Where it is.
    pub placement: Placement,
    /// A negative primitive contributes −D_e to eq. (3)'s sum.
    pub negative: bool,
}

impl GeometricPrimitive {
    /// A positive primitive, validated (every size finite and > 0).
    pub fn new(shape: GeometricShape, placement: Placement) -> Result<Self, DsmError> {
        match shape {
            GeometricShape::Box { half } | GeometricShape::Ellipsoid { semi: half } => {
                positive("half extent x", half.x)?;
                positive("half extent y", half.y)?;
                positive("half extent z", half.z)?;
            }
            GeometricShape::Cylinder {
                radius,
                half_height,
            } => {
                positive("radius", radius)?;
                positive("half height", half_height)?;
            }
            GeometricShape::Sphere { radius } => {
                positive("radius", radius)?;
            }
            GeometricShape::Hyperboloid {
                waist,
                c,
                half_height,
            } => {
                positive("waist", waist)?;
                positive("c", c)?;
                positive("half height", half_height)?;
            }
        }
        Ok(Self {
            shape,
            placement,
            negative: false,
        })
    }

    /// The same primitive with negative density (−D_e).
    pub fn negated(mut self) -> Self {
        self.negative = !self.negative;
        self
    }

    /// The boundary function g at a world point (value only): ≥ 0 inside.
    pub fn value(&self, p: DVec3) -> f64 {
        self.shape.value(self.placement.to_local(p))
    }

    /// g with its world gradient and Hessian.
    pub fn jet(&self, p: DVec3) -> Jet {
        self.shape
            .jet(self.placement.to_local(p))
            .rotate(&self.placement.rotation())
    }

    /// Whether a world point is inside (g ≥ 0).
    pub fn contains(&self, p: DVec3) -> bool {
        self.value(p) >= 0.0
    }

    /// A ball (centre, radius) containing the primitive.
    pub fn bounds(&self) -> (DVec3, f64) {
        (self.placement.translation(), self.shape.bounding_radius())
    }
}

/// A jet of a function of (ρ, z) (ρ the distance from the local z axis), lifted to 3-D.
/// `d` = (g_ρ, g_z), `h` = (g_ρρ, g_ρz, g_zz).
fn lift_revolution(q: DVec3, value: f64, d: (f64, f64), h: (f64, f64, f64)) -> Jet {
    let rho = Jet::radial(q);
    let ez = DVec3::Z;
    let gr = rho.grad;
    let o = |a: DVec3, b: DVec3| DMat3::from_cols(a * b.x, a * b.y, a * b.z);
    Jet {
        value,
        grad: gr * d.0 + ez * d.1,
        hess: o(gr, gr) * h.0 + (o(gr, ez) + o(ez, gr)) * h.1 + o(ez, ez) * h.2 + rho.hess * d.0,
    }
}

/// 2-D signed-distance jet of the rectangle |ρ| ≤ a, |z| ≤ b in the (ρ, z) half plane,
/// negated (≥ 0 inside): returns (value, (g_ρ, g_z), (g_ρρ, g_ρz, g_zz)).
fn capped_profile(rho: f64, z: f64, a: f64, b: f64) -> (f64, (f64, f64), (f64, f64, f64)) {
    let sz = if z < 0.0 { -1.0 } else { 1.0 };
    let dx = rho - a;
    let dz = z.abs() - b;
    if dx > 0.0 && dz > 0.0 {
        let n = (dx * dx + dz * dz).sqrt();
        let (ux, uz) = (dx / n, dz / n);
        // sdf = n; g = −n; ∇n = (ux, sz·uz); ∇²n = (I − ûûᵀ)/n in (ρ, |z|).
        let hxx = (1.0 - ux * ux) / n;
        let hxz = -ux * uz / n * sz;
        let hzz = (1.0 - uz * uz) / n;
        (-n, (-ux, -uz * sz), (-hxx, -hxz, -hzz))
    } else if dx >= dz {
        (-dx, (-1.0, 0.0), (0.0, 0.0, 0.0))
    } else {
        (-dz, (0.0, -sz), (0.0, 0.0, 0.0))
    }
}

impl GeometricShape {
    /// A radius of a ball about the local origin that contains the shape.
    pub fn bounding_radius(&self) -> f64 {
        match *self {
            GeometricShape::Box { half } => half.length(),
            GeometricShape::Cylinder {
                radius,
                half_height,
            } => radius.hypot(half_height),
            GeometricShape::Sphere { radius } => radius,
            GeometricShape::Ellipsoid { semi } => semi.max_element(),
            GeometricShape::Hyperboloid {
                waist,
                c,
                half_height,
            } => (waist * (1.0 + (half_height / c).powi(2)).sqrt()).hypot(half_height),
        }
    }

    /// g(q), ≥ 0 inside, 1-Lipschitz.
    pub fn value(&self, q: DVec3) -> f64 {
        match *self {
            GeometricShape::Box { half } => {
                let d = q.abs() - half;
                -(d.max(DVec3::ZERO).length() + d.max_element().min(0.0))
            }
            GeometricShape::Sphere { radius } => radius - q.length(),
            _ => self.jet(q).value,
        }
    }

    /// g(q) with its local gradient and Hessian.
    pub fn jet(&self, q: DVec3) -> Jet {
        match *self {
            GeometricShape::Sphere { radius } => Jet::norm(q).scale(-1.0).add_constant(radius),
            GeometricShape::Ellipsoid { semi } => {
                // g = m (1 − |q ⊘ s|), m = min semi-axis: 1-Lipschitz since |∇|q⊘s|| ≤ 1/m.
                let m = semi.min_element();
                let inv = DVec3::ONE / semi;
                let w = q * inv;
                let n = Jet::norm(w);
                let s = DMat3::from_diagonal(inv);
                Jet {
                    value: m * (1.0 - n.value),
                    grad: s * n.grad * -m,
                    hess: s * n.hess * s * -m,
                }
            }
            GeometricShape::Box { half } => {
                let s = q.signum();
                let d = q.abs() - half;
                let w = d.max(DVec3::ZERO);
                let n = w.length();
                if n > 0.0 {
                    // Outside: sdf = |w| over the active components.
                    let u = w / n;
                    let act = DVec3::new(
                        (w.x > 0.0) as u8 as f64,
                        (w.y > 0.0) as u8 as f64,
                        (w.z > 0.0) as u8 as f64,
                    );
                    let su = u * s;
                    let a = DMat3::from_diagonal(act);
                    let hess = (a - DMat3::from_cols(su * su.x, su * su.y, su * su.z)) * (1.0 / n);
                    Jet {
                        value: -n,
                        grad: -su,
                        hess: hess * -1.0,
                    }
                } else {
                    // Inside: g = −max component of d.
                    let i = if d.x >= d.y && d.x >= d.z {
                        0
                    } else if d.y >= d.z {
                        1
                    } else {
                        2
                    };
                    let mut grad = DVec3::ZERO;
                    grad[i] = -s[i];
                    Jet {
                        value: -d[i],
                        grad,
                        hess: DMat3::ZERO,
                    }
                }
            }
            GeometricShape::Cylinder {
                radius,
                half_height,
            } => {
                let rho = (q.x * q.x + q.y * q.y).sqrt();
                let (v, d, h) = capped_profile(rho, q.z, radius, half_height);
                lift_revolution(q, v, d, h)
            }
            GeometricShape::Hyperboloid {
                waist,
                c,
                half_height,
            } => {
                let rho = (q.x * q.x + q.y * q.y).sqrt();
                let a2c2 = (waist / c).powi(2);
                let k = 1.0 / (1.0 + a2c2).sqrt();
                let w = waist * (1.0 + (q.z / c).powi(2)).sqrt();
                let side = k * (w - rho);
                let cap = half_height - q.z.abs();
                if side <= cap {
                    // w' = a² z / (c² w), w'' = (a² / (c² w)) (1 − z w' / w).
                    let w1 = a2c2 * q.z / w;
                    let w2 = a2c2 / w * (1.0 - q.z * w1 / w);
                    lift_revolution(q, side, (-k, k * w1), (0.0, 0.0, k * w2))
                } else {
                    let sz = if q.z < 0.0 { -1.0 } else { 1.0 };
                    lift_revolution(q, cap, (0.0, -sz), (0.0, 0.0, 0.0))
                }
            }
        }
    }
}
