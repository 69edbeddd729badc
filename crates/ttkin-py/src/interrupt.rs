//! Long calls that Ctrl-C can stop: the work runs without the GIL on a scoped thread while the
//! calling thread wakes every [`POLL`], takes the GIL and checks Python's signals. On a signal
//! the cancel flag the work receives is set; work that polls it between its items (balls, hits,
//! chunks) stops within one item, and the signal's exception (`KeyboardInterrupt`) is returned.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use pyo3::prelude::*;

/// How often the calling thread checks for a signal while the work runs.
pub const POLL: Duration = Duration::from_millis(50);

/// Runs `work(cancel)` without the GIL, checking Python's signals every [`POLL`]; returns its
/// result, or the signal's exception once the work has stopped. A panic in the work is resumed on
/// this thread (the boundary guard turns it into `InternalError`).
pub fn detach_interruptible<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&AtomicBool) -> T + Send,
{
    let cancel = AtomicBool::new(false);
    let (done_tx, done_rx) = mpsc::channel::<()>();
    std::thread::scope(|scope| {
        let cancel_ref = &cancel;
        let handle = scope.spawn(move || {
            let out = work(cancel_ref);
            let _ = done_tx.send(());
            out
        });
        let mut interrupted = None;
        let mut rx = done_rx;
        loop {
            // Ok: finished; Err(Disconnected): the work panicked (its sender dropped).
            let (back, finished) = py.detach(move || {
                let r = rx.recv_timeout(POLL);
                (rx, !matches!(r, Err(mpsc::RecvTimeoutError::Timeout)))
            });
            rx = back;
            if finished {
                break;
            }
            if interrupted.is_none() {
                if let Err(e) = py.check_signals() {
                    cancel.store(true, Ordering::Relaxed);
                    interrupted = Some(e);
                }
            }
        }
        let out = match handle.join() {
            Ok(out) => out,
            Err(panic) => std::panic::resume_unwind(panic),
        };
        match interrupted {
            Some(e) => Err(e),
            None => Ok(out),
        }
    })
}

/// Whether the work was asked to stop.
pub fn cancelled(cancel: &AtomicBool) -> bool {
    cancel.load(Ordering::Relaxed)
}
