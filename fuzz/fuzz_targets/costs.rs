//! Arbitrary scenes, trajectories and cost settings (raw f32 bits: NaN, infinities, huge and
//! tiny values). The costs must return a finite, non-negative value with a finite gradient or a
//! typed error that matches the input; a row's `CostMemo`, told which waypoint moved, must give
//! the bits of a fresh evaluation; the exact checker must answer or refuse, never panic.
#![no_main]

use edmp_core::robot::PANDA;
use edmp_core::Error;
use edmp_core::collision::checker::{CheckConfig, check_state, check_trajectory};
use edmp_core::cost::{CostConfig, CostKind, CostMemo, trajectory_cost, trajectory_cost_memo};
use edmp_core::cost::boxes::{BoxFrame, CylinderBox, Inflation};
use edmp_core::scene::{Obstacle, Scene, SceneError};
use libfuzzer_sys::fuzz_target;

const H: usize = 8;

struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn byte(&mut self) -> u8 {
        let (&b, rest) = self.0.split_first().unwrap_or((&0, &[]));
        self.0 = rest;
        b
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes([self.byte(), self.byte(), self.byte(), self.byte()])
    }
    fn array<const M: usize>(&mut self) -> [f32; M] {
        core::array::from_fn(|_| self.f32())
    }
}

/// Builds an obstacle, retrying with a normalised quaternion so valid shapes are common.
fn obstacle(kind: u8, center: [f32; 3], size: [f32; 3], quat: [f32; 4]) -> Result<Obstacle, SceneError> {
    let build = |q: [f32; 4]| match kind % 3 {
        0 => Obstacle::cuboid(center, size, q),
        1 => Obstacle::cylinder(center, size[0], size[1], q),
        _ => Obstacle::sphere(center, size[0]),
    };
    match build(quat) {
        Err(SceneError::QuaternionNorm) => {
            let n = quat.iter().map(|v| v * v).sum::<f32>().sqrt();
            if n.is_finite() && n > 1e-3 { build(quat.map(|v| v / n)) } else { Err(SceneError::QuaternionNorm) }
        }
        other => other,
    }
}

fuzz_target!(|data: &[u8]| {
    let mut r = Reader(data);
    let count = r.byte() % 9;
    let flags = r.byte();
    let mut scene = Scene::<8>::new();
    for _ in 0..count {
        let kind = r.byte();
        let (center, size, quat) = (r.array::<3>(), r.array::<3>(), r.array::<4>());
        if let Ok(o) = obstacle(kind, center, size, quat) {
            assert!(o.center.iter().chain(o.rotation.iter()).all(|x| x.is_finite()));
            scene.push(o).expect("capacity 8 holds at most 8");
        }
    }
    if flags & 4 != 0 {
        let kind = r.byte();
        let (center, size, quat) = (r.array::<3>(), r.array::<3>(), r.array::<4>());
        if let Ok(o) = obstacle(kind, center, size, quat) {
            scene.hold(o);
        }
    }
    let inflation = Inflation { clearance: r.f32(), expansion: r.f32() };
    let trajectory: [[f32; 7]; H] = core::array::from_fn(|_| r.array::<7>());
    let kind = match (flags & 32 != 0, flags & 1 == 0) {
        (true, _) => CostKind::Clearance,
        (false, true) => CostKind::Intersection,
        (false, false) => CostKind::Swept,
    };
    let cylinder = if flags & 2 == 0 { CylinderBox::Enclosing } else { CylinderBox::OriginalEdmp };
    let frame = if flags & 16 == 0 { BoxFrame::Obstacle } else { BoxFrame::World };
    let config = CostConfig { kind, inflation, cylinder, frame };

    let joints_finite = trajectory.iter().flatten().all(|x| x.is_finite());
    let params_ok = inflation.clearance.is_finite()
        && inflation.expansion.is_finite()
        && inflation.clearance >= 0.0
        && inflation.expansion >= 0.0;
    let mut gradient = [[0.0f32; 7]; H];
    match trajectory_cost(&PANDA, &scene, &trajectory, &config, Some(&mut gradient)) {
        Ok(cost) => {
            assert!(joints_finite && params_ok);
            assert!(cost.is_finite() && cost >= 0.0, "cost {cost}");
            assert!(gradient.iter().flatten().all(|g| g.is_finite()), "{gradient:?}");
        }
        Err(Error::BadParameter) => assert!(!params_ok),
        Err(Error::NonFiniteJoint { .. }) => assert!(params_ok && !joints_finite),
        Err(Error::Overflow) | Err(Error::NonFiniteGradient) => assert!(params_ok && joints_finite),
        Err(e) => panic!("unexpected cost error {e:?}"),
    }

    // The memo: evaluate, move one waypoint by the input's amount, report it, evaluate again.
    let mut memo = CostMemo::NONE;
    let first = trajectory_cost_memo(&PANDA, &scene, &trajectory, &config, Some(&mut gradient), Some(&mut memo));
    let (w, j, by) = (usize::from(r.byte()) % H, usize::from(r.byte()) % 7, r.f32());
    let mut moved = trajectory;
    moved[w][j] += by;
    if moved[w][j].to_bits() != trajectory[w][j].to_bits() {
        memo.moved(1 << w);
    }
    let mut fresh = [[0.0f32; 7]; H];
    let mut memoed = [[0.0f32; 7]; H];
    let want = trajectory_cost(&PANDA, &scene, &moved, &config, Some(&mut fresh));
    let got = trajectory_cost_memo(&PANDA, &scene, &moved, &config, Some(&mut memoed), Some(&mut memo));
    if first.is_ok() {
        let bits = |x: Result<f32, Error>| x.map(f32::to_bits);
        assert_eq!(bits(got), bits(want), "memo after moving waypoint {w}");
        if want.is_ok() {
            let g = |x: &[[f32; 7]; H]| x.map(|q| q.map(f32::to_bits));
            assert_eq!(g(&memoed), g(&fresh), "memo gradient after moving waypoint {w}");
        }
    }

    let check = CheckConfig { self_collision: flags & 8 == 0, ..CheckConfig::default() };
    for q in trajectory.iter().take(2) {
        match check_state(&edmp_core::robot::PANDA, &scene, q, &check) {
            Ok(_) => assert!(q.iter().all(|x| x.is_finite())),
            Err(Error::NonFiniteJoint { .. }) => assert!(!q.iter().all(|x| x.is_finite())),
            Err(e) => panic!("unexpected checker error {e:?}"),
        }
    }
    let short: [[f32; 7]; 2] = [trajectory[0], trajectory[1]];
    match check_trajectory(&edmp_core::robot::PANDA, &scene, &short, &check, true) {
        // Stopping at the first contact may end after one state; a free report saw both ends.
        Ok(report) => {
            assert!(report.states >= 1 && report.colliding_states <= report.states);
            assert!(report.first_contact.is_some() || report.states >= 2);
            assert_eq!(report.first_contact.is_some(), report.colliding_states > 0);
        }
        Err(Error::NonFiniteJoint { .. }) | Err(Error::SegmentTooLong) => {}
        Err(e) => panic!("unexpected trajectory check error {e:?}"),
    }
});
