//! The diffusion prior over trajectories: the trained int8 UNet ([`predict_noise`]) and the
//! reverse-diffusion samplers that turn noise into a trajectory between a start and a goal.
//!
//! Three samplers share one step interface, so the guided planner can apply its costs between
//! steps: EDMP's original ancestral sampler (all `STEPS` = 255 steps, noise std β_t, exactly
//! as the original implementation, vishal-2000/EDMP); the same rule on `K` evenly strided steps (the
//! strided step's β' = 1 − ᾱ_t/ᾱ_prev), which trades steps for speed; and DDIM (η = 0) on `K`
//! strided steps, for comparison. All write the start and the goal into the first and last
//! waypoint after every step.

pub mod arms;
mod layers;
mod net;
mod weights;

pub use net::{Network, Scratch, TimeEmbedding, predict_noise, predict_noise_on};
pub use weights::{DIMS, LENGTHS, LEVELS, MACS, PARAMETERS, STEPS, WEIGHT_BYTES, WEIGHTS_FNV1A};

use crate::Error;
use crate::path::{HORIZON, Path};
use crate::rng::Rng;
use crate::robot::JOINTS;

// The network must have been trained on this robot's joints and the planner's horizon.
const _: () = assert!(
    weights::JOINTS == JOINTS,
    "weights/prior was trained for another joint count"
);
const _: () = assert!(LENGTHS[0] == HORIZON, "weights/prior was trained for another horizon");

/// The Panda's network.
pub static PANDA: &Network<JOINTS> = &weights::NETWORK;

/// The weight blob the build embedded for the Panda: `include_bytes!` of the codegen output.
pub fn weight_blob() -> &'static [u8] {
    PANDA.weight_blob()
}

/// Whether the Panda's embedded weights still hash to the checksum codegen computed.
pub fn weights_intact() -> bool {
    PANDA.weights_intact()
}

/// How to walk from noise to a trajectory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampler {
    /// EDMP's ancestral sampler: every step t = 255 … 1,
    /// x ← (x − β_t/√(1−ᾱ_t)·ε̂)/√α_t + β_t·z (z = 0 at t = 1).
    Ancestral,
    /// EDMP's rule on `steps` strided steps t_j = T − ⌊j·T/K⌋, j = 0 … K − 1, with the
    /// strided β' = 1 − ᾱ_t/ᾱ_prev in place of β_t (K = T is the ancestral walk up to rounding).
    Strided {
        /// K, 1 ..= `STEPS`.
        steps: u16,
    },
    /// Deterministic DDIM on the same strided steps.
    Ddim {
        /// K, 1 ..= `STEPS`.
        steps: u16,
    },
}

/// One reverse step: denoise at `t`, land on `prev` (0 is the clean trajectory).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Step {
    /// The step the network is evaluated at.
    pub t: u16,
    /// The step the update lands on.
    pub prev: u16,
}

impl Sampler {
    /// Refuses a DDIM step count outside 1 ..= `STEPS`.
    pub fn validate(&self) -> Result<(), Error> {
        match *self {
            Self::Ancestral => Ok(()),
            Self::Strided { steps } | Self::Ddim { steps } if steps >= 1 && usize::from(steps) <= STEPS => Ok(()),
            Self::Strided { .. } | Self::Ddim { .. } => Err(Error::BadParameter),
        }
    }

    /// Network evaluations per trajectory.
    pub fn evaluations(&self) -> usize {
        match *self {
            Self::Ancestral => STEPS,
            Self::Strided { steps } | Self::Ddim { steps } => usize::from(steps),
        }
    }

    /// The `j`-th step of the walk (`j < evaluations()`).
    pub fn step(&self, j: usize) -> Step {
        let at = |j: usize| -> u16 {
            let k = self.evaluations();
            if j >= k { 0 } else { (STEPS - j * STEPS / k) as u16 }
        };
        Step {
            t: at(j),
            prev: at(j + 1),
        }
    }

    /// Moves `x` from step `step.t` to `step.prev` given the network's `eps` (the noise draw
    /// comes from `rng`, one normal per entry, waypoint-major). Then re-inpaints: the start/goal
    /// conditioning of EDMP.
    pub fn update<const J: usize>(
        &self,
        step: Step,
        x: &mut Path<J>,
        eps: &Path<J>,
        rng: &mut Rng,
        start: &[f32; J],
        goal: &[f32; J],
    ) {
        self.advance(step, x, eps, rng);
        inpaint(x, start, goal);
    }

