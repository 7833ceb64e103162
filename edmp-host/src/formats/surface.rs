//! The `points` and `mesh` obstacles of `edmp-scene/1` (docs/formats.md, "Point clouds and
//! meshes"): read inline or from files beside the scene, placed in the world, the robot's own
//! points dropped, a cloud reduced when it exceeds the capacity, and built into the buffers a
//! core [`Surface`] borrows.

use super::fields::{InputError, field, number, numbers, object, quaternion};
use super::file_error::FileError;
use super::{cloud, mesh_file};
use edmp_core::collision::checker::moves;
use edmp_core::collision::filter::filter_robot;
use edmp_core::cost::cover::covers;
use edmp_core::robot::Robot;
use edmp_core::robot::kinematics::Joints;
use edmp_core::scene::{Obstacle, rotation_from_wxyz};
use edmp_core::surface::Surface;
use edmp_core::surface::bvh::{Key, Node, bound_on, nodes_for, split_on};
use edmp_core::surface::element::{Element, Piece, SurfaceError};
use edmp_core::surface::points::{Reduced, reduce};
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use serde_json::Value;
use std::path::Path;

/// The most pieces (cloud balls and mesh triangles, all obstacles together) the host holds:
/// a 640 × 480 camera's 307,200 points are reduced to fit; a 200,000-point cloud is kept whole.
pub const MAX_PIECES: usize = 1 << 18;

/// The most boxes the guides get around a scene's clouds and meshes (fewer when the scene's
/// obstacle capacity runs out first).
pub const SURFACE_BOXES: usize = 24;

/// A cloud or a mesh as the scene gives it, in the world frame.
#[derive(Clone, Debug, PartialEq)]
pub enum SurfaceKind {
    /// Balls of `radius` around the points (after `filter_robot`, before any reduction).
    Points {
        /// The points, in the world.
        points: Vec<[f32; 3]>,
        /// The ball radius.
        radius: f32,
        /// The robot's own points were those within this distance of it at `start`.
        filter_robot: Option<f32>,
    },
    /// Triangles (degenerate ones included: the core ignores them).
    Mesh {
        /// Vertices, in the world.
        vertices: Vec<[f32; 3]>,
        /// Vertex indices, checked to be in range.
        triangles: Vec<[u32; 3]>,
    },
}

/// A `points` or `mesh` obstacle and its index in the scene's `obstacles`.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceObstacle {
    /// Index in `obstacles`.
    pub index: usize,
    /// The geometry.
    pub kind: SurfaceKind,
}

/// Every cloud and mesh of a scene, and the core's pieces and tree over them.
#[derive(Clone, Debug, Default)]
pub struct Surfaces {
    /// The obstacles as read (clouds filtered, not reduced).
    pub obstacles: Vec<SurfaceObstacle>,
    /// How many cloud points `filter_robot` dropped, all clouds together.
    pub points_filtered: usize,
    /// Per reduced cloud (its obstacle index), how it was reduced.
    pub reduced: Vec<(usize, Reduced)>,
    /// The boxes the guides see around the pieces ([`covers`]).
    pub boxes: Vec<Obstacle>,
    /// Per obstacle, whether it is a closed mesh ([`is_closed`]), found once for both ends.
    closed: Vec<bool>,
    pieces: Vec<Element>,
    nodes: Vec<Node>,
}

impl Surfaces {
    /// The view the core's scene borrows.
    pub fn surface(&self) -> Surface<'_> {
        // Built by `bvh::build` over exactly these pieces (`build_surfaces` checked it once with
        // `Surface::new`), and private: no need to walk them again on every call.
        Surface::from_built(&self.pieces, &self.nodes)
    }

    /// Pieces held (balls and non-degenerate triangles).
    pub fn pieces(&self) -> usize {
        self.pieces.len()
    }
}

/// Whether an obstacle's `type` is one of these.
pub fn is_surface(v: &Value) -> bool {
    matches!(v.get("type").and_then(Value::as_str), Some("points" | "mesh"))
}

