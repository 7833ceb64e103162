//! EDMP's ensemble of guides as data: one row per guide, each a cost kind and three schedules
//! over the diffusion step t (clearance c(t), expansion e(t), step size s(t)) plus whether its
//! gradient is normalized. The table is the original's `cfg1` (the original implementation, vishal-2000/EDMP:
//! guides 1-5, 10, 11, 13, 14, 16, 18, 21); the planner reads it, it holds no code.

use crate::cost::CostKind;
use crate::cost::boxes::Inflation;

/// A value that depends on the diffusion step. `i = t − 1` (0 ..= 254), as the original indexes
/// its per-step tables.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Schedule {
    /// The same value at every step.
    Constant(f32),
    /// `from + (to − from)·i/254`: NumPy's `linspace(from, to, 255)[i]`.
    Linear {
        /// Value at i = 0 (t = 1).
        from: f32,
        /// Value at i = 254 (t = 255).
        to: f32,
    },
    /// 0 below `start`, `value·(i − origin)/(end − origin)` for `start ≤ i ≤ end`, `value`
    /// above `end` (the original's expansion ramps; `origin` may precede `start`).
    Ramp {
        /// First step index of the ramp.
        start: u16,
        /// Index at which the ramp's line crosses zero.
        origin: u16,
        /// Last index of the ramp; the value holds after it.
        end: u16,
        /// The value the ramp reaches.
        value: f32,
    },
    /// 0 below `start`, `value` from it on.
    Step {
        /// First step index with `value`.
        start: u16,
        /// The value.
        value: f32,
    },
    /// `base + i/255`: the original's "varying" step size (2.396 at t = 255, 1.42 at t = 6).
    Varying {
        /// Value at i = 0.
        base: f32,
    },
}

impl Schedule {
    /// The value at diffusion step `t` (1 ..= 255; outside, the nearest end).
    pub fn at(&self, t: u16) -> f32 {
        let i = t.clamp(1, 255) - 1;
        match *self {
            Self::Constant(v) => v,
            Self::Linear { from, to } => from + (to - from) * f32::from(i) / 254.0,
            Self::Ramp {
                start,
                origin,
                end,
                value,
            } => {
                if i < start {
                    0.0
                } else if i > end {
                    value
                } else {
                    value * f32::from(i - origin) / f32::from(end - origin)
                }
            }
            Self::Step { start, value } => {
                if i < start {
                    0.0
                } else {
                    value
                }
            }
            Self::Varying { base } => base + f32::from(i) / 255.0,
        }
    }
}

/// One member of the ensemble.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Guide {
    /// The original's guide number (its `guideN.yaml`).
    pub id: u8,
    /// Intersection volume of the interior waypoints, or swept volume of the segments.
    pub cost: CostKind,
    /// Clearance c(t), metres added to every full extent of every obstacle box.
    pub clearance: Schedule,
    /// Expansion e(t), metres: every full extent raised to at least this.
    pub expansion: Schedule,
    /// Whether the gradient is scaled to unit norm before the step (per guide, with a zero guard;
    /// the original's batched version divides by the norm of the whole batch, 0/0 included).
    pub normalize: bool,
    /// Step size s(t): the interior waypoints move by −s(t)·gradient.
    pub step: Schedule,
    /// Weight of the smoothness term: where the cost pulls a row, its waypoints also move by
    /// `−smooth·∇½Σ|q_{i−1} − 2q_i + q_{i+1}|²` ([`crate::guidance::bending_gradient`]), so that
    /// the guide does not buy clearance with jerk. 0 in EDMP's table (an ablation; below 1/8).
    pub smooth: f32,
}

impl Guide {
    /// The obstacle inflation this guide uses at step `t`.
    pub fn inflation(&self, t: u16) -> Inflation {
        Inflation {
            clearance: self.clearance.at(t),
            expansion: self.expansion.at(t),
        }
    }
}

/// EDMP's step size when the gradient is not normalized.
const VARYING: Schedule = Schedule::Varying { base: 1.4 };
/// Expansion of guides 11, 13, 14 and 16: 0.4·(i − 20)/129 from i = 20, 0.4 from i = 150.
const E11: Schedule = Schedule::Ramp {
    start: 20,
    origin: 20,
    end: 149,
    value: 0.4,
};
/// Expansion of guides 18 and 21: 0.4·(i − 10)/29 from i = 20 (0.138), 0.4 from i = 40.
const E18: Schedule = Schedule::Ramp {
    start: 20,
    origin: 10,
    end: 39,
    value: 0.4,
};

const fn iv(id: u8, clearance: Schedule) -> Guide {
    Guide {
        id,
        cost: CostKind::Intersection,
        clearance,
        expansion: Schedule::Constant(0.0),
        normalize: false,
        step: VARYING,
        smooth: 0.0,
    }
}

