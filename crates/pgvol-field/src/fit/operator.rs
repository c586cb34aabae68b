//! The fitting matrix `A_ij = w_i B_j(p_i)` applied without storing it: each product recomputes
//! the few kernel values each sample point touches.

use glam::Vec3;
use rayon::prelude::*;

use crate::basis::Basis;
use crate::stencil::{self, VALUE};

/// Points per chunk of the transposed product; fixed so results do not depend on thread count.
const CHUNK: usize = 16_384;

/// Weighted sample points (in grid coordinates, inside the grid box) for one basis and grid.
pub struct Operator<'a> {
    pub basis: Basis,
    pub dims: [usize; 3],
    pub points: &'a [Vec3],
    /// Square roots of the row weights; `None` for unit weights.
    pub sqrt_weights: Option<&'a [f64]>,
}

impl Operator<'_> {
    pub fn rows(&self) -> usize {
        self.points.len()
    }

    pub fn cols(&self) -> usize {
        self.dims.iter().product()
    }

    #[inline]
    fn weight(&self, i: usize) -> f64 {
        self.sqrt_weights.map_or(1.0, |w| w[i])
    }

    /// `A c`.
    pub fn forward(&self, c: &[f64]) -> Vec<f64> {
        self.points
            .par_iter()
            .enumerate()
            .map(|(i, &u)| {
                let mut s = 0.0f64;
                stencil::visit::<VALUE>(self.basis, self.dims, u, |j, jet| {
                    s += c[j] * jet.value as f64;
                });
                s * self.weight(i)
            })
            .collect()
    }

    /// `Aᵀ r`, accumulated per chunk of points over the z-slab the chunk can reach, then summed
    /// in chunk order.
    pub fn adjoint(&self, r: &[f64]) -> Vec<f64> {
        self.scatter(|i, w| r[i] * w)
    }

    /// `Σ_i A_ij²`, the squared column norms (the Jacobi preconditioner of `AᵀA`).
    pub fn column_norms_sq(&self) -> Vec<f64> {
        self.scatter_sq()
    }

    fn slab(&self, chunk: &[Vec3]) -> (usize, usize) {
        let [nx, ny, nz] = self.dims;
        let s = self.basis.support() + 1.0;
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for u in chunk {
            lo = lo.min(u.z);
            hi = hi.max(u.z);
        }
        let zlo = ((lo - s).floor().max(0.0)) as usize;
        let zhi = ((hi + s).ceil() as usize).min(nz - 1);
        (nx * ny * zlo, nx * ny * (zhi + 1))
    }

    fn scatter(&self, row_value: impl Fn(usize, f64) -> f64 + Sync) -> Vec<f64> {
        self.scatter_with(|i, w, jet_value, acc: &mut f64| *acc += row_value(i, w) * jet_value)
    }

    fn scatter_sq(&self) -> Vec<f64> {
        self.scatter_with(|_, w, jet_value, acc: &mut f64| {
            let a = w * jet_value;
            *acc += a * a
        })
    }

    fn scatter_with(&self, add: impl Fn(usize, f64, f64, &mut f64) + Sync) -> Vec<f64> {
        let mut out = vec![0.0f64; self.cols()];
        let chunks: Vec<(usize, &[Vec3])> = self
            .points
            .chunks(CHUNK)
            .enumerate()
            .map(|(n, c)| (n * CHUNK, c))
            .collect();
        // Bounded groups keep at most a few slabs alive at once.
        let group = 2 * rayon::current_num_threads().max(1);
        for batch in chunks.chunks(group) {
            let partial: Vec<(usize, Vec<f64>)> = batch
                .par_iter()
                .map(|&(start, pts)| {
                    let (lo, hi) = self.slab(pts);
                    let mut acc = vec![0.0f64; hi - lo];
                    for (k, &u) in pts.iter().enumerate() {
                        let i = start + k;
                        let w = self.weight(i);
                        stencil::visit::<VALUE>(self.basis, self.dims, u, |j, jet| {
                            add(i, w, jet.value as f64, &mut acc[j - lo]);
                        });
                    }
                    (lo, acc)
                })
                .collect();
            for (lo, acc) in partial {
                for (o, a) in out[lo..lo + acc.len()].iter_mut().zip(&acc) {
                    *o += a;
                }
            }
        }
        out
    }
}

/// Grid coordinates of every node, x fastest.
pub fn node_points(dims: [usize; 3]) -> Vec<Vec3> {
    let [nx, ny, nz] = dims;
    let mut v = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                v.push(Vec3::new(i as f32, j as f32, k as f32));
            }
        }
    }
    v
}
