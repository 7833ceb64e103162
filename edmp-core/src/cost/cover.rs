//! Boxes around a surface for the guides. EDMP's costs are intersection and swept volumes of
//! the arm's link boxes with obstacle boxes; a cloud or a mesh joins them as a few boxes, each
//! around one subtree of the hierarchy, turned about z to fit its pieces (the walls of a
//! shelf stand at any yaw). The guides only steer: the checker still judges the exact pieces.

use crate::scene::Obstacle;
use crate::surface::Surface;
use crate::surface::bvh::{MAX_DEPTH, Node};
use nalgebra::Vector3;

/// The most boxes one surface gets.
pub const MAX_COVERS: usize = 64;

/// Thinnest box side (metres): a flat wall's box keeps a thickness the costs can measure.
pub const MIN_SIDE: f32 = 0.005;

/// Up to `out.len()` (at most [`MAX_COVERS`]) boxes that together hold every piece of
/// `surface`; returns how many were written. The subtree with the largest box is split until
/// the boxes are used up or only leaves are left. Deterministic.
pub fn covers(surface: &Surface<'_>, out: &mut [Obstacle]) -> usize {
    let nodes = surface.nodes();
    let limit = out.len().min(MAX_COVERS);
    if surface.is_empty() || nodes.is_empty() || limit == 0 {
        return 0;
    }
    let mut frontier: heapless::Vec<u32, MAX_COVERS> = heapless::Vec::new();
    let _ = frontier.push(0);
    while frontier.len() < limit {
        // The splittable node with the largest box (the first such, on ties).
        let mut pick: Option<(usize, f32)> = None;
        for (k, &i) in frontier.iter().enumerate() {
            if let Some(n) = nodes.get(i as usize)
                && n.left != 0
            {
                let v = n.bounds().volume();
                if pick.is_none_or(|(_, best)| v > best) {
                    pick = Some((k, v));
                }
            }
        }
        let Some((k, _)) = pick else { break };
        let Some(left) = frontier.get(k).and_then(|&i| nodes.get(i as usize)).map(|n| n.left) else {
            break;
        };
        if let Some(slot) = frontier.get_mut(k) {
            *slot = left;
        }
        if frontier.push(left + 1).is_err() {
            break;
        }
    }
    let mut written = 0;
    for (slot, &i) in out.iter_mut().zip(frontier.iter()) {
        if let Some(b) = nodes.get(i as usize).and_then(|n| fitted(surface, n)) {
            *slot = b;
            written += 1;
        }
    }
    // Boxes that could not be fitted (none in practice) leave no gap in `out`.
    written
}

/// The box around one node's pieces, turned about z by the principal axis of their centroids.
fn fitted(surface: &Surface<'_>, node: &Node) -> Option<Obstacle> {
    let end = node.first as usize + node.count as usize;
    let pieces = surface.pieces().get(node.first as usize..end)?;
    let n = pieces.len() as f32;
    if pieces.is_empty() {
        return None;
    }
    let mean = pieces.iter().fold(Vector3::zeros(), |m, e| m + e.centroid()) / n;
    let (mut xx, mut xy, mut yy) = (0.0f32, 0.0f32, 0.0f32);
    for e in pieces {
        let d = e.centroid() - mean;
        xx += d.x * d.x;
        xy += d.x * d.y;
        yy += d.y * d.y;
    }
    let angle = 0.5 * libm::atan2f(2.0 * xy, xx - yy);
    let (s, c) = (libm::sinf(angle), libm::cosf(angle));
    let axes = [Vector3::new(c, s, 0.0), Vector3::new(-s, c, 0.0), Vector3::z()];
    // `e.support(-a).dot(a)` is exactly `-(e.support(-a).dot(-a))`: the lower side is the
    // reach along `-a`, negated.
    let hi = axes.map(|a| reach(surface, node, &a));
    let lo = axes.map(|a| -reach(surface, node, &-a));
    let mid: [f32; 3] = core::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let center = axes[0] * mid[0] + axes[1] * mid[1] + axes[2] * mid[2];
    let dims: [f32; 3] = core::array::from_fn(|k| (hi[k] - lo[k]).max(MIN_SIDE));
    let half = 0.5 * angle;
    let quaternion = [libm::cosf(half), 0.0, 0.0, libm::sinf(half)];
    Obstacle::cuboid(center.into(), dims, quaternion).ok()
}

/// How far the pieces under `node` reach along `a`: the largest `e.support(a).dot(a)`, the
/// same value a pass over every piece finds (a maximum does not depend on the order), found by
/// visiting only the subtrees whose box could reach beyond the best so far. On a cloud of
/// 200,000 balls this visits a few leaves instead of every ball.
fn reach(surface: &Surface<'_>, node: &Node, a: &Vector3<f32>) -> f32 {
    let (nodes, pieces) = (surface.nodes(), surface.pieces());
    let mut best = f32::NEG_INFINITY;
    // `|a|` found once, not once a ball: a wall along `a` ties at every leaf, so every one of
    // its balls is read.
    let norm = crate::float::sqrt(a.norm_squared());
    let over = |run: &Node, best: f32| {
        let end = run.first as usize + run.count as usize;
        let run = pieces.get(run.first as usize..end).unwrap_or(&[]);
        run.iter().fold(best, |best, e| {
            let v = e.support_with_norm(a, norm).dot(a);
            if v > best { v } else { best }
        })
    };
    // Depth-first, the child that reaches further first; a pop pushes at most two, so a
    // stack one deeper than the tree suffices, and a node that finds it full is read whole
    // (its run holds its subtree's pieces).
    let mut stack = [*node; MAX_DEPTH + 2];
    let mut len: usize = 1;
    while let Some(top) = len.checked_sub(1) {
        len = top;
        let Some(&n) = stack.get(top) else { break };
        let bound = box_reach(&n, a);
        // The box holds every support point; the slack absorbs the rounding of both sides.
        if bound + 1e-5 * (1.0 + bound.abs()) < best {
            continue;
        }
        let children = (nodes.get(n.left as usize), nodes.get(n.left as usize + 1));
        match children {
            (Some(&l), Some(&r)) if n.left != 0 && len + 2 <= stack.len() => {
                let (near, far) = if box_reach(&l, a) > box_reach(&r, a) {
                    (r, l)
                } else {
                    (l, r)
                };
                if let Some(slot) = stack.get_mut(len) {
                    *slot = near;
                }
                if let Some(slot) = stack.get_mut(len + 1) {
                    *slot = far;
                }
                len += 2;
            }
            _ => best = over(&n, best),
        }
    }
    best
}

