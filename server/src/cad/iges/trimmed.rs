//! Entity 144, the trimmed (parametric) surface, as the writer emits it: a
//! B-spline surface (128) of which only the part inside one closed polygon
//! of its parameter space is meant — how a network face's refit (a bicubic
//! over the square around its n-gon domain) is exchanged.
//!
//! Entities, each pointing to the next (physically dependent, status
//! `00010000`, except the 144 itself):
//!
//! * 144: `144, PTS, N1 = 1, N2 = 0, PTO` — the surface, an outer boundary
//!   that is not the surface's own, no inner boundaries, the boundary;
//! * 128: the surface;
//! * 126: the polygon as a closed planar degree-1 curve in (u, v, 0)
//!   (PROP1 = 1 planar, PROP2 = 1 closed, normal (0, 0, 1), knots 0, 0, 1,
//!   …, n, n over the n + 1 points, the first repeated last), use flag 5
//!   (2D parametric);
//! * 142: `142, CRTN = 0, SPTR, BPTR, CPTR = 0, PREF = 1` — the curve on
//!   the surface given by its parameter-space curve alone (preferred).

use super::IgesError;
use super::curve::IgesCurve;
use super::surface::IgesSurface;

/// A surface trimmed to the inside of one closed polygon of its parameter
/// space.
#[derive(Clone, Debug, PartialEq)]
pub struct IgesTrimmed {
    /// The surface.
    pub surface: IgesSurface,
    /// The outer boundary's vertices (u, v) in order (at least 3; the
    /// first is not repeated), inside the surface's parameter domain.
    pub outer: Vec<[f64; 2]>,
}

impl IgesTrimmed {
    pub(super) fn validate(&self) -> Result<(), IgesError> {
        self.surface.validate()?;
        let s = &self.surface;
        let (u0, u1) = (s.u_knots[s.u_degree], s.u_knots[s.nu]);
        let (v0, v1) = (s.v_knots[s.v_degree], s.v_knots[s.nv]);
        if self.outer.len() < 3 {
            return Err(IgesError::InvalidSurface(format!(
                "a trimming polygon of {} vertices (at least 3)",
                self.outer.len()
            )));
        }
        let inside = |[u, v]: [f64; 2]| {
            u.is_finite() && v.is_finite() && (u0..=u1).contains(&u) && (v0..=v1).contains(&v)
        };
        if !self.outer.iter().all(|p| inside(*p)) {
            return Err(IgesError::InvalidSurface(format!(
                "a trimming polygon vertex outside the parameter domain [{u0}, {u1}] × [{v0}, {v1}]"
            )));
        }
        Ok(())
    }

    /// The outer boundary as the closed degree-1 curve of entity 126's
    /// parameter data (planar, closed, normal (0, 0, 1)).
    pub(super) fn loop_params(&self) -> Vec<String> {
        let n = self.outer.len();
        let mut points: Vec<[f64; 3]> = self.outer.iter().map(|[u, v]| [*u, *v, 0.0]).collect();
        points.push(points[0]);
        let mut knots = vec![0.0];
        knots.extend((0..=n).map(|k| k as f64));
        knots.push(n as f64);
        let mut params = IgesCurve {
            degree: 1,
            knots,
            points,
        }
        .params();
        // PROP1 planar, PROP2 closed; the plane's normal last.
        params[3] = "1".into();
        params[4] = "1".into();
        let len = params.len();
        params[len - 1] = super::format::real(1.0);
        params
    }
}
