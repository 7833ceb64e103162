//! Bounded global search: RRT-Connect in joint space, for when no diffusion candidate is free.
//!
//! The prior proposes paths near the data it was trained on; in a scene unlike that data every
//! candidate may collide. This stage then finds *some* collision-free coarse path, which the
//! planner hands back to the prior. It is the classical bidirectional RRT with greedy connect
//! (Kuffner & LaValle 2000) within the soft limits, followed by random shortcuts, resampling to
//! [`HORIZON`] waypoints and a final check of every resampled segment.
//!
//! Embedded rules, as in the rest of the core:
//! - **No allocation.** Both trees live in a caller-provided [`SearchSpace`] whose capacity is
//!   a const generic, so it can be a `static` on a microcontroller; after the trees meet, the
//!   same memory holds the raw path while it is shortcut.
//! - **Deterministic, bounded work.** All randomness comes from the caller's [`Rng`]; there is
//!   no clock. Work is bounded by the counts in [`SearchConfig`]; the worst-case number of
//!   validity queries is [`SearchConfig::max_oracle_calls`].
//! - **Validity is an oracle.** The caller passes `edge_free(a, b)`: is the straight
//!   joint-space segment from `a` to `b`, both ends included, collision-free? (`a == b` asks
//!   about one configuration.) The search never calls the checker itself, so it can be tested
//!   with analytic obstacles and wired to the exact checker (a `SegmentChecker`) by the planner.
//! - **Lazy edges** ([`SearchConfig::lazy`], the default): a new node is checked alone and
//!   the edge to it only once it lies on a path between the roots, root side first; a blocked
//!   edge drops its node and what grew from it, and a full tree reuses dropped nodes' slots.
//!   Most edges a search grows lead nowhere, and a node alone is one state of the checker
//!   where an edge is up to thirty. What the search returns was checked edge by edge, as before.

// Never panic: no indexing, unwrapping or unchecked integer arithmetic outside the tests.
#![deny(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::unreachable,
    clippy::arithmetic_side_effects
)]

use crate::error::Error;
use crate::path::{HORIZON, Path};
use crate::rng::Rng;
use crate::robot::kinematics::Joints;
use crate::robot::{JOINTS, Robot};
use core::fmt;

/// Link value that ends a chain while its parent links are reversed: never a node index,
/// because a tree holds at most `u16::MAX` nodes (indices `0..=u16::MAX - 1`).
const NO_NODE: u16 = u16::MAX;

/// Segments of the output path.
const SPANS: usize = HORIZON - 1;

/// Failing oracle calls a seed path may add to a search: its chain from each root, and the
/// connect of the goal tree to the start chain's tip.
const SEED_FAILS: u64 = 3;

/// Oracle calls of the two verifications (even resampling, then the vertex-keeping fallback).
const VERIFY_CALLS: u64 = 2 * SPANS as u64;

/// How much work one search may do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchConfig {
    /// Tree-growing iterations (one random sample each) before giving up.
    pub max_iterations: u32,
    /// Largest joint change of one tree edge (max-norm, radians): short edges keep each
    /// oracle call cheap (0.3 rad is 30 checker states at the spec's 0.01 rad).
    pub step: f32,
    /// Random shortcut attempts on the raw path.
    pub shortcuts: u32,
    /// Nodes per tree, the root included; the space's `CAP` caps it (`u16::MAX` means "all of
    /// `CAP`"), so one static space can serve smaller budgets.
    pub max_nodes: u16,
    /// Lazy edges: a new node is checked alone (`edge_free(q, q)`), and the edge to it only
    /// when it lies on a path between the roots; a blocked edge drops its node and everything
    /// grown from it, and the trees grow on. Most edges a search grows are never on its path,
    /// so it checks a fraction of their states; the path it returns is checked like any other.
    pub lazy: bool,
}

impl SearchConfig {
    /// The planner's fallback setting: the host's RRT baseline's step, and all of the space's
    /// capacity (a plan's bits depend on it: the firmware and `edmp-host embed` hold 512 nodes
    /// per tree). 8,000 iterations: on the Panda's suites, the problems the first stage leaves
    /// need up to about 5,300 (the host, with 16,384 nodes per tree, allows 32,000 for other
    /// arms' harder problems). 25 shortcut attempts (the RRT baseline makes
    /// 100): the prior reshapes the path and the winner is shortened again, so more attempts
    /// buy nothing measurable (docs/benchmark.md).
    pub const DEFAULT: Self = Self {
        max_iterations: 8000,
        step: 0.3,
        shortcuts: 25,
        max_nodes: u16::MAX,
        lazy: true,
    };

    /// Nodes per tree that a [`SearchSpace<CAP>`] with `CAP = capacity` allows.
    pub const fn tree_capacity(&self, capacity: usize) -> usize {
        let wanted = self.max_nodes as usize;
        if wanted < capacity { wanted } else { capacity }
    }

    /// Worst-case calls of `edge_free` in one [`search`] with a space of `capacity` nodes per
    /// tree (`N = tree_capacity(capacity)`):
    ///
    /// `1 + max_iterations + 3 + 2 (N − 1) + shortcuts + 2 (HORIZON − 1)`, plus `6 (N − 1)` when
    /// [`lazy`](Self::lazy).
    ///
    /// Why: one call for the direct start–goal edge; during growth every call either adds a
    /// node (at most `N − 1` per tree) or fails, and each iteration has at most one failing
    /// call (its extension, or the connect that follows it, stops at the first blocked edge);
    /// a seed path ([`search_from`]) adds at most three failing calls (the chain from each
    /// root, then the connect of the goal tree to the start chain's tip); one call per shortcut
    /// attempt; `HORIZON − 1` calls to verify the evenly resampled path and as many again for
    /// the vertex-keeping fallback. A lazy tree adds at most `2 (N − 1)` nodes over the
    /// search (a full tree reuses its dropped nodes' slots), each with one call for the node
    /// and at most one for the edge to it, when the trees meet. Besides the oracle, each
    /// extension scans its tree for the nearest node (at most `N` distances).
    pub const fn max_oracle_calls(&self, capacity: usize) -> u64 {
        let nodes = self.tree_capacity(capacity) as u64;
        let edges = nodes.saturating_sub(1).saturating_mul(2);
        let growth = (self.max_iterations as u64).saturating_add(edges);
        let lazy = if self.lazy { edges.saturating_mul(3) } else { 0 };
        growth
            .saturating_add(lazy)
            .saturating_add(1 + SEED_FAILS)
            .saturating_add(self.shortcuts as u64)
            .saturating_add(VERIFY_CALLS)
    }

    fn validate(&self) -> Result<(), Error> {
        if self.step.is_finite() && self.step > 0.0 && self.max_nodes > 0 {
            Ok(())
        } else {
            Err(Error::BadParameter)
        }
    }
}

impl Default for SearchConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Memory of one search: two trees of at most `CAP` nodes (`1 ≤ CAP ≤ u16::MAX`), each node a
/// configuration, the `u16` index of its parent, whether the edge to it is checked and where
/// it moves when the tree is compacted. About `66 · CAP` bytes.
///
/// Reusable: every [`search`] starts by clearing it. `new` is `const`, so on a
/// microcontroller it can sit in a `static` instead of on the stack.
pub struct SearchSpace<const CAP: usize, const J: usize = JOINTS> {
    nodes: [[Joints<f32, J>; CAP]; 2],
    parents: [[u16; CAP]; 2],
    edges: [[Edge; CAP]; 2],
    moved_to: [[u16; CAP]; 2],
    len: [usize; 2],
    added: [usize; 2],
}

/// What is known of the edge from a node's parent to it (the root's: `Checked`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Edge {
    /// Free by the oracle.
    Checked,
    /// Its node is free; the edge is checked when it lies on a path ([`SearchConfig::lazy`]).
    Unchecked,
    /// Blocked, or below a blocked one: the node is out of the tree.
    Dropped,
}

impl<const CAP: usize, const J: usize> SearchSpace<CAP, J> {
    /// Size of the space in bytes (for sizing statics and stacks).
    pub const BYTES: usize = core::mem::size_of::<Self>();

