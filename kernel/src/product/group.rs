//! The joint solve of a group: surface parts connected by joins, with the
//! bindings that hold curves on them. One solver over the block-diagonal
//! stiffness diag(K_1, …, K_m) (each part's own energy, measured from its own
//! reference), each part's icon rows offset to its block, and the join and
//! binding rows coupling them. A drag of one member's icon is the solver's
//! drag fast path on that icon's (re-keyed) group, as for a part alone.

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::DVec3;

use super::{Binding, BindingId, Join, JoinId, Part, PartId};
use crate::bspline::KnotVector;
use crate::design::{Design, DesignError, SolveBackend};
use crate::energy::{Stiffness, SurfaceMaterial};
use crate::solve::{Equation, Group, GroupKey, Problem, SolveError, SolveReport, Solver};

/// Icon keys are below this; member m's icon k is `(m + 1) << KEY_BITS | k`,
/// and join and binding groups take the keys below it.
const KEY_BITS: u32 = 40;

/// One surface part of a group.
#[derive(Debug)]
pub(crate) struct Member {
    pub id: PartId,
    pub offset: usize,
    pub len: usize,
    /// What its stiffness block was built from.
    layout: (KnotVector, KnotVector, SurfaceMaterial),
}

/// A group of jointly solved surface parts.
#[derive(Debug)]
pub(crate) struct SolveGroup {
    pub members: Vec<Member>,
    pub ids: Arc<[PartId]>,
    pub joins: Vec<JoinId>,
    pub bindings: Vec<BindingId>,
    solver: Option<Solver>,
    member_groups: Vec<Vec<Group>>,
    extra: Vec<Group>,
    reference: Vec<DVec3>,
    pub out: Vec<DVec3>,
    problem_dirty: bool,
}

fn surface_of(parts: &BTreeMap<PartId, Part>, id: PartId) -> Result<&Design, DesignError> {
    parts
        .get(&id)
        .and_then(Part::as_surface)
        .ok_or_else(|| DesignError::Unsupported(format!("group member {} is no surface", id.0)))
}

fn remap_key(member: usize, key: GroupKey) -> Result<GroupKey, DesignError> {
    if key >= 1 << KEY_BITS {
        return Err(DesignError::Unsupported(format!(
            "icon id {key} too large for a joined part"
        )));
    }
    Ok(((member as u64 + 1) << KEY_BITS) | key)
}

/// `problem`'s groups with keys re-keyed for `member` and rows offset.
fn remap(problem: Problem, member: usize, offset: usize) -> Result<Vec<Group>, DesignError> {
    let shift = |row: &mut crate::solve::ScalarRow| {
        for i in &mut row.indices {
            *i += offset;
        }
    };
    problem
        .groups
        .into_iter()
        .map(|mut g| {
            g.key = remap_key(member, g.key)?;
            for e in &mut g.equations {
                match e {
                    Equation::Vector { row, .. } | Equation::Projected { row, .. } => shift(row),
                }
            }
            for l in &mut g.loads {
                shift(&mut l.row);
            }
            Ok(g)
        })
        .collect()
}

impl SolveGroup {
    /// A group of the surface parts `ids` (ascending) with these joins and
    /// bindings; nothing is solved yet ([`Self::refresh`] builds it).
    pub fn new(
        parts: &BTreeMap<PartId, Part>,
        ids: Vec<PartId>,
        joins: Vec<JoinId>,
        bindings: Vec<BindingId>,
    ) -> Result<Self, DesignError> {
        let mut members = Vec::with_capacity(ids.len());
        let mut offset = 0;
        for &id in &ids {
            let d = surface_of(parts, id)?;
            let len = d.surface().points().len();
            members.push(Member {
                id,
                offset,
                len,
                layout: (
                    d.surface().u_knots().clone(),
                    d.surface().v_knots().clone(),
                    d.material(),
                ),
            });
            offset += len;
        }
        Ok(Self {
            member_groups: vec![Vec::new(); members.len()],
            members,
            ids: ids.into(),
            joins,
            bindings,
            solver: None,
            extra: Vec::new(),
            reference: vec![DVec3::ZERO; offset],
            out: vec![DVec3::ZERO; offset],
            problem_dirty: true,
        })
    }

