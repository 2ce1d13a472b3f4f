//! Icon states (paper 003): driving, passive, sleeping.

/// What an icon does now.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum IconState {
    /// Bound to a sensor or pointer: moving it drives the deformation.
    Driving,
    /// Not bound: a constraint still holds; a load carries no force and
    /// follows the surface.
    Passive,
    /// Drawn grey, no effect; follows the surface.
    Sleeping,
}
