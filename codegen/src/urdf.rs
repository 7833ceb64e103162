//! The kinematic chain read from an arm's URDF: frames in parent-before-child order, the
//! actuated joints with both limit sets, one collision body per convex piece of each link's
//! collision meshes, and the self-collision pairs by the arm's rule.
//!
//! Body names: the link's name when the link has one piece (every Panda and iiwa link: one
//! mesh, one hull), `LINK#k` for piece `k` (from 0, in file order) when it has several (the
//! xArm's V-HACD pieces).

use crate::arms::{ArmSpec, LimitSource, PairRule};
use crate::hull_distance::hull_distance;
use crate::math::{self, Mat3, Vec3};
use crate::mesh::{self, OrientedBox};
use std::path::{Path, PathBuf};

/// Default opening of each Panda finger: the MpiNets / robofin convention that
/// docs/formats.md makes the value of an absent `gripper` field. The opening itself is
/// an input (the scene's `gripper.finger`), not folded into the tables.
pub const FINGER_OPENING: f64 = 0.025;

/// How a frame moves relative to its parent.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    /// Rigidly attached (fixed joints).
    Fixed,
    /// A finger on a prismatic joint: it slides by `slide · w` from its origin, `w` being the
    /// gripper opening (the driving finger joint's value; a `<mimic>` joint follows it).
    Finger {
        /// Unit joint axis in the child frame, as the URDF gives it.
        axis: Vec3,
        /// `R_origin · axis · multiplier`: the frame's displacement per metre of opening, in
        /// the parent frame.
        slide: Vec3,
    },
    /// Turns about `axis` (in its own frame) by the actuated joint `joint`.
    Revolute {
        /// Index among the actuated joints, in chain order.
        joint: usize,
        /// Unit axis in the child frame.
        axis: Vec3,
    },
}

/// One link frame of the chain.
#[derive(Clone, Debug)]
pub struct Frame {
    /// URDF link name.
    pub name: String,
    /// Index of the parent frame; the root is its own parent.
    pub parent: usize,
    /// Rotation of the joint origin relative to the parent frame.
    pub origin_rotation: Mat3,
    /// Translation of the joint origin relative to the parent frame (for a finger: at opening
    /// 0, a mimic joint's offset folded in).
    pub origin_translation: Vec3,
    /// How the frame moves.
    pub motion: Motion,
    /// Where the numbers come from, for the generated comment.
    pub provenance: String,
}

/// Limits of one actuated joint.
#[derive(Clone, Debug)]
pub struct JointLimits {
    /// URDF joint name.
    pub name: String,
    /// `<limit lower upper>`: the hardware range.
    pub hard: [f64; 2],
    /// The planning range: `<safety_controller soft_lower_limit soft_upper_limit>` (Franka's
    /// official range) or `<limit>` again, as the arm's [`LimitSource`] says.
    pub soft: [f64; 2],
}

/// A collision body: one convex piece of a mesh rigidly attached to a frame, and its boxes.
#[derive(Clone, Debug)]
pub struct Body {
    /// URDF link name, with `#k` for piece `k` of a link with several (module docs).
    pub name: String,
    /// Index of the frame the box is expressed in.
    pub frame: usize,
    /// Mesh file, relative to the URDF's folder (and which piece, if it has several).
    pub mesh: String,
    /// Number of mesh vertices the boxes were fitted to.
    pub vertex_count: usize,
    /// The tight oriented box in the link frame.
    pub tight: OrientedBox,
    /// The link-frame axis-aligned box (what the original EDMP uses), for comparison.
    pub aabb: OrientedBox,
    /// The mesh vertices that are vertices of its convex hull, in the link frame, in file
    /// order: their hull is the body's exact collision geometry (PyBullet collides the same hull).
    pub points: Vec<Vec3>,
}

/// The gripper: one driving prismatic joint whose value is the opening.
#[derive(Clone, Debug)]
pub struct Gripper {
    /// The driving finger joint (the one the others `<mimic>`).
    pub joint: String,
    /// Its `<limit lower upper>`: the range of the opening.
    pub limits: [f64; 2],
}

