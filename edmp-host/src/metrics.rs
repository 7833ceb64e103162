//! Trajectory measures of the EDMP paper: roughness (§V ablations: AR, MRESG, RF2W, RL2W, each
//! the L2 norm between adjacent waypoints in joint space), path length, and the ensemble's
//! diversity as ACSM (the mean cosine similarity over all pairs of a batch's trajectories,
//! each flattened to one vector; lower is more diverse).

/// The paper's four roughness numbers of one trajectory (radians).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Roughness {
    /// Average roughness: the mean step.
    pub(crate) ar: f64,
    /// Max roughness excluding the first and the last step.
    pub(crate) mresg: f64,
    /// Roughness of the first step.
    pub(crate) rf2w: f64,
    /// Roughness of the last step.
    pub(crate) rl2w: f64,
}

/// The L2 norm of one step in joint space.
pub(crate) fn step_norm<const J: usize>(a: &[f32; J], b: &[f32; J]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| f64::from(x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Roughness of a trajectory of at least three waypoints (fewer: all zero).
pub(crate) fn roughness<const J: usize>(path: &[[f32; J]]) -> Roughness {
    if path.len() < 3 {
        return Roughness::default();
    }
    let steps: Vec<f64> = path.windows(2).map(|w| step_norm(&w[0], &w[1])).collect();
    Roughness {
        ar: steps.iter().sum::<f64>() / steps.len() as f64,
        mresg: steps[1..steps.len() - 1].iter().copied().fold(0.0, f64::max),
        rf2w: steps[0],
        rl2w: steps[steps.len() - 1],
    }
}

/// Joint-space length of a trajectory (radians).
pub(crate) fn path_length<const J: usize>(path: &[[f32; J]]) -> f64 {
    path.windows(2).map(|w| step_norm(&w[0], &w[1])).sum()
}

/// Average Cosine Similarity Mean of a batch (None for fewer than two trajectories).
pub(crate) fn acsm<const J: usize>(batch: &[&[[f32; J]]]) -> Option<f64> {
    let flat: Vec<Vec<f64>> = batch
        .iter()
        .map(|p| p.iter().flatten().map(|v| f64::from(*v)).collect())
        .collect();
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let (mut sum, mut pairs) = (0.0, 0usize);
    for i in 0..flat.len() {
        for j in i + 1..flat.len() {
            let dot: f64 = flat[i].iter().zip(&flat[j]).map(|(a, b)| a * b).sum();
            let denominator = norm(&flat[i]) * norm(&flat[j]);
            if denominator > 0.0 {
                sum += dot / denominator;
                pairs += 1;
            }
        }
    }
    (pairs > 0).then(|| sum / pairs as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roughness_reads_the_steps_it_names() {
        let mut path = [[0.0f32; 7]; 5];
        for (i, q) in path.iter_mut().enumerate() {
            q[0] = [0.0, 0.3, 0.4, 0.8, 1.0][i];
        }
        let r = roughness(&path);
        assert!((r.rf2w - 0.3).abs() < 1e-6);
        assert!((r.rl2w - 0.2).abs() < 1e-6);
        assert!((r.mresg - 0.4).abs() < 1e-6);
        assert!((r.ar - 0.25).abs() < 1e-6);
        assert!((path_length(&path) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn acsm_is_one_for_copies_and_lower_for_different_paths() {
        let a = [[1.0f32, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]; 3];
        let b = [[0.0f32, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]; 3];
        assert!((acsm(&[&a, &a]).unwrap() - 1.0).abs() < 1e-12);
        assert!(acsm(&[&a, &b]).unwrap().abs() < 1e-12);
        assert!((acsm(&[&a, &a, &b]).unwrap() - 1.0 / 3.0).abs() < 1e-12);
        assert_eq!(acsm(&[&a]), None);
    }
}
