//! The fitting matrix restricted to the coefficients a set of sample points can move (the
//! "active" ones), applied without storing it. Unknown vectors hold only the active
//! coefficients, in grid order; a grid-sized scratch array lets the forward product read
//! coefficients by grid index, and the transposed product accumulate into it by blocks of
//! z-layers (see [`LayerBlocks`]).

use std::ops::Range;

use glam::Vec3;
use rayon::prelude::*;

use super::layer_blocks::{LayerBlocks, LAYERS};
use super::row_kernels;
use super::row_window::{windows, Window};

use crate::basis::Basis;
use crate::stencil::{self, VALUE};

/// Where the basis functions of each sample point lie: the point's window, for bases that have
/// one on grids of at least 4 nodes per axis (other cases go through the generic stencil), and
/// the rows grouped by the z-layers they reach.
pub(crate) struct RowStencils<'a> {
    pub basis: Basis,
    pub dims: [usize; 3],
    pub points: &'a [Vec3],
    windows: Option<Vec<Window>>,
    blocks: LayerBlocks,
}

impl<'a> RowStencils<'a> {
    /// The stencils of `points` (grid coordinates, inside the grid box).
    pub fn new(basis: Basis, dims: [usize; 3], points: &'a [Vec3]) -> Self {
        Self::with_windows(basis, dims, points, windows(basis, dims, points))
    }

