//! Undo/redo: bounded stacks of design documents (the state before each
//! change). A new change clears the redo stack.

use super::model::DesignDoc;
use std::collections::VecDeque;

/// Bounded undo and redo stacks.
#[derive(Debug)]
pub struct UndoStack {
    limit: usize,
    undo: VecDeque<DesignDoc>,
    redo: Vec<DesignDoc>,
}

impl UndoStack {
    /// Stacks keeping at most `limit` undo steps.
    pub fn new(limit: usize) -> Self {
        Self {
            limit: limit.max(1),
            undo: VecDeque::new(),
            redo: Vec::new(),
        }
    }

    /// Records the state before a change.
    pub fn push(&mut self, before: DesignDoc) {
        if self.undo.len() == self.limit {
            self.undo.pop_front();
        }
        self.undo.push_back(before);
        self.redo.clear();
    }

    /// The state to go back to, given the current one (kept for redo).
    pub fn undo(&mut self, current: DesignDoc) -> Option<DesignDoc> {
        let prev = self.undo.pop_back()?;
        self.redo.push(current);
        Some(prev)
    }

    /// The state to go forward to, given the current one (kept for undo).
    pub fn redo(&mut self, current: DesignDoc) -> Option<DesignDoc> {
        let next = self.redo.pop()?;
        self.undo.push_back(current);
        Some(next)
    }

    /// Whether there is something to undo.
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    /// Whether there is something to redo.
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Number of undo steps available.
    pub fn undo_len(&self) -> usize {
        self.undo.len()
    }
}
