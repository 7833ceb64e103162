//! A static bounding-volume hierarchy over a surface's pieces, built in the caller's buffers:
//! each node's pieces are one contiguous run of the piece buffer (the build reorders it), and
//! a node's children sit side by side in the node buffer. Median splits along the longest axis
//! of the centroids keep the depth at about log₂ of the piece count.

use crate::executor::{Executor, MAX_PARTS};
use crate::surface::element::{Aabb, Element, SurfaceError};

/// A leaf holds at most this many pieces, and a split leaves at least half as many on each
/// side.
pub const LEAF: usize = 16;

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

/// How many nodes a tree over `pieces` pieces can need: a split leaves at least `LEAF / 2`
/// pieces on each side, so a tree has at most `pieces / (LEAF / 2)` leaves and fewer than
/// twice as many nodes.
pub const fn nodes_for(pieces: usize) -> usize {
    let most = 2 * (pieces / (LEAF / 2));
    if most == 0 { 1 } else { most }
}

/// A piece as the build sorts it: its centroid and the number its caller gave it. The build
/// moves these 16-byte keys instead of the pieces, which are then put in place once. Held as
/// four words (x, y and z as `f32` bits, then the number), so that a key moves as one 16-byte
/// value and the splits' partition can pick between two keys without a branch.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct Key {
    bits: [u32; 4],
}

impl Key {
    /// Fills key buffers before [`build`] writes them.
    pub const EMPTY: Self = Self { bits: [0; 4] };

    /// The key of piece number `piece`, whose centroid (finite) is `centroid`.
    pub const fn new(centroid: [f32; 3], piece: u32) -> Self {
        Self {
            bits: [
                centroid[0].to_bits(),
                centroid[1].to_bits(),
                centroid[2].to_bits(),
                piece,
            ],
        }
    }

    /// The number the piece was given.
    pub const fn piece(&self) -> u32 {
        self.bits[3]
    }

    /// The piece's centroid as the key was made with it (a cloud's point itself: the caller
    /// can make the ball from the key, without reading the point again).
    pub const fn centroid(&self) -> [f32; 3] {
        [
            f32::from_bits(self.bits[0]),
            f32::from_bits(self.bits[1]),
            f32::from_bits(self.bits[2]),
        ]
    }

    /// The centroid's coordinate on `axis` (0, 1 or 2).
    fn coordinate(&self, axis: usize) -> f32 {
        f32::from_bits(self.bits.get(axis).copied().unwrap_or(0))
    }

    /// `a` if `take_a`, else `b`, word by word through a mask: no branch on a coin toss.
    fn pick(take_a: bool, a: Self, b: Self) -> Self {
        let mask = 0u32.wrapping_sub(u32::from(take_a));
        Self {
            bits: core::array::from_fn(|k| (a.bits[k] & mask) | (b.bits[k] & !mask)),
        }
    }
}

/// The box of the centroids of `keys`, as (lo, hi). Centroids are finite (pieces are
/// validated), so a plain comparison does what `f32::min` does, without its NaN handling.
fn centroid_box(keys: &[Key]) -> ([f32; 3], [f32; 3]) {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for key in keys {
        let centroid = key.centroid();
        for k in 0..3 {
            let c = centroid[k];
            lo[k] = if c < lo[k] { c } else { lo[k] };
            hi[k] = if c > hi[k] { c } else { hi[k] };
        }
    }
    (lo, hi)
}

/// Moves the keys whose centroid lies below `middle` on `axis` to the front, keeping no order;
/// returns how many. No branch on the side (every key is swapped, only the cursor moves on
/// the side): on a cloud the side is a coin toss, and a mispredicted branch per key would cost
/// more than the pass.
fn partition(keys: &mut [Key], axis: usize, middle: f32) -> usize {
    // The axis a constant in each loop: a coordinate picked at run time was read through
    // memory.
    match axis {
        0 => partition_on::<0>(keys, middle),
        1 => partition_on::<1>(keys, middle),
        _ => partition_on::<2>(keys, middle),
    }
}

/// [`partition`] on axis `AXIS`. The key at `front` is carried in a register (`first`): read
/// back from the slot the last step wrote, it would wait on that store whenever the last key
/// went to the back.
fn partition_on<const AXIS: usize>(keys: &mut [Key], middle: f32) -> usize {
    let Some(&(mut first)) = keys.first() else {
        return 0;
    };
    let mut front = 0;
    for i in 0..keys.len() {
        let Some(&key) = keys.get(i) else {
            break;
        };
        if let Some(slot) = keys.get_mut(i) {
            *slot = first;
        }
        if let Some(slot) = keys.get_mut(front) {
            *slot = key;
        }
        let to_front = f32::from_bits(key.bits[AXIS]) < middle;
        // The key at `front` next: the one after it when this key went to the front (read
        // either way), else this key.
        let after = keys.get(front + 1).copied().unwrap_or(key);
        front += usize::from(to_front);
        first = Key::pick(to_front, after, key);
    }
    front
}