    /// An empty space. `CAP` outside `1..=u16::MAX` does not compile: parents are `u16`.
    pub const fn new() -> Self {
        const {
            assert!(
                CAP >= 1 && CAP <= u16::MAX as usize,
                "SearchSpace needs 1 <= CAP <= u16::MAX"
            );
        }
        Self {
            nodes: [[[0.0; J]; CAP]; 2],
            parents: [[0; CAP]; 2],
            edges: [[Edge::Checked; CAP]; 2],
            moved_to: [[0; CAP]; 2],
            len: [0; 2],
            added: [0; 2],
        }
    }

    /// The start tree and the goal tree, borrowed for growing, each holding at most `capacity`
    /// nodes at once and adding at most `limit` in all.
    fn trees(&mut self, capacity: usize, limit: usize) -> [Tree<'_, CAP, J>; 2] {
        let Self {
            nodes: [n0, n1],
            parents: [p0, p1],
            edges: [e0, e1],
            moved_to: [m0, m1],
            len: [l0, l1],
            added: [a0, a1],
        } = self;
        [
            Tree {
                nodes: n0,
                parents: p0,
                edges: e0,
                moved_to: m0,
                len: l0,
                added: a0,
                capacity,
                limit,
            },
            Tree {
                nodes: n1,
                parents: p1,
                edges: e1,
                moved_to: m1,
                len: l1,
                added: a1,
                capacity,
                limit,
            },
        ]
    }
}

impl<const CAP: usize, const J: usize> Default for SearchSpace<CAP, J> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const CAP: usize, const J: usize> fmt::Debug for SearchSpace<CAP, J> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SearchSpace")
            .field("capacity", &CAP)
            .field("nodes", &self.len)
            .finish()
    }
}

/// A found path and what finding it cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchOutcome<const J: usize = JOINTS> {
    /// `HORIZON` waypoints from exactly the start to exactly the goal; every segment passed
    /// `edge_free`.
    pub path: Path<J>,
    /// Waypoints of the shortcut polyline that `path` was resampled from (2 for a direct edge).
    pub corners: usize,
    /// `true` when the waypoints are evenly spaced by joint-space arc length; `false` when
    /// even spacing cut a corner the oracle refused and the fallback, which keeps every
    /// polyline vertex as a waypoint (spans shared out by length), was used.
    pub even: bool,
    /// Nodes in the trees when they met, both roots included (dropped nodes left out).
    pub nodes: usize,
    /// Growing iterations used (0 for a direct edge).
    pub iterations: u32,
    /// Calls of `edge_free` made, at most [`SearchConfig::max_oracle_calls`].
    pub oracle_calls: u32,
}

/// Searches for a collision-free path from `start` to `goal`, both assumed valid.
///
/// `Ok(None)` when the budget (iterations or tree capacity) runs out, or when neither
/// resampling of the found polyline passes the oracle: "no path", never an unchecked one.
/// Errors: a non-finite end ([`Error::NonFiniteJoint`]), an end outside the soft limits
/// ([`Error::OutsideLimits`]), a bad config ([`Error::BadParameter`]), or whatever `edge_free`
/// returns, passed on at once.
///
/// Work: at most [`SearchConfig::max_oracle_calls`]`(CAP)` oracle calls; the rng advances by
/// `JOINTS` numbers per iteration and two per shortcut attempt.
pub fn search<const CAP: usize, const J: usize>(
    robot: &Robot<f32, J>,
    start: &Joints<f32, J>,
    goal: &Joints<f32, J>,
    config: &SearchConfig,
    space: &mut SearchSpace<CAP, J>,
    rng: &mut Rng,
    edge_free: &mut impl FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
) -> Result<Option<SearchOutcome<J>>, Error> {
    search_from(robot, start, goal, &[], config, space, rng, edge_free)
}

/// [`search`] with trees that start from a seed path as well as from their roots: the start
/// tree takes the seed's waypoints from the start on, each under the previous one, as long as
/// the edge to it is free; the goal tree likewise from the goal back; then the goal tree
/// tries to connect to the start chain's tip, as after any extension. A candidate of the
/// prior that collides in one place thus leaves the search only the gap around that place
/// to bridge, instead of the whole way. The seed's first and last waypoints stand for the
/// ends (they are not read); waypoints outside the soft limits end a chain (the trees stay
/// within them). No randomness is used by the seeding: with an empty seed this is [`search`].
#[allow(clippy::too_many_arguments)] // the arm, the problem, the budget and its memory, the oracle
pub fn search_from<const CAP: usize, const J: usize>(
    robot: &Robot<f32, J>,
    start: &Joints<f32, J>,
    goal: &Joints<f32, J>,
    seed: &[Joints<f32, J>],
    config: &SearchConfig,
    space: &mut SearchSpace<CAP, J>,
    rng: &mut Rng,
    edge_free: &mut impl FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
) -> Result<Option<SearchOutcome<J>>, Error> {
    check_finite(start)?;
    check_finite(goal)?;
    check_within_limits(robot, start)?;
    check_within_limits(robot, goal)?;
    config.validate()?;
    let capacity = config.tree_capacity(CAP);
    if capacity == 0 {
        return Err(Error::BadParameter);
    }
    let mut oracle = Oracle {
        edge_free,
        calls: 0,
        iterations: 0,
    };
    space.len = [0; 2];
    let corners = if oracle.free(start, goal)? {
        // Slots 0 and 1 exist: the two trees hold at least one node each.
        if let Some([a, b]) = space.nodes.as_flattened_mut().first_chunk_mut() {
            *a = *start;
            *b = *goal;
        }
        space.len = [1, 1];
        2
    } else {
        let Some((s, g)) = grow(robot, start, goal, seed, config, space, rng, &mut oracle)? else {
            return Ok(None);
        };
        join(space, s, g)
    };
    let nodes = space.len.iter().sum();
    let flat = space.nodes.as_flattened_mut();
    let Some(raw) = flat.get_mut(..corners) else {
        return Ok(None);
    };
    let corners = shortcut(raw, config.shortcuts, rng, &mut oracle)?;
    let Some(polyline) = raw.get(..corners) else {
        return Ok(None);
    };
    let mut even = true;
    let mut path = resample_even(polyline);
    if !verify(&path, &mut oracle)? {
        even = false;
        match resample_through_vertices(polyline) {
            Some(p) if verify(&p, &mut oracle)? => path = p,
            _ => return Ok(None),
        }
    }
    Ok(Some(SearchOutcome {
        path,
        corners,
        even,
        nodes,
        iterations: oracle.iterations,
        oracle_calls: oracle.calls,
    }))
}

/// Random shortcuts on the polyline `path` over the caller's `edge_free` (see [`search`]): a
/// pair of waypoints (i, j ≥ i + 2) is joined when the straight edge is free, dropping the
/// waypoints between. Returns the new length and the oracle calls made (at most `attempts`).
pub fn shortcut_polyline<const J: usize>(
    path: &mut [Joints<f32, J>],
    attempts: u32,
    rng: &mut Rng,
    edge_free: &mut impl FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
) -> Result<(usize, u32), Error> {
    let mut oracle = Oracle {
        edge_free,
        calls: 0,
        iterations: 0,
    };
    let n = shortcut(path, attempts, rng, &mut oracle)?;
    Ok((n, oracle.calls))
}

/// The caller's `edge_free`, counted.
struct Oracle<'f, F> {
    edge_free: &'f mut F,
    calls: u32,
    /// Growing iterations spent, counted by [`grow`].
    iterations: u32,
}

impl<F> Oracle<'_, F> {
    fn free<const J: usize>(&mut self, a: &Joints<f32, J>, b: &Joints<f32, J>) -> Result<bool, Error>
    where
        F: FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
    {
        self.calls = self.calls.saturating_add(1);
        (self.edge_free)(a, b)
    }
}

/// One tree of the space, borrowed for growing.
struct Tree<'a, const CAP: usize, const J: usize> {
    nodes: &'a mut [Joints<f32, J>; CAP],
    parents: &'a mut [u16; CAP],
    edges: &'a mut [Edge; CAP],
    moved_to: &'a mut [u16; CAP],
    len: &'a mut usize,
    /// Nodes added since the root was planted.
    added: &'a mut usize,
    capacity: usize,
    /// Nodes it may add in all: `capacity − 1`, twice that when lazy (dropped nodes' slots are
    /// reused).
    limit: usize,
}