/// Where a cloud's or a mesh's own frame stands: world = centre + rotation · (scale ⊙ local).
struct Placement {
    center: Vector3<f32>,
    rotation: Matrix3<f32>,
    scale: Vector3<f32>,
}

fn placement(map: &serde_json::Map<String, Value>, path: &str, scaled: bool) -> Result<Placement, InputError> {
    let center = match map.get("center") {
        Some(c) => Vector3::from(numbers::<3>(c, &format!("{path}.center"))?),
        None => Vector3::zeros(),
    };
    let rotation = match map.get("quaternion") {
        Some(q) => {
            let qp = format!("{path}.quaternion");
            rotation_from_wxyz(quaternion(q, &qp)?).map_err(|e| InputError::at(&qp, e.to_string()))?
        }
        None => Matrix3::identity(),
    };
    let scale = match map.get("scale").filter(|_| scaled) {
        None => Vector3::repeat(1.0),
        Some(s) => {
            let sp = format!("{path}.scale");
            let v = if s.is_number() {
                Vector3::repeat(number(s, &sp)?)
            } else {
                Vector3::from(numbers::<3>(s, &sp)?)
            };
            if v.iter().any(|&x| x <= 0.0) {
                return Err(InputError::at(&sp, "must be positive"));
            }
            v
        }
    };
    Ok(Placement {
        center,
        rotation,
        scale,
    })
}

fn place(points: &mut [[f32; 3]], at: Placement, path: &str) -> Result<(), InputError> {
    for p in points.iter_mut() {
        let w = at.center + at.rotation * Vector3::from(*p).component_mul(&at.scale);
        if w.iter().any(|x| !x.is_finite()) {
            return Err(InputError::at(path, "a placed coordinate is not a finite f32"));
        }
        *p = w.into();
    }
    Ok(())
}

fn file_error(path: &str, e: FileError) -> InputError {
    InputError::at(&format!("{path}.file"), e.to_string())
}

fn inline_points(v: &Value, path: &str) -> Result<Vec<[f32; 3]>, InputError> {
    let items = v
        .as_array()
        .ok_or_else(|| InputError::at(path, "expected an array of [x, y, z]"))?;
    items
        .iter()
        .enumerate()
        .map(|(i, p)| numbers::<3>(p, &format!("{path}[{i}]")))
        .collect()
}

