//! Validation of client messages: every number finite and of sane
//! magnitude, every string and array within its limit. The server checks
//! what needs the design (ids, the (u,v) domain) itself.

use crate::client::ClientMessage;
use crate::error::{ErrorCode, ProtocolError};
use crate::limits::*;
use crate::types::{Anchor, IconSpec, Material, UvCurve};

fn number(name: &str, x: f64) -> Result<(), ProtocolError> {
    if !x.is_finite() {
        return Err(ProtocolError::new(
            ErrorCode::NotFinite,
            format!("{name} is not finite"),
        ));
    }
    if x.abs() > MAX_MAGNITUDE {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            format!("{name} = {x} exceeds ±{MAX_MAGNITUDE}"),
        ));
    }
    Ok(())
}

fn numbers(name: &str, xs: &[f64]) -> Result<(), ProtocolError> {
    xs.iter().try_for_each(|&x| number(name, x))
}

fn string(name: &str, s: &str) -> Result<(), ProtocolError> {
    if s.len() > MAX_STRING_BYTES {
        return Err(ProtocolError::new(
            ErrorCode::TooLarge,
            format!("{name} is {} bytes, limit {MAX_STRING_BYTES}", s.len()),
        ));
    }
    Ok(())
}

fn nonempty(name: &str, s: &str) -> Result<(), ProtocolError> {
    if s.trim().is_empty() {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            format!("{name} is empty"),
        ));
    }
    string(name, s)
}

/// A name shown to people and written to logs: no control characters.
fn name_text(name: &str, s: &str) -> Result<(), ProtocolError> {
    nonempty(name, s)?;
    if s.chars().any(char::is_control) {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            format!("{name} contains control characters"),
        ));
    }
    Ok(())
}

fn uv_curve(c: &UvCurve) -> Result<(), ProtocolError> {
    if c.points.len() > MAX_CURVE_POINTS || c.knots.knots.len() > MAX_KNOTS {
        return Err(ProtocolError::new(
            ErrorCode::TooLarge,
            "curve has too many points or knots",
        ));
    }
    if c.knots.degree < 1 || c.knots.degree > 7 {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            "curve degree must be 1..=7",
        ));
    }
    numbers("curve knot", &c.knots.knots)?;
    c.points.iter().try_for_each(|p| numbers("curve point", p))
}

fn anchor(a: &Anchor) -> Result<(), ProtocolError> {
    match a {
        Anchor::Point { u, v } => numbers("(u,v)", &[*u, *v]),
        Anchor::Curve { curve } => uv_curve(curve),
        Anchor::Region { u0, v0, u1, v1, .. } => numbers("region corner", &[*u0, *v0, *u1, *v1]),
    }
}

fn spec(s: &IconSpec) -> Result<(), ProtocolError> {
    anchor(&s.anchor)?;
    match &s.target {
        Some(t) => numbers("target", t),
        None => Ok(()),
    }
}

fn material(m: &Material) -> Result<(), ProtocolError> {
    let all = [
        m.alpha11, m.alpha12, m.alpha22, m.beta11, m.beta12, m.beta22,
    ];
    numbers("material", &all)?;
    if [m.alpha11, m.alpha22, m.beta11, m.beta12, m.beta22]
        .iter()
        .any(|&x| x < 0.0)
    {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            "α11, α22 and β must be ≥ 0",
        ));
    }
    Ok(())
}

impl ClientMessage {
    /// Checks everything that can be checked without the design.
    pub fn validate(&self) -> Result<(), ProtocolError> {
        use ClientMessage::*;
        match self {
            Hello {
                token, client_name, ..
            } => {
                string("token", token)?;
                string("client_name", client_name)
            }
            CreateDesign { name } => name_text("name", name),
            CreateIcon { spec: s } => spec(s),
            EditIcon { anchor: a, .. } => anchor(a),
            MoveIcon { xyz, .. } | Drag { xyz, .. } => numbers("xyz", xyz),
            BindSensor { sensor, .. } | UnbindSensor { sensor, .. } => nonempty("sensor", sensor),
            DeviceSample {
                sensor,
                position,
                orientation,
                flexion,
                ..
            } => {
                nonempty("sensor", sensor)?;
                numbers("position", position)?;
                numbers("orientation", orientation)?;
                let q = orientation.iter().map(|x| x * x).sum::<f64>().sqrt();
                if (q - 1.0).abs() > 1e-3 {
                    return Err(ProtocolError::new(
                        ErrorCode::OutOfRange,
                        format!("orientation is not a unit quaternion (|q| = {q})"),
                    ));
                }
                if let Some(f) = flexion {
                    if f.len() > MAX_FLEXION {
                        return Err(ProtocolError::new(
                            ErrorCode::TooLarge,
                            "too many flexion values",
                        ));
                    }
                    numbers("flexion", f)?;
                }
                Ok(())
            }
            DeviceStatus {
                device, message, ..
            } => {
                nonempty("device", device)?;
                string("message", message)
            }
            SetMaterial { material: m } => material(m),
            Commit { message } => string("message", message),
            Presence { pointer: Some(p) } => numbers("pointer", p),
            _ => Ok(()),
        }
    }
}
