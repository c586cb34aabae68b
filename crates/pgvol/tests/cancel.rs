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

/// Counts every report of stage `at` in `run`, which passes the counter on through
/// [`NoCancel`].
fn reports_of_whole_stage(at: &'static str, run: impl Fn(&StopIn)) -> usize {
    let counting = StopIn::new(at);
    run(&counting);
    counting.reports.load(Relaxed)
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
    let stop = StopIn::new("distance");
    let e = encode(&stop).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Cancelled);
    // The first report asks to stop; rows already running may report once more each.
    let after = stop.reports.load(Relaxed) - 1;
    assert!(after <= 2, "{after} reports after the cancel");
    // Uncancelled, the stage reports many times over.
    let whole = reports_of_whole_stage("distance", |p| {
        let _ = encode(&NoCancel(p));
    });
    assert!(whole >= 20, "{whole} reports in the whole stage");
}

#[test]
fn a_cancel_stops_contouring_within_a_few_blocks() {
    let field = encode(&Silent).unwrap();
    let stop = StopIn::new("contour");
    let e = field.to_mesh(&DecodeOptions::default(), &stop).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Cancelled);
    let after = stop.reports.load(Relaxed) - 1;
    assert!(after <= 3, "{after} reports after the cancel");
    let whole = reports_of_whole_stage("contour", |p| {
        field
            .to_mesh(&DecodeOptions::default(), &NoCancel(p))
            .unwrap();
    });
    assert!(whole >= 20, "{whole} reports in the whole stage");
}

#[test]
fn a_cancel_stops_the_fit_within_a_few_brick_groups() {
    let stop = StopIn::new("fit");
    let e = encode(&stop).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Cancelled);
    // Groups in flight on other threads may report once each, and the sign check once before
    // its first poll.
    let after = stop.reports.load(Relaxed) - 1;
    assert!(after <= 3, "{after} reports after the cancel");
    let whole = reports_of_whole_stage("fit", |p| {
        let _ = encode(&NoCancel(p));
    });
    assert!(whole >= 20, "{whole} reports in the whole stage");
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
    let stop = StopIn::new("hollow");
    let e = field.shell(&options, &stop).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Cancelled, "{e}");
    let after = stop.reports.load(Relaxed) - 1;
    assert!(after <= 2, "{after} reports after the cancel");
    let whole = reports_of_whole_stage("hollow", |p| {
        field.shell(&options, &NoCancel(p)).unwrap();
    });
    assert!(whole >= 20, "{whole} reports in the whole stage");
}

#[test]
fn a_cancel_stops_slicing_at_the_next_layer() {
    let field = encode(&Silent).unwrap();
    let options = SliceOptions::new(field.grid().spacing);
    let stop = StopIn::new("slice");
    let e = field.slice(&options, &stop).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Cancelled);
    // The layer that reported is the last one handed on.
    assert_eq!(stop.reports.load(Relaxed), 1);
    let whole = reports_of_whole_stage("slice", |p| {
        field.slice(&options, &NoCancel(p)).unwrap();
    });
    assert!(whole >= 20, "{whole} reports in the whole stage");
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
