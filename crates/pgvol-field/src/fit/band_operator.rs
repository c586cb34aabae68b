//! The fitting matrix restricted to the coefficients a set of sample points can move (the
//! "active" ones), applied without storing it. Unknown vectors hold only the active
//! coefficients, in grid order; a grid-sized scratch array lets the forward product read
//! coefficients by grid index, and the transposed product accumulates per z-slab.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use crate::kernel::{axis_window, Profile};
use crate::stencil::{self, mirror, VALUE};
use crate::Basis;

/// Rows per chunk of the transposed product: about a dozen z-layers of band rows at 256³, so
/// the slab each chunk accumulates into is not mostly margin. Fixed so that results do not
/// depend on the number of threads.
const CHUNK: usize = 131_072;

/// The grid indices (ascending) of every coefficient whose basis function is non-zero at some
/// point of `points` (grid coordinates, inside the grid box).
pub(crate) fn active_columns(basis: Basis, dims: [usize; 3], points: &[Vec3]) -> Vec<usize> {
    let len = dims.iter().product::<usize>();
    let touched: Vec<AtomicBool> = (0..len).map(|_| AtomicBool::new(false)).collect();
    let mark = |j: usize| touched[j].store(true, Ordering::Relaxed);
    let [nx, ny, _] = dims;
    match windows(basis, dims, points) {
        Some(windows) => windows.par_iter().for_each(|win| {
            win.for_each(nx, nx * ny, |j, w| {
                if w != 0.0 {
                    mark(j)
                }
            })
        }),
        None => points.par_iter().for_each(|&u| {
            stencil::visit::<VALUE>(basis, dims, u, |j, jet| {
                if jet.value != 0.0 {
                    mark(j)
                }
            });
        }),
    }
    let plane = nx * ny;
    touched
        .par_chunks(plane)
        .enumerate()
        .flat_map_iter(|(k, layer)| {
            layer
                .iter()
                .enumerate()
                .filter(|(_, t)| t.load(Ordering::Relaxed))
                .map(move |(i, _)| k * plane + i)
        })
        .collect()
}

/// `W^½ A` on the active columns stacked over `anchor · I` (one row per unknown holding it to its
/// start), each column scaled by `scale` (the Jacobi preconditioner).
pub(crate) struct BandOperator<'a> {
    pub basis: Basis,
    pub dims: [usize; 3],
    pub points: &'a [Vec3],
    pub sqrt_weights: &'a [f64],
    pub active: &'a [usize],
    pub anchor: f64,
    pub scale: Vec<f64>,
    /// Grid-sized, zero outside the active columns.
    scratch: Vec<f64>,
    /// Each row's separable window, for bases that have one on grids of at least 4 nodes per
    /// axis; other cases go through the generic stencil.
    windows: Option<Vec<Window>>,
}

/// A separable basis at one point: 4 nodes per axis from flat index `first`, with their weights
/// (mirrored nodes folded in, unused ones zero), so products need no per-iteration kernel work.
struct Window {
    first: usize,
    w: [[f32; 4]; 3],
}

/// The windows of every point, or `None` when the basis or the grid has none.
fn windows(basis: Basis, dims: [usize; 3], points: &[Vec3]) -> Option<Vec<Window>> {
    let profile = match basis {
        Basis::Trilinear => Profile::Linear,
        Basis::Bspline2 => Profile::Quadratic,
        Basis::Bspline3 => Profile::Cubic,
        Basis::Pg { .. } => return None,
    };
    if dims.iter().any(|&n| n < 4) {
        return None;
    }
    let axis = |u: f32, n: usize| -> (usize, [f32; 4]) {
        let win = axis_window(profile, u, n);
        let mut nodes = [0usize; 4];
        for (a, m) in nodes.iter_mut().enumerate().take(win.len) {
            *m = mirror(win.first + a as i64, n);
        }
        let nodes = &nodes[..win.len];
        let lo = nodes.iter().copied().min().unwrap_or(0).min(n - 4);
        let mut w = [0.0f32; 4];
        for (a, &m) in nodes.iter().enumerate() {
            w[m - lo] += win.w[a][0];
        }
        (lo, w)
    };
    let [nx, ny, _] = dims;
    Some(
        points
            .par_iter()
            .map(|u| {
                let (i, wx) = axis(u.x, dims[0]);
                let (j, wy) = axis(u.y, dims[1]);
                let (k, wz) = axis(u.z, dims[2]);
                Window {
                    first: i + nx * (j + ny * k),
                    w: [wx, wy, wz],
                }
            })
            .collect(),
    )
}

