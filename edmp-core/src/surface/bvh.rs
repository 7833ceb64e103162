//! A static bounding-volume hierarchy over a surface's pieces, built in the caller's buffers:
//! each node's pieces are one contiguous run of the piece buffer (the build reorders it), and
//! a node's children sit side by side in the node buffer. Median splits along the longest axis
//! of the centroids keep the depth at about log₂ of the piece count.

use crate::surface::element::{Aabb, Element, Piece, SurfaceError};

/// A leaf holds at most this many pieces.
pub const LEAF: usize = 4;

/// The deepest a tree may be: a median split halves the run, so 2⁴⁰ pieces would still fit.
pub const MAX_DEPTH: usize = 40;

/// One node: its box and its run of pieces; `left` is the first of its two children
/// (`left + 1` the second), 0 for a leaf (the root, node 0, is nobody's child).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Node {
    /// Holds every piece of the run.
    pub lo: [f32; 3],
    /// Holds every piece of the run.
    pub hi: [f32; 3],
    /// The run's first piece.
    pub first: u32,
    /// The run's length.
    pub count: u32,
    /// First child, or 0 for a leaf.
    pub left: u32,
}

impl Node {
    /// A node with nothing in it: fills node buffers before [`build`] writes them.
    pub const EMPTY: Self = Self {
        lo: [0.0; 3],
        hi: [0.0; 3],
        first: 0,
        count: 0,
        left: 0,
    };

    /// The node's box.
    pub fn bounds(&self) -> Aabb {
        Aabb {
            lo: self.lo.into(),
            hi: self.hi.into(),
        }
    }
}

/// How many nodes a tree over `pieces` pieces can need: a run is split only above [`LEAF`]
/// pieces, so every leaf holds at least two and there are fewer than `pieces` nodes.
pub const fn nodes_for(pieces: usize) -> usize {
    if pieces == 0 { 1 } else { pieces }
}

/// One pass over a run: the box of its pieces, and the box of their centroids (where it is
/// split). Plain arrays: this loop is most of a build's time.
fn boxes_of(run: &[Element]) -> (Aabb, Aabb) {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    let (mut clo, mut chi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for e in run {
        let (elo, ehi, c) = match &e.piece {
            Piece::Ball { center, radius } => {
                let c = [center.x, center.y, center.z];
                (c.map(|x| x - radius), c.map(|x| x + radius), c)
            }
            Piece::Triangle { corners: [a, b, c] } => {
                let lo = [a.x.min(b.x).min(c.x), a.y.min(b.y).min(c.y), a.z.min(b.z).min(c.z)];
                let hi = [a.x.max(b.x).max(c.x), a.y.max(b.y).max(c.y), a.z.max(b.z).max(c.z)];
                let m = (a + b + c) / 3.0;
                (lo, hi, [m.x, m.y, m.z])
            }
        };
        for k in 0..3 {
            lo[k] = lo[k].min(elo[k]);
            hi[k] = hi[k].max(ehi[k]);
            clo[k] = clo[k].min(c[k]);
            chi[k] = chi[k].max(c[k]);
        }
    }
    let aabb = |lo: [f32; 3], hi: [f32; 3]| Aabb {
        lo: lo.into(),
        hi: hi.into(),
    };
    (aabb(lo, hi), aabb(clo, chi))
}

/// Moves the pieces for which `left` holds to the front, keeping no order; returns how many.
fn partition(run: &mut [Element], left: impl Fn(&Element) -> bool) -> usize {
    let mut front = 0;
    for i in 0..run.len() {
        if run.get(i).is_some_and(&left) {
            run.swap(front, i);
            front += 1;
        }
    }
    front
}

/// Builds the tree over `pieces` (reordering them) into `nodes`; returns the number of nodes
/// used. Deterministic: the same pieces give the same tree on every target.
pub fn build(pieces: &mut [Element], nodes: &mut [Node]) -> Result<usize, SurfaceError> {
    if pieces.len() > u32::MAX as usize {
        return Err(SurfaceError::TooManyPieces);
    }
    if nodes.len() < nodes_for(pieces.len()) {
        return Err(SurfaceError::TooFewNodes);
    }
    let mut used = 1;
    // Nodes still to fill: (node, first, count); a split pushes two, the depth bounds the stack.
    let mut todo = [(0usize, 0usize, 0usize); MAX_DEPTH + 1];
    todo[0] = (0, 0, pieces.len());
    let mut depth = 1;
    while depth > 0 {
        depth -= 1;
        let (at, first, count) = todo[depth];
        let Some(run) = pieces.get_mut(first..first + count) else {
            return Err(SurfaceError::TooManyPieces);
        };
        let (b, c) = boxes_of(run);
        let mut node = Node {
            lo: b.lo.into(),
            hi: b.hi.into(),
            first: first as u32,
            count: count as u32,
            left: 0,
        };
        if count > LEAF && depth + 2 <= MAX_DEPTH && used + 2 <= nodes.len() {
            let extent = c.hi - c.lo;
            let axis = if extent.x >= extent.y && extent.x >= extent.z {
                0
            } else if extent.y >= extent.z {
                1
            } else {
                2
            };
            // Split at the middle of the centroids' extent (one pass); when that leaves
            // fewer than an eighth on one side, at the median instead.
            let middle = 0.5 * (c.lo[axis] + c.hi[axis]);
            let mut mid = partition(run, |e| e.centroid()[axis] < middle);
            if mid < count / 8 || mid > count - count / 8 {
                mid = count / 2;
                run.select_nth_unstable_by(mid, |a, b| a.centroid()[axis].total_cmp(&b.centroid()[axis]));
            }
            node.left = used as u32;
            todo[depth] = (used, first, mid);
            todo[depth + 1] = (used + 1, first + mid, count - mid);
            depth += 2;
            used += 2;
        }
        if let Some(slot) = nodes.get_mut(at) {
            *slot = node;
        }
    }
    Ok(used)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    #[test]
    fn every_node_holds_its_run_and_leaves_partition_the_pieces() {
        let mut pieces: Vec<Element> = (0..1000)
            .map(|i| {
                let f = i as f32;
                Element::ball([libm::sinf(f) * 0.5, libm::cosf(f * 1.3) * 0.4, f * 1e-3], 0.01, 0).unwrap()
            })
            .collect();
        let mut nodes = std::vec![Node::EMPTY; nodes_for(1000)];
        let used = build(&mut pieces, &mut nodes).unwrap();
        assert!(used < 1000);
        let mut covered = 0;
        for n in &nodes[..used] {
            let b = n.bounds();
            for e in &pieces[n.first as usize..(n.first + n.count) as usize] {
                let eb = e.bounds();
                assert!((0..3).all(|k| eb.lo[k] >= b.lo[k] && eb.hi[k] <= b.hi[k]));
            }
            if n.left == 0 {
                assert!(n.count as usize <= LEAF);
                covered += n.count;
            } else {
                let (l, r) = (nodes[n.left as usize], nodes[n.left as usize + 1]);
                assert_eq!(
                    (l.first, l.count + r.count, r.first),
                    (n.first, n.count, n.first + l.count)
                );
            }
        }
        assert_eq!(covered, 1000);
        let mut short = [nodes[0]; 10];
        assert_eq!(build(&mut pieces, &mut short), Err(SurfaceError::TooFewNodes));
    }
}
