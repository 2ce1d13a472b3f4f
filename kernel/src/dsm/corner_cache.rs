//! Φ samples at grid corners kept for one meshing run: a sparse grid of 4³-corner
//! blocks, allocated where the mesher samples (near the surface), so a corner
//! shared by several octree nodes or check lattices is sampled once. The
//! blocks are found through a dense table over the grid when it has at most
//! 2²⁴ blocks (grids up to 1024 cells a side), else through a hash map.
//!
//! A sample is stored as Φ alone: its sign bit is the membership (Φ is +d
//! inside and −d outside with d ≥ 0, so +0 and −0 on the boundary itself keep
//! it, [`super::model::Sample`]); NaN marks a corner not sampled.

use super::model::Sample;
use glam::IVec3;
use std::collections::HashMap;

/// Corners per block axis.
const B: i32 = 4;

/// The sampled corners of one run.
pub(crate) struct CornerCache {
    /// Blocks per axis of the dense table (0: the hash map is used).
    nb: IVec3,
    /// Dense block table: first index of the block in `pool`, or u32::MAX.
    table: Vec<u32>,
    /// The table entries set in this run (cleared by [`Self::reset`]).
    touched: Vec<u32>,
    /// Block key → first index of the block in `pool` (grids too large for
    /// the table).
    blocks: HashMap<u64, u32>,
    /// The last block looked up (key, first index): most lookups are within it.
    last: Option<(u64, u32)>,
    pool: Vec<f64>,
    count: usize,
}

impl CornerCache {
    /// A cache for the corners 0 ..= `max` of a grid.
    pub(crate) fn new(max: IVec3) -> Self {
        let nb = max / B + IVec3::ONE;
        let n = nb.x as u64 * nb.y as u64 * nb.z as u64;
        let dense = n <= 1 << 24;
        Self {
            nb: if dense { nb } else { IVec3::ZERO },
            table: if dense {
                vec![u32::MAX; n as usize]
            } else {
                Vec::new()
            },
            touched: Vec::new(),
            blocks: HashMap::new(),
            last: None,
            pool: Vec::new(),
            count: 0,
        }
    }

    /// Empties the cache for a grid of corners 0 ..= `max`, keeping its
    /// memory: a cache kept between runs (one per thread) takes no page
    /// faults once warm.
    pub(crate) fn reset(&mut self, max: IVec3) {
        if self.nb.x > 0 && max / B + IVec3::ONE == self.nb {
            for &i in &self.touched {
                self.table[i as usize] = u32::MAX;
            }
            self.touched.clear();
        } else {
            let pool = std::mem::take(&mut self.pool);
            *self = Self::new(max);
            self.pool = pool;
        }
        self.blocks.clear();
        self.pool.clear();
        self.last = None;
        self.count = 0;
    }

    /// The block key and the index within the block of corner c (coordinates
    /// non-negative, below 2²¹).
    fn split(c: IVec3) -> (u64, usize) {
        let b = c / B;
        let l = c - b * B;
        (
            (b.x as u64) | ((b.y as u64) << 21) | ((b.z as u64) << 42),
            ((l.z * B + l.y) * B + l.x) as usize,
        )
    }

    fn block(&mut self, k: u64, create: bool) -> Option<u32> {
        if let Some((lk, at)) = self.last
            && lk == k
        {
            return Some(at);
        }
        let slot = if self.nb.x > 0 {
            let (x, y, z) = (k & 0x1f_ffff, (k >> 21) & 0x1f_ffff, k >> 42);
            let nb = self.nb.as_u64vec3();
            if x >= nb.x || y >= nb.y || z >= nb.z {
                return None;
            }
            Some(((z * nb.y + y) * nb.x + x) as usize)
        } else {
            None
        };
        let found = match slot {
            Some(i) => Some(self.table[i]).filter(|&at| at != u32::MAX),
            None => self.blocks.get(&k).copied(),
        };
        let at = match found {
            Some(at) => at,
            None if create => {
                let at = self.pool.len() as u32;
                self.pool
                    .resize(self.pool.len() + (B * B * B) as usize, f64::NAN);
                match slot {
                    Some(i) => {
                        self.table[i] = at;
                        self.touched.push(i as u32);
                    }
                    None => {
                        self.blocks.insert(k, at);
                    }
                }
                at
            }
            None => return None,
        };
        self.last = Some((k, at));
        Some(at)
    }

    /// The sample at corner c, if taken.
    pub(crate) fn get(&mut self, c: IVec3) -> Option<Sample> {
        let (k, i) = Self::split(c);
        let at = self.block(k, false)?;
        let phi = self.pool[at as usize + i];
        (!phi.is_nan()).then(|| Sample {
            inside: phi.is_sign_positive(),
            phi,
        })
    }

    /// Keeps the sample at corner c.
    pub(crate) fn set(&mut self, c: IVec3, s: Sample) {
        let (k, i) = Self::split(c);
        let at = self.block(k, true).expect("created") as usize;
        // Φ's sign bit is the membership; a boundary sample keeps its side.
        let phi = if s.inside { s.phi.abs() } else { -s.phi.abs() };
        if self.pool[at + i].is_nan() {
            self.count += 1;
        }
        self.pool[at + i] = phi;
    }

    /// Corners sampled.
    pub(crate) fn len(&self) -> usize {
        self.count
    }
}
