//! Progress bars on standard error, one per stage of a library call.

use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressStyle};

/// Bars for the stages the library announces, hidden when quiet or when standard error is not
/// a terminal.
pub struct Bars {
    quiet: bool,
    current: Mutex<Option<ProgressBar>>,
}

/// Steps per bar: fine enough for a smooth bar, coarse enough to redraw rarely.
const STEPS: u64 = 1000;

impl Bars {
    pub fn new(quiet: bool) -> Self {
        Self {
            quiet,
            current: Mutex::new(None),
        }
    }

    fn with_bar(&self, f: impl FnOnce(&mut Option<ProgressBar>)) {
        if let Ok(mut bar) = self.current.lock() {
            f(&mut bar);
        }
    }
}

impl pgvol::Progress for Bars {
    fn stage(&self, name: &str) {
        if self.quiet {
            return;
        }
        let pb = ProgressBar::new(STEPS);
        pb.set_style(
            ProgressStyle::with_template("{msg:>12} [{bar:40}] {percent:>3}% {elapsed}")
                .expect("static template")
                .progress_chars("=> "),
        );
        pb.set_message(name.to_string());
        self.with_bar(|bar| *bar = Some(pb));
    }

    fn update(&self, done: f64) {
        self.with_bar(|bar| {
            if let Some(pb) = bar {
                pb.set_position((done.clamp(0.0, 1.0) * STEPS as f64) as u64);
            }
        });
    }

    fn warn(&self, message: &str) {
        crate::report::record(message);
        if !self.quiet {
            self.with_bar(|bar| match bar {
                Some(pb) => pb.suspend(|| eprintln!("warning: {message}")),
                None => eprintln!("warning: {message}"),
            });
        }
    }

    fn finish(&self) {
        self.with_bar(|bar| {
            if let Some(pb) = bar.take() {
                pb.finish_and_clear();
            }
        });
    }
}
