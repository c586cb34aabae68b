//! Long calls run with the GIL released; their progress reaches an optional Python callback,
//! and Ctrl-C (or an exception raised by the callback) stops them at the library's next check.

use std::ffi::CString;
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
    /// The thread the call came from: the only one whose signal checks can run a handler.
    caller: std::thread::ThreadId,
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
            caller: std::thread::current().id(),
        }
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
        if self.failed() {
            return true;
        }
        // Python runs signal handlers on its main thread alone, so the library's worker threads
        // do not take the GIL to ask: it would only be taken from Python threads that run
        // meanwhile (a timer about to send the signal, say), row after row.
        if std::thread::current().id() != self.caller {
            return false;
        }
        // Runs the signal handlers: Ctrl-C raises KeyboardInterrupt here (on the main thread).
        Python::attach(|py| match py.check_signals() {
            Ok(()) => false,
            Err(e) => {
                self.fail(e);
                true
            }
        })
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
    let out = py.detach(|| work(&progress));
    if let Some(e) = progress.take_error() {
        return Err(e);
    }
    out.map_err(|e| errors::to_py(py, e))
}

/// Runs `work` with the GIL released, for calls with no progress to report and nothing to
/// cancel.
pub(crate) fn quiet<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> pgvol::Result<T> + Send,
) -> PyResult<T> {
    py.detach(work).map_err(|e| errors::to_py(py, e))
}
