//! A curve network: styling curves (B-spline curves, as sculpted by
//! [`crate::curve_design::CurveDesign`]), their meetings, faces, ribbons and
//! handles, and one patch per face.
//!
//! Edits are values-in, result-out: [`CurveNetwork::set_curve`] re-tracks
//! every meeting of the changed curve from its previous parameters
//! (closest-point refinement); a meeting that no longer closes within the
//! tolerance is [`NetworkError::LostIntersection`], and any other refusal
//! (an open or self-intersecting face) also leaves the network unchanged.
//! Only the changed curve's pairs are searched again. When the faces keep
//! their structure (same curves around the same faces) the handles are
//! kept; otherwise the faces are re-derived and the handles reset.

use glam::DVec3;

use super::error::NetworkError;
use super::intersect::{CurveHit, intersections, refine};
use super::patch::Patch;
use super::ribbon::{NormalPiece, SideRibbon};
use super::topology::{Face, Topology, check_simple};
use crate::bspline::BSplineCurve;

/// How a network finds its meetings and orients its faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NetworkOptions {
    /// Curves closer than this meet (model units).
    pub tolerance: f64,
    /// The side the normals face (seed of the consistent orientation).
    pub up: DVec3,
}

impl Default for NetworkOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-6,
            up: DVec3::Z,
        }
    }
}

/// What an edit did to the faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Update {
    /// Same faces, moved; handles kept.
    Moved,
    /// The faces changed; handles reset to their defaults.
    Rebuilt,
}

/// A network of styling curves and the faces they bound.
#[derive(Clone, Debug)]
pub struct CurveNetwork {
    curves: Vec<BSplineCurve>,
    options: NetworkOptions,
    hits: Vec<Vec<Vec<CurveHit>>>,
    topo: Topology,
    twists: Vec<f64>,
    scales: Vec<Vec<f64>>,
    tuning: Vec<Vec<DVec3>>,
}

/// The faces' structure: the curve sequence around each face.
fn signature(t: &Topology) -> Vec<Vec<(usize, usize)>> {
    t.faces
        .iter()
        .map(|f| f.sides.iter().map(|s| (s.curve, s.edges.len())).collect())
        .collect()
}

impl CurveNetwork {
    /// The network of `curves`: meetings, faces, default handles.
    pub fn new(curves: Vec<BSplineCurve>, options: NetworkOptions) -> Result<Self, NetworkError> {
        if !options.up.is_finite() || options.up == DVec3::ZERO {
            return Err(NetworkError::BadValue(
                "up must be a finite non-zero vector".into(),
            ));
        }
        let hits = Topology::pair_hits(&curves, options.tolerance)?;
        let topo = Topology::build(&curves, &hits, options.tolerance, options.up)?;
        let mut net = Self {
            curves,
            options,
            hits,
            topo,
            twists: Vec::new(),
            scales: Vec::new(),
            tuning: Vec::new(),
        };
        net.reset_handles();
        Ok(net)
    }

    fn reset_handles(&mut self) {
        self.twists = vec![0.0; self.topo.edges.len()];
        self.scales = self
            .topo
            .faces
            .iter()
            .map(|f| vec![1.0; f.sides.len()])
            .collect();
        self.tuning = self
            .topo
            .faces
            .iter()
            .map(|f| vec![DVec3::ZERO; f.sides.len() + 1])
            .collect();
    }

    /// The curves.
    pub fn curves(&self) -> &[BSplineCurve] {
        &self.curves
    }

    /// The options.
    pub fn options(&self) -> &NetworkOptions {
        &self.options
    }

    /// Vertices, edges and faces.
    pub fn topology(&self) -> &Topology {
        &self.topo
    }

    /// The faces.
    pub fn faces(&self) -> &[Face] {
        &self.topo.faces
    }

    /// Replaces curve `index` (e.g. after a drag on its curve design),
    /// keeping the meetings it had. Refused edits change nothing.
    pub fn set_curve(&mut self, index: usize, curve: BSplineCurve) -> Result<Update, NetworkError> {
        if index >= self.curves.len() {
            return Err(NetworkError::Unknown {
                what: "curve",
                index,
            });
        }
        let tol = self.options.tolerance;
        check_simple(&curve, index, tol)?;
        // Track every meeting of this curve.
        for v in &self.topo.vertices {
            let Some(&(_, ti)) = v.incidences.iter().find(|(c, _)| *c == index) else {
                continue;
            };
            for &(j, tj) in v.incidences.iter().filter(|(c, _)| *c != index) {
                let h = refine(&curve, &self.curves[j], ti, tj);
                if h.gap > tol {
                    return Err(NetworkError::LostIntersection {
                        a: index,
                        b: j,
                        gap: h.gap,
                        tolerance: tol,
                    });
                }
            }
        }
        let mut curves = self.curves.clone();
        curves[index] = curve;
        let mut hits = self.hits.clone();
        for j in 0..curves.len() {
            if j == index {
                continue;
            }
            let (a, b) = (index.min(j), index.max(j));
            hits[a][b] = intersections(&curves[a], &curves[b], tol);
        }
        let topo = Topology::build(&curves, &hits, tol, self.options.up)?;
        let same =
            signature(&topo) == signature(&self.topo) && topo.edges.len() == self.topo.edges.len();
        self.curves = curves;
        self.hits = hits;
        self.topo = topo;
        if same {
            Ok(Update::Moved)
        } else {
            self.reset_handles();
            Ok(Update::Rebuilt)
        }
    }

