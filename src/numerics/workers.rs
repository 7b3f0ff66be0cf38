//! Threads inside one run: the tiles and bands of a 2-D stage run on a rayon pool that
//! the stages of one pipeline share and own.
//!
//! With one thread there is no pool and the work runs in order on the caller's thread
//! (no rayon at all). With more, each stepped tile (the stages, the maps, the copy of
//! the state: [`Workers::tiles`]) or band of rows (the diagnostics, whose sums go band
//! by band: [`Workers::map_bands`]) is one task
//! (`with_max_len(1)`: a thread that runs out of work steals single tasks, so the dry
//! and wet parts of a run balance). The partition does not depend on the number of
//! threads, each task writes only its own cells, and every reduction is combined in a
//! fixed order (band order for sums) or by an order-free rule (the first minimum in
//! cell order): the results are the same bits for 1, 2 or 4 threads. Scratch is
//! allocated once by the stage (per thread), so no task allocates.

pub use crate::state::disjoint::Disjoint;
use rayon::prelude::*;
use std::sync::Arc;

/// The threads of one run's 2-D stages: `None` runs serially.
#[derive(Debug, Clone, Default)]
pub struct Workers {
    pool: Option<Arc<rayon::ThreadPool>>,
}

impl Workers {
    /// `threads` ≤ 1: serial, no pool. More: a pool of that many threads.
    pub fn new(threads: usize) -> Result<Workers, String> {
        if threads <= 1 {
            return Ok(Workers::default());
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|k| format!("granflow-band-{k}"))
            .build()
            .map_err(|e| format!("cannot start {threads} threads: {e}"))?;
        Ok(Workers {
            pool: Some(Arc::new(pool)),
        })
    }

    /// Serial execution.
    pub fn serial() -> Workers {
        Workers::default()
    }

    /// `f(k)` for every band k < `bands`, in band order (for reductions combined in
    /// that order, whatever the number of threads).
    pub fn map_bands<T, F>(&self, bands: usize, f: F) -> Vec<T>
    where
        T: Send,
        F: Fn(usize) -> T + Sync + Send,
    {
        match &self.pool {
            None => (0..bands).map(f).collect(),
            Some(pool) => {
                pool.install(|| (0..bands).into_par_iter().with_max_len(1).map(f).collect())
            }
        }
    }

    /// Copies `src` into `dst` (the same length) band by band (chunks of `chunk`
    /// values): the run loop's copy of the state of t^n.
    pub fn copy(&self, chunk: usize, dst: &mut [f64], src: &[f64]) {
        assert_eq!(dst.len(), src.len(), "a copy between buffers of one length");
        match &self.pool {
            None => dst.copy_from_slice(src),
            Some(pool) => pool.install(|| {
                dst.par_chunks_mut(chunk)
                    .zip(src.par_chunks(chunk))
                    .with_max_len(1)
                    .for_each(|(d, s)| d.copy_from_slice(s));
            }),
        }
    }

    /// The number of threads (1 when serial): the run's tasks index per-thread scratch
    /// with [`Self::tiles`]'s first argument, below it.
    pub fn threads(&self) -> usize {
        self.pool.as_ref().map_or(1, |p| p.current_num_threads())
    }

    /// Calls `f(thread, t)` for every tile `t` of `tiles`, `thread` < [`Self::threads`]
    /// the index of the thread that runs it (for its scratch). Each tile is one task
    /// (`with_max_len(1)`): the threads share the tiles wherever the flow is, and a
    /// thread that runs out of work steals single tiles. A single tile runs on the
    /// caller's thread, with no hand-off to the pool (as thread 0 outside the pool,
    /// while the pool is idle).
    pub fn tiles<F>(&self, tiles: &[u32], f: F)
    where
        F: Fn(usize, usize) + Sync + Send,
    {
        match &self.pool {
            None => tiles.iter().for_each(|&t| f(0, t as usize)),
            Some(_) if tiles.len() <= 1 => {
                let thread = rayon::current_thread_index().unwrap_or(0);
                tiles.iter().for_each(|&t| f(thread, t as usize))
            }
            Some(pool) => pool.install(|| {
                tiles
                    .par_iter()
                    .with_max_len(1)
                    .for_each(|&t| f(rayon::current_thread_index().unwrap_or(0), t as usize))
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::panic::{catch_unwind, AssertUnwindSafe};
    use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

    #[test]
    fn every_task_runs_once_and_bands_come_back_in_order() {
        for threads in [1, 2, 4] {
            let w = Workers::new(threads).expect("a pool");
            assert_eq!(w.threads(), threads);
            // Many calls in a row, as the stages of a run's steps make them.
            for round in 0..200 {
                let n = 1 + round % 70;
                let tiles: Vec<u32> = (0..n as u32).map(|t| 3 * t).collect();
                let mut seen = vec![0usize; 3 * n];
                let d = Disjoint::new(&mut seen);
                let calls = AtomicUsize::new(0);
                w.tiles(&tiles, |thread, t| {
                    assert!(thread < threads);
                    calls.fetch_add(1, Relaxed);
                    // SAFETY: each tile is one task.
                    unsafe { d.set(t, d.get(t) + 1) };
                });
                assert_eq!(calls.load(Relaxed), n);
                assert!(seen
                    .iter()
                    .enumerate()
                    .all(|(t, &c)| c == usize::from(t % 3 == 0)));
                let squares = w.map_bands(n, |k| vec![k * k]);
                assert!(squares.iter().enumerate().all(|(k, v)| v == &[k * k]));
            }
            let src: Vec<f64> = (0..1000).map(f64::from).collect();
            let mut dst = vec![0.0; 1000];
            w.copy(64, &mut dst, &src);
            assert_eq!(dst, src);
        }
    }

    #[test]
    fn a_panic_in_a_task_reaches_the_caller_and_the_pool_goes_on() {
        let w = Workers::new(2).expect("a pool");
        let tiles: Vec<u32> = (0..64).collect();
        let caught = catch_unwind(AssertUnwindSafe(|| {
            w.tiles(&tiles, |_, t| assert!(t != 40, "task 40 fails"));
        }));
        assert!(caught.is_err());
        let done = AtomicUsize::new(0);
        w.tiles(&tiles, |_, _| {
            done.fetch_add(1, Relaxed);
        });
        assert_eq!(done.load(Relaxed), 64);
    }

    #[test]
    fn a_call_from_inside_a_task_runs_its_tasks() {
        let w = Workers::new(2).expect("a pool");
        let outer: Vec<u32> = (0..8).collect();
        let total = AtomicUsize::new(0);
        w.tiles(&outer, |_, _| {
            w.tiles(&outer, |_, _| {
                total.fetch_add(1, Relaxed);
            });
        });
        assert_eq!(total.load(Relaxed), 64);
    }
}
