//! Which parts an edit or a drag frame changed, so a server sends only
//! those. One part is held inline and a group's list is shared (an `Arc`),
//! so reporting never allocates on a drag frame.

use std::sync::Arc;

use super::PartId;

#[derive(Clone, Debug)]
enum Repr {
    One(PartId),
    Many(Arc<[PartId]>),
}

/// The parts whose shape (control points) or icons changed, ascending,
/// without repeats. Equal when they name the same parts.
#[derive(Clone, Debug)]
pub struct ChangedParts(Repr);

impl PartialEq for ChangedParts {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl Eq for ChangedParts {}

impl ChangedParts {
    /// No part.
    pub fn none() -> Self {
        Self(Repr::Many(Arc::from(Vec::new())))
    }

    /// One part.
    pub fn one(id: PartId) -> Self {
        Self(Repr::One(id))
    }

    /// An already sorted, deduplicated shared list.
    pub(crate) fn shared(ids: Arc<[PartId]>) -> Self {
        Self(Repr::Many(ids))
    }

    /// Any parts (sorted and deduplicated here).
    pub fn from_ids(ids: impl IntoIterator<Item = PartId>) -> Self {
        let mut v: Vec<PartId> = ids.into_iter().collect();
        v.sort_unstable();
        v.dedup();
        Self(Repr::Many(v.into()))
    }

    /// The parts, ascending.
    pub fn as_slice(&self) -> &[PartId] {
        match &self.0 {
            Repr::One(id) => std::slice::from_ref(id),
            Repr::Many(v) => v,
        }
    }

    /// The parts, ascending.
    pub fn iter(&self) -> impl Iterator<Item = PartId> + '_ {
        self.as_slice().iter().copied()
    }

    /// Whether `id` is among them.
    pub fn contains(&self, id: PartId) -> bool {
        self.as_slice().binary_search(&id).is_ok()
    }

    /// How many.
    pub fn len(&self) -> usize {
        self.as_slice().len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.as_slice().is_empty()
    }

    /// The union with `other`.
    pub fn union(&self, other: &ChangedParts) -> ChangedParts {
        if other.is_empty() {
            return self.clone();
        }
        if self.is_empty() {
            return other.clone();
        }
        Self::from_ids(self.iter().chain(other.iter()))
    }
}
