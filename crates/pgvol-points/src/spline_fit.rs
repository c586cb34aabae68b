//! The `spline` method's fit: the cubic B-spline coefficients of the band's bricks fitted
//! directly to the constraints (value 0 at the points, ±ε off the surface) by weighted least
//! squares, with a smoothness term (squared second differences of the coefficients along each
//! axis) for the regions the points leave open and a weak pull towards a starting volume (the
//! tangent-plane field's) where no constraint reaches:
//!
//! minimise Σ_c (f(x_c) − h_c)² + λ Σ_axes ‖D² x‖² + μ ‖x − x₀‖².
//!
//! The normal equations are solved matrix-free by conjugate gradients with a Jacobi
//! preconditioner, starting from x₀. Each product visits the 4³ coefficients of every
//! constraint and six neighbours of every unknown, so memory and time follow the surface:
//! the unknowns are the stored bricks only, the other coefficients keep their background.

use glam::Vec3;
use pgvol_core::sparse::{brick_offset, BRICK_EDGE, BRICK_NODES};
use pgvol_core::{Grid, SparseGrid};
use rayon::prelude::*;

/// Weight λ of the squared second differences, relative to one constraint's squared
/// residual (both in the field's units). On spot at 64³ from 2 500 to 20 000 points, 0.003
/// loses detail between sparse points and 0.03 flattens the dense ones (`docs/points.md`).
pub const SMOOTHNESS: f32 = 0.01;

/// Weight μ of the pull towards the starting coefficients at one point per grid spacing; see
/// [`pull_weight`].
pub const PULL: f32 = 0.003;

/// The pull μ for points `spacing` apart on a grid of `grid_spacing`: [`PULL`] × (grid
/// spacing / point spacing)⁴. The tangent-plane field the pull leads to is poor where points
/// are about a grid spacing apart and close to exact where several share a cell, faster than
/// the data term's weight per coefficient grows (the square of that ratio). Measured on spot:
/// best μ about 0.001–0.003 at 2 500 points on 64³ (ratio 1.3) and about 1 at 10 000 (2.5).
pub fn pull_weight(grid_spacing: f32, spacing: f32) -> f32 {
    PULL * (grid_spacing / spacing.max(f32::MIN_POSITIVE)).powi(4)
}

/// Residual of the normal equations, relative to their right-hand side, at which the
/// iterations stop.
pub const TOLERANCE: f64 = 1e-4;

/// Iteration cap.
pub const MAX_ITERATIONS: usize = 400;

/// Bytes per stored brick while fitting: per unknown eight f64 vectors (solution, start,
/// right-hand side, diagonal, residual, preconditioned residual, direction, product), three
/// second differences, six neighbour indices and one f64 per chunk of rows (four chunks on two
/// threads; `fit_bytes` scales it).
const BYTES_PER_UNKNOWN: u64 = 8 * 8 + 3 * 8 + 6 * 4;

/// Bytes per constraint row.
pub const BYTES_PER_ROW: u64 = size_of::<Row>() as u64;

/// Estimated peak bytes of [`fit`] over `bricks` stored bricks and `constraints` rows.
pub fn fit_bytes(bricks: u64, constraints: u64) -> u64 {
    let chunks = 2 * rayon::current_num_threads().max(1) as u64;
    let per_unknown = BYTES_PER_UNKNOWN + 8 * chunks;
    bricks
        .saturating_mul(BRICK_NODES as u64 * per_unknown)
        .saturating_add(constraints.saturating_mul(BYTES_PER_ROW))
}

/// What the fit did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SplineFitReport {
    /// Unknown coefficients (nodes of the stored bricks inside the grid).
    pub unknowns: usize,
    /// Constraints used (those whose 4³ coefficients are all unknowns).
    pub constraints: usize,
    pub iterations: usize,
    /// Final relative residual of the normal equations.
    pub residual: f64,
}

