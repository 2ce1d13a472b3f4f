//! Starter designs: the demo (a bicubic 16 × 12 mouse-shell-like dome with
//! two position constraints, a load and a normal constraint) created on
//! first start, and the flat plate new designs begin from.

use super::doc::{
    AnchorDoc, DOC_FORMAT, DesignDoc, IconDoc, IconRoleDoc, IconStateDoc, MaterialDoc, SurfaceDoc,
};
use super::edit::SurfaceQuery;
use super::engine::Engine;
use super::error::{CommandError, ErrorKind};
use vsculpt_kernel::bspline::{KnotVector, greville, interpolate_surface};

fn kernel(e: impl std::fmt::Display) -> CommandError {
    CommandError::new(ErrorKind::InvalidValue, e.to_string())
}

/// A bicubic surface with clamped uniform knots whose control points are
/// `f` at the Greville abscissae (so a smooth `f` gives a smooth surface
/// close to it).
fn surface_from(
    nu: usize,
    nv: usize,
    f: impl Fn(f64, f64) -> [f64; 3],
) -> Result<SurfaceDoc, CommandError> {
    let ku = KnotVector::clamped_uniform(3, nu).map_err(kernel)?;
    let kv = KnotVector::clamped_uniform(3, nv).map_err(kernel)?;
    let (gu, gv) = (greville(&ku), greville(&kv));
    let mut points = Vec::with_capacity(nu * nv);
    for &s in &gu {
        for &t in &gv {
            points.push(f(s, t));
        }
    }
    Ok(SurfaceDoc {
        u_degree: 3,
        v_degree: 3,
        u_knots: ku.knots().to_vec(),
        v_knots: kv.knots().to_vec(),
        nu,
        nv,
        points,
    })
}

/// Checks a new design's name: 1 to 200 bytes after trimming, no control
/// characters (a name is printed in the start banner and in logs, where a
/// line break would forge a line).
pub fn check_name(name: &str) -> Result<(), CommandError> {
    let name = name.trim();
    if name.is_empty() || name.len() > 200 {
        return Err(CommandError::new(
            ErrorKind::InvalidValue,
            "a design name has 1 to 200 bytes",
        ));
    }
    if name.chars().any(char::is_control) {
        return Err(CommandError::new(
            ErrorKind::InvalidValue,
            "a design name may not contain control characters (line breaks, tabs, escapes)",
        ));
    }
    Ok(())
}

/// A flat `nu × nv` bicubic plate, 100 × 100 (model units: mm), no icons.
pub fn plate(name: &str, nu: usize, nv: usize) -> Result<DesignDoc, CommandError> {
    let surface = surface_from(nu, nv, |s, t| [100.0 * s - 50.0, 100.0 * t - 50.0, 0.0])?;
    Ok(DesignDoc {
        format: DOC_FORMAT,
        name: name.to_string(),
        surface,
        material: MaterialDoc::default(),
        icons: Vec::new(),
        next_icon: 1,
        kappa: None,
    })
}

/// The height of the mouse shell over the unit square: an elliptic dome,
/// higher towards the palm (s → 1), flattening into a skirt at the rim.
fn shell_height(s: f64, t: f64) -> f64 {
    let x = 2.0 * s - 1.0;
    let y = 2.0 * t - 1.0;
    let r2 = (x * x + y * y * 1.15).min(1.0);
    let dome = (1.0 - r2).powf(0.8);
    38.0 * dome * (0.8 + 0.25 * s)
}

/// The demo design: a 16 × 12 bicubic mouse shell, 120 × 70 mm, with two
/// position constraints (front and back), a load on the palm rest and a
/// normal constraint on the button area. The surface interpolates a
/// 16 × 12 grid of points on the shell (kernel `interpolate_surface`).
pub fn demo() -> Result<DesignDoc, CommandError> {
    let (m, n) = (16, 12);
    let mut grid = Vec::with_capacity(m * n);
    for k in 0..m {
        for l in 0..n {
            let (s, t) = (k as f64 / (m - 1) as f64, l as f64 / (n - 1) as f64);
            grid.push(glam::DVec3::new(
                120.0 * s - 60.0,
                70.0 * t - 35.0,
                shell_height(s, t),
            ));
        }
    }
    let fitted = interpolate_surface(&grid, m, n, 3, 3).map_err(kernel)?;
    let surface = SurfaceDoc {
        u_degree: 3,
        v_degree: 3,
        u_knots: fitted.u_knots().knots().to_vec(),
        v_knots: fitted.v_knots().knots().to_vec(),
        nu: fitted.nu(),
        nv: fitted.nv(),
        points: fitted.points().iter().map(|p| p.to_array()).collect(),
    };
    let mut doc = DesignDoc {
        format: DOC_FORMAT,
        name: "demo".into(),
        surface,
        material: MaterialDoc::default(),
        icons: Vec::new(),
        next_icon: 1,
        kappa: None,
    };
    let engine = Engine::build_unsolved(&doc)?;
    let icons = [
        (AnchorDoc::Point { u: 0.12, v: 0.5 }, IconRoleDoc::Position),
        (AnchorDoc::Point { u: 0.88, v: 0.5 }, IconRoleDoc::Position),
        (AnchorDoc::Point { u: 0.62, v: 0.5 }, IconRoleDoc::Load),
        (AnchorDoc::Point { u: 0.3, v: 0.35 }, IconRoleDoc::Normal),
    ];
    for (anchor, role) in icons {
        let id = doc.next_icon;
        doc.next_icon += 1;
        doc.icons.push(IconDoc {
            id,
            xyz: engine.point_at(&anchor),
            target: engine.current_target(&anchor, role),
            anchor,
            role,
            state: IconStateDoc::Passive,
            sensors: Vec::new(),
        });
    }
    doc.validate()?;
    Ok(doc)
}
