//! Threads inside one run: the tiles and bands of a 2-D stage run on a small pool of
//! threads that the stages of one pipeline share and own.
//!
//! With one thread there is no pool and the work runs in order on the caller's thread.
//! With N, the caller and N − 1 helper threads share each call's tasks: each stepped
//! tile (the stages, the maps, the copy of the state: [`Workers::tiles`]) or band of
//! rows (the diagnostics, whose sums go band by band: [`Workers::map_bands`]) is one
//! task, and a thread that finishes one takes the next not yet taken (one atomic
//! counter), so the dry and wet parts of a run balance. The partition does not depend
//! on the number of threads, each task writes only its own cells, and every reduction
//! is combined in a fixed order (band order for sums) or by an order-free rule (the
//! first minimum in cell order): the results are the same bits for 1, 2 or 4 threads.
//! Scratch is allocated once by the stage (per thread), so no task allocates.
//!
//! Why not a general work-stealing pool: a step of a raster run that follows the flow
//! is about seven parallel calls of under 3 ms each, over a few dozen tiles. A call
//! that hands its work to a pool and sleeps until the pool is done costs two wake-ups
//! across threads, and the caller's thread sits idle while it waits. Here the caller
//! works on the call's tasks itself, and a helper waits for the next call by spinning
//! briefly, then yielding, then sleeping (it is woken by the next call), so back-to-back
//! calls within a step cost an atomic store and a few loads.

use std::any::Any;
use std::ops::Range;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering::*};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, TryLockError};
use std::thread::JoinHandle;

/// Waits of a helper between calls: a few spin-loop hints and yields of its core (the
/// caller's serial work between two calls of a step is short), then sleep. Long spins
/// cost more than they save on a shared machine: a helper that spent its time slices
/// spinning is scheduled late when it holds a tile the caller waits for.
const SPINS: u32 = 1 << 6;
const YIELDS: u32 = 1 << 5;

/// The threads of one run's 2-D stages: `None` runs serially.
#[derive(Debug, Clone, Default)]
pub struct Workers {
    pool: Option<Arc<Pool>>,
}

/// A call's tasks as the helpers see them: `f(thread, task)` for task < `tasks`.
#[derive(Clone, Copy)]
struct Job {
    f: &'static (dyn Fn(usize, usize) + Sync),
    tasks: usize,
}

/// What the caller and the helpers share.
struct Shared {
    /// Bumped by every call (the helpers wait for it to change).
    generation: AtomicU64,
    /// The call's tasks may be taken (set once the job is in place, cleared when the
    /// caller has found no task left).
    open: AtomicBool,
    /// The next task not yet taken.
    next: AtomicUsize,
    /// Helpers inside the current call: the caller returns once it is 0.
    active: AtomicUsize,
    job: Mutex<Option<Job>>,
    /// The first panic of a helper's task, re-raised on the caller's thread.
    panic: Mutex<Option<Box<dyn Any + Send>>>,
    /// Sleeping helpers, woken by the next call.
    sleepers: AtomicUsize,
    sleep: Mutex<()>,
    wake: Condvar,
    shutdown: AtomicBool,
}

/// The helper threads of a [`Workers`] and the lock that lets one call at a time use them.
struct Pool {
    threads: usize,
    shared: Arc<Shared>,
    helpers: Vec<JoinHandle<()>>,
    caller: Mutex<()>,
}

impl std::fmt::Debug for Pool {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Pool({} threads)", self.threads)
    }
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Shared {
    /// Takes and runs tasks of `job` on thread `thread` until none is left.
    fn work(&self, job: Job, thread: usize) {
        loop {
            let k = self.next.fetch_add(1, Relaxed);
            if k >= job.tasks {
                return;
            }
            (job.f)(thread, k);
        }
    }

    /// Helper `thread`'s life: wait for a call, join it, until the pool is dropped.
    fn helper(&self, thread: usize) {
        let mut seen = self.generation.load(Acquire);
        loop {
            let mut waits = 0u32;
            loop {
                if self.shutdown.load(Acquire) {
                    return;
                }
                let g = self.generation.load(Acquire);
                if g != seen {
                    seen = g;
                    break;
                }
                waits += 1;
                if waits < SPINS {
                    std::hint::spin_loop();
                } else if waits < SPINS + YIELDS {
                    std::thread::yield_now();
                } else {
                    let guard = lock(&self.sleep);
                    self.sleepers.fetch_add(1, SeqCst);
                    // Checked under the lock the caller takes to wake: no lost wake-up.
                    let guard =
                        if self.generation.load(SeqCst) == seen && !self.shutdown.load(SeqCst) {
                            self.wake.wait(guard).unwrap_or_else(|e| e.into_inner())
                        } else {
                            guard
                        };
                    self.sleepers.fetch_sub(1, SeqCst);
                    drop(guard);
                    waits = 0;
                }
            }
            // Join the call if its tasks are still open (else it is over: wait again).
            self.active.fetch_add(1, SeqCst);
            if self.open.load(SeqCst) {
                let job = *lock(&self.job);
                if let Some(job) = job {
                    if let Err(p) = catch_unwind(AssertUnwindSafe(|| self.work(job, thread))) {
                        lock(&self.panic).get_or_insert(p);
                    }
                }
            }
            self.active.fetch_sub(1, SeqCst);
        }
    }
}