impl<const CAP: usize, const J: usize> Tree<'_, CAP, J> {
    fn plant(&mut self, root: &Joints<f32, J>) {
        if let (Some(n), Some(p), Some(e)) = (self.nodes.first_mut(), self.parents.first_mut(), self.edges.first_mut())
        {
            *n = *root;
            *p = 0;
            *e = Edge::Checked;
            *self.len = 1;
            *self.added = 0;
        }
    }

    /// Whether a node can be added: within the limit, and a free slot, made by compacting the
    /// tree (dropping its dropped nodes) when it is full.
    fn has_room(&mut self) -> bool {
        if *self.added >= self.limit {
            return false;
        }
        if *self.len < self.capacity {
            return true;
        }
        self.compact();
        *self.len < self.capacity
    }

    /// Moves the nodes that are not dropped to the front, in order, their links renumbered
    /// (a parent comes before its children, so its new index is known when they move).
    fn compact(&mut self) {
        let mut kept = 0usize;
        for i in 0..*self.len {
            let (Some(&edge), Some(&parent), Some(&q)) = (self.edges.get(i), self.parents.get(i), self.nodes.get(i))
            else {
                break;
            };
            if edge == Edge::Dropped {
                continue;
            }
            let link = self.moved_to.get(usize::from(parent)).copied().unwrap_or(0);
            let new = u16::try_from(kept).unwrap_or(NO_NODE);
            if let (Some(m), Some(n), Some(p), Some(e)) = (
                self.moved_to.get_mut(i),
                self.nodes.get_mut(kept),
                self.parents.get_mut(kept),
                self.edges.get_mut(kept),
            ) {
                (*m, *n, *p, *e) = (new, q, if i == 0 { 0 } else { link }, edge);
            }
            kept = kept.saturating_add(1);
        }
        *self.len = kept;
    }

    fn grown(&self) -> &[Joints<f32, J>] {
        self.nodes.get(..*self.len).unwrap_or(&[])
    }

    /// Index and value of the node nearest to `q` (Euclidean; the first on ties), dropped
    /// nodes left out.
    fn nearest(&self, q: &Joints<f32, J>) -> Option<(usize, Joints<f32, J>)> {
        let mut best: Option<(f32, usize, Joints<f32, J>)> = None;
        for ((i, n), e) in self.grown().iter().enumerate().zip(self.edges.iter()) {
            if *e == Edge::Dropped {
                continue;
            }
            let d = distance2(n, q);
            if best.is_none_or(|(b, _, _)| d < b) {
                best = Some((d, i, *n));
            }
        }
        best.map(|(_, i, n)| (i, n))
    }

    /// Appends `q` under `parent` (< the new index, which [`compact_chain`] and
    /// [`Tree::drop_below`] rely on).
    fn push(&mut self, q: Joints<f32, J>, parent: usize, edge: Edge) -> Option<usize> {
        let i = *self.len;
        if i >= self.capacity {
            return None;
        }
        if *self.added >= self.limit {
            return None;
        }
        let link = u16::try_from(parent).ok()?;
        *self.nodes.get_mut(i)? = q;
        *self.parents.get_mut(i)? = link;
        *self.edges.get_mut(i)? = edge;
        *self.len = i.saturating_add(1);
        *self.added = self.added.saturating_add(1);
        Some(i)
    }

    /// Checks the unchecked edges on the chain from the root down to `leaf`, root side first
    /// (a blocked edge drops every node below it, so none of their edges is checked in vain):
    /// `true` when all are free. A blocked edge drops its node and every node below it.
    fn check_chain<F>(&mut self, leaf: usize, oracle: &mut Oracle<'_, F>) -> Result<bool, Error>
    where
        F: FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
    {
        // Turn the chain's links to point from the root towards the leaf (the leaf's: NO_NODE),
        // walk it down, then turn them back. Parents have smaller indices: at most `len` steps.
        // An oracle error ends the whole search, whose next use plants the trees afresh.
        let (mut prev, mut cur) = (NO_NODE, leaf);
        for _ in 0..*self.len {
            let Some(link) = self.parents.get_mut(cur) else { break };
            let next = usize::from(*link);
            *link = prev;
            prev = u16::try_from(cur).unwrap_or(NO_NODE);
            if cur == 0 || next >= cur {
                break;
            }
            cur = next;
        }
        let (mut parent, mut blocked) = (usize::from(prev), None);
        for _ in 0..*self.len {
            let Some(&link) = self.parents.get(parent) else { break };
            if link == NO_NODE {
                break;
            }
            let child = usize::from(link);
            if self.edges.get(child) == Some(&Edge::Unchecked) {
                let (Some(from), Some(to)) = (self.nodes.get(parent).copied(), self.nodes.get(child).copied()) else {
                    break;
                };
                if !oracle.free(&from, &to)? {
                    blocked = Some(child);
                    break;
                }
                if let Some(e) = self.edges.get_mut(child) {
                    *e = Edge::Checked;
                }
            }
            parent = child;
        }
        let (mut prev, mut cur) = (0u16, usize::from(prev));
        for _ in 0..*self.len {
            let Some(link) = self.parents.get_mut(cur) else { break };
            let next = *link;
            *link = prev;
            if next == NO_NODE {
                break;
            }
            prev = u16::try_from(cur).unwrap_or(NO_NODE);
            cur = usize::from(next);
        }
        match blocked {
            Some(node) => {
                self.drop_below(node);
                Ok(false)
            }
            None => Ok(true),
        }
    }

    /// Drops `node` and its descendants (one pass: a child comes after its parent).
    fn drop_below(&mut self, node: usize) {
        if let Some(e) = self.edges.get_mut(node) {
            *e = Edge::Dropped;
        }
        for i in node.saturating_add(1)..*self.len {
            let parent = self.parents.get(i).map_or(0, |&p| usize::from(p));
            if self.edges.get(parent) == Some(&Edge::Dropped)
                && let Some(e) = self.edges.get_mut(i)
            {
                *e = Edge::Dropped;
            }
        }
    }
}

/// What one extension did.
enum Extension {
    /// The tree is at capacity: the search is over.
    Full,
    /// The edge towards the target is blocked.
    Trapped,
    /// A node was added short of the target.
    Advanced(usize),
    /// A node was added exactly at the target.
    Reached(usize),
}

/// One step of `tree` from its nearest node towards `target`: the edge checked, or with
/// `config.lazy` the new node alone.
fn extend<const CAP: usize, F, const J: usize>(
    tree: &mut Tree<'_, CAP, J>,
    target: &Joints<f32, J>,
    config: &SearchConfig,
    oracle: &mut Oracle<'_, F>,
) -> Result<Extension, Error>
where
    F: FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
{
    if !tree.has_room() {
        return Ok(Extension::Full);
    }
    let Some((near, from)) = tree.nearest(target) else {
        return Ok(Extension::Full);
    };
    let q = steer(&from, target, config.step);
    let (checked_from, edge) = if config.lazy {
        (&q, Edge::Unchecked)
    } else {
        (&from, Edge::Checked)
    };
    if !oracle.free(checked_from, &q)? {
        return Ok(Extension::Trapped);
    }
    Ok(match tree.push(q, near, edge) {
        None => Extension::Full,
        Some(i) if q == *target => Extension::Reached(i),
        Some(i) => Extension::Advanced(i),
    })
}

