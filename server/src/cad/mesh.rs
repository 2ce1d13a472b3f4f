//! The triangle mesh every mesh exporter (OBJ, STL, glTF) takes: positions,
//! normals and indices as produced by the kernel's tessellation, validated
//! once here so each writer can index without checks.

use thiserror::Error;

/// Why a mesh cannot be exported.
#[derive(Debug, Error, PartialEq)]
pub enum MeshError {
    /// `normals` and `positions` differ in length.
    #[error("mesh has {positions} positions but {normals} normals")]
    NormalCount {
        /// Number of positions.
        positions: usize,
        /// Number of normals.
        normals: usize,
    },
    /// The index count is not a multiple of three.
    #[error("mesh index count {0} is not a multiple of 3")]
    NotTriangles(usize),
    /// An index points past the vertex list.
    #[error("mesh index {index} out of range for {vertices} vertices")]
    IndexOutOfRange {
        /// The bad index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("mesh has a non-finite coordinate")]
    NonFinite,
}

/// A validated indexed triangle mesh borrowed from a tessellation.
#[derive(Clone, Copy, Debug)]
pub struct Mesh<'a> {
    positions: &'a [[f32; 3]],
    normals: &'a [[f32; 3]],
    indices: &'a [u32],
}

impl<'a> Mesh<'a> {
    /// Checks that normals match positions, indices form triangles and stay in
    /// range, and every coordinate is finite.
    pub fn new(
        positions: &'a [[f32; 3]],
        normals: &'a [[f32; 3]],
        indices: &'a [u32],
    ) -> Result<Self, MeshError> {
        if positions.len() != normals.len() {
            return Err(MeshError::NormalCount {
                positions: positions.len(),
                normals: normals.len(),
            });
        }
        if !indices.len().is_multiple_of(3) {
            return Err(MeshError::NotTriangles(indices.len()));
        }
        if let Some(&index) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(MeshError::IndexOutOfRange {
                index,
                vertices: positions.len(),
            });
        }
        let finite = |v: &[f32; 3]| v.iter().all(|c| c.is_finite());
        if !positions.iter().all(finite) || !normals.iter().all(finite) {
            return Err(MeshError::NonFinite);
        }
        Ok(Self {
            positions,
            normals,
            indices,
        })
    }

    /// Vertex positions.
    pub fn positions(&self) -> &'a [[f32; 3]] {
        self.positions
    }

    /// Unit vertex normals, one per position.
    pub fn normals(&self) -> &'a [[f32; 3]] {
        self.normals
    }

    /// Triangle vertex indices, three per triangle.
    pub fn indices(&self) -> &'a [u32] {
        self.indices
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The three corner positions of triangle `t`.
    pub fn triangle(&self, t: usize) -> [[f32; 3]; 3] {
        let i = &self.indices[3 * t..3 * t + 3];
        [
            self.positions[i[0] as usize],
            self.positions[i[1] as usize],
            self.positions[i[2] as usize],
        ]
    }
}
