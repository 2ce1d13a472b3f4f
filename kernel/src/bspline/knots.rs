//! Clamped knot vectors: validation, the parameter domain and span lookup.
//!
//! A knot vector of degree p for n control points has n + p + 1 knots. It is
//! *clamped*: the first and the last knot have multiplicity p + 1, so curves
//! interpolate their end control points. Interior knots may repeat up to p
//! times.

use super::GeometryError;

/// A validated, clamped, non-decreasing knot vector.
#[derive(Clone, Debug, PartialEq)]
pub struct KnotVector {
    degree: usize,
    knots: Vec<f64>,
}

impl KnotVector {
    /// Validates `knots` for `degree`: finite, non-decreasing, clamped (end
    /// multiplicity degree+1), interior multiplicity ≤ degree, non-empty domain.
    pub fn new(degree: usize, knots: Vec<f64>) -> Result<Self, GeometryError> {
        if degree < 1 {
            return Err(GeometryError::BadDegree(degree));
        }
        if let Some(index) = knots.iter().position(|k| !k.is_finite()) {
            return Err(GeometryError::NonFiniteKnot { index });
        }
        if let Some(index) = (1..knots.len()).find(|&i| knots[i] < knots[i - 1]) {
            return Err(GeometryError::DecreasingKnots { index });
        }
        let num_ctrl = knots.len().saturating_sub(degree + 1);
        if num_ctrl < degree + 1 {
            return Err(GeometryError::TooFewControlPoints {
                degree,
                needed: degree + 1,
                got: num_ctrl,
            });
        }
        let m = knots.len() - 1;
        let (start, end) = (knots[0], knots[m]);
        if end <= start {
            return Err(GeometryError::EmptyDomain);
        }
        if knots[..=degree].iter().any(|&k| k != start)
            || knots[m - degree..].iter().any(|&k| k != end)
        {
            return Err(GeometryError::NotClamped);
        }
        let mut i = degree + 1;
        while i < m - degree {
            let value = knots[i];
            let multiplicity = knots[i..].iter().take_while(|&&k| k == value).count();
            if multiplicity > degree {
                return Err(GeometryError::InteriorMultiplicity {
                    value,
                    multiplicity,
                    degree,
                });
            }
            i += multiplicity;
        }
        Ok(Self { degree, knots })
    }

    /// The clamped uniform knot vector of `degree` for `num_ctrl` control
    /// points on the domain [0, 1].
    pub fn clamped_uniform(degree: usize, num_ctrl: usize) -> Result<Self, GeometryError> {
        if degree < 1 {
            return Err(GeometryError::BadDegree(degree));
        }
        if num_ctrl < degree + 1 {
            return Err(GeometryError::TooFewControlPoints {
                degree,
                needed: degree + 1,
                got: num_ctrl,
            });
        }
        let spans = num_ctrl - degree;
        let mut knots = Vec::with_capacity(num_ctrl + degree + 1);
        knots.extend(std::iter::repeat_n(0.0, degree + 1));
        knots.extend((1..spans).map(|i| i as f64 / spans as f64));
        knots.extend(std::iter::repeat_n(1.0, degree + 1));
        Self::new(degree, knots)
    }

    /// The degree p.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// All knots, n + p + 1 of them.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The number of control points n this knot vector serves.
    pub fn num_ctrl(&self) -> usize {
        self.knots.len() - self.degree - 1
    }

    /// The parameter domain [u_p, u_n].
    pub fn domain(&self) -> (f64, f64) {
        (self.knots[0], self.knots[self.knots.len() - 1])
    }

    /// Whether `t` is a finite parameter inside the domain.
    pub fn contains(&self, t: f64) -> bool {
        let (a, b) = self.domain();
        t.is_finite() && t >= a && t <= b
    }

    /// The index i of the knot span [u_i, u_{i+1}) holding `t` (Piegl &
    /// Tiller A2.1). `t` is clamped into the domain; the domain's end belongs
    /// to the last non-empty span. NaN maps to the first span.
    pub fn find_span(&self, t: f64) -> usize {
        let p = self.degree;
        let n = self.num_ctrl();
        let (a, b) = self.domain();
        let t = if t.is_nan() { a } else { t.clamp(a, b) };
        if t >= self.knots[n] {
            return n - 1;
        }
        // Binary search for the last i in [p, n-1] with knots[i] <= t.
        let slice = &self.knots[p..=n];
        let k = slice.partition_point(|&x| x <= t);
        p + k - 1
    }

    /// Every non-empty knot span as (span index, start, end), in order.
    pub fn spans(&self) -> Vec<(usize, f64, f64)> {
        let p = self.degree;
        let n = self.num_ctrl();
        (p..n)
            .filter(|&i| self.knots[i + 1] > self.knots[i])
            .map(|i| (i, self.knots[i], self.knots[i + 1]))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamped_uniform_has_expected_knots() {
        let kv = KnotVector::clamped_uniform(3, 6).unwrap();
        assert_eq!(
            kv.knots(),
            &[0.0, 0.0, 0.0, 0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0, 1.0, 1.0, 1.0]
        );
        assert_eq!(kv.num_ctrl(), 6);
        assert_eq!(kv.spans().len(), 3);
    }

    #[test]
    fn find_span_brackets_parameter() {
        let kv = KnotVector::new(2, vec![0.0, 0.0, 0.0, 0.25, 0.5, 0.5, 1.0, 1.0, 1.0]).unwrap();
        for &t in &[0.0, 0.1, 0.25, 0.3, 0.5, 0.7, 0.999, 1.0] {
            let s = kv.find_span(t);
            let k = kv.knots();
            assert!(
                k[s] <= t && (t < k[s + 1] || (t == 1.0 && k[s + 1] == 1.0)),
                "t={t} s={s}"
            );
            assert!(k[s + 1] > k[s], "span must be non-empty");
        }
        assert_eq!(kv.find_span(-5.0), kv.find_span(0.0));
        assert_eq!(kv.find_span(f64::NAN), kv.find_span(0.0));
    }

    #[test]
    fn bad_knot_vectors_are_rejected() {
        assert_eq!(
            KnotVector::new(0, vec![0.0, 1.0]),
            Err(GeometryError::BadDegree(0))
        );
        assert!(matches!(
            KnotVector::new(1, vec![0.0, 0.0, f64::NAN, 1.0, 1.0]),
            Err(GeometryError::NonFiniteKnot { index: 2 })
        ));
        assert!(matches!(
            KnotVector::new(1, vec![0.0, 0.0, 0.6, 0.4, 1.0, 1.0]),
            Err(GeometryError::DecreasingKnots { index: 3 })
        ));
        assert_eq!(
            KnotVector::new(2, vec![0.0, 0.0, 0.5, 1.0, 1.0, 1.0]),
            Err(GeometryError::NotClamped)
        );
        assert!(matches!(
            KnotVector::new(2, vec![0.0, 0.0, 0.0, 0.5, 0.5, 0.5, 1.0, 1.0, 1.0]),
            Err(GeometryError::InteriorMultiplicity { .. })
        ));
        assert!(KnotVector::clamped_uniform(3, 3).is_err());
    }
}
