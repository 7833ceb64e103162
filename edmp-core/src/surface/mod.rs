//! Obstacles as a real cell gives them: the balls around a depth camera's points and the
//! triangles of a CAD mesh, held exactly (never boxed) so that the checker's "free" is free of
//! the input, in buffers the caller owns.
//!
//! - [`element`]: a piece (a ball or a triangle) and the obstacle it came from.
//! - [`bvh`]: the static hierarchy the checker walks to find the pieces near a body.
//! - [`points`]: a cloud reduced to a capacity, conservatively.
//!
//! Above the scene, `collision::filter` drops the robot's own points from a cloud and
//! `cost::cover` fits the few boxes the guides see around the pieces (EDMP's costs are box
//! volumes).
//!
//! A [`Surface`] is a borrowed view of built buffers: the host builds it from files, firmware
//! receives it built (the tree is part of the wire).

pub mod bvh;
pub mod element;
pub mod points;

use crate::float::sqrt_below;
use bvh::{MAX_DEPTH, Node};
use element::{Aabb, Element, Piece, SurfaceError};

/// Subtrees of at most this many pieces are offered to a proof as one box first.
pub const BOX_PROOF: usize = 32;

/// What [`Surface::gap`] asks its caller to prove clear.
#[derive(Clone, Copy, Debug)]
pub enum Probe<'p> {
    /// One piece.
    Piece(&'p Element),
    /// The box holding a subtree's pieces: clear of it means clear of them all.
    Box(&'p Aabb),
}

/// The pieces of every cloud and mesh of a scene, and the tree over them.
#[derive(Clone, Copy, Debug)]
pub struct Surface<'a> {
    pieces: &'a [Element],
    nodes: &'a [Node],
}

impl Default for Surface<'_> {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl<'a> Surface<'a> {
    /// No pieces.
    pub const EMPTY: Surface<'static> = Surface {
        pieces: &[],
        nodes: &[],
    };

    /// A view of pieces and the tree [`bvh::build`] made over them, checked to be a tree over
    /// exactly these pieces (so a tree from the wire cannot send the walk astray).
    pub fn new(pieces: &'a [Element], nodes: &'a [Node]) -> Result<Self, SurfaceError> {
        if pieces.is_empty() {
            return Ok(Surface { pieces, nodes: &[] });
        }
        let root = nodes.first().ok_or(SurfaceError::TooFewNodes)?;
        if root.first != 0 || root.count as usize != pieces.len() {
            return Err(SurfaceError::TooFewNodes);
        }
        for (i, n) in nodes.iter().enumerate() {
            let end = n.first as usize + n.count as usize;
            if end > pieces.len() || n.lo.iter().chain(&n.hi).any(|x| x.is_nan()) {
                return Err(SurfaceError::TooFewNodes);
            }
            if n.left != 0 {
                // Children after their parent, side by side, splitting its run: the walk ends.
                let l = n.left as usize;
                let (Some(a), Some(b)) = (nodes.get(l), nodes.get(l + 1)) else {
                    return Err(SurfaceError::TooFewNodes);
                };
                let inside = |c: &Node| (0..3).all(|k| c.lo[k] >= n.lo[k] && c.hi[k] <= n.hi[k]);
                if l <= i
                    || a.first != n.first
                    || b.first != a.first + a.count
                    || a.count + b.count != n.count
                    || !inside(a)
                    || !inside(b)
                {
                    return Err(SurfaceError::TooFewNodes);
                }
            } else {
                for e in pieces.get(n.first as usize..end).unwrap_or(&[]) {
                    let eb = e.bounds();
                    if (0..3).any(|k| eb.lo[k] < n.lo[k] || eb.hi[k] > n.hi[k]) {
                        return Err(SurfaceError::TooFewNodes);
                    }
                }
            }
        }
        Ok(Self { pieces, nodes })
    }

    /// A view of buffers [`bvh::build`] has just filled, without [`Surface::new`]'s walk over
    /// every piece (a host that keeps the buffers private to itself calls this on every plan).
    /// A tree not made by `build` over these pieces gives wrong verdicts, never a panic.
    pub fn from_built(pieces: &'a [Element], nodes: &'a [Node]) -> Self {
        Self { pieces, nodes }
    }

    /// The pieces, in the tree's order.
    pub fn pieces(&self) -> &'a [Element] {
        self.pieces
    }

    /// The tree's nodes (node 0 is the root).
    pub fn nodes(&self) -> &'a [Node] {
        self.nodes
    }

    /// No pieces at all.
    pub fn is_empty(&self) -> bool {
        self.pieces.is_empty()
    }

    /// A certified lower bound on the distance from a convex shape to every piece, capped at
    /// `horizon`; `Err(obstacle)` names a piece's obstacle that is not proven clear.
    ///
    /// The shape lies in the axis-aligned box `shape`. A subtree or a piece whose box that
    /// box's distance alone proves more than `near` away counts with that bound (and a subtree
    /// is not opened); only the pieces nearer go to `prove`, which returns the certified gap
    /// (above the caller's margin) or `None`. A small subtree near the shape is first offered
    /// whole, as its box ([`Probe::Box`]): one proof for up to [`BOX_PROOF`] pieces.
    pub fn gap<F>(&self, shape: &Aabb, near: f32, horizon: f32, mut prove: F) -> Result<f32, u16>
    where
        F: FnMut(Probe<'_>) -> Option<f32>,
    {
        let mut best = horizon;
        let Some(root) = self.nodes.first() else {
            return Ok(best);
        };
        let bound = |b: &Aabb| sqrt_below(b.distance_squared_to(shape));
        let mut todo = [0u32; MAX_DEPTH + 2];
        let mut depth = 0usize;
        let mut node = *root;
        loop {
            let lb = bound(&node.bounds());
            if lb < best && lb > near {
                // The box alone proves the whole subtree clear: its bound stands for it.
                best = lb;
            } else if lb < best {
                let boxed = if node.count as usize <= BOX_PROOF && node.count > 1 {
                    prove(Probe::Box(&node.bounds()))
                } else {
                    None
                };
                if let Some(gap) = boxed {
                    best = best.min(gap);
                } else if node.left == 0 {
                    let end = node.first as usize + node.count as usize;
                    for e in self.pieces.get(node.first as usize..end).unwrap_or(&[]) {
                        let lb = match e.piece {
                            Piece::Ball { center: c, radius: r } => sqrt_below(shape.distance_squared(&c)) - r,
                            Piece::Triangle { .. } => bound(&e.bounds()),
                        };
                        if lb >= best {
                            continue;
                        }
                        best = if lb > near {
                            lb
                        } else {
                            prove(Probe::Piece(e)).ok_or(e.obstacle)?.min(best)
                        };
                    }
                } else if let (Some(a), Some(b)) = (todo.get_mut(depth), self.nodes.get(node.left as usize)) {
                    *a = node.left + 1;
                    depth += 1;
                    node = *b;
                    continue;
                } else {
                    // Deeper than any tree `bvh::build` makes: refuse to call it clear.
                    return Err(node_obstacle(self.pieces, &node));
                }
            }
            if depth == 0 {
                return Ok(best);
            }
            depth -= 1;
            match todo.get(depth).and_then(|&i| self.nodes.get(i as usize)) {
                Some(n) => node = *n,
                None => return Ok(best),
            }
        }
    }
}