impl Pool {
    fn new(threads: usize) -> Result<Pool, String> {
        let shared = Arc::new(Shared {
            generation: AtomicU64::new(0),
            open: AtomicBool::new(false),
            next: AtomicUsize::new(0),
            active: AtomicUsize::new(0),
            job: Mutex::new(None),
            panic: Mutex::new(None),
            sleepers: AtomicUsize::new(0),
            sleep: Mutex::new(()),
            wake: Condvar::new(),
            shutdown: AtomicBool::new(false),
        });
        let mut pool = Pool {
            threads,
            shared,
            helpers: Vec::with_capacity(threads - 1),
            caller: Mutex::new(()),
        };
        for thread in 1..threads {
            let shared = Arc::clone(&pool.shared);
            let helper = std::thread::Builder::new()
                .name(format!("granflow-band-{thread}"))
                .spawn(move || shared.helper(thread))
                .map_err(|e| format!("cannot start {threads} threads: {e}"))?;
            pool.helpers.push(helper);
        }
        Ok(pool)
    }

    /// `f(thread, k)` for every task k < `tasks`, shared by the caller (thread 0) and
    /// the helpers. A second call while one runs (from another thread, or from inside a
    /// task) runs its tasks serially on its own thread: the same results.
    fn run(&self, tasks: usize, f: &(dyn Fn(usize, usize) + Sync)) {
        let _one_call = match self.caller.try_lock() {
            Ok(guard) => guard,
            Err(TryLockError::Poisoned(e)) => e.into_inner(),
            Err(TryLockError::WouldBlock) => {
                (0..tasks).for_each(|k| f(0, k));
                return;
            }
        };
        if tasks <= 1 {
            (0..tasks).for_each(|k| f(0, k));
            return;
        }
        // SAFETY: the helpers call `f` only while they are counted in `active` and the
        // call is open, and this function returns (ending `f`'s borrow) only once the
        // call is closed and `active` is 0; the job is cleared before the return.
        let f: &'static (dyn Fn(usize, usize) + Sync) = unsafe { std::mem::transmute(f) };
        let s = &*self.shared;
        *lock(&s.job) = Some(Job { f, tasks });
        s.next.store(0, SeqCst);
        s.open.store(true, SeqCst);
        s.generation.fetch_add(1, SeqCst);
        if s.sleepers.load(SeqCst) > 0 {
            let _guard = lock(&s.sleep);
            s.wake.notify_all();
        }
        let mine = catch_unwind(AssertUnwindSafe(|| s.work(Job { f, tasks }, 0)));
        s.open.store(false, SeqCst);
        let mut waits = 0u32;
        while s.active.load(SeqCst) != 0 {
            waits += 1;
            if waits < SPINS {
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
        *lock(&s.job) = None;
        if let Err(p) = mine {
            resume_unwind(p);
        }
        if let Some(p) = lock(&s.panic).take() {
            resume_unwind(p);
        }
    }
}

impl Drop for Pool {
    fn drop(&mut self) {
        self.shared.shutdown.store(true, SeqCst);
        {
            let _guard = lock(&self.shared.sleep);
            self.shared.wake.notify_all();
        }
        for helper in self.helpers.drain(..) {
            let _ = helper.join();
        }
    }
}

/// A pointer to a slice's elements that the tasks of one call write at disjoint
/// indices (for results of any type, [`Workers::map_bands`]).
struct Slots<T>(*mut T);
// SAFETY: each task writes its own index only (see `map_bands`).
unsafe impl<T: Send> Sync for Slots<T> {}

impl Workers {
    /// `threads` ≤ 1: serial, no pool. More: the caller and `threads` − 1 helpers.
    pub fn new(threads: usize) -> Result<Workers, String> {
        if threads <= 1 {
            return Ok(Workers::default());
        }
        Ok(Workers {
            pool: Some(Arc::new(Pool::new(threads)?)),
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
                let mut out: Vec<Option<T>> = (0..bands).map(|_| None).collect();
                let slots = Slots(out.as_mut_ptr());
                let slots = &slots;
                // SAFETY: task k writes slot k < bands alone, and `out` outlives the call.
                pool.run(bands, &|_, k| unsafe { *slots.0.add(k) = Some(f(k)) });
                out.into_iter()
                    .map(|v| v.expect("every band computed"))
                    .collect()
            }
        }
    }

    /// Copies `src` into `dst` (the same length) in chunks of `chunk` values, one task
    /// each: the run loop's copy of the state of t^n.
    pub fn copy(&self, chunk: usize, dst: &mut [f64], src: &[f64]) {
        assert_eq!(dst.len(), src.len(), "a copy between buffers of one length");
        match &self.pool {
            None => dst.copy_from_slice(src),
            Some(pool) => {
                let n = src.len();
                let d = Disjoint::new(dst);
                pool.run(n.div_ceil(chunk.max(1)), &|_, k| {
                    let cells = k * chunk..((k + 1) * chunk).min(n);
                    // SAFETY: chunk k is this task's alone.
                    unsafe { d.slice(cells.clone()) }.copy_from_slice(&src[cells]);
                });
            }
        }
    }

    /// The number of threads (1 when serial): the run's tasks index per-thread scratch
    /// with [`Self::tiles`]'s first argument, below it.
    pub fn threads(&self) -> usize {
        self.pool.as_ref().map_or(1, |p| p.threads)
    }

    /// Calls `f(thread, t)` for every tile `t` of `tiles`, `thread` < [`Self::threads`]
    /// the index of the thread that runs it (for its scratch). Each tile is one task:
    /// the threads share the tiles wherever the flow is, each taking the next tile not
    /// yet taken.
    pub fn tiles<F>(&self, tiles: &[u32], f: F)
    where
        F: Fn(usize, usize) + Sync + Send,
    {
        match &self.pool {
            None => tiles.iter().for_each(|&t| f(0, t as usize)),
            Some(pool) => pool.run(tiles.len(), &|thread, k| f(thread, tiles[k] as usize)),
        }
    }
}

/// A slice that the tasks of one parallel call write at disjoint indices (each task
/// its own tile's cells, which are not contiguous in a row-major array).
///
/// The caller of [`Disjoint::set`] and [`Disjoint::get`] guarantees that while the
/// parallel call runs, no index written by one task is read or written by another:
/// the tiles of a stepped set are disjoint, and a task touches its own tile's cells and
/// its own entry of per-tile arrays only.
pub struct Disjoint<'a, T> {
    ptr: *mut T,
    len: usize,
    _slice: std::marker::PhantomData<&'a mut [T]>,
}

// SAFETY: the tasks access disjoint indices (the type's contract), so sharing the
// pointer between threads is sharing `&mut` to disjoint parts of the slice.
unsafe impl<T: Send> Send for Disjoint<'_, T> {}
unsafe impl<T: Send> Sync for Disjoint<'_, T> {}

impl<'a, T: Copy> Disjoint<'a, T> {
    /// The slice `s`, borrowed for the parallel call.
    pub fn new(s: &'a mut [T]) -> Self {
        Disjoint {
            ptr: s.as_mut_ptr(),
            len: s.len(),
            _slice: std::marker::PhantomData,
        }
    }

