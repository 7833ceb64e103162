//! Arbitrary scenes, ends and planner settings through the core planner with a short schedule:
//! it must return a plan whose every candidate is finite, starts at the start and ends at the
//! goal, or a typed error; never a panic, never a NaN. The work per input is bounded by the
//! settings (at most 3 denoising steps, 2 gradient steps each, 12 rows); the refinement's early
//! stop (`PlanConfig::refine_stop`) is fuzzed too, zero settings (typed errors) included.
#![no_main]

use edmp_core::robot::PANDA;
use edmp_core::collision::checker::CheckConfig;
use edmp_core::cost::boxes::{BoxFrame, CylinderBox};
use edmp_core::planner::{GlobalConfig, MAX_ATTEMPTS};
use edmp_core::guidance::guides::{CLEARANCE_GUIDE, EDMP_GUIDES};
use edmp_core::planner::{Request, GuidanceSchedule, Judging, PlanConfig, RefineStop, Workspace, plan};
use edmp_core::prior::{Sampler, Scratch};
use edmp_core::path::HORIZON;
use edmp_core::rng::Rng;
use edmp_core::scene::{Obstacle, Scene};
use edmp_core::planner::search::SearchConfig;
use edmp_core::planner::shortcut::ShortcutConfig;
use libfuzzer_sys::fuzz_target;

struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn byte(&mut self) -> u8 {
        let (&b, rest) = self.0.split_first().unwrap_or((&0, &[]));
        self.0 = rest;
        b
    }
    /// Raw bits half the time (NaN, infinities, huge values), a tame value in [-4, 4) otherwise.
    fn f32(&mut self) -> f32 {
        let raw = f32::from_le_bytes([self.byte(), self.byte(), self.byte(), self.byte()]);
        if self.byte() & 1 == 0 {
            raw
        } else {
            (raw.to_bits() % 8000) as f32 / 1000.0 - 4.0
        }
    }
    fn array<const M: usize>(&mut self) -> [f32; M] {
        core::array::from_fn(|_| self.f32())
    }
}

