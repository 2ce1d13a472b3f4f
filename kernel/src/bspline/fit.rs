//! Global interpolation (Piegl & Tiller §9.2.1 and §9.2.5): a curve through
//! a sequence of points, a surface through a grid of points.
//!
//! Parameters are centripetal (square roots of chord lengths), averaged over
//! the rows and columns of a grid; knots are averages of p consecutive
//! parameters, which keeps the collocation matrix non-singular
//! (Schoenberg–Whitney). The square systems are solved by dense LU (faer),
//! and the residual is checked, so degenerate data is an error, never NaN.

use faer::Mat;
use faer::prelude::Solve;
use glam::DVec3;

use super::{BSplineCurve, BSplineSurface, GeometryError, KnotVector, basis_derivs};

/// Centripetal parameters in [0, 1] for points along one line of data.
fn centripetal(points: &[DVec3]) -> Result<Vec<f64>, GeometryError> {
    let d: Vec<f64> = points
        .windows(2)
        .map(|w| (w[1] - w[0]).length().sqrt())
        .collect();
    let total: f64 = d.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(GeometryError::Singular("all points coincide".into()));
    }
    let mut t = Vec::with_capacity(points.len());
    t.push(0.0);
    let mut acc = 0.0;
    for di in &d {
        acc += di;
        t.push(acc / total);
    }
    if let Some(last) = t.last_mut() {
        *last = 1.0;
    }
    Ok(t)
}

/// Knots by averaging (P&T eq. 9.8).
fn averaged_knots(params: &[f64], degree: usize) -> Result<KnotVector, GeometryError> {
    let n = params.len();
    let mut knots = vec![0.0; degree + 1];
    for j in 1..n - degree {
        knots.push(params[j..j + degree].iter().sum::<f64>() / degree as f64);
    }
    knots.extend(std::iter::repeat_n(1.0, degree + 1));
    KnotVector::new(degree, knots)
}

/// Solves N · X = rhs for every column of `rhs` (each a line of data), with
/// N[k][i] = N_i(params[k]).
fn collocate(
    kv: &KnotVector,
    params: &[f64],
    rhs: &[Vec<DVec3>],
) -> Result<Vec<Vec<DVec3>>, GeometryError> {
    let n = params.len();
    let mut a = Mat::<f64>::zeros(n, n);
    for (k, &t) in params.iter().enumerate() {
        let b = basis_derivs(kv, t, 0);
        for i in 0..=kv.degree() {
            a[(k, b.first + i)] = b.get(0, i);
        }
    }
    let lu = a.partial_piv_lu();
    let cols = rhs.len() * 3;
    let b = Mat::<f64>::from_fn(n, cols, |k, c| rhs[c / 3][k][c % 3]);
    let x = lu.solve(&b);
    let mut out = Vec::with_capacity(rhs.len());
    for (line, data) in rhs.iter().enumerate() {
        let pts: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new(x[(i, 3 * line)], x[(i, 3 * line + 1)], x[(i, 3 * line + 2)]))
            .collect();
        // Check: the interpolant passes through the data.
        let scale = data
            .iter()
            .fold(1.0f64, |m, p| m.max(p.abs().max_element()));
        for (k, &t) in params.iter().enumerate() {
            let b = basis_derivs(kv, t, 0);
            let p: DVec3 = (0..=kv.degree())
                .map(|i| pts[b.first + i] * b.get(0, i))
                .sum();
            if !p.is_finite() || (p - data[k]).length() > 1e-8 * scale {
                return Err(GeometryError::Singular(
                    "interpolation system is singular".into(),
                ));
            }
        }
        out.push(pts);
    }
    Ok(out)
}

/// The degree-`degree` curve through `points` (at least degree+1 of them).
pub fn interpolate_curve(points: &[DVec3], degree: usize) -> Result<BSplineCurve, GeometryError> {
    if degree < 1 {
        return Err(GeometryError::BadDegree(degree));
    }
    if points.len() < degree + 1 {
        return Err(GeometryError::TooFewControlPoints {
            degree,
            needed: degree + 1,
            got: points.len(),
        });
    }
    if let Some(index) = points.iter().position(|p| !p.is_finite()) {
        return Err(GeometryError::NonFinitePoint { index });
    }
    let params = centripetal(points)?;
    if params.windows(2).any(|w| w[1] <= w[0]) {
        return Err(GeometryError::Singular(
            "consecutive points coincide".into(),
        ));
    }
    let kv = averaged_knots(&params, degree)?;
    let mut sol = collocate(&kv, &params, &[points.to_vec()])?;
    BSplineCurve::new(kv, sol.remove(0))
}

