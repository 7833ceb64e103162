//! The planner's working memory: noise predictions and gradients for `B` rows, what the
//! refinement's checks learned of each row, and the global stage's search trees. Sized at
//! compile time; `const`-constructible so that a controller can keep it in a `static`.

use crate::path::{HORIZON, Path};
use crate::planner::search::SearchSpace;
use crate::robot::JOINTS;

/// Nodes per tree of the global stage's search in the default [`Workspace`].
pub const DEFAULT_SEARCH_NODES: usize = 512;

/// Working memory of the planner for `B` rows (gradients and noise predictions) and of the
/// global stage's search (`CAP` nodes per tree).
#[derive(Debug)]
pub struct Workspace<const B: usize, const CAP: usize = DEFAULT_SEARCH_NODES, const J: usize = JOINTS> {
    pub(crate) eps: [Path<J>; B],
    pub(crate) grads: [Path<J>; B],
    /// What the refinement's checks learned of each row, for the judge ([`RefineStop`](crate::planner::RefineStop)).
    pub checks: RowChecks<B>,
    pub(crate) search: SearchSpace<CAP, J>,
}

impl<const B: usize, const CAP: usize, const J: usize> Default for Workspace<B, CAP, J> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const B: usize, const CAP: usize, const J: usize> Workspace<B, CAP, J> {
    /// Zeroed working memory (`const`: it can live in a `static`).
    pub const fn new() -> Self {
        Self {
            eps: [[[0.0; J]; HORIZON]; B],
            grads: [[[0.0; J]; HORIZON]; B],
            checks: RowChecks::NONE,
            search: SearchSpace::new(),
        }
    }
}

/// What the refinement's checks ([`RefineStop`](crate::planner::RefineStop)) learned of each row, for the judge: a row
/// certified free and not moved since need not be checked again, and a row that touched is
/// walked from the segment where it last did (where it most likely touches still; whether it
/// is free does not depend on where the walk starts).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RowChecks<const B: usize> {
    /// Certified free, in the form the judge checks (clamped, ends exact), and not moved since.
    pub free: [bool; B],
    /// The segment of each row's first contact at its last check.
    pub touched: [Option<u16>; B],
    /// Rows of waves that did not run ([`PlanConfig::waves`](crate::planner::PlanConfig::waves)): no candidate, nothing to judge.
    pub skipped: [bool; B],
}

impl<const B: usize> RowChecks<B> {
    /// Nothing known: the judge checks every row from its start.
    pub const NONE: Self = Self {
        free: [false; B],
        touched: [None; B],
        skipped: [false; B],
    };
}

/// One wave's share of the batch: its rows' paths, noise predictions and gradients.
pub(crate) type WaveRows<'a, const J: usize> = (&'a mut [Path<J>], &'a mut [Path<J>], &'a mut [Path<J>]);
/// The refinement's checks of one wave's rows: certified free, where each touched.
pub(crate) type WaveChecks<'a> = (&'a mut [bool], &'a mut [Option<u16>]);
