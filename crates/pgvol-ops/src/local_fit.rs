//! Re-fitting the coefficients around a box of nodes to new node values, leaving every
//! coefficient whose support misses the box bit-identical.
//!
//! The unknowns are the corrections of the coefficients within 2 nodes of the box (every
//! coefficient whose support, 2 spacings wide for the cubic B-spline, meets it); the rows are
//! the field's values at every node those coefficients touch (1 node farther), asked to equal
//! the new values inside the box and the old ones outside it. The least-squares problem is
//! solved by CGLS; its rows outside the box keep the field continuous with the untouched one.

use pgvol_field::fit::solve::cgls;
use pgvol_field::{mirror, Basis, CoefficientVolume};

use crate::error::OpsError;

/// A box of nodes, `lo..=hi` per axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeBox {
    pub lo: [usize; 3],
    pub hi: [usize; 3],
}

impl NodeBox {
    /// Nodes per axis.
    pub fn dims(&self) -> [usize; 3] {
        [0, 1, 2].map(|a| self.hi[a] - self.lo[a] + 1)
    }

    pub fn count(&self) -> usize {
        self.dims().iter().product()
    }

    /// The box grown by `by` nodes, clipped to a grid of `dims`.
    pub fn grown(&self, by: usize, dims: [usize; 3]) -> NodeBox {
        NodeBox {
            lo: self.lo.map(|l| l.saturating_sub(by)),
            hi: [0, 1, 2].map(|a| (self.hi[a] + by).min(dims[a] - 1)),
        }
    }

    /// Flat index (x fastest) of node `n` of the box.
    pub fn index(&self, n: [usize; 3]) -> usize {
        let d = self.dims();
        (n[0] - self.lo[0]) + d[0] * ((n[1] - self.lo[1]) + d[1] * (n[2] - self.lo[2]))
    }

    /// The node at flat index `i`.
    pub fn node(&self, i: usize) -> [usize; 3] {
        let d = self.dims();
        [
            self.lo[0] + i % d[0],
            self.lo[1] + (i / d[0]) % d[1],
            self.lo[2] + i / (d[0] * d[1]),
        ]
    }

    pub fn contains(&self, n: [usize; 3]) -> bool {
        (0..3).all(|a| n[a] >= self.lo[a] && n[a] <= self.hi[a])
    }
}

/// The weights of the coefficients at offsets −1, 0, 1 in the value at a node.
fn node_weights(basis: Basis) -> Result<[f32; 3], OpsError> {
    match basis {
        Basis::Trilinear => Ok([0.0, 1.0, 0.0]),
        Basis::Bspline2 => Ok([0.125, 0.75, 0.125]),
        Basis::Bspline3 => Ok([1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0]),
        Basis::Pg { .. } => Err(OpsError::BadParameter(
            "local editing needs a B-spline or trilinear basis; the pseudo-Gaussian's \
             coefficients are coupled across the whole grid (encode with --basis bspline3)"
                .into(),
        )),
    }
}

/// Calls `f(column, weight)` for each coefficient of `cols` in the value at node `n`
/// (mirrored indices past the grid's border, as the basis lays them, may repeat a column).
fn for_each_column(
    w: &[f32; 3],
    dims: [usize; 3],
    cols: &NodeBox,
    n: [usize; 3],
    mut f: impl FnMut(usize, f32),
) {
    for (dz, wz) in w.iter().enumerate() {
        for (dy, wy) in w.iter().enumerate() {
            for (dx, wx) in w.iter().enumerate() {
                let weight = wx * wy * wz;
                if weight == 0.0 {
                    continue;
                }
                let c = [
                    mirror(n[0] as i64 + dx as i64 - 1, dims[0]),
                    mirror(n[1] as i64 + dy as i64 - 1, dims[1]),
                    mirror(n[2] as i64 + dz as i64 - 1, dims[2]),
                ];
                if cols.contains(c) {
                    f(cols.index(c), weight);
                }
            }
        }
    }
}

/// The field's value at node `n` from the coefficients.
pub fn node_value(volume: &CoefficientVolume, n: [usize; 3]) -> Result<f32, OpsError> {
    let w = node_weights(volume.basis)?;
    let dims = volume.grid.dims;
    let mut v = 0.0f64;
    for dz in 0..3 {
        for dy in 0..3 {
            for dx in 0..3 {
                let weight = w[dx] * w[dy] * w[dz];
                if weight != 0.0 {
                    let c = [
                        mirror(n[0] as i64 + dx as i64 - 1, dims[0]),
                        mirror(n[1] as i64 + dy as i64 - 1, dims[1]),
                        mirror(n[2] as i64 + dz as i64 - 1, dims[2]),
                    ];
                    v += weight as f64 * volume.coeffs.get(c) as f64;
                }
            }
        }
    }
    Ok(v as f32)
}

/// Outcome of one local re-fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalFit {
    /// Coefficients that may have changed.
    pub coefficients: usize,
    pub iterations: usize,
    /// Largest difference between the field and the new values at the box's nodes after the
    /// fit.
    pub max_error: f32,
}

/// Re-fits the coefficients around `region` so that the field takes `values` (one per node of
/// `region`, x fastest) there and keeps its old values at the nodes around it.
pub fn refit_box(
    volume: &mut CoefficientVolume,
    region: &NodeBox,
    values: &[f32],
) -> Result<LocalFit, OpsError> {
    let dims = volume.grid.dims;
    let cols = region.grown(2, dims);
    let rows = region.grown(3, dims);
    let w = node_weights(volume.basis)?;
    let mut target = Vec::with_capacity(rows.count());
    for r in 0..rows.count() {
        let n = rows.node(r);
        let now = node_value(volume, n)?;
        let want = if region.contains(n) {
            values[region.index(n)]
        } else {
            now
        };
        target.push((want - now) as f64);
    }
    let forward = |x: &[f64]| -> Vec<f64> {
        (0..rows.count())
            .map(|r| {
                let mut sum = 0.0;
                for_each_column(&w, dims, &cols, rows.node(r), |c, wt| {
                    sum += wt as f64 * x[c]
                });
                sum
            })
            .collect()
    };
    let adjoint = |res: &[f64]| -> Vec<f64> {
        let mut y = vec![0.0; cols.count()];
        for (r, &ri) in res.iter().enumerate() {
            for_each_column(&w, dims, &cols, rows.node(r), |c, wt| {
                y[c] += wt as f64 * ri
            });
        }
        y
    };
    let (delta, outcome) = cgls(forward, adjoint, &target, cols.count(), 0.0, 1e-5, 200);
    for (i, d) in delta.iter().enumerate() {
        let n = cols.node(i);
        let b = pgvol_core::sparse::brick_of(n);
        let brick = volume.coeffs.brick_or_background(b);
        let at = pgvol_core::sparse::brick_offset(n);
        brick[at] = (brick[at] as f64 + d) as f32;
    }
    let mut max_error: f32 = 0.0;
    for (i, &want) in values.iter().enumerate() {
        max_error = max_error.max((node_value(volume, region.node(i))? - want).abs());
    }
    Ok(LocalFit {
        coefficients: cols.count(),
        iterations: outcome.iterations,
        max_error,
    })
}
