//! Progress reports and cancellation for long calls, through one callback interface.

use pgvol_core::progress::Interrupt;

use crate::error::{Error, ErrorKind, Result};

/// Receives progress from a long library call and may ask it to stop.
///
/// A call announces each stage by name ("distance", "fit", "contour", …) and then reports the
/// fraction of that stage done, from any thread. When [`Progress::cancelled`] returns `true` the
/// call stops and returns an error of kind [`ErrorKind::Cancelled`]: it is asked between stages
/// and, in the long stages (distance sampling, contouring), each time a stage reports its
/// fraction, after which the stage's loops begin no further work.
pub trait Progress: Sync {
    /// A new stage begins.
    fn stage(&self, _name: &str) {}
    /// `done` of the current stage is finished, from 0 to 1.
    fn update(&self, _done: f64) {}
    /// The current stage has ended.
    fn finish(&self) {}
    /// Something the caller should know about a result that is still produced.
    fn warn(&self, _message: &str) {}
    /// Whether the caller wants the call to stop.
    fn cancelled(&self) -> bool {
        false
    }
}

/// Progress that reports nothing and never cancels.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {}

/// The cancellation error, or `Ok` to go on.
pub(crate) fn check(progress: &dyn Progress) -> Result<()> {
    if progress.cancelled() {
        Err(Error::new(ErrorKind::Cancelled, "cancelled"))
    } else {
        Ok(())
    }
}

/// A caller's progress as the stage crates' loops see it.
struct Forward<'a>(&'a dyn Progress);

impl Interrupt for Forward<'_> {
    fn update(&self, done: f64) {
        self.0.update(done);
    }
    fn cancelled(&self) -> bool {
        self.0.cancelled()
    }
}

/// Runs `work` as the stage `name` of `progress`, passing it the stage's interrupt, and checks
/// for cancellation before and after: a stage stopped inside its loops returns an incomplete
/// result, dropped here for the cancellation error.
pub(crate) fn stage<T>(
    progress: &dyn Progress,
    name: &str,
    work: impl FnOnce(&dyn Interrupt) -> T,
) -> Result<T> {
    check(progress)?;
    progress.stage(name);
    let out = work(&Forward(progress));
    progress.finish();
    check(progress)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

    struct Counting {
        stages: AtomicUsize,
        stop: AtomicBool,
    }

    impl Progress for Counting {
        fn stage(&self, _name: &str) {
            self.stages.fetch_add(1, Ordering::Relaxed);
        }
        fn cancelled(&self) -> bool {
            self.stop.load(Ordering::Relaxed)
        }
    }

    #[test]
    fn a_stage_runs_and_a_cancelled_one_does_not() {
        let p = Counting {
            stages: AtomicUsize::new(0),
            stop: AtomicBool::new(false),
        };
        assert_eq!(stage(&p, "a", |_| 7).unwrap(), 7);
        assert_eq!(p.stages.load(Ordering::Relaxed), 1);
        p.stop.store(true, Ordering::Relaxed);
        let e = stage(&p, "b", |_| unreachable!()).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Cancelled);
        assert_eq!(p.stages.load(Ordering::Relaxed), 1);
    }
}