/// A `points` or `mesh` obstacle at `path` (index `index` of `obstacles`), files read
/// relative to `dir`, placed in the world.
pub fn read_obstacle(v: &Value, path: &str, index: usize, dir: &Path) -> Result<SurfaceObstacle, InputError> {
    let kind = match v.get("type").and_then(Value::as_str) {
        Some("points") => {
            let map = object(
                v,
                path,
                &[
                    "type",
                    "points",
                    "file",
                    "radius",
                    "filter_robot",
                    "center",
                    "quaternion",
                ],
            )?;
            let mut points = match (map.get("points"), map.get("file")) {
                (Some(p), None) => inline_points(p, &format!("{path}.points"))?,
                (None, Some(f)) => {
                    let fp = format!("{path}.file");
                    let name = f.as_str().ok_or_else(|| InputError::at(&fp, "expected a file path"))?;
                    cloud::read_points(&dir.join(name)).map_err(|e| file_error(path, e))?
                }
                _ => return Err(InputError::at(path, "expected exactly one of \"points\" or \"file\"")),
            };
            let (r, rp) = field(map, path, "radius")?;
            let radius = number(r, &rp)?;
            if radius <= 0.0 {
                return Err(InputError::at(&rp, "must be positive"));
            }
            let filter_robot = match map.get("filter_robot") {
                Some(d) => {
                    let dp = format!("{path}.filter_robot");
                    let d = number(d, &dp)?;
                    if d < 0.0 {
                        return Err(InputError::at(&dp, "must not be negative"));
                    }
                    Some(d)
                }
                None => None,
            };
            place(&mut points, placement(map, path, false)?, path)?;
            SurfaceKind::Points {
                points,
                radius,
                filter_robot,
            }
        }
        Some("mesh") => {
            let map = object(
                v,
                path,
                &["type", "file", "vertices", "triangles", "center", "quaternion", "scale"],
            )?;
            let mut mesh = match (map.get("file"), map.get("vertices"), map.get("triangles")) {
                (Some(f), None, None) => {
                    let fp = format!("{path}.file");
                    let name = f.as_str().ok_or_else(|| InputError::at(&fp, "expected a file path"))?;
                    mesh_file::read_mesh(&dir.join(name)).map_err(|e| file_error(path, e))?
                }
                (None, Some(v), Some(t)) => {
                    let vertices = inline_points(v, &format!("{path}.vertices"))?;
                    let tp = format!("{path}.triangles");
                    let items = t
                        .as_array()
                        .ok_or_else(|| InputError::at(&tp, "expected an array of [i, j, k]"))?;
                    let mut triangles = Vec::with_capacity(items.len());
                    for (i, tri) in items.iter().enumerate() {
                        let ip = format!("{tp}[{i}]");
                        let ks = tri
                            .as_array()
                            .filter(|a| a.len() == 3)
                            .ok_or_else(|| InputError::at(&ip, "expected 3 vertex indices"))?;
                        let mut out = [0u32; 3];
                        for (k, (slot, x)) in out.iter_mut().zip(ks).enumerate() {
                            *slot = x.as_u64().filter(|&n| (n as usize) < vertices.len()).ok_or_else(|| {
                                InputError::at(
                                    &format!("{ip}[{k}]"),
                                    format!("expected a vertex index below {}, found {x}", vertices.len()),
                                )
                            })? as u32;
                        }
                        triangles.push(out);
                    }
                    mesh_file::TriangleMesh { vertices, triangles }
                }
                _ => {
                    return Err(InputError::at(
                        path,
                        "expected either \"file\" or both \"vertices\" and \"triangles\"",
                    ));
                }
            };
            place(&mut mesh.vertices, placement(map, path, true)?, path)?;
            SurfaceKind::Mesh {
                vertices: mesh.vertices,
                triangles: mesh.triangles,
            }
        }
        _ => {
            return Err(InputError::at(
                &format!("{path}.type"),
                "expected \"points\" or \"mesh\"",
            ));
        }
    };
    Ok(SurfaceObstacle { index, kind })
}

fn surface_error(e: SurfaceError, path: &str) -> InputError {
    InputError::at(path, e.to_string())
}

/// Where a surface's pieces come from, in the order they are numbered for the tree: a
/// cloud's points (kept or reduced) with their ball radius, or a mesh's valid triangles.
enum Source<'a> {
    Balls {
        points: &'a [[f32; 3]],
        radius: f32,
        tag: u16,
    },
    Pieces(&'a [Element]),
}

/// What [`build_surfaces`] holds of one obstacle before the tree: a cloud's radius (its points
/// kept as read) or its reduced copy, or a mesh's valid triangles.
enum Held {
    Kept(f32),
    Reduced(Vec<[f32; 3]>, f32),
    Mesh(Vec<Element>),
}

impl Source<'_> {
    fn len(&self) -> usize {
        match self {
            Source::Balls { points, .. } => points.len(),
            Source::Pieces(pieces) => pieces.len(),
        }
    }

    fn centroid(&self, i: usize) -> [f32; 3] {
        match self {
            Source::Balls { points, .. } => points.get(i).copied().unwrap_or_default(),
            Source::Pieces(pieces) => pieces.get(i).map_or([0.0; 3], |e| e.centroid().into()),
        }
    }

    /// The piece of `key`, numbered `i` in this source: a ball is made from the key's centroid
    /// (its point), so the points are not read again in the tree's (random) order.
    fn piece(&self, key: &Key, i: usize) -> Option<Result<Element, SurfaceError>> {
        match self {
            Source::Balls { radius, tag, .. } => Some(Element::ball(key.centroid(), *radius, *tag)),
            Source::Pieces(pieces) => pieces.get(i).map(|e| Ok(*e)),
        }
    }
}

