//! A planning problem as plain numbers, for the wire (postcard) into firmware.
//!
//! [`Scene`] holds validated obstacles (rotation matrices); the wire carries what a scene file
//! says instead: each primitive's parameters and quaternion, the finger opening, the start, a joint goal (a pose
//! goal is resolved on the host: the firmware runs no IK) and the seed. [`Problem::to_scene`]
//! rebuilds the scene through the same [`Primitive::to_obstacle`] the host uses, so both sides
//! plan on the same bits. Only with the `serde` feature.
//!
//! A scene with clouds or meshes adds a surface section after the problem's bytes (a problem
//! without one is byte for byte what it was before surfaces): a header (piece and node counts,
//! the guide boxes' limit), then each piece (a ball or a triangle and its obstacle index), then
//! each node of the tree the host built with [`crate::surface::bvh::build`]. [`decode`] reads
//! it into caller-owned [`WireSurface`] buffers one item at a time (no temporary copy),
//! validating every piece ([`Element::ball`], [`Element::triangle`]) and the tree
//! ([`Surface::new`]); [`Problem::to_scene_with`] fits the guide boxes with the host's own
//! [`covers`]. Every refusal is a [`WireError`], never a panic.

use crate::cost::cover::{MAX_COVERS, covers};
use crate::robot::JOINTS;
use crate::scene::{MAX_OBSTACLES, Obstacle, Primitive, Scene, SceneError};
use crate::surface::Surface;
use crate::surface::bvh::Node;
use crate::surface::element::{Element, Piece, SurfaceError};
use serde::{Deserialize, Serialize};
/// One planning problem: obstacles (at most `N`), the held object, the finger opening, the
/// ends (`J` joints: the arm the firmware was built for; the bytes do not name it) and the seed.
/// A joint vector is `J` plain `f32`s on the wire, so the Panda's bytes are what they were
/// before the arm became a parameter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(bound(serialize = "[f32; J]: Serialize", deserialize = "[f32; J]: Deserialize<'de>"))]
pub struct Problem<const N: usize = MAX_OBSTACLES, const J: usize = JOINTS> {
    /// The obstacles, in the scene file's order (the checker reports contacts by index).
    pub obstacles: heapless::Vec<Primitive, N>,
    /// An object held in the hand (pose in the `panda_hand` frame; another arm's TCP link), if
    /// any.
    pub held: Option<Primitive>,
    /// Opening of each finger, metres (the scene file's `gripper.finger`; 0.025 when absent),
    /// validated by [`Scene::set_gripper`].
    pub finger: f32,
    /// Start configuration.
    pub start: [f32; J],
    /// Goal configuration.
    pub goal: [f32; J],
    /// Seed of the planner's [`crate::rng::Rng`].
    pub seed: u64,
}

impl<const N: usize, const J: usize> Problem<N, J> {
    /// The scene, every primitive validated on the way in.
    pub fn to_scene(&self) -> Result<Scene<'static, N>, SceneError> {
        let mut scene = Scene::new();
        for primitive in &self.obstacles {
            scene.push(primitive.to_obstacle()?)?;
        }
        if let Some(held) = &self.held {
            scene.hold(held.to_obstacle()?);
        }
        scene.set_gripper(self.finger)?;
        Ok(scene)
    }

    /// The scene with the decoded surface (when it has pieces) and the guide boxes around it:
    /// [`covers`] with the limit the host used, so the boxes are the host's bit for bit.
    pub fn to_scene_with<'a, const P: usize, const T: usize>(
        &self,
        surface: &'a WireSurface<P, T>,
    ) -> Result<Scene<'a, N>, WireError> {
        let scene = self.to_scene().map_err(WireError::Scene)?;
        if surface.pieces.is_empty() {
            return Ok(scene);
        }
        let view = surface.surface()?;
        let mut boxes = [Obstacle::PLACEHOLDER; MAX_COVERS];
        let limit = usize::from(surface.boxes).min(MAX_COVERS);
        let made = covers(&view, boxes.get_mut(..limit).unwrap_or(&mut []));
        Ok(scene.with_surface(view, boxes.get(..made).unwrap_or(&[])))
    }
}

/// Why wire bytes were refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum WireError {
    /// Not the postcard bytes of a problem and a surface section: truncated, a bad tag, more
    /// obstacles than the capacity, an empty or unfinished section, bytes after it.
    Decode,
    /// More pieces or nodes than the [`WireSurface`] holds.
    Capacity,
    /// More guide boxes than [`MAX_COVERS`].
    TooManyBoxes,
    /// A degenerate triangle (the host drops those before building the tree).
    DegenerateTriangle,
    /// A piece or the tree refused ([`Element::ball`], [`Surface::new`]).
    Surface(SurfaceError),
    /// A primitive or the finger opening refused.
    Scene(SceneError),
}

