//! The exact-clearance cost: how far the checker's own shapes come inside a clearance `c` of the
//! true obstacles, with its hand-written adjoint.
//!
//! EDMP's costs compare boxes: every link's oriented box against every obstacle's inflated box.
//! The checker judges something else, each moving body's convex hull (and the held object)
//! against the exact primitives, so a row can be box-free and still touch, or touch in the boxes
//! where the hulls pass (a 26 cm slot between bars is narrower than a forearm's box, not its
//! hull). This cost measures what the checker measures: over the segments, bodies and
//! obstacles, `Σ max(0, c − gap)²`, each body on a segment being the convex hull of its two
//! placements (as EDMP's swept volume unions a segment's two boxes: a cost on the waypoints
//! alone let rows slip through thin boards between them, measured), and `gap` the signed
//! separation of that hull and the obstacle along a direction `n`:
//! - apart: `n` is the direction GJK finds from the obstacle to the body, and `gap` the exact
//!   lower bound along it (`gjk::gap_along`), the distance up to f32;
//! - overlapping (GJK finds the origin inside): `n` is the best of the obstacle's face normals
//!   (both ways) and the direction between the centres, and `gap < 0` the depth along it (the
//!   shallowest way out that these directions offer).
//!
//! The gradient keeps `n` fixed (at the optimum direction the gap is stationary in it) and moves
//! the support point in `−n`, a point of the closest feature, rigidly with its frame at the
//! segment end it belongs to: a force `−2 (c − gap) n` there ([`Cotangent::add_point`]), then the
//! FK adjoint. Where a face is the closest feature the moment is that of one of its vertices, not
//! of the witness point: the joint gradient is then a descent direction, not the exact derivative.
//!
//! Work: one FK per waypoint; per (body, segment, obstacle) whose bounding balls come within `c`,
//! a GJK on the body's two oriented boxes (which hold its hulls), and only where those come within
//! `c` a GJK on the hulls. A guide with this cost is data like any other
//! ([`crate::guidance::guides::CLEARANCE_GUIDE`]).

use crate::collision::checker::moves;
use crate::collision::convex::{Convex, Hull, Solid};
use crate::collision::gjk::{closest, gap_along};
use crate::error::Error;
use crate::robot::kinematics::{Cotangent, Joints, Kinematics, forward_with};
use crate::robot::{MAX_BODIES, MAX_FRAMES, Robot};
use crate::scene::Scene;
use nalgebra::Vector3;

