//! The threads a reconstruction runs on, and how the idle ones wait for work.
//!
//! A reconstruction is thousands of parallel loops of a few thousand items each (every round's
//! octree, systems, relaxation sweeps, extraction and closest-point queries), separated by short
//! serial steps. Rayon lets an idle worker poll for about 30 yields and then sleep on a futex;
//! the next loop wakes it, and on a virtual machine that wake-up costs tens to hundreds of
//! microseconds, during which the loop runs on one thread. Between such short loops the workers
//! fall asleep and are woken again thousands of times per run (docs/speed.md, item 27).
//!
//! So while [`on_pool`]'s work runs, each other worker of the pool runs a waiter: it executes
//! whatever work it can take (`rayon::yield_now`) and keeps polling while there is none, until
//! [`ACTIVE_WAIT`] passes without work; then it leaves, and the worker sleeps as rayon has it.
//! The stages call [`waiters_back`] as they start, which brings the waiters that left back. This
//! is the active wait policy of OpenMP runtimes (`OMP_WAIT_POLICY=active`, `KMP_BLOCKTIME`), with
//! a short block time: a serial step costs the other cores at most [`ACTIVE_WAIT`] of polling,
//! and a long one (at 129^3 the components' judgement takes seconds on one thread) no more.
//! Which thread runs which part of a loop never changes a result: every loop's output is
//! ordered by its input, so the mesh is the same for any thread count.

use std::cell::{Cell, RefCell};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use crate::{Error, Result};

/// How long a waiter polls without finding work before it leaves: longer than the serial steps
/// between two parallel loops of a stage at 21^3 (the solver's coarse depths, a mesh index's
/// build: a few milliseconds), short against a stage at 129^3.
pub(crate) const ACTIVE_WAIT: Duration = Duration::from_millis(5);

/// The waiters of one run: how many are out, and whether the run is over.
struct Waiters {
    /// The pool's workers.
    workers: usize,
    /// The worker that runs the work (a waiter there leaves at once).
    owner: Option<usize>,
    /// Waiters spawned and not left yet.
    out: AtomicUsize,
    done: AtomicBool,
}

thread_local! {
    /// Whether this thread runs a waiter already (a waiter that takes another waiter as work
    /// leaves at once).
    static WAITING: Cell<bool> = const { Cell::new(false) };
    /// The waiters of the run this thread owns, for [`waiters_back`].
    static OWN: RefCell<Option<Arc<Waiters>>> = const { RefCell::new(None) };
}

/// How the process's global pool was started by [`start_global_pool`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GlobalPool {
    /// Its threads.
    pub threads: usize,
    /// What was asked for and where, when it was more than the cores and so was capped:
    /// `(count, "--threads")` or `(count, "RAYON_NUM_THREADS")`.
    pub capped: Option<(usize, &'static str)>,
}

/// The cores here: the most threads a pool gets (threads beyond them only cost, results never
/// depend on the count, and asking for 100,000 failed to start; hostile test E4).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
}

