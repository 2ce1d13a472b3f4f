//! Materials of the thin-plate deformation energy: stretch α and bend β
//! (paper 003), plus `rest`, the weight of a mass term ∫|w − w_ref|² about
//! the reference shape that keeps an unconstrained surface bounded.

use thiserror::Error;

/// A material coefficient is NaN, infinite or negative.
#[derive(Clone, Debug, Error, PartialEq)]
#[error("material: {0}")]
pub struct MaterialError(pub String);

fn check(name: &str, x: f64, positive: bool) -> Result<(), MaterialError> {
    if !x.is_finite() {
        return Err(MaterialError(format!("{name} is not finite")));
    }
    if x < 0.0 || (positive && x == 0.0) {
        return Err(MaterialError(format!(
            "{name} = {x} must be {}",
            if positive { "> 0" } else { "≥ 0" }
        )));
    }
    Ok(())
}

/// The surface energy's coefficients:
/// ∫∫ α11|w_u|² + 2α12 w_u·w_v + α22|w_v|² + β11|w_uu|² + 2β12|w_uv|² + β22|w_vv|² + rest·|w − w_ref|².
///
/// Units: the integral is over the *parameter* domain (du dv), as in paper
/// 003, so α and β are per unit of parameter area and a surface's stiffness
/// does not change when it is scaled in model space. With α = 0 and
/// β11 = β12 = β22 = β the shape obeys β Δ²w = f: a Kirchhoff plate of
/// flexural rigidity D = β (Poisson's ratio 0) over the parameter square,
/// loaded by f per unit parameter area (kernel README, "Units").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceMaterial {
    /// Stretch along u.
    pub alpha11: f64,
    /// Stretch coupling; |α12| ≤ sqrt(α11 α22) keeps the energy convex.
    pub alpha12: f64,
    /// Stretch along v.
    pub alpha22: f64,
    /// Bend along u.
    pub beta11: f64,
    /// Twist.
    pub beta12: f64,
    /// Bend along v.
    pub beta22: f64,
    /// Mass term weight (> 0).
    pub rest: f64,
}

impl Default for SurfaceMaterial {
    /// A fair sculpting material: mostly bending (β = 1), a little stretch
    /// (α = 0.01), a rest term small enough not to resist sculpting (1e-4).
    fn default() -> Self {
        Self {
            alpha11: 0.01,
            alpha12: 0.0,
            alpha22: 0.01,
            beta11: 1.0,
            beta12: 1.0,
            beta22: 1.0,
            rest: 1e-4,
        }
    }
}

impl SurfaceMaterial {
    /// Checks every coefficient is finite, α11, α22, β ≥ 0, rest > 0 and
    /// |α12| ≤ sqrt(α11 α22).
    pub fn validate(&self) -> Result<(), MaterialError> {
        check("alpha11", self.alpha11, false)?;
        check("alpha22", self.alpha22, false)?;
        check("beta11", self.beta11, false)?;
        check("beta12", self.beta12, false)?;
        check("beta22", self.beta22, false)?;
        check("rest", self.rest, true)?;
        if !self.alpha12.is_finite() {
            return Err(MaterialError("alpha12 is not finite".into()));
        }
        if self.alpha12.abs() > (self.alpha11 * self.alpha22).sqrt() * (1.0 + 1e-12) {
            return Err(MaterialError(
                "|alpha12| must not exceed sqrt(alpha11·alpha22)".into(),
            ));
        }
        Ok(())
    }
}

/// The curve energy's coefficients: ∫ α|w_u|² + β|w_uu|² + rest·|w − w_ref|².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveMaterial {
    /// Stretch.
    pub alpha: f64,
    /// Bend.
    pub beta: f64,
    /// Mass term weight (> 0).
    pub rest: f64,
}

impl Default for CurveMaterial {
    /// As [`SurfaceMaterial::default`]: α = 0.01, β = 1, rest = 1e-4.
    fn default() -> Self {
        Self {
            alpha: 0.01,
            beta: 1.0,
            rest: 1e-4,
        }
    }
}

impl CurveMaterial {
    /// Checks α, β ≥ 0 and rest > 0, all finite.
    pub fn validate(&self) -> Result<(), MaterialError> {
        check("alpha", self.alpha, false)?;
        check("beta", self.beta, false)?;
        check("rest", self.rest, true)
    }
}
