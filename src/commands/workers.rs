//! Independent simulations (evaluation scenes, single-object attempts, collection scenes) on
//! several threads at once, their results handed back in job order.
//!
//! Physics steps on one core, so one scene at a time leaves the other cores idle while the
//! arm moves. A job's result depends only on its own seeds and the network's weights, and the
//! network gives the same maps on one libtorch thread as on several, so running jobs side by
//! side changes no byte of what a command writes.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;

/// Threads for `jobs` independent jobs with `threads` cores, and the libtorch threads each
/// worker's network then gets.
pub(crate) fn plan(threads: u16, jobs: usize) -> (usize, u16) {
    let workers = usize::from(threads).min(jobs).max(1);
    let per_worker = (usize::from(threads) / workers).max(1);
    (workers, u16::try_from(per_worker).unwrap_or(u16::MAX))
}

/// Runs `work` on every job on `workers` threads, each with its own state from `start` (a
/// policy with its own copy of the network), and calls `done` on this thread with each result,
/// in job order. `work` returns `None` when a signal stopped it; the jobs after it are not
/// started, and the results finished before it still reach `done`, in order. The first error
/// (by job order) stops the handing out of jobs and is returned after every worker has stopped.
/// Returns the workers' states.
pub(crate) fn run_in_order<J, S, R>(
    jobs: &[J],
    workers: usize,
    start: impl Fn() -> anyhow::Result<S> + Sync,
    work: impl Fn(&mut S, &J) -> anyhow::Result<Option<R>> + Sync,
    mut done: impl FnMut(R),
) -> anyhow::Result<Vec<S>>
where
    J: Sync,
    S: Send,
    R: Send,
{
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let (sender, receiver) = mpsc::channel::<(usize, anyhow::Result<Option<R>>)>();
    let mut errors: BTreeMap<usize, anyhow::Error> = BTreeMap::new();
    let mut states = Vec::new();
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers.clamp(1, jobs.len().max(1)))
            .map(|_| {
                let sender = sender.clone();
                let (next, stop, start, work) = (&next, &stop, &start, &work);
                scope.spawn(move || -> anyhow::Result<S> {
                    let mut state = start().inspect_err(|_| stop.store(true, Ordering::SeqCst))?;
                    while !stop.load(Ordering::SeqCst) {
                        let j = next.fetch_add(1, Ordering::SeqCst);
                        let Some(job) = jobs.get(j) else { break };
                        let result = work(&mut state, job);
                        if !matches!(result, Ok(Some(_))) {
                            stop.store(true, Ordering::SeqCst);
                        }
                        // The receiver lives until every worker has been joined.
                        let _ = sender.send((j, result));
                    }
                    Ok(state)
                })
            })
            .collect();
        drop(sender);
        let mut pending: BTreeMap<usize, Option<R>> = BTreeMap::new();
        let mut due = 0;
        for (j, result) in receiver {
            match result {
                Ok(finished) => {
                    pending.insert(j, finished);
                }
                Err(e) => {
                    errors.insert(j, e);
                }
            }
            while let Some(finished) = pending.remove(&due) {
                due += 1;
                finished.into_iter().for_each(&mut done);
            }
        }
        // What finished after a failed job: kept, still in job order.
        pending.into_values().flatten().for_each(&mut done);
        for (i, handle) in handles.into_iter().enumerate() {
            match handle.join() {
                Ok(Ok(state)) => states.push(state),
                Ok(Err(e)) => {
                    errors.insert(usize::MAX - i, e);
                }
                Err(panic) => std::panic::resume_unwind(panic),
            }
        }
    });
    match errors.into_values().next() {
        Some(e) => Err(e),
        None => Ok(states),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_arrive_in_job_order_whichever_worker_finishes_first() {
        // Each job waits until every later one has finished, so with a worker per job they
        // finish last to first, whatever the scheduler does.
        let jobs: Vec<u64> = (0..4).collect();
        let finished = std::sync::Mutex::new(Vec::new());
        let changed = std::sync::Condvar::new();
        let mut seen = Vec::new();
        run_in_order(
            &jobs,
            jobs.len(),
            || Ok(()),
            |_, &j| {
                let mut done = finished.lock().unwrap();
                while done.len() < jobs.len() - 1 - j as usize {
                    let (next, timeout) = changed
                        .wait_timeout(done, std::time::Duration::from_secs(30))
                        .unwrap();
                    assert!(
                        !timeout.timed_out(),
                        "job {j} waited 30 s for the later jobs"
                    );
                    done = next;
                }
                done.push(j);
                changed.notify_all();
                Ok(Some(j * 10))
            },
            |r| seen.push(r),
        )
        .unwrap();
        assert_eq!(
            *finished.lock().unwrap(),
            [3, 2, 1, 0],
            "they finished out of order"
        );
        assert_eq!(seen, [0, 10, 20, 30], "their results arrived in job order");
    }

    #[test]
    fn a_stopped_job_keeps_what_finished_and_starts_nothing_after_it() {
        let jobs: Vec<u64> = (0..50).collect();
        let started = AtomicUsize::new(0);
        let mut seen = Vec::new();
        run_in_order(
            &jobs,
            1,
            || Ok(()),
            |_, &j| {
                started.fetch_add(1, Ordering::SeqCst);
                Ok((j != 3).then_some(j))
            },
            |r| seen.push(r),
        )
        .unwrap();
        assert_eq!(seen, [0, 1, 2]);
        assert_eq!(started.load(Ordering::SeqCst), 4);
    }

    #[test]
    fn the_first_error_by_job_order_is_returned() {
        let jobs: Vec<u64> = (0..8).collect();
        let out = run_in_order(
            &jobs,
            1,
            || Ok(()),
            |_, &j| match j {
                2 | 5 => Err(anyhow::anyhow!("job {j} failed")),
                _ => Ok(Some(j)),
            },
            |_| {},
        );
        assert_eq!(out.unwrap_err().to_string(), "job 2 failed");
    }

    #[test]
    fn workers_share_the_cores_and_libtorch_the_rest() {
        assert_eq!(plan(2, 10), (2, 1));
        assert_eq!(plan(2, 1), (1, 2));
        assert_eq!(plan(8, 3), (3, 2));
        assert_eq!(plan(1, 10), (1, 1));
        assert_eq!(plan(4, 0), (1, 4));
    }
}
