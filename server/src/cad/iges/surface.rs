//! Entity 128, the rational B-spline surface: the polynomial surface the
//! kernel sculpts, its checks, and its parameter data in and out.
//!
//! Parameter data: `128,K1,K2,M1,M2,PROP1..PROP5, S(-M1..N1+M1), T(..),
//! W(0,0),W(1,0)..W(K1,K2), X,Y,Z(0,0),X,Y,Z(1,0).., U0,U1,V0,V1` with u
//! fastest, K the count − 1, M the degree and PROP3 = 1 for polynomial.

use super::format::{knots_ok, real};
use super::parse::Fields;
use super::{IgesError, MAX_IGES_DEGREE, MAX_IGES_MAGNITUDE, MAX_IGES_POINTS};
use glam::DVec3;

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
    pub(super) fn validate(&self) -> Result<(), IgesError> {
        let bad = |s: String| Err(IgesError::InvalidSurface(s));
        if self.u_degree == 0 || self.v_degree == 0 {
            return bad("degree must be at least 1".into());
        }
        if self.u_degree > MAX_IGES_DEGREE || self.v_degree > MAX_IGES_DEGREE {
            return bad(format!("degree above {MAX_IGES_DEGREE}"));
        }
        if self.nu.saturating_mul(self.nv) > MAX_IGES_POINTS {
            return bad(format!("more than {MAX_IGES_POINTS} control points"));
        }
        if self.nu <= self.u_degree || self.nv <= self.v_degree {
            return bad("too few control points for the degree".into());
        }
        if Some(self.points.len()) != self.nu.checked_mul(self.nv) {
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
        if !self.points.iter().all(|p| p.is_finite()) {
            return bad("non-finite control point".into());
        }
        knots_ok(&self.u_knots, self.u_degree, self.nu)
            .and_then(|()| knots_ok(&self.v_knots, self.v_degree, self.nv))
            .or_else(bad)
    }

    /// The parameter fields of this surface as entity 128 (weights all 1,
    /// polynomial), without delimiters or trailing pointer groups.
    pub(super) fn params(&self) -> Vec<String> {
        let (nu, nv) = (self.nu, self.nv);
        let mut params = vec![
            "128".to_string(),
            (nu - 1).to_string(),
            (nv - 1).to_string(),
            self.u_degree.to_string(),
            self.v_degree.to_string(),
            "0".into(),
            "0".into(),
            "1".into(),
            "0".into(),
            "0".into(),
        ];
        params.extend(self.u_knots.iter().map(|&x| real(x)));
        params.extend(self.v_knots.iter().map(|&x| real(x)));
        params.extend(std::iter::repeat_n(real(1.0), nu * nv));
        for j in 0..nv {
            for i in 0..nu {
                let p = self.points[i * nv + j];
                params.extend([real(p.x), real(p.y), real(p.z)]);
            }
        }
        let u0 = self.u_knots[self.u_degree];
        let u1 = self.u_knots[nu];
        let v0 = self.v_knots[self.v_degree];
        let v1 = self.v_knots[nv];
        params.extend([real(u0), real(u1), real(v0), real(v1)]);
        params
    }

    /// Every knot and control-point coordinate finite and within
    /// ±[`MAX_IGES_MAGNITUDE`] (checked after any transformation).
    pub(super) fn check_magnitudes(&self, de: usize) -> Result<(), IgesError> {
        check_magnitudes(
            de,
            self.u_knots.iter().chain(&self.v_knots).copied(),
            self.points.iter().flat_map(|p| p.to_array()),
        )
    }
}

/// Every knot and coordinate finite and within ±[`MAX_IGES_MAGNITUDE`].
pub(super) fn check_magnitudes(
    de: usize,
    mut knots: impl Iterator<Item = f64>,
    mut coords: impl Iterator<Item = f64>,
) -> Result<(), IgesError> {
    let bad = |x: &f64| !x.is_finite() || x.abs() > MAX_IGES_MAGNITUDE;
    if let Some(value) = knots.find(bad) {
        return Err(IgesError::TooLarge {
            de,
            what: "knot",
            value,
        });
    }
    if let Some(value) = coords.find(bad) {
        return Err(IgesError::TooLarge {
            de,
            what: "control point coordinate",
            value,
        });
    }
    Ok(())
}

/// The weights of a rational entity are usable as polynomial: all positive
/// and equal (to a relative 1e-12); else the (min, max) that are not.
pub(super) fn uniform_weights(weights: &[f64]) -> Result<(), (f64, f64)> {
    let min = weights.iter().copied().fold(f64::INFINITY, f64::min);
    let max = weights.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if min <= 0.0 || (max - min) > 1e-12 * max.abs() {
        Err((min, max))
    } else {
        Ok(())
    }
}

/// Reads an entity 128; returns the surface and the number of its own
/// parameter fields (where the trailing pointer groups start).
pub(super) fn parse_surface(f: &Fields<'_>) -> Result<(IgesSurface, usize), IgesError> {
    let de = f.de;
    if f.int(0)? != 128 {
        return Err(f.bad("parameter data does not start with 128".into()));
    }
    let (k1, k2, m1, m2) = (f.int(1)?, f.int(2)?, f.int(3)?, f.int(4)?);
    let (kmax, mmax) = (MAX_IGES_POINTS as i64, MAX_IGES_DEGREE as i64);
    if k1 < 1 || k2 < 1 || m1 < 1 || m2 < 1 || k1 >= kmax || k2 >= kmax || m1 > mmax || m2 > mmax {
        return Err(f.bad(format!("unsupported sizes K1={k1} K2={k2} M1={m1} M2={m2}")));
    }
    let (nu, nv, du, dv) = (k1 as usize + 1, k2 as usize + 1, m1 as usize, m2 as usize);
    if nu * nv > MAX_IGES_POINTS {
        return Err(f.bad("control net too large".into()));
    }
    let polynomial = f.int(7)? == 1;
    let mut k = 10;
    let u_knots = f.reals(&mut k, nu + du + 1)?;
    let v_knots = f.reals(&mut k, nv + dv + 1)?;
    let weights = f.reals(&mut k, nu * nv)?;
    let coords = f.reals(&mut k, 3 * nu * nv)?;
    let own = k + 4;
    if !polynomial {
        uniform_weights(&weights).map_err(|(min, max)| IgesError::RationalWeights {
            de,
            min,
            max,
        })?;
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
    s.validate().map_err(|e| f.bad(e.to_string()))?;
    Ok((s, own))
}
