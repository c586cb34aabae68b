//! Slicing sparse coefficient volumes: only the blocks a contour can cross are evaluated, and
//! what is skipped changes nothing.

use glam::Vec3;
use pgvol_core::progress::QUIET;
use pgvol_core::{Background, SparseGrid, BRICK_EDGE, BRICK_NODES};
use pgvol_field::{Basis, CoefficientVolume, Grid};
use pgvol_slice::{slice, slice_bricks, slice_volume, Axis, Layer, LayerCost, SliceOptions};

/// A sparse volume whose coefficients are `sdf` at the nodes: bricks within `band` of the
/// surface stored, the others absent on their side. Only the bricks of node layers
/// `layers` along z are built (all of them for `None`).
fn sparse_volume(
    grid: Grid,
    band: f32,
    layers: Option<(usize, usize)>,
    sdf: impl Fn(Vec3) -> f32,
) -> CoefficientVolume {
    let mut coeffs = SparseGrid::new(grid.dims, Background::clamp(band));
    let counts = grid.dims.map(|n| n.div_ceil(BRICK_EDGE));
    let (k0, k1) = layers.map_or((0, counts[2]), |(a, b)| {
        (a / BRICK_EDGE, b / BRICK_EDGE + 1)
    });
    let half = grid.spacing * BRICK_EDGE as f32 * 0.5;
    let reach = band + half * 3f32.sqrt();
    for bk in k0..k1.min(counts[2]) {
        for bj in 0..counts[1] {
            for bi in 0..counts[0] {
                let b = [bi, bj, bk];
                let first = b.map(|c| c * BRICK_EDGE);
                let centre = grid.point(first[0], first[1], first[2]) + Vec3::splat(half);
                let d = sdf(centre);
                if d.abs() > reach {
                    if d < 0.0 {
                        coeffs.set_inside(b, true);
                    }
                    continue;
                }
                let mut values = Box::new([0.0f32; BRICK_NODES]);
                for (n, v) in values.iter_mut().enumerate() {
                    let at = [n % 8, n / 8 % 8, n / 64].map(|x| x as f32);
                    let p =
                        grid.point(first[0], first[1], first[2]) + Vec3::from(at) * grid.spacing;
                    *v = sdf(p);
                }
                coeffs.insert(b, values);
            }
        }
    }
    CoefficientVolume::from_sparse(grid, Basis::Bspline3, coeffs).unwrap()
}

fn cube_grid(res: usize) -> Grid {
    Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), res).unwrap()
}

/// Nodes evaluated per layer and the layers of 8 planes through a sphere's equator at `res`³.
fn equator_cost(res: usize) -> (LayerCost, Vec<Layer>) {
    let grid = cube_grid(res);
    let h = grid.spacing;
    let mid = res / 2;
    let volume = sparse_volume(grid, 4.0 * h, Some((mid - 12, mid + 12)), |p| {
        p.length() - 0.8
    });
    let mut options = SliceOptions::new(Axis::Z, h, h);
    options.first = Some(-4.0 * h);
    let bounds = (Vec3::splat(-0.9), Vec3::splat(0.9));
    let mut layers = Vec::new();
    let cost = slice_bricks(
        &volume.coeffs,
        &volume.grid,
        volume.basis,
        volume.coeffs.background(),
        bounds,
        &options,
        0..8,
        &mut |layer| {
            layers.push(layer);
            Ok(())
        },
    )
    .unwrap();
    (cost, layers)
}

#[test]
fn a_layers_cost_follows_its_contour_not_its_plane() {
    let (small, small_layers) = equator_cost(512);
    let (large, large_layers) = equator_cost(1024);
    for layers in [&small_layers, &large_layers] {
        assert_eq!(layers.len(), 8);
        for layer in layers.iter() {
            // One disc of radius about 0.8 (the plane is within a few spacings of the equator).
            assert_eq!(layer.loops.len(), 1, "at {}", layer.height);
            let area = layer.area();
            let want = std::f64::consts::PI * 0.64;
            assert!(
                (area - want).abs() < 0.01 * want,
                "area {area}, want {want}"
            );
        }
    }
    // The contour is twice as long in nodes; the plane holds four times the nodes.
    let ratio = large.nodes as f64 / small.nodes as f64;
    assert!(
        (1.6..2.6).contains(&ratio),
        "nodes evaluated grew {ratio:.2}× from 512³ to 1024³ ({small:?}, {large:?})"
    );
    let crossings = large.crossings as f64 / small.crossings as f64;
    assert!(
        (1.8..2.2).contains(&crossings),
        "crossings grew {crossings:.2}×"
    );
    // And only a thin band of the plane is evaluated.
    let plane_nodes = 8.0 * (0.9f64 * 2.0 / cube_grid(1024).spacing as f64).powi(2);
    assert!(
        (large.nodes as f64) < 0.1 * plane_nodes,
        "{} of {plane_nodes} nodes evaluated",
        large.nodes
    );
}

#[test]
fn skipping_blocks_changes_no_contour() {
    // Two spheres, a box hole, and absent bricks on both sides, sliced along every axis: the
    // same loops as slicing that evaluates every node. At full size one sphere is cut by the
    // grid's faces (every block is asked); at half size the contours keep away from them (only
    // the blocks near a change of side are).
    for scale in [1.0, 0.5] {
        skipping_changes_no_contour_at(scale);
    }
}

fn skipping_changes_no_contour_at(scale: f32) {
    let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), 90).unwrap();
    let sdf = |p: Vec3| {
        let p = p / scale;
        let a = (p - Vec3::new(-0.3, 0.1, 0.0)).length() - 0.5;
        let b = (p - Vec3::new(0.75, -0.7, 0.6)).length() - 0.45;
        let q = (p - Vec3::new(-0.3, 0.1, 0.0)).abs() - Vec3::splat(0.15);
        let hole = q.max(Vec3::ZERO).length() + q.max_element().min(0.0);
        a.min(b).max(-hole) * scale
    };
    let volume = sparse_volume(grid, 4.0 * grid.spacing, None, sdf);
    assert!(volume.coeffs.stored_count() < volume.coeffs.all_bricks().count() / 2);
    let bounds = (volume.grid.origin, volume.grid.max_corner());
    for axis in [Axis::X, Axis::Y, Axis::Z] {
        // Unsimplified, so rounding differences cannot pick other points.
        let mut options = SliceOptions::new(axis, 0.07 * scale, grid.spacing);
        options.tolerance = 0.0;
        let sparse = slice_volume(&volume, bounds, &options, QUIET).unwrap();
        let dense = slice(&|p| volume.value(p), bounds, &options).unwrap();
        assert_eq!(sparse.len(), dense.len());
        let mut loops = 0;
        for (s, d) in sparse.iter().zip(&dense) {
            assert_eq!(s.loops.len(), d.loops.len(), "{axis:?} at {}", s.height);
            let (a, b) = (s.area(), d.area());
            assert!(
                (a - b).abs() <= 1e-4 * b.abs().max(1e-3),
                "{axis:?} at {}: {a} vs {b}",
                s.height
            );
            loops += s.loops.len();
        }
        assert!(loops > 20, "{axis:?}: {loops} loops");
    }
}
