//! Long calls on a worker thread without the GIL, the calling thread forwarding progress and
//! watching for Ctrl-C.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, mpsc};
use std::time::Duration;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use rfta::Stage;

use crate::error;

/// A stage as the progress callback sees it: `(stage, done, of)`.
fn stage_tuple(stage: Stage) -> (String, usize, usize) {
    match stage {
        Stage::Initial => ("initial".into(), 0, 1),
        Stage::FineTune { round, of } => (format!("round {round}/{of}"), round - 1, of),
        Stage::Final => ("final".into(), 0, 1),
        Stage::Progress { done, of } => ("progress".into(), done, of),
        _ => ("stage".into(), 0, 1),
    }
}

/// Runs `work` on a worker thread without the GIL, while this thread forwards its stages to
/// `progress`, and on Ctrl-C (or an exception raised by `progress`) sets the cancel flag, waits
/// for the worker to stop and raises.
pub(crate) fn detached<T: Send>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce(&mut (dyn FnMut(Stage) + Send), &AtomicBool) -> rfta::Result<T> + Send,
) -> PyResult<T> {
    let cancel = AtomicBool::new(false);
    let (send, receive) = mpsc::channel::<Stage>();
    // Waited on without the GIL, so shared with the closure that runs detached.
    let receive = Mutex::new(receive);
    let mut raised: Option<PyErr> = None;
    let outcome = std::thread::scope(|scope| {
        let worker = scope.spawn(|| {
            let mut forward = move |stage: Stage| {
                let _ = send.send(stage);
            };
            work(&mut forward, &cancel)
        });
        loop {
            let next = py.detach(|| match receive.lock() {
                Ok(r) => r.recv_timeout(Duration::from_millis(100)),
                Err(_) => Err(mpsc::RecvTimeoutError::Disconnected),
            });
            match next {
                Ok(stage) => {
                    if let (Some(cb), None) = (progress, &raised)
                        && let Err(e) = cb.call1(stage_tuple(stage))
                    {
                        cancel.store(true, Ordering::Relaxed);
                        raised = Some(e);
                    }
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if raised.is_none()
                        && let Err(e) = py.check_signals()
                    {
                        cancel.store(true, Ordering::Relaxed);
                        raised = Some(e);
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
            }
        }
        py.detach(|| worker.join())
    });
    if let Some(e) = raised {
        return Err(e);
    }
    match outcome {
        Ok(result) => result.map_err(error),
        Err(_) => Err(PyRuntimeError::new_err(
            "rfta panicked (a bug: please report it with the input)",
        )),
    }
}