    fn with_windows(
        basis: Basis,
        dims: [usize; 3],
        points: &'a [Vec3],
        windows: Option<Vec<Window>>,
    ) -> Self {
        let [nx, ny, nz] = dims;
        let blocks = match &windows {
            Some(w) => LayerBlocks::new(nz, LAYERS, w.len(), |i| {
                let k = w[i].layer(nx * ny);
                k..=k + 3
            }),
            None => {
                // Nodes past the support, and mirrored ones, lie within one more spacing.
                let reach = basis.support() + 1.0;
                let layers = LAYERS.max(2 * reach.ceil() as usize);
                LayerBlocks::new(nz, layers, points.len(), |i| {
                    let z = points[i].z;
                    let lo = (z - reach).floor().max(0.0) as usize;
                    let hi = ((z + reach).ceil() as usize).min(nz - 1);
                    lo..=hi
                })
            }
        };
        RowStencils {
            basis,
            dims,
            points,
            windows,
            blocks,
        }
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Calls `f(flat index, weight)` for the nodes of row `i` in the z-layers `layers`.
    #[inline]
    fn visit_layers(&self, i: usize, layers: &Range<usize>, mut f: impl FnMut(usize, f64)) {
        let [nx, ny, _] = self.dims;
        let plane = nx * ny;
        match &self.windows {
            Some(windows) => {
                let win = &windows[i];
                let within = win.layers_within(layers, plane);
                win.for_each(within, nx, plane, f);
            }
            None => {
                let nodes = layers.start * plane..layers.end * plane;
                stencil::visit::<VALUE>(self.basis, self.dims, self.points[i], |j, jet| {
                    if nodes.contains(&j) {
                        f(j, jet.value as f64);
                    }
                });
            }
        }
    }

    /// Runs `f(first node, slab)` on every block of layers, in parallel, `slab` being the
    /// block's part of the grid-sized `grid`; returns the results in block order.
    fn per_block<R: Send>(
        &self,
        grid: &mut [f64],
        f: impl Fn(usize, &mut [f64]) -> R + Sync,
    ) -> Vec<R> {
        let [nx, ny, _] = self.dims;
        let span = self.blocks.layers * nx * ny;
        grid.par_chunks_mut(span)
            .enumerate()
            .map(|(b, slab)| f(b * span, slab))
            .collect()
    }

    /// Adds `value(i) · B_j(p_i)` (`B_j²` when `SQUARED`) to `slab[j − lo]` for the nodes j of
    /// the block starting at node `lo`, row by row in order.
    fn accumulate<const SQUARED: bool>(
        &self,
        slab: &mut [f64],
        lo: usize,
        value: &(impl Fn(usize) -> f64 + Sync),
    ) {
        let [nx, ny, nz] = self.dims;
        let plane = nx * ny;
        let b = lo / (self.blocks.layers * plane);
        let layers = self.blocks.layer_range(b, nz);
        let rows = self.blocks.rows[b].clone();
        match &self.windows {
            Some(windows) => row_kernels::accumulate::<SQUARED>(
                windows, rows, &layers, value, slab, lo, nx, plane,
            ),
            None => {
                for i in rows {
                    let v = value(i);
                    self.visit_layers(i, &layers, |j, w| {
                        slab[j - lo] += v * if SQUARED { w * w } else { w };
                    });
                }
            }
        }
    }

    /// The columns where `Σ_i value(i) · B_j(p_i)²` is non-zero (ascending) with those sums,
    /// accumulated in `grid`, which must be zero and is left holding them.
    fn squared_column_sums(
        &self,
        grid: &mut [f64],
        value: impl Fn(usize) -> f64 + Sync,
    ) -> (Vec<usize>, Vec<f64>) {
        let [nx, ny, nz] = self.dims;
        let blocks = self.per_block(grid, |lo, slab| {
            self.accumulate::<true>(slab, lo, &value);
            // Only x lines some window reaches can hold non-zeros: the rest of the slab, most
            // of it, is neither read nor brought into memory.
            let lines = self.reached_lines(lo, nx, ny, nz);
            let columns: Vec<usize> = (0..lines.len())
                .filter(|&l| lines[l])
                .flat_map(|l| l * nx..(l + 1) * nx)
                .filter(|&j| slab[j] != 0.0)
                .collect();
            let sums = columns.iter().map(|&j| slab[j]).collect::<Vec<f64>>();
            (
                columns.into_iter().map(|j| lo + j).collect::<Vec<_>>(),
                sums,
            )
        });
        let (columns, sums): (Vec<_>, Vec<_>) = blocks.into_iter().unzip();
        (columns.concat(), sums.concat())
    }

    /// Which x lines of the block starting at node `lo` (by `y + ny · layer`, layers counted
    /// from the block's first) some row reaches; every line for stencils without windows.
    fn reached_lines(&self, lo: usize, nx: usize, ny: usize, nz: usize) -> Vec<bool> {
        let plane = nx * ny;
        let b = lo / (self.blocks.layers * plane);
        let layers = self.blocks.layer_range(b, nz);
        let Some(windows) = &self.windows else {
            return vec![true; layers.len() * ny];
        };
        let mut lines = vec![false; layers.len() * ny];
        for win in &windows[self.blocks.rows[b].clone()] {
            let k = win.layer(plane);
            let j = (win.first % plane) / nx;
            for c in win.layers_within(&layers, plane) {
                let line = j + ny * (k + c - layers.start);
                lines[line..line + 4].fill(true);
            }
        }
        lines
    }

    /// `Σ_i value(i) · B_j(p_i)` for every column j of `active`. Each block zeroes the active
    /// entries of its part of `grid`, adds its rows' terms there and reads them out; entries off
    /// `active` only ever receive zeros.
    fn scatter(
        &self,
        grid: &mut [f64],
        active: &[usize],
        value: impl Fn(usize) -> f64 + Sync,
    ) -> Vec<f64> {
        let blocks = self.per_block(grid, |lo, slab| {
            let first = active.partition_point(|&j| j < lo);
            let last = active.partition_point(|&j| j < lo + slab.len());
            let columns = &active[first..last];
            for &j in columns {
                slab[j - lo] = 0.0;
            }
            self.accumulate::<false>(slab, lo, &value);
            columns.iter().map(|&j| slab[j - lo]).collect::<Vec<f64>>()
        });
        blocks.concat()
    }
}

/// `W^½ A` on the active columns stacked over `anchor · I` (one row per unknown holding it to its
/// start), each column scaled by `scale` (the Jacobi preconditioner).
pub(crate) struct BandOperator<'a> {
    pub stencils: RowStencils<'a>,
    pub sqrt_weights: &'a [f64],
    /// The coefficients some weighted sample reaches (grid indices, ascending): the unknowns.
    /// The others cannot lower the objective, so they keep their start.
    pub active: Vec<usize>,
    pub anchor: f64,
    /// One over each column's norm.
    pub scale: Vec<f64>,
    /// Grid-sized, zero outside the active columns.
    scratch: Vec<f64>,
}