/// The surface of degree (pu, pv) through the `m × n` grid `points`
/// (row-major, `points[k * n + l]`, k along u).
pub fn interpolate_surface(
    points: &[DVec3],
    m: usize,
    n: usize,
    pu: usize,
    pv: usize,
) -> Result<BSplineSurface, GeometryError> {
    if points.len() != m * n {
        return Err(GeometryError::GridSize {
            expected: m * n,
            got: points.len(),
        });
    }
    for (deg, count) in [(pu, m), (pv, n)] {
        if deg < 1 {
            return Err(GeometryError::BadDegree(deg));
        }
        if count < deg + 1 {
            return Err(GeometryError::TooFewControlPoints {
                degree: deg,
                needed: deg + 1,
                got: count,
            });
        }
    }
    if let Some(index) = points.iter().position(|p| !p.is_finite()) {
        return Err(GeometryError::NonFinitePoint { index });
    }
    // Average the centripetal parameters of every column (u) and row (v).
    let mut uk = vec![0.0; m];
    for l in 0..n {
        let col: Vec<DVec3> = (0..m).map(|k| points[k * n + l]).collect();
        for (a, b) in uk.iter_mut().zip(centripetal(&col)?) {
            *a += b / n as f64;
        }
    }
    let mut vl = vec![0.0; n];
    for k in 0..m {
        for (a, b) in vl.iter_mut().zip(centripetal(&points[k * n..(k + 1) * n])?) {
            *a += b / m as f64;
        }
    }
    for p in [&uk, &vl] {
        if p.windows(2).any(|w| w[1] <= w[0]) {
            return Err(GeometryError::Singular(
                "grid rows or columns coincide".into(),
            ));
        }
    }
    let ku = averaged_knots(&uk, pu)?;
    let kv = averaged_knots(&vl, pv)?;
    // Along u for every column, then along v for every row of the result.
    let columns: Vec<Vec<DVec3>> = (0..n)
        .map(|l| (0..m).map(|k| points[k * n + l]).collect())
        .collect();
    let r = collocate(&ku, &uk, &columns)?; // r[l][i]
    let rows: Vec<Vec<DVec3>> = (0..m).map(|i| (0..n).map(|l| r[l][i]).collect()).collect();
    let p = collocate(&kv, &vl, &rows)?; // p[i][j]
    BSplineSurface::new(ku, kv, p.into_iter().flatten().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_passes_through_its_points() {
        let pts: Vec<DVec3> = (0..9)
            .map(|k| DVec3::new(k as f64, (k as f64).sin(), 0.1 * (k * k) as f64))
            .collect();
        let c = interpolate_curve(&pts, 3).unwrap();
        let b = c.knots().clone();
        assert_eq!(b.num_ctrl(), 9);
        let params = centripetal(&pts).unwrap();
        for (p, t) in pts.iter().zip(params) {
            assert!((c.point(t) - *p).length() < 1e-10);
        }
    }

    #[test]
    fn surface_passes_through_its_grid() {
        let (m, n) = (7, 6);
        let pts: Vec<DVec3> = (0..m * n)
            .map(|k| {
                let (i, j) = ((k / n) as f64, (k % n) as f64);
                DVec3::new(i, j, (0.4 * i).sin() * (0.3 * j).cos())
            })
            .collect();
        let s = interpolate_surface(&pts, m, n, 3, 3).unwrap();
        assert_eq!((s.nu(), s.nv()), (m, n));
        // Corners are interpolated exactly; interior data at the averaged parameters.
        assert!((s.point(0.0, 0.0) - pts[0]).length() < 1e-10);
        assert!((s.point(1.0, 1.0) - pts[m * n - 1]).length() < 1e-10);
    }

    #[test]
    fn degenerate_data_is_an_error() {
        let same = vec![DVec3::ONE; 5];
        assert!(interpolate_curve(&same, 3).is_err());
        let mut pts: Vec<DVec3> = (0..5).map(|k| DVec3::X * k as f64).collect();
        pts[2] = pts[1];
        assert!(interpolate_curve(&pts, 2).is_err());
        assert!(interpolate_curve(&pts[..2], 3).is_err());
        assert!(interpolate_surface(&[DVec3::ZERO; 4], 2, 3, 1, 1).is_err());
    }
}