    /// The member index of part `id`.
    pub fn member(&self, id: PartId) -> Option<usize> {
        self.members.iter().position(|m| m.id == id)
    }

    /// Re-reads every member (problem, reference, stiffness layout) and the
    /// join and binding rows; refactors when a member's knots or material
    /// changed. Nothing is solved.
    pub fn refresh(
        &mut self,
        parts: &mut BTreeMap<PartId, Part>,
        joins: &BTreeMap<JoinId, Join>,
        bindings: &BTreeMap<BindingId, Binding>,
    ) -> Result<(), DesignError> {
        let mut layout_changed = self.solver.is_none();
        for (m, member) in self.members.iter_mut().enumerate() {
            let d = surface_of(parts, member.id)?;
            let s = d.surface();
            if s.points().len() != member.len {
                return Err(DesignError::Unsupported(format!(
                    "part {} changed its control-point count while joined",
                    member.id.0
                )));
            }
            let layout = (s.u_knots().clone(), s.v_knots().clone(), d.material());
            if layout != member.layout {
                member.layout = layout;
                layout_changed = true;
            }
            self.member_groups[m] = remap(d.problem(), m, member.offset)?;
            self.reference[member.offset..member.offset + member.len]
                .copy_from_slice(d.reference());
        }
        // Each member's problem now comes from here (built with its spring's
        // current stiffness): its next drag frame re-sends its own.
        for member in &self.members {
            if let Some(d) = parts.get_mut(&member.id).and_then(Part::as_surface_mut) {
                d.mark_problem_dirty();
            }
        }
        let parts = &*parts;
        if layout_changed {
            let blocks = self
                .members
                .iter()
                .map(|m| Stiffness::surface(&m.layout.0, &m.layout.1, &m.layout.2))
                .collect::<Result<Vec<_>, _>>()?;
            let refs: Vec<&Stiffness> = blocks.iter().collect();
            self.solver = Some(Solver::new(Stiffness::block_diagonal(&refs)?)?);
        }
        self.extra.clear();
        for (k, jid) in self.joins.iter().enumerate() {
            let join = joins
                .get(jid)
                .ok_or_else(|| DesignError::Unsupported(format!("no join {}", jid.0)))?;
            let (ma, mb) = (self.member(join.spec.a), self.member(join.spec.b));
            let (Some(ma), Some(mb)) = (ma, mb) else {
                return Err(DesignError::Unsupported("join outside its group".into()));
            };
            let a = surface_of(parts, join.spec.a)?.surface();
            let b = surface_of(parts, join.spec.b)?.surface();
            self.extra.push(Group {
                key: k as u64,
                equations: join.equations(a, self.members[ma].offset, b, self.members[mb].offset),
                loads: Vec::new(),
            });
        }
        self.refresh_bindings(parts, bindings)?;
        self.problem_dirty = true;
        Ok(())
    }

    /// Re-reads the bindings' targets (the curves' control points).
    fn refresh_bindings(
        &mut self,
        parts: &BTreeMap<PartId, Part>,
        bindings: &BTreeMap<BindingId, Binding>,
    ) -> Result<(), DesignError> {
        self.extra.truncate(self.joins.len());
        for (k, bid) in self.bindings.iter().enumerate() {
            let binding = bindings
                .get(bid)
                .ok_or_else(|| DesignError::Unsupported(format!("no binding {}", bid.0)))?;
            let m = self
                .member(binding.spec.surface)
                .ok_or_else(|| DesignError::Unsupported("binding outside its group".into()))?;
            let curve = parts
                .get(&binding.spec.curve)
                .and_then(Part::as_curve)
                .ok_or_else(|| DesignError::Unsupported("bound part is no curve".into()))?;
            let surface = surface_of(parts, binding.spec.surface)?.surface();
            self.extra.push(Group {
                key: (self.joins.len() + k) as u64,
                equations: binding.equations(curve.curve(), surface, self.members[m].offset),
                loads: Vec::new(),
            });
        }
        self.problem_dirty = true;
        Ok(())
    }

