//! What a viewer draws of a body (paper 002 §2.1): the shaded boundary and
//! isoparametric surfaces at constant u, v and w.
//!
//! Every surface is exact ([`BSplineVolume::iso_surface`]) and tessellated
//! by the surface tessellator of [`crate::analysis`] (positions, normals,
//! curvature). Boundary faces are oriented outward when det J > 0: the
//! natural normal of the face at u = end is x_v × x_w, which points along
//! x_u, so the faces u = start, v = end and w = start are flipped
//! (reversed triangles, negated normals). A [`BodyDisplay`] keeps its
//! tessellators and buffers and refills them in place per frame.

use super::{BSplineVolume, Dir, Face};
use crate::analysis::{Tessellation, Tessellator};

/// The interior parameters of `count` isoparametric surfaces in `dir`,
/// evenly spaced strictly inside the domain.
pub fn iso_parameters(vol: &BSplineVolume, dir: Dir, count: usize) -> Vec<f64> {
    let (a, b) = vol.knots(dir).domain();
    (1..=count)
        .map(|k| a + (b - a) * k as f64 / (count + 1) as f64)
        .collect()
}

fn flipped(face: Face) -> bool {
    match face.dir {
        Dir::U | Dir::W => !face.end,
        Dir::V => face.end,
    }
}

fn flip(t: &mut Tessellation) {
    for tri in t.indices.chunks_exact_mut(3) {
        tri.swap(1, 2);
    }
    for n in &mut t.normals {
        *n = [-n[0], -n[1], -n[2]];
    }
}

/// Tessellations of a body's six faces and its isoparametric surfaces,
/// refilled in place.
pub struct BodyDisplay {
    per_dir: usize,
    samples: usize,
    tess: [Option<Tessellator>; 3],
    /// The six boundary faces, in [`Face::ALL`] order, outward.
    pub faces: Vec<Tessellation>,
    /// Isoparametric surfaces: (direction, parameter, mesh), `per_dir` per
    /// direction.
    pub iso: Vec<(Dir, f64, Tessellation)>,
}

impl BodyDisplay {
    /// A display with `per_dir` isoparametric surfaces per direction and
    /// `samples × samples` vertices per surface (at least 2).
    pub fn new(per_dir: usize, samples: usize) -> Self {
        Self {
            per_dir,
            samples: samples.max(2),
            tess: [None, None, None],
            faces: Vec::new(),
            iso: Vec::new(),
        }
    }

    /// Re-evaluates everything for `vol`.
    pub fn update(&mut self, vol: &BSplineVolume) {
        self.faces.resize_with(6, Tessellation::default);
        let n_iso = 3 * self.per_dir;
        self.iso
            .resize_with(n_iso, || (Dir::U, 0.0, Tessellation::default()));
        for (f, face) in Face::ALL.iter().enumerate() {
            let s = vol.face(*face);
            let t = self.tess[face.dir.index()]
                .get_or_insert_with(|| Tessellator::new(&s, self.samples, self.samples));
            t.fill(&s, &mut self.faces[f]);
            if flipped(*face) {
                flip(&mut self.faces[f]);
            }
        }
        let mut slot = 0;
        for dir in Dir::ALL {
            for t in iso_parameters(vol, dir, self.per_dir) {
                let s = vol.iso_surface(dir, t);
                let tess = self.tess[dir.index()]
                    .get_or_insert_with(|| Tessellator::new(&s, self.samples, self.samples));
                let entry = &mut self.iso[slot];
                entry.0 = dir;
                entry.1 = t;
                tess.fill(&s, &mut entry.2);
                slot += 1;
            }
        }
    }
}
