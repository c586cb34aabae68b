//! The paper's 2D study, reproduced: circles, squares at several angles and rectangles on a
//! 13 × 13 grid, every basis (pseudo-Gaussian n = 1..4 at several radii, quadratic and cubic
//! B-splines, bilinear) and fit (interpolation at the nodes; the paper's isoline points for fixed
//! and searched `z_step`). Prints markdown tables, writes every row to
//! `target/basis-study-2d.csv` and PNG panels of representative fields to `docs/images/`.
//!
//! `cargo run --release -p pgvol-studies --bin basis_study_2d [-- [--figures-only] [IMAGE_DIR]]`
//! (from the repository root; IMAGE_DIR defaults to `docs/images`).

mod basis2d;
mod dense;
mod fit2d;
mod fonts;
mod isoline;
mod plot;
mod report;
mod shapes;

use rayon::prelude::*;

use basis2d::{Basis2, Field2, Grid2};
use fit2d::{iso_points, node_points, search_like_pgvol, solve, solve_quiet, Points};
use isoline::{error, trace, IsoError, Isoline, Samples};
use pgvol_field::fit::golden_section as golden;
use shapes::{study_shapes, Shape};

/// The paper's grid: 13 × 13 nodes, spacing 1, so lengths in the tables are in spacings.
const GRID: Grid2 = Grid2 {
    n: 13,
    origin: -6.0,
    spacing: 1.0,
};
/// Fine samples per spacing for tracing the isoline that is measured.
const TRACE_DENSITY: usize = 20;
/// The step the paper found best for its Fig. 6 square by numerical optimisation.
const PAPER_BEST_STEP: f64 = 0.081384;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fit {
    Interp,
    Iso(f64),
    /// `z_step` from pgvol's search criterion (RMS of f − SDF near the zero set).
    IsoSearched,
    /// `z_step` with the smallest isoline Hausdorff error: the best this point choice can do.
    IsoBest,
}

impl Fit {
    pub fn label(self) -> String {
        match self {
            Fit::Interp => "interp".into(),
            Fit::Iso(z) => format!("iso z={z}"),
            Fit::IsoSearched => "iso z* (pgvol search)".into(),
            Fit::IsoBest => "iso z best".into(),
        }
    }
}

pub const FITS: [Fit; 6] = [
    Fit::Interp,
    Fit::Iso(0.25),
    Fit::Iso(0.5),
    Fit::Iso(PAPER_BEST_STEP),
    Fit::IsoSearched,
    Fit::IsoBest,
];

fn bases() -> Vec<Basis2> {
    let mut b = vec![Basis2::Bilinear, Basis2::Bspline2, Basis2::Bspline3];
    for r in [1.0, 1.5, 2.0, 3.0] {
        for n in 1..=4 {
            b.push(Basis2::Pg { n, r });
        }
    }
    b
}

/// One measured fit.
pub struct Row {
    pub shape: String,
    pub basis: Basis2,
    pub fit: Fit,
    pub z: Option<f64>,
    pub iso: IsoError,
    /// RMS of |f − SDF| over the grid box, in spacings.
    pub field_rms: f64,
    /// Nodes with |SDF| > k where the field's sign is wrong.
    pub spurious: usize,
    pub shift_mean: f64,
    pub shift_max: f64,
    pub kept: usize,
    pub condition: Option<f64>,
    pub residual: f64,
    pub cgls: (usize, bool),
}

fn points_for(shape: &Shape, basis: Basis2, z: Option<f64>) -> Points {
    match z {
        None => node_points(shape, &GRID),
        Some(z) => iso_points(shape, basis, &GRID, z),
    }
}

fn isoline_of(field: &Field2, density: usize) -> (Samples, Isoline) {
    let s = Samples::new(field, density);
    let iso = trace(field, &s);
    (s, iso)
}

/// The step in [0.02, 1] with the smallest isoline Hausdorff error: a scan, then golden section
/// around the best scanned step (the error is far from unimodal in z).
fn best_step(shape: &Shape, basis: Basis2) -> f64 {
    let cost = |z: f64| {
        let f = solve_quiet(basis, &GRID, &iso_points(shape, basis, &GRID, z));
        let (_, iso) = isoline_of(&f, 5);
        error(&iso, shape, GRID.spacing).hausdorff()
    };
    let (z0, _) = (1..=50)
        .map(|i| 0.02 * i as f64)
        .map(|z| (z, cost(z)))
        .fold((0.02, f64::INFINITY), |b, c| if c.1 < b.1 { c } else { b });
    golden(cost, (z0 - 0.02).max(0.01), (z0 + 0.02).min(1.0), 12)
}

fn measure(shape: &Shape, basis: Basis2, fit: Fit) -> (Row, Field2, Isoline, Points) {
    let z = match fit {
        Fit::Interp => None,
        Fit::Iso(z) => Some(z),
        Fit::IsoSearched => Some(search_like_pgvol(shape, basis, &GRID)),
        Fit::IsoBest => Some(best_step(shape, basis)),
    };
    let pts = points_for(shape, basis, z);
    let solved = solve(basis, &GRID, &pts);
    let (samples, iso) = isoline_of(&solved.field, TRACE_DENSITY);
    let k = GRID.spacing;
    let mut sq = 0.0;
    for y in 0..samples.n {
        for x in 0..samples.n {
            let d = shape.sdf(samples.point(x, y)).0;
            sq += (samples.values[x + samples.n * y] - d).powi(2);
        }
    }
    let field_rms = (sq / (samples.n * samples.n) as f64).sqrt() / k;
    let spurious = (0..GRID.len())
        .filter(|&i| {
            let p = GRID.node(i);
            let d = shape.sdf(p).0;
            d.abs() > k && (solved.field.value(p) < 0.0) != (d < 0.0)
        })
        .count();
    let moved: Vec<f64> = pts.shifts.iter().copied().filter(|&s| s > 0.0).collect();
    // `Sum` of an empty f64 iterator is −0.0; fold from +0.0 so unmoved fits print 0.
    let row = Row {
        shape: shape.name.clone(),
        basis,
        fit,
        z,
        iso: error(&iso, shape, k),
        field_rms,
        spurious,
        shift_mean: moved.iter().fold(0.0, |a, b| a + b) / moved.len().max(1) as f64,
        shift_max: moved.iter().copied().fold(0.0, f64::max),
        kept: pts.kept,
        condition: solved.condition,
        residual: solved.residual,
        cgls: solved.cgls,
    };
    (row, solved.field, iso, pts)
}