/// Orders `keys` as the tree's leaves hold them and writes the tree's nodes (their runs, not
/// yet their boxes: [`bound`] fills those once the pieces are in this order); returns the
/// number of nodes used. Deterministic: the same keys give the same tree on every target.
///
/// Each node is split at the middle of its centroids' extent along the longest axis, or at
/// the median when the middle leaves fewer than an eighth (or two) on one side.
pub fn split(keys: &mut [Key], nodes: &mut [Node]) -> Result<usize, SurfaceError> {
    check_buffers(keys, nodes)?;
    subtree(keys, nodes, Offsets::ROOT)
}

/// [`split`] with the root's two subtrees built as two items of `exec` (at once on a host's
/// threads): the same tree, bit for bit, as [`split`] makes.
pub fn split_on<E: Executor>(exec: &E, keys: &mut [Key], nodes: &mut [Node]) -> Result<usize, SurfaceError> {
    check_buffers(keys, nodes)?;
    let count = keys.len();
    // Below this many keys, or on one thread, the handing over costs more than it saves.
    if exec.parts() < 2 || count < PARALLEL_FROM || nodes.len() < 3 {
        return subtree(keys, nodes, Offsets::ROOT);
    }
    let mid = divide(keys);
    let (left_keys, right_keys) = keys.split_at_mut(mid);
    // `split` numbers the root 0, its children 1 and 2, then the right child's descendants
    // (the stack's top), then the left child's. Each subtree is built in a region of its own
    // with local numbers (its root 0), then moved to those places.
    let right_room = nodes_for(right_keys.len()) - 1;
    let (head, rest) = nodes.split_at_mut(2);
    let (right_nodes, left_nodes) = rest.split_at_mut(right_room.min(rest.len()));
    let mut parts = [
        Part {
            keys: left_keys,
            nodes: left_nodes,
            at: Offsets { first: 0, depth: 0 },
            used: Err(SurfaceError::TooFewNodes),
        },
        Part {
            keys: right_keys,
            nodes: right_nodes,
            at: Offsets { first: mid, depth: 1 },
            used: Err(SurfaceError::TooFewNodes),
        },
    ];
    // The task never fails: a subtree's own error travels in its `used` (as does a part an
    // executor did not run).
    let _ = exec.each(&mut parts, |part| {
        part.used = subtree(part.keys, part.nodes, part.at);
        Ok(())
    });
    let [left, right] = parts;
    let (left_used, right_used) = (left.used?, right.used?);
    // The right subtree is in place (its root is node 2): its children's numbers move by 2.
    for node in right.nodes.iter_mut().take(right_used) {
        if node.left != 0 {
            node.left += 2;
        }
    }
    // The left subtree's root becomes node 1, its descendants follow the right subtree's.
    let shift = 1 + right_used as u32;
    for node in left.nodes.iter_mut().take(left_used) {
        if node.left != 0 {
            node.left += shift;
        }
    }
    let left_root = left.nodes.first().copied().unwrap_or(Node::EMPTY);
    if let [root, left_child] = head {
        *root = Node {
            first: 0,
            count: count as u32,
            left: 1,
            ..Node::EMPTY
        };
        *left_child = left_root;
    }
    let left_start = 2 + right_room;
    if left_used >= 1 && left_start + left_used <= nodes.len() {
        nodes.copy_within(left_start + 1..left_start + left_used, 2 + right_used);
    }
    Ok(1 + right_used + left_used)
}

/// Below this many keys [`split_on`] splits on the calling thread.
const PARALLEL_FROM: usize = 1 << 14;

/// One subtree of [`split_on`]: its keys, the region its nodes are built in, where it stands in
/// the whole tree, and how many nodes it used.
struct Part<'a> {
    keys: &'a mut [Key],
    nodes: &'a mut [Node],
    at: Offsets,
    used: Result<usize, SurfaceError>,
}

/// Where a subtree stands in the whole tree: the number of its first key, and how deep
/// [`split`]'s stack already is when it reaches the subtree's root.
#[derive(Clone, Copy)]
struct Offsets {
    first: usize,
    depth: usize,
}

impl Offsets {
    const ROOT: Self = Self { first: 0, depth: 0 };
}

