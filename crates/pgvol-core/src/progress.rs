//! Fractions done of a long stage (sampling, a fit, contouring), reported from inside its loops
//! to a caller's progress display, and the caller's request to stop, polled by those loops.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering::Relaxed};

/// What a long stage's loops talk to, from any thread: they report the fraction done and poll
/// whether the caller wants them to stop. A stopped stage skips its remaining work and returns
/// an incomplete result, which the caller (who asked for the stop) discards.
pub trait Interrupt: Sync {
    /// `done` of the stage is finished, from 0 to 1.
    fn update(&self, _done: f64) {}
    /// Whether the caller wants the stage to stop.
    fn cancelled(&self) -> bool {
        false
    }
}

/// A fraction callback is an interrupt that never stops.
impl<F: Fn(f64) + Sync> Interrupt for F {
    fn update(&self, done: f64) {
        self(done)
    }
}

/// Reports nothing and never stops.
pub const QUIET: &dyn Interrupt = &|_: f64| {};

/// The stage's interrupt.
pub type Report<'a> = &'a dyn Interrupt;

/// A part `[from, to]` of the whole call's fraction, given to one stage of it.
#[derive(Clone, Copy)]
pub struct Span<'a> {
    report: Report<'a>,
    from: f64,
    to: f64,
}

impl<'a> Span<'a> {
    pub fn whole(report: Report<'a>) -> Self {
        Self {
            report,
            from: 0.0,
            to: 1.0,
        }
    }

    /// The part of this span between fractions `a` and `b` of it.
    pub fn part(self, a: f64, b: f64) -> Self {
        let width = self.to - self.from;
        Self {
            from: self.from + a * width,
            to: self.from + b * width,
            ..self
        }
    }

    /// Reports `fraction` of this span done.
    pub fn report(&self, fraction: f64) {
        self.report
            .update(self.from + fraction.clamp(0.0, 1.0) * (self.to - self.from));
    }

    /// Whether the caller wants the stage to stop.
    pub fn cancelled(&self) -> bool {
        self.report.cancelled()
    }

    /// Counts `total` items of work through this span.
    pub fn counter(self, total: usize) -> Counter<'a> {
        Counter {
            span: self,
            total: total.max(1),
            // About 200 reports per stage: smooth, and no contention on the callback.
            every: (total / 200).max(1),
            done: AtomicUsize::new(0),
            stop: AtomicBool::new(false),
        }
    }
}

/// A span is the interrupt of the part of the work it covers: what a sub-stage reports lands
/// within the span, and its stop requests are the caller's.
impl Interrupt for Span<'_> {
    fn update(&self, done: f64) {
        self.report(done);
    }
    fn cancelled(&self) -> bool {
        self.report.cancelled()
    }
}

/// Items of one stage done so far; reports every `every` items, and polls the caller's stop
/// request as often.
pub struct Counter<'a> {
    span: Span<'a>,
    total: usize,
    every: usize,
    done: AtomicUsize,
    stop: AtomicBool,
}

impl Counter<'_> {
    pub fn tick(&self) {
        let done = self.done.fetch_add(1, Relaxed) + 1;
        if done.is_multiple_of(self.every) || done == self.total {
            self.span
                .report(done.min(self.total) as f64 / self.total as f64);
            if self.span.cancelled() {
                self.stop.store(true, Relaxed);
            }
        }
    }

    /// Whether the caller asked to stop, as of the last poll: items not yet begun are skipped.
    pub fn stopped(&self) -> bool {
        self.stop.load(Relaxed)
    }
}

/// Ticks `counter` when there is one.
pub fn tick(counter: Option<&Counter>) {
    if let Some(c) = counter {
        c.tick();
    }
}

/// Whether `counter`'s caller asked to stop (never without a counter).
pub fn stopped(counter: Option<&Counter>) -> bool {
    counter.is_some_and(Counter::stopped)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[test]
    fn a_counter_reports_rising_fractions_within_its_span_and_ends_at_its_end() {
        let seen = Mutex::new(Vec::new());
        let report = |f: f64| seen.lock().unwrap().push(f);
        let span = Span::whole(&report).part(0.5, 1.0).part(0.0, 0.5);
        let counter = span.counter(1000);
        for _ in 0..1000 {
            counter.tick();
        }
        let seen = seen.into_inner().unwrap();
        assert!(
            seen.len() >= 100 && seen.len() <= 201,
            "{} reports",
            seen.len()
        );
        assert!(seen.windows(2).all(|w| w[0] < w[1]));
        assert!(seen[0] > 0.5 && *seen.last().unwrap() == 0.75);
    }

    /// Stops after its first report.
    struct StopAtOnce(AtomicUsize);

    impl Interrupt for StopAtOnce {
        fn update(&self, _done: f64) {
            self.0.fetch_add(1, Relaxed);
        }
        fn cancelled(&self) -> bool {
            self.0.load(Relaxed) > 0
        }
    }

    #[test]
    fn a_counter_stops_the_items_after_the_poll_that_sees_the_request() {
        let interrupt = StopAtOnce(AtomicUsize::new(0));
        let counter = Span::whole(&interrupt).counter(10_000);
        let mut worked = 0;
        for _ in 0..10_000 {
            if counter.stopped() {
                continue;
            }
            worked += 1;
            counter.tick();
        }
        // The first poll, after `every` = 50 items, sees the request; nothing runs after it.
        assert_eq!(worked, 50);
        assert!(!Span::whole(QUIET).counter(10).stopped());
    }
}
