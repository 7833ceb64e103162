//! The kinematic chain read from an arm's URDF: frames in parent-before-child order, the
//! actuated joints with both limit sets, one collision body per link that has a collision
//! mesh, and the self-collision pairs by the arm's rule.

use crate::arms::{ArmSpec, LimitSource, PairRule};
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

/// A collision body: a mesh rigidly attached to a frame, and its boxes.
#[derive(Clone, Debug)]
pub struct Body {
    /// URDF link name.
    pub name: String,
    /// Index of the frame the box is expressed in.
    pub frame: usize,
    /// Mesh file, relative to the URDF's folder.
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
        let mut points = Vec::new();
        let mut meshes = Vec::new();
        for collision in &link.collision {
            let urdf_rs::Geometry::Mesh { filename, scale } = &collision.geometry else {
                return Err(format!(
                    "link `{}`: only mesh collision geometry is supported",
                    link.name
                ));
            };
            let relative = filename.strip_prefix("package://").unwrap_or(filename);
            let file = root_dir.join(relative);
            let scale = scale.map(|s| *s).unwrap_or([1.0; 3]);
            let rotation = math::rpy_to_matrix(&collision.origin.rpy);
            for v in mesh::read_obj_vertices(&file)? {
                let scaled = [v[0] * scale[0], v[1] * scale[1], v[2] * scale[2]];
                points.push(math::add(&math::mul_vec(&rotation, &scaled), &collision.origin.xyz));
            }
            meshes.push(relative.to_string());
            inputs.push(file);
        }
        if points.is_empty() {
            continue;
        }
        bodies.push(Body {
            name: link.name.clone(),
            frame: index,
            mesh: meshes.join(" + "),
            vertex_count: points.len(),
            tight: mesh::tight_box(&points),
            aabb: mesh::aabb(&points),
            points: mesh::hull_vertices(&mesh::distinct(&points)),
        });
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
        PairRule::ApartAtZero => {
            return Err(format!(
                "arm `{}`: the apart-at-zero pair rule is not built yet",
                arm.name
            ));
        }
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

fn normalised(v: &Vec3, joint: &str) -> Result<Vec3, String> {
    let n = math::norm(v);
    if n.is_nan() || n <= 0.0 || !n.is_finite() {
        return Err(format!("joint `{joint}`: axis {v:?} is not a direction"));
    }
    Ok([v[0] / n, v[1] / n, v[2] / n])
}
