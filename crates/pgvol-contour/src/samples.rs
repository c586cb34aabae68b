//! The grid of samples being contoured, and the sources its node values come from.
//!
//! Contouring reads values only through the boxes of the blocks that may hold a crossing (see
//! `blocks`), so a source need not hold the grid: [`DenseNodes`] and [`PaddedNodes`] wrap
//! caller arrays, and the sparse sampling of a coefficient volume evaluates only near the
//! level set.

use glam::Vec3;

use crate::blocks::{box_index, scan_active, BoxValues, Rows};
use pgvol_core::progress::{Counter, Span};

/// Where node values come from.
pub(crate) trait Nodes: Sync {
    /// Nodes per axis.
    fn dims(&self) -> [usize; 3];

    /// Ids of the blocks (x fastest, ascending) whose box may hold nodes on both sides of
    /// `iso`: every active block, and maybe others, which reading their box rules out.
    fn candidates(&self, iso: f32) -> Vec<u32>;

    /// The `n` nodes from node `lo` (at most [`BOX`](crate::blocks::BOX) per axis, all in the
    /// grid) into `out`.
    fn read_box(&self, lo: [usize; 3], n: [usize; 3], out: &mut BoxValues);
}

/// Node values held by the caller, x fastest: `values[i + nx * (j + ny * k)]`.
pub(crate) struct DenseNodes<'a> {
    values: &'a [f32],
    dims: [usize; 3],
}

impl<'a> DenseNodes<'a> {
    /// # Panics
    ///
    /// If `values.len()` does not match `dims`.
    pub fn new(values: &'a [f32], dims: [usize; 3]) -> Self {
        let nodes = dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
        assert_eq!(
            nodes,
            Some(values.len()),
            "values do not match grid dims {dims:?}"
        );
        Self { values, dims }
    }

    #[inline]
    fn row(&self, j: usize, k: usize) -> &'a [f32] {
        let nx = self.dims[0];
        let start = nx * (j + self.dims[1] * k);
        &self.values[start..start + nx]
    }
}

impl Rows for DenseNodes<'_> {
    fn row<'s>(&'s self, j: usize, k: usize, _: &'s mut Vec<f32>) -> &'s [f32] {
        DenseNodes::row(self, j, k)
    }
}

impl Nodes for DenseNodes<'_> {
    fn dims(&self) -> [usize; 3] {
        self.dims
    }

    fn candidates(&self, iso: f32) -> Vec<u32> {
        scan_active(self.dims, iso, self)
    }

    fn read_box(&self, lo: [usize; 3], n: [usize; 3], out: &mut BoxValues) {
        for dk in 0..n[2] {
            for dj in 0..n[1] {
                let row = &self.row(lo[1] + dj, lo[2] + dk)[lo[0]..lo[0] + n[0]];
                let at = box_index([0, dj, dk]);
                out[at..at + n[0]].copy_from_slice(row);
            }
        }
    }
}

/// Caller values (x fastest) surrounded by one layer of `pad`, without copying them: node
/// `(i, j, k)` of this grid is node `(i - 1, j - 1, k - 1)` of the values.
pub(crate) struct PaddedNodes<'a> {
    inner: DenseNodes<'a>,
    pad: f32,
}

impl<'a> PaddedNodes<'a> {
    /// # Panics
    ///
    /// If `values.len()` does not match `dims`.
    pub fn new(values: &'a [f32], dims: [usize; 3], pad: f32) -> Self {
        Self {
            inner: DenseNodes::new(values, dims),
            pad,
        }
    }
}

impl Rows for PaddedNodes<'_> {
    fn row<'s>(&'s self, j: usize, k: usize, buf: &'s mut Vec<f32>) -> &'s [f32] {
        let [nx, ny, nz] = self.inner.dims;
        buf.clear();
        if j == 0 || k == 0 || j > ny || k > nz {
            buf.resize(nx + 2, self.pad);
        } else {
            buf.push(self.pad);
            buf.extend_from_slice(self.inner.row(j - 1, k - 1));
            buf.push(self.pad);
        }
        buf
    }
}

impl Nodes for PaddedNodes<'_> {
    fn dims(&self) -> [usize; 3] {
        self.inner.dims.map(|n| n + 2)
    }

    fn candidates(&self, iso: f32) -> Vec<u32> {
        scan_active(self.dims(), iso, self)
    }

    fn read_box(&self, lo: [usize; 3], n: [usize; 3], out: &mut BoxValues) {
        let mut buf = Vec::new();
        for dk in 0..n[2] {
            for dj in 0..n[1] {
                let row = &self.row(lo[1] + dj, lo[2] + dk, &mut buf)[lo[0]..lo[0] + n[0]];
                let at = box_index([0, dj, dk]);
                out[at..at + n[0]].copy_from_slice(row);
            }
        }
    }
}

/// The part of a contouring's progress spent finding edge crossings; placing vertices and
/// triangles takes the rest.
pub(crate) const CROSSINGS_PART: f64 = 0.85;

/// A grid of node values being contoured: node `(i, j, k)` at
/// `origin + spacing * ((i, j, k) + offset)`.
#[derive(Clone, Copy)]
pub(crate) struct Samples<'a> {
    pub nodes: &'a dyn Nodes,
    pub dims: [usize; 3],
    pub origin: Vec3,
    /// Where this grid's first node is in a larger grid: a run of layers (or a box) contoured
    /// on its own places its nodes as the whole grid does, so nodes shared by two runs get one
    /// position, and a box of the grid gives the positions of the whole.
    pub offset: [usize; 3],
    pub spacing: f32,
    pub iso: f32,
    /// Where the contouring's fraction done goes, if anywhere.
    pub progress: Option<Span<'a>>,
}

impl<'a> Samples<'a> {
    /// Checks the grid description; `None` when the grid has no cells.
    ///
    /// # Panics
    ///
    /// If `spacing` is not positive and finite.
    pub fn checked(
        nodes: &'a dyn Nodes,
        origin: Vec3,
        spacing: f32,
        iso: f32,
    ) -> Option<Samples<'a>> {
        assert!(
            spacing.is_finite() && spacing > 0.0,
            "grid spacing must be positive, got {spacing}"
        );
        let dims = nodes.dims();
        if dims.iter().any(|&d| d < 2) {
            return None;
        }
        Some(Samples {
            nodes,
            dims,
            origin,
            offset: [0; 3],
            spacing,
            iso,
            progress: None,
        })
    }

    /// These samples as the nodes from `offset` on of a grid with the same origin.
    pub fn shifted(self, offset: [usize; 3]) -> Self {
        Self { offset, ..self }
    }

    /// These samples, reporting the contouring's progress through `span`.
    pub fn reporting(self, span: Option<Span<'a>>) -> Self {
        Self {
            progress: span,
            ..self
        }
    }

    /// Counts `total` items of the part `[a, b]` of the contouring's progress.
    pub fn counter(&self, a: f64, b: f64, total: usize) -> Option<Counter<'a>> {
        self.progress.map(|s| s.part(a, b).counter(total))
    }

    /// Flat index of a node (x fastest), a key only: no array is indexed by it.
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Node position; every caller goes through here so shared nodes get bit-identical positions.
    #[inline]
    pub fn node(&self, n: [usize; 3]) -> Vec3 {
        let [i, j, k] = [0, 1, 2].map(|a| (n[a] + self.offset[a]) as f32);
        self.origin + self.spacing * Vec3::new(i, j, k)
    }

    /// Inside means below iso; NaN compares false and so counts as outside.
    #[inline]
    pub fn inside(&self, v: f32) -> bool {
        v < self.iso
    }
}
