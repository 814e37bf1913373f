//! Long library calls from Python: run on a worker thread with the GIL released (other Python
//! threads run meanwhile), report progress to an optional Python callback, and stop on Ctrl-C.
//!
//! The calling thread waits for the worker in steps of [`POLL`], taking the GIL between steps
//! only to let Python handle its signals: a `KeyboardInterrupt` (Ctrl-C in a notebook or a
//! terminal) asks the call to stop through [`Progress::cancelled`], waits for it to return
//! (every long call checks it between its steps) and is raised. An exception raised by the
//! progress callback stops the call the same way and is raised in its place.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use pyo3::prelude::*;
use sandjumper_output::Progress;

/// How often the waiting thread looks at Python's signals.
const POLL: Duration = Duration::from_millis(50);

/// The shortest interval between two `advance` reports to the callback (stage starts and ends
/// are always reported): a 10,000-jump sweep calls back a few times a second, not 10,000 times.
const REPORT_EVERY: Duration = Duration::from_millis(100);

/// Where a stage stands.
#[derive(Default)]
struct Stage {
    what: String,
    len: Option<u64>,
    done: u64,
    reported: Option<Instant>,
}

/// A [`Progress`] for one Python call: `callback(stage, done, total)` (`total` None when the
/// stage's length is not known), notes to `logging.getLogger("sandjumper")`, and the
/// cancellation flag the waiting thread sets.
pub struct PyProgress {
    callback: Option<Py<PyAny>>,
    cancel: AtomicBool,
    stage: Mutex<Stage>,
    /// The first exception the callback raised.
    error: Mutex<Option<PyErr>>,
}

impl PyProgress {
    /// A progress reporting to `callback` (None: nowhere).
    pub fn new(callback: Option<Py<PyAny>>) -> Self {
        Self {
            callback,
            cancel: AtomicBool::new(false),
            stage: Mutex::new(Stage::default()),
            error: Mutex::new(None),
        }
    }

    fn report(&self, force: bool) {
        let Some(callback) = &self.callback else {
            return;
        };
        // Once the callback raised, it is not called again.
        if self
            .error
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .is_some()
        {
            return;
        }
        let (what, done, len) = {
            let mut s = self.stage.lock().unwrap_or_else(|e| e.into_inner());
            let now = Instant::now();
            if !force && s.reported.is_some_and(|t| now - t < REPORT_EVERY) {
                return;
            }
            s.reported = Some(now);
            (s.what.clone(), s.done, s.len)
        };
        Python::attach(|py| {
            if let Err(e) = callback.call1(py, (what, done, len)) {
                self.fail(e);
            }
        });
    }

    /// Stop the call because of `e`, raised when it returns.
    fn fail(&self, e: PyErr) {
        let mut error = self.error.lock().unwrap_or_else(|e| e.into_inner());
        if error.is_none() {
            *error = Some(e);
        }
        self.cancel.store(true, Ordering::Relaxed);
    }
}

impl Progress for PyProgress {
    fn start(&self, what: &str, len: Option<u64>) {
        {
            let mut s = self.stage.lock().unwrap_or_else(|e| e.into_inner());
            *s = Stage {
                what: what.to_string(),
                len,
                done: 0,
                reported: None,
            };
        }
        self.report(true);
    }

    fn advance(&self, n: u64) {
        self.stage.lock().unwrap_or_else(|e| e.into_inner()).done += n;
        self.report(false);
    }

    fn finish(&self) {
        // The steps done as they were counted: a stage that stopped early ends short.
        self.report(true);
    }

    fn note(&self, line: &str) {
        Python::attach(|py| {
            if let Err(e) = log_note(py, line) {
                self.fail(e);
            }
        });
    }

    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
}

/// Run `f` on a worker thread with the GIL released, reporting to `callback`, and stop it on
/// Ctrl-C (see the module's documentation). `f`'s own result is returned as it is; a
/// `KeyboardInterrupt` or the callback's exception take its place when they stopped it.
pub fn long_call<R, F>(py: Python<'_>, callback: Option<Py<PyAny>>, f: F) -> PyResult<R>
where
    R: Send,
    F: FnOnce(&PyProgress) -> R + Send,
{
    let progress = PyProgress::new(callback);
    let mut interrupt: Option<PyErr> = None;
    let result = std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel();
        let progress = &progress;
        let worker = scope.spawn(move || {
            // The receiver outlives the worker: a failed send cannot happen.
            let _ = tx.send(f(progress));
        });
        let mut rx = rx;
        let got = loop {
            // The receiver goes into the GIL-free wait and comes back (it is not `Sync`).
            let (received, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
            rx = back;
            match received {
                Ok(r) => break Some(r),
                Err(mpsc::RecvTimeoutError::Disconnected) => break None,
                Err(mpsc::RecvTimeoutError::Timeout) => {}
            }
            if interrupt.is_none()
                && let Err(e) = py.check_signals()
            {
                // Ctrl-C: ask the call to stop, then go on waiting for it to return.
                progress.cancel.store(true, Ordering::Relaxed);
                interrupt = Some(e);
            }
        };
        // Joined here, a panic of the worker is this call's error, not the scope's panic.
        let joined = py.detach(|| worker.join());
        got.filter(|_| joined.is_ok())
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    if let Some(e) = progress
        .error
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .take()
    {
        return Err(e);
    }
    result.ok_or_else(|| {
        pyo3::exceptions::PyRuntimeError::new_err("the call's worker thread panicked")
    })
}

/// A library's note `line` on the `sandjumper` logger: a line the command line prints as
/// `warning: ...` at WARNING (shown by Python's default logging), any other at INFO.
pub fn log_note(py: Python<'_>, line: &str) -> PyResult<()> {
    let level = if line.starts_with("warning:") {
        "warning"
    } else {
        "info"
    };
    py.import("logging")?
        .call_method1("getLogger", ("sandjumper",))?
        .call_method1(level, (line,))?;
    Ok(())
}
