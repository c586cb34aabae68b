//! The grid of samples being contoured.

use glam::Vec3;

/// Node values on a regular grid, x fastest: node `(i, j, k)` is `values[i + nx * (j + ny * k)]`
/// at `origin + spacing * (i, j, k)`.
#[derive(Clone, Copy)]
pub(crate) struct Samples<'a> {
    pub values: &'a [f32],
    pub dims: [usize; 3],
    pub origin: Vec3,
    pub spacing: f32,
    pub iso: f32,
}

impl Samples<'_> {
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Node position; every caller goes through here so shared nodes get bit-identical positions.
    #[inline]
    pub fn node(&self, n: [usize; 3]) -> Vec3 {
        self.origin + self.spacing * Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32)
    }

    /// Inside means below iso; NaN compares false and so counts as outside.
    #[inline]
    pub fn inside(&self, v: f32) -> bool {
        v < self.iso
    }
}