    /// Solves the group (with member `drag.0`'s icon `drag.1` at input
    /// `drag.2`) into [`Self::out`].
    fn run(&mut self, drag: Option<(usize, GroupKey, DVec3)>) -> Result<SolveReport, DesignError> {
        let solver = self
            .solver
            .as_mut()
            .ok_or(DesignError::Solve(SolveError::Factor(
                "group not built".into(),
            )))?;
        if self.problem_dirty {
            let groups = self
                .member_groups
                .iter()
                .flatten()
                .chain(&self.extra)
                .cloned()
                .collect();
            solver.retarget(Problem { groups })?;
            self.problem_dirty = false;
        }
        Ok(match drag {
            Some((m, key, t)) => {
                solver.drag(remap_key(m, key)?, t, &self.reference, &mut self.out)?
            }
            None => solver.solve(&self.reference, &mut self.out)?,
        })
    }

    /// A full solve of the group (with a member's running drag at its
    /// input), written to every member. Call it after [`Self::refresh`]:
    /// the drag input is the raw one, right for problems built there.
    pub fn solve(
        &mut self,
        parts: &mut BTreeMap<PartId, Part>,
    ) -> Result<SolveReport, DesignError> {
        let drag = self.members.iter().enumerate().find_map(|(m, member)| {
            parts
                .get(&member.id)
                .and_then(Part::as_surface)
                .and_then(Design::drag_input)
                .map(|(key, t)| (m, key, t))
        });
        let report = self.run(drag)?;
        self.write_back(parts, None)?;
        Ok(report)
    }

    /// Writes the last solution to every member but `skip`.
    pub fn write_back(
        &self,
        parts: &mut BTreeMap<PartId, Part>,
        skip: Option<PartId>,
    ) -> Result<(), DesignError> {
        for m in &self.members {
            if Some(m.id) == skip {
                continue;
            }
            if let Some(d) = parts.get_mut(&m.id).and_then(Part::as_surface_mut) {
                d.adopt_points(&self.out[m.offset..m.offset + m.len])?;
            }
        }
        Ok(())
    }

    /// The backend that solves member `member`'s design in this group.
    pub fn backend(&mut self, member: usize) -> MemberBackend<'_> {
        MemberBackend {
            group: self,
            member,
        }
    }
}

/// Solves one member's design through its group's joint solver.
pub(crate) struct MemberBackend<'a> {
    group: &'a mut SolveGroup,
    member: usize,
}

impl SolveBackend for MemberBackend<'_> {
    fn solve(
        &mut self,
        design: &Design,
        problem_changed: bool,
        drag: Option<(u64, DVec3)>,
        out: &mut [DVec3],
    ) -> Result<SolveReport, DesignError> {
        let g = &mut *self.group;
        let m = self.member;
        let (offset, len) = (g.members[m].offset, g.members[m].len);
        if out.len() != len || design.reference().len() != len {
            return Err(DesignError::Solve(SolveError::Size {
                expected: len,
                got: out.len(),
            }));
        }
        if problem_changed {
            g.member_groups[m] = remap(design.problem(), m, offset)?;
            g.reference[offset..offset + len].copy_from_slice(design.reference());
            g.problem_dirty = true;
        }
        let report = g.run(drag.map(|(k, t)| (m, k, t)))?;
        out.copy_from_slice(&g.out[offset..offset + len]);
        Ok(report)
    }
}