/// Drops each cloud's points on `robot` at `start` (fingers at `finger`), reduces clouds beyond
/// the capacity left by the meshes, and builds the pieces and their tree. A cloud's balls are
/// made once, straight into the tree's order (no copy of 200,000 pieces to sort).
pub fn build_surfaces<const J: usize>(
    mut obstacles: Vec<SurfaceObstacle>,
    robot: &'static Robot<f32, J>,
    start: &Joints<f32, J>,
    finger: f32,
) -> Result<Surfaces, InputError> {
    let mut points_filtered = 0;
    let triangles: usize = obstacles
        .iter()
        .map(|o| match &o.kind {
            SurfaceKind::Mesh { triangles, .. } => triangles.len(),
            SurfaceKind::Points { .. } => 0,
        })
        .sum();
    if triangles > MAX_PIECES {
        return Err(InputError::at(
            "obstacles",
            format!("{triangles} mesh triangles, at most {MAX_PIECES}"),
        ));
    }
    let mut clouds_left = obstacles
        .iter()
        .filter(|o| matches!(o.kind, SurfaceKind::Points { .. }))
        .count();
    let mut room = MAX_PIECES - triangles;
    let mut reduced = Vec::new();
    // Per obstacle, what its pieces are made from (`Held`).
    let mut held = Vec::with_capacity(obstacles.len());
    for o in obstacles.iter_mut() {
        let path = format!("obstacles[{}]", o.index);
        let tag = u16::try_from(o.index).map_err(|_| InputError::at(&path, "obstacle index beyond 65535"))?;
        match &mut o.kind {
            SurfaceKind::Points {
                points,
                radius,
                filter_robot: filter,
            } => {
                if let Some(d) = *filter {
                    let kept = filter_robot(robot, points, start, finger, d)
                        .map_err(|e| InputError::at(&format!("{path}.filter_robot"), e.to_string()))?;
                    points_filtered += points.len() - kept;
                    points.truncate(kept);
                }
                let share = room / clouds_left.max(1);
                if points.len() > share {
                    let mut copy = points.clone();
                    let r = reduce(&mut copy, *radius, share).map_err(|e| surface_error(e, &path))?;
                    copy.truncate(r.points);
                    reduced.push((o.index, r));
                    room -= r.points;
                    held.push(Held::Reduced(copy, r.radius));
                } else {
                    let r = reduce(points, *radius, share).map_err(|e| surface_error(e, &path))?;
                    room -= r.points;
                    held.push(Held::Kept(r.radius));
                }
                clouds_left -= 1;
            }
            SurfaceKind::Mesh { vertices, triangles } => {
                let mut pieces = Vec::with_capacity(triangles.len());
                for t in triangles.iter() {
                    let corner = |i: u32| {
                        vertices
                            .get(i as usize)
                            .copied()
                            .ok_or_else(|| InputError::at(&path, format!("vertex index {i} out of range")))
                    };
                    let corners = [corner(t[0])?, corner(t[1])?, corner(t[2])?];
                    if let Some(e) = Element::triangle(corners, tag).map_err(|e| surface_error(e, &path))? {
                        pieces.push(e);
                    }
                }
                held.push(Held::Mesh(pieces));
            }
        }
    }
    let mut sources = Vec::with_capacity(obstacles.len());
    for (o, held) in obstacles.iter().zip(&held) {
        // The tags fitted in a u16 above.
        let tag = o.index as u16;
        sources.push(match (held, &o.kind) {
            (Held::Reduced(points, radius), _) => Source::Balls {
                points,
                radius: *radius,
                tag,
            },
            (Held::Kept(radius), SurfaceKind::Points { points, .. }) => Source::Balls {
                points,
                radius: *radius,
                tag,
            },
            (Held::Mesh(pieces), _) => Source::Pieces(pieces),
            (Held::Kept(_), SurfaceKind::Mesh { .. }) => Source::Pieces(&[]),
        });
    }
    let (pieces, nodes) = if sources.iter().all(|s| s.len() == 0) {
        (Vec::new(), Vec::new())
    } else {
        // The process's pool of two threads, whatever the planner's `--threads` (the one
        // `--threads 2` plans on): reading a large cloud is mostly this tree.
        let threads = crate::threads::Threads::new(2).map_err(|e| InputError::at("obstacles", e))?;
        threads.install(|| tree(&threads, &sources, &obstacles))?
    };
    drop(sources);
    drop(held);
    let closed = obstacles
        .iter()
        .map(|o| match &o.kind {
            SurfaceKind::Mesh { vertices, triangles } => is_closed(vertices, triangles),
            SurfaceKind::Points { .. } => false,
        })
        .collect();
    let mut surfaces = Surfaces {
        closed,
        obstacles,
        points_filtered,
        reduced,
        boxes: Vec::new(),
        pieces,
        nodes,
    };
    // `bvh::split` makes valid trees; the walk that proves it is for trees from a wire.
    debug_assert!(Surface::new(&surfaces.pieces, &surfaces.nodes).is_ok());
    let mut boxes = [Obstacle::PLACEHOLDER; SURFACE_BOXES];
    let made = covers(&surfaces.surface(), &mut boxes);
    surfaces.boxes = boxes[..made].to_vec();
    Ok(surfaces)
}

