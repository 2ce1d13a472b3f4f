//! Validation of client messages: every number finite and of sane
//! magnitude, every string and array within its limit. The server checks
//! what needs the design (ids, the (u,v) domain) itself.

use crate::client::ClientMessage;
use crate::error::{ErrorCode, ProtocolError};
use crate::limits::*;
use crate::parts::{CurveData, PartMaterial, PartShape, PartSpec, is_colour};
use crate::types::{Anchor, Camera, IconSpec, Knots, Material, SurfaceData, UvCurve};

/// A finite number within ±[`MAX_MAGNITUDE`], or `not_finite` /
/// `out_of_range` naming `name`.
pub(crate) fn number(name: &str, x: f64) -> Result<(), ProtocolError> {
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
        Anchor::Edge { .. } => Ok(()),
        Anchor::Param { t } => number("t", *t),
        Anchor::Span { t0, t1 } => numbers("span", &[*t0, *t1]),
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

fn part_material(m: &PartMaterial) -> Result<(), ProtocolError> {
    match m {
        PartMaterial::Surface(m) => material(m),
        PartMaterial::Curve(c) => {
            numbers("material", &[c.alpha, c.beta])?;
            if c.alpha < 0.0 || c.beta < 0.0 {
                return Err(ProtocolError::new(
                    ErrorCode::OutOfRange,
                    "α and β must be ≥ 0",
                ));
            }
            Ok(())
        }
    }
}

fn knots(k: &Knots, points: usize) -> Result<(), ProtocolError> {
    if k.knots.len() > MAX_KNOTS {
        return Err(ProtocolError::new(ErrorCode::TooLarge, "too many knots"));
    }
    if k.degree < 1 || k.degree > 7 {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            "degree must be 1..=7",
        ));
    }
    numbers("knot", &k.knots)?;
    if k.knots.len() != points + k.degree as usize + 1 {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            "knot count must be control points + degree + 1",
        ));
    }
    if k.knots.windows(2).any(|w| w[1] < w[0]) {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            "knots must not decrease",
        ));
    }
    Ok(())
}

fn surface(s: &SurfaceData) -> Result<(), ProtocolError> {
    if s.nu as usize > MAX_GRID || s.nv as usize > MAX_GRID {
        return Err(ProtocolError::new(
            ErrorCode::TooLarge,
            "control grid too large",
        ));
    }
    if s.points.len() != s.nu as usize * s.nv as usize {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            "control point count must be nu · nv",
        ));
    }
    knots(&s.u, s.nu as usize)?;
    knots(&s.v, s.nv as usize)?;
    s.points
        .iter()
        .try_for_each(|p| numbers("control point", p))
}

fn curve(c: &CurveData) -> Result<(), ProtocolError> {
    if c.points.len() > MAX_KNOTS {
        return Err(ProtocolError::new(
            ErrorCode::TooLarge,
            "too many control points",
        ));
    }
    knots(&c.knots, c.points.len())?;
    c.points
        .iter()
        .try_for_each(|p| numbers("control point", p))
}

fn colour(c: &str) -> Result<(), ProtocolError> {
    if !is_colour(c) {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            "colour must be #rrggbb",
        ));
    }
    Ok(())
}

fn part_spec(p: &PartSpec) -> Result<(), ProtocolError> {
    name_text("name", &p.name)?;
    match &p.shape {
        PartShape::Surface { surface: s } => surface(s)?,
        PartShape::Curve { curve: c } => curve(c)?,
        PartShape::Dsm { dsm } => dsm.validate()?,
        PartShape::Network { network } => network.validate()?,
        PartShape::Body { body } => body.validate()?,
    }
    if let Some(m) = &p.material {
        part_material(m)?;
        if let PartShape::Body { .. } = &p.shape {
            return Err(ProtocolError::new(
                ErrorCode::OutOfRange,
                "a body part has no material",
            ));
        }
        let fits = matches!(
            (&p.shape, m),
            (PartShape::Surface { .. }, PartMaterial::Surface(_))
                | (PartShape::Curve { .. }, PartMaterial::Curve(_))
        );
        if !fits {
            return Err(ProtocolError::new(
                ErrorCode::OutOfRange,
                "the material does not fit the part's kind",
            ));
        }
    }
    p.colour.as_deref().map_or(Ok(()), colour)
}

/// A view camera: finite, its eye away from its target, its field of view
/// an angle a camera can have.
fn view_camera(c: &Camera) -> Result<(), ProtocolError> {
    numbers("camera.eye", &c.eye)?;
    numbers("camera.target", &c.target)?;
    number("camera.fov", c.fov)?;
    let d: f64 = (0..3).map(|i| (c.eye[i] - c.target[i]).powi(2)).sum();
    if d.sqrt() <= 1e-9 * (1.0 + c.eye.iter().fold(0.0f64, |m, x| m.max(x.abs()))) {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            "camera.eye is at camera.target",
        ));
    }
    if !(c.fov > 0.0 && c.fov < 180.0) {
        return Err(ProtocolError::new(
            ErrorCode::OutOfRange,
            format!("camera.fov = {} is not in (0, 180) degrees", c.fov),
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
            CreateIcon { spec: s, .. } => spec(s),
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
            SetMaterial { material: m, .. } => part_material(m),
            CreatePart { spec } => part_spec(spec),
            DsmEdit { edit, .. } => edit.validate(),
            NetworkEdit { edit, .. } => edit.validate(),
            BodyEdit { edit, .. } => edit.validate(),
            BodyMorph { t, .. } => crate::body::validate_morph_time(*t),
            Relate {
                relation: crate::parts::RelationSpec::Binding { line, .. },
            } => match line {
                crate::parts::IsoLine::U(x) | crate::parts::IsoLine::V(x) => number("line", *x),
            },
            SetPart {
                name, colour: c, ..
            } => {
                if let Some(n) = name {
                    name_text("name", n)?;
                }
                c.as_deref().map_or(Ok(()), colour)
            }
            Commit { message } => string("message", message),
            AddComment { anchor, text, .. } => {
                anchor.validate()?;
                crate::comment::validate_text(text)
            }
            ReplyComment { text, .. } | EditComment { text, .. } => {
                crate::comment::validate_text(text)
            }
            Presence { pointer, camera } => {
                if let Some(p) = pointer {
                    numbers("pointer", p)?;
                }
                camera.as_ref().map_or(Ok(()), view_camera)
            }
            _ => Ok(()),
        }
    }
}
