//! Rigid placement of a primitive: a rotation and a translation taking the
//! primitive's local frame to the world. Local coordinates are q = Rᵀ(p − t).

use super::error::DsmError;
use glam::{DMat3, DVec3};

/// A rigid transform (rotation R, translation t): world p = R q + t.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    rotation: DMat3,
    translation: DVec3,
}

impl Default for Placement {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Placement {
    /// The identity: local = world.
    pub const IDENTITY: Self = Self {
        rotation: DMat3::IDENTITY,
        translation: DVec3::ZERO,
    };

    /// A pure translation to `origin`.
    pub fn at(origin: DVec3) -> Self {
        Self {
            rotation: DMat3::IDENTITY,
            translation: origin,
        }
    }

    /// A rotation (orthonormal, determinant +1 to 1e-9) then a translation.
    pub fn new(rotation: DMat3, translation: DVec3) -> Result<Self, DsmError> {
        let rtr = rotation.transpose() * rotation;
        let off = (rtr - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        if !translation.is_finite()
            || off.is_nan()
            || off > 1e-9
            || (rotation.determinant() - 1.0).abs() > 1e-9
        {
            return Err(DsmError::BadPlacement);
        }
        Ok(Self {
            rotation,
            translation,
        })
    }

    /// The frame whose local z axis is `axis` (any length > 0) at `origin`; the
    /// local x axis is the unit vector most nearly perpendicular to `axis` among
    /// the world axes, made orthogonal.
    pub fn with_axis(origin: DVec3, axis: DVec3) -> Result<Self, DsmError> {
        let z = axis.try_normalize().ok_or(DsmError::BadPlacement)?;
        let x = z.any_orthonormal_vector();
        let y = z.cross(x);
        Self::new(DMat3::from_cols(x, y, z), origin)
    }

    /// The frame with local axes x, y (made orthonormal, z = x × y) at `origin`.
    pub fn with_axes(origin: DVec3, x: DVec3, y: DVec3) -> Result<Self, DsmError> {
        let x = x.try_normalize().ok_or(DsmError::BadPlacement)?;
        let y = (y - x * x.dot(y))
            .try_normalize()
            .ok_or(DsmError::BadPlacement)?;
        Self::new(DMat3::from_cols(x, y, x.cross(y)), origin)
    }

    /// The rotation R.
    pub fn rotation(&self) -> DMat3 {
        self.rotation
    }

    /// The translation t (the local origin in the world).
    pub fn translation(&self) -> DVec3 {
        self.translation
    }

    /// Local coordinates of a world point.
    #[inline]
    pub fn to_local(&self, p: DVec3) -> DVec3 {
        self.rotation.transpose() * (p - self.translation)
    }

    /// The world point of local coordinates.
    #[inline]
    pub fn to_world(&self, q: DVec3) -> DVec3 {
        self.rotation * q + self.translation
    }

    /// This placement moved by a world translation.
    pub fn translated(mut self, d: DVec3) -> Self {
        self.translation += d;
        self
    }
}