    /// Writes `v` at index `i` (bounds-checked).
    ///
    /// # Safety
    /// No other task reads or writes index `i` during the parallel call.
    #[inline(always)]
    pub unsafe fn set(&self, i: usize, v: T) {
        assert!(i < self.len, "index {i} out of {}", self.len);
        // SAFETY: in bounds (checked), and exclusive to this task (the caller's contract).
        unsafe { *self.ptr.add(i) = v }
    }

    /// The elements `range` as one slice (bounds-checked), for copies of whole rows.
    ///
    /// # Safety
    /// No other task reads or writes an index of `range` while the slice lives.
    #[inline(always)]
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn slice(&self, range: Range<usize>) -> &mut [T] {
        assert!(
            range.start <= range.end && range.end <= self.len,
            "range {range:?} out of {}",
            self.len
        );
        // SAFETY: in bounds (checked), and exclusive to this task (the caller's contract).
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.len()) }
    }

    /// Reads index `i` (bounds-checked).
    ///
    /// # Safety
    /// No other task writes index `i` during the parallel call.
    #[inline(always)]
    pub unsafe fn get(&self, i: usize) -> T {
        assert!(i < self.len, "index {i} out of {}", self.len);
        // SAFETY: in bounds (checked), and not written by another task (the contract).
        unsafe { *self.ptr.add(i) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;

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
    fn a_call_from_inside_a_task_runs_serially() {
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