/// The unknowns: every node inside the grid of the stored bricks of the starting volume.
struct Unknowns {
    dims: [usize; 3],
    brick_counts: [usize; 3],
    /// Slot of each brick in the unknown vector, `u32::MAX` when not stored.
    slot: Vec<u32>,
    /// The stored bricks, by slot.
    bricks: Vec<[usize; 3]>,
}

impl Unknowns {
    fn new(start: &SparseGrid) -> Self {
        let counts = start.brick_counts();
        let mut slot = vec![u32::MAX; counts.iter().product()];
        let bricks: Vec<[usize; 3]> = start.stored().map(|(b, _)| b).collect();
        for (s, b) in bricks.iter().enumerate() {
            slot[b[0] + counts[0] * (b[1] + counts[1] * b[2])] = s as u32;
        }
        Self {
            dims: start.dims(),
            brick_counts: counts,
            slot,
            bricks,
        }
    }

    fn len(&self) -> usize {
        self.bricks.len() * BRICK_NODES
    }

    /// The unknown of node `n` (grid indices, maybe out of range), if it is one.
    #[inline]
    fn index(&self, n: [i64; 3]) -> Option<usize> {
        let mut b = [0usize; 3];
        let mut local = [0usize; 3];
        for a in 0..3 {
            if n[a] < 0 || n[a] as usize >= self.dims[a] {
                return None;
            }
            b[a] = n[a] as usize / BRICK_EDGE;
            local[a] = n[a] as usize % BRICK_EDGE;
        }
        let c = self.brick_counts;
        let s = self.slot[b[0] + c[0] * (b[1] + c[1] * b[2])];
        (s != u32::MAX).then(|| s as usize * BRICK_NODES + brick_offset(local))
    }

    /// Node indices of unknown `u`, `None` past the grid's end (padding of border bricks).
    #[inline]
    fn node(&self, u: usize) -> Option<[i64; 3]> {
        let b = self.bricks[u / BRICK_NODES];
        let at = u % BRICK_NODES;
        let local = [
            at % BRICK_EDGE,
            at / BRICK_EDGE % BRICK_EDGE,
            at / (BRICK_EDGE * BRICK_EDGE),
        ];
        let n: [usize; 3] = std::array::from_fn(|a| b[a] * BRICK_EDGE + local[a]);
        (0..3)
            .all(|a| n[a] < self.dims[a])
            .then(|| n.map(|v| v as i64))
    }
}

