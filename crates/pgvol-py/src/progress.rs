//! Long calls run with the GIL released; their progress reaches an optional Python callback,
//! and Ctrl-C (or an exception raised by the callback) stops them at the library's next check.

use std::ffi::CString;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use pyo3::prelude::*;

use crate::errors;

/// The shortest time between two calls of the callback within a stage.
const REPORT_INTERVAL: Duration = Duration::from_millis(100);

/// The stage being run and when the callback last heard of it.
struct Stage {
    name: String,
    reported: Instant,
}

/// [`pgvol::Progress`] for a call from Python: forwards stages and fractions to `callback`
/// (`callback(stage, fraction)`), warnings to Python's `warnings` module, and asks for
/// cancellation when a signal handler raised (Ctrl-C) or the callback failed. The first Python
/// exception raised along the way is kept and re-raised by [`run`].
pub(crate) struct PyProgress {
    callback: Option<Py<PyAny>>,
    stage: Mutex<Stage>,
    error: Mutex<Option<PyErr>>,
}

impl PyProgress {
    fn new(callback: Option<Py<PyAny>>) -> Self {
        Self {
            callback,
            stage: Mutex::new(Stage {
                name: String::new(),
                reported: Instant::now(),
            }),
            error: Mutex::new(None),
        }
    }

    /// Runs Python's signal handlers (Ctrl-C raises KeyboardInterrupt, on the main thread),
    /// keeping the exception one raises.
    fn check_signals(&self) {
        Python::attach(|py| {
            if let Err(e) = py.check_signals() {
                self.fail(e);
            }
        });
    }

    /// Keeps the first Python exception.
    fn fail(&self, e: PyErr) {
        if let Ok(mut slot) = self.error.lock() {
            if slot.is_none() {
                *slot = Some(e);
            }
        }
    }

    fn failed(&self) -> bool {
        self.error.lock().map(|e| e.is_some()).unwrap_or(true)
    }

    fn take_error(&self) -> Option<PyErr> {
        self.error.lock().ok().and_then(|mut e| e.take())
    }

    fn stage_name(&self) -> String {
        self.stage
            .lock()
            .map(|s| s.name.clone())
            .unwrap_or_default()
    }

    /// Calls the callback with the GIL held, keeping its exception.
    fn report(&self, name: &str, done: f64) {
        let Some(callback) = &self.callback else {
            return;
        };
        if self.failed() {
            return;
        }
        Python::attach(|py| {
            if let Err(e) = callback.call1(py, (name, done)) {
                self.fail(e);
            }
        });
    }
}

impl pgvol::Progress for PyProgress {
    fn stage(&self, name: &str) {
        if let Ok(mut s) = self.stage.lock() {
            s.name = name.to_string();
            s.reported = Instant::now();
        }
        self.report(name, 0.0);
    }

    fn update(&self, done: f64) {
        if self.callback.is_none() {
            return;
        }
        let name = match self.stage.lock() {
            Ok(mut s) if s.reported.elapsed() >= REPORT_INTERVAL => {
                s.reported = Instant::now();
                s.name.clone()
            }
            _ => return,
        };
        self.report(&name, done.clamp(0.0, 1.0));
    }

    fn finish(&self) {
        self.report(&self.stage_name(), 1.0);
    }

    fn warn(&self, message: &str) {
        let text = CString::new(message.replace('\0', " ")).unwrap_or_default();
        Python::attach(|py| {
            let warned =
                errors::warning_class(py).and_then(|category| PyErr::warn(py, &category, &text, 1));
            if let Err(e) = warned {
                self.fail(e);
            }
        });
    }

    fn cancelled(&self) -> bool {
        // The calling thread runs the signal handlers meanwhile (`watching_signals`).
        self.failed()
    }
}

/// Runs `work` with the GIL released and a [`PyProgress`] for `callback`; an exception raised
/// by the callback or a signal handler wins over the library's result.
pub(crate) fn run<T: Send>(
    py: Python<'_>,
    callback: Option<Py<PyAny>>,
    work: impl FnOnce(&dyn pgvol::Progress) -> pgvol::Result<T> + Send,
) -> PyResult<T> {
    if let Some(cb) = &callback {
        if !cb.bind(py).is_callable() {
            return Err(errors::parameter(
                py,
                "progress must be a callable taking (stage, fraction)",
            ));
        }
    }
    let progress = PyProgress::new(callback);
    let out = py.detach(|| watching_signals(&progress, work));
    if let Some(e) = progress.take_error() {
        return Err(e);
    }
    out.map_err(|e| errors::to_py(py, e))
}

/// How often the calling thread runs Python's signal handlers while the work goes on.
const SIGNAL_POLL: Duration = Duration::from_millis(20);

/// Runs `work` on a thread of its own while this thread, the one the call came from, runs
/// Python's signal handlers every [`SIGNAL_POLL`]: Python runs them on its main thread alone,
/// which would otherwise wait in the library's parallel loops and see a Ctrl-C only between
/// stages. A handler's exception makes `progress` ask the work to stop.
fn watching_signals<T: Send>(
    progress: &PyProgress,
    work: impl FnOnce(&dyn pgvol::Progress) -> pgvol::Result<T> + Send,
) -> pgvol::Result<T> {
    let caller = std::thread::current();
    let done = AtomicBool::new(false);
    std::thread::scope(|scope| {
        let worker = scope.spawn(|| {
            let out = work(progress);
            done.store(true, Ordering::Release);
            caller.unpark();
            out
        });
        while !done.load(Ordering::Acquire) {
            std::thread::park_timeout(SIGNAL_POLL);
            if !done.load(Ordering::Acquire) {
                progress.check_signals();
            }
        }
        worker
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    })
}

/// Runs `work` with the GIL released, for calls with no progress to report and nothing to
/// cancel.
pub(crate) fn quiet<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> pgvol::Result<T> + Send,
) -> PyResult<T> {
    py.detach(work).map_err(|e| errors::to_py(py, e))
}