impl core::fmt::Display for WireError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Decode => f.write_str("not the postcard bytes of a problem"),
            Self::Capacity => f.write_str("more pieces or nodes than the decoder's capacity"),
            Self::TooManyBoxes => f.write_str("more guide boxes than cost::cover::MAX_COVERS"),
            Self::DegenerateTriangle => f.write_str("a degenerate triangle"),
            Self::Surface(e) => write!(f, "surface: {e}"),
            Self::Scene(e) => write!(f, "scene: {e}"),
        }
    }
}

impl core::error::Error for WireError {}

/// The surface section's header.
#[derive(Serialize, Deserialize)]
struct Header {
    pieces: u32,
    nodes: u32,
    boxes: u8,
}

/// A piece as plain numbers.
#[derive(Serialize, Deserialize)]
enum WirePiece {
    Ball { center: [f32; 3], radius: f32 },
    Triangle { corners: [[f32; 3]; 3] },
}

#[derive(Serialize, Deserialize)]
struct WireElement {
    piece: WirePiece,
    obstacle: u16,
}

impl WireElement {
    fn of(e: &Element) -> Self {
        let piece = match e.piece {
            Piece::Ball { center, radius } => WirePiece::Ball {
                center: center.into(),
                radius,
            },
            Piece::Triangle { corners } => WirePiece::Triangle {
                corners: corners.map(Into::into),
            },
        };
        Self {
            piece,
            obstacle: e.obstacle,
        }
    }

    fn element(&self) -> Result<Element, WireError> {
        match self.piece {
            WirePiece::Ball { center, radius } => {
                Element::ball(center, radius, self.obstacle).map_err(WireError::Surface)
            }
            WirePiece::Triangle { corners } => Element::triangle(corners, self.obstacle)
                .map_err(WireError::Surface)?
                .ok_or(WireError::DegenerateTriangle),
        }
    }
}

/// Bytes a surface section of `pieces` pieces and `nodes` nodes takes at most.
pub const fn surface_bytes_max(pieces: usize, nodes: usize) -> usize {
    // Header: two varint u32 and a byte; a piece: tag, 9 floats, varint u16; a node: 6 floats,
    // 3 varint u32.
    11 + pieces * 40 + nodes * 39
}

/// Writes the surface section (what follows a problem's bytes) into `out`; returns its length.
/// `boxes` is the limit the host gave [`covers`].
pub fn encode_surface(pieces: &[Element], nodes: &[Node], boxes: u8, out: &mut [u8]) -> Result<usize, WireError> {
    let (Ok(np), Ok(nn)) = (u32::try_from(pieces.len()), u32::try_from(nodes.len())) else {
        return Err(WireError::Capacity);
    };
    let header = Header {
        pieces: np,
        nodes: nn,
        boxes,
    };
    let mut used = put(&header, out, 0)?;
    for e in pieces {
        used = put(&WireElement::of(e), out, used)?;
    }
    for n in nodes {
        used = put(n, out, used)?;
    }
    Ok(used)
}

fn put<T: Serialize>(value: &T, out: &mut [u8], at: usize) -> Result<usize, WireError> {
    let rest = out.get_mut(at..).ok_or(WireError::Capacity)?;
    let n = postcard::to_slice(value, rest).map_err(|_| WireError::Capacity)?.len();
    Ok(at + n)
}

fn take<'b, T: Deserialize<'b>>(bytes: &'b [u8]) -> Result<(T, &'b [u8]), WireError> {
    postcard::take_from_bytes(bytes).map_err(|_| WireError::Decode)
}

/// The decoded pieces (at most `P`, balls and triangles of every cloud and mesh together), the
/// tree over them (at most `T` nodes: [`crate::surface::bvh::nodes_for`]`(P)` holds any tree
/// the host builds over `P` pieces) and the guide boxes' limit. Big (about 44 bytes a piece and
/// 36 a node): firmware keeps it in a `static`.
#[derive(Clone, Debug, PartialEq)]
pub struct WireSurface<const P: usize, const T: usize = P> {
    pieces: heapless::Vec<Element, P>,
    nodes: heapless::Vec<Node, T>,
    boxes: u8,
}

