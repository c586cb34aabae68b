//! Volumes the writer's unit tests compare against dense reference computations: dense ones,
//! and sparse ones whose background changes side both across stored bricks and without any.

use glam::Vec3;
use pgvol_core::{Background, SparseGrid, BRICK_NODES};
use pgvol_field::{Basis, CoefficientVolume, Grid};

/// The bases with distinct band rules.
pub(crate) const BASES: [Basis; 5] = [
    Basis::Trilinear,
    Basis::Bspline2,
    Basis::Bspline3,
    Basis::Pg { n: 3, r: 1.5 },
    Basis::Pg { n: 2, r: 2.0 },
];

fn random(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        ((s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) as f32
    }
}

/// Every brick stored: uniform random coefficients in ±`scale`.
pub(crate) fn dense(dims: [usize; 3], basis: Basis, seed: u64, scale: f32) -> CoefficientVolume {
    let grid = Grid {
        origin: Vec3::new(-0.4, 0.3, 0.1),
        spacing: 0.1,
        dims,
        offset: Default::default(),
    };
    let mut r = random(seed);
    let coeffs = (0..grid.len()).map(|_| r() * scale).collect();
    CoefficientVolume::new(grid, basis, coeffs).unwrap()
}

/// A 37 × 29 × 26 grid (spacing 0.1) of background `bg`: a few stored bricks of random values
/// in ±0.4 with the bricks beside them inside, and a corner region inside with no stored brick
/// at its border, where the field passes near zero between the two backgrounds.
pub(crate) fn sparse(basis: Basis, bg: Background, seed: u64) -> CoefficientVolume {
    let grid = Grid {
        origin: Vec3::ZERO,
        spacing: 0.1,
        dims: [37, 29, 26],
        offset: Default::default(),
    };
    let mut r = random(seed);
    let mut coeffs = SparseGrid::new(grid.dims, bg);
    for b in [[1, 1, 1], [2, 1, 1], [4, 3, 2], [1, 2, 3]] {
        let mut v = Box::new([0.0; BRICK_NODES]);
        v.iter_mut().for_each(|c| *c = r() * 0.4);
        coeffs.insert(b, v);
    }
    for b in [
        [3, 1, 1],
        [1, 1, 2],
        [4, 3, 1],
        [0, 3, 0],
        [4, 0, 3],
        [4, 1, 3],
    ] {
        coeffs.set_inside(b, true);
    }
    CoefficientVolume::from_sparse(grid, basis, coeffs).unwrap()
}