/// `Σ max(0, clearance − gap)²` over the `H − 1` segments of `trajectory`, every moving body
/// (and the held object) and every obstacle of `scene`, each body on a segment being the convex
/// hull of its placements at the two ends (the swept volume's analogue: a path cannot slip
/// through a thin board between waypoints); with `gradient`, its gradient with respect to every
/// waypoint (zero at the ends). Non-finite joints and a negative or non-finite clearance are
/// typed errors; so is an overflowing result.
pub fn trajectory_cost<const H: usize, const N: usize, const J: usize>(
    robot: &'static Robot<f32, J>,
    scene: &Scene<N>,
    trajectory: &[Joints<f32, J>; H],
    clearance: f32,
    gradient: Option<&mut [Joints<f32, J>; H]>,
) -> Result<f32, Error> {
    if !(clearance.is_finite() && clearance >= 0.0) {
        return Err(Error::BadParameter);
    }
    for q in trajectory {
        if let Some(joint) = q.iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFiniteJoint { joint: joint as u8 });
        }
    }
    let obstacles: [Solid; N] = core::array::from_fn(|i| {
        scene.guide_obstacles().get(i).map_or(
            Solid::cuboid(&crate::robot::kinematics::Pose::identity(), &Vector3::zeros()),
            Solid::obstacle,
        )
    });
    let obstacles = obstacles.get(..scene.guide_obstacles().len()).unwrap_or(&[]);
    let mut reach = [0.0f32; N];
    for (r, o) in reach.iter_mut().zip(obstacles) {
        *r = o.bounding_radius() + clearance;
    }
    let mut radius = [0.0f32; MAX_BODIES];
    for (r, body) in radius.iter_mut().zip(robot.bodies.iter()) {
        *r = crate::float::sqrt(body.half_extents.norm_squared());
    }

    let mut gradient = gradient;
    if let Some(g) = gradient.as_deref_mut() {
        g.fill([0.0; J]);
    }
    let mut total = 0.0f32;
    // Waypoint w − 1 and w in flight, each with the cotangent its segments gather.
    let mut before: Option<(Kinematics<f32, J>, Cotangent<f32>, bool)> = None;
    let hand = robot.hand_frame.min(MAX_FRAMES - 1);
    for (w, q) in trajectory.iter().enumerate() {
        let k = forward_with(robot, q, robot.finger_opening(scene.gripper()))?;
        let mut current = (k, Cotangent::new(), false);
        if let Some((kb, cot_b, touched_b)) = before.as_mut() {
            let (kc, cot_c, touched_c) = (&current.0, &mut current.1, &mut current.2);
            let mut segment = |ends: [&dyn Convex; 2],
                               boxes: Option<[&dyn Convex; 2]>,
                               frame: usize,
                               centers: [&Vector3<f32>; 2],
                               radius: f32| {
                let mid = (centers[0] + centers[1]) * 0.5;
                let radius = radius + 0.5 * crate::float::sqrt((centers[1] - centers[0]).norm_squared());
                let swept = Union(ends);
                for (o, &reach) in obstacles.iter().zip(&reach) {
                    let limit = radius + reach;
                    if (mid - o.center).norm_squared() > limit * limit {
                        continue;
                    }
                    // The bodies' boxes hold their hulls: boxes proven `clearance` apart are
                    // enough, and a box's support is three signs, not a scan of the hull.
                    let mut towards = mid - o.center;
                    if let Some(boxes) = boxes {
                        match closest(&Union(boxes), o, &towards) {
                            Some(v) if apart_by(&Union(boxes), o, &v, clearance) => continue,
                            Some(v) => towards = v,
                            None => {}
                        }
                    }
                    let (gap, n) = signed_gap(&swept, o, &towards);
                    if gap >= clearance {
                        continue;
                    }
                    let depth = clearance - gap;
                    total += depth * depth;
                    let (side, point) = swept.support_side(&-n);
                    let pull = n * (-2.0 * depth);
                    if side == 0 {
                        cot_b.add_point(frame, &point, &pull);
                        *touched_b = true;
                    } else {
                        cot_c.add_point(frame, &point, &pull);
                        *touched_c = true;
                    }
                }
            };
            for b in (0..robot.bodies.len().min(MAX_BODIES)).filter(|&b| moves(robot, b)) {
                let Some(body) = robot.bodies.get(b) else { continue };
                let frame = body.frame.min(MAX_FRAMES - 1);
                let (hb, hc) = (
                    Hull::of_body(robot, b, &kb.frames[frame]),
                    Hull::of_body(robot, b, &kc.frames[frame]),
                );
                let half = &body.half_extents;
                let (Some(box_b), Some(box_c), Some(&r)) = (kb.boxes.get(b), kc.boxes.get(b), radius.get(b)) else {
                    continue;
                };
                let (bb, bc) = (Solid::cuboid(box_b, half), Solid::cuboid(box_c, half));
                segment(
                    [&hb, &hc],
                    Some([&bb, &bc]),
                    frame,
                    [&box_b.translation, &box_c.translation],
                    r,
                );
            }
            if let Some(h) = scene.held() {
                let (pb, pc) = (
                    Solid::attached(h, &kb.frames[hand]),
                    Solid::attached(h, &kc.frames[hand]),
                );
                segment([&pb, &pc], None, hand, [&pb.center, &pc.center], pb.bounding_radius());
            }
        }
        if let Some((kb, cot_b, touched_b)) = before.take() {
            write_gradient(gradient.as_deref_mut(), w - 1, &kb, &cot_b, touched_b)?;
        }
        before = Some(current);
    }
    if let Some((kb, cot_b, touched_b)) = before {
        write_gradient(gradient, H - 1, &kb, &cot_b, touched_b)?;
    }
    if total.is_finite() {
        Ok(total)
    } else {
        Err(Error::Overflow)
    }
}

