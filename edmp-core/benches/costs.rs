//! EDMP's two costs with their gradient on one row through the suite's heaviest kind of scene
//! (dresser-000's 28 boxes, the straight line from start to goal, which runs into them), the
//! kernel the guides spend most of a hard plan in. Run: `cargo bench -p edmp-core --bench costs`.

use criterion::{Criterion, criterion_group, criterion_main};
use edmp_core::cost::boxes::{BoxFrame, CylinderBox, Inflation};
use edmp_core::cost::{CostConfig, CostKind, trajectory_cost};
use edmp_core::path::{HORIZON, Path};
use edmp_core::scene::{Obstacle, Scene};
use serde_json::Value;

const DRESSER: &str = include_str!("../../benchmarks/problems/dresser/000.json");

fn floats<const K: usize>(v: &Value) -> [f32; K] {
    core::array::from_fn(|i| v[i].as_f64().expect("a number") as f32)
}

fn dresser() -> (Scene<'static, 64>, Path) {
    let problem: Value = serde_json::from_str(DRESSER).expect("the committed problem parses");
    let mut scene = Scene::new();
    for o in problem["obstacles"].as_array().expect("obstacles") {
        assert_eq!(o["type"], "cuboid", "dresser-000 holds cuboids alone");
        let box_ = Obstacle::cuboid(floats(&o["center"]), floats(&o["dims"]), floats(&o["quaternion"]));
        scene.push(box_.expect("a valid box")).expect("room for it");
    }
    let (start, goal): ([f32; 7], [f32; 7]) = (floats(&problem["start"]), floats(&problem["goal"]["joints"]));
    let line = core::array::from_fn(|i| {
        let s = i as f32 / (HORIZON - 1) as f32;
        core::array::from_fn(|j| start[j] + (goal[j] - start[j]) * s)
    });
    (scene, line)
}

fn bench(c: &mut Criterion) {
    let (scene, line) = dresser();
    let mut group = c.benchmark_group("costs");
    for kind in [CostKind::Intersection, CostKind::Swept] {
        let config = CostConfig {
            kind,
            inflation: Inflation {
                clearance: 0.05,
                expansion: 0.1,
            },
            cylinder: CylinderBox::Enclosing,
            frame: BoxFrame::Obstacle,
        };
        let mut gradient = [[0.0f32; 7]; HORIZON];
        let cost = trajectory_cost(&edmp_core::robot::PANDA, &scene, &line, &config, Some(&mut gradient)).unwrap();
        assert!(cost > 0.0, "the straight line runs into the dresser");
        group.bench_function(format!("dresser-000, straight line, {kind:?}, with gradient"), |b| {
            b.iter(|| trajectory_cost(&edmp_core::robot::PANDA, &scene, &line, &config, Some(&mut gradient)))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