impl<const P: usize, const T: usize> Default for WireSurface<P, T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const P: usize, const T: usize> WireSurface<P, T> {
    /// No pieces.
    pub const fn new() -> Self {
        Self {
            pieces: heapless::Vec::new(),
            nodes: heapless::Vec::new(),
            boxes: 0,
        }
    }

    /// The pieces, in the tree's order.
    pub fn pieces(&self) -> &[Element] {
        &self.pieces
    }

    /// The tree's nodes.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The limit the host gave [`covers`].
    pub fn boxes(&self) -> u8 {
        self.boxes
    }

    /// The validated view the scene borrows.
    pub fn surface(&self) -> Result<Surface<'_>, WireError> {
        Surface::new(&self.pieces, &self.nodes).map_err(WireError::Surface)
    }
}

/// Decodes a problem (at most `N` obstacles) and, when bytes follow it, its surface section
/// into `surface` (emptied first), validating each piece and the tree.
pub fn decode<const N: usize, const P: usize, const T: usize, const J: usize>(
    bytes: &[u8],
    surface: &mut WireSurface<P, T>,
) -> Result<Problem<N, J>, WireError>
where
    [f32; J]: for<'de> Deserialize<'de>,
{
    let decoded = decode_into(bytes, surface);
    if decoded.is_err() {
        // A refused section leaves no half-filled buffers behind.
        surface.pieces.clear();
        surface.nodes.clear();
        surface.boxes = 0;
    }
    decoded
}

