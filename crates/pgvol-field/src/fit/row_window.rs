//! A separable basis at one sample point as 4 nodes per axis with their weights, mirrored nodes
//! folded in: computed once per row, so products need no kernel work per iteration.

use std::ops::Range;

use glam::Vec3;
use rayon::prelude::*;

use crate::basis::Basis;
use crate::kernel::{axis_window, Profile};
use crate::stencil::mirror;

/// 4 nodes per axis from flat index `first`, with their weights (unused ones zero).
pub(crate) struct Window {
    pub first: usize,
    pub w: [[f32; 4]; 3],
}

/// The windows of every point, or `None` when the basis or the grid has none.
pub(crate) fn windows(basis: Basis, dims: [usize; 3], points: &[Vec3]) -> Option<Vec<Window>> {
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
    /// The first z-layer of the window.
    #[inline(always)]
    pub fn layer(&self, plane: usize) -> usize {
        self.first / plane
    }

    /// The layers (0..4) of the window that fall in the z-layers `layers`.
    #[inline(always)]
    pub fn layers_within(&self, layers: &Range<usize>, plane: usize) -> Range<usize> {
        let k = self.layer(plane);
        let first = layers.start.saturating_sub(k).min(4);
        first..layers.end.saturating_sub(k).clamp(first, 4)
    }

    /// `Σ w · x` over the window. The x weight is applied last, so the 16 lines add up lane by
    /// lane (vector registers) rather than each being summed across.
    #[inline(always)]
    pub fn dot<T: Copy + Into<f64>>(&self, x: &[T], nx: usize, plane: usize) -> f64 {
        let [wx, wy, wz] = self.w;
        let mut acc = [0.0f64; 4];
        for (c, &z) in wz.iter().enumerate() {
            for (b, &y) in wy.iter().enumerate() {
                let at = self.first + c * plane + b * nx;
                let line: &[T; 4] = x[at..at + 4].try_into().expect("4 nodes");
                let zy = z as f64 * y as f64;
                for (s, &v) in acc.iter_mut().zip(line) {
                    *s += zy * v.into();
                }
            }
        }
        (wx[0] as f64 * acc[0] + wx[1] as f64 * acc[1])
            + (wx[2] as f64 * acc[2] + wx[3] as f64 * acc[3])
    }

    /// Calls `f(flat index, weight)` for the nodes of the window's layers `layers` (0..4). The
    /// weight is formed in f64, as products form it, so it is zero only where a factor is.
    #[inline(always)]
    pub fn for_each(
        &self,
        layers: Range<usize>,
        nx: usize,
        plane: usize,
        mut f: impl FnMut(usize, f64),
    ) {
        let [wx, wy, wz] = self.w;
        for c in layers {
            for (b, &y) in wy.iter().enumerate() {
                let at = self.first + c * plane + b * nx;
                let zy = wz[c] as f64 * y as f64;
                for (a, &x) in wx.iter().enumerate() {
                    f(at + a, zy * x as f64);
                }
            }
        }
    }

    /// `x += v · w` (`v · w²` when `SQUARED`) over the window's layers `layers` (0..4), `x`
    /// starting at flat index `offset`.
    #[inline(always)]
    pub fn add<const SQUARED: bool>(
        &self,
        x: &mut [f64],
        offset: usize,
        v: f64,
        layers: Range<usize>,
        nx: usize,
        plane: usize,
    ) {
        let [wx, wy, wz] = self.w;
        let wx = wx.map(|w| {
            if SQUARED {
                w as f64 * w as f64
            } else {
                w as f64
            }
        });
        for c in layers {
            for (b, &y) in wy.iter().enumerate() {
                let at = self.first + c * plane + b * nx - offset;
                let zy = wz[c] as f64 * y as f64;
                let zy = v * if SQUARED { zy * zy } else { zy };
                for (o, &w) in x[at..at + 4].iter_mut().zip(&wx) {
                    *o += zy * w;
                }
            }
        }
    }
}