fn check_buffers(keys: &[Key], nodes: &[Node]) -> Result<(), SurfaceError> {
    if keys.len() > u32::MAX as usize {
        return Err(SurfaceError::TooManyPieces);
    }
    if nodes.len() < nodes_for(keys.len()) {
        return Err(SurfaceError::TooFewNodes);
    }
    Ok(())
}

/// Splits `run` in two as the tree does (see [`split`]) and returns the length of the first
/// part; `run` holds more than [`LEAF`] keys.
fn divide(run: &mut [Key]) -> usize {
    let count = run.len();
    let (clo, chi) = centroid_box(run);
    let extent: [f32; 3] = core::array::from_fn(|k| chi[k] - clo[k]);
    let axis = if extent[0] >= extent[1] && extent[0] >= extent[2] {
        0
    } else if extent[1] >= extent[2] {
        1
    } else {
        2
    };
    let middle = 0.5 * (clo[axis] + chi[axis]);
    let mut mid = partition(run, axis, middle);
    // At least an eighth on each side, and half a leaf: every leaf then holds that
    // many (so `nodes_for` suffices) and equal centroids cannot chain empty nodes.
    let least = (count / 8).max(LEAF / 2);
    if mid < least || mid > count - least {
        mid = count / 2;
        run.select_nth_unstable_by(mid, |a, b| a.coordinate(axis).total_cmp(&b.coordinate(axis)));
    }
    mid
}

/// [`split`] of the subtree whose keys are `keys`, at `at` in the whole tree, into `nodes`
/// (its root node 0; `left` and `first` as the whole tree numbers keys, nodes locally).
fn subtree(keys: &mut [Key], nodes: &mut [Node], at: Offsets) -> Result<usize, SurfaceError> {
    let mut used = 1;
    // Nodes still to split: (node, first, count); a split pushes two, the depth bounds the stack.
    let mut todo = [(0usize, 0usize, 0usize); MAX_DEPTH + 1];
    todo[0] = (0, 0, keys.len());
    let mut depth = 1;
    while depth > 0 {
        depth -= 1;
        let (node_at, first, count) = todo[depth];
        let Some(run) = keys.get_mut(first..first + count) else {
            return Err(SurfaceError::TooManyPieces);
        };
        let mut node = Node {
            first: (at.first + first) as u32,
            count: count as u32,
            ..Node::EMPTY
        };
        if count > LEAF && at.depth + depth + 2 <= MAX_DEPTH && used + 2 <= nodes.len() {
            let mid = divide(run);
            node.left = used as u32;
            let Some(slots) = todo.get_mut(depth..depth + 2) else {
                return Err(SurfaceError::TooFewNodes);
            };
            slots[0] = (used, first, mid);
            slots[1] = (used + 1, first + mid, count - mid);
            depth += 2;
            used += 2;
        }
        if let Some(slot) = nodes.get_mut(node_at) {
            *slot = node;
        }
    }
    Ok(used)
}

/// Fills the boxes of the nodes [`split`] wrote, over the pieces in the keys' order. Children
/// come after their parent: one backward pass fills every box from below.
pub fn bound(pieces: &[Element], nodes: &mut [Node]) {
    bound_leaves(pieces, nodes);
    bound_inner(nodes);
}

/// [`bound`] with the leaves' boxes (a pass over every piece) filled in parts of the node
/// buffer, as items of `exec`: the same boxes (a box is a minimum and a maximum, whatever the
/// order).
pub fn bound_on<E: Executor>(exec: &E, pieces: &[Element], nodes: &mut [Node]) {
    let parts = exec.parts().clamp(1, MAX_PARTS);
    let size = nodes.len().div_ceil(parts).max(1);
    let mut chunks: [&mut [Node]; MAX_PARTS] = Default::default();
    for (slot, chunk) in chunks.iter_mut().zip(nodes.chunks_mut(size)) {
        *slot = chunk;
    }
    let parted = exec.each(&mut chunks[..parts], |chunk| {
        bound_leaves(pieces, chunk);
        Ok(())
    });
    if parted.is_err() {
        // No task fails; should an executor not run them all, the serial pass does.
        bound_leaves(pieces, nodes);
    }
    bound_inner(nodes);
}

/// The boxes of the leaves among `nodes` (a leaf's run of `pieces` names its pieces).
fn bound_leaves(pieces: &[Element], nodes: &mut [Node]) {
    for node in nodes.iter_mut().filter(|n| n.left == 0) {
        let end = node.first as usize + node.count as usize;
        let b = pieces
            .get(node.first as usize..end)
            .unwrap_or(&[])
            .iter()
            .fold(Aabb::EMPTY, |b, e| b.union(&e.bounds()));
        node.lo = b.lo.into();
        node.hi = b.hi.into();
    }
}

