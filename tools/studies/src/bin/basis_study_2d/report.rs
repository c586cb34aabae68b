//! Markdown tables and CSV of the 2D study.

use std::fmt::Write as _;

use super::basis2d::{weights, Basis2, Grid2};
use super::dense::{cgls_iterations, symmetric_eigen_range, Lu};
use super::fit2d::{collocation, node_points};
use super::shapes::Shape;
use super::{Row, FITS};

fn header(first: &str) -> String {
    let mut s = format!("| {first} |");
    for f in FITS {
        let _ = write!(s, " {} |", f.label());
    }
    s.push_str("\n|---|");
    s.push_str(&"---|".repeat(FITS.len()));
    s.push('\n');
    s
}

/// Nodes one evaluation touches, averaged over points spread through a cell.
fn nodes_per_evaluation(basis: Basis2, grid: &Grid2) -> f64 {
    let m = 16;
    let total: usize = (0..m * m)
        .map(|i| {
            let p = [
                (i % m) as f64 / m as f64 + 0.03,
                (i / m) as f64 / m as f64 + 0.07,
            ];
            weights(basis, grid, p).len()
        })
        .sum();
    total as f64 / (m * m) as f64
}

/// The node-collocation matrix of each basis (the same for every shape): definiteness,
/// condition and whether CGLS reaches pgvol's tolerance on `shape`'s node values.
pub fn matrix_table(bases: &[Basis2], grid: &Grid2, shape: &Shape) -> String {
    let mut out = String::from(
        "\n### Node-collocation matrix (13 × 13 nodes)\n\n| basis | nodes per evaluation | λ min | λ max | definite | κ₁ | CGLS iterations to 1e-5 |\n|---|---|---|---|---|---|---|\n",
    );
    let pts = node_points(shape, grid);
    for &b in bases {
        let m = collocation(b, grid, &pts.points);
        let (lo, hi) = symmetric_eigen_range(&m);
        let cond = Lu::new(&m).map(|lu| lu.condition(&m));
        let (it, ok) = cgls_iterations(&m, &pts.targets, 1e-5, 2000);
        let _ = writeln!(
            out,
            "| {} | {:.1} | {:.4} | {:.3} | {} | {} | {}{} |",
            b.label(),
            nodes_per_evaluation(b, grid),
            lo,
            hi,
            if lo > 0.0 { "yes" } else { "**no**" },
            cond.map_or("singular".into(), |c| format!("{c:.3e}")),
            it,
            if ok { "" } else { " (not reached)" }
        );
    }
    out
}

fn rows_of(rows: &[Row], basis: Basis2, fit: super::Fit) -> Vec<&Row> {
    rows.iter()
        .filter(|r| r.basis == basis && r.fit == fit)
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn num(v: f64) -> String {
    if !v.is_finite() {
        "∞".into()
    } else if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 0.01 {
        format!("{v:.3}")
    } else {
        format!("{v:.1e}")
    }
}

/// Over all shapes, per basis and fit: isoline accuracy, then the systems and point shifts.
pub fn summary(rows: &[Row], bases: &[Basis2]) -> String {
    let shapes = rows_of(rows, bases[0], FITS[0]).len();
    let mut acc = format!(
        "\n### Zero isoline over the {shapes} shapes: median RMS / worst Hausdorff (spacings), shapes with wrong pieces, spurious nodes\n\n{}",
        header("basis")
    );
    let mut sys = format!(
        "\n### Systems and points over the {shapes} shapes: worst κ₁, CGLS converged (of {shapes}), mean / max point shift (spacings)\n\n{}",
        header("basis")
    );
    for &b in bases {
        let _ = write!(acc, "| {} |", b.label());
        let _ = write!(sys, "| {} |", b.label());
        for f in FITS {
            let rs = rows_of(rows, b, f);
            let med = median(rs.iter().map(|r| r.iso.rms).collect());
            let worst = rs.iter().map(|r| r.iso.hausdorff()).fold(0.0, f64::max);
            let wrong = rs.iter().filter(|r| r.iso.pieces != 1).count();
            let spurious: usize = rs.iter().map(|r| r.spurious).sum();
            let _ = write!(acc, " {} / {}, {wrong}, {spurious} |", num(med), num(worst));
            let cond = rs
                .iter()
                .map(|r| r.condition.unwrap_or(f64::INFINITY))
                .fold(0.0, f64::max);
            let conv = rs.iter().filter(|r| r.cgls.1).count();
            let shift = rs.iter().map(|r| r.shift_mean).sum::<f64>() / rs.len().max(1) as f64;
            let shift_max = rs.iter().map(|r| r.shift_max).fold(0.0, f64::max);
            let _ = write!(
                sys,
                " {:.1e}, {conv}, {:.2} / {:.2} |",
                cond, shift, shift_max
            );
        }
        acc.push('\n');
        sys.push('\n');
    }
    acc + &sys
}

/// One table per shape: isoline RMS / max (spacings), pieces, spurious nodes; `z` found.
pub fn per_shape(rows: &[Row], shapes: &[Shape], bases: &[Basis2]) -> String {
    let mut out = String::new();
    for s in shapes {
        let _ = write!(
            out,
            "\n#### {}: isoline RMS / max, pieces, spurious nodes\n\n{}",
            s.name,
            header("basis")
        );
        for &b in bases {
            let _ = write!(out, "| {} |", b.label());
            for f in FITS {
                if let Some(r) = rows
                    .iter()
                    .find(|r| r.shape == s.name && r.basis == b && r.fit == f)
                {
                    let z = match (f, r.z) {
                        (super::Fit::IsoSearched | super::Fit::IsoBest, Some(z)) => {
                            format!(" z={z:.3}")
                        }
                        _ => String::new(),
                    };
                    let _ = write!(
                        out,
                        " {} / {}, {}, {}{z} |",
                        num(r.iso.rms),
                        num(r.iso.max),
                        r.iso.pieces,
                        r.spurious
                    );
                }
            }
            out.push('\n');
        }
    }
    out
}

pub fn csv(rows: &[Row]) -> String {
    let mut out = String::from(
        "shape,basis,fit,z_step,iso_rms,iso_max,reverse_max,pieces,field_rms,spurious_nodes,shift_mean,shift_max,points_kept_on_node,condition_1,residual,cgls_iterations,cgls_converged\n",
    );
    for r in rows {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.shape,
            r.basis.label(),
            r.fit.label(),
            r.z.map_or(String::new(), |z| format!("{z:.6}")),
            r.iso.rms,
            r.iso.max,
            r.iso.reverse_max,
            r.iso.pieces,
            r.field_rms,
            r.spurious,
            r.shift_mean,
            r.shift_max,
            r.kept,
            r.condition.map_or("inf".into(), |c| format!("{c:e}")),
            r.residual,
            r.cgls.0,
            r.cgls.1
        );
    }
    out
}