    fn face_index(&self, face: usize) -> Result<&Face, NetworkError> {
        self.topo.faces.get(face).ok_or(NetworkError::Unknown {
            what: "face",
            index: face,
        })
    }

    /// The twist handle of an edge (radians at its middle).
    pub fn twist(&self, edge: usize) -> Option<f64> {
        self.twists.get(edge).copied()
    }

    /// Sets an edge's twist handle: the tangent plane along the edge turns
    /// about the curve by `radians`·sin(πu) (both faces on it follow).
    pub fn set_twist(&mut self, edge: usize, radians: f64) -> Result<(), NetworkError> {
        if !radians.is_finite() || radians.abs() >= std::f64::consts::FRAC_PI_2 {
            return Err(NetworkError::BadValue(format!(
                "twist {radians} (must be finite, |twist| < π/2)"
            )));
        }
        let slot = self.twists.get_mut(edge).ok_or(NetworkError::Unknown {
            what: "edge",
            index: edge,
        })?;
        *slot = radians;
        Ok(())
    }

    /// The scale handle of side `side` of `face`.
    pub fn scale(&self, face: usize, side: usize) -> Option<f64> {
        self.scales.get(face)?.get(side).copied()
    }

    /// Sets a side's scale handle (> 0): the cross-boundary derivative's
    /// length is multiplied by 1 + (scale − 1) sin(πs) along the side.
    pub fn set_scale(&mut self, face: usize, side: usize, scale: f64) -> Result<(), NetworkError> {
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(NetworkError::BadValue(format!(
                "scale {scale} (must be > 0)"
            )));
        }
        self.face_index(face)?;
        let slot = self.scales[face]
            .get_mut(side)
            .ok_or(NetworkError::Unknown {
                what: "side",
                index: side,
            })?;
        *slot = scale;
        Ok(())
    }

    /// The tuning handles of a face: centre, then one per corner.
    pub fn tuning(&self, face: usize) -> Option<&[DVec3]> {
        self.tuning.get(face).map(|v| v.as_slice())
    }

    /// Sets a face's tuning handles (sides + 1 finite vectors).
    pub fn set_tuning(&mut self, face: usize, handles: Vec<DVec3>) -> Result<(), NetworkError> {
        let n = self.face_index(face)?.sides.len();
        if handles.len() != n + 1 || handles.iter().any(|h| !h.is_finite()) {
            return Err(NetworkError::BadValue(format!(
                "face {face} needs {} finite tuning vectors",
                n + 1
            )));
        }
        self.tuning[face] = handles;
        Ok(())
    }

    /// The patch of `face`.
    pub fn patch(&self, face: usize) -> Result<Patch, NetworkError> {
        let f = self.face_index(face)?;
        let mut ribbons: Vec<SideRibbon> = f
            .sides
            .iter()
            .enumerate()
            .map(|(k, s)| {
                let mut pieces: Vec<NormalPiece> = s
                    .edges
                    .iter()
                    .map(|&e| {
                        let edge = &self.topo.edges[e];
                        NormalPiece::new(
                            &self.curves[edge.curve],
                            edge.t0,
                            edge.t1,
                            self.topo.vertices[edge.v0].normal,
                            self.topo.vertices[edge.v1].normal,
                            self.twists[e],
                        )
                    })
                    .collect();
                pieces.sort_by(|a, b| a.t0.total_cmp(&b.t0));
                SideRibbon {
                    curve: self.curves[s.curve].clone(),
                    t_start: s.t_start,
                    t_end: s.t_end,
                    pieces,
                    a: [0.0; 2],
                    b: [0.0; 2],
                    scale: self.scales[face][k],
                }
            })
            .collect();
        let n = ribbons.len();
        for k in 0..n {
            let d0 = -ribbons[(k + n - 1) % n].tangent(1.0);
            let d1 = ribbons[(k + 1) % n].tangent(0.0);
            ribbons[k].set_corners(d0, d1);
        }
        let mut p = Patch::new(ribbons);
        p.set_tuning(self.tuning[face].clone());
        Ok(p)
    }

    /// Every face's patch.
    pub fn patches(&self) -> Vec<Patch> {
        (0..self.topo.faces.len())
            .map(|f| self.patch(f).expect("face index in range"))
            .collect()
    }
}