/// Grows the start tree (space tree 0) and the goal tree (tree 1) in turn until they meet:
/// the meeting node's index in each, or `None` when the budget runs out.
#[allow(clippy::too_many_arguments)]
fn grow<const CAP: usize, F, const J: usize>(
    robot: &Robot<f32, J>,
    start: &Joints<f32, J>,
    goal: &Joints<f32, J>,
    seed: &[Joints<f32, J>],
    config: &SearchConfig,
    space: &mut SearchSpace<CAP, J>,
    rng: &mut Rng,
    oracle: &mut Oracle<'_, F>,
) -> Result<Option<(usize, usize)>, Error>
where
    F: FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
{
    let capacity = config.tree_capacity(CAP);
    let additions = capacity.saturating_sub(1);
    let limit = if config.lazy {
        additions.saturating_mul(2)
    } else {
        additions
    };
    let [mut s, mut g] = space.trees(capacity, limit);
    s.plant(start);
    g.plant(goal);
    let inner = seed.get(1..seed.len().saturating_sub(1)).unwrap_or(&[]);
    let tip = grow_chain(robot, &mut s, inner.iter(), oracle)?;
    grow_chain(robot, &mut g, inner.iter().rev(), oracle)?;
    if let Some(tip) = tip
        && let Some(target) = s.grown().get(tip).copied()
    {
        match connect(&mut g, &target, config, oracle)? {
            Connect::Full => return Ok(None),
            Connect::Trapped => {}
            Connect::Reached(j) => {
                if met(&mut s, tip, &mut g, j, oracle)? {
                    return Ok(Some((tip, j)));
                }
            }
        }
    }
    let mut from_start = true;
    while oracle.iterations < config.max_iterations {
        oracle.iterations = oracle.iterations.saturating_add(1);
        let mut sample = [0.0f32; J];
        for ((v, lo), hi) in sample.iter_mut().zip(&robot.soft_lower).zip(&robot.soft_upper) {
            *v = rng.uniform_f32(*lo, *hi);
        }
        let (a, b) = if from_start { (&mut s, &mut g) } else { (&mut g, &mut s) };
        let new = match extend(a, &sample, config, oracle)? {
            Extension::Full => return Ok(None),
            Extension::Trapped => None,
            Extension::Advanced(i) | Extension::Reached(i) => Some(i),
        };
        if let Some((i, target)) = new.and_then(|i| a.grown().get(i).map(|q| (i, *q))) {
            match connect(b, &target, config, oracle)? {
                Connect::Full => return Ok(None),
                Connect::Trapped => {}
                Connect::Reached(j) => {
                    let (si, gi) = if from_start { (i, j) } else { (j, i) };
                    if met(&mut s, si, &mut g, gi, oracle)? {
                        return Ok(Some((si, gi)));
                    }
                }
            }
        }
        from_start = !from_start;
    }
    Ok(None)
}

/// How a greedy connect ended.
enum Connect {
    /// The tree is at capacity: the search is over.
    Full,
    /// An edge towards the target is blocked.
    Trapped,
    /// The tree reached the target: the index of the node there.
    Reached(usize),
}

/// Greedy connect of `tree` to `target`: extensions until one is blocked or reaches it. Each
/// pass adds a node or ends, so at most `capacity` passes.
fn connect<const CAP: usize, F, const J: usize>(
    tree: &mut Tree<'_, CAP, J>,
    target: &Joints<f32, J>,
    config: &SearchConfig,
    oracle: &mut Oracle<'_, F>,
) -> Result<Connect, Error>
where
    F: FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
{
    loop {
        match extend(tree, target, config, oracle)? {
            Extension::Full => return Ok(Connect::Full),
            Extension::Trapped => return Ok(Connect::Trapped),
            Extension::Advanced(_) => {}
            Extension::Reached(j) => return Ok(Connect::Reached(j)),
        }
    }
}

/// Whether the trees, met at node `si` of the start tree and `gi` of the goal tree, join the
/// roots by checked edges: the unchecked ones on the way are checked now (start side first),
/// and a blocked one drops its node and what grew from it ([`SearchConfig::lazy`]).
fn met<const CAP: usize, F, const J: usize>(
    s: &mut Tree<'_, CAP, J>,
    si: usize,
    g: &mut Tree<'_, CAP, J>,
    gi: usize,
    oracle: &mut Oracle<'_, F>,
) -> Result<bool, Error>
where
    F: FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
{
    Ok(s.check_chain(si, oracle)? && g.check_chain(gi, oracle)?)
}

/// Appends `chain` to `tree` from its root, each waypoint under the one before, while the edge
/// to it is free and the waypoint lies within the soft limits (a repeat of the last node is
/// skipped); the last node added, if any.
fn grow_chain<'c, const CAP: usize, F, const J: usize>(
    robot: &Robot<f32, J>,
    tree: &mut Tree<'_, CAP, J>,
    chain: impl Iterator<Item = &'c Joints<f32, J>>,
    oracle: &mut Oracle<'_, F>,
) -> Result<Option<usize>, Error>
where
    F: FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
{
    let (mut last, mut added) = (0usize, None);
    for q in chain {
        let Some(from) = tree.grown().get(last).copied() else {
            break;
        };
        if *q == from {
            continue;
        }
        if check_finite(q).is_err() || check_within_limits(robot, q).is_err() || !oracle.free(&from, q)? {
            break;
        }
        let Some(i) = tree.push(*q, last, Edge::Checked) else {
            break;
        };
        (last, added) = (i, Some(i));
    }
    Ok(added)
}

/// Lays the path out from the start: the start tree's chain root → `s` at flat positions
/// `0..ls`, then the goal tree's chain after `g` (which equals `s`) down to its root.
/// Returns the number of waypoints. The trees are spent afterwards.
fn join<const CAP: usize, const J: usize>(space: &mut SearchSpace<CAP, J>, s: usize, g: usize) -> usize {
    let SearchSpace {
        nodes: [n0, n1],
        parents: [p0, p1],
        ..
    } = space;
    let ls = compact_chain(n0, p0, s);
    let lg = compact_chain(n1, p1, g);
    if let Some(chain) = n1.get_mut(..lg) {
        chain.reverse(); // meeting node first, goal last
    }
    // Flat index CAP + k (goal chain, k ≥ 1) moves to ls + k − 1 ≤ CAP + k − 1: each write
    // lands below every source not yet read.
    let flat = space.nodes.as_flattened_mut();
    for k in 1..lg {
        if let Some(q) = flat.get(CAP.saturating_add(k)).copied()
            && let Some(slot) = flat.get_mut(ls.saturating_sub(1).saturating_add(k))
        {
            *slot = q;
        }
    }
    ls.saturating_add(lg).saturating_sub(1)
}

/// Moves the chain root → `leaf` of one tree to positions `0..len` of its nodes, in that
/// order; returns `len`. Parents have smaller indices than their children, so the chain's
/// k-th node from the root sits at index ≥ k and is read before anything overwrites it.
fn compact_chain<const CAP: usize, const J: usize>(
    nodes: &mut [Joints<f32, J>; CAP],
    parents: &mut [u16; CAP],
    leaf: usize,
) -> usize {
    // Reverse the links so that they point from the root towards the leaf.
    let (mut prev, mut cur, mut len) = (NO_NODE, leaf, 0usize);
    while let Some(link) = parents.get_mut(cur) {
        let next = usize::from(*link);
        *link = prev;
        prev = u16::try_from(cur).unwrap_or(NO_NODE);
        len = len.saturating_add(1);
        if next >= cur {
            break; // the root (its own parent); parents are always smaller otherwise
        }
        cur = next;
    }
    let mut cur = usize::from(prev);
    for k in 0..len {
        if let Some(q) = nodes.get(cur).copied()
            && let Some(slot) = nodes.get_mut(k)
        {
            *slot = q;
        }
        match parents.get(cur) {
            Some(&next) if next != NO_NODE => cur = usize::from(next),
            _ => return k.saturating_add(1),
        }
    }
    len
}

/// Random shortcuts on the polyline `path`: a pair (i, j ≥ i + 2) is joined when the oracle
/// frees the straight edge, dropping the waypoints between. Returns the new length.
fn shortcut<F, const J: usize>(
    path: &mut [Joints<f32, J>],
    attempts: u32,
    rng: &mut Rng,
    oracle: &mut Oracle<'_, F>,
) -> Result<usize, Error>
where
    F: FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
{
    let mut n = path.len();
    for _ in 0..attempts {
        if n < 3 {
            break;
        }
        // i ≤ n − 3 and i + 2 ≤ j ≤ n − 1, because `below(m) < m`; n ≤ 2 CAP < 2^17 fits u32.
        let i = below(rng, n.saturating_sub(2));
        let j = i
            .saturating_add(2)
            .saturating_add(below(rng, n.saturating_sub(i).saturating_sub(2)));
        let (Some(a), Some(b)) = (path.get(i).copied(), path.get(j).copied()) else {
            continue;
        };
        if j < n && oracle.free(&a, &b)? {
            let gap = j.saturating_sub(i).saturating_sub(1);
            for k in i.saturating_add(1)..n.saturating_sub(gap) {
                if let Some(q) = path.get(k.saturating_add(gap)).copied()
                    && let Some(slot) = path.get_mut(k)
                {
                    *slot = q;
                }
            }
            n = n.saturating_sub(gap);
        }
    }
    Ok(n)
}