/// The pieces of `sources` (one per obstacle of `obstacles`) in the tree's order, and the tree,
/// made on `threads` (inside its pool): the keys, [`split_on`], the pieces made from the keys,
/// [`bound_on`]. The same buffers, bit for bit, as on one thread.
fn tree(
    threads: &crate::threads::Threads,
    sources: &[Source<'_>],
    obstacles: &[SurfaceObstacle],
) -> Result<(Vec<Element>, Vec<Node>), InputError> {
    // Keys numbered across the sources; pieces then made in the keys' order.
    let mut firsts = Vec::with_capacity(sources.len());
    let mut keys = Vec::with_capacity(sources.iter().map(Source::len).sum());
    for source in sources {
        let first = keys.len();
        firsts.push(first);
        keys.par_extend(
            (0..source.len())
                .into_par_iter()
                .map(|i| Key::new(source.centroid(i), (first + i) as u32)),
        );
    }
    let mut nodes = vec![Node::EMPTY; nodes_for(keys.len())];
    let used = if keys.is_empty() {
        0
    } else {
        split_on(threads, &mut keys, &mut nodes).map_err(|e| surface_error(e, "obstacles"))?
    };
    nodes.truncate(used);
    // Made on the pool's threads, in the keys' order. A piece that cannot be made (the sources
    // were validated: none in practice) stands as its key's ball meanwhile; the first such in
    // key order is the error.
    let failed = std::sync::Mutex::new(None::<(u32, usize, SurfaceError)>);
    let mut pieces = Vec::with_capacity(keys.len());
    keys.par_iter()
        .map(|key| {
            let n = key.piece() as usize;
            let s = firsts.partition_point(|&f| f <= n).saturating_sub(1);
            let made = match (sources.get(s), firsts.get(s)) {
                (Some(source), Some(first)) => source.piece(key, n - first),
                _ => None,
            };
            match made.unwrap_or(Err(SurfaceError::TooManyPieces)) {
                Ok(piece) => piece,
                Err(e) => {
                    if let Ok(mut first) = failed.lock()
                        && first.is_none_or(|(k, ..)| key.piece() < k)
                    {
                        *first = Some((key.piece(), s, e));
                    }
                    Element {
                        piece: Piece::Ball {
                            center: key.centroid().into(),
                            radius: 1.0,
                        },
                        obstacle: 0,
                    }
                }
            }
        })
        .collect_into_vec(&mut pieces);
    if let Some((_, s, e)) = failed.into_inner().ok().flatten() {
        let index = obstacles.get(s).map_or(0, |o| o.index);
        return Err(surface_error(e, &format!("obstacles[{index}]")));
    }
    drop(keys);
    bound_on(threads, &pieces, &mut nodes);
    Ok((pieces, nodes))
}

/// Whether a mesh is closed: every edge is shared by exactly two of its (non-degenerate)
/// triangles. A closed mesh's inside is part of the obstacle (docs/formats.md).
pub fn is_closed(vertices: &[[f32; 3]], triangles: &[[u32; 3]]) -> bool {
    let mut edges = Vec::with_capacity(3 * triangles.len());
    for t in triangles {
        let corner = |i: u32| vertices.get(i as usize).map(|v| Vector3::from(*v));
        let (Some(a), Some(b), Some(c)) = (corner(t[0]), corner(t[1]), corner(t[2])) else {
            return false;
        };
        if (b - a).cross(&(c - a)).norm_squared() <= 1e-20 {
            continue;
        }
        for (i, j) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            edges.push((i.min(j), i.max(j)));
        }
    }
    // Sorted, every edge must come exactly twice.
    edges.sort_unstable();
    !edges.is_empty() && edges.chunk_by(|a, b| a == b).all(|run| run.len() == 2)
}

