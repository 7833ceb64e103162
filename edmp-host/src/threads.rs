//! The core's [`Executor`] on several cores (`--threads`): a rayon pool runs the items the
//! planner hands over (parts of the network's batch, groups of guides, the refinement's row
//! checks). Every item's result is its own, so a plan is the same, bit for bit, on any number of
//! threads (`edmp-host/tests/cli.rs` and the core's tests check it).

use edmp_core::Error;
use edmp_core::executor::{Executor, MAX_PARTS};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// A pool of `threads` worker threads (kept for the life of the process: one per thread count).
#[derive(Clone)]
pub struct Threads {
    pool: Arc<rayon::ThreadPool>,
}

impl core::fmt::Debug for Threads {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Threads")
            .field("threads", &self.pool.current_num_threads())
            .finish()
    }
}

impl Threads {
    /// The process's pool of `threads` threads (at least 2), made on first use.
    pub fn new(threads: usize) -> Result<Self, String> {
        static POOLS: OnceLock<Mutex<HashMap<usize, Arc<rayon::ThreadPool>>>> = OnceLock::new();
        let threads = threads.max(2);
        let mut pools = POOLS
            .get_or_init(|| Mutex::new(HashMap::new()))
            .lock()
            .map_err(|_| "the thread pools' lock is poisoned".to_owned())?;
        if let Some(pool) = pools.get(&threads) {
            return Ok(Self { pool: pool.clone() });
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("edmp-plan-{i}"))
            .build()
            .map_err(|e| format!("--threads: cannot start {threads} threads: {e}"))?;
        let pool = Arc::new(pool);
        pools.insert(threads, pool.clone());
        Ok(Self { pool })
    }

    /// Runs `work` inside the pool: rayon's parallel iterators in it use these threads.
    pub fn install<R: Send>(&self, work: impl FnOnce() -> R + Send) -> R {
        self.pool.install(work)
    }
}

impl Executor for Threads {
    fn parts(&self) -> usize {
        // More parts than threads: the guides' costs differ, and the pool balances small parts.
        MAX_PARTS
    }

    fn each<T: Send, F: Fn(&mut T) -> Result<(), Error> + Sync>(&self, items: &mut [T], task: F) -> Result<(), Error> {
        if items.len() <= 1 {
            return items.iter_mut().try_for_each(task);
        }
        let results: Vec<Result<(), Error>> = self.pool.install(|| items.par_iter_mut().map(&task).collect());
        results.into_iter().collect()
    }
}