/// `HORIZON` points evenly spaced by joint-space arc length along `path` (ends exact). Public
/// for the shortening of the chosen path ([`crate::planner::shortcut`]).
pub fn resample_even<const J: usize>(path: &[Joints<f32, J>]) -> Path<J> {
    let first = path.first().copied().unwrap_or([0.0; J]);
    let last = path.last().copied().unwrap_or(first);
    let total: f32 = path.windows(2).map(segment_length).sum();
    let length_of = |seg: usize| path.get(seg..seg.saturating_add(2)).map_or(0.0, segment_length);
    let mut out = [first; HORIZON];
    let (mut seg, mut before) = (0usize, 0.0f32);
    for (k, slot) in out.iter_mut().enumerate() {
        let s = total * k as f32 / SPANS as f32;
        while seg.saturating_add(2) < path.len() && before + length_of(seg) < s {
            before += length_of(seg);
            seg = seg.saturating_add(1);
        }
        let len = length_of(seg);
        let t = if len > 0.0 {
            ((s - before) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        if let (Some(a), Some(b)) = (path.get(seg), path.get(seg.saturating_add(1)).or(path.get(seg))) {
            *slot = lerp(a, b, t);
        }
    }
    set_ends(&mut out, &first, &last);
    out
}

fn set_ends<const J: usize>(path: &mut [[f32; J]; HORIZON], first: &[f32; J], last: &[f32; J]) {
    if let Some(q) = path.first_mut() {
        *q = *first;
    }
    if let Some(q) = path.last_mut() {
        *q = *last;
    }
}

/// `HORIZON` points that keep every vertex of `path`: each segment gets at least one of the
/// `HORIZON − 1` spans and the rest go, one at a time, to the segment whose spans are
/// longest. Every output segment then lies on a polyline segment, so no corner is cut.
/// `None` when the polyline has more segments than the output. Public for the host's
/// RRT-Connect baseline, whose even resampling can cut a corner too.
pub fn resample_through_vertices<const J: usize>(path: &[[f32; J]]) -> Option<[[f32; J]; HORIZON]> {
    let segments = path.len().checked_sub(1)?;
    if segments == 0 || segments > SPANS {
        return None;
    }
    let length_of = |seg: usize| path.get(seg..seg.saturating_add(2)).map_or(0.0, segment_length);
    let mut spans = [0u32; SPANS];
    for s in spans.iter_mut().take(segments) {
        *s = 1;
    }
    for _ in segments..SPANS {
        // Longest span first: compare len_i / spans_i by cross-multiplying (no division).
        let mut best = 0usize;
        for (i, &c) in spans.iter().enumerate().take(segments) {
            let b = spans.get(best).copied().unwrap_or(1);
            if length_of(i) * b as f32 > length_of(best) * c as f32 {
                best = i;
            }
        }
        if let Some(c) = spans.get_mut(best) {
            *c = c.saturating_add(1);
        }
    }
    let first = *path.first()?;
    let mut out = [first; HORIZON];
    let mut slots = out.iter_mut();
    for (w, &c) in path.windows(2).zip(&spans) {
        if let [a, b] = w {
            for s in 0..c {
                if let Some(slot) = slots.next() {
                    *slot = lerp(a, b, s as f32 / c as f32);
                }
            }
        }
    }
    // Ends exact to the bit (interpolation turns a -0.0 into 0.0).
    set_ends(&mut out, &first, path.last()?);
    Some(out)
}

/// Every segment of `path` through the oracle, stopping at the first blocked one.
fn verify<F, const J: usize>(path: &Path<J>, oracle: &mut Oracle<'_, F>) -> Result<bool, Error>
where
    F: FnMut(&Joints<f32, J>, &Joints<f32, J>) -> Result<bool, Error>,
{
    for w in path.windows(2) {
        if let [a, b] = w
            && !oracle.free(a, b)?
        {
            return Ok(false);
        }
    }
    Ok(true)
}

fn check_finite<const J: usize>(q: &Joints<f32, J>) -> Result<(), Error> {
    match q.iter().position(|v| !v.is_finite()) {
        Some(joint) => Err(Error::NonFiniteJoint {
            joint: u8::try_from(joint).unwrap_or(u8::MAX),
        }),
        None => Ok(()),
    }
}

/// Ends inside the soft limits (the spec's 1e-5 rad tolerance): the trees grow within them, and
/// an end far outside would make path lengths overflow (a fuzz finding:
/// `fuzz/artifacts-kept/search/nan-path-huge-start`).
fn check_within_limits<const J: usize>(robot: &Robot<f32, J>, q: &Joints<f32, J>) -> Result<(), Error> {
    let outside = q
        .iter()
        .zip(robot.soft_lower.iter().zip(robot.soft_upper.iter()))
        .position(|(v, (lo, hi))| !(*v >= lo - LIMIT_TOLERANCE && *v <= hi + LIMIT_TOLERANCE));
    match outside {
        Some(joint) => Err(Error::OutsideLimits {
            joint: u8::try_from(joint).unwrap_or(u8::MAX),
        }),
        None => Ok(()),
    }
}

/// How far outside the soft limits an end may lie (docs/formats.md).
const LIMIT_TOLERANCE: f32 = 1e-5;

/// Uniform in `0..n` for a `usize` bound (`n` fits `u32` here: paths hold < 2^17 points).
fn below(rng: &mut Rng, n: usize) -> usize {
    rng.below(u32::try_from(n).unwrap_or(u32::MAX)) as usize
}

fn distance2<const J: usize>(a: &[f32; J], b: &[f32; J]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// Euclidean length of a two-point window (0 for any other length).
pub(crate) fn segment_length<const J: usize>(w: &[[f32; J]]) -> f32 {
    match w {
        [a, b] => crate::float::sqrt(distance2(a, b)),
        _ => 0.0,
    }
}

fn lerp<const J: usize>(a: &[f32; J], b: &[f32; J], t: f32) -> [f32; J] {
    let mut q = *a;
    for (v, (x, y)) in q.iter_mut().zip(a.iter().zip(b)) {
        *v = x + (y - x) * t;
    }
    q
}

/// `from` moved towards `to` by at most `step` on every joint (exactly `to` when in reach).
fn steer<const J: usize>(from: &Joints<f32, J>, to: &Joints<f32, J>, step: f32) -> Joints<f32, J> {
    let widest = from.iter().zip(to).map(|(a, b)| (b - a).abs()).fold(0.0f32, f32::max);
    if widest <= step {
        return *to;
    }
    lerp(from, to, step / widest)
}

#[cfg(test)]
#[allow(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::arithmetic_side_effects
)]
mod tests {
    use super::*;
    use crate::robot::PANDA;
    use std::boxed::Box;

    // A -0.0 in the start: the output's ends must keep its bits.
    const START: Joints<f32> = [-1.0, -1.0, 0.0, -1.5, -0.0, 1.5, 0.0];
    const GOAL: Joints<f32> = [1.0, -1.0, 0.0, -1.5, 0.0, 1.5, 0.0];

    /// A joint-space wall: the slab `lo ≤ q0 ≤ hi`, open only where `q1` lies in `gap`.
    #[derive(Clone, Copy)]
    struct Wall {
        lo: f32,
        hi: f32,
        gap: Option<(f32, f32)>,
    }

    impl Wall {
        /// Exact: the part of the segment inside the slab is a parameter interval, and `q1`
        /// is linear on it, so it stays in the (convex) gap iff both its ends do.
        fn edge_free(&self, a: &Joints<f32>, b: &Joints<f32>) -> bool {
            let d = b[0] - a[0];
            let (t0, t1) = if d == 0.0 {
                if a[0] < self.lo || a[0] > self.hi {
                    return true;
                }
                (0.0, 1.0)
            } else {
                let (ta, tb) = ((self.lo - a[0]) / d, (self.hi - a[0]) / d);
                (ta.min(tb).max(0.0), ta.max(tb).min(1.0))
            };
            if t0 > t1 {
                return true;
            }
            let Some((g0, g1)) = self.gap else {
                return false;
            };
            let inside = |t: f32| (g0..=g1).contains(&(a[1] + (b[1] - a[1]) * t));
            inside(t0) && inside(t1)
        }
    }

    const GAPPED: Wall = Wall {
        lo: -0.2,
        hi: 0.2,
        gap: Some((0.6, 1.0)),
    };
    const CLOSED: Wall = Wall {
        lo: -0.2,
        hi: 0.2,
        gap: None,
    };

    fn run<const CAP: usize>(
        wall: Option<Wall>,
        config: &SearchConfig,
        seed: u64,
    ) -> (Result<Option<SearchOutcome>, Error>, u64) {
        let mut space = Box::new(SearchSpace::<CAP>::new());
        let mut calls = 0u64;
        let mut oracle = |a: &Joints<f32>, b: &Joints<f32>| {
            calls += 1;
            Ok(wall.is_none_or(|w| w.edge_free(a, b)))
        };
        let out = search(
            &PANDA,
            &START,
            &GOAL,
            config,
            &mut space,
            &mut Rng::new(seed),
            &mut oracle,
        );
        (out, calls)
    }

    fn run_seeded(
        wall: Wall,
        seed_path: &[Joints<f32>],
        config: &SearchConfig,
        seed: u64,
    ) -> (Result<Option<SearchOutcome>, Error>, u64) {
        let mut space = Box::new(SearchSpace::<256>::new());
        let mut calls = 0u64;
        let mut oracle = |a: &Joints<f32>, b: &Joints<f32>| {
            calls += 1;
            Ok(wall.edge_free(a, b))
        };
        let out = search_from(
            &PANDA,
            &START,
            &GOAL,
            seed_path,
            config,
            &mut space,
            &mut Rng::new(seed),
            &mut oracle,
        );
        (out, calls)
    }

    /// `HORIZON` waypoints along the polyline through `corners`, evenly by arc length.
    fn along(corners: &[Joints<f32>]) -> Path {
        resample_even(corners)
    }

    fn assert_valid(o: &SearchOutcome, wall: Option<Wall>) {
        let bits = |q: &Joints<f32>| q.map(f32::to_bits);
        assert_eq!(bits(&o.path[0]), bits(&START));
        assert_eq!(bits(&o.path[HORIZON - 1]), bits(&GOAL));
        for w in o.path.windows(2) {
            assert!(wall.is_none_or(|x| x.edge_free(&w[0], &w[1])), "{w:?}");
        }
        for q in &o.path {
            assert!(PANDA.within_soft_limits(q, 1e-6), "{q:?}");
        }
    }

    #[test]
    fn a_seed_through_the_gap_is_followed_without_sampling() {
        // Up into the gap's band of q1, across the wall, down again: free all the way.
        let (mut up, mut down) = (START, GOAL);
        up[1] = 0.8;
        down[1] = 0.8;
        let seed_path = along(&[START, up, down, GOAL]);
        let config = SearchConfig {
            max_iterations: 0,
            ..SearchConfig::DEFAULT
        };
        let (unseeded, _) = run::<256>(Some(GAPPED), &config, 3);
        assert_eq!(unseeded, Ok(None), "no sampling, no path from the ends alone");
        let (out, calls) = run_seeded(GAPPED, &seed_path, &config, 3);
        let o = out.unwrap().expect("the seed's chains meet");
        assert_valid(&o, Some(GAPPED));
        assert_eq!(o.iterations, 0);
        assert_eq!(u64::from(o.oracle_calls), calls);
        assert!(calls <= config.max_oracle_calls(256));
    }

    #[test]
    #[cfg_attr(miri, ignore = "hundreds of RRT iterations: too slow under Miri")]
    fn a_seed_that_collides_in_the_middle_leaves_only_the_gap_to_bridge() {
        // Straight through the wall below its gap: each chain stops at the wall.
        let seed_path = along(&[START, GOAL]);
        let mut seeded_iterations = 0;
        let mut plain_iterations = 0;
        for seed in 0..8 {
            let (out, calls) = run_seeded(GAPPED, &seed_path, &SearchConfig::DEFAULT, seed);
            let o = out.unwrap().expect("found");
            assert_valid(&o, Some(GAPPED));
            assert!(calls <= SearchConfig::DEFAULT.max_oracle_calls(256));
            // Both chains reach the wall: 2 × 19 inner waypoints lie outside the slab.
            assert!(o.nodes >= 2 + 2 * 19, "{}", o.nodes);
            seeded_iterations += o.iterations;
            let (plain, _) = run::<256>(Some(GAPPED), &SearchConfig::DEFAULT, seed);
            plain_iterations += plain.unwrap().expect("found").iterations;
        }
        // Not a speed claim (the chains end at a wall here), just that seeding is no hindrance
        // by much and the searches are not the same.
        assert!(
            seeded_iterations <= 2 * plain_iterations + 16,
            "{seeded_iterations} vs {plain_iterations}"
        );
        // A seed with a non-finite or out-of-limits waypoint ends its chain there; no error.
        let mut broken = seed_path;
        broken[5][2] = f32::NAN;
        broken[HORIZON - 6][3] = 10.0;
        let (out, _) = run_seeded(GAPPED, &broken, &SearchConfig::DEFAULT, 1);
        assert_valid(&out.unwrap().expect("found"), Some(GAPPED));
    }

    #[test]
    fn free_space_connects_directly() {
        let (out, calls) = run::<64>(None, &SearchConfig::DEFAULT, 1);
        let o = out.unwrap().unwrap();
        assert_valid(&o, None);
        assert_eq!((o.corners, o.iterations, o.nodes, o.even), (2, 0, 2, true));
        assert_eq!(u64::from(o.oracle_calls), calls);
        assert_eq!(calls, 1 + SPANS as u64);
        // Evenly spaced on the straight line.
        let step = (GOAL[0] - START[0]) / SPANS as f32;
        for (k, q) in o.path.iter().enumerate() {
            assert!((q[0] - (START[0] + step * k as f32)).abs() < 1e-5);
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "thousands of RRT iterations: too slow under Miri")]
    fn finds_the_gap_in_a_wall() {
        for seed in 0..20 {
            let (out, calls) = run::<2048>(Some(GAPPED), &SearchConfig::DEFAULT, seed);
            let o = out.unwrap().unwrap_or_else(|| panic!("seed {seed}: no path"));
            assert_valid(&o, Some(GAPPED));
            assert!(o.iterations > 0 && o.corners >= 3, "{seed}: {o:?}");
            assert!(
                o.path
                    .iter()
                    .any(|q| (-0.2..=0.2).contains(&q[0]) && (0.6..=1.0).contains(&q[1]))
            );
            assert_eq!(u64::from(o.oracle_calls), calls);
            assert!(calls <= SearchConfig::DEFAULT.max_oracle_calls(2048));
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "thousands of RRT iterations: too slow under Miri")]
    fn lazy_trees_drop_the_edges_through_a_thin_wall() {
        // A wall thinner than a step: single nodes land on both sides of it, so lazy trees meet
        // through it, check the edges between and drop what lies beyond a blocked one.
        const THIN: Wall = Wall {
            lo: -0.05,
            hi: 0.05,
            gap: Some((0.6, 1.0)),
        };
        let (mut dropped, mut found) = (0, 0);
        for seed in 0..20 {
            let config = SearchConfig::DEFAULT;
            let mut space = Box::new(SearchSpace::<4096>::new());
            let (mut calls, mut blocked) = (0u64, 0);
            let mut oracle = |a: &Joints<f32>, b: &Joints<f32>| {
                calls += 1;
                let free = THIN.edge_free(a, b);
                blocked += usize::from(!free && a != b && THIN.edge_free(a, a) && THIN.edge_free(b, b));
                Ok(free)
            };
            let out = search(
                &PANDA,
                &START,
                &GOAL,
                &config,
                &mut space,
                &mut Rng::new(seed),
                &mut oracle,
            );
            if let Some(o) = out.unwrap() {
                assert_valid(&o, Some(THIN));
                found += 1;
            }
            assert!(calls <= config.max_oracle_calls(4096));
            dropped += usize::from(blocked > 0);
        }
        assert!(
            dropped >= 10 && found == 20,
            "{dropped} searches dropped edges, {found} found"
        );
    }

    #[test]
    fn a_full_tree_reuses_its_dropped_nodes_slots() {
        let mut space = SearchSpace::<8>::new();
        let [mut tree, _] = space.trees(8, 11);
        tree.plant(&mark(0.0));
        // 0 ─ 1 ─ 2 ─ 4 ─ 6, and 1 ─ 3 ─ 5 ─ 7: dropping 3 drops 5 and 7.
        for (i, parent) in [0, 1, 1, 2, 3, 4, 5].into_iter().enumerate() {
            assert_eq!(tree.push(mark(i as f32 + 1.0), parent, Edge::Unchecked), Some(i + 1));
        }
        tree.drop_below(3);
        assert!(tree.has_room(), "compacted");
        assert_eq!(tree.grown(), [0.0, 1.0, 2.0, 4.0, 6.0].map(mark));
        assert_eq!(tree.parents.get(..5), Some(&[0, 0, 1, 2, 3][..]));
        assert_eq!(tree.nearest(&mark(5.0)).map(|(i, _)| i), Some(3));
        assert_eq!(tree.push(mark(9.0), 4, Edge::Unchecked), Some(5));
        for k in 0..2 {
            assert!(tree.has_room());
            tree.push(mark(10.0 + k as f32), 5, Edge::Unchecked);
        }
        assert!(!tree.has_room(), "full, nothing dropped");
        // The limit counts every node added, the dropped ones too.
        tree.drop_below(5);
        assert!(tree.has_room() && tree.push(mark(12.0), 4, Edge::Unchecked) == Some(5));
        assert_eq!((*tree.added, *tree.len), (11, 6));
        assert!(!tree.has_room(), "at the limit");
    }

    #[test]
    #[cfg_attr(miri, ignore = "thousands of RRT iterations: too slow under Miri")]
    fn a_closed_wall_is_no_path_within_the_budget() {
        let config = SearchConfig {
            max_iterations: 300,
            ..SearchConfig::DEFAULT
        };
        let (out, calls) = run::<2048>(Some(CLOSED), &config, 3);
        assert_eq!(out, Ok(None));
        assert!(calls <= config.max_oracle_calls(2048), "{calls}");
        assert!(calls > 300); // it did search, not give up early
    }

    #[test]
    #[cfg_attr(miri, ignore = "thousands of RRT iterations: too slow under Miri")]
    fn deterministic_for_a_seed() {
        let (a, ca) = run::<1024>(Some(GAPPED), &SearchConfig::DEFAULT, 11);
        let (b, cb) = run::<1024>(Some(GAPPED), &SearchConfig::DEFAULT, 11);
        let (a, b) = (a.unwrap().unwrap(), b.unwrap().unwrap());
        let bits = |o: &SearchOutcome| {
            o.path
                .as_flattened()
                .iter()
                .map(|v| v.to_bits())
                .collect::<std::vec::Vec<_>>()
        };
        assert_eq!(bits(&a), bits(&b));
        assert_eq!(
            (a.nodes, a.iterations, a.oracle_calls, a.corners, ca),
            (b.nodes, b.iterations, b.oracle_calls, b.corners, cb)
        );
        let (c, _) = run::<1024>(Some(GAPPED), &SearchConfig::DEFAULT, 12);
        assert_ne!(bits(&a), bits(&c.unwrap().unwrap()));
    }

    #[test]
    fn ends_outside_the_limits_are_typed_errors_not_nan_paths() {
        // The fuzz finding `fuzz/artifacts-kept/search/nan-path-huge-start`: a start far outside
        // the limits once gave waypoints of NaN (the path length overflowed f32).
        let start = [-2.088_445_4e38, -2.588, 1.695, 1.783, -2.121, 1.09e-19, 5.4e-39];
        let goal = [0.0, 3.168, 2.9e-39, 1.824, 3.295, -3.297, 0.039];
        let mut space = std::boxed::Box::new(SearchSpace::<8>::new());
        let mut free = |_: &Joints<f32>, _: &Joints<f32>| Ok(true);
        let out = search(
            &PANDA,
            &start,
            &goal,
            &SearchConfig::DEFAULT,
            &mut space,
            &mut Rng::new(1),
            &mut free,
        );
        assert_eq!(out.err(), Some(Error::OutsideLimits { joint: 0 }));
        let inside = [0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0];
        let out = search(
            &PANDA,
            &inside,
            &goal,
            &SearchConfig::DEFAULT,
            &mut space,
            &mut Rng::new(1),
            &mut free,
        );
        assert_eq!(out.err(), Some(Error::OutsideLimits { joint: 1 }));
    }

    #[test]
    #[cfg_attr(miri, ignore = "thousands of RRT iterations: too slow under Miri")]
    fn work_stays_within_the_documented_bound() {
        // Tight budgets of every kind, against the closed wall (the worst case: no early exit).
        let budgets = [(0, 0, 2), (1, 5, 2), (50, 10, 8), (400, 100, 64), (2000, 0, 300)];
        for ((iterations, shortcuts, nodes), lazy) in budgets.into_iter().flat_map(|b| [(b, true), (b, false)]) {
            let config = SearchConfig {
                max_iterations: iterations,
                shortcuts,
                max_nodes: nodes,
                lazy,
                ..SearchConfig::DEFAULT
            };
            for wall in [CLOSED, GAPPED] {
                for seed in 0..4 {
                    let (out, calls) = run::<256>(Some(wall), &config, seed);
                    assert!(out.is_ok());
                    assert!(calls <= config.max_oracle_calls(256), "{config:?}: {calls}");
                    if let Ok(Some(o)) = out {
                        assert_eq!(u64::from(o.oracle_calls), calls);
                        assert!(o.iterations <= iterations && o.nodes <= 2 * usize::from(nodes));
                    }
                }
            }
        }
        assert_eq!(SearchConfig::DEFAULT.tree_capacity(512), 512);
        assert_eq!(
            SearchConfig::DEFAULT.max_oracle_calls(512),
            1 + 3 + 8000 + 2 * 511 + 6 * 511 + 25 + 98
        );
        let eager = SearchConfig {
            lazy: false,
            ..SearchConfig::DEFAULT
        };
        assert_eq!(eager.max_oracle_calls(512), 1 + 3 + 8000 + 2 * 511 + 25 + 98);
    }

    #[test]
    #[cfg_attr(miri, ignore = "thousands of RRT iterations: too slow under Miri")]
    fn capacity_exhaustion_is_no_path() {
        // Eight nodes per tree cannot reach through the gap; neither can 8 of a larger space.
        let (out, calls) = run::<8>(Some(GAPPED), &SearchConfig::DEFAULT, 5);
        assert_eq!(out, Ok(None));
        assert!(calls <= SearchConfig::DEFAULT.max_oracle_calls(8));
        let small = SearchConfig {
            max_nodes: 8,
            ..SearchConfig::DEFAULT
        };
        let (out, calls) = run::<512>(Some(GAPPED), &small, 5);
        assert_eq!(out, Ok(None));
        assert!(calls <= small.max_oracle_calls(512));
        // One node per tree: only the roots, so only the direct edge can succeed.
        assert_eq!(run::<1>(Some(GAPPED), &SearchConfig::DEFAULT, 5).0, Ok(None));
        assert!(run::<1>(None, &SearchConfig::DEFAULT, 5).0.unwrap().is_some());
    }

    #[test]
    fn bad_input_is_an_error() {
        let mut space = SearchSpace::<16>::new();
        let mut free = |_: &Joints<f32>, _: &Joints<f32>| Ok(true);
        let mut rng = Rng::new(0);
        let mut bad = START;
        bad[3] = f32::NAN;
        let cfg = SearchConfig::DEFAULT;
        assert_eq!(
            search(&PANDA, &bad, &GOAL, &cfg, &mut space, &mut rng, &mut free),
            Err(Error::NonFiniteJoint { joint: 3 })
        );
        bad[3] = f32::INFINITY;
        assert_eq!(
            search(&PANDA, &START, &bad, &cfg, &mut space, &mut rng, &mut free),
            Err(Error::NonFiniteJoint { joint: 3 })
        );
        for config in [
            SearchConfig { step: 0.0, ..cfg },
            SearchConfig { step: -0.3, ..cfg },
            SearchConfig { step: f32::NAN, ..cfg },
            SearchConfig {
                step: f32::INFINITY,
                ..cfg
            },
            SearchConfig { max_nodes: 0, ..cfg },
        ] {
            assert_eq!(
                search(&PANDA, &START, &GOAL, &config, &mut space, &mut rng, &mut free),
                Err(Error::BadParameter)
            );
        }
        // The oracle's own errors come back at once.
        let mut failing = |_: &Joints<f32>, _: &Joints<f32>| Err(Error::SegmentTooLong);
        assert_eq!(
            search(&PANDA, &START, &GOAL, &cfg, &mut space, &mut rng, &mut failing),
            Err(Error::SegmentTooLong)
        );
    }

    #[test]
    #[cfg_attr(miri, ignore = "thousands of RRT iterations: too slow under Miri")]
    fn a_space_can_be_a_static_and_is_reusable() {
        static EMPTY: SearchSpace<4> = SearchSpace::new();
        assert_eq!(EMPTY.len, [0, 0]);
        assert_eq!(
            SearchSpace::<512>::BYTES,
            512 * 2 * (JOINTS * 4 + 2 + 1 + 2) + 4 * core::mem::size_of::<usize>()
        );
        // One space, two searches: the second does not see the first's trees.
        let mut space = Box::new(SearchSpace::<1024>::new());
        let mut oracle = |a: &Joints<f32>, b: &Joints<f32>| Ok(GAPPED.edge_free(a, b));
        let cfg = SearchConfig::DEFAULT;
        let first = search(&PANDA, &START, &GOAL, &cfg, &mut space, &mut Rng::new(9), &mut oracle);
        let again = search(&PANDA, &START, &GOAL, &cfg, &mut space, &mut Rng::new(9), &mut oracle);
        assert_eq!(first, again);
        assert!(first.unwrap().is_some());
    }

    #[test]
    fn chains_are_laid_out_root_first() {
        // Tree 0: 0 ← 1 ← 3, 0 ← 2 ← 4 ← 5; tree 1: 0 ← 1 ← 2. Meeting at (5, 2).
        let mut space = SearchSpace::<8>::new();
        let mark = |v: f32| [v; JOINTS];
        for (i, p) in [0u16, 0, 0, 1, 2, 4].iter().enumerate() {
            space.nodes[0][i] = mark(i as f32);
            space.parents[0][i] = *p;
        }
        for (i, p) in [0u16, 0, 1].iter().enumerate() {
            space.nodes[1][i] = mark(100.0 + i as f32);
            space.parents[1][i] = *p;
        }
        space.len = [6, 3];
        let n = join(&mut space, 5, 2);
        let got: std::vec::Vec<f32> = space.nodes.as_flattened()[..n].iter().map(|q| q[0]).collect();
        // The goal tree's meeting node (102) duplicates the start tree's and is dropped.
        assert_eq!(got, [0.0, 2.0, 4.0, 5.0, 101.0, 100.0]);
    }

    #[test]
    #[cfg_attr(miri, ignore = "thousands of RRT iterations: too slow under Miri")]
    fn shortcuts_only_remove_waypoints_the_oracle_frees() {
        let mut path = [mark(0.0), mark(1.0), mark(2.0), mark(3.0), mark(4.0)];
        // Only 0 → 4 is free besides neighbours: every join must be (0, 4) or none.
        let mut o = |a: &Joints<f32>, b: &Joints<f32>| Ok((a[0] - b[0]).abs() <= 1.0 || (a[0] == 0.0 && b[0] == 4.0));
        let mut oracle = Oracle {
            edge_free: &mut o,
            calls: 0,
            iterations: 0,
        };
        let n = shortcut(&mut path, 200, &mut Rng::new(2), &mut oracle).unwrap();
        assert_eq!(n, 2);
        assert_eq!((path[0][0], path[1][0]), (0.0, 4.0));
        assert!(oracle.calls <= 200);
    }

    #[test]
    #[cfg_attr(miri, ignore = "thousands of RRT iterations: too slow under Miri")]
    fn a_cut_corner_falls_back_to_the_vertices() {
        // An oracle that frees a short segment (< 0.2 rad) only on an edge it freed before:
        // growth and shortcuts work as against the gapped wall, but every even-resampling
        // chord that cuts a corner is refused, so the vertex-keeping fallback must be used.
        let mut approved: std::vec::Vec<(Joints<f32>, Joints<f32>)> = std::vec::Vec::new();
        let on = |p: &Joints<f32>, (a, b): &(Joints<f32>, Joints<f32>)| {
            let ab = distance2(a, b);
            let t = if ab > 0.0 {
                (a.iter().zip(b).zip(p).map(|((x, y), z)| (y - x) * (z - x)).sum::<f32>() / ab).clamp(0.0, 1.0)
            } else {
                0.0
            };
            distance2(&lerp(a, b, t), p) < 1e-8
        };
        let mut oracle = |a: &Joints<f32>, b: &Joints<f32>| {
            let widest = a.iter().zip(b).map(|(x, y)| (y - x).abs()).fold(0.0f32, f32::max);
            if widest < 0.2 && a != b {
                return Ok(approved.iter().any(|e| on(a, e) && on(b, e)));
            }
            let free = GAPPED.edge_free(a, b);
            if free {
                approved.push((*a, *b));
            }
            Ok(free)
        };
        let mut space = Box::new(SearchSpace::<2048>::new());
        let o = search(
            &PANDA,
            &START,
            &GOAL,
            &SearchConfig::DEFAULT,
            &mut space,
            &mut Rng::new(4),
            &mut oracle,
        )
        .unwrap()
        .unwrap();
        assert!(!o.even && o.corners >= 3, "{o:?}");
        assert_valid(&o, Some(GAPPED));
        assert!(u64::from(o.oracle_calls) <= SearchConfig::DEFAULT.max_oracle_calls(2048));
        // An oracle that refuses every short segment fails both resamplings: no path, not an
        // unchecked one.
        let mut calls = 0u64;
        let mut picky = |a: &Joints<f32>, b: &Joints<f32>| {
            calls += 1;
            let widest = a.iter().zip(b).map(|(x, y)| (y - x).abs()).fold(0.0f32, f32::max);
            Ok(widest >= 0.2 && GAPPED.edge_free(a, b))
        };
        let none = search(
            &PANDA,
            &START,
            &GOAL,
            &SearchConfig::DEFAULT,
            &mut space,
            &mut Rng::new(4),
            &mut picky,
        );
        assert_eq!(none, Ok(None));
        assert!(calls <= SearchConfig::DEFAULT.max_oracle_calls(2048));
    }

    fn mark(v: f32) -> Joints<f32> {
        [v; JOINTS]
    }

    #[test]
    fn resamplings_keep_the_ends_and_the_polyline() {
        let poly = [
            [0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0],
            [1.0, 0.3, 0.0, -1.0, 0.0, 1.0, 0.0],
            [2.0, 0.3, 0.0, -1.0, 0.0, 1.0, 0.0],
        ];
        let even = resample_even(&poly);
        assert_eq!((even[0], even[HORIZON - 1]), (poly[0], poly[3]));
        let total = 2.3f32;
        for w in even.windows(2) {
            let d = crate::float::sqrt(distance2(&w[0], &w[1]));
            assert!(d <= total / SPANS as f32 + 1e-5, "{d}");
        }
        let kept = resample_through_vertices(&poly).unwrap();
        assert_eq!((kept[0], kept[HORIZON - 1]), (poly[0], poly[3]));
        for v in &poly {
            assert!(kept.contains(v), "{v:?}");
        }
        // Spans shared by length: 1 : 0.3 : 1 of 49 gives 21, 7, 21 (or a neighbour split).
        assert!(kept.iter().filter(|q| q[1] > 0.0 && q[1] < 0.3).count() >= 5);
        // More segments than spans: no vertex-keeping path.
        assert!(resample_through_vertices(&[[0.0; JOINTS]; HORIZON + 1]).is_none());
        assert!(resample_through_vertices(&[[0.0; JOINTS]; HORIZON]).is_some());
    }
}
