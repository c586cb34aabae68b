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
//! constraint and four neighbours per axis of every unknown, so memory and time follow the
//! surface: the unknowns are the stored bricks only, the other coefficients keep their
//! background. The constraints' contributions are summed per brick colour (see [`colour`]) so
//! threads never write the same coefficient and no per-thread copy of the vector is needed.

use glam::Vec3;
use pgvol_core::sparse::{brick_offset, BRICK_EDGE, BRICK_NODES};
use pgvol_core::{Grid, SparseGrid};
use rayon::prelude::*;
use std::ops::Range;

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

/// Bytes per unknown while fitting: five f32 vectors (solution, residual, direction, product,
/// diagonal). Neighbours and second differences are recomputed in each product rather than
/// stored.
const BYTES_PER_UNKNOWN: u64 = 5 * 4;

/// Bytes per constraint row.
pub const BYTES_PER_ROW: u64 = size_of::<Row>() as u64;

/// Estimated peak bytes of [`fit`] over `bricks` stored bricks and `constraints` rows: the
/// vectors, the rows, and the scatter blocks of one colour class (an eighth of the bricks,
/// each with its 2 × 2 × 2 bricks of f64 sums).
pub fn fit_bytes(bricks: u64, constraints: u64) -> u64 {
    let per_brick = BRICK_NODES as u64 * BYTES_PER_UNKNOWN;
    let scatter = (bricks / 8 + 1).saturating_mul(8 * BRICK_NODES as u64 * 8);
    bricks
        .saturating_mul(per_brick)
        .saturating_add(scatter)
        .saturating_add(constraints.saturating_mul(BYTES_PER_ROW + 4))
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
    /// Whether the residual reached [`TOLERANCE`] before the iteration cap.
    pub converged: bool,
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

    /// The slot of the brick at `brick`, if it is stored.
    #[inline]
    fn slot_of(&self, brick: [usize; 3]) -> Option<usize> {
        let c = self.brick_counts;
        if (0..3).any(|a| brick[a] >= c[a]) {
            return None;
        }
        let s = self.slot[brick[0] + c[0] * (brick[1] + c[1] * brick[2])];
        (s != u32::MAX).then_some(s as usize)
    }

    /// The unknown `k` nodes from node `n` (unknown `u`) along axis `a`, if it is one; found
    /// without a brick lookup when it lies in u's own brick.
    #[inline]
    fn neighbour(&self, n: [i64; 3], u: usize, a: usize, k: i64) -> Option<usize> {
        let local = n[a] % BRICK_EDGE as i64 + k;
        let m = n[a] + k;
        if (0..BRICK_EDGE as i64).contains(&local) && m < self.dims[a] as i64 {
            let stride = (BRICK_EDGE as i64).pow(a as u32);
            return Some((u as i64 + k * stride) as usize);
        }
        let mut node = n;
        node[a] = m;
        self.index(node)
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

    /// Calls `f(unknown, node, &mut values[unknown])` for every unknown in parallel, brick by
    /// brick; `node` is `None` for padding past the grid's end.
    fn for_each_unknown(
        &self,
        values: &mut [f32],
        f: impl Fn(usize, Option<[i64; 3]>, &mut f32) + Sync,
    ) {
        values
            .par_chunks_mut(BRICK_NODES)
            .zip(&self.bricks)
            .enumerate()
            .for_each(|(slot, (values, b))| {
                for (at, v) in values.iter_mut().enumerate() {
                    let local = [
                        at % BRICK_EDGE,
                        at / BRICK_EDGE % BRICK_EDGE,
                        at / (BRICK_EDGE * BRICK_EDGE),
                    ];
                    let n: [usize; 3] = std::array::from_fn(|a| b[a] * BRICK_EDGE + local[a]);
                    let inside = (0..3).all(|a| n[a] < self.dims[a]);
                    f(
                        slot * BRICK_NODES + at,
                        inside.then(|| n.map(|v| v as i64)),
                        v,
                    );
                }
            });
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
    /// Calls `f(brick, offset, weight)` for the 64 coefficients of the stencil, where `brick`
    /// (0..8, x fastest) is which of the 2 × 2 × 2 bricks from the stencil's lowest corner's
    /// brick holds the coefficient and `offset` its place in that brick.
    #[inline]
    fn for_each_local(&self, mut f: impl FnMut(usize, usize, f32)) {
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
                    f(
                        ox + 2 * (oy + 2 * oz),
                        brick_offset([lx, ly, lz]),
                        axes[0].1[i] * wyz,
                    );
                }
            }
        }
    }

    /// Calls `f(unknown, weight)` for the 64 coefficients of the stencil.
    #[inline]
    fn for_each(&self, mut f: impl FnMut(usize, f32)) {
        self.for_each_local(|o, at, w| f(self.bricks[o] as usize * BRICK_NODES + at, w));
    }

    /// `Σ w p` over the stencil.
    #[inline]
    fn dot(&self, p: &[f32]) -> f64 {
        let mut r = 0.0f64;
        self.for_each(|i, w| r += w as f64 * p[i] as f64);
        r
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

/// The colour of a brick: the parities of its coordinates. The rows whose lowest stencil
/// corner lies in bricks of one colour write disjoint sets of bricks (their 2 × 2 × 2 blocks are
/// at least two bricks apart along some axis), so a colour's blocks can be summed in parallel.
fn colour(brick: [usize; 3]) -> usize {
    (brick[0] & 1) | (brick[1] & 1) << 1 | (brick[2] & 1) << 2
}

/// Sorts `rows` by colour and base brick (the brick of the stencil's lowest corner) and returns,
/// per colour, the ranges of rows sharing a base brick.
fn group(unknowns: &Unknowns, rows: &mut [Row]) -> [Vec<Range<usize>>; 8] {
    let key = |row: &Row| {
        let base = row.bricks[0];
        (colour(unknowns.bricks[base as usize]), base)
    };
    rows.par_sort_unstable_by_key(key);
    let mut groups: [Vec<Range<usize>>; 8] = Default::default();
    let mut start = 0;
    while start < rows.len() {
        let k = key(&rows[start]);
        let end = start + rows[start..].partition_point(|r| key(r) == k);
        groups[k.0].push(start..end);
        start = end;
    }
    groups
}

/// Groups summed at once per colour: enough to keep every thread busy, few enough that their
/// blocks (32 KiB each) stay small.
fn batch_len() -> usize {
    16 * rayon::current_num_threads().max(1)
}

/// `y = (AᵀA + λ DᵀD + μ I) p` over the unknowns (padding nodes: `y = p`).
struct Operator<'a> {
    unknowns: &'a Unknowns,
    rows: &'a [Row],
    groups: &'a [Vec<Range<usize>>; 8],
    smoothness: f64,
    pull: f64,
}

