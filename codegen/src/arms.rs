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
        prior: Some("weights/xarm6"),
    },
];

/// The arm called `name`.
pub fn arm(name: &str) -> Option<&'static ArmSpec> {
    ARMS.iter().find(|a| a.name == name)
}