    /// [`Self::update`] without the inpainting: every waypoint, the ends included, follows the
    /// network (the paper's "without conditioning" ablation, Table IV).
    pub fn advance<const J: usize>(&self, step: Step, x: &mut Path<J>, eps: &Path<J>, rng: &mut Rng) {
        let i = table_index(step.t);
        match *self {
            Self::Ancestral => {
                let (a, c, sigma) = (weights::SQRT_RECIP_ALPHA[i], weights::EPS_COEF[i], weights::BETA[i]);
                for (xw, ew) in x.iter_mut().zip(eps) {
                    for (xv, ev) in xw.iter_mut().zip(ew) {
                        let z = if step.t > 1 { rng.normal_f32() } else { 0.0 };
                        *xv = a * (*xv - c * ev) + sigma * z;
                    }
                }
            }
            Self::Strided { .. } => {
                let abar = |t: u16| match t {
                    0 => 1.0,
                    t => {
                        let s = weights::SQRT_ALPHA_BAR[table_index(t)];
                        s * s
                    }
                };
                let beta = 1.0 - abar(step.t) / abar(step.prev);
                let (a, c) = (
                    1.0 / crate::float::sqrt(1.0 - beta),
                    beta / weights::SQRT_ONE_MINUS_ALPHA_BAR[i],
                );
                for (xw, ew) in x.iter_mut().zip(eps) {
                    for (xv, ev) in xw.iter_mut().zip(ew) {
                        let z = if step.prev > 0 { rng.normal_f32() } else { 0.0 };
                        *xv = a * (*xv - c * ev) + beta * z;
                    }
                }
            }
            Self::Ddim { .. } => {
                let (sa, sn) = (weights::SQRT_ALPHA_BAR[i], weights::SQRT_ONE_MINUS_ALPHA_BAR[i]);
                let (pa, pn) = match step.prev {
                    0 => (1.0, 0.0),
                    p => {
                        let p = table_index(p);
                        (weights::SQRT_ALPHA_BAR[p], weights::SQRT_ONE_MINUS_ALPHA_BAR[p])
                    }
                };
                for (xw, ew) in x.iter_mut().zip(eps) {
                    for (xv, ev) in xw.iter_mut().zip(ew) {
                        let x0 = (*xv - sn * ev) / sa;
                        *xv = pa * x0 + pn * ev;
                    }
                }
            }
        }
    }
}

impl Step {
    /// The `j`-th step of a strided walk of `steps` steps that starts at diffusion step `from`
    /// rather than at `STEPS`: t_j = from − ⌊j·from/steps⌋, landing on 0 after the last. The
    /// strided rule applies to any such step ([`Sampler::update`] with `Sampler::Strided`).
    pub fn partial(from: u16, steps: u16, j: usize) -> Self {
        let at = |j: usize| -> u16 {
            let (from, k) = (usize::from(from), usize::from(steps));
            match (j * from).checked_div(k) {
                Some(back) if j < k => from.saturating_sub(back) as u16,
                _ => 0,
            }
        };
        Self {
            t: at(j),
            prev: at(j + 1),
        }
    }
}

/// The forward process q(x_t | x_0): `x ← √ᾱ_t·x + √(1−ᾱ_t)·ε` (standard normals from `rng`,
/// waypoint-major), then the ends written in: how a trajectory found elsewhere is handed to the
/// prior at an intermediate step (SDEdit), to be denoised from there.
pub fn diffuse<const J: usize>(x: &mut Path<J>, t: u16, rng: &mut Rng, start: &[f32; J], goal: &[f32; J]) {
    let i = table_index(t);
    let (a, n) = (weights::SQRT_ALPHA_BAR[i], weights::SQRT_ONE_MINUS_ALPHA_BAR[i]);
    for v in x.iter_mut().flatten() {
        *v = a * *v + n * rng.normal_f32();
    }
    inpaint(x, start, goal);
}

/// Index of step `t` in the schedule tables; steps outside 1 ..= `STEPS` (a hand-made [`Step`])
/// take the nearest end instead of panicking.
fn table_index(t: u16) -> usize {
    usize::from(t).clamp(1, STEPS) - 1
}

/// Writes the start and the goal into the first and last waypoints.
pub fn inpaint<const J: usize>(x: &mut Path<J>, start: &[f32; J], goal: &[f32; J]) {
    x[0] = *start;
    x[HORIZON - 1] = *goal;
}

/// The sampler's starting point: standard normal entries (waypoint-major), then inpainted.
pub fn initial_noise<const J: usize>(x: &mut Path<J>, rng: &mut Rng, start: &[f32; J], goal: &[f32; J]) {
    for v in x.iter_mut().flatten() {
        *v = rng.normal_f32();
    }
    inpaint(x, start, goal);
}