impl Operator<'_> {
    fn apply(&self, p: &[f32], y: &mut [f32]) {
        self.unknowns.for_each_unknown(y, |u, node, yu| {
            *yu = match node {
                None => p[u],
                Some(n) => {
                    (self.smoothness * self.second_differences(n, u, p) + self.pull * p[u] as f64)
                        as f32
                }
            };
        });
        self.scatter(y, 1, |row| row.dot(p));
    }

    /// `(DᵀD p)_u` for the unknown `u` at node `n`: along each axis, the second differences
    /// centred at u − e, u and u + e that exist (both ends unknowns), weighted 1, −2 and 1.
    fn second_differences(&self, n: [i64; 3], u: usize, p: &[f32]) -> f64 {
        let at = |i: Option<usize>| i.map(|i| p[i] as f64);
        let pu = p[u] as f64;
        let mut s = 0.0;
        for a in 0..3 {
            let step = |k: i64| at(self.unknowns.neighbour(n, u, a, k));
            let (m2, m1, p1, p2) = (step(-2), step(-1), step(1), step(2));
            if let (Some(m1), Some(p1)) = (m1, p1) {
                s -= 2.0 * (m1 - 2.0 * pu + p1);
            }
            if let (Some(m2), Some(m1)) = (m2, m1) {
                s += m2 - 2.0 * m1 + pu;
            }
            if let (Some(p1), Some(p2)) = (p1, p2) {
                s += pu - 2.0 * p1 + p2;
            }
        }
        s
    }

    /// `y += Σ_rows w^power s(row)` over each row's stencil weights w: per colour, each base
    /// brick's rows summed into a block of its 2 × 2 × 2 bricks in parallel, the blocks then
    /// added to `y` (disjoint within a colour). With `s(row) = row·p` and power 1 it is `AᵀA p`.
    fn scatter(&self, y: &mut [f32], power: i32, s: impl Fn(&Row) -> f64 + Sync) {
        for groups in self.groups {
            for batch in groups.chunks(batch_len()) {
                let blocks: Vec<(u32, Vec<f64>)> = batch
                    .par_iter()
                    .map(|range| {
                        let rows = &self.rows[range.clone()];
                        let mut block = vec![0.0f64; 8 * BRICK_NODES];
                        for row in rows {
                            let r = s(row);
                            row.for_each_local(|o, at, w| {
                                block[o * BRICK_NODES + at] += (w as f64).powi(power) * r
                            });
                        }
                        (rows[0].bricks[0], block)
                    })
                    .collect();
                for (base, block) in blocks {
                    let b = self.unknowns.bricks[base as usize];
                    for (o, part) in block.chunks(BRICK_NODES).enumerate() {
                        let brick = [b[0] + (o & 1), b[1] + (o >> 1 & 1), b[2] + (o >> 2 & 1)];
                        let Some(slot) = self.unknowns.slot_of(brick) else {
                            continue;
                        };
                        let dst = &mut y[slot * BRICK_NODES..(slot + 1) * BRICK_NODES];
                        for (d, v) in dst.iter_mut().zip(part) {
                            *d += *v as f32;
                        }
                    }
                }
            }
        }
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
    let mut rows = rows(grid, &unknowns, centres, values);
    let groups = group(&unknowns, &mut rows);
    let x0: Vec<f32> = (0..n)
        .into_par_iter()
        .map(|u| {
            start
                .brick(unknowns.bricks[u / BRICK_NODES])
                .expect("stored")[u % BRICK_NODES]
        })
        .collect();
    let op = Operator {
        unknowns: &unknowns,
        rows: &rows,
        groups: &groups,
        smoothness: smoothness as f64,
        pull: pull as f64,
    };
    // Right-hand side Aᵀh + μ x₀ and the diagonal (padding: x₀ and 1, so it stays put).
    let mut b = vec![0.0f32; n];
    unknowns.for_each_unknown(&mut b, |u, node, bu| {
        *bu = if node.is_some() { pull * x0[u] } else { x0[u] }
    });
    op.scatter(&mut b, 1, |row| row.target as f64);
    let mut diag = vec![0.0f32; n];
    unknowns.for_each_unknown(&mut diag, |u, node, du| {
        *du = match node {
            None => 1.0,
            Some(node) => pull + smoothness * smoothness_diagonal(&unknowns, node, u) as f32,
        }
    });
    op.scatter(&mut diag, 2, |_| 1.0);
    let inside = (0..n).filter(|&u| unknowns.node(u).is_some()).count();
    let (x, iterations, residual) =
        preconditioned_cg(|p, y| op.apply(p, y), b, &diag, x0, MAX_ITERATIONS);
    let mut coeffs = start.clone();
    for (s, b) in unknowns.bricks.iter().enumerate() {
        let brick = coeffs.brick_mut(*b).expect("stored");
        brick.copy_from_slice(&x[s * BRICK_NODES..(s + 1) * BRICK_NODES]);
    }
    (
        coeffs,
        SplineFitReport {
            unknowns: inside,
            constraints: rows.len(),
            iterations,
            residual,
            converged: residual <= TOLERANCE,
        },
    )
}