/// Cubic B-spline weights of the four nodes `floor(u) − 1 ..= floor(u) + 2` at `u`.
#[inline]
fn weights(u: f32) -> (i64, [f32; 4]) {
    let f = u.floor();
    let t = u - f;
    let s = 1.0 - t;
    let t2 = t * t;
    let t3 = t2 * t;
    (
        f as i64 - 1,
        [
            s * s * s / 6.0,
            (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
            (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
            t3 / 6.0,
        ],
    )
}

/// One constraint: where it is (grid coordinates), its target, and the slots of the up to
/// 2 × 2 × 2 bricks its 4³ stencil touches (x fastest), from which each node's unknown follows.
/// 48 bytes, against 512 for the stencil's indices and weights.
struct Row {
    at: Vec3,
    target: f32,
    bricks: [u32; 8],
}

impl Row {
    /// Calls `f(unknown, weight)` for the 64 coefficients of the stencil.
    #[inline]
    fn for_each(&self, mut f: impl FnMut(usize, f32)) {
        let axes = [weights(self.at.x), weights(self.at.y), weights(self.at.z)];
        // Per axis and stencil node: which of the two bricks, and the place within it.
        let split = |a: usize| -> [(usize, usize); 4] {
            let base = axes[a].0 as usize;
            let first = base / BRICK_EDGE;
            std::array::from_fn(|i| {
                let n = base + i;
                (n / BRICK_EDGE - first, n % BRICK_EDGE)
            })
        };
        let (sx, sy, sz) = (split(0), split(1), split(2));
        for (k, &(oz, lz)) in sz.iter().enumerate() {
            for (j, &(oy, ly)) in sy.iter().enumerate() {
                let wyz = axes[1].1[j] * axes[2].1[k];
                for (i, &(ox, lx)) in sx.iter().enumerate() {
                    let slot = self.bricks[ox + 2 * (oy + 2 * oz)] as usize;
                    f(
                        slot * BRICK_NODES + brick_offset([lx, ly, lz]),
                        axes[0].1[i] * wyz,
                    );
                }
            }
        }
    }
}

/// The rows of the constraints whose stencil lies wholly on unknowns.
fn rows(grid: &Grid, unknowns: &Unknowns, centres: &[Vec3], values: &[f32]) -> Vec<Row> {
    centres
        .par_iter()
        .zip(values)
        .filter_map(|(&c, &target)| {
            let at = grid.to_grid(c);
            let base = [at.x, at.y, at.z].map(|u| weights(u).0);
            // Every stencil node must be an unknown: inside the grid, in the (up to) 2 × 2 × 2
            // stored bricks its corners fall in. A brick not reached along an axis repeats.
            if (0..3).any(|a| base[a] < 0 || (base[a] + 3) as usize >= unknowns.dims[a]) {
                return None;
            }
            let mut bricks = [0u32; 8];
            for (o, slot) in bricks.iter_mut().enumerate() {
                let corner: [i64; 3] = std::array::from_fn(|a| base[a] + 3 * ((o >> a) & 1) as i64);
                *slot = (unknowns.index(corner)? / BRICK_NODES) as u32;
            }
            Some(Row { at, target, bricks })
        })
        .collect()
}

/// The neighbours of each unknown along each axis, (minus, plus), `u32::MAX` where the
/// neighbour is not an unknown. A second difference is centred on every unknown with both.
fn neighbours(unknowns: &Unknowns) -> Vec<[[u32; 2]; 3]> {
    (0..unknowns.len())
        .into_par_iter()
        .map(|u| {
            let mut out = [[u32::MAX; 2]; 3];
            if let Some(n) = unknowns.node(u) {
                for (a, pair) in out.iter_mut().enumerate() {
                    let mut lo = n;
                    let mut hi = n;
                    lo[a] -= 1;
                    hi[a] += 1;
                    for (end, m) in pair.iter_mut().zip([lo, hi]) {
                        if let Some(v) = unknowns.index(m) {
                            *end = v as u32;
                        }
                    }
                }
            }
            out
        })
        .collect()
}

/// `y = (AᵀA + λ DᵀD + μ I) p` over the unknowns (padding nodes: `y = p`).
struct Operator<'a> {
    rows: &'a [Row],
    neighbours: &'a [[[u32; 2]; 3]],
    inside: &'a [bool],
    smoothness: f64,
    pull: f64,
}

impl Operator<'_> {
    fn apply(&self, p: &[f64], y: &mut [f64]) {
        let n = p.len();
        // Data term, scattered into one buffer per chunk of rows, then summed.
        let chunks = (rayon::current_num_threads() * 2).max(1);
        let per = self.rows.len().div_ceil(chunks).max(1);
        let partial: Vec<Vec<f64>> = self
            .rows
            .par_chunks(per)
            .map(|rows| {
                let mut acc = vec![0.0f64; n];
                for row in rows {
                    let mut r = 0.0f64;
                    row.for_each(|i, w| r += w as f64 * p[i]);
                    row.for_each(|i, w| acc[i] += w as f64 * r);
                }
                acc
            })
            .collect();
        // Second differences centred at every unknown along each axis (0 where one end is
        // missing: no such row).
        let d: Vec<[f64; 3]> = self
            .neighbours
            .par_iter()
            .enumerate()
            .map(|(u, t)| {
                std::array::from_fn(|a| {
                    let [l, h] = t[a];
                    if l == u32::MAX || h == u32::MAX {
                        0.0
                    } else {
                        p[l as usize] - 2.0 * p[u] + p[h as usize]
                    }
                })
            })
            .collect();
        y.par_iter_mut().enumerate().for_each(|(u, yu)| {
            if !self.inside[u] {
                *yu = p[u];
                return;
            }
            let mut v: f64 = partial.iter().map(|acc| acc[u]).sum();
            // Dᵀ: −2 from the difference centred on u, +1 from those centred on its
            // neighbours.
            let mut s = 0.0;
            for (a, ends) in self.neighbours[u].iter().enumerate() {
                s -= 2.0 * d[u][a];
                for &m in ends {
                    if m != u32::MAX {
                        s += d[m as usize][a];
                    }
                }
            }
            v += self.smoothness * s + self.pull * p[u];
            *yu = v;
        });
    }
}