/// Whether `p` lies inside a closed mesh: the parity of the mesh's triangles a ray from `p`
/// crosses (a direction no axis-aligned face is parallel to).
pub fn encloses(vertices: &[[f32; 3]], triangles: &[[u32; 3]], p: &Vector3<f32>) -> bool {
    first_enclosed(vertices, triangles, core::slice::from_ref(p)).is_some()
}

/// The first of `points` inside a closed mesh ([`encloses`] for each, in one pass over the
/// triangles: a triangle's edges and the ray's terms that do not depend on the point are
/// computed once; points outside the mesh's box are never inside).
pub fn first_enclosed(vertices: &[[f32; 3]], triangles: &[[u32; 3]], points: &[Vector3<f32>]) -> Option<usize> {
    let (lo, hi) = vertices
        .iter()
        .fold(([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]), |(lo, hi), v| {
            (
                core::array::from_fn(|k| lo[k].min(v[k])),
                core::array::from_fn(|k| hi[k].max(v[k])),
            )
        });
    let candidates: Vec<usize> = (0..points.len())
        .filter(|&i| (0..3).all(|k| points[i][k] >= lo[k] && points[i][k] <= hi[k]))
        .collect();
    if candidates.is_empty() {
        return None;
    }
    let d = Vector3::new(0.577_215_7, 0.313_717_4, 0.759_397_5).normalize();
    let mut crossings = vec![0u32; candidates.len()];
    for t in triangles {
        let corner = |i: u32| vertices.get(i as usize).map(|v| Vector3::from(*v));
        let (Some(a), Some(b), Some(c)) = (corner(t[0]), corner(t[1]), corner(t[2])) else {
            continue;
        };
        // Möller-Trumbore.
        let (e1, e2) = (b - a, c - a);
        let h = d.cross(&e2);
        let det = e1.dot(&h);
        if det.abs() < 1e-12 {
            continue;
        }
        for (n, &i) in crossings.iter_mut().zip(&candidates) {
            let s = points[i] - a;
            let u = s.dot(&h) / det;
            if !(0.0..=1.0).contains(&u) {
                continue;
            }
            let q = s.cross(&e1);
            let v = d.dot(&q) / det;
            let t = e2.dot(&q) / det;
            if v >= 0.0 && u + v <= 1.0 && t > 0.0 {
                *n += 1;
            }
        }
    }
    crossings
        .iter()
        .zip(&candidates)
        .find(|(n, _)| *n % 2 == 1)
        .map(|(_, &i)| i)
}

