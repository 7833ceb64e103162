//! The ensemble in waves: the guides dealt into groups that run one after another on their own
//! rows, each wave certified by the exact checker before the next; the first wave with a free
//! row ends the stage. One wave is EDMP's one batch.

use crate::error::Error;
use crate::executor::Executor;
use crate::guidance::guides::Guide;
use crate::path::Path;
use crate::planner::judge::certify;
use crate::planner::request::Request;
use crate::planner::workspace::{RowChecks, WaveChecks, WaveRows, Workspace};

/// Runs `wave` on the batch in [`PlanConfig::waves`] waves, one after another: wave `w` gives
/// guides `w`, `w + waves`, `w + 2·waves`, … (so that each wave mixes the caller's order) their
/// rows of `paths`; the exact checker certifies each wave's rows ([`certify`]) before the next
/// runs, and the first wave with a free row ends it. The rows of waves not run are
/// `RowChecks::skipped` in `work.checks` (never judged), and every row is put back in the
/// caller's order (row r follows guide r / k whatever the waves). At most `limit` waves run
/// (0 is [`Error::BadParameter`]). Shared by the first stage
/// ([`denoise_on`](crate::planner::denoise_on)) and the global stage's reseeding
/// ([`crate::planner::global`]).
pub(crate) fn in_waves<E: Executor, const B: usize, const N: usize, const CAP: usize, const J: usize>(
    exec: &E,
    req: &Request<'_, N, J>,
    work: &mut Workspace<B, CAP, J>,
    paths: &mut [Path<J>; B],
    limit: usize,
    mut wave: impl FnMut(&[Guide], WaveRows<'_, J>, WaveChecks<'_>) -> Result<(), Error>,
) -> Result<(), Error> {
    let guides = req.guides;
    if B == 0 || guides.is_empty() || !B.is_multiple_of(guides.len()) || limit == 0 {
        return Err(Error::BadParameter);
    }
    let waves = req.config.waves_for(guides.len())?;
    let per_wave = guides.len() / waves;
    let rows = B / waves;
    // The guides in the order the waves run them, the rows likewise: wave w runs rows
    // `w·rows .. (w + 1)·rows` of `paths`, which are put back in the caller's order at the end.
    let Some(&first) = guides.first() else {
        return Err(Error::BadParameter);
    };
    let mut order = [first; B];
    for (slot, g) in order.iter_mut().zip(wave_order(guides.len(), waves)) {
        *slot = guides.get(g).copied().ok_or(Error::BadParameter)?;
    }
    work.checks = RowChecks::NONE;
    let Workspace { eps, grads, checks, .. } = work;
    let mut ran = 0;
    let runnable = waves.min(limit);
    for w in 0..runnable {
        let (Some(wave_guides), Some(x), Some(e), Some(d), Some(free), Some(touched)) = (
            order.get(w * per_wave..(w + 1) * per_wave),
            paths.get_mut(w * rows..(w + 1) * rows),
            eps.get_mut(w * rows..(w + 1) * rows),
            grads.get_mut(w * rows..(w + 1) * rows),
            checks.free.get_mut(w * rows..(w + 1) * rows),
            checks.touched.get_mut(w * rows..(w + 1) * rows),
        ) else {
            return Err(Error::BadParameter);
        };
        wave(wave_guides, (x, e, d), (free, touched))?;
        ran = w + 1;
        // A later wave runs only when no row of this one is free (the judge would check them
        // the same way; what is learnt here it does not check again).
        if ran < runnable && certify::<E, B, N, J>(exec, req, x, free, touched, 1)? > 0 {
            break;
        }
    }
    for skipped in checks.skipped.iter_mut().skip(ran * rows) {
        *skipped = true;
    }
    if waves > 1 {
        let k = B / guides.len();
        // Row `r` of the caller's order (guide `r / k`) is row `source[r]` of the waves' order:
        // `wave_order` inverted, so the two orders cannot disagree.
        let mut source = [0usize; B];
        for (slot, g) in wave_order(guides.len(), waves).enumerate() {
            for i in 0..k {
                if let Some(src) = source.get_mut(g * k + i) {
                    *src = slot * k + i;
                }
            }
        }
        permute(paths, &source);
        permute(&mut checks.free, &source);
        permute(&mut checks.touched, &source);
        permute(&mut checks.skipped, &source);
    }
    Ok(())
}

/// The caller's guide index at each slot of the waves' order: wave `w` takes guides `w`,
/// `w + waves`, `w + 2·waves`, … (`waves` divides `guides`).
pub(crate) fn wave_order(guides: usize, waves: usize) -> impl Iterator<Item = usize> {
    let per_wave = guides / waves.max(1);
    (0..guides).map(move |slot| (slot % per_wave.max(1)) * waves + slot / per_wave.max(1))
}

/// `items[r] = old items[source[r]]` for every `r`, in place (`source` a permutation).
pub(crate) fn permute<T>(items: &mut [T], source: &[usize]) {
    for (r, &first) in source.iter().enumerate().take(items.len()) {
        // Follow the cycle to where the swaps before have moved the item that belongs at `r`.
        let mut from = first;
        while from < r {
            from = source.get(from).copied().unwrap_or(r);
        }
        if from < items.len() {
            items.swap(r, from);
        }
    }
}