/// The boxes of the inner nodes, from their children's: children come after their parent, so
/// one backward pass fills them from below.
fn bound_inner(nodes: &mut [Node]) {
    for i in (0..nodes.len()).rev() {
        let Some(&node) = nodes.get(i) else { continue };
        if node.left == 0 {
            continue;
        }
        let child = |k: u32| nodes.get(k as usize).map_or(Aabb::EMPTY, Node::bounds);
        let b = child(node.left).union(&child(node.left + 1));
        if let Some(slot) = nodes.get_mut(i) {
            slot.lo = b.lo.into();
            slot.hi = b.hi.into();
        }
    }
}

/// Builds the tree over `input` into `nodes`, writing the pieces in the tree's order to
/// `pieces` (at least as long as `input`), with `keys` (as long as `input`) as scratch;
/// returns the number of nodes used: [`split`], each piece copied once to its place, [`bound`].
/// A caller that makes its pieces from other data (a cloud's points) can skip `input`: keys
/// from that data, [`split`], the pieces made in the keys' order, [`bound`].
pub fn build(
    input: &[Element],
    pieces: &mut [Element],
    nodes: &mut [Node],
    keys: &mut [Key],
) -> Result<usize, SurfaceError> {
    if input.len() > u32::MAX as usize || pieces.len() < input.len() {
        return Err(SurfaceError::TooManyPieces);
    }
    let Some(keys) = keys.get_mut(..input.len()) else {
        return Err(SurfaceError::TooFewKeys);
    };
    for (i, (key, e)) in keys.iter_mut().zip(input.iter()).enumerate() {
        *key = Key::new(e.centroid().into(), i as u32);
    }
    let used = split(keys, nodes)?;
    for (slot, key) in pieces.iter_mut().zip(keys.iter()) {
        if let Some(e) = input.get(key.piece() as usize) {
            *slot = *e;
        }
    }
    if let Some(nodes) = nodes.get_mut(..used) {
        bound(pieces.get(..input.len()).unwrap_or(&[]), nodes);
    }
    Ok(used)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// Checks the tree over `pieces` and returns how many nodes it has.
    fn checked_tree(pieces: &mut [Element]) -> usize {
        let count = pieces.len();
        let mut nodes = std::vec![Node::EMPTY; nodes_for(count)];
        let mut keys = std::vec![Key::EMPTY; count];
        let input = pieces.to_vec();
        let used = build(&input, pieces, &mut nodes, &mut keys).unwrap();
        let mut covered = 0;
        for n in &nodes[..used] {
            let b = n.bounds();
            for e in &pieces[n.first as usize..(n.first + n.count) as usize] {
                let eb = e.bounds();
                assert!((0..3).all(|k| eb.lo[k] >= b.lo[k] && eb.hi[k] <= b.hi[k]));
            }
            if n.left == 0 {
                assert!(n.count as usize <= LEAF && n.count as usize >= LEAF / 2);
                covered += n.count as usize;
            } else {
                let (l, r) = (nodes[n.left as usize], nodes[n.left as usize + 1]);
                assert_eq!(
                    (l.first, l.count + r.count, r.first),
                    (n.first, n.count, n.first + l.count)
                );
            }
        }
        assert_eq!(covered, count);
        used
    }

    #[test]
    fn split_on_threads_makes_the_same_tree_as_split() {
        use crate::executor::Reversed;
        // Surfaces of a few planes (many equal coordinates: the medians' ties), and a blob.
        for (n, planes) in [(PARALLEL_FROM + 5, true), (40_000, true), (70_001, false)] {
            let keys: Vec<Key> = (0..n)
                .map(|i| {
                    let f = i as f32;
                    let c = if planes {
                        [
                            ((i % 7) as f32) * 0.1,
                            (i % 113) as f32 * 0.01,
                            ((i / 113) % 97) as f32 * 0.01,
                        ]
                    } else {
                        [
                            libm::sinf(f) * 0.5,
                            libm::cosf(f * 1.3) * 0.4,
                            libm::sinf(f * 0.7) * 0.3,
                        ]
                    };
                    Key::new(c, i as u32)
                })
                .collect();
            let (mut serial_keys, mut threaded_keys) = (keys.clone(), keys.clone());
            let mut serial = std::vec![Node::EMPTY; nodes_for(n)];
            let mut threaded = std::vec![Node::EMPTY; nodes_for(n)];
            let used = split(&mut serial_keys, &mut serial).unwrap();
            let used_on = split_on(&Reversed(2), &mut threaded_keys, &mut threaded).unwrap();
            assert_eq!(used, used_on, "{n} keys");
            assert_eq!(serial[..used], threaded[..used], "{n} keys");
            assert_eq!(serial_keys, threaded_keys, "{n} keys");
            // The boxes too, over balls in the keys' order.
            let pieces: Vec<Element> = serial_keys
                .iter()
                .map(|k| Element::ball(k.centroid(), 0.0075, 0).unwrap())
                .collect();
            bound(&pieces, &mut serial[..used]);
            bound_on(&Reversed(3), &pieces, &mut threaded[..used]);
            assert_eq!(serial[..used], threaded[..used], "{n} keys");
            assert!(serial[0].lo[0] < serial[0].hi[0]);
        }
    }

    #[test]
    fn partition_leaves_the_keys_as_the_plain_swapping_pass_does() {
        // The pass as first written: every key swapped with the one at `front`, read back from
        // the buffer. The carried key must leave every key where that pass leaves it.
        fn swapping(keys: &mut [Key], axis: usize, middle: f32) -> usize {
            let mut front = 0;
            for i in 0..keys.len() {
                keys.swap(i, front);
                front += usize::from(keys[front].centroid()[axis] < middle);
            }
            front
        }
        let mut rng = crate::rng::Rng::new(3);
        for n in [0usize, 1, 2, 17, 1000] {
            let keys: Vec<Key> = (0..n)
                .map(|i| {
                    // A coarse grid: equal coordinates, runs of one side, -0.0 beside 0.0.
                    let c = core::array::from_fn(|_| (rng.uniform_f32(-3.0, 3.0) as i32) as f32 * 0.5);
                    let c = if i % 7 == 0 { [-0.0, c[1], c[2]] } else { c };
                    Key::new(c, i as u32)
                })
                .collect();
            for axis in 0..3 {
                for middle in [-1.0f32, 0.0, 0.25, 5.0] {
                    let (mut ours, mut theirs) = (keys.clone(), keys.clone());
                    let front = partition(&mut ours, axis, middle);
                    assert_eq!(front, swapping(&mut theirs, axis, middle), "{n} keys, axis {axis}");
                    assert_eq!(ours, theirs, "{n} keys, axis {axis}, middle {middle}");
                }
            }
        }
    }

    #[test]
    fn a_key_gives_back_its_centroid_and_piece_bit_for_bit() {
        let key = Key::new([-0.0, 1.5e-39, -7.25], u32::MAX);
        assert_eq!(
            key.centroid().map(f32::to_bits),
            [(-0.0f32).to_bits(), 1.5e-39f32.to_bits(), (-7.25f32).to_bits()]
        );
        assert_eq!((key.piece(), key.coordinate(2)), (u32::MAX, -7.25));
        let other = Key::new([1.0; 3], 4);
        assert_eq!(Key::pick(true, key, other), key);
        assert_eq!(Key::pick(false, key, other), other);
    }

    #[test]
    fn equal_points_make_a_balanced_tree_of_full_leaves() {
        // A camera's cloud repeats points; the middle of an empty extent splits nothing.
        let mut pieces = std::vec![Element::ball([0.5, 0.0, 0.3], 0.01, 0).unwrap(); 1000];
        assert!(checked_tree(&mut pieces) <= nodes_for(1000));
    }

    #[test]
    fn every_node_holds_its_run_and_leaves_partition_the_pieces() {
        let mut pieces: Vec<Element> = (0..1000)
            .map(|i| {
                let f = i as f32;
                Element::ball([libm::sinf(f) * 0.5, libm::cosf(f * 1.3) * 0.4, f * 1e-3], 0.01, 0).unwrap()
            })
            .collect();
        assert!(checked_tree(&mut pieces) <= nodes_for(1000));
        let mut nodes = std::vec![Node::EMPTY; nodes_for(1000)];
        let mut keys = std::vec![Key::EMPTY; 1000];
        let used = build(&pieces.clone(), &mut pieces, &mut nodes, &mut keys).unwrap();
        assert!(used <= nodes_for(1000));
        let mut short = [nodes[0]; 10];
        assert_eq!(
            build(&pieces.clone(), &mut pieces, &mut short, &mut keys),
            Err(SurfaceError::TooFewNodes)
        );
        assert_eq!(
            build(&pieces.clone(), &mut pieces, &mut nodes, &mut keys[..999]),
            Err(SurfaceError::TooFewKeys)
        );
    }
}
