//! Entity 126, the rational B-spline curve: the polynomial curve the kernel
//! sculpts (paper 003's deformable curve), its checks, and its parameter
//! data in and out.
//!
//! Parameter data: `126,K,M,PROP1..PROP4, T(-M..N+M) [K+M+2 knots],
//! W(0)..W(K), X,Y,Z(0)..X,Y,Z(K), V0,V1, XNORM,YNORM,ZNORM` with K the
//! count − 1, M the degree, PROP1 = 1 for planar (the normal then matters)
//! and PROP3 = 1 for polynomial.

use super::format::{knots_ok, real};
use super::parse::Fields;
use super::surface::{check_magnitudes, uniform_weights};
use super::{IgesError, MAX_IGES_DEGREE, MAX_IGES_POINTS};

/// A polynomial B-spline curve as IGES carries it: degree, full knot vector
/// (`points.len() + degree + 1` values) and control points.
#[derive(Clone, Debug, PartialEq)]
pub struct IgesCurve {
    /// Degree.
    pub degree: usize,
    /// Knots (`points.len() + degree + 1` values, non-decreasing).
    pub knots: Vec<f64>,
    /// Control points.
    pub points: Vec<[f64; 3]>,
}

impl IgesCurve {
    pub(super) fn validate(&self) -> Result<(), IgesError> {
        let bad = |s: String| Err(IgesError::InvalidCurve(s));
        if self.degree == 0 {
            return bad("degree must be at least 1".into());
        }
        if self.degree > MAX_IGES_DEGREE {
            return bad(format!("degree above {MAX_IGES_DEGREE}"));
        }
        let n = self.points.len();
        if n > MAX_IGES_POINTS {
            return bad(format!("more than {MAX_IGES_POINTS} control points"));
        }
        if n <= self.degree {
            return bad(format!(
                "{n} control points are too few for degree {}",
                self.degree
            ));
        }
        if self.knots.len() != n + self.degree + 1 {
            return bad(format!(
                "{} knots for {n} control points of degree {} (needs {})",
                self.knots.len(),
                self.degree,
                n + self.degree + 1
            ));
        }
        if !self.points.iter().flatten().all(|x| x.is_finite()) {
            return bad("non-finite control point".into());
        }
        knots_ok(&self.knots, self.degree, n).or_else(bad)
    }

    /// The parameter fields of this curve as entity 126 (weights all 1,
    /// polynomial, non-planar, normal 0), without delimiters or trailing
    /// pointer groups.
    pub(super) fn params(&self) -> Vec<String> {
        let n = self.points.len();
        let mut params = vec![
            "126".to_string(),
            (n - 1).to_string(),
            self.degree.to_string(),
            "0".into(),
            "0".into(),
            "1".into(),
            "0".into(),
        ];
        params.extend(self.knots.iter().map(|&x| real(x)));
        params.extend(std::iter::repeat_n(real(1.0), n));
        for p in &self.points {
            params.extend(p.iter().map(|&x| real(x)));
        }
        params.extend([real(self.knots[self.degree]), real(self.knots[n])]);
        params.extend([real(0.0), real(0.0), real(0.0)]);
        params
    }

    /// Every knot and control-point coordinate finite and within
    /// ±[`super::MAX_IGES_MAGNITUDE`] (checked after any transformation).
    pub(super) fn check_magnitudes(&self, de: usize) -> Result<(), IgesError> {
        check_magnitudes(
            de,
            self.knots.iter().copied(),
            self.points.iter().flatten().copied(),
        )
    }
}

/// Reads an entity 126; returns the curve and the number of its own
/// parameter fields (where the trailing pointer groups start).
pub(super) fn parse_curve(f: &Fields<'_>) -> Result<(IgesCurve, usize), IgesError> {
    let de = f.de;
    if f.int(0)? != 126 {
        return Err(f.bad("parameter data does not start with 126".into()));
    }
    let (k, m) = (f.int(1)?, f.int(2)?);
    if !(1..MAX_IGES_POINTS as i64).contains(&k) || !(1..=MAX_IGES_DEGREE as i64).contains(&m) {
        return Err(f.bad(format!("unsupported sizes K={k} M={m}")));
    }
    let (n, degree) = (k as usize + 1, m as usize);
    let polynomial = f.int(5)? == 1;
    let mut at = 7;
    let knots = f.reals(&mut at, n + degree + 1)?;
    let weights = f.reals(&mut at, n)?;
    let coords = f.reals(&mut at, 3 * n)?;
    // V0, V1, then the unit normal (which some writers leave out).
    let own = at + 5;
    if !polynomial {
        uniform_weights(&weights).map_err(|(min, max)| IgesError::RationalCurve {
            de,
            min,
            max,
        })?;
    }
    let c = IgesCurve {
        degree,
        knots,
        points: coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    };
    c.validate().map_err(|e| f.bad(e.to_string()))?;
    Ok((c, own))
}
