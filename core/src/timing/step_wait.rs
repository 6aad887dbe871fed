//! How a step is waited for ([`StepWait`]): blocking, or deferred to a thread of the timer's that waits for
//! each step and notes when it completed.

use std::sync::{mpsc, Arc, Condvar, Mutex, OnceLock};
use std::time::{Duration, Instant};

use crate::error::GpuError;

/// How [`PassTimer::submit`] waits for a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum StepWait {
    /// Drain the queue, submit, wait for the step: its wall time is its own (the CLI, sweeps and tests).
    #[default]
    Blocking,
    /// Submit and return. A thread of the timer's waits for the step and notes when it completed; its wall
    /// time runs from when it could start (submitted, and everything submitted before it done) to its
    /// completion, so other work on the queue (the app's painting) stays out of it. Only the thread that
    /// waits blocks: the app's UI thread polls [`PassTimer::steps_in_flight`]. Not on the GL backend, whose
    /// waits hold the GL context's lock (every other call of the UI thread would wait behind them).
    Deferred,
}

/// The wall time of a deferred step, once its waiter saw it complete (an error when the wait failed).
pub(super) type StepSlot = Arc<OnceLock<Result<f64, String>>>;

pub(super) struct Waiting {
    /// The submission just before the step's: done when everything submitted before the step is.
    pub(super) before: wgpu::SubmissionIndex,
    pub(super) step: wgpu::SubmissionIndex,
    pub(super) submitted: Instant,
    pub(super) slot: StepSlot,
}

/// The thread that waits for deferred steps, and how many it has not seen complete.
pub(super) struct StepWaiter {
    jobs: mpsc::Sender<Waiting>,
    pending: Arc<(Mutex<usize>, Condvar)>,
}

impl StepWaiter {
    pub(super) fn new(device: wgpu::Device) -> StepWaiter {
        let (jobs, rx) = mpsc::channel::<Waiting>();
        let pending = Arc::new((Mutex::new(0usize), Condvar::new()));
        let counter = pending.clone();
        std::thread::Builder::new()
            .name("shadowlab step waiter".into())
            .spawn(move || {
                // Ends when the timer (the sender) is dropped.
                for w in rx {
                    let wait = |index: wgpu::SubmissionIndex| {
                        device
                            .poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })
                            .map(|_| Instant::now())
                            .map_err(|e| format!("waiting for a step failed: {e}"))
                    };
                    let wall = wait(w.before).and_then(|ready| {
                        let done = wait(w.step)?;
                        Ok(done.duration_since(ready.max(w.submitted)).as_secs_f64() * 1000.0)
                    });
                    let _ = w.slot.set(wall);
                    let (count, changed) = &*counter;
                    if let Ok(mut n) = count.lock() {
                        *n = n.saturating_sub(1);
                    }
                    changed.notify_all();
                }
            })
            .expect("a thread can be spawned");
        StepWaiter { jobs, pending }
    }

    /// Hand a step to the thread (counted in flight until it has seen it complete); false when the thread is
    /// gone.
    pub(super) fn send(&self, waiting: Waiting) -> bool {
        if let Ok(mut n) = self.pending.0.lock() {
            *n += 1;
        }
        if self.jobs.send(waiting).is_ok() {
            return true;
        }
        if let Ok(mut n) = self.pending.0.lock() {
            *n = n.saturating_sub(1);
        }
        false
    }

    pub(super) fn in_flight(&self) -> usize {
        self.pending.0.lock().map_or(0, |n| *n)
    }

    /// Wait until the thread has seen every step it was given complete (the GPU is idle when this is called,
    /// so this is the thread's own bookkeeping: it fails after `timeout` instead of hanging).
    pub(super) fn drain(&self, timeout: Duration) -> Result<(), GpuError> {
        let (count, changed) = &*self.pending;
        let guard = count.lock().map_err(|_| GpuError::Validation("the step waiter's lock is poisoned".into()))?;
        let (n, _) = changed
            .wait_timeout_while(guard, timeout, |n| *n > 0)
            .map_err(|_| GpuError::Validation("the step waiter's lock is poisoned".into()))?;
        if *n > 0 {
            return Err(GpuError::Validation(format!("{} steps were not seen to complete in {timeout:?}", *n)));
        }
        Ok(())
    }
}
