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

impl<'a> Samples<'a> {
    /// Checks the grid description; `None` when the grid has no cells.
    ///
    /// # Panics
    ///
    /// If `values.len()` does not match `dims`, or `spacing` is not positive and finite.
    pub fn checked(
        values: &'a [f32],
        dims: [usize; 3],
        origin: Vec3,
        spacing: f32,
        iso: f32,
    ) -> Option<Samples<'a>> {
        let nodes = dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
        assert_eq!(
            nodes,
            Some(values.len()),
            "values do not match grid dims {dims:?}"
        );
        assert!(
            spacing.is_finite() && spacing > 0.0,
            "grid spacing must be positive, got {spacing}"
        );
        if dims.iter().any(|&d| d < 2) {
            return None;
        }
        Some(Samples {
            values,
            dims,
            origin,
            spacing,
            iso,
        })
    }

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