/// Redraws the two ends of an [`initial_noise`] as standard normals (a second, independent
/// draw): the starting point of the unconditioned ablation.
pub fn free_ends<const J: usize>(x: &mut Path<J>, rng: &mut Rng) {
    for w in [0, HORIZON - 1] {
        for v in x[w].iter_mut() {
            *v = rng.normal_f32();
        }
    }
}

/// A joint vector with a NaN or an infinity is a typed error naming the joint.
pub(crate) fn check_joints<const J: usize>(q: &[f32; J]) -> Result<(), Error> {
    match q.iter().position(|v| !v.is_finite()) {
        Some(joint) => Err(Error::NonFiniteJoint { joint: joint as u8 }),
        None => Ok(()),
    }
}

/// Unguided sampling of `B` trajectories from `start` to `goal`, all from one `rng` stream
/// (trajectory 0's noise first, then 1's, at every step). Fixed work: `sampler.evaluations()`
/// batched network forwards, `C` trajectories at a time.
pub fn sample<const B: usize, const C: usize>(
    sampler: Sampler,
    start: &[f32; JOINTS],
    goal: &[f32; JOINTS],
    rng: &mut Rng,
    scratch: &mut Scratch<C>,
    out: &mut [Path; B],
) -> Result<(), Error> {
    sample_conditioned(sampler, true, start, goal, rng, scratch, out)
}

/// [`sample`], or with `condition = false` the paper's unconditioned ablation: no inpainting
/// while denoising (the noise starts free too); the start and goal are written into the ends
/// only after the last step.
pub fn sample_conditioned<const B: usize, const C: usize>(
    sampler: Sampler,
    condition: bool,
    start: &[f32; JOINTS],
    goal: &[f32; JOINTS],
    rng: &mut Rng,
    scratch: &mut Scratch<C>,
    out: &mut [Path; B],
) -> Result<(), Error> {
    sample_with(PANDA, sampler, condition, start, goal, rng, scratch, out)
}

