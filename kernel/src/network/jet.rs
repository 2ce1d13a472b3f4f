//! Forward-mode first derivatives over the patch domain. Every patch
//! formula is written once, generic over [`Scalar`]: with `f64` it is the
//! plain evaluation (the fast path), with [`Jet`] it carries the exact
//! gradient with respect to the domain point (x, y), so patch normals are
//! exact (no finite differences), which is what the G1 figures measure.

use std::fmt::Debug;
use std::ops::{Add, Div, Mul, Neg, Sub};

use glam::DVec3;

/// A number the patch formulas can be evaluated with.
pub trait Scalar:
    Copy
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// A constant (zero gradient).
    fn cst(x: f64) -> Self;
    /// The value.
    fn val(self) -> f64;
    /// f(self), given f and f′ at `self.val()` (the chain rule).
    fn chain(self, f: f64, df: f64) -> Self;
    /// Square root (of a positive number).
    fn sqrt(self) -> Self {
        let r = self.val().sqrt();
        self.chain(r, 0.5 / r)
    }
    /// Sine.
    fn sin(self) -> Self {
        self.chain(self.val().sin(), self.val().cos())
    }
    /// Cosine.
    fn cos(self) -> Self {
        self.chain(self.val().cos(), -self.val().sin())
    }
}

impl Scalar for f64 {
    fn cst(x: f64) -> Self {
        x
    }
    fn val(self) -> f64 {
        self
    }
    fn chain(self, f: f64, _df: f64) -> Self {
        f
    }
}

/// A value with its gradient with respect to the domain point (x, y).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Jet {
    /// The value.
    pub v: f64,
    /// ∂/∂x.
    pub dx: f64,
    /// ∂/∂y.
    pub dy: f64,
}

impl Jet {
    /// The independent variables at the domain point (x, y).
    pub fn variables(x: f64, y: f64) -> (Jet, Jet) {
        (
            Jet {
                v: x,
                dx: 1.0,
                dy: 0.0,
            },
            Jet {
                v: y,
                dx: 0.0,
                dy: 1.0,
            },
        )
    }
}

impl Add for Jet {
    type Output = Jet;
    fn add(self, o: Jet) -> Jet {
        Jet {
            v: self.v + o.v,
            dx: self.dx + o.dx,
            dy: self.dy + o.dy,
        }
    }
}
impl Sub for Jet {
    type Output = Jet;
    fn sub(self, o: Jet) -> Jet {
        Jet {
            v: self.v - o.v,
            dx: self.dx - o.dx,
            dy: self.dy - o.dy,
        }
    }
}
impl Mul for Jet {
    type Output = Jet;
    fn mul(self, o: Jet) -> Jet {
        Jet {
            v: self.v * o.v,
            dx: self.dx * o.v + self.v * o.dx,
            dy: self.dy * o.v + self.v * o.dy,
        }
    }
}
impl Div for Jet {
    type Output = Jet;
    fn div(self, o: Jet) -> Jet {
        let q = self.v / o.v;
        Jet {
            v: q,
            dx: (self.dx - q * o.dx) / o.v,
            dy: (self.dy - q * o.dy) / o.v,
        }
    }
}
impl Neg for Jet {
    type Output = Jet;
    fn neg(self) -> Jet {
        Jet {
            v: -self.v,
            dx: -self.dx,
            dy: -self.dy,
        }
    }
}

impl Scalar for Jet {
    fn cst(x: f64) -> Self {
        Jet {
            v: x,
            dx: 0.0,
            dy: 0.0,
        }
    }
    fn val(self) -> f64 {
        self.v
    }
    fn chain(self, f: f64, df: f64) -> Self {
        Jet {
            v: f,
            dx: df * self.dx,
            dy: df * self.dy,
        }
    }
}

/// A 3-vector of [`Scalar`]s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<S> {
    /// x.
    pub x: S,
    /// y.
    pub y: S,
    /// z.
    pub z: S,
}

impl<S: Scalar> V3<S> {
    /// A constant vector.
    pub fn cst(v: DVec3) -> Self {
        V3 {
            x: S::cst(v.x),
            y: S::cst(v.y),
            z: S::cst(v.z),
        }
    }
    /// g(t) for a vector function g of the scalar t, given g and g′ at `t.val()`.
    pub fn chain(t: S, g: DVec3, dg: DVec3) -> Self {
        V3 {
            x: t.chain(g.x, dg.x),
            y: t.chain(g.y, dg.y),
            z: t.chain(g.z, dg.z),
        }
    }
    /// The value.
    pub fn val(&self) -> DVec3 {
        DVec3::new(self.x.val(), self.y.val(), self.z.val())
    }
    /// Sum.
    pub fn plus(self, o: Self) -> Self {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
    /// Difference.
    pub fn minus(self, o: Self) -> Self {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
    /// Scaled by `s`.
    pub fn scale(self, s: S) -> Self {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    /// Dot product.
    pub fn dot(self, o: Self) -> S {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// Cross product.
    pub fn cross(self, o: Self) -> Self {
        V3 {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }
    /// The unit vector along `self` (non-zero).
    pub fn normalize(self) -> Self {
        let l = self.dot(self).sqrt();
        self.scale(S::cst(1.0) / l)
    }
}

impl V3<Jet> {
    /// ∂/∂x of the vector.
    pub fn dx(&self) -> DVec3 {
        DVec3::new(self.x.dx, self.y.dx, self.z.dx)
    }
    /// ∂/∂y of the vector.
    pub fn dy(&self) -> DVec3 {
        DVec3::new(self.x.dy, self.y.dy, self.z.dy)
    }
}