impl Window {
    /// `Σ w · x` over the window.
    #[inline]
    fn dot<T: Copy + Into<f64>>(&self, x: &[T], nx: usize, plane: usize) -> f64 {
        let [wx, wy, wz] = self.w;
        let mut s = 0.0f64;
        for (c, &z) in wz.iter().enumerate() {
            for (b, &y) in wy.iter().enumerate() {
                let at = self.first + c * plane + b * nx;
                let row = &x[at..at + 4];
                let line = wx[0] as f64 * row[0].into()
                    + wx[1] as f64 * row[1].into()
                    + wx[2] as f64 * row[2].into()
                    + wx[3] as f64 * row[3].into();
                s += (z * y) as f64 * line;
            }
        }
        s
    }

    /// Calls `f(flat index, weight)` for the 64 nodes of the window.
    #[inline]
    fn for_each(&self, nx: usize, plane: usize, mut f: impl FnMut(usize, f32)) {
        let [wx, wy, wz] = self.w;
        for (c, &z) in wz.iter().enumerate() {
            for (b, &y) in wy.iter().enumerate() {
                let at = self.first + c * plane + b * nx;
                for (a, &x) in wx.iter().enumerate() {
                    f(at + a, x * y * z);
                }
            }
        }
    }

    /// The window of the squared weights.
    fn squared(&self) -> Window {
        Window {
            first: self.first,
            w: self.w.map(|axis| axis.map(|w| w * w)),
        }
    }

    /// `x += v · w` over the window, `x` starting at flat index `offset`.
    #[inline]
    fn add(&self, x: &mut [f64], offset: usize, v: f64, nx: usize, plane: usize) {
        let [wx, wy, wz] = self.w;
        for (c, &z) in wz.iter().enumerate() {
            for (b, &y) in wy.iter().enumerate() {
                let at = self.first - offset + c * plane + b * nx;
                let zy = v * (z * y) as f64;
                for (o, &w) in x[at..at + 4].iter_mut().zip(&wx) {
                    *o += zy * w as f64;
                }
            }
        }
    }
}

impl<'a> BandOperator<'a> {
    /// The operator with unit column scales.
    pub fn new(
        basis: Basis,
        dims: [usize; 3],
        points: &'a [Vec3],
        sqrt_weights: &'a [f64],
        active: &'a [usize],
        anchor: f64,
    ) -> Self {
        BandOperator {
            basis,
            dims,
            points,
            sqrt_weights,
            active,
            anchor,
            scale: vec![1.0; active.len()],
            scratch: vec![0.0; dims.iter().product()],
            windows: windows(basis, dims, points),
        }
    }

    /// Sets each column's scale to one over its norm (zero for empty columns).
    pub fn precondition(&mut self) {
        let squared = self
            .windows
            .as_ref()
            .map(|w| w.par_iter().map(Window::squared).collect::<Vec<_>>());
        // Squared windows turn the squared column norms into a linear scatter.
        let sq = match squared {
            Some(squared) => {
                let linear = self.windows.replace(squared);
                let sq = self.scatter(true, |i, v| self.sqrt_weights[i].powi(2) * v);
                self.windows = linear;
                sq
            }
            None => self.scatter(false, |i, v| (self.sqrt_weights[i] * v).powi(2)),
        };
        let a2 = self.anchor * self.anchor;
        self.scale = sq
            .iter()
            .map(|&s| {
                if s + a2 > 1e-24 {
                    1.0 / (s + a2).sqrt()
                } else {
                    0.0
                }
            })
            .collect();
    }

    /// Sample rows then anchor rows.
    pub fn rows(&self) -> usize {
        self.points.len() + self.active.len()
    }

    /// `[W^½ A; anchor I] D y`.
    pub fn forward(&mut self, y: &[f64]) -> Vec<f64> {
        for ((&j, &y), &s) in self.active.iter().zip(y).zip(&self.scale) {
            self.scratch[j] = y * s;
        }
        let mut out = self.full_product(&self.scratch);
        out.extend(y.iter().zip(&self.scale).map(|(y, s)| self.anchor * s * y));
        out
    }