impl<'a> BandOperator<'a> {
    /// The operator on the columns the rows reach, Jacobi-scaled: each column's squared norm
    /// is found with the column itself.
    pub fn new(stencils: RowStencils<'a>, sqrt_weights: &'a [f64], anchor: f64) -> Self {
        let mut scratch = vec![0.0; stencils.dims.iter().product()];
        let w = sqrt_weights;
        let (active, norms_sq) = stencils.squared_column_sums(&mut scratch, |i| w[i] * w[i]);
        let a2 = anchor * anchor;
        let scale = norms_sq
            .iter()
            .map(|&s| {
                if s + a2 > 1e-24 {
                    1.0 / (s + a2).sqrt()
                } else {
                    0.0
                }
            })
            .collect();
        BandOperator {
            stencils,
            sqrt_weights,
            active,
            anchor,
            scale,
            scratch,
        }
    }

    /// Sample rows then anchor rows.
    pub fn rows(&self) -> usize {
        self.stencils.len() + self.active.len()
    }

    /// `[W^½ A; anchor I] D y`.
    pub fn forward(&mut self, y: &[f64]) -> Vec<f64> {
        for ((&j, &y), &s) in self.active.iter().zip(y).zip(&self.scale) {
            self.scratch[j] = y * s;
        }
        let mut out = Vec::with_capacity(self.rows());
        self.product_into(&self.scratch, &mut out);
        out.extend(y.iter().zip(&self.scale).map(|(y, s)| self.anchor * s * y));
        out
    }

    /// `W^½ A c` for a grid-sized coefficient vector `c`, every column included.
    pub fn full_product<T: Copy + Into<f64> + Sync>(&self, c: &[T]) -> Vec<f64> {
        let mut out = Vec::new();
        self.product_into(c, &mut out);
        out
    }

    fn product_into<T: Copy + Into<f64> + Sync>(&self, c: &[T], out: &mut Vec<f64>) {
        let RowStencils {
            basis,
            dims,
            points,
            ..
        } = self.stencils;
        let [nx, ny, _] = dims;
        if let Some(windows) = &self.stencils.windows {
            return windows
                .par_iter()
                .zip(self.sqrt_weights)
                .map(|(win, &w)| win.dot(c, nx, nx * ny) * w)
                .collect_into_vec(out);
        }
        points
            .par_iter()
            .zip(self.sqrt_weights)
            .map(|(&u, &w)| {
                let mut s = 0.0f64;
                stencil::visit::<VALUE>(basis, dims, u, |j, jet| {
                    s += c[j].into() * jet.value as f64;
                });
                s * w
            })
            .collect_into_vec(out)
    }

