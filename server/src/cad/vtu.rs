//! The VTK XML unstructured grid (`.vtu`, VTK file format version 1.0,
//! ASCII): hexahedral cells (VTK type 12) with a point scalar, as ParaView,
//! `meshio` and other VTK readers take it — a Coons body's interior as
//! simulation input (paper 002).

use std::io::{self, Write};

/// VTK's cell type number of an 8-node hexahedron.
pub const VTK_HEXAHEDRON: u8 = 12;

/// A hexahedral mesh: points, cells of 8 point indices in VTK's order
/// (bottom face counter-clockwise, then the top face above it), and one
/// scalar per point.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HexGrid {
    /// Point positions.
    pub points: Vec<[f64; 3]>,
    /// Cells, 8 point indices each.
    pub cells: Vec<[u64; 8]>,
    /// The scalar's name.
    pub scalar_name: String,
    /// One value per point.
    pub scalar: Vec<f64>,
}

/// Why a grid cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum VtuError {
    /// A cell names a point that is not there, or the scalar's size is wrong.
    #[error("invalid grid: {0}")]
    Invalid(String),
    /// A coordinate or value is NaN or infinite.
    #[error("grid has a non-finite number")]
    NotFinite,
}

impl HexGrid {
    /// Checks indices, sizes and finiteness.
    pub fn check(&self) -> Result<(), VtuError> {
        let n = self.points.len() as u64;
        if self.cells.iter().flatten().any(|&i| i >= n) {
            return Err(VtuError::Invalid("a cell names a missing point".into()));
        }
        if self.scalar.len() != self.points.len() {
            return Err(VtuError::Invalid(
                "the scalar needs one value per point".into(),
            ));
        }
        let finite = self.points.iter().flatten().all(|x| x.is_finite())
            && self.scalar.iter().all(|x| x.is_finite());
        if !finite {
            return Err(VtuError::NotFinite);
        }
        if self.scalar_name.is_empty()
            || !self
                .scalar_name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_')
        {
            return Err(VtuError::Invalid(
                "the scalar's name is letters, digits and _".into(),
            ));
        }
        Ok(())
    }

    /// Appends `other`, its indices shifted.
    pub fn append(&mut self, other: &HexGrid) {
        let base = self.points.len() as u64;
        self.points.extend_from_slice(&other.points);
        self.scalar.extend_from_slice(&other.scalar);
        self.cells
            .extend(other.cells.iter().map(|c| c.map(|i| i + base)));
    }
}

/// Writes `grid` as a `.vtu` file (call [`HexGrid::check`] first; an
/// unchecked grid may give a file readers refuse).
pub fn write_vtu_to(grid: &HexGrid, out: &mut impl Write) -> io::Result<()> {
    writeln!(out, "<?xml version=\"1.0\"?>")?;
    writeln!(
        out,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(out, "<UnstructuredGrid>")?;
    writeln!(
        out,
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        grid.points.len(),
        grid.cells.len()
    )?;
    writeln!(out, "<PointData Scalars=\"{}\">", grid.scalar_name)?;
    writeln!(
        out,
        "<DataArray type=\"Float64\" Name=\"{}\" format=\"ascii\">",
        grid.scalar_name
    )?;
    for x in &grid.scalar {
        writeln!(out, "{x}")?;
    }
    writeln!(out, "</DataArray>\n</PointData>")?;
    writeln!(
        out,
        "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
    )?;
    for p in &grid.points {
        writeln!(out, "{} {} {}", p[0], p[1], p[2])?;
    }
    writeln!(out, "</DataArray>\n</Points>\n<Cells>")?;
    writeln!(
        out,
        "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    )?;
    for c in &grid.cells {
        let s: Vec<String> = c.iter().map(u64::to_string).collect();
        writeln!(out, "{}", s.join(" "))?;
    }
    writeln!(out, "</DataArray>")?;
    writeln!(
        out,
        "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">"
    )?;
    for k in 1..=grid.cells.len() {
        writeln!(out, "{}", 8 * k)?;
    }
    writeln!(out, "</DataArray>")?;
    writeln!(
        out,
        "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">"
    )?;
    for _ in &grid.cells {
        writeln!(out, "{VTK_HEXAHEDRON}")?;
    }
    writeln!(
        out,
        "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>"
    )
}