/// The first body of `robot` (by name) whose box centre lies inside a closed mesh at `q`, and
/// that mesh's obstacle index: an end there touches no triangle yet is inside the obstacle.
pub fn inside_closed_mesh<const J: usize>(
    robot: &'static Robot<f32, J>,
    surfaces: &Surfaces,
    q: &Joints<f32, J>,
    finger: f32,
) -> Option<(&'static str, usize)> {
    let k = edmp_core::robot::kinematics::forward_with(robot, q, robot.finger_opening(finger)).ok()?;
    let bodies: Vec<(Vector3<f32>, &'static str)> = k
        .boxes
        .iter()
        .zip(robot.body_names)
        .enumerate()
        .filter(|&(b, _)| moves(robot, b))
        .map(|(_, (pose, name))| (pose.translation, *name))
        .collect();
    let centres: Vec<Vector3<f32>> = bodies.iter().map(|(c, _)| *c).collect();
    for (o, &closed) in surfaces.obstacles.iter().zip(&surfaces.closed) {
        let SurfaceKind::Mesh { vertices, triangles } = &o.kind else {
            continue;
        };
        if !closed {
            continue;
        }
        if let Some(i) = first_enclosed(vertices, triangles, &centres) {
            return bodies.get(i).map(|(_, name)| (*name, o.index));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use edmp_core::surface::element::Piece;

    /// The unit cube's 12 triangles, outward.
    fn cube() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let vertices = (0..8u32)
            .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
            .collect();
        let faces = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = faces.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect();
        (vertices, triangles)
    }

    #[test]
    fn a_cube_is_closed_and_holds_its_inside_an_open_one_does_not() {
        let (vertices, mut triangles) = cube();
        assert!(is_closed(&vertices, &triangles));
        let points = [
            Vector3::new(2.0, 0.5, 0.5),
            Vector3::new(0.5, 0.5, 1.5),
            Vector3::new(0.3, 0.6, 0.2),
        ];
        assert_eq!(first_enclosed(&vertices, &triangles, &points), Some(2));
        assert!(encloses(&vertices, &triangles, &Vector3::new(0.9, 0.1, 0.5)));
        assert!(!encloses(&vertices, &triangles, &Vector3::new(1.1, 0.5, 0.5)));
        // A third triangle on an edge, or a missing one, opens it.
        triangles.push([0, 2, 7]);
        assert!(!is_closed(&vertices, &triangles));
        triangles.truncate(11);
        assert!(!is_closed(&vertices, &triangles));
        // A degenerate triangle is ignored, an index out of range is not a closed mesh.
        let (vertices, mut triangles) = cube();
        triangles.push([0, 0, 1]);
        assert!(is_closed(&vertices, &triangles));
        triangles.push([0, 1, 8]);
        assert!(!is_closed(&vertices, &triangles));
    }

    #[test]
    fn a_cloud_beyond_the_capacity_is_reduced_to_cover_it_and_a_mesh_beside_it_is_kept() {
        // 300,304 points 2 mm apart on a wall at x = 0.6, and one triangle.
        let side = 548;
        let points: Vec<[f32; 3]> = (0..side * side)
            .map(|i| [0.6, (i % side) as f32 * 0.002 - 0.5, (i / side) as f32 * 0.002])
            .collect();
        let cloud = SurfaceObstacle {
            index: 0,
            kind: SurfaceKind::Points {
                points: points.clone(),
                radius: 0.0075,
                filter_robot: None,
            },
        };
        let mesh = SurfaceObstacle {
            index: 1,
            kind: SurfaceKind::Mesh {
                vertices: vec![[0.3, -0.5, 0.0], [0.3, 0.5, 0.0], [0.3, 0.0, 1.0]],
                triangles: vec![[0, 1, 2]],
            },
        };
        let s = build_surfaces(vec![cloud, mesh], &edmp_core::robot::PANDA, &[0.0; 7], 0.025).unwrap();
        assert!(s.pieces() <= MAX_PIECES && s.pieces() > 1);
        assert!(Surface::new(&s.pieces, &s.nodes).is_ok());
        let [(0, r)] = s.reduced[..] else {
            panic!("{:?}", s.reduced)
        };
        assert!(r.cell > 0.0 && r.radius > 0.0075);
        let mut balls = Vec::new();
        let mut triangles = 0;
        for e in &s.pieces {
            match e.piece {
                Piece::Ball { center, radius } => balls.push((center, radius, e.obstacle)),
                Piece::Triangle { .. } => triangles += usize::from(e.obstacle == 1),
            }
        }
        assert_eq!(triangles, 1);
        // Every input ball (a sample) lies inside a reduced ball of the cloud.
        for p in points.iter().step_by(997) {
            let p = Vector3::from(*p);
            assert!(
                balls
                    .iter()
                    .any(|(c, radius, o)| *o == 0 && (c - p).norm() + 0.0075 <= radius + 1e-6),
                "{p:?} not covered"
            );
        }
        // The obstacle keeps its points as read.
        let SurfaceKind::Points { points: kept, .. } = &s.obstacles[0].kind else {
            panic!()
        };
        assert_eq!(kept.len(), side * side);
    }
}