    /// `D [Aᵀ W^½, anchor I] r`.
    pub fn adjoint(&mut self, r: &[f64]) -> Vec<f64> {
        let (samples, anchors) = r.split_at(self.stencils.len());
        let w = self.sqrt_weights;
        let mut g = self
            .stencils
            .scatter(&mut self.scratch, &self.active, |i| samples[i] * w[i]);
        for ((g, s), a) in g.iter_mut().zip(&self.scale).zip(anchors) {
            *g = (*g + self.anchor * a) * s;
        }
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ⟨A y, r⟩ = ⟨y, Aᵀ r⟩ for random vectors: the two products are transposes.
    #[test]
    fn adjoint_is_the_transpose_of_forward() {
        let dims = [14, 12, 16];
        let points: Vec<Vec3> = (0..300)
            .map(|i| {
                let t = i as f32;
                Vec3::new(
                    4.0 + 2.5 * (t * 0.37).sin(),
                    3.5 + 2.0 * (t * 0.71).cos(),
                    4.5 + 3.0 * (t * 0.13).sin(),
                )
            })
            .collect();
        let w: Vec<f64> = (0..points.len()).map(|i| 0.5 + (i % 3) as f64).collect();
        for basis in [
            Basis::Bspline3,
            Basis::Trilinear,
            Basis::Pg { n: 3, r: 1.5 },
        ] {
            let mut op = BandOperator::new(RowStencils::new(basis, dims, &points), &w, 0.3);
            let active = op.active.clone();
            // The points fill only part of the grid.
            assert!(!active.is_empty() && active.len() < 14 * 12 * 16 / 2);
            let y: Vec<f64> = (0..active.len())
                .map(|i| ((i * 7) % 5) as f64 - 2.0)
                .collect();
            let r: Vec<f64> = (0..op.rows()).map(|i| ((i * 3) % 4) as f64 - 1.5).collect();
            let ay = op.forward(&y);
            let atr = op.adjoint(&r);
            let lhs: f64 = ay.iter().zip(&r).map(|(a, b)| a * b).sum();
            let rhs: f64 = y.iter().zip(&atr).map(|(a, b)| a * b).sum();
            assert!(
                (lhs - rhs).abs() < 1e-9 * lhs.abs().max(1.0),
                "{basis}: {lhs} vs {rhs}"
            );
            // Scaled columns have unit norm.
            let mut unit = vec![0.0; active.len()];
            unit[active.len() / 2] = 1.0;
            let col = op.forward(&unit);
            let norm: f64 = col.iter().map(|v| v * v).sum();
            assert!((norm - 1.0).abs() < 1e-6, "{basis}: {norm}");
        }
    }

    /// Precomputed windows, mirrored nodes folded in, give the generic stencil's products.
    /// The operator assembled as a stored sparse matrix (sprs) from the generic stencil, entry
    /// by entry: the matrix-free products must equal its products and its transpose's.
    #[test]
    fn products_equal_a_stored_matrix_built_from_the_stencil() {
        use sprs::{CsMat, TriMat};
        let dims = [11, 9, 13];
        let points = scattered_points(dims, 400);
        let w: Vec<f64> = (0..points.len()).map(|i| 0.3 + (i % 4) as f64).collect();
        for basis in [
            Basis::Bspline3,
            Basis::Bspline2,
            Basis::Trilinear,
            Basis::Pg { n: 2, r: 2.0 },
        ] {
            let mut op = BandOperator::new(RowStencils::new(basis, dims, &points), &w, 0.2);
            let (n_rows, n_cols) = (op.rows(), op.active.len());
            let column = |j: usize| op.active.binary_search(&j).ok();
            let mut entries = TriMat::new((n_rows, n_cols));
            for (i, &u) in points.iter().enumerate() {
                stencil::visit::<VALUE>(basis, dims, u, |j, jet| {
                    if jet.value != 0.0 {
                        let c = column(j).expect("a reached coefficient is an unknown");
                        entries.add_triplet(i, c, w[i] * f64::from(jet.value) * op.scale[c]);
                    }
                });
            }
            for c in 0..n_cols {
                entries.add_triplet(points.len() + c, c, op.anchor * op.scale[c]);
            }
            let matrix: CsMat<f64> = entries.to_csr();
            let y: Vec<f64> = (0..n_cols).map(|i| ((i * 5) % 7) as f64 - 3.0).collect();
            let r: Vec<f64> = (0..n_rows).map(|i| ((i * 3) % 5) as f64 - 2.0).collect();
            let stored_ay = &matrix * &sparse(&y);
            let stored_atr = &matrix.transpose_view() * &sparse(&r);
            // The operator keeps per-axis weights in f32 and multiplies them out in its own
            // order, so entries agree to single precision; a wrong index or weight is O(1).
            let close = |a: &[f64], b: &[f64]| {
                a.len() == b.len()
                    && a.iter()
                        .zip(b)
                        .all(|(x, y)| (x - y).abs() <= 1e-5 * (1.0 + y.abs()))
            };
            assert!(
                close(&op.forward(&y), &dense(&stored_ay, n_rows)),
                "{basis}: A y"
            );
            assert!(
                close(&op.adjoint(&r), &dense(&stored_atr, n_cols)),
                "{basis}: Aᵀ r"
            );
        }
    }

    /// `v` as a sparse vector, for products with a stored matrix.
    fn sparse(v: &[f64]) -> sprs::CsVec<f64> {
        let (idx, val): (Vec<usize>, Vec<f64>) = v
            .iter()
            .enumerate()
            .filter(|(_, x)| **x != 0.0)
            .map(|(i, &x)| (i, x))
            .unzip();
        sprs::CsVec::new(v.len(), idx, val)
    }

    fn dense(v: &sprs::CsVec<f64>, len: usize) -> Vec<f64> {
        let mut out = vec![0.0; len];
        for (i, &x) in v.iter() {
            out[i] = x;
        }
        out
    }

    #[test]
    fn windows_match_the_stencil_at_the_border() {
        let dims = [5, 6, 4];
        let points: Vec<Vec3> = (0..200)
            .map(|i| {
                let t = i as f32;
                Vec3::new(
                    2.0 + 2.0 * (t * 0.37).sin(),
                    2.5 + 2.5 * (t * 0.71).cos(),
                    1.5 + 1.5 * (t * 0.13).sin(),
                )
            })
            .collect();
        let w = vec![1.0; points.len()];
        for basis in [Basis::Bspline3, Basis::Bspline2, Basis::Trilinear] {
            let fast = RowStencils::new(basis, dims, &points);
            assert!(fast.windows.is_some());
            let slow = RowStencils::with_windows(basis, dims, &points, None);
            let mut fast = BandOperator::new(fast, &w, 0.3);
            let mut slow = BandOperator::new(slow, &w, 0.3);
            assert_eq!(fast.active, slow.active, "{basis}");
            let active = fast.active.clone();
            // Compare the products, not the scales: the stencil counts a mirrored node once per
            // visit in its column norm, the window once with the folded weight.
            fast.scale.fill(1.0);
            slow.scale.fill(1.0);
            let y: Vec<f64> = (0..active.len())
                .map(|i| ((i * 7) % 5) as f64 - 2.0)
                .collect();
            for (a, b) in fast.forward(&y).iter().zip(&slow.forward(&y)) {
                assert!((a - b).abs() < 1e-6, "{basis}: {a} vs {b}");
            }
            let r: Vec<f64> = (0..fast.rows())
                .map(|i| ((i * 3) % 4) as f64 - 1.5)
                .collect();
            for (a, b) in fast.adjoint(&r).iter().zip(&slow.adjoint(&r)) {
                assert!((a - b).abs() < 1e-6, "{basis}: {a} vs {b}");
            }
        }
    }

    /// Points spread over many z-layers in scrambled order, so that rows reach several blocks
    /// and blocks take rows from all over.
    fn scattered_points(dims: [usize; 3], n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let t = (i * 7919 % n) as f32;
                Vec3::new(
                    (dims[0] - 1) as f32 * (0.5 + 0.5 * (t * 0.37).sin()),
                    (dims[1] - 1) as f32 * (0.5 + 0.5 * (t * 0.71).cos()),
                    (dims[2] - 1) as f32 * (0.5 + 0.5 * (t * 0.013).sin()),
                )
            })
            .collect()
    }

    /// The active columns are exactly the nodes some point's stencil weighs.
    #[test]
    fn active_columns_are_the_nodes_the_stencils_reach() {
        let dims = [9, 7, 40];
        let points = scattered_points(dims, 150);
        for basis in [Basis::Bspline3, Basis::Bspline2, Basis::Pg { n: 3, r: 1.5 }] {
            let mut want = vec![false; dims.iter().product()];
            for &u in &points {
                stencil::visit::<VALUE>(basis, dims, u, |j, jet| {
                    want[j] |= jet.value != 0.0;
                });
            }
            let want: Vec<usize> = (0..want.len()).filter(|&j| want[j]).collect();
            let w = vec![1.0; points.len()];
            let op = BandOperator::new(RowStencils::new(basis, dims, &points), &w, 0.3);
            assert_eq!(op.active, want, "{basis}");
        }
    }

    /// Products are bit for bit the same on one thread as on several.
    #[test]
    fn products_do_not_depend_on_the_thread_count() {
        let dims = [12, 10, 50];
        let points = scattered_points(dims, 2000);
        let w: Vec<f64> = (0..points.len()).map(|i| 0.5 + (i % 3) as f64).collect();
        for basis in [Basis::Bspline3, Basis::Pg { n: 3, r: 1.5 }] {
            let run = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| {
                    let mut op = BandOperator::new(RowStencils::new(basis, dims, &points), &w, 0.3);
                    let r: Vec<f64> = (0..op.rows()).map(|i| (i as f64 * 0.37).sin()).collect();
                    let g = op.adjoint(&r);
                    let f = op.forward(&g);
                    (op.active.clone(), op.scale.clone(), g, f)
                })
            };
            let one = run(1);
            for threads in [2, 3, 8] {
                assert!(one == run(threads), "{basis}: {threads} threads");
            }
        }
    }
}