/// Everything the generator knows of the robot.
#[derive(Clone, Debug)]
pub struct Chain {
    /// The arm this chain was read for.
    pub arm: ArmSpec,
    /// Frames, parents first.
    pub frames: Vec<Frame>,
    /// Actuated joints, in chain order.
    pub joints: Vec<JointLimits>,
    /// Collision bodies, in frame order.
    pub bodies: Vec<Body>,
    /// Index of the TCP frame.
    pub tcp: usize,
    /// Index of the frame a held object attaches to.
    pub hand: usize,
    /// The gripper, for arms with one.
    pub gripper: Option<Gripper>,
    /// Body index pairs `(a, b)`, `a < b`, checked against each other, by the arm's rule.
    pub self_pairs: Vec<(usize, usize)>,
    /// Every file that was read (for `cargo:rerun-if-changed`).
    pub inputs: Vec<PathBuf>,
}

/// Reads the URDF at `path` and the collision meshes it names, for the arm `arm`.
pub fn read_chain(path: &Path, arm: &ArmSpec) -> Result<Chain, String> {
    let robot = urdf_rs::read_file(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let root_dir = path.parent().unwrap_or(Path::new("."));
    let mut inputs = vec![path.to_path_buf()];

    let is_child = |name: &str| robot.joints.iter().any(|j| j.child.link == name);
    let roots: Vec<_> = robot.links.iter().filter(|l| !is_child(&l.name)).collect();
    let [root] = roots.as_slice() else {
        return Err(format!("expected one root link, found {}", roots.len()));
    };

    let mut frames = vec![Frame {
        name: root.name.clone(),
        parent: 0,
        origin_rotation: math::IDENTITY,
        origin_translation: [0.0; 3],
        motion: Motion::Fixed,
        provenance: format!("root link `{}`: the world frame", root.name),
    }];
    let mut joints = Vec::new();
    // Prismatic joints that drive themselves (name, limits), and every prismatic joint with
    // the joint it follows.
    let mut fingers: Vec<(String, [f64; 2])> = Vec::new();
    let mut drivers: Vec<(String, String)> = Vec::new();
    // Breadth-first in declaration order, so every parent precedes its children.
    let mut next = 0;
    while next < frames.len() {
        let parent_name = frames[next].name.clone();
        for joint in robot.joints.iter().filter(|j| j.parent.link == parent_name) {
            let origin_rotation = math::rpy_to_matrix(&joint.origin.rpy);
            let mut origin_translation = *joint.origin.xyz;
            let xyz = *joint.origin.xyz;
            let rpy = *joint.origin.rpy;
            let (motion, provenance) = match joint.joint_type {
                urdf_rs::JointType::Revolute => {
                    let axis = normalised(&joint.axis.xyz, &joint.name)?;
                    let hard = [joint.limit.lower, joint.limit.upper];
                    let soft = match arm.limits {
                        LimitSource::Limit => hard,
                        LimitSource::SafetyController => {
                            let safety = joint
                                .safety_controller
                                .as_ref()
                                .ok_or(format!("joint `{}` has no <safety_controller> soft limits", joint.name))?;
                            [safety.soft_lower_limit, safety.soft_upper_limit]
                        }
                    };
                    joints.push(JointLimits {
                        name: joint.name.clone(),
                        hard,
                        soft,
                    });
                    let motion = Motion::Revolute {
                        joint: joints.len() - 1,
                        axis,
                    };
                    (
                        motion,
                        format!(
                            "revolute `{}`: origin xyz={xyz:?} rpy={rpy:?}, axis {axis:?}",
                            joint.name
                        ),
                    )
                }
                urdf_rs::JointType::Fixed => (
                    Motion::Fixed,
                    format!("fixed `{}`: origin xyz={xyz:?} rpy={rpy:?}", joint.name),
                ),
                urdf_rs::JointType::Prismatic => {
                    let axis = normalised(&joint.axis.xyz, &joint.name)?;
                    // Opening w: this joint's value is `multiplier · w + offset` (1 and 0 for
                    // the driving joint). The offset is folded into the origin; the frame then
                    // moves by R_origin · axis · multiplier per metre of w.
                    let (multiplier, offset, driver) = match &joint.mimic {
                        Some(m) => (m.multiplier.unwrap_or(1.0), m.offset.unwrap_or(0.0), m.joint.clone()),
                        None => {
                            fingers.push((joint.name.clone(), [joint.limit.lower, joint.limit.upper]));
                            (1.0, 0.0, joint.name.clone())
                        }
                    };
                    drivers.push((joint.name.clone(), driver.clone()));
                    let direction = math::mul_vec(&origin_rotation, &axis);
                    for (o, d) in origin_translation.iter_mut().zip(direction) {
                        *o += d * offset;
                    }
                    let slide = direction.map(|d| d * multiplier);
                    let provenance = if driver == joint.name {
                        format!(
                            "prismatic `{}`, the gripper opening w, axis {axis:?}: origin xyz={xyz:?} rpy={rpy:?}, \
                             slides by w along R_origin·axis",
                            joint.name
                        )
                    } else {
                        format!(
                            "prismatic `{}`, mimics `{driver}` (multiplier {multiplier}, offset {offset}), axis {axis:?}: \
                             origin xyz={xyz:?} rpy={rpy:?}, slides by w along R_origin·axis·multiplier",
                            joint.name
                        )
                    };
                    (Motion::Finger { axis, slide }, provenance)
                }
                ref other => return Err(format!("joint `{}`: unsupported type {other:?}", joint.name)),
            };
            frames.push(Frame {
                name: joint.child.link.clone(),
                parent: next,
                origin_rotation,
                origin_translation,
                motion,
                provenance,
            });
        }
        next += 1;
    }
    if frames.len() != robot.links.len() {
        return Err(format!(
            "{} links but {} reachable from the root",
            robot.links.len(),
            frames.len()
        ));
    }

    // One opening for the whole gripper: one driving finger joint, every other one mimics it.
    let gripper = match fingers.as_slice() {
        [] if !arm.gripper => None,
        [] => return Err("no prismatic finger joint: the gripper opening has nothing to drive".to_owned()),
        [(name, _)] if !arm.gripper => {
            return Err(format!("prismatic `{name}`: arm `{}` has no gripper", arm.name));
        }
        [(name, limits)] => {
            if let Some((follower, driver)) = drivers.iter().find(|(_, d)| d != name) {
                return Err(format!(
                    "prismatic `{follower}` follows `{driver}`, not the gripper's driving joint `{name}`"
                ));
            }
            if !(limits[0].is_finite() && limits[1].is_finite() && limits[0] <= limits[1]) {
                return Err(format!("prismatic `{name}`: limits {limits:?} are not a range"));
            }
            if !(limits[0] <= FINGER_OPENING && FINGER_OPENING <= limits[1]) {
                return Err(format!(
                    "the default finger opening {FINGER_OPENING} m is outside the URDF's limits {limits:?}"
                ));
            }
            Some(Gripper {
                joint: name.clone(),
                limits: *limits,
            })
        }
        more => {
            let names: Vec<_> = more.iter().map(|(n, _)| n.as_str()).collect();
            return Err(format!(
                "prismatic joints {names:?} each drive themselves: one opening needs one driver (the others <mimic> it)"
            ));
        }
    };

    let mut bodies = Vec::new();
    for (index, frame) in frames.iter().enumerate() {
        let link = robot
            .links
            .iter()
            .find(|l| l.name == frame.name)
            .ok_or("link vanished")?;
        // Each convex piece of each collision mesh, in the link frame, named by its file.
        let mut pieces: Vec<(String, Vec<Vec3>)> = Vec::new();
        for collision in &link.collision {
            let urdf_rs::Geometry::Mesh { filename, scale } = &collision.geometry else {
                return Err(format!(
                    "link `{}`: only mesh collision geometry is supported",
                    link.name
                ));
            };
            // `package://NAME/...` resolves to `<URDF folder>/NAME/...`: the package sits
            // beside the URDF (weights/xarm6/xarm_description/).
            let relative = filename.strip_prefix("package://").unwrap_or(filename);
            let file = root_dir.join(relative);
            let scale = scale.map(|s| *s).unwrap_or([1.0; 3]);
            let rotation = math::rpy_to_matrix(&collision.origin.rpy);
            let read = mesh::read_mesh_pieces(&file).map_err(|e| format!("link `{}`: {e}", link.name))?;
            let count = read.len();
            for (k, piece) in read.into_iter().enumerate() {
                let points = piece
                    .iter()
                    .map(|v| {
                        let scaled = [v[0] * scale[0], v[1] * scale[1], v[2] * scale[2]];
                        math::add(&math::mul_vec(&rotation, &scaled), &collision.origin.xyz)
                    })
                    .collect();
                let name = if count == 1 {
                    relative.to_string()
                } else {
                    format!("{relative} (convex piece {k} of {count})")
                };
                pieces.push((name, points));
            }
            inputs.push(file);
        }
        // One body per piece: PyBullet collides each piece's hull on its own, and one hull
        // around a V-HACD decomposition would fill the concavities it was made to keep.
        let count = pieces.len();
        for (k, (mesh_name, points)) in pieces.into_iter().enumerate() {
            let name = if count == 1 {
                link.name.clone()
            } else {
                format!("{}#{k}", link.name)
            };
            bodies.push(Body {
                name,
                frame: index,
                mesh: mesh_name,
                vertex_count: points.len(),
                tight: mesh::tight_box(&points),
                aabb: mesh::aabb(&points),
                points: mesh::hull_vertices(&mesh::distinct(&points)),
            });
        }
    }

    let find = |name: &str| {
        frames
            .iter()
            .position(|f| f.name == name)
            .ok_or(format!("no link `{name}`"))
    };
    let tcp = find(arm.tcp_link)?;
    let hand = find(arm.hand_link)?;
    let self_pairs = match arm.pairs {
        PairRule::Levels => level_pairs(&frames, &bodies),
        PairRule::ApartAtZero => apart_at_zero_pairs(&frames, &bodies)?,
    };
    Ok(Chain {
        arm: *arm,
        frames,
        joints,
        bodies,
        tcp,
        hand,
        gripper,
        self_pairs,
        inputs,
    })
}

/// How many revolute joints lie between `frame` and the root.
pub fn level(frames: &[Frame], frame: usize) -> usize {
    let mut f = frame;
    let mut joints = 0;
    for _ in 0..frames.len() {
        if matches!(frames[f].motion, Motion::Revolute { .. }) {
            joints += 1;
        }
        if f == 0 {
            break;
        }
        f = frames[f].parent;
    }
    joints
}

/// The Panda's rule ([`PairRule::Levels`]): bodies two or more revolute joints apart.
fn level_pairs(frames: &[Frame], bodies: &[Body]) -> Vec<(usize, usize)> {
    let levels: Vec<_> = bodies.iter().map(|b| level(frames, b.frame)).collect();
    let mut pairs = Vec::new();
    for a in 0..bodies.len() {
        for b in a + 1..bodies.len() {
            if levels[a].abs_diff(levels[b]) >= 2 {
                pairs.push((a, b));
            }
        }
    }
    pairs
}

/// How close (metres) two convex pieces may come at the all-zero configuration and still
/// count as apart.
///
/// PyBullet inflates every convex hull it loads from a URDF by a collision margin of 1 mm
/// (`gUrdfDefaultCollisionMargin`), so `getClosestPoints(distance = 0)` reports two hulls
/// whose exact distance is below 2 mm as touching. The same threshold here makes the rule
/// agree with PyBullet by construction; for the arms in [`crate::arms::ARMS`] the choice is
/// not delicate anyway: at q = 0 the closest non-adjacent links are 31.2 mm apart (iiwa
/// `lbr_iiwa_link_5`–`lbr_iiwa_link_7`; PyBullet reports 29.2 mm, the two margins less) and
/// 40.8 mm (xArm `link2`–`link4`; PyBullet 38.8 mm), and `tests/tests/fk_fixture_arms.rs` compares the table with the pairs
/// PyBullet reports.
pub const TOUCH_DISTANCE: f64 = 0.002;

/// The world pose `(rotation, translation)` of every frame at the all-zero configuration
/// (revolute joints at 0, fingers at opening 0).
pub fn zero_poses(frames: &[Frame]) -> Vec<(Mat3, Vec3)> {
    let mut poses: Vec<(Mat3, Vec3)> = Vec::with_capacity(frames.len());
    for (i, f) in frames.iter().enumerate() {
        let pose = match poses.get(f.parent) {
            Some((r, t)) if i > 0 => (
                math::mul(r, &f.origin_rotation),
                math::add(t, &math::mul_vec(r, &f.origin_translation)),
            ),
            _ => (math::IDENTITY, [0.0; 3]),
        };
        poses.push(pose);
    }
    poses
}

/// The rule of every arm but the Panda ([`PairRule::ApartAtZero`]): links that are not parent
/// and child in the URDF tree and whose convex pieces are all more than [`TOUCH_DISTANCE`]
/// apart at q = 0; every pair of their pieces is checked. Parent and child means the child's
/// joint names the parent, as PyBullet's self-collision filter has it (it does not look
/// through fixed joints); neither arm here has a fixed joint between two links with bodies.
fn apart_at_zero_pairs(frames: &[Frame], bodies: &[Body]) -> Result<Vec<(usize, usize)>, String> {
    let poses = zero_poses(frames);
    let world: Vec<Vec<Vec3>> = bodies
        .iter()
        .map(|b| {
            let (r, t) = &poses[b.frame];
            b.points.iter().map(|p| math::add(t, &math::mul_vec(r, p))).collect()
        })
        .collect();
    let adjacent = |a: usize, b: usize| frames[a].parent == b || frames[b].parent == a;
    // Whether two links touch: their closest pieces are within TOUCH_DISTANCE.
    let touch = |fa: usize, fb: usize| -> Result<bool, String> {
        for (i, a) in bodies.iter().enumerate().filter(|(_, a)| a.frame == fa) {
            for (j, b) in bodies.iter().enumerate().filter(|(_, b)| b.frame == fb) {
                let d = hull_distance(&world[i], &world[j])
                    .ok_or(format!("bodies `{}` and `{}`: no hull distance", a.name, b.name))?;
                if d <= TOUCH_DISTANCE {
                    return Ok(true);
                }
            }
        }
        Ok(false)
    };
    let mut apart = Vec::new();
    let mut pairs = Vec::new();
    for a in 0..bodies.len() {
        for b in a + 1..bodies.len() {
            let (fa, fb) = (bodies[a].frame, bodies[b].frame);
            if fa == fb || adjacent(fa, fb) {
                continue;
            }
            let link_pair = (fa.min(fb), fa.max(fb));
            let known = apart.iter().find(|(pair, _)| *pair == link_pair).map(|(_, v)| *v);
            let is_apart = match known {
                Some(v) => v,
                None => {
                    let v = !touch(fa, fb)?;
                    apart.push((link_pair, v));
                    v
                }
            };
            if is_apart {
                pairs.push((a, b));
            }
        }
    }
    Ok(pairs)
}

fn normalised(v: &Vec3, joint: &str) -> Result<Vec3, String> {
    let n = math::norm(v);
    if n.is_nan() || n <= 0.0 || !n.is_finite() {
        return Err(format!("joint `{joint}`: axis {v:?} is not a direction"));
    }
    Ok([v[0] / n, v[1] / n, v[2] / n])
}
