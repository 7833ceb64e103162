//! Where the planner's independent work runs: on the calling thread ([`Serial`]: firmware, and
//! every plan by default), or on several cores, by an executor the host brings (the core has no
//! threads).
//!
//! The planner hands an executor slices of independent items: parts of the batch for the
//! network, groups of guides for the guidance, rows for the refinement's checks. Each item's
//! result depends on that item alone (the network's rows are independent of how they are
//! grouped, a guide's step of its own rows, a row's check of that row), so every executor gives
//! the same plan, bit for bit.

use crate::Error;

/// At most this many parts of the work at once (items of one [`Executor::each`] call beyond the
/// rows).
pub const MAX_PARTS: usize = 8;

/// Runs independent items of the planner's work.
pub trait Executor: Sync {
    /// Into how many parts the planner cuts the network's batch and the guides (1: serial;
    /// at most [`MAX_PARTS`]).
    fn parts(&self) -> usize;

    /// Runs `task` once on every item (each task sees its own item only; in any order, or at
    /// once) and returns the error of the first failing item in item order, if any; items after
    /// a failing one may or may not have run.
    fn each<T: Send, F: Fn(&mut T) -> Result<(), Error> + Sync>(&self, items: &mut [T], task: F) -> Result<(), Error>;
}

/// Every item in order on the calling thread, stopping at the first error.
#[derive(Clone, Copy, Debug, Default)]
pub struct Serial;

impl Executor for Serial {
    fn parts(&self) -> usize {
        1
    }

    fn each<T: Send, F: Fn(&mut T) -> Result<(), Error> + Sync>(&self, items: &mut [T], task: F) -> Result<(), Error> {
        items.iter_mut().try_for_each(task)
    }
}

/// For tests: runs items in reverse order, cut into `self.0` parts (any order must give the same
/// bits).
#[cfg(test)]
pub(crate) struct Reversed(pub usize);

#[cfg(test)]
impl Executor for Reversed {
    fn parts(&self) -> usize {
        self.0
    }

    fn each<T: Send, F: Fn(&mut T) -> Result<(), Error> + Sync>(&self, items: &mut [T], task: F) -> Result<(), Error> {
        items.iter_mut().rev().try_for_each(task)
    }
}

/// `n` items cut into at most `parts` contiguous runs of whole groups of `group` items: the
/// length of each run (0 past the last). `group` 0 counts as 1.
pub(crate) fn split(n: usize, group: usize, parts: usize) -> [usize; MAX_PARTS] {
    let group = group.max(1);
    let groups = n.div_ceil(group);
    let parts = parts.clamp(1, MAX_PARTS).min(groups.max(1));
    let mut lens = [0usize; MAX_PARTS];
    let mut left = n;
    for (i, len) in lens.iter_mut().enumerate().take(parts) {
        let share = (groups * (i + 1)).div_ceil(parts) - (groups * i).div_ceil(parts);
        *len = (share * group).min(left);
        left -= *len;
    }
    lens
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_cover_every_item_once_in_whole_groups() {
        for n in 0..30 {
            for group in 0..5 {
                for parts in 0..10 {
                    let lens = split(n, group, parts);
                    assert_eq!(lens.iter().sum::<usize>(), n, "{n} {group} {parts}");
                    let g = group.max(1);
                    let used = lens.iter().filter(|&&l| l > 0).count();
                    assert!(used <= parts.clamp(1, MAX_PARTS));
                    // Every run but the last holds whole groups.
                    let last = lens.iter().rposition(|&l| l > 0).unwrap_or(0);
                    assert!(lens[..last].iter().all(|l| l % g == 0), "{lens:?}");
                }
            }
        }
        assert_eq!(split(12, 4, 2)[..3], [8, 4, 0]);
        assert_eq!(split(12, 1, 2)[..3], [6, 6, 0]);
    }

    #[test]
    fn serial_stops_at_the_first_error() {
        let mut items = [1, 2, 3, 4];
        let r = Serial.each(&mut items, |x| {
            *x *= 10;
            if *x == 20 { Err(Error::BadParameter) } else { Ok(()) }
        });
        assert_eq!(r, Err(Error::BadParameter));
        assert_eq!(items, [10, 20, 3, 4]);
    }
}
