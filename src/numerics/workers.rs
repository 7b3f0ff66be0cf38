//! Threads inside one run: the tiles and bands of a 2-D stage run on a rayon pool that
//! the stages of one pipeline share and own.
//!
//! With one thread there is no pool and the work runs in order on the caller's thread
//! (no rayon at all). With more, each stepped tile (the stages, the maps, the copy of
//! the state: [`Workers::tiles`]) or band of rows (the diagnostics, whose sums go band
//! by band: [`Workers::map_bands`]) is one task. The threads of a pass over tiles take
//! its tasks in turn from a shared counter, heavy tiles (with flow) listed first, so
//! that the pass ends on light tiles and both threads end it together; the bands are
//! single tasks that a thread out of work steals. The partition does not depend on the
//! number of threads, each task writes only its own cells, and every reduction is
//! combined in a fixed order (band order for sums) or by an order-free rule (the first
//! minimum in cell order): the results are the same bits for 1, 2 or 4 threads.
//! Scratch is allocated once by the stage (per thread), so no task allocates.
//!
//! A raster run's time loop itself runs on one of the pool's threads
//! ([`Workers::install`], called by the run loop through `Model::workers`): a pass
//! then starts and ends on a thread that takes its share of the tasks, where a caller
//! outside the pool would hand each pass over and sleep until it ends.

pub use crate::state::disjoint::Disjoint;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
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

    /// Runs `f` on a thread of the pool (on the caller's without one), the caller
    /// waiting: the parallel passes `f` starts then begin and end on a thread of the
    /// pool, which takes its share of the tasks, instead of a caller that hands every
    /// pass to the pool and sleeps until it ends (two wake-ups per pass, tens of µs on
    /// a virtual machine).
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match &self.pool {
            None => f(),
            Some(pool) => pool.install(f),
        }
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

    /// [`Self::map_bands`] and [`Self::tiles`] in one pass: `band(k)` for every band
    /// k < `bands` (returned in band order) and `tile(t)` for every tile of `tiles`,
    /// one task each, the bands first. A pass whose bands are few and unequal (a flow
    /// in two or three bands of rows) keeps both threads busy with the tiles' tasks.
    pub fn map_bands_and_tiles<T, B, F>(
        &self,
        bands: usize,
        band: B,
        tiles: &[u32],
        tile: F,
    ) -> Vec<T>
    where
        T: Copy + Send,
        B: Fn(usize) -> T + Sync + Send,
        F: Fn(usize) + Sync + Send,
    {
        match &self.pool {
            None => {
                let out = (0..bands).map(&band).collect();
                tiles.iter().for_each(|&t| tile(t as usize));
                out
            }
            Some(pool) => {
                let mut out = vec![None; bands];
                let results = Disjoint::new(&mut out[..]);
                in_turn(pool, bands + tiles.len(), |_, k| {
                    match k.checked_sub(bands) {
                        // SAFETY: entry k is this task's alone.
                        None => unsafe { results.set(k, Some(band(k))) },
                        Some(i) => tile(tiles[i] as usize),
                    }
                });
                out.into_iter()
                    .map(|b| b.expect("a band's result"))
                    .collect()
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
    /// the index of the thread that runs it (for its scratch). Each tile is one task,
    /// and the threads take the tiles in turn in the order of `tiles` (pass the heavy
    /// ones first: `Tiles::stepped_by_load`), wherever the flow is. A single tile runs
    /// on the caller's thread, with no hand-off to the pool (as thread 0 outside the
    /// pool, while the pool is idle).
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
            Some(pool) => in_turn(pool, tiles.len(), |thread, i| f(thread, tiles[i] as usize)),
        }
    }
}

/// Calls `task(thread, i)` for every i < `n` on the threads of `pool`, each thread
/// taking the next index as it becomes free, in increasing order (a shared counter):
/// callers list the heavy tasks first, so that a pass ends on light ones, and a
/// thread that starts late finds the others' work already done rather than a half of
/// the list set aside for it. `thread` is the index of the thread in the pool.
fn in_turn(pool: &rayon::ThreadPool, n: usize, task: impl Fn(usize, usize) + Sync + Send) {
    let next = AtomicUsize::new(0);
    let threads = pool.current_num_threads().min(n);
    pool.install(|| {
        (0..threads).into_par_iter().with_max_len(1).for_each(|_| {
            let thread = rayon::current_thread_index().unwrap_or(0);
            loop {
                let i = next.fetch_add(1, Relaxed);
                if i >= n {
                    break;
                }
                task(thread, i);
            }
        })
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::panic::{catch_unwind, AssertUnwindSafe};

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
    fn bands_and_tiles_in_one_pass_run_each_once_and_bands_come_back_in_order() {
        for threads in [1, 2, 4] {
            let w = Workers::new(threads).expect("a pool");
            for round in 0..100 {
                let (bands, n) = (1 + round % 9, round % 40);
                let tiles: Vec<u32> = (0..n as u32).map(|t| 2 * t + 1).collect();
                let mut seen = vec![0usize; 2 * n + 1];
                let d = Disjoint::new(&mut seen);
                let sums = w.map_bands_and_tiles(
                    bands,
                    |k| k * 10,
                    &tiles,
                    // SAFETY: each tile is one task.
                    |t| unsafe { d.set(t, d.get(t) + 1) },
                );
                assert_eq!(sums, (0..bands).map(|k| k * 10).collect::<Vec<_>>());
                assert!(seen
                    .iter()
                    .enumerate()
                    .all(|(t, &c)| c == usize::from(t % 2 == 1)));
            }
        }
    }

    #[test]
    fn install_runs_on_a_thread_of_the_pool_and_its_passes_use_every_thread() {
        let w = Workers::new(2).expect("a pool");
        assert_eq!(rayon::current_thread_index(), None);
        let tiles: Vec<u32> = (0..64).collect();
        let used = w.install(|| {
            assert!(rayon::current_thread_index().is_some());
            let used: Vec<AtomicUsize> = (0..2).map(|_| AtomicUsize::new(0)).collect();
            w.tiles(&tiles, |thread, _| {
                // Long enough tasks that the second thread takes some.
                std::thread::sleep(std::time::Duration::from_micros(200));
                used[thread].fetch_add(1, Relaxed);
            });
            used.iter().map(|u| u.load(Relaxed)).collect::<Vec<_>>()
        });
        assert_eq!(used.iter().sum::<usize>(), 64);
        assert!(used.iter().all(|&u| u > 0), "{used:?}");
        assert_eq!(Workers::serial().install(|| 7), 7);
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
