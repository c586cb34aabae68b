//! Collocation fits in 2D: at the nodes (`interp`) or at the paper's isoline points (`iso`):
//! each node's point moved to the nearest point of the isoline `SDF = q · z_step` (q the
//! nearest integer). Solved exactly (dense LU) so what is measured is the system, not a solver.

use super::basis2d::{weights, Basis2, Field2, Grid2};
use super::dense::{cgls_iterations, relative_residual, Lu, Mat};
use super::shapes::{Shape, P2};
use pgvol_field::fit::golden_section as golden;

/// One interpolation point per node and the value the field must take there.
pub struct Points {
    pub points: Vec<P2>,
    pub targets: Vec<f64>,
    /// Distance each point moved from its node, in spacings.
    pub shifts: Vec<f64>,
    /// Nodes whose moved point would leave the support or the grid: they stay on the node.
    pub kept: usize,
}

pub fn node_points(shape: &Shape, grid: &Grid2) -> Points {
    let points: Vec<P2> = (0..grid.len()).map(|i| grid.node(i)).collect();
    let targets = points.iter().map(|&p| shape.sdf(p).0).collect();
    Points {
        shifts: vec![0.0; points.len()],
        points,
        targets,
        kept: 0,
    }
}

/// The paper's points for isoline step `z` (in spacings).
pub fn iso_points(shape: &Shape, basis: Basis2, grid: &Grid2, z: f64) -> Points {
    let k = grid.spacing;
    let mut out = Points {
        points: Vec::new(),
        targets: Vec::new(),
        shifts: Vec::new(),
        kept: 0,
    };
    for idx in 0..grid.len() {
        let g = grid.node(idx);
        let (d, n) = shape.sdf(g);
        let t = (d / (z * k)).round() * z * k;
        let p = [g[0] - (d - t) * n[0], g[1] - (d - t) * n[1]];
        let shift = (p[0] - g[0]).hypot(p[1] - g[1]);
        let inside_support = match basis {
            Basis2::Pg { .. } => shift < basis.reach() * k,
            _ => (p[0] - g[0]).abs().max((p[1] - g[1]).abs()) < basis.reach() * k,
        };
        if inside_support && grid.contains(p) && (shape.sdf(p).0 - t).abs() < 1e-6 * k {
            out.points.push(p);
            out.targets.push(t);
            out.shifts.push(shift / k);
        } else {
            out.points.push(g);
            out.targets.push(d);
            out.shifts.push(0.0);
            out.kept += 1;
        }
    }
    out
}

/// Rows: points; columns: nodes.
pub fn collocation(basis: Basis2, grid: &Grid2, points: &[P2]) -> Mat {
    let mut m = Mat::zeros(points.len(), grid.len());
    for (r, &p) in points.iter().enumerate() {
        for (c, w) in weights(basis, grid, p) {
            m.add(r, c, w);
        }
    }
    m
}

/// What solving one system gave.
pub struct Solved {
    pub field: Field2,
    /// `None` when LU met a zero pivot (singular system).
    pub condition: Option<f64>,
    pub residual: f64,
    /// CGLS iterations to a relative residual of 1e-5 (pgvol's tolerance), and whether reached.
    pub cgls: (usize, bool),
}

pub fn solve(basis: Basis2, grid: &Grid2, pts: &Points) -> Solved {
    let m = collocation(basis, grid, &pts.points);
    let cgls = cgls_iterations(&m, &pts.targets, 1e-5, 2000);
    let (coeffs, condition) = match Lu::new(&m) {
        Some(lu) => (lu.solve(&pts.targets), Some(lu.condition(&m))),
        None => (vec![0.0; grid.len()], None),
    };
    let residual = relative_residual(&m, &coeffs, &pts.targets);
    Solved {
        field: Field2 {
            basis,
            grid: *grid,
            coeffs,
        },
        condition,
        residual,
        cgls,
    }
}

/// pgvol's `z_step` search, in 2D: golden section over [0.05, 1] spacings, 10 fits, for the
/// smallest RMS of `f − SDF` at cell centres within two spacings of the zero set and at the
/// nodes' closest zero-set points.
pub fn search_like_pgvol(shape: &Shape, basis: Basis2, grid: &Grid2) -> f64 {
    let k = grid.spacing;
    let mut check = Vec::new();
    for idx in 0..grid.len() {
        let g = grid.node(idx);
        let (d, n) = shape.sdf(g);
        if d.abs() >= 2.0 * k {
            continue;
        }
        let s = [g[0] - d * n[0], g[1] - d * n[1]];
        if grid.contains(s) {
            check.push((s, 0.0));
        }
        let c = [g[0] + 0.5 * k, g[1] + 0.5 * k];
        if grid.contains(c) {
            check.push((c, shape.sdf(c).0));
        }
    }
    let cost = |z: f64| {
        let f = solve_quiet(basis, grid, &iso_points(shape, basis, grid, z));
        let e: f64 = check
            .iter()
            .map(|&(p, want)| (f.value(p) - want).powi(2))
            .sum::<f64>()
            / check.len().max(1) as f64;
        if e.is_finite() {
            e.sqrt()
        } else {
            f64::INFINITY
        }
    };
    golden(cost, 0.05, 1.0, 10)
}

/// The exact solution only (no diagnostics), for searches.
pub fn solve_quiet(basis: Basis2, grid: &Grid2, pts: &Points) -> Field2 {
    let m = collocation(basis, grid, &pts.points);
    let coeffs = Lu::new(&m)
        .map(|lu| lu.solve(&pts.targets))
        .unwrap_or_else(|| vec![0.0; grid.len()]);
    Field2 {
        basis,
        grid: *grid,
        coeffs,
    }
}