/// Fits the coefficients of `start`'s stored bricks to `values` at `centres` (see the module
/// doc); the other coefficients are kept. `start` is a cubic B-spline coefficient grid on
/// `grid`.
pub fn fit(
    grid: &Grid,
    start: &SparseGrid,
    centres: &[Vec3],
    values: &[f32],
    smoothness: f32,
    pull: f32,
) -> (SparseGrid, SplineFitReport) {
    let unknowns = Unknowns::new(start);
    let n = unknowns.len();
    let rows = rows(grid, &unknowns, centres, values);
    let neighbours = neighbours(&unknowns);
    let inside: Vec<bool> = (0..n)
        .into_par_iter()
        .map(|u| unknowns.node(u).is_some())
        .collect();
    let x0: Vec<f64> = (0..n)
        .into_par_iter()
        .map(|u| {
            let brick = start
                .brick(unknowns.bricks[u / BRICK_NODES])
                .expect("stored");
            brick[u % BRICK_NODES] as f64
        })
        .collect();
    let op = Operator {
        rows: &rows,
        neighbours: &neighbours,
        inside: &inside,
        smoothness: smoothness as f64,
        pull: pull as f64,
    };
    // Right-hand side Aᵀh + μ x₀ (padding: x₀, so it stays put).
    let mut b: Vec<f64> = (0..n)
        .map(|u| {
            if inside[u] {
                pull as f64 * x0[u]
            } else {
                x0[u]
            }
        })
        .collect();
    let mut diag: Vec<f64> = (0..n)
        .map(|u| if inside[u] { pull as f64 } else { 1.0 })
        .collect();
    for row in &rows {
        row.for_each(|i, w| {
            b[i] += w as f64 * row.target as f64;
            diag[i] += (w as f64) * (w as f64);
        });
    }
    for u in 0..n {
        if !inside[u] {
            continue;
        }
        let has_row = |m: u32, a: usize| {
            m != u32::MAX && neighbours[m as usize][a].iter().all(|&e| e != u32::MAX)
        };
        for (a, ends) in neighbours[u].iter().enumerate() {
            if has_row(u as u32, a) {
                diag[u] += 4.0 * smoothness as f64;
            }
            for &m in ends {
                if has_row(m, a) {
                    diag[u] += smoothness as f64;
                }
            }
        }
    }
    let (x, iterations, residual) = preconditioned_cg(|p, y| op.apply(p, y), &b, &diag, x0);
    let mut coeffs = start.clone();
    let bricks = unknowns.bricks.clone();
    for (s, b) in bricks.iter().enumerate() {
        let brick = coeffs.brick_mut(*b).expect("stored");
        for (at, v) in brick.iter_mut().enumerate() {
            *v = x[s * BRICK_NODES + at] as f32;
        }
    }
    (
        coeffs,
        SplineFitReport {
            unknowns: inside.iter().filter(|&&i| i).count(),
            constraints: rows.len(),
            iterations,
            residual,
        },
    )
}

