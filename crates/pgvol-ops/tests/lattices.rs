//! Lattices cut to a part and filling a hollowed part, against volumes of the same implicit
//! sampled finely, and drain holes that cut through the infill.

use glam::Vec3;
use pgvol_contour::{contour_volume, Method};
use pgvol_core::{Background, SparseGrid, BRICK_EDGE};
use pgvol_field::fit::interp_sparse;
use pgvol_field::{Basis, CoefficientVolume, Grid};
use pgvol_ops::{infill, lattice_part, Drain, Lattice, LatticeStyle, Tpms};
use rayon::prelude::*;

const RES: usize = 112;
const HALF: f32 = 0.5;

fn unit_cube(p: Vec3) -> f32 {
    let q = p.abs() - Vec3::splat(HALF);
    q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
}

/// The cube's distance stored as the encoder stores a mesh's: bricks within `band` of the
/// surface, the others background by side; on `res` nodes over a box `margin` wider.
fn cube_field_on(res: usize, margin: f32, band: f32) -> CoefficientVolume {
    let grid =
        Grid::cube_res(Vec3::splat(-HALF - margin), Vec3::splat(HALF + margin), res).unwrap();
    let [nx, ny, nz] = grid.dims;
    let values: Vec<f32> = (0..nx * ny * nz)
        .map(|i| unit_cube(grid.point(i % nx, (i / nx) % ny, i / (nx * ny))).clamp(-band, band))
        .collect();
    let edge = BRICK_EDGE as f32 * grid.spacing;
    let samples = SparseGrid::from_dense_where(grid.dims, &values, Background::clamp(band), |b| {
        let centre = grid.origin + (Vec3::from(b.map(|c| c as f32)) + 0.5) * edge;
        let v = unit_cube(centre);
        if v.abs() < band + edge {
            Some(true)
        } else {
            (v > 0.0).then_some(false)
        }
    });
    interp_sparse(grid, Basis::Bspline3, &samples, pgvol_core::progress::QUIET)
        .unwrap()
        .0
}

/// The cube on the default grid, with distances exact a wall's thickness deep.
fn cube_field() -> CoefficientVolume {
    cube_field_on(RES, 0.0, 0.1)
}

/// The volume of `{solid < 0}` within the unit cube by the midpoint rule on `n³` cells.
fn sampled_volume(n: usize, solid: impl Fn(Vec3) -> f32 + Sync) -> f64 {
    let h = 2.0 * HALF / n as f32;
    let inside: usize = (0..n)
        .into_par_iter()
        .map(|k| {
            let mut count = 0;
            for j in 0..n {
                for i in 0..n {
                    let p = Vec3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5) * h
                        - Vec3::splat(HALF);
                    count += (solid(p) < 0.0) as usize;
                }
            }
            count
        })
        .sum();
    inside as f64 * (h as f64).powi(3)
}

fn contoured(volume: &CoefficientVolume) -> (f64, f64) {
    let mesh = contour_volume(
        volume,
        &volume.grid,
        0.0,
        Method::MarchingCubes,
        pgvol_core::progress::QUIET,
    );
    let s = mesh.stats();
    assert!(
        s.watertight && s.winding_consistent && s.non_manifold_edges == 0,
        "{s:?}"
    );
    (s.volume, s.area)
}

#[test]
fn sheet_and_strut_volumes_match_the_sampled_implicit() {
    let cube = cube_field();
    for (surface, style, thickness) in [
        (Tpms::Gyroid, LatticeStyle::Sheet, 0.08),
        (Tpms::SchwarzP, LatticeStyle::Sheet, 0.08),
        (Tpms::Diamond, LatticeStyle::Strut, 0.02),
        (Tpms::Neovius, LatticeStyle::Sheet, 0.08),
    ] {
        let lattice = Lattice {
            style,
            ..Lattice::sheet(surface, 0.4, thickness)
        };
        let (got, area) = contoured(&lattice_part(&cube, &lattice).unwrap().volume);
        let want = sampled_volume(320, |p| unit_cube(p).max(lattice.value(p, unit_cube(p))));
        let error = (got - want).abs() / want;
        eprintln!("{surface} {style:?}: fraction {got:.4} vs {want:.4}, area {area:.3}");
        assert!(error < 0.01, "{surface}: volume {got} vs sampled {want}");
    }
}

#[test]
fn infill_keeps_the_wall_and_drains_cut_through_the_lattice() {
    let cube = cube_field();
    let wall = 0.05;
    let lattice = Lattice::sheet(Tpms::Gyroid, 0.3, 0.04);
    let drain = Drain {
        point: Vec3::ZERO,
        direction: Vec3::Z,
        diameter: 0.12,
    };
    let filled = infill(&cube, wall, &lattice, &[drain]).unwrap().volume;
    let (got, _) = contoured(&filled);
    let want = sampled_volume(320, |p| {
        let v = unit_cube(p);
        let g = v.max((-(v + wall)).min(lattice.value(p, v)));
        let radial = (p.x * p.x + p.y * p.y).sqrt() - 0.06;
        g.max(-radial.max(-p.z))
    });
    assert!((got - want).abs() < 0.01 * want, "{got} vs {want}");
    // The wall is solid away from the drain, the drain is open through wall and infill alike.
    assert!(filled.value(Vec3::new(0.3, 0.2, -0.48)) < 0.0);
    for z in [0.1, 0.25, 0.4, 0.48] {
        assert!(
            filled.value(Vec3::new(0.0, 0.0, z)) > 0.0,
            "closed at z = {z}"
        );
    }
    // Without the drain the same line crosses solid infill or wall.
    let closed = infill(&cube, wall, &lattice, &[]).unwrap().volume;
    assert!([0.1f32, 0.25, 0.4, 0.48]
        .iter()
        .any(|&z| closed.value(Vec3::new(0.0, 0.0, z)) < 0.0));
}

#[test]
fn bricks_outside_the_part_stay_background() {
    let cube = cube_field_on(128, 1.5, 0.1);
    let lattice = Lattice::sheet(Tpms::Gyroid, 0.4, 0.06);
    let result = lattice_part(&cube, &lattice).unwrap().volume;
    // Stored: the bricks inside the cube and those the fit's support reaches around them;
    // the cube fills a twelfth of the grid's box, the bricks far outside stay background.
    let total = result.coeffs.all_bricks().count();
    let stored = result.coeffs.stored_count();
    assert!(stored >= pgvol_ops::lattice_bricks(&cube), "{stored}");
    assert!(2 * stored < total, "{stored} of {total}");
    assert!(result.value(Vec3::splat(0.54)) > 0.0);
}
