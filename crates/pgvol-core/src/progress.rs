//! Fractions done of a long stage (contouring, a fit), reported from inside its loops to a
//! caller's progress display.

use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

/// Receives the fraction of a stage done, from 0 to 1, from any thread.
pub type Report<'a> = &'a (dyn Fn(f64) + Sync);

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
        (self.report)(self.from + fraction.clamp(0.0, 1.0) * (self.to - self.from));
    }

    /// Counts `total` items of work through this span.
    pub fn counter(self, total: usize) -> Counter<'a> {
        Counter {
            span: self,
            total: total.max(1),
            // About 200 reports per stage: smooth, and no contention on the callback.
            every: (total / 200).max(1),
            done: AtomicUsize::new(0),
        }
    }
}

/// Items of one stage done so far; reports every `every` items.
pub struct Counter<'a> {
    span: Span<'a>,
    total: usize,
    every: usize,
    done: AtomicUsize,
}

impl Counter<'_> {
    pub fn tick(&self) {
        let done = self.done.fetch_add(1, Relaxed) + 1;
        if done.is_multiple_of(self.every) || done == self.total {
            self.span
                .report(done.min(self.total) as f64 / self.total as f64);
        }
    }
}

/// Ticks `counter` when there is one.
pub fn tick(counter: Option<&Counter>) {
    if let Some(c) = counter {
        c.tick();
    }
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
}
