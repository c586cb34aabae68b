//! A cancel takes effect inside a long stage, not only between stages: once the caller's
//! progress says stop, the stage's loops begin no further work (counted here by the fraction
//! reports, which come every few rows or blocks of work, rather than timed).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering::Relaxed};
use std::sync::Mutex;

use pgvol::{
    DecodeOptions, EncodeOptions, ErrorKind, Field, GridSpec, Progress, ShellKind, ShellOptions,
    Silent, SliceOptions,
};

/// Asks to stop at the first report of stage `at`, and counts that stage's reports.
struct StopIn {
    at: &'static str,
    stage: Mutex<String>,
    reports: AtomicUsize,
    stop: AtomicBool,
}

impl StopIn {
    fn new(at: &'static str) -> Self {
        StopIn {
            at,
            stage: Mutex::new(String::new()),
            reports: AtomicUsize::new(0),
            stop: AtomicBool::new(false),
        }
    }
}

impl Progress for StopIn {
    fn stage(&self, name: &str) {
        *self.stage.lock().unwrap() = name.to_string();
    }
    fn update(&self, _done: f64) {
        if *self.stage.lock().unwrap() == self.at {
            self.reports.fetch_add(1, Relaxed);
            self.stop.store(true, Relaxed);
        }
    }
    fn cancelled(&self) -> bool {
        self.stop.load(Relaxed)
    }
}

/// Checks that `run`, stopped at the first report of stage `at`, fails as cancelled after at
/// most `max_after` further reports of that stage, and that run to the end (through
/// [`NoCancel`]) the stage reports at least 20 times: enough that stopping early is seen.
fn stops_within<T>(
    at: &'static str,
    max_after: usize,
    run: impl Fn(&dyn Progress) -> pgvol::Result<T>,
) {
    let stop = StopIn::new(at);
    let e = run(&stop).err().expect("a cancelled call fails");
    assert_eq!(e.kind(), ErrorKind::Cancelled, "{e}");
    // The first report asks to stop; what was already running may report again.
    let after = stop.reports.load(Relaxed) - 1;
    assert!(after <= max_after, "{after} reports after the cancel");
    let whole = StopIn::new(at);
    run(&NoCancel(&whole)).unwrap();
    let whole = whole.reports.load(Relaxed);
    assert!(whole >= 20, "{whole} reports in the whole stage");
}

fn sphere() -> pgvol::Mesh {
    pgvol::mesh::shapes::octasphere(5)
}

fn encode(progress: &dyn Progress) -> pgvol::Result<Field> {
    let options = EncodeOptions {
        grid: GridSpec::Res(256),
        ..EncodeOptions::default()
    };
    Field::from_mesh(&sphere(), &options, progress)
}

#[test]
fn a_cancel_stops_the_distance_sampling_within_a_few_rows() {
    // Rows already running may report once more each.
    stops_within("distance", 2, encode);
}

#[test]
fn a_cancel_stops_contouring_within_a_few_blocks() {
    let field = encode(&Silent).unwrap();
    stops_within("contour", 3, |p| {
        field.to_mesh(&DecodeOptions::default(), p)
    });
}

#[test]
fn a_cancel_stops_the_fit_within_a_few_brick_groups() {
    // Groups in flight on other threads may report once each, and the sign check once before
    // its first poll.
    stops_within("fit", 3, encode);
}

#[test]
fn a_cancel_stops_a_shell_within_a_few_brick_groups() {
    // A band wide enough for a wall the grid resolves.
    let options = EncodeOptions {
        grid: GridSpec::Res(256),
        band: 8.0,
        ..EncodeOptions::default()
    };
    let field = Field::from_mesh(&sphere(), &options, &Silent).unwrap();
    let options = ShellOptions {
        thickness: 2.5 * field.grid().spacing,
        kind: ShellKind::Hollow,
        drains: Vec::new(),
    };
    stops_within("hollow", 2, |p| field.shell(&options, p));
}

#[test]
fn a_cancel_stops_slicing_at_the_next_layer() {
    let field = encode(&Silent).unwrap();
    let options = SliceOptions::new(field.grid().spacing);
    // The layer that reported is the last one handed on.
    stops_within("slice", 0, |p| field.slice(&options, p));
}

/// Forwards stages and reports to a [`StopIn`] but never cancels.
struct NoCancel<'a>(&'a StopIn);

impl Progress for NoCancel<'_> {
    fn stage(&self, name: &str) {
        self.0.stage(name);
    }
    fn update(&self, done: f64) {
        self.0.update(done);
    }
}