/// Figures: file name and the (shape, basis, fit) of each panel.
type Figure = (&'static str, Vec<(&'static str, Basis2, Fit)>);

fn figures() -> Vec<Figure> {
    let pg = |n, r| Basis2::Pg { n, r };
    let sq45 = "square 45°";
    let sq22 = "square 22.5°";
    let sq30 = "square 30°";
    vec![
        (
            "basis-2d-square45.png",
            vec![
                (sq45, Basis2::Bilinear, Fit::Interp),
                (sq45, Basis2::Bspline3, Fit::Interp),
                (sq45, pg(3, 1.5), Fit::Interp),
                (sq45, pg(3, 2.0), Fit::Interp),
                (sq45, pg(3, 2.0), Fit::Iso(0.25)),
                (sq45, pg(3, 2.0), Fit::IsoBest),
            ],
        ),
        (
            "basis-2d-failures.png",
            vec![
                (sq45, pg(1, 1.5), Fit::Iso(0.25)),
                (sq45, pg(1, 1.5), Fit::Iso(PAPER_BEST_STEP)),
                (sq30, pg(2, 2.0), Fit::Iso(0.5)),
                (sq22, pg(4, 3.0), Fit::Interp),
            ],
        ),
        (
            "basis-2d-circle-rect.png",
            vec![
                ("circle", Basis2::Bilinear, Fit::Interp),
                ("circle", Basis2::Bspline2, Fit::Interp),
                ("circle", pg(1, 1.0), Fit::Interp),
                ("rectangle 30°", Basis2::Bilinear, Fit::Interp),
                ("rectangle 30°", Basis2::Bspline3, Fit::Interp),
                ("rectangle 0°", Basis2::Bilinear, Fit::Iso(0.5)),
            ],
        ),
    ]
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let figures_only = args.iter().any(|a| a == "--figures-only");
    let image_dir = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .cloned()
        .unwrap_or_else(|| "docs/images".into());
    let shapes = study_shapes();
    if !figures_only {
        run_study(&shapes);
    }
    draw_figures(&shapes, &image_dir);
}

fn run_study(shapes: &[Shape]) {
    let bases = bases();

    let matrices = report::matrix_table(&bases, &GRID, &shapes[0]);
    let jobs: Vec<(usize, Basis2, Fit)> = (0..shapes.len())
        .flat_map(|s| bases.iter().flat_map(move |&b| FITS.map(|f| (s, b, f))))
        .collect();
    let rows: Vec<Row> = jobs
        .par_iter()
        .map(|&(s, b, f)| measure(&shapes[s], b, f).0)
        .collect();

    print!("{matrices}");
    print!("{}", report::summary(&rows, &bases));
    print!("{}", report::per_shape(&rows, shapes, &bases));
    let _ = std::fs::create_dir_all("target");
    if let Err(e) = std::fs::write("target/basis-study-2d.csv", report::csv(&rows)) {
        eprintln!("could not write target/basis-study-2d.csv: {e}");
    }
}

fn draw_figures(shapes: &[Shape], image_dir: &str) {
    let text = fonts::load();
    if let Err(e) = std::fs::create_dir_all(image_dir) {
        eprintln!("could not create {image_dir}: {e}");
        return;
    }
    for (file, cases) in figures() {
        let drawn: Vec<(&Shape, Row, Field2, Isoline, Points)> = cases
            .par_iter()
            .filter_map(|&(name, b, f)| {
                let shape = shapes.iter().find(|s| s.name == name)?;
                let (row, field, iso, pts) = measure(shape, b, f);
                Some((shape, row, field, iso, pts))
            })
            .collect();
        let panels: Vec<plot::Panel> = drawn
            .iter()
            .map(|(shape, row, field, iso, pts)| plot::Panel {
                title: format!(
                    "{} {}: H {:.2}, {} pc",
                    row.basis.label(),
                    match (row.fit, row.z) {
                        (Fit::Interp, _) => "interp".to_string(),
                        (Fit::IsoSearched, Some(z)) => format!("iso z*={z:.3}"),
                        (Fit::IsoBest, Some(z)) => format!("iso best z={z:.3}"),
                        (_, z) => format!("iso z={}", z.unwrap_or(f64::NAN)),
                    },
                    row.iso.hausdorff(),
                    row.iso.pieces
                ),
                field,
                iso,
                shape,
                points: row.z.is_some().then_some(pts.points.as_slice()),
            })
            .collect();
        let path = format!("{image_dir}/{file}");
        let columns = if panels.len() == 4 { 2 } else { 3 };
        match plot::write(&path, &panels, columns, text) {
            Ok(()) => eprintln!("wrote {path}"),
            Err(e) => eprintln!("could not write {path}: {e}"),
        }
    }
}