fn node_obstacle(pieces: &[Element], node: &Node) -> u16 {
    pieces.get(node.first as usize).map_or(0, |e| e.obstacle)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::convex::Solid;
    use crate::collision::gjk::distance_lower_bound;
    use crate::scene::Obstacle;
    use nalgebra::Vector3;
    use std::vec::Vec;

    fn cloud() -> (Vec<Element>, Vec<Node>) {
        // A 1 m × 1 m wall of points at x = 0.5, 1 cm apart.
        let mut pieces: Vec<Element> = (0..10_000)
            .map(|i| Element::ball([0.5, (i % 100) as f32 * 0.01 - 0.5, (i / 100) as f32 * 0.01], 0.0075, 2).unwrap())
            .collect();
        let mut nodes = std::vec![Node::EMPTY; bvh::nodes_for(pieces.len())];
        let mut keys = std::vec![bvh::Key::EMPTY; pieces.len()];
        let used = bvh::build(&pieces.clone(), &mut pieces, &mut nodes, &mut keys).unwrap();
        nodes.truncate(used);
        (pieces, nodes)
    }

    /// The box around a 5 cm ball at `(x, 0, 0.5)`.
    fn around(x: f32) -> Aabb {
        let c = Vector3::new(x, 0.0, 0.5);
        Aabb {
            lo: c.add_scalar(-0.05),
            hi: c.add_scalar(0.05),
        }
    }

    #[test]
    fn the_gap_is_the_distance_to_the_nearest_ball_and_contact_names_the_obstacle() {
        let (pieces, nodes) = cloud();
        let s = Surface::new(&pieces, &nodes).unwrap();
        for (x, expect) in [
            (0.3f32, 0.2f32 - 0.0075 - 0.05),
            (0.44, 0.06 - 0.0075 - 0.05),
            (0.9, 0.4 - 0.0075 - 0.05),
        ] {
            let ball = Solid::obstacle(&Obstacle::sphere([x, 0.0, 0.5], 0.05).unwrap());
            let g = s
                .gap(&around(x), 0.002, 0.1, |p| match p {
                    Probe::Piece(e) => Some(distance_lower_bound(&ball, e)),
                    Probe::Box(_) => None,
                })
                .unwrap();
            // Within the horizon the bound is the true gap, to the lower bounds' rounding.
            let want = expect.min(0.1);
            assert!(g <= want + 1e-6 && g >= want - 1e-3, "x {x}: gap {g}, want {want}");
        }
        let touching = Solid::obstacle(&Obstacle::sphere([0.46, 0.0, 0.5], 0.05).unwrap());
        let r = s.gap(&around(0.46), 0.002, 0.1, |p| match p {
            Probe::Piece(e) => {
                let d = distance_lower_bound(&touching, e);
                (d > 0.002).then_some(d)
            }
            Probe::Box(_) => None,
        });
        assert_eq!(r, Err(2));
    }

    #[test]
    fn malformed_trees_are_refused() {
        let (pieces, nodes) = cloud();
        assert!(Surface::new(&pieces, &nodes).is_ok());
        assert!(Surface::new(&pieces[1..], &nodes).is_err());
        let l = nodes[0].left as usize;
        let mut runs = nodes.clone();
        runs[l].count += 1;
        assert!(Surface::new(&pieces, &runs).is_err());
        // A child's box that the parent's does not hold would let the walk skip its pieces.
        let mut boxes = nodes.clone();
        boxes[l + 1].hi[0] = boxes[0].hi[0] + 1.0;
        assert!(Surface::new(&pieces, &boxes).is_err());
        let mut cycle = nodes.clone();
        cycle[l].left = 0;
        cycle[l + 1].left = l as u32;
        assert!(Surface::new(&pieces, &cycle).is_err());
        assert!(Surface::new(&pieces, &[]).is_err());
    }
}