/// `(DᵀD)_uu` at `node`: 4 for the second difference centred there, 1 for each centred on a
/// neighbour, counting those whose ends are both unknowns.
fn smoothness_diagonal(unknowns: &Unknowns, node: [i64; 3], u: usize) -> f64 {
    let mut d = 0.0;
    for a in 0..3 {
        let step = |k: i64| unknowns.neighbour(node, u, a, k).is_some();
        let (m2, m1, p1, p2) = (step(-2), step(-1), step(1), step(2));
        if m1 && p1 {
            d += 4.0;
        }
        if m2 && m1 {
            d += 1.0;
        }
        if p1 && p2 {
            d += 1.0;
        }
    }
    d
}

/// Solves A x = b (A symmetric positive definite, given by its product) from `x`, with the
/// Jacobi preconditioner `diag`, in at most `max_iterations`. Vectors are stored in f32 (the
/// coefficients' own precision), sums taken in f64; `b` becomes the residual.
fn preconditioned_cg(
    matvec: impl Fn(&[f32], &mut [f32]),
    mut r: Vec<f32>,
    diag: &[f32],
    mut x: Vec<f32>,
    max_iterations: usize,
) -> (Vec<f32>, usize, f64) {
    let n = r.len();
    let sum = |f: &(dyn Fn(usize) -> f64 + Sync)| -> f64 { (0..n).into_par_iter().map(f).sum() };
    let norm_b = sum(&|i| r[i] as f64 * r[i] as f64)
        .sqrt()
        .max(f64::MIN_POSITIVE);
    let mut ax = vec![0.0f32; n];
    matvec(&x, &mut ax);
    r.par_iter_mut().zip(&ax).for_each(|(r, a)| *r -= a);
    // z = r / diag is formed where used rather than stored.
    let mut p: Vec<f32> = r.iter().zip(diag).map(|(r, d)| r / d).collect();
    let mut rz = sum(&|i| r[i] as f64 * r[i] as f64 / diag[i] as f64);
    let mut iterations = 0;
    let mut residual = sum(&|i| r[i] as f64 * r[i] as f64).sqrt() / norm_b;
    while iterations < max_iterations && residual > TOLERANCE {
        matvec(&p, &mut ax);
        let pap = sum(&|i| p[i] as f64 * ax[i] as f64);
        if pap <= 0.0 {
            break;
        }
        let alpha = rz / pap;
        x.par_iter_mut()
            .zip(r.par_iter_mut())
            .zip(p.par_iter().zip(&ax))
            .for_each(|((xi, ri), (pi, api))| {
                *xi = (*xi as f64 + alpha * *pi as f64) as f32;
                *ri = (*ri as f64 - alpha * *api as f64) as f32;
            });
        let rz_new = sum(&|i| r[i] as f64 * r[i] as f64 / diag[i] as f64);
        let beta = rz_new / rz;
        p.par_iter_mut()
            .zip(&r)
            .zip(diag)
            .for_each(|((pi, ri), di)| *pi = (*ri as f64 / *di as f64 + beta * *pi as f64) as f32);
        rz = rz_new;
        residual = sum(&|i| r[i] as f64 * r[i] as f64).sqrt() / norm_b;
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
            proptest::prop_assert!(report.converged);
            proptest::prop_assert!(worst < 2e-3, "error {} for {} {}", worst, n, d);
        }
    }

    /// A solve cut short by its cap reports a residual above the tolerance, which the fit
    /// reports as not converged; the same solve run on converges.
    #[test]
    fn a_solve_stopped_by_its_cap_is_not_converged() {
        // The 1D Laplacian plus a little diagonal: slow for conjugate gradients.
        let n = 100;
        let matvec = |p: &[f32], y: &mut [f32]| {
            for i in 0..n {
                let left = if i > 0 { p[i - 1] } else { 0.0 };
                let right = if i + 1 < n { p[i + 1] } else { 0.0 };
                y[i] = 2.001 * p[i] - left - right;
            }
        };
        let b: Vec<f32> = (0..n).map(|i| ((i * 7) % 11) as f32 - 5.0).collect();
        let diag = vec![2.001; n];
        let (_, iterations, residual) =
            preconditioned_cg(matvec, b.clone(), &diag, vec![0.0; n], 10);
        assert_eq!(iterations, 10);
        assert!(residual > TOLERANCE, "{residual}");
        let (_, iterations, residual) =
            preconditioned_cg(matvec, b, &diag, vec![0.0; n], MAX_ITERATIONS);
        assert!(
            iterations < MAX_ITERATIONS && residual <= TOLERANCE,
            "{residual}"
        );
    }

    #[test]
    fn pull_grows_with_the_density() {
        assert_eq!(pull_weight(1.0, 1.0), PULL);
        assert!((pull_weight(2.0, 1.0) - 16.0 * PULL).abs() < 1e-6);
    }
}