/// Starts rayon's global pool once for the process, with `asked` threads or else what
/// `RAYON_NUM_THREADS` says (a positive number; anything else is rayon's default of one per
/// core), at most [`cores`]: the one cap for every way of asking. A program calls it before any
/// parallel work; rayon would otherwise start the pool itself from `RAYON_NUM_THREADS`
/// uncapped, and panic where that many threads cannot start.
///
/// # Errors
/// [`Error::ThreadPool`] when the threads cannot be started (the pool was started already, or
/// the system refuses them).
pub fn start_global_pool(asked: Option<usize>) -> Result<GlobalPool> {
    let from_env = || {
        std::env::var("RAYON_NUM_THREADS")
            .ok()
            .and_then(|v| v.trim().parse::<usize>().ok())
            .filter(|&n| n > 0)
            .map(|n| (n, "RAYON_NUM_THREADS"))
    };
    let asked = asked.map(|n| (n.max(1), "--threads")).or_else(from_env);
    let cores = cores();
    let (threads, capped) = match asked {
        Some((n, from)) if n > cores => (cores, Some((n, from))),
        Some((n, _)) => (n, None),
        None => (cores, None),
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .map_err(|e| Error::ThreadPool {
            threads,
            reason: e.to_string(),
        })?;
    Ok(GlobalPool { threads, capped })
}

/// Runs `work` on `threads` workers (`None`: on a worker of the global pool, where the caller
/// is not on one already: each parallel loop then forks from inside the pool instead of being
/// injected into it), the pool's other workers waiting actively for its parallel loops.
pub(crate) fn on_pool<T: Send>(
    threads: Option<usize>,
    work: impl FnOnce() -> Result<T> + Send,
) -> Result<T> {
    let work = || with_waiters(work);
    match threads {
        None => rayon::scope(|_| work()),
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .map_err(|e| Error::ThreadPool {
                threads: t,
                reason: e.to_string(),
            })?
            .install(work),
    }
}

/// Brings back the waiters of the run on this thread that left for lack of work (nothing
/// outside a run, or with one worker). Called as each stage starts.
pub(crate) fn waiters_back() {
    OWN.with_borrow(|own| {
        if let Some(w) = own {
            w.fill();
        }
    });
}

/// Runs `work` on this worker with a waiter on each other worker of its pool; returns once
/// `work` has and every waiter has left (also when `work` panics).
fn with_waiters<T>(work: impl FnOnce() -> T) -> T {
    let workers = rayon::current_num_threads();
    if workers < 2 {
        return work();
    }
    let waiters = Arc::new(Waiters {
        workers,
        owner: rayon::current_thread_index(),
        out: AtomicUsize::new(0),
        done: AtomicBool::new(false),
    });
    /// Ends the run's waiting and restores the thread's previous run (a run inside a run).
    struct Run(Arc<Waiters>, Option<Arc<Waiters>>);
    impl Drop for Run {
        fn drop(&mut self) {
            self.0.done.store(true, Ordering::Release);
            // A waiter still queued here is taken and leaves at once; the others see `done`.
            while self.0.out.load(Ordering::Acquire) > 0 {
                if rayon::yield_now() != Some(rayon::Yield::Executed) {
                    std::thread::yield_now();
                }
            }
            OWN.set(self.1.take());
        }
    }
    let _run = Run(waiters.clone(), OWN.replace(Some(waiters.clone())));
    waiters.fill();
    work()
}

impl Waiters {
    /// Spawns waiters until one per other worker is out.
    fn fill(self: &Arc<Self>) {
        while self.out.load(Ordering::Acquire) + 1 < self.workers {
            self.out.fetch_add(1, Ordering::AcqRel);
            let w = self.clone();
            rayon::spawn(move || w.wait());
        }
    }

    /// A waiter: takes work from the pool until the run is done or [`ACTIVE_WAIT`] passes
    /// without any.
    fn wait(&self) {
        if rayon::current_thread_index() != self.owner && !WAITING.get() {
            WAITING.set(true);
            let mut idle_since: Option<Instant> = None;
            while !self.done.load(Ordering::Acquire) {
                if rayon::yield_now() == Some(rayon::Yield::Executed) {
                    idle_since = None;
                } else if idle_since.get_or_insert_with(Instant::now).elapsed() < ACTIVE_WAIT {
                    std::hint::spin_loop();
                } else {
                    break;
                }
            }
            WAITING.set(false);
        }
        self.out.fetch_sub(1, Ordering::AcqRel);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    /// Waiters out on the owner's thread's run.
    fn out() -> usize {
        OWN.with_borrow(|w| w.as_ref().map_or(0, |w| w.out.load(Ordering::Acquire)))
    }

    /// One waiter per other worker goes out, leaves after a serial step longer than the active
    /// wait, comes back with `waiters_back`, and all have left when `on_pool` returns (else this
    /// test hangs); the loops between still finish with the right sum (sum of i^2 for i < 10^5,
    /// (n - 1) n (2n - 1) / 6).
    #[test]
    fn waiters_leave_when_idle_and_come_back() -> Result<()> {
        for threads in [1, 2, 3] {
            let sums = on_pool(Some(threads), || {
                assert_eq!(
                    out(),
                    threads - 1,
                    "{threads} threads: waiters at the start"
                );
                let mut sums = Vec::new();
                for _ in 0..3 {
                    let t = Instant::now();
                    while out() > 0 && t.elapsed() < Duration::from_secs(5) {
                        std::thread::sleep(ACTIVE_WAIT / 4);
                    }
                    assert_eq!(out(), 0, "{threads} threads: a waiter stayed without work");
                    waiters_back();
                    assert_eq!(out(), threads - 1, "{threads} threads: waiters not back");
                    sums.push((0..100_000u64).into_par_iter().map(|i| i * i).sum::<u64>());
                }
                Ok(sums)
            })?;
            assert_eq!(sums, vec![333_328_333_350_000; 3]);
            assert!(OWN.with_borrow(Option::is_none));
        }
        Ok(())
    }
}
