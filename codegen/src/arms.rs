//! The arms edmp-rs knows, each a URDF and the few facts a URDF does not say: which link is
//! the tool centre point, where a held object attaches, which limits plan, and how the
//! self-collision pairs are chosen (docs/formats.md, "Other arms").

/// Where an arm's planning limits come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LimitSource {
    /// `<safety_controller soft_lower_limit soft_upper_limit>` (Franka's official range).
    SafetyController,
    /// `<limit lower upper>`: the URDF's only range.
    Limit,
}

/// How the self-collision pairs are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairRule {
    /// Bodies whose numbers of revolute joints to the root differ by two or more (the Panda's:
    /// link7, hand and fingers share one level and form one rigid group).
    Levels,
    /// Links that are not parent and child in the chain and do not touch at the all-zero
    /// configuration (the rule docs/formats.md gives every other arm).
    ApartAtZero,
}

/// An arm's joint velocity, acceleration and jerk limits, the time law's bounds
/// (`edmp_core::trajectory`), each with where it comes from: URDFs carry at most a velocity,
/// and not always the manufacturer's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dynamics {
    /// Largest joint velocity per actuated joint, rad/s.
    pub velocity: &'static [f64],
    /// Where `velocity` comes from (written beside the numbers).
    pub velocity_source: &'static str,
    /// Largest joint acceleration per actuated joint, rad/s².
    pub acceleration: &'static [f64],
    /// Where `acceleration` comes from.
    pub acceleration_source: &'static str,
    /// Largest joint jerk per actuated joint, rad/s³.
    pub jerk: &'static [f64],
    /// Where `jerk` comes from.
    pub jerk_source: &'static str,
}

/// Radians per degree: datasheets give axis speeds in °/s.
const DEG: f64 = core::f64::consts::PI / 180.0;

/// One arm: its URDF and the facts around it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmSpec {
    /// The scene format's `robot` name, the generated module's name and the cargo feature.
    pub name: &'static str,
    /// The URDF, relative to the repository root.
    pub urdf: &'static str,
    /// The tool centre point's link (pose goals).
    pub tcp_link: &'static str,
    /// The link a held object is attached to.
    pub hand_link: &'static str,
    /// Which limits plan.
    pub limits: LimitSource,
    /// Whether a gripper opening drives prismatic finger joints.
    pub gripper: bool,
    /// How the self-collision pairs are chosen.
    pub pairs: PairRule,
    /// The ready configuration problems start from or return to (the scene generators'
    /// neutral ends), one value per actuated joint in URDF order: the gripper pointing down in
    /// front of the base, elbow up.
    pub neutral: &'static [f64],
    /// The joint velocity, acceleration and jerk limits the time law keeps to.
    pub dynamics: Dynamics,
    /// The folder of its trained prior (`prior.safetensors`, `prior.json`), relative to the
    /// repository root; `None` until one is trained.
    pub prior: Option<&'static str>,
}

/// Every arm, the Panda first.
pub const ARMS: [ArmSpec; 3] = [
    ArmSpec {
        name: "panda",
        urdf: "weights/panda/panda.urdf",
        tcp_link: "panda_grasptarget",
        hand_link: "panda_hand",
        limits: LimitSource::SafetyController,
        gripper: true,
        pairs: PairRule::Levels,
        // MpiNets' neutral configuration (robofin `FrankaRobot.NEUTRAL`).
        neutral: &[-0.0178, -0.7601, 0.0198, -2.3421, 0.0298, 1.5412, 0.7534],
        dynamics: Dynamics {
            velocity: &[2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61],
            velocity_source: "Franka's datasheet (control parameters, q̇_max): joints 1-4, then 5-7",
            acceleration: &[15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0],
            acceleration_source: "Franka's datasheet (control parameters, q̈_max)",
            jerk: &[7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0],
            jerk_source: "Franka's datasheet (control parameters, q⃛_max)",
        },
        prior: Some("weights/prior"),
    },
    // KUKA LBR iiwa 7 (pybullet_data/kuka_iiwa): 7 revolute joints, one STL hull per link,
    // no tool flange link, so the TCP and the hand are the last link.
    ArmSpec {
        name: "iiwa7",
        urdf: "weights/iiwa7/model.urdf",
        tcp_link: "lbr_iiwa_link_7",
        hand_link: "lbr_iiwa_link_7",
        limits: LimitSource::Limit,
        gripper: false,
        pairs: PairRule::ApartAtZero,
        // Flange at about (0.43, 0, 0.46) m, pointing down (q2 - q4 + q6 ≈ π).
        neutral: &[0.0, 0.2, 0.0, -2.0, 0.0, 0.95, 0.0],
        dynamics: Dynamics {
            velocity: &[
                98.0 * DEG,
                98.0 * DEG,
                100.0 * DEG,
                130.0 * DEG,
                140.0 * DEG,
                180.0 * DEG,
                180.0 * DEG,
            ],
            velocity_source: "KUKA's LBR iiwa 7 R800 datasheet, axis speeds 98, 98, 100, 130, 140, 180, 180 °/s \
                              (the URDF's velocity=\"10\" is a placeholder)",
            // KUKA publishes no acceleration limit.
            acceleration: &[8.65, 5.44, 5.69, 11.01, 11.78, 13.76, 13.17],
            acceleration_source: "none published by KUKA: Drake's iiwa 7 estimate (manipulation/models/\
                                  iiwa_description/README.md: the iiwa 14's averages measured by Larsen 2019, scaled \
                                  by the iiwa 7's mass matrix and torques; gravity-free, so an assumption)",
            // Nor any jerk limit: MoveIt 2's generic default, low on purpose.
            jerk: &[20.0; 7],
            jerk_source: "none published by KUKA: MoveIt 2's Ruckig smoothing default (DEFAULT_MAX_JERK = 20 rad/s³), \
                          a conservative assumption",
        },
        prior: Some("weights/iiwa7"),
    },
    // UFACTORY xArm 6 (pybullet_data/xarm): 6 revolute joints under a geometry-free `world`
    // root, V-HACD collision meshes (several convex pieces per link).
    ArmSpec {
        name: "xarm6",
        urdf: "weights/xarm6/xarm6_robot.urdf",
        tcp_link: "link6",
        hand_link: "link6",
        limits: LimitSource::Limit,
        gripper: false,
        pairs: PairRule::ApartAtZero,
        // Flange at about (0.34, 0, 0.43) m, pointing down.
        neutral: &[0.0, -0.5, -0.8, 0.0, 1.3, 0.0],
        dynamics: Dynamics {
            velocity: &[180.0 * DEG; 6],
            velocity_source: "UFACTORY's xArm 6 datasheet, 180 °/s per joint",
            // UFACTORY's datasheet gives no acceleration.
            acceleration: &[500.0 * DEG; 6],
            acceleration_source: "none in UFACTORY's datasheet: the xArm Python SDK's default joint acceleration, \
                                  500 °/s² (xarm/x3/base.py `_last_joint_acc`; the SDK accepts up to 20 rad/s²)",
            jerk: &[20.0; 6],
            jerk_source: "none in UFACTORY's datasheet: the xArm Python SDK's joint jerk setting, 20 rad/s³ \
                          (xarm/x3/base.py `_joint_jerk`)",
        },
        prior: Some("weights/xarm6"),
    },
];

/// The arm called `name`.
pub fn arm(name: &str) -> Option<&'static ArmSpec> {
    ARMS.iter().find(|a| a.name == name)
}