const fn sv(id: u8, clearance: f32, expansion: Schedule, normalize: bool, step: Schedule) -> Guide {
    Guide {
        id,
        cost: CostKind::Swept,
        clearance: Schedule::Constant(clearance),
        expansion,
        normalize,
        step,
        smooth: 0.0,
    }
}

/// Number of guides in EDMP's ensemble.
pub const EDMP_GUIDE_COUNT: usize = 12;

/// EDMP's 12 guides (`cfg1`): 5 intersection, 7 swept volume, in the original's order.
pub const EDMP_GUIDES: [Guide; EDMP_GUIDE_COUNT] = [
    iv(1, Schedule::Constant(0.10)),
    iv(2, Schedule::Constant(0.05)),
    iv(3, Schedule::Constant(0.01)),
    iv(4, Schedule::Constant(0.15)),
    iv(5, Schedule::Linear { from: 0.01, to: 0.15 }),
    sv(10, 0.06, Schedule::Step { start: 80, value: 0.4 }, false, VARYING),
    sv(11, 0.00, E11, true, Schedule::Constant(0.05)),
    sv(13, 0.00, E11, true, Schedule::Constant(0.01)),
    sv(14, 0.02, E11, true, Schedule::Constant(0.10)),
    sv(16, 0.10, E11, true, Schedule::Constant(0.10)),
    sv(18, 0.05, E18, true, Schedule::Constant(0.05)),
    sv(21, 0.05, E18, true, Schedule::Constant(0.10)),
];

/// A guide on the exact clearance of the checker's hulls ([`CostKind::Clearance`]; not one of
/// EDMP's): 3 cm of clearance, a normalized step of 0.05. The refinement's ablation
/// ([`crate::planner::PlanConfig::refine_guide`]) gives it to every row.
pub const CLEARANCE_GUIDE: Guide = Guide {
    id: 30,
    cost: CostKind::Clearance,
    clearance: Schedule::Constant(0.03),
    expansion: Schedule::Constant(0.0),
    normalize: true,
    step: Schedule::Constant(0.05),
    smooth: 0.0,
};

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() <= 1e-5
    }

    #[test]
    fn the_table_matches_the_reference_numbers() {
        let by_id = |id: u8| EDMP_GUIDES.iter().find(|g| g.id == id).unwrap();
        assert_eq!(
            EDMP_GUIDES.iter().filter(|g| g.cost == CostKind::Intersection).count(),
            5
        );
        assert_eq!(EDMP_GUIDES.iter().filter(|g| g.cost == CostKind::Swept).count(), 7);
        // Varying step: 1.4 + (t − 1)/255.
        assert!(close(by_id(1).step.at(255), 2.396_078));
        assert!(close(by_id(1).step.at(6), 1.419_608));
        // Guide 5: linspace(0.01, 0.15, 255).
        assert!(close(by_id(5).clearance.at(1), 0.01));
        assert!(close(by_id(5).clearance.at(255), 0.15));
        // Guide 10: 0.4 from i = 80 (t = 81).
        assert_eq!(by_id(10).expansion.at(80), 0.0);
        assert_eq!(by_id(10).expansion.at(81), 0.4);
        // e11: 0 for i < 20, 0.4·(i − 20)/129 up to i = 149, then 0.4.
        let e11 = by_id(11).expansion;
        assert_eq!(e11.at(20), 0.0);
        assert!(close(e11.at(21 + 64), 0.4 * 64.0 / 129.0));
        assert!(close(e11.at(150), 0.4));
        assert_eq!(e11.at(255), 0.4);
        // e18: i = 20 gives 0.4·10/29 = 0.138; 0.4 from i = 40; 0 below i = 20.
        let e18 = by_id(18).expansion;
        assert_eq!(e18.at(20), 0.0);
        assert!(close(e18.at(21), 0.4 * 10.0 / 29.0));
        assert!(close(e18.at(41), 0.4));
        assert_eq!(by_id(21).expansion, e18);
        // Normalized guides are exactly the sv ones after guide 10.
        assert!(
            EDMP_GUIDES
                .iter()
                .all(|g| g.normalize == matches!(g.id, 11 | 13 | 14 | 16 | 18 | 21))
        );
        assert_eq!(by_id(13).step.at(100), 0.01);
        assert_eq!(
            by_id(16).inflation(1),
            Inflation {
                clearance: 0.10,
                expansion: 0.0
            }
        );
    }

    #[test]
    fn schedules_clamp_steps_outside_the_table() {
        let e11 = E11;
        assert_eq!(e11.at(0), e11.at(1));
        assert_eq!(e11.at(1000), e11.at(255));
        assert!(EDMP_GUIDES.iter().all(|g| {
            (0..=300).all(|t| g.step.at(t).is_finite() && g.clearance.at(t) >= 0.0 && g.expansion.at(t) >= 0.0)
        }));
    }
}