fn decode_into<const N: usize, const P: usize, const T: usize, const J: usize>(
    bytes: &[u8],
    surface: &mut WireSurface<P, T>,
) -> Result<Problem<N, J>, WireError>
where
    [f32; J]: for<'de> Deserialize<'de>,
{
    surface.pieces.clear();
    surface.nodes.clear();
    surface.boxes = 0;
    let (problem, rest) = take::<Problem<N, J>>(bytes)?;
    if rest.is_empty() {
        return Ok(problem);
    }
    let (header, mut rest) = take::<Header>(rest)?;
    if header.pieces == 0 {
        // The host writes a section only for pieces: one form per problem.
        return Err(WireError::Decode);
    }
    if header.pieces as usize > P || header.nodes as usize > T {
        return Err(WireError::Capacity);
    }
    if usize::from(header.boxes) > MAX_COVERS {
        return Err(WireError::TooManyBoxes);
    }
    for _ in 0..header.pieces {
        let (w, r) = take::<WireElement>(rest)?;
        rest = r;
        surface.pieces.push(w.element()?).map_err(|_| WireError::Capacity)?;
    }
    for _ in 0..header.nodes {
        let (n, r) = take::<Node>(rest)?;
        rest = r;
        surface.nodes.push(n).map_err(|_| WireError::Capacity)?;
    }
    if !rest.is_empty() {
        return Err(WireError::Decode);
    }
    surface.boxes = header.boxes;
    surface.surface()?;
    Ok(problem)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Obstacle;

    const ID: [f32; 4] = [1.0, 0.0, 0.0, 0.0];

    fn problem() -> Problem<4> {
        let mut obstacles = heapless::Vec::new();
        for p in [
            Primitive::Cuboid {
                center: [0.5, 0.0, -0.01],
                dims: [1.2, 1.6, 0.02],
                quaternion: ID,
            },
            Primitive::Cylinder {
                center: [0.45, 0.45, 0.1],
                radius: 0.05,
                height: 0.2,
                quaternion: ID,
            },
            Primitive::Sphere {
                center: [0.35, -0.45, 0.6],
                radius: 0.06,
            },
        ] {
            obstacles.push(p).unwrap();
        }
        Problem {
            obstacles,
            held: None,
            finger: 0.025,
            start: [0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785],
            goal: [-0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785],
            seed: 7,
        }
    }

    #[test]
    fn builds_the_scene_through_the_constructors() {
        let p = problem();
        let scene = p.to_scene().unwrap();
        assert_eq!(scene.obstacles().len(), 3);
        assert_eq!(
            scene.obstacles()[1],
            Obstacle::cylinder([0.45, 0.45, 0.1], 0.05, 0.2, ID).unwrap()
        );
        assert!(scene.held().is_none());
        assert_eq!(scene.gripper(), 0.025);
    }

    #[test]
    fn bad_primitives_are_typed_errors() {
        let mut p = problem();
        p.held = Some(Primitive::Sphere {
            center: [0.0; 3],
            radius: -1.0,
        });
        assert_eq!(p.to_scene().unwrap_err(), SceneError::NonPositiveSize);
        p.held = None;
        p.obstacles[0] = Primitive::Cuboid {
            center: [0.0; 3],
            dims: [1.0; 3],
            quaternion: [0.5, 0.0, 0.0, 0.0],
        };
        assert_eq!(p.to_scene().unwrap_err(), SceneError::QuaternionNorm);
    }

    #[test]
    fn carries_the_finger_opening() {
        let mut p = problem();
        p.finger = 0.04;
        assert_eq!(p.to_scene().unwrap().gripper(), 0.04);
        for (bad, e) in [
            (0.041, SceneError::FingerOutOfRange),
            (-0.01, SceneError::FingerOutOfRange),
            (f32::NAN, SceneError::NonFinite),
        ] {
            p.finger = bad;
            assert_eq!(p.to_scene().unwrap_err(), e, "{bad}");
        }
    }

    #[test]
    fn carries_the_held_object() {
        let mut p = problem();
        p.held = Some(p.obstacles[2]);
        let scene = p.to_scene().unwrap();
        assert_eq!(scene.held(), Some(&scene.obstacles()[2]));
    }

    fn cloud(n: usize) -> (std::vec::Vec<Element>, std::vec::Vec<Node>) {
        use crate::surface::bvh::{Key, build, nodes_for};
        let mut pieces: std::vec::Vec<Element> = (0..n)
            .map(|i| {
                Element::ball(
                    [0.55, (i % 10) as f32 * 0.02 - 0.1, 0.3 + (i / 10) as f32 * 0.02],
                    0.0075,
                    1,
                )
                .unwrap()
            })
            .collect();
        let mut nodes = std::vec![Node::EMPTY; nodes_for(n)];
        let mut keys = std::vec![Key::EMPTY; n];
        let used = build(&pieces.clone(), &mut pieces, &mut nodes, &mut keys).unwrap();
        nodes.truncate(used);
        (pieces, nodes)
    }

    /// The problem's bytes, then a surface section of these pieces and nodes.
    fn bytes(p: &Problem<4>, pieces: &[Element], nodes: &[Node], boxes: u8) -> std::vec::Vec<u8> {
        let mut buf = std::vec![0u8; 1024 + surface_bytes_max(pieces.len(), nodes.len())];
        let n = postcard::to_slice(p, &mut buf).unwrap().len();
        let m = if pieces.is_empty() {
            0
        } else {
            encode_surface(pieces, nodes, boxes, &mut buf[n..]).unwrap()
        };
        buf.truncate(n + m);
        buf
    }

    #[test]
    fn a_surface_travels_after_the_problem() {
        let p = problem();
        let (pieces, nodes) = cloud(60);
        let mut s = std::boxed::Box::new(WireSurface::<64>::new());
        // Without a section: the bytes of a problem as before surfaces.
        assert_eq!(
            decode::<4, 64, 64, JOINTS>(&bytes(&p, &[], &[], 0), &mut s),
            Ok(p.clone())
        );
        assert!(s.pieces().is_empty());
        let b = bytes(&p, &pieces, &nodes, 5);
        assert_eq!(decode::<4, 64, 64, JOINTS>(&b, &mut s), Ok(p.clone()));
        assert_eq!((s.pieces(), s.nodes(), s.boxes()), (&pieces[..], &nodes[..], 5));
        let scene = p.to_scene_with(&s).unwrap();
        assert_eq!(scene.obstacles(), p.to_scene().unwrap().obstacles());
        assert_eq!(scene.surface().pieces().len(), 60);
        // The host's covers, with the same limit, after the primitives (as many as N leaves room for).
        let view = Surface::new(&pieces, &nodes).unwrap();
        let mut boxes = [Obstacle::PLACEHOLDER; 5];
        // At most one box a leaf: 60 pieces may have fewer leaves than the limit.
        assert!((1..=5).contains(&covers(&view, &mut boxes)));
        assert_eq!(&scene.guide_obstacles()[3..], &boxes[..1]);
        // A mesh's triangles travel too.
        let t = Element::triangle([[0.5, 0.0, 0.0], [0.6, 0.0, 0.0], [0.5, 0.1, 0.2]], 2)
            .unwrap()
            .unwrap();
        let root = Node {
            lo: t.bounds().lo.into(),
            hi: t.bounds().hi.into(),
            first: 0,
            count: 1,
            left: 0,
        };
        assert_eq!(
            decode::<4, 64, 64, JOINTS>(&bytes(&p, &[t], &[root], 1), &mut s),
            Ok(p.clone())
        );
        assert_eq!(s.pieces(), &[t]);
    }

    #[test]
    fn malformed_sections_are_typed_errors() {
        let p = problem();
        let (pieces, nodes) = cloud(60);
        let mut s = std::boxed::Box::new(WireSurface::<64>::new());
        let good = bytes(&p, &pieces, &nodes, 5);
        // A child's box not inside its parent's: the walk could skip its pieces.
        let l = nodes[0].left as usize;
        let mut outside = nodes.clone();
        outside[l].lo[1] -= 1.0;
        let refused = Err(WireError::Surface(SurfaceError::TooFewNodes));
        assert_eq!(
            decode::<4, 64, 64, JOINTS>(&bytes(&p, &pieces, &outside, 5), &mut s),
            refused
        );
        assert!(s.pieces().is_empty(), "a refused section leaves the buffers empty");
        // A run beyond the pieces, and a leaf whose run misses one of its pieces' boxes.
        let mut run = nodes.clone();
        let leaf = run.iter().position(|n| n.left == 0).unwrap();
        run[leaf].first = 59;
        run[leaf].count = 4;
        assert_eq!(
            decode::<4, 64, 64, JOINTS>(&bytes(&p, &pieces, &run, 5), &mut s),
            refused
        );
        let mut cycle = nodes.clone();
        cycle[l].left = l as u32;
        assert_eq!(
            decode::<4, 64, 64, JOINTS>(&bytes(&p, &pieces, &cycle, 5), &mut s),
            refused
        );
        assert_eq!(
            decode::<4, 64, 64, JOINTS>(&bytes(&p, &pieces, &[], 5), &mut s),
            refused
        );
        // Pieces validated as the constructors do.
        let mut bad = pieces.clone();
        bad[3].piece = Piece::Ball {
            center: nalgebra::Vector3::new(0.5, f32::NAN, 0.3),
            radius: 0.0075,
        };
        assert_eq!(
            decode::<4, 64, 64, JOINTS>(&bytes(&p, &bad, &nodes, 5), &mut s),
            Err(WireError::Surface(SurfaceError::NonFinite))
        );
        let flat = [[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        bad[3].piece = Piece::Triangle {
            corners: flat.map(Into::into),
        };
        assert_eq!(
            decode::<4, 64, 64, JOINTS>(&bytes(&p, &bad, &nodes, 5), &mut s),
            Err(WireError::DegenerateTriangle)
        );
        // Capacity, boxes, truncation, trailing bytes.
        assert_eq!(
            decode::<4, 32, 32, JOINTS>(&good, &mut std::boxed::Box::new(WireSurface::new())),
            Err(WireError::Capacity)
        );
        // Room for the pieces, not for their tree's nodes.
        assert!(nodes.len() > 1);
        assert_eq!(
            decode::<4, 64, 1, JOINTS>(&good, &mut std::boxed::Box::new(WireSurface::new())),
            Err(WireError::Capacity)
        );
        assert_eq!(
            decode::<4, 64, 64, JOINTS>(&bytes(&p, &pieces, &nodes, 65), &mut s),
            Err(WireError::TooManyBoxes)
        );
        for cut in [good.len() - 1, good.len() - 30, 80] {
            assert_eq!(
                decode::<4, 64, 64, JOINTS>(&good[..cut], &mut s),
                Err(WireError::Decode),
                "{cut}"
            );
        }
        let mut long = good.clone();
        long.push(0);
        assert_eq!(decode::<4, 64, 64, JOINTS>(&long, &mut s), Err(WireError::Decode));
        assert_eq!(decode::<4, 64, 64, JOINTS>(&good, &mut s), Ok(p));
    }

    #[test]
    fn arbitrary_bytes_never_panic() {
        // A cheap stand-in for the fuzz target: every prefix and many byte flips of a good input.
        let p = problem();
        let (pieces, nodes) = cloud(20);
        let good = bytes(&p, &pieces, &nodes, 3);
        let mut s = std::boxed::Box::new(WireSurface::<32>::new());
        let mut rng = crate::rng::Rng::new(11);
        for cut in 0..good.len() {
            let _ = decode::<4, 32, 32, JOINTS>(&good[..cut], &mut s);
        }
        for _ in 0..20_000 {
            let mut b = good.clone();
            for _ in 0..3 {
                let i = (rng.next_u64() % b.len() as u64) as usize;
                b[i] = rng.next_u64() as u8;
            }
            if decode::<4, 32, 32, JOINTS>(&b, &mut s).is_ok_and(|q| q.to_scene_with(&s).is_ok()) {
                assert!(s.surface().is_ok());
            }
        }
    }
}