fuzz_target!(|data: &[u8]| {
    let mut r = Reader(data);
    let count = r.byte() % 5;
    let mut scene = Scene::<4>::new();
    for _ in 0..count {
        let (kind, center, size) = (r.byte(), r.array::<3>(), r.array::<3>());
        let built = match kind % 3 {
            0 => Obstacle::cuboid(center, size, [1.0, 0.0, 0.0, 0.0]),
            1 => Obstacle::cylinder(center, size[0], size[1], [1.0, 0.0, 0.0, 0.0]),
            _ => Obstacle::sphere(center, size[0]),
        };
        if let Ok(o) = built {
            scene.push(o).expect("capacity 4 holds at most 4");
        }
    }
    let (start, goal) = (r.array::<7>(), r.array::<7>());
    let steps = u16::from(r.byte() % 4);
    let mut config = PlanConfig {
        sampler: if r.byte() & 1 == 0 {
            Sampler::Strided { steps }
        } else {
            Sampler::Ddim { steps }
        },
        guidance: GuidanceSchedule::Every { per_step: r.byte() % 3 },
        condition: r.byte() & 1 == 0,
        refine: r.byte() % 3,
        step_limit: if r.byte() & 1 == 0 { f32::INFINITY } else { 0.1 },
        cylinder: CylinderBox::Enclosing,
        frame: if r.byte() & 1 == 0 {
            BoxFrame::Obstacle
        } else {
            BoxFrame::World
        },
        check: CheckConfig::default(),
        // The global stage with a small, fuzzed budget and noise level (it runs only when no
        // candidate is free, which most fuzzed scenes reach).
        global: if r.byte() & 1 == 0 {
            None
        } else {
            Some(GlobalConfig {
                search: SearchConfig {
                    max_iterations: u32::from(r.byte()),
                    max_nodes: u16::from(r.byte()).max(1),
                    ..SearchConfig::DEFAULT
                },
                noise_step: u16::from(r.byte()),
                steps: u16::from(r.byte() % 4),
                per_step: r.byte() % 3,
                refine: r.byte() % 3,
                // Fuzzed last (below).
                attempts: 1,
                seeded: false,
            })
        },
        // Shortening of a free winner, with a fuzzed budget.
        shortcut: if r.byte() & 1 == 0 {
            None
        } else {
            Some(ShortcutConfig {
                greedy_checks: u32::from(r.byte() % 80),
                attempts: u32::from(r.byte() % 16),
                smoothing: r.byte() % 4,
            })
        },
        refine_stop: None,
        refine_guide: None,
        step_control: false,
        judging: Judging::Every,
        start_draws: u8::MAX,
        waves: 1,
        first_stage_waves: u8::MAX,
        wave_budget: None,
    };
    let count = [1, 2, 3, 4, 6, 12][usize::from(r.byte() % 6)];
    let mut scratch = Box::new(Scratch::<4>::new());
    let mut work = Box::new(Workspace::<12>::new());
    let seed = u64::from(r.byte());
    // Read last, so the inputs kept from before it still mean what they meant.
    if r.byte() & 1 == 1 {
        config.refine_stop = Some(RefineStop {
            every: r.byte() % 4,
            free: r.byte() % 14,
            stall: 0,
        });
    }
    // The optimizer's ablations: step-size control, the clearance refinement, a smoothness term.
    let extra = r.byte();
    config.step_control = extra & 1 != 0;
    if extra & 8 != 0 {
        config.judging = Judging::Winner;
    }
    if extra & 2 != 0 {
        config.refine_guide = Some(CLEARANCE_GUIDE);
    }
    // Searches of the global stage, 1-8 (an input that ends before this byte: 1, as before).
    // Then whether the search is seeded (an input that ends before it: unseeded, as before).
    if let Some(global) = &mut config.global {
        global.attempts = 1 + r.byte() % MAX_ATTEMPTS;
        global.seeded = r.byte() & 1 == 1;
    }
    // Then the refinement's stall stop (an input that ends before it: none, as before).
    if let Some(stop) = &mut config.refine_stop {
        stop.stall = r.byte() % 24;
    }
    // Then the draws the rows start from (an input that ends before it: one per row, as before;
    // 0 after the modulo counts as 1).
    config.start_draws = match r.byte() {
        0 => u8::MAX,
        b => b % 14,
    };
    // Then the waves (an input that ends before it: one, as before; 0 is refused, 5 runs as
    // the most waves up to 5 that divide the guides).
    config.waves = [1, 2, 3, 4, 6, 12, 0, 5][usize::from(r.byte() % 8)];
    // Then the first stage's cap on its waves (an input that ends before it: all, as before;
    // 0 is refused).
    config.first_stage_waves = match r.byte() {
        0 => u8::MAX,
        b => b % 5,
    };
    // Then the bound on the waves in guide boxes × waves (an input that ends before it: none,
    // as before; any budget runs at least one wave of each stage).
    config.wave_budget = match r.byte() {
        0 => None,
        b => Some(u16::from(b) % 80),
    };
    let mut table = EDMP_GUIDES;
    for g in &mut table {
        g.smooth = if extra & 4 != 0 { 0.1 } else { 0.0 };
    }
    let guides = &table[..count];
    if let Ok(p) = plan(&Request { robot: &PANDA, network: edmp_core::prior::PANDA, scene: &scene, start: &start, goal: &goal, guides: guides, config: &config }, &mut Rng::new(seed), &mut scratch, &mut work) {
        assert!(steps >= 1);
        for (path, verdict) in p.paths.iter().zip(&p.verdicts) {
            assert!(path.iter().flatten().all(|v| v.is_finite()));
            if verdict.made {
                assert_eq!(path[0], start);
                assert_eq!(path[HORIZON - 1], goal);
                assert!(verdict.swept.is_finite() && verdict.swept >= 0.0);
            } else {
                // Only rows of waves that did not run, and never the winner.
                assert!(config.waves > 1 && !verdict.checked && !verdict.free);
            }
        }
        assert!(p.verdicts.get(p.best).is_some_and(|v| v.made));
        // The chosen candidate is always judged, whichever candidates the judge skipped.
        assert!(p.verdicts.get(p.best).is_some_and(|v| v.checked));
    }
});
