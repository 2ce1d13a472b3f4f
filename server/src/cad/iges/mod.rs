//! IGES 5.3 exchange of B-spline surfaces (entity 128, "rational B-spline
//! surface"), curves (entity 126, "rational B-spline curve") and, written
//! only, surfaces trimmed to a polygon of their parameter space (entity
//! 144), the format designers' CAD tools read and write.
//!
//! The writer emits a fixed-format ASCII file: Start (S), Global (G),
//! Directory Entry (D, two 80-column records per entity), Parameter Data (P,
//! 64 data columns plus the back-pointer to the entity's D record) and
//! Terminate (T) sections, Hollerith strings (`5Hhello`), weights all 1 and
//! PROP3 = 1 (polynomial). Reals are written in Rust's shortest round-trip
//! form, so a write → read cycle reproduces every knot and control point
//! bit for bit. [`write_iges_parts`] writes one entity per part and names it
//! the way OpenCASCADE's own IGES writer does: a Name property (entity 406
//! form 15) referenced from the entity's parameter data, plus the first
//! eight characters as the directory entry's label.
//!
//! The reader accepts files from other tools: any parameter/record
//! delimiters declared in the Global section, `D` exponents, short (trimmed)
//! lines, CRLF, other entity types (skipped), an optional transformation
//! matrix (entity 124) applied to the control points, and rational entities
//! whose weights are all equal (equivalent to polynomial). Entities with
//! non-uniform weights are rejected with [`IgesError::RationalWeights`] or
//! [`IgesError::RationalCurve`], because the kernel's shapes are polynomial.
//! [`read_iges_parts`] explains which entities become parts and how they are
//! named.

mod curve;
mod format;
mod parse;
mod read;
mod surface;
mod trimmed;
mod write;

pub use curve::IgesCurve;
pub use format::{iges_text, iges_timestamp};
pub use read::{read_iges, read_iges_parts};
pub use surface::IgesSurface;
pub use trimmed::IgesTrimmed;
pub use write::{write_iges, write_iges_parts};

use thiserror::Error;

/// Why an IGES file could not be read (or a surface or curve written).
#[derive(Debug, Error, PartialEq)]
pub enum IgesError {
    /// The file is not fixed-format ASCII IGES (e.g. binary or compressed).
    #[error("not an ASCII IGES file: {0}")]
    NotIges(String),
    /// A section record is malformed.
    #[error("malformed IGES {section} section at line {line}: {reason}")]
    Malformed {
        /// Section letter.
        section: char,
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A parameter of an entity could not be parsed.
    #[error("entity at D{de}: {reason}")]
    BadParameter {
        /// The entity's directory-entry sequence number.
        de: usize,
        /// What is wrong.
        reason: String,
    },
    /// The file has no B-spline surface (entity 128).
    #[error("the file contains no B-spline surface (entity 128)")]
    NoSurface,
    /// The file has no B-spline surface (128) or curve (126) that is a part
    /// of its own, or there are no parts to write.
    #[error("no B-spline surface (entity 128) or curve (entity 126) parts")]
    NoParts,
    /// The surface is genuinely rational (weights not all equal).
    #[error(
        "entity at D{de} is a rational surface with non-uniform weights (min {min}, max {max}); only polynomial B-spline surfaces are supported"
    )]
    RationalWeights {
        /// The entity's directory-entry sequence number.
        de: usize,
        /// Smallest weight.
        min: f64,
        /// Largest weight.
        max: f64,
    },
    /// The curve is genuinely rational (weights not all equal).
    #[error(
        "entity at D{de} is a rational curve with non-uniform weights (min {min}, max {max}); only polynomial B-spline curves are supported"
    )]
    RationalCurve {
        /// The entity's directory-entry sequence number.
        de: usize,
        /// Smallest weight.
        min: f64,
        /// Largest weight.
        max: f64,
    },
    /// A knot or (transformed) control point is beyond [`MAX_IGES_MAGNITUDE`].
    #[error(
        "entity at D{de}: {what} {value:e} is beyond ±{MAX_IGES_MAGNITUDE:e}, the largest coordinate accepted"
    )]
    TooLarge {
        /// The entity's directory-entry sequence number.
        de: usize,
        /// Which kind of number ("knot" or "control point coordinate").
        what: &'static str,
        /// The offending value (may be infinite after a transformation).
        value: f64,
    },
    /// The surface to write is inconsistent.
    #[error("invalid surface: {0}")]
    InvalidSurface(String),
    /// The curve to write is inconsistent.
    #[error("invalid curve: {0}")]
    InvalidCurve(String),
}

/// Largest magnitude of a knot or control-point coordinate read from IGES:
/// the protocol's limit for any coordinate (`vsculpt_protocol::limits`), so
/// an imported surface can be solved, sent in f32 frames and exported.
pub const MAX_IGES_MAGNITUDE: f64 = vsculpt_protocol::limits::MAX_MAGNITUDE;

/// Highest degree read or written (the reader refuses more, so the writer
/// does too: what vsculpt writes it can read back).
pub const MAX_IGES_DEGREE: usize = 30;

/// Most control points of a surface or curve read or written.
pub const MAX_IGES_POINTS: usize = 1_000_000;

/// The geometry of one part: a surface (entity 128) or a curve (entity 126).
#[derive(Clone, Debug, PartialEq)]
pub enum IgesEntity {
    /// A polynomial B-spline surface.
    Surface(IgesSurface),
    /// A polynomial B-spline curve.
    Curve(IgesCurve),
    /// A surface trimmed to a polygon of its parameter space (written as
    /// entity 144; the reader gives its surface as [`IgesEntity::Surface`]).
    Trimmed(IgesTrimmed),
}

/// One part of a design as IGES carries it: its geometry and its name.
#[derive(Clone, Debug, PartialEq)]
pub struct IgesPart {
    /// The part's name, if the file gives one (see [`read_iges_parts`]);
    /// written as a Name property (406 form 15), printable ASCII only.
    pub name: Option<String>,
    /// The part's geometry.
    pub entity: IgesEntity,
}

/// Text for the Global section.
#[derive(Clone, Debug)]
pub struct IgesMeta {
    /// Product / file name.
    pub name: String,
    /// Author.
    pub author: String,
    /// Time of writing as `YYYYMMDD.HHNNSS`.
    pub timestamp: String,
}

impl IgesMeta {
    /// Metadata stamped with the current UTC time.
    pub fn now(name: &str, author: &str) -> Self {
        Self {
            name: name.to_string(),
            author: author.to_string(),
            timestamp: iges_timestamp(std::time::SystemTime::now()),
        }
    }
}
