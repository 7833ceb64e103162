//! What the planner returns: every candidate with its verdict, the chosen one, which stage made
//! it, and what the search and the shortening did.

use crate::path::{HORIZON, Path};
use crate::planner::shortcut::ShortcutReport;
use crate::robot::JOINTS;

/// One candidate's verdict.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Verdict {
    /// Swept volume of the final trajectory against the uninflated obstacles (m³·segments).
    pub swept: f32,
    /// Whether the exact checker judged this candidate; `false` only under
    /// [`Judging::Winner`](crate::planner::Judging::Winner), for candidates after the winner in order of swept volume (then
    /// `free` is `false` and `colliding_states` is `u32::MAX`: unknown, never picked).
    pub checked: bool,
    /// Whether the exact checker found no contact anywhere along the trajectory.
    pub free: bool,
    /// States the exact checker found in contact. Counted in full only when no candidate is
    /// free (the fallback ranks by it); otherwise the check of a colliding candidate stops at
    /// its first contact and this is 1. 0 exactly when `free`.
    pub colliding_states: u32,
    /// Whether the planner made this candidate: `false` only for the rows of waves that did
    /// not run ([`PlanConfig::waves`](crate::planner::PlanConfig::waves)); then the path is all zeros, `checked` and `free` are
    /// `false`, `swept` is +∞ and `colliding_states` is `u32::MAX`, and it is never picked.
    pub made: bool,
}

/// The planner's output: every candidate (row `r` followed guide `r / k`), its verdict, and the
/// chosen one.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan<const B: usize, const J: usize = JOINTS> {
    /// The candidates, each inside the soft joint limits, starting at the start and ending at
    /// the goal.
    pub paths: [Path<J>; B],
    /// The checker's and the swept cost's verdict on each.
    pub verdicts: [Verdict; B],
    /// Index of the chosen candidate: the free one with the lowest swept volume (lowest index on
    /// ties), or, if none is free, the one with the fewest colliding states (then swept volume).
    pub best: usize,
    /// Which stage produced the chosen candidate. After the global stage, `paths` are its
    /// reseeded candidates, and with [`Stage::Search`] row `best` holds the search path.
    pub stage: Stage,
    /// What the global stage's search did, when it ran.
    pub search: Option<SearchReport>,
    /// What shortening did to the chosen candidate, when it ran (a free plan with
    /// `PlanConfig::shortcut`).
    pub shortcut: Option<ShortcutReport>,
}

impl<const B: usize, const J: usize> Plan<B, J> {
    /// Zero candidates, not yet judged: the memory a plan is built in.
    pub const fn empty() -> Self {
        Self {
            paths: [[[0.0; J]; HORIZON]; B],
            verdicts: [Verdict {
                swept: 0.0,
                checked: false,
                free: false,
                colliding_states: 0,
                made: true,
            }; B],
            best: 0,
            stage: Stage::None,
            search: None,
            shortcut: None,
        }
    }

    /// Whether the chosen candidate passed the exact checker.
    pub fn is_free(&self) -> bool {
        self.verdicts.get(self.best).is_some_and(|v| v.free)
    }

    /// FNV-1a (64 bit) over the bits of every candidate, every verdict and the chosen index:
    /// equal fingerprints on two machines mean the same plan, bit for bit.
    pub fn fingerprint(&self) -> u64 {
        let mut hash = 0xcbf2_9ce4_8422_2325u64;
        let mut eat = |word: u32| {
            for byte in word.to_le_bytes() {
                hash = (hash ^ u64::from(byte)).wrapping_mul(0x0000_0100_0000_01b3);
            }
        };
        for path in &self.paths {
            for v in path.iter().flatten() {
                eat(v.to_bits());
            }
        }
        for verdict in &self.verdicts {
            eat(verdict.swept.to_bits());
            eat(u32::from(verdict.checked));
            eat(u32::from(verdict.free));
            eat(verdict.colliding_states);
        }
        eat(self.best as u32);
        eat(self.stage as u32);
        if let Some(s) = &self.shortcut {
            eat(s.length_after.to_bits());
        }
        hash
    }
}

/// Which stage produced the chosen trajectory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The guided diffusion from noise (EDMP's Algorithm 2).
    Diffusion,
    /// The prior and the guides, started from the search's path noised to an intermediate step.
    Reseeded,
    /// The search's own path (shortcut and resampled): no reseeded candidate was free.
    Search,
    /// Nothing was free; the least colliding candidate is returned.
    None,
}

impl Stage {
    /// A short name for plans and tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::Diffusion => "diffusion",
            Self::Reseeded => "reseeded",
            Self::Search => "search",
            Self::None => "none",
        }
    }
}

/// What the search did, when it ran.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SearchReport {
    /// Whether it found a path.
    pub found: bool,
    /// Tree nodes grown (both trees; 0 when nothing was found, since a failed search reports
    /// no trees).
    pub nodes: u32,
    /// Sampling iterations of the last attempt (when nothing was found: the budget, which the
    /// trees' capacity may have cut short).
    pub iterations: u32,
    /// Searches run ([`GlobalConfig::attempts`](crate::planner::GlobalConfig::attempts) at most): the last one found the path, or all
    /// failed.
    pub attempts: u8,
    /// Segment checks asked of the exact checker.
    pub segment_checks: u32,
}