/// [`sample_conditioned`] with `network`: any arm's prior.
#[allow(clippy::too_many_arguments)]
pub fn sample_with<const J: usize, const B: usize, const C: usize>(
    network: &Network<J>,
    sampler: Sampler,
    condition: bool,
    start: &[f32; J],
    goal: &[f32; J],
    rng: &mut Rng,
    scratch: &mut Scratch<C>,
    out: &mut [Path<J>; B],
) -> Result<(), Error> {
    sampler.validate()?;
    check_joints(start)?;
    check_joints(goal)?;
    for x in out.iter_mut() {
        initial_noise(x, rng, start, goal);
        if !condition {
            free_ends(x, rng);
        }
    }
    let mut eps = [[[0.0f32; J]; HORIZON]; B];
    for j in 0..sampler.evaluations() {
        let step = sampler.step(j);
        let time = network.time(step.t)?;
        network.predict_noise(out, &time, scratch, &mut eps)?;
        for (x, e) in out.iter_mut().zip(&eps) {
            if condition {
                sampler.update(step, x, e, rng, start, goal);
            } else {
                sampler.advance(step, x, e, rng);
            }
        }
    }
    if !condition {
        for x in out.iter_mut() {
            inpaint(x, start, goal);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ddim_strides_cover_the_schedule() {
        let s = Sampler::Ddim { steps: 10 };
        assert_eq!(s.step(0), Step { t: 255, prev: 230 });
        assert_eq!(s.step(9), Step { t: 26, prev: 0 });
        let all = Sampler::Ddim { steps: 255 };
        assert!((0..255).all(|j| all.step(j).t == 255 - j as u16));
        assert_eq!(Sampler::Ancestral.step(254), Step { t: 1, prev: 0 });
        assert_eq!(Sampler::Ddim { steps: 0 }.validate(), Err(Error::BadParameter));
        assert_eq!(Sampler::Ddim { steps: 256 }.validate(), Err(Error::BadParameter));
        assert_eq!(Sampler::Strided { steps: 0 }.validate(), Err(Error::BadParameter));
        assert_eq!(Sampler::Strided { steps: 7 }.step(6), Step { t: 37, prev: 0 });
        // A hand-made step outside the schedule is clamped, not a panic.
        let (start, goal) = ([0.0; JOINTS], [0.1; JOINTS]);
        for sampler in [
            Sampler::Ancestral,
            Sampler::Strided { steps: 3 },
            Sampler::Ddim { steps: 3 },
        ] {
            let mut x = [[0.5f32; JOINTS]; HORIZON];
            let eps = [[0.1f32; JOINTS]; HORIZON];
            sampler.update(
                Step { t: 900, prev: 700 },
                &mut x,
                &eps,
                &mut Rng::new(1),
                &start,
                &goal,
            );
            assert!(x.iter().flatten().all(|v| v.is_finite()));
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "the UNet or its 1 MB of weights: too slow under Miri")]
    fn embedded_weights_match_their_checksum() {
        assert!(weights_intact());
        assert_eq!(weight_blob().len(), WEIGHT_BYTES);
        assert_eq!(weight_blob().as_ptr() as usize % 16, 0);
    }

    #[test]
    fn time_embedding_refuses_steps_outside_the_schedule() {
        assert_eq!(TimeEmbedding::new(0), Err(Error::BadParameter));
        assert_eq!(TimeEmbedding::new(STEPS as u16 + 1), Err(Error::BadParameter));
        assert!(TimeEmbedding::new(1).is_ok());
    }

    #[test]
    #[cfg_attr(miri, ignore = "the UNet or its 1 MB of weights: too slow under Miri")]
    fn noise_prediction_refuses_nan_and_does_not_depend_on_the_batch() {
        let time = TimeEmbedding::new(100).unwrap();
        let mut rng = Rng::new(3);
        let mut x = [[[0.0f32; JOINTS]; HORIZON]; 3];
        for x in &mut x {
            initial_noise(x, &mut rng, &[0.0; JOINTS], &[0.5; JOINTS]);
        }
        let mut batch = [[[0.0f32; JOINTS]; HORIZON]; 3];
        predict_noise(&x, &time, &mut std::boxed::Box::new(Scratch::<3>::new()), &mut batch).unwrap();
        let mut pairs = [[[0.0f32; JOINTS]; HORIZON]; 3];
        predict_noise(&x, &time, &mut std::boxed::Box::new(Scratch::<2>::new()), &mut pairs).unwrap();
        assert_eq!(pairs, batch);
        for (xi, bi) in x.iter().zip(&batch) {
            let mut one = [[[0.0f32; JOINTS]; HORIZON]; 1];
            predict_noise(&[*xi], &time, &mut Scratch::<1>::new(), &mut one).unwrap();
            assert_eq!(&one[0], bi);
        }
        assert_eq!(
            predict_noise(&x, &time, &mut Scratch::<0>::new(), &mut batch),
            Err(Error::BadParameter)
        );
        x[1][7][3] = f32::NAN;
        let got = predict_noise(&x, &time, &mut Scratch::<1>::new(), &mut batch);
        assert_eq!(got, Err(Error::NonFiniteJoint { joint: 3 }));
    }

    #[test]
    #[cfg_attr(miri, ignore = "the UNet or its 1 MB of weights: too slow under Miri")]
    fn noise_prediction_in_parts_gives_the_same_bits() {
        let time = TimeEmbedding::new(40).unwrap();
        let mut rng = Rng::new(5);
        let mut x = [[[0.0f32; JOINTS]; HORIZON]; 12];
        for x in &mut x {
            initial_noise(x, &mut rng, &[0.1; JOINTS], &[0.6; JOINTS]);
        }
        let mut whole = [[[0.0f32; JOINTS]; HORIZON]; 12];
        predict_noise(&x, &time, &mut std::boxed::Box::new(Scratch::<4>::new()), &mut whole).unwrap();
        for parts in [1, 2, 3, 4, 8] {
            let mut scratches: std::vec::Vec<Scratch<3>> = (0..parts).map(|_| Scratch::new()).collect();
            let mut split = [[[0.0f32; JOINTS]; HORIZON]; 12];
            predict_noise_on(&crate::executor::Reversed(parts), &x, &time, &mut scratches, &mut split).unwrap();
            assert!(split == whole, "{parts} parts");
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "the UNet or its 1 MB of weights: too slow under Miri")]
    fn samples_keep_start_and_goal_and_stay_finite() {
        let (start, goal) = (
            [0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.7],
            [0.8, 0.2, 0.1, -1.5, 0.3, 1.8, 0.2],
        );
        let mut out = [[[0.0f32; JOINTS]; HORIZON]; 2];
        let mut rng = Rng::new(9);
        sample(
            Sampler::Ddim { steps: 5 },
            &start,
            &goal,
            &mut rng,
            &mut std::boxed::Box::new(Scratch::<2>::new()),
            &mut out,
        )
        .unwrap();
        for x in &out {
            assert_eq!(x[0], start);
            assert_eq!(x[HORIZON - 1], goal);
            assert!(x.iter().flatten().all(|v| v.is_finite()));
        }
    }
}
