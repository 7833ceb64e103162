//! Clouds and meshes in the exact checker: a ball or a triangle placed at a known distance
//! from a robot body's hull (along a support direction, where the distance is exact) is
//! refused when it is nearer than the ends' margin and accepted when it is farther: valid ends
//! near clouds and meshes are never refused, and contact is never missed.

use edmp_core::collision::checker::{CheckConfig, Contact, END_MARGIN, check_end};
use edmp_core::collision::convex::{Convex, Hull};
use edmp_core::collision::gjk::distance_lower_bound;
use edmp_core::robot::kinematics::forward_with;
use edmp_core::robot::{BODIES, FRAMES, PANDA};
use edmp_core::scene::Scene;
use edmp_core::surface::Surface;
use edmp_core::surface::bvh::{Key, Node, build, nodes_for};
use edmp_core::surface::element::Element;
use nalgebra::Vector3;
use proptest::prelude::*;

const RADIUS: f32 = 0.0075;

/// A configuration inside the limits, free of self-contact at the ends' margin.
fn configuration() -> impl Strategy<Value = [f32; 7]> {
    let ranges: [core::ops::RangeInclusive<f32>; 7] =
        core::array::from_fn(|j| PANDA.soft_lower[j] + 0.05..=PANDA.soft_upper[j] - 0.05);
    ranges.prop_filter("free of self-contact", |q| {
        check_end(&edmp_core::robot::PANDA, &Scene::<1>::new(), q, &CheckConfig::default()) == Ok(None)
    })
}

/// Body `b`'s hull and the point `gap` beyond it along `d` (unit), with the exact distance
/// from that point to the hull (`gap`) and the foot on the hull.
fn beyond(q: &[f32; 7], b: usize, d: Vector3<f32>, gap: f32) -> (Vector3<f32>, Vector3<f32>) {
    let k = forward_with(&edmp_core::robot::PANDA, q, 0.025).unwrap();
    let hull = Hull::of_body(&PANDA, b, &k.frames[PANDA.bodies[b].frame.min(FRAMES - 1)]);
    let foot = hull.support(&d);
    (foot, foot + d * gap)
}

/// The distance from `p` to the nearest moving body other than `b` (GJK's lower bound).
fn nearest_other(q: &[f32; 7], b: usize, p: &Element) -> f32 {
    let k = forward_with(&edmp_core::robot::PANDA, q, 0.025).unwrap();
    (0..BODIES)
        .filter(|&o| o != b && PANDA.bodies[o].frame != 0)
        .map(|o| {
            let hull = Hull::of_body(&PANDA, o, &k.frames[PANDA.bodies[o].frame.min(FRAMES - 1)]);
            distance_lower_bound(&hull, p)
        })
        .fold(f32::INFINITY, f32::min)
}

fn checked(pieces: &mut [Element], q: &[f32; 7]) -> Option<Contact> {
    let mut nodes = vec![Node::EMPTY; nodes_for(pieces.len())];
    let mut keys = vec![Key::EMPTY; pieces.len()];
    let input = pieces.to_vec();
    let used = build(&input, pieces, &mut nodes, &mut keys).unwrap();
    let surface = Surface::new(pieces, &nodes[..used]).unwrap();
    let scene = Scene::<4>::new().with_surface(surface, &[]);
    check_end(&edmp_core::robot::PANDA, &scene, q, &CheckConfig::default()).unwrap()
}

fn direction(theta: f32, phi: f32) -> Vector3<f32> {
    Vector3::new(phi.cos() * theta.cos(), phi.cos() * theta.sin(), phi.sin())
}

/// A few far-away balls, so the hierarchy has more than one leaf.
fn far_balls() -> Vec<Element> {
    (0..40)
        .map(|i| Element::ball([3.0 + i as f32 * 0.1, 3.0, 0.0], RADIUS, 9).unwrap())
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn a_ball_beyond_the_margin_is_accepted_and_one_within_it_refused(
        q in configuration(),
        b in 1usize..BODIES,
        theta in -3.1f32..3.1,
        phi in -1.5f32..1.5,
    ) {
        prop_assume!(PANDA.bodies[b].frame != 0);
        let d = direction(theta, phi);
        // Clear: the ball's surface 1.5 mm from the hull (the ends keep ~1 mm).
        let (_, p) = beyond(&q, b, d, RADIUS + 0.0015);
        let ball = Element::ball(p.into(), RADIUS, 3).unwrap();
        prop_assume!(nearest_other(&q, b, &ball) > END_MARGIN + 1e-4);
        let mut clear = far_balls();
        clear.push(ball);
        prop_assert_eq!(checked(&mut clear, &q), None);
        // Touching: the ball reaches 0.5 mm into the hull's surroundings, inside its margin.
        let (_, p) = beyond(&q, b, d, RADIUS + 0.0005);
        let mut near = far_balls();
        near.push(Element::ball(p.into(), RADIUS, 3).unwrap());
        let contact = checked(&mut near, &q);
        prop_assert!(matches!(contact, Some(Contact::Surface { obstacle: 3, .. })), "{:?}", contact);
    }

    #[test]
    fn a_triangle_beyond_the_margin_is_accepted_and_one_within_it_refused(
        q in configuration(),
        b in 1usize..BODIES,
        theta in -3.1f32..3.1,
        phi in -1.5f32..1.5,
    ) {
        prop_assume!(PANDA.bodies[b].frame != 0);
        let d = direction(theta, phi);
        // A small triangle in the plane normal to `d`, around the foot point moved out by `gap`.
        let triangle = |gap: f32| {
            let (_, c) = beyond(&q, b, d, gap);
            let u = d.cross(&Vector3::new(0.3, 0.5, 0.8)).normalize() * 0.01;
            let v = d.cross(&u);
            Element::triangle([(c + u).into(), (c - u + v).into(), (c - u - v).into()], 4).unwrap().unwrap()
        };
        let t = triangle(0.0015);
        prop_assume!(nearest_other(&q, b, &t) > END_MARGIN + 1e-4);
        let mut clear = far_balls();
        clear.push(t);
        prop_assert_eq!(checked(&mut clear, &q), None);
        let mut near = far_balls();
        near.push(triangle(0.0005));
        let contact = checked(&mut near, &q);
        prop_assert!(matches!(contact, Some(Contact::Surface { obstacle: 4, .. })), "{:?}", contact);
    }
}