/// Waypoint `w`'s joint gradient from its cotangent, zero at the ends and where nothing pulled.
fn write_gradient<const H: usize, const J: usize>(
    gradient: Option<&mut [Joints<f32, J>; H]>,
    w: usize,
    k: &Kinematics<f32, J>,
    cot: &Cotangent<f32>,
    touched: bool,
) -> Result<(), Error> {
    if w == 0 || w + 1 >= H || !touched {
        return Ok(());
    }
    if let Some(slot) = gradient.and_then(|g| g.get_mut(w)) {
        *slot = k.joint_gradient(cot).map_err(|e| match e {
            Error::NonFiniteGradient => Error::Overflow,
            other => other,
        })?;
    }
    Ok(())
}

/// Whether `a` is proven more than `clearance` from `b` along GJK's vector `v` (from `b` to `a`).
fn apart_by<A: Convex>(a: &A, b: &Solid, v: &Vector3<f32>, clearance: f32) -> bool {
    let len = crate::float::sqrt(v.norm_squared());
    len > 0.0 && len.is_finite() && gap_along(a, b, &(v / len)) >= clearance
}

/// The convex hull of two placements of a body (a segment's ends).
struct Union<'a>([&'a dyn Convex; 2]);

impl Union<'_> {
    /// Which placement (0 or 1) holds the support point along `d`, and the point.
    fn support_side(&self, d: &Vector3<f32>) -> (usize, Vector3<f32>) {
        let [a, b] = self.0;
        let (pa, pb) = (a.support(d), b.support(d));
        if pb.dot(d) > pa.dot(d) { (1, pb) } else { (0, pa) }
    }
}

impl Convex for Union<'_> {
    fn support(&self, d: &Vector3<f32>) -> Vector3<f32> {
        self.support_side(d).1
    }
}