    /// `W^½ A c` for a grid-sized coefficient vector `c`, every column included.
    pub fn full_product<T: Copy + Into<f64> + Sync>(&self, c: &[T]) -> Vec<f64> {
        let [nx, ny, _] = self.dims;
        if let Some(windows) = &self.windows {
            return windows
                .par_iter()
                .zip(self.sqrt_weights)
                .map(|(win, &w)| win.dot(c, nx, nx * ny) * w)
                .collect();
        }
        self.points
            .par_iter()
            .zip(self.sqrt_weights)
            .map(|(&u, &w)| {
                let mut s = 0.0f64;
                stencil::visit::<VALUE>(self.basis, self.dims, u, |j, jet| {
                    s += c[j].into() * jet.value as f64;
                });
                s * w
            })
            .collect()
    }

    /// `D [Aᵀ W^½, anchor I] r`.
    pub fn adjoint(&self, r: &[f64]) -> Vec<f64> {
        let (samples, anchors) = r.split_at(self.points.len());
        let mut g = self.scatter(true, |i, v| samples[i] * self.sqrt_weights[i] * v);
        for ((g, s), a) in g.iter_mut().zip(&self.scale).zip(anchors) {
            *g = (*g + self.anchor * a) * s;
        }
        g
    }

    /// `Σ_i term(i, B_j(p_i))` for every active column j, accumulated per chunk of rows over the
    /// z-slab the chunk reaches and added in chunk order.
    /// `linear` says that `term(i, v)` is `term(i, 1) · v`, which lets the windows be used.
    fn scatter(&self, linear: bool, term: impl Fn(usize, f64) -> f64 + Sync) -> Vec<f64> {
        let [nx, ny, nz] = self.dims;
        let plane = nx * ny;
        // Windows span 4 nodes from at most one below the point.
        let reach = (self.basis.support() + 1.0).max(3.0);
        let mut out = vec![0.0f64; self.active.len()];
        let chunks: Vec<(usize, &[Vec3])> = self
            .points
            .chunks(CHUNK)
            .enumerate()
            .map(|(n, c)| (n * CHUNK, c))
            .collect();
        // Bounded batches keep at most a few slabs alive at once.
        let group = rayon::current_num_threads().max(1);
        for batch in chunks.chunks(group) {
            let partial: Vec<(usize, Vec<f64>)> = batch
                .par_iter()
                .map(|&(start, pts)| {
                    let (zlo, zhi) = pts
                        .iter()
                        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), u| {
                            (a.min(u.z), b.max(u.z))
                        });
                    let lo = plane * ((zlo - reach).floor().max(0.0) as usize);
                    let hi = plane * (((zhi + reach).ceil() as usize).min(nz - 1) + 1);
                    let mut acc = vec![0.0f64; hi - lo];
                    match &self.windows {
                        // Linear terms: one value per row, spread by the window's weights.
                        Some(windows) if linear => {
                            for (n, win) in windows[start..start + pts.len()].iter().enumerate() {
                                win.add(&mut acc, lo, term(start + n, 1.0), nx, plane);
                            }
                        }
                        _ => {
                            for (n, &u) in pts.iter().enumerate() {
                                let i = start + n;
                                stencil::visit::<VALUE>(self.basis, self.dims, u, |j, jet| {
                                    acc[j - lo] += term(i, jet.value as f64);
                                });
                            }
                        }
                    }
                    (lo, acc)
                })
                .collect();
            for (lo, acc) in partial {
                let first = self.active.partition_point(|&j| j < lo);
                let last = self.active.partition_point(|&j| j < lo + acc.len());
                for (o, &j) in out[first..last].iter_mut().zip(&self.active[first..last]) {
                    *o += acc[j - lo];
                }
            }
        }
        out
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
            let active = active_columns(basis, dims, &points);
            // The points fill only part of the grid.
            assert!(!active.is_empty() && active.len() < 14 * 12 * 16 / 2);
            let mut op = BandOperator::new(basis, dims, &points, &w, &active, 0.3);
            op.precondition();
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
            let active = active_columns(basis, dims, &points);
            let mut fast = BandOperator::new(basis, dims, &points, &w, &active, 0.3);
            let mut slow = BandOperator::new(basis, dims, &points, &w, &active, 0.3);
            slow.windows = None;
            assert!(fast.windows.is_some());
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
}
