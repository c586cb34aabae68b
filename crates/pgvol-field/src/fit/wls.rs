//! Weighted least squares: more samples than coefficients, concentrated where meshing looks.
//! Every node keeps a weak sample of its own SDF so far regions stay determined; band nodes add
//! their nearest points on the zero surface and on the ±k/2 offsets, whose values are exact.

use glam::Vec3;

use super::{
    project, report, to_f32, weighted_solve, FitOptions, FitReport, NodeSdf, SignedDistance,
};
use crate::{Basis, Grid};

pub(crate) fn fit(
    grid: &Grid,
    basis: Basis,
    nodes: &NodeSdf,
    sdf: &dyn SignedDistance,
    options: &FitOptions,
) -> (Vec<f32>, FitReport) {
    let k = grid.spacing;
    let warm = super::interp::warm_start(grid, basis, &nodes.distance, options);
    let [nx, ny, _] = grid.dims;
    let hi = grid.max_corner();
    let inside = |p: Vec3| p.is_finite() && p.cmpge(grid.origin).all() && p.cmple(hi).all();
    let reach = (options.band + 1.0) * k;
    let mut pts = Vec::with_capacity(grid.len() * 2);
    let mut tgt = Vec::with_capacity(grid.len() * 2);
    let mut wts = Vec::with_capacity(grid.len() * 2);
    for (idx, (&d, &n)) in nodes.distance.iter().zip(&nodes.gradient).enumerate() {
        let g = grid.point(idx % nx, (idx / nx) % ny, idx / (nx * ny));
        pts.push(grid.to_grid(g));
        tgt.push(d);
        wts.push(options.node_weight as f64);
        if d.abs() >= options.band * k {
            continue;
        }
        for (t, w) in [
            (0.0, options.surface_weight),
            (0.5 * k, options.offset_weight),
            (-0.5 * k, options.offset_weight),
        ] {
            let p = project(sdf, g, d, n, t);
            if inside(p) && p.distance(g) < reach {
                pts.push(grid.to_grid(p));
                tgt.push(t);
                wts.push(w as f64);
            }
        }
    }
    let (c, outcome) = weighted_solve(
        grid,
        basis,
        super::Rows {
            points: &pts,
            targets: &tgt,
            weights: Some(&wts),
        },
        &warm,
        options.damping,
        options,
    );
    (to_f32(c), report("cgls", Some(outcome)))
}