/// Solves A x = b (A symmetric positive definite, given by its product) from `x`, with the
/// Jacobi preconditioner `diag`.
fn preconditioned_cg(
    matvec: impl Fn(&[f64], &mut [f64]),
    b: &[f64],
    diag: &[f64],
    mut x: Vec<f64>,
) -> (Vec<f64>, usize, f64) {
    let n = b.len();
    let dot = |a: &[f64], b: &[f64]| -> f64 { a.par_iter().zip(b).map(|(x, y)| x * y).sum() };
    let norm_b = dot(b, b).sqrt().max(f64::MIN_POSITIVE);
    let mut ax = vec![0.0; n];
    matvec(&x, &mut ax);
    let mut r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
    let mut z: Vec<f64> = r.iter().zip(diag).map(|(r, d)| r / d).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut iterations = 0;
    let mut residual = dot(&r, &r).sqrt() / norm_b;
    while iterations < MAX_ITERATIONS && residual > TOLERANCE {
        matvec(&p, &mut ax);
        let pap = dot(&p, &ax);
        if pap <= 0.0 {
            break;
        }
        let alpha = rz / pap;
        x.par_iter_mut()
            .zip(r.par_iter_mut())
            .zip(p.par_iter().zip(&ax))
            .for_each(|((xi, ri), (pi, api))| {
                *xi += alpha * pi;
                *ri -= alpha * api;
            });
        z.par_iter_mut()
            .zip(&r)
            .zip(diag)
            .for_each(|((zi, ri), di)| *zi = ri / di);
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        p.par_iter_mut()
            .zip(&z)
            .for_each(|(pi, zi)| *pi = zi + beta * *pi);
        rz = rz_new;
        residual = dot(&r, &r).sqrt() / norm_b;
        iterations += 1;
    }
    (x, iterations, residual)
}

#[cfg(test)]
mod tests {
    use super::*;
    use pgvol_core::sparse::Background;

    /// Fits the linear field `n·x − d` from constraints spread through [-0.85, 0.85]³ on a
    /// 24³ grid over [-1, 1]³, starting from it plus a ripple; returns the largest error at
    /// constraints away from the grid's corners (where few constraints hold the outermost
    /// coefficients) and the report.
    fn plane_error(n: Vec3, d: f32) -> (f32, SplineFitReport) {
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), 24).unwrap();
        let plane = |x: Vec3| n.dot(x) - d;
        let [nx, ny, _] = grid.dims;
        let start: Vec<f32> = (0..grid.len())
            .map(|i| plane(grid.point(i % nx, i / nx % ny, i / (nx * ny))) + 0.05 * (i % 7) as f32)
            .collect();
        let start = SparseGrid::from_dense(grid.dims, &start, Background::clamp(1.0));
        let centres: Vec<Vec3> = (0..20_000)
            .map(|i| {
                let t = i as f32;
                Vec3::new(
                    (t * 0.371).fract(),
                    (t * 0.613).fract(),
                    (t * 0.1137).fract(),
                ) * 1.7
                    - 0.85
            })
            .collect();
        let values: Vec<f32> = centres.iter().map(|&c| plane(c)).collect();
        let (coeffs, report) = fit(&grid, &start, &centres, &values, SMOOTHNESS, 1e-6);
        let volume =
            pgvol_field::CoefficientVolume::from_sparse(grid, pgvol_field::Basis::Bspline3, coeffs)
                .unwrap();
        let worst = centres
            .iter()
            .step_by(97)
            .filter(|c| c.abs().max_element() < 0.7)
            .map(|&c| (volume.value(c) - plane(c)).abs())
            .fold(0.0, f32::max);
        (worst, report)
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(6))]
        /// A linear field is the fit's exact answer whatever the start: its second
        /// differences vanish and the cubic B-spline reproduces it from its node values.
        #[test]
        fn recovers_any_plane_from_a_wrong_start(
            nx in -1.0f32..1.0, ny in -1.0f32..1.0, nz in 0.2f32..1.0, d in -0.3f32..0.3,
        ) {
            let n = Vec3::new(nx, ny, nz).normalize();
            let (worst, report) = plane_error(n, d);
            proptest::prop_assert_eq!(report.constraints, 20_000);
            proptest::prop_assert!(report.iterations > 0 && report.residual <= TOLERANCE);
            proptest::prop_assert!(worst < 2e-3, "error {} for {} {}", worst, n, d);
        }
    }

    #[test]
    fn pull_grows_with_the_density() {
        assert_eq!(pull_weight(1.0, 1.0), PULL);
        assert!((pull_weight(2.0, 1.0) - 16.0 * PULL).abs() < 1e-6);
    }
}
