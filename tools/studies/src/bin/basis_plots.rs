//! Plots the 3D basis study's error against stored bytes from `target/basis-study.csv` (written
//! by `basis_study`): one panel per shape and fit, one line per basis, log-log.
//!
//! `cargo run --release -p pgvol-studies --bin basis_plots [-- CSV PNG]` (from the repository
//! root; defaults `target/basis-study.csv` and `docs/images/basis-error-vs-bytes.png`).

#[path = "basis_study_2d/fonts.rs"]
mod fonts;

use plotters::prelude::*;

/// One CSV row: the fields the plot needs.
struct Point {
    shape: String,
    res: usize,
    basis: String,
    fit: String,
    /// Stored coefficient bytes (dense f32), in KiB.
    kib: f64,
    /// Surface RMS in field units (the CSV holds it in grid spacings).
    surface_rms: f64,
}

/// The study's grid spans 2.2 units (`Grid::cube_res` over [-1, 1]³) with `res` nodes per axis.
fn spacing(res: usize) -> f64 {
    2.2 / (res.max(2) - 1) as f64
}

fn read(path: &str) -> Result<Vec<Point>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .ok_or_else(|| format!("{path}: empty"))?
        .split(',')
        .collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| format!("{path}: no column {name}"))
    };
    let (shape, res, basis, fit, bytes, surf) = (
        col("shape")?,
        col("res")?,
        col("basis")?,
        col("fit")?,
        col("bytes")?,
        col("surf_rms")?,
    );
    let mut out = Vec::new();
    for (n, line) in lines.enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        let get = |i: usize| {
            f.get(i)
                .copied()
                .ok_or_else(|| format!("{path}:{}: short row", n + 2))
        };
        let parse = |i: usize| -> Result<f64, String> {
            get(i)?
                .parse::<f64>()
                .map_err(|e| format!("{path}:{}: {e}", n + 2))
        };
        let res = parse(res)? as usize;
        out.push(Point {
            shape: get(shape)?.to_string(),
            res,
            basis: get(basis)?.to_string(),
            fit: get(fit)?.to_string(),
            kib: parse(bytes)? / 1024.0,
            surface_rms: parse(surf)? * spacing(res),
        });
    }
    Ok(out)
}

const BASES: [(&str, RGBColor); 6] = [
    ("trilinear", RGBColor(110, 110, 110)),
    ("bspline2", RGBColor(30, 150, 60)),
    ("bspline3", RGBColor(30, 90, 200)),
    ("pg-n3-r1.5", RGBColor(230, 130, 20)),
    ("pg-n4-r1.5", RGBColor(200, 30, 30)),
    ("pg-n3-r2", RGBColor(140, 60, 170)),
];
const FITS: [&str; 2] = ["interp", "wls"];

fn draw(points: &[Point], out: &str, text: bool) -> Result<(), Box<dyn std::error::Error>> {
    let mut shapes: Vec<&str> = Vec::new();
    for p in points {
        if !shapes.contains(&p.shape.as_str()) {
            shapes.push(&p.shape);
        }
    }
    let positive = |p: &&Point| p.surface_rms > 0.0 && p.kib > 0.0;
    let (mut xlo, mut xhi, mut ylo, mut yhi) = (f64::MAX, 0.0f64, f64::MAX, 0.0f64);
    for p in points.iter().filter(positive) {
        xlo = xlo.min(p.kib);
        xhi = xhi.max(p.kib);
        ylo = ylo.min(p.surface_rms);
        yhi = yhi.max(p.surface_rms);
    }
    if xhi <= 0.0 || shapes.is_empty() {
        return Err("no rows to plot".into());
    }
    let root = BitMapBackend::new(out, (300 * shapes.len() as u32, 2 * 270)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((FITS.len(), shapes.len()));
    for (i, area) in panels.iter().enumerate() {
        let (fit, shape) = (FITS[i / shapes.len()], shapes[i % shapes.len()]);
        let mut builder = ChartBuilder::on(area);
        builder.margin(8);
        if text {
            builder
                .caption(format!("{shape}, {fit}"), ("sans-serif", 15))
                .x_label_area_size(30)
                .y_label_area_size(48);
        }
        let mut chart = builder.build_cartesian_2d(
            (xlo / 1.5..xhi * 1.5).log_scale(),
            (ylo / 2.0..yhi * 2.0).log_scale(),
        )?;
        let mut mesh = chart.configure_mesh();
        if text {
            mesh.x_desc("KiB (f32 coefficients)")
                .y_desc("surface RMS (units)")
                .x_label_formatter(&|v| format!("{v:.0}"))
                .y_label_formatter(&|v| format!("{v:.0e}"));
        } else {
            mesh.x_labels(0).y_labels(0);
        }
        // No minor grid lines: they add nothing on three points and double the PNG size.
        mesh.light_line_style(WHITE).draw()?;
        for (basis, colour) in BASES {
            let mut line: Vec<(usize, f64, f64)> = points
                .iter()
                .filter(positive)
                .filter(|p| p.shape == shape && p.fit == fit && p.basis == basis)
                .map(|p| (p.res, p.kib, p.surface_rms))
                .collect();
            line.sort_by_key(|l| l.0);
            let xy: Vec<(f64, f64)> = line.iter().map(|l| (l.1, l.2)).collect();
            let series = chart.draw_series(LineSeries::new(xy.clone(), colour.stroke_width(2)))?;
            if text && i == 0 {
                series.label(basis).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                });
            }
            chart.draw_series(xy.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
        }
        if text && i == 0 {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerLeft)
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .label_font(("sans-serif", 11))
                .draw()?;
        }
    }
    root.present()?;
    Ok(())
}

fn main() {
    let mut args = std::env::args().skip(1);
    let csv = args
        .next()
        .unwrap_or_else(|| "target/basis-study.csv".into());
    let out = args
        .next()
        .unwrap_or_else(|| "docs/images/basis-error-vs-bytes.png".into());
    let points = match read(&csv) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    let text = fonts::load();
    match draw(&points, &out, text) {
        Ok(()) => eprintln!("wrote {out}"),
        Err(e) => {
            eprintln!("could not write {out}: {e}");
            std::process::exit(1);
        }
    }
}
