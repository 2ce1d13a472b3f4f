//! Second-order jets: a scalar field's value, gradient and Hessian at one point,
//! in 3-D ([`Jet`]) and on a parameter plane ([`Jet2`]), with the few operations
//! the primitives are built from (sum, product, reciprocal, `exp(−x)`, composition).
//! Every derivative in the Density Spatial Model is carried analytically this way.

use glam::{DMat2, DMat3, DVec2, DVec3};

/// Value, gradient and Hessian of a scalar field of space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet {
    /// f(p).
    pub value: f64,
    /// ∇f(p).
    pub grad: DVec3,
    /// ∇²f(p) (symmetric).
    pub hess: DMat3,
}

/// Value, gradient and Hessian of a scalar field on a (u, v) plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet2 {
    /// f(u, v).
    pub value: f64,
    /// (f_u, f_v).
    pub grad: DVec2,
    /// [[f_uu, f_uv], [f_uv, f_vv]].
    pub hess: DMat2,
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

fn outer2(a: DVec2, b: DVec2) -> DMat2 {
    DMat2::from_cols(a * b.x, a * b.y)
}

impl Jet {
    /// A constant field.
    pub fn constant(value: f64) -> Self {
        Self {
            value,
            grad: DVec3::ZERO,
            hess: DMat3::ZERO,
        }
    }

    /// The linear field n·p + c.
    pub fn linear(n: DVec3, value: f64) -> Self {
        Self {
            value,
            grad: n,
            hess: DMat3::ZERO,
        }
    }

    /// |q| at q (gradient q/|q|, Hessian (I − q̂q̂ᵀ)/|q|); at q = 0 the cusp is
    /// reported with zero gradient and Hessian.
    pub fn norm(q: DVec3) -> Self {
        let n = q.length();
        if n == 0.0 {
            return Self::constant(0.0);
        }
        let u = q / n;
        Self {
            value: n,
            grad: u,
            hess: (DMat3::IDENTITY - outer(u, u)) * (1.0 / n),
        }
    }

    /// The distance from the z axis, sqrt(x² + y²), with its derivatives (zero
    /// gradient on the axis).
    pub fn radial(q: DVec3) -> Self {
        Self::norm(DVec3::new(q.x, q.y, 0.0)).with_flat_z()
    }

    fn with_flat_z(mut self) -> Self {
        // norm() of a vector with z = 0 has an identity z-row in (I − q̂q̂ᵀ)/n: remove it.
        if self.value > 0.0 {
            self.hess.z_axis = DVec3::ZERO;
            self.hess.x_axis.z = 0.0;
            self.hess.y_axis.z = 0.0;
        }
        self
    }

    /// self + other.
    pub fn plus(self, o: Self) -> Self {
        Self {
            value: self.value + o.value,
            grad: self.grad + o.grad,
            hess: self.hess + o.hess,
        }
    }

    /// self + c.
    pub fn add_constant(mut self, c: f64) -> Self {
        self.value += c;
        self
    }

    /// c · self.
    pub fn scale(self, c: f64) -> Self {
        Self {
            value: self.value * c,
            grad: self.grad * c,
            hess: self.hess * c,
        }
    }

    /// self · other (product rule).
    pub fn times(self, o: Self) -> Self {
        Self {
            value: self.value * o.value,
            grad: self.grad * o.value + o.grad * self.value,
            hess: self.hess * o.value
                + o.hess * self.value
                + outer(self.grad, o.grad)
                + outer(o.grad, self.grad),
        }
    }

    /// 1 / self (self ≠ 0).
    pub fn recip(self) -> Self {
        let v = self.value;
        let inv = 1.0 / v;
        Self {
            value: inv,
            grad: self.grad * (-inv * inv),
            hess: self.hess * (-inv * inv) + outer(self.grad, self.grad) * (2.0 * inv * inv * inv),
        }
    }

    /// exp(−self).
    pub fn exp_neg(self) -> Self {
        let e = (-self.value).exp();
        Self {
            value: e,
            grad: self.grad * (-e),
            hess: (outer(self.grad, self.grad) - self.hess) * e,
        }
    }

    /// |self| (its sign flips the derivatives; the kink at 0 is not smoothed).
    pub fn abs(self) -> Self {
        if self.value < 0.0 {
            self.scale(-1.0)
        } else {
            self
        }
    }

    /// f(u(p), v(p)) for a plane field f and two space fields u, v (chain rule).
    pub fn compose(f: Jet2, u: Jet, v: Jet) -> Self {
        let (fu, fv) = (f.grad.x, f.grad.y);
        let (fuu, fuv, fvv) = (f.hess.x_axis.x, f.hess.y_axis.x, f.hess.y_axis.y);
        Self {
            value: f.value,
            grad: u.grad * fu + v.grad * fv,
            hess: outer(u.grad, u.grad) * fuu
                + (outer(u.grad, v.grad) + outer(v.grad, u.grad)) * fuv
                + outer(v.grad, v.grad) * fvv
                + u.hess * fu
                + v.hess * fv,
        }
    }

    /// Lift a rigid-body local jet to world coordinates: local = Rᵀ(p − t) gives
    /// ∇ = R ∇_local and ∇² = R ∇²_local Rᵀ.
    pub fn rotate(self, r: &DMat3) -> Self {
        Self {
            value: self.value,
            grad: *r * self.grad,
            hess: *r * self.hess * r.transpose(),
        }
    }
}

impl Jet2 {
    /// A constant plane field.
    pub fn constant(value: f64) -> Self {
        Self {
            value,
            grad: DVec2::ZERO,
            hess: DMat2::ZERO,
        }
    }

    /// self + other.
    pub fn plus(self, o: Self) -> Self {
        Self {
            value: self.value + o.value,
            grad: self.grad + o.grad,
            hess: self.hess + o.hess,
        }
    }

    /// self · other.
    pub fn times(self, o: Self) -> Self {
        Self {
            value: self.value * o.value,
            grad: self.grad * o.value + o.grad * self.value,
            hess: self.hess * o.value
                + o.hess * self.value
                + outer2(self.grad, o.grad)
                + outer2(o.grad, self.grad),
        }
    }

    /// c · self.
    pub fn scale(self, c: f64) -> Self {
        Self {
            value: self.value * c,
            grad: self.grad * c,
            hess: self.hess * c,
        }
    }

    /// ln(self) (self > 0).
    pub fn ln(self) -> Self {
        let inv = 1.0 / self.value;
        Self {
            value: self.value.ln(),
            grad: self.grad * inv,
            hess: self.hess * inv - outer2(self.grad, self.grad) * (inv * inv),
        }
    }
}