/// The largest `p.dot(a)` over the points `p` of a node's box.
fn box_reach(n: &Node, a: &Vector3<f32>) -> f32 {
    (0..3).fold(0.0, |sum, k| sum + (n.lo[k] * a[k]).max(n.hi[k] * a[k]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::convex::{Convex, Solid};
    use crate::surface::bvh::{Key, build, nodes_for};
    use crate::surface::element::Element;
    use std::vec::Vec;

    #[test]
    fn a_turned_wall_gets_a_turned_box_that_holds_every_ball() {
        // A 1 m × 0.5 m wall of points turned 30° about z.
        let (s, c) = (0.5f32, 0.866_025_4f32);
        let mut pieces: Vec<Element> = (0..5000)
            .map(|i| {
                let (u, z) = ((i % 100) as f32 * 0.01 - 0.5, (i / 100) as f32 * 0.01);
                Element::ball([0.6 + u * c, u * s, z], 0.0075, 0).unwrap()
            })
            .collect();
        let mut nodes = std::vec![Node::EMPTY; nodes_for(5000)];
        let mut keys = std::vec![Key::EMPTY; 5000];
        let used = build(&pieces.clone(), &mut pieces, &mut nodes, &mut keys).unwrap();
        let surface = Surface::new(&pieces, &nodes[..used]).unwrap();
        let mut out = [Obstacle::sphere([0.0; 3], 1.0).unwrap(); 1];
        assert_eq!(covers(&surface, &mut out), 1);
        let Solid {
            shape,
            rotation,
            center,
        } = Solid::obstacle(&out[0]);
        let crate::scene::Shape::Cuboid { dims } = shape else {
            panic!()
        };
        // Thin across the wall (the balls' diameter), not the 0.5 m an axis-aligned box needs.
        assert!(dims.y < 0.02 && dims.x > 1.0, "{dims:?}");
        for e in &pieces {
            let local = rotation.tr_mul(&(e.centroid() - center));
            assert!((0..3).all(|k| local[k].abs() <= 0.5 * dims[k] + 1e-4));
        }
        let mut many = [out[0]; 8];
        assert_eq!(covers(&surface, &mut many), 8);
    }

    #[test]
    fn reach_is_the_largest_support_a_pass_over_every_piece_finds() {
        // Walls along the axes (every leaf ties along their normal), balls of two radii, a few
        // triangles, and directions of any length (zero included).
        let mut rng = crate::rng::Rng::new(11);
        let mut pieces: Vec<Element> = (0..3000)
            .map(|i| {
                let (u, v) = ((i % 50) as f32 * 0.01, ((i / 50) % 60) as f32 * 0.01);
                let c = match i % 3 {
                    0 => [0.5, u, v],
                    1 => [u, -0.2, v],
                    _ => [u, v, 0.1],
                };
                Element::ball(c, if i % 7 == 0 { 0.01 } else { 0.0075 }, 0).unwrap()
            })
            .collect();
        for _ in 0..40 {
            let corner = |rng: &mut crate::rng::Rng| [0; 3].map(|_| rng.uniform_f32(-0.3, 0.8));
            let t = [corner(&mut rng), corner(&mut rng), corner(&mut rng)];
            if let Ok(Some(e)) = Element::triangle(t, 1) {
                pieces.push(e);
            }
        }
        let n = pieces.len();
        let mut nodes = std::vec![Node::EMPTY; nodes_for(n)];
        let mut keys = std::vec![Key::EMPTY; n];
        let used = build(&pieces.clone(), &mut pieces, &mut nodes, &mut keys).unwrap();
        let surface = Surface::new(&pieces, &nodes[..used]).unwrap();
        let mut directions: Vec<Vector3<f32>> = (0..200)
            .map(|_| Vector3::from([0; 3].map(|_| rng.uniform_f32(-2.0, 2.0))))
            .collect();
        directions.extend([Vector3::x(), -Vector3::y(), Vector3::z() * 3.0, Vector3::zeros()]);
        for a in &directions {
            let every = pieces.iter().fold(f32::NEG_INFINITY, |best, e| {
                let v = e.support(a).dot(a);
                if v > best { v } else { best }
            });
            for node in &nodes[..used] {
                let end = (node.first + node.count) as usize;
                let under = pieces[node.first as usize..end]
                    .iter()
                    .fold(f32::NEG_INFINITY, |best, e| {
                        let v = e.support(a).dot(a);
                        if v > best { v } else { best }
                    });
                assert_eq!(reach(&surface, node, a).to_bits(), under.to_bits(), "{a:?}");
            }
            assert_eq!(reach(&surface, &nodes[0], a).to_bits(), every.to_bits(), "{a:?}");
        }
    }
}
