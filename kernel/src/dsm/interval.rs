//! Closed intervals of reals for conservative bounds of the density field over a
//! ball of space (used to cull primitives and to skip empty or full regions
//! while meshing), and the three-valued membership they give.

/// A closed interval [lo, hi].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Lower bound.
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
}

impl Interval {
    /// [v, v].
    pub fn point(v: f64) -> Self {
        Self { lo: v, hi: v }
    }

    /// [lo, hi].
    pub fn new(lo: f64, hi: f64) -> Self {
        Self { lo, hi }
    }

    /// The interval hull with 0.
    pub fn with_zero(self) -> Self {
        Self {
            lo: self.lo.min(0.0),
            hi: self.hi.max(0.0),
        }
    }

    /// Sum.
    pub fn plus(self, o: Self) -> Self {
        Self {
            lo: self.lo + o.lo,
            hi: self.hi + o.hi,
        }
    }

    /// c · self.
    pub fn scale(self, c: f64) -> Self {
        if c >= 0.0 {
            Self {
                lo: self.lo * c,
                hi: self.hi * c,
            }
        } else {
            Self {
                lo: self.hi * c,
                hi: self.lo * c,
            }
        }
    }

    /// Product with a non-negative interval `o` (o.lo ≥ 0).
    pub fn mul_nonneg(self, o: Self) -> Self {
        let c = [
            self.lo * o.lo,
            self.lo * o.hi,
            self.hi * o.lo,
            self.hi * o.hi,
        ];
        Self {
            lo: c.iter().copied().fold(f64::INFINITY, f64::min),
            hi: c.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }

    /// Three-valued `self ≥ t`.
    pub fn at_least(self, t: f64) -> Tri {
        if self.lo >= t {
            Tri::Yes
        } else if self.hi < t {
            Tri::No
        } else {
            Tri::Maybe
        }
    }
}

/// A three-valued truth: definitely, definitely not, or undecided over a region.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tri {
    /// True everywhere in the region.
    Yes,
    /// False everywhere in the region.
    No,
    /// Undecided.
    Maybe,
}

impl Tri {
    /// The indicator value as an interval ({0}, {1} or [0, 1]).
    pub fn indicator(self) -> Interval {
        match self {
            Tri::Yes => Interval::point(1.0),
            Tri::No => Interval::point(0.0),
            Tri::Maybe => Interval::new(0.0, 1.0),
        }
    }
}
