//! One planning request: what every stage of the pipeline reads and none of them changes.

use crate::guidance::guides::Guide;
use crate::planner::config::{PlanConfig, waves_within};
use crate::prior::Network;
use crate::robot::kinematics::Joints;
use crate::robot::{JOINTS, Robot};
use crate::scene::Scene;

/// The arm (its tables and its prior), the problem (scene, start, goal), the guides its rows
/// follow and the tuning, travelling together through the stages. Row `r` of a batch of `B`
/// follows guide `r / (B / guides.len())`. `J` is the arm's number of joints.
#[derive(Clone, Copy, Debug)]
pub struct Request<'a, const N: usize, const J: usize = JOINTS> {
    /// The arm: kinematics, collision bodies, limits ([`crate::robot::PANDA`] for the Panda).
    pub robot: &'static Robot<f32, J>,
    /// The arm's prior ([`crate::prior::PANDA`] for the Panda).
    pub network: &'static Network<J>,
    /// The obstacles, the held object and the gripper opening.
    pub scene: &'a Scene<'a, N>,
    /// The first waypoint of every candidate.
    pub start: &'a Joints<f32, J>,
    /// The last waypoint of every candidate.
    pub goal: &'a Joints<f32, J>,
    /// The guides the rows follow (EDMP's ensemble: [`crate::guidance::guides::EDMP_GUIDES`]).
    pub guides: &'a [Guide],
    /// Everything else the planner is told.
    pub config: &'a PlanConfig,
}

impl<'a, const N: usize, const J: usize> Request<'a, N, J> {
    /// The same request for another set of guides: a wave of the ensemble
    /// ([`PlanConfig::waves`]) runs its own guides on its own rows.
    pub fn with_guides(&self, guides: &'a [Guide]) -> Self {
        Self { guides, ..*self }
    }

    /// The waves one stage (the first, or the global stage's reseeding) may run: the wave
    /// budget (the config's, else the prior's) over the scene's guide boxes
    /// ([`PlanConfig::wave_budget`]).
    pub fn waves_within_budget(&self) -> usize {
        let budget = self.config.wave_budget.or(self.network.wave_budget);
        waves_within(budget, self.scene.guide_obstacles().len())
    }
}