/// The signed separation of `a` from `b` along a direction `n` (unit, from `b` towards `a`) and
/// that direction: GJK's when they are apart, else the best of `b`'s face normals and the
/// centres' direction `towards` (see the module docs).
fn signed_gap<A: Convex>(a: &A, b: &Solid, towards: &Vector3<f32>) -> (f32, Vector3<f32>) {
    if let Some(v) = closest(a, b, towards) {
        let len = crate::float::sqrt(v.norm_squared());
        if len > 0.0 && len.is_finite() {
            let n = v / len;
            return (gap_along(a, b, &n), n);
        }
    }
    let mut best = (f32::NEG_INFINITY, Vector3::z());
    let mut consider = |n: Vector3<f32>| {
        let gap = gap_along(a, b, &n);
        if gap > best.0 {
            best = (gap, n);
        }
    };
    let len = crate::float::sqrt(towards.norm_squared());
    if len > 0.0 && len.is_finite() {
        consider(towards / len);
    }
    if let Some(normals) = b.face_normals() {
        for n in normals.column_iter() {
            consider(n.into_owned());
            consider(-n);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{BODIES, JOINTS, PANDA};
    use crate::scene::Obstacle;

    const H: usize = 6;

    /// A wall in front of the robot, its face at x = 0.45.
    fn wall() -> Scene<'static, 4> {
        let mut s = Scene::new();
        let o = Obstacle::cuboid([0.6, 0.0, 0.5], [0.3, 1.0, 1.0], [1.0, 0.0, 0.0, 0.0]);
        s.push(o.unwrap()).unwrap();
        s
    }

    fn reach(s: f32) -> [Joints<f32>; H] {
        core::array::from_fn(|w| {
            let a = s * w as f32 / (H - 1) as f32;
            [0.1 * a, 0.2 + a, 0.05, -2.0 + 1.2 * a, 0.1, 1.8, 0.7]
        })
    }

    #[test]
    fn far_from_everything_the_cost_and_gradient_are_zero() {
        let mut g = [[1.0; JOINTS]; H];
        let c = trajectory_cost(&PANDA, &Scene::<4>::new(), &reach(1.0), 0.05, Some(&mut g)).unwrap();
        assert_eq!(c, 0.0);
        assert!(g.iter().flatten().all(|&x| x == 0.0));
    }

    #[test]
    fn the_gradient_matches_finite_differences_and_descends() {
        let scene = wall();
        let x = reach(0.55);
        let clearance = 0.05;
        let mut g = [[0.0; JOINTS]; H];
        let c = trajectory_cost(&PANDA, &scene, &x, clearance, Some(&mut g)).unwrap();
        assert!(c > 0.0, "the arm comes within the clearance of the wall");
        assert_eq!(g[0], [0.0; JOINTS]);
        assert_eq!(g[H - 1], [0.0; JOINTS]);
        let mut checked = 0;
        for w in 1..H - 1 {
            for j in 0..JOINTS {
                let h = 1e-3;
                let (mut up, mut down) = (x, x);
                up[w][j] += h;
                down[w][j] -= h;
                let fd = (trajectory_cost(&PANDA, &scene, &up, clearance, None).unwrap()
                    - trajectory_cost(&PANDA, &scene, &down, clearance, None).unwrap())
                    / (2.0 * h);
                let scale = fd.abs().max(g[w][j].abs()).max(1e-3);
                assert!(
                    (fd - g[w][j]).abs() <= 0.05 * scale,
                    "w {w} j {j}: fd {fd} vs {}",
                    g[w][j]
                );
                checked += usize::from(fd.abs() > 1e-3);
            }
        }
        assert!(checked >= 4, "some joints move the arm towards the wall");
        // A small step down the gradient lowers the cost.
        let norm = crate::float::sqrt(g.iter().flatten().map(|v| v * v).sum::<f32>());
        let mut next = x;
        for (q, gq) in next.iter_mut().zip(&g) {
            for (v, gv) in q.iter_mut().zip(gq) {
                *v -= 0.01 * gv / norm;
            }
        }
        assert!(trajectory_cost(&PANDA, &scene, &next, clearance, None).unwrap() < c);
    }

    /// Many arms near many obstacles (a fixed stream of random cases): wherever the cost pulls,
    /// a small step down its gradient lowers it. Where the closest features are faces the
    /// moment is a vertex's, so this is the property the refinement relies on, not equality
    /// with finite differences; a handful of cases at support switches may not descend.
    #[test]
    fn the_gradient_descends_on_random_cases() {
        let mut rng = crate::rng::Rng::new(7);
        let mut u = |lo: f32, hi: f32| rng.uniform_f32(lo, hi);
        let (mut pulled, mut descended) = (0, 0);
        for _ in 0..200 {
            let a: Joints<f32> = core::array::from_fn(|j| u(PANDA.soft_lower[j], PANDA.soft_upper[j]));
            let b: Joints<f32> =
                core::array::from_fn(|j| (a[j] + u(-0.4, 0.4)).clamp(PANDA.soft_lower[j], PANDA.soft_upper[j]));
            let x: [Joints<f32>; H] = core::array::from_fn(|w| {
                let t = w as f32 / (H - 1) as f32;
                core::array::from_fn(|j| a[j] + t * (b[j] - a[j]))
            });
            let k = forward_with(&crate::robot::PANDA, &x[H / 2], 0.025).unwrap();
            let near = k.boxes[(u(1.0, BODIES as f32) as usize).min(BODIES - 1)].translation;
            let mut scene = Scene::<4>::new();
            let center = [near.x + u(-0.1, 0.1), near.y + u(-0.1, 0.1), near.z + u(-0.1, 0.1)];
            let o = match u(0.0, 3.0) as u32 {
                0 => Obstacle::cuboid(center, [u(0.02, 0.3), u(0.02, 0.3), u(0.02, 0.3)], [1.0, 0.0, 0.0, 0.0]),
                1 => Obstacle::cylinder(center, u(0.02, 0.1), u(0.05, 0.4), [0.9, 0.1, 0.3, 0.3]),
                _ => Obstacle::sphere(center, u(0.02, 0.12)),
            };
            scene.push(o.unwrap()).unwrap();
            let mut g = [[0.0; JOINTS]; H];
            let c = trajectory_cost(&PANDA, &scene, &x, 0.03, Some(&mut g)).unwrap();
            assert!(c.is_finite() && c >= 0.0);
            let norm = crate::float::sqrt(g.iter().flatten().map(|v| v * v).sum::<f32>());
            if norm == 0.0 {
                continue;
            }
            pulled += 1;
            let mut next = x;
            for (q, gq) in next.iter_mut().zip(&g) {
                for (v, gv) in q.iter_mut().zip(gq) {
                    *v -= 1e-3 * gv / norm;
                }
            }
            descended += usize::from(trajectory_cost(&PANDA, &scene, &next, 0.03, None).unwrap() < c);
        }
        assert!(pulled >= 50, "{pulled} cases pull");
        assert!(descended * 100 >= pulled * 95, "{descended} of {pulled} descend");
    }

    #[test]
    fn a_segment_through_a_thin_board_costs_though_both_its_ends_are_clear() {
        let mut scene = Scene::<4>::new();
        let board = Obstacle::cuboid([0.55, 0.0, 0.4], [0.3, 0.01, 0.8], [1.0, 0.0, 0.0, 0.0]);
        scene.push(board.unwrap()).unwrap();
        let (a, b) = (
            [-0.7, 0.3, 0.0, -2.0, 0.0, 2.2, 0.7],
            [0.7, 0.3, 0.0, -2.0, 0.0, 2.2, 0.7],
        );
        let cost = |x: &[Joints<f32>; 3]| trajectory_cost(&PANDA, &scene, x, 0.01, None).unwrap();
        assert_eq!(cost(&[a; 3]), 0.0);
        assert_eq!(cost(&[b; 3]), 0.0);
        let mut g = [[0.0; JOINTS]; 3];
        assert!(trajectory_cost(&PANDA, &scene, &[a, a, b], 0.01, Some(&mut g)).unwrap() > 0.0);
        assert!(
            g[1].iter().any(|&v| v != 0.0),
            "the interior waypoint is pulled back from the board"
        );
    }

    #[test]
    fn inside_an_obstacle_the_gap_is_negative_and_points_out() {
        let b = Solid::obstacle(&Obstacle::cuboid([0.0; 3], [1.0, 1.0, 0.2], [1.0, 0.0, 0.0, 0.0]).unwrap());
        let a = Solid::obstacle(&Obstacle::sphere([0.0, 0.3, 0.05], 0.1).unwrap());
        let (gap, n) = signed_gap(&a, &b, &Vector3::new(0.0, 0.3, 0.05));
        assert!((gap - (-0.15)).abs() < 1e-5, "{gap}");
        assert!((n - Vector3::z()).norm() < 1e-6, "{n}");
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let mut x = reach(0.5);
        assert_eq!(
            trajectory_cost(&PANDA, &wall(), &x, -0.1, None),
            Err(Error::BadParameter)
        );
        assert_eq!(
            trajectory_cost(&PANDA, &wall(), &x, f32::NAN, None),
            Err(Error::BadParameter)
        );
        x[2][3] = f32::INFINITY;
        assert_eq!(
            trajectory_cost(&PANDA, &wall(), &x, 0.05, None),
            Err(Error::NonFiniteJoint { joint: 3 })
        );
    }
}
