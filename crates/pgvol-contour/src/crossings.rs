//! Surface vertices: one per grid edge whose end values straddle iso.
//!
//! Edges are grouped by the z layer of their lower node (x and y edges in the layer, z edges
//! rising from it) and within a layer by row, so a cell finds its vertices in a few short sorted
//! lists without a dense per-edge index.

use glam::Vec3;
use rayon::prelude::*;

use crate::place::onto_edge;
use crate::samples::Samples;

/// Callback placing the crossing on the edge from `a` (value `va`) to `b` (value `vb`).
pub(crate) type Refine<'r> = dyn Fn(Vec3, f32, Vec3, f32) -> Vec3 + Sync + 'r;

/// Crossed edges whose lower node lies in one z layer, in scan order.
pub(crate) struct Layer {
    /// Offset into `keys` of each row `j`, plus a final end marker.
    row_start: Vec<u32>,
    /// `3 * i + axis` of each crossed edge, ascending within a row.
    keys: Vec<u32>,
    pub positions: Vec<Vec3>,
}

impl Layer {
    /// Keys of row `j` and the layer-local index of the row's first vertex.
    #[inline]
    pub fn row(&self, j: usize) -> (&[u32], u32) {
        let (s, e) = (self.row_start[j], self.row_start[j + 1]);
        (&self.keys[s as usize..e as usize], s)
    }

    /// Row and key of the crossing with layer-local index `local`.
    pub fn locate(&self, local: u32) -> (usize, u32) {
        // Empty rows repeat a start offset; the last row starting at or before `local` holds it.
        let j = self.row_start.partition_point(|&s| s <= local) - 1;
        (j, self.keys[local as usize])
    }

    pub fn len(&self) -> usize {
        self.keys.len()
    }
}

/// Finds and places the crossings of the edges owned by layer `z`.
pub(crate) fn layer_crossings(field: &Samples, z: usize, refine: &Refine) -> Layer {
    let [nx, ny, nz] = field.dims;
    let mut layer = Layer {
        row_start: Vec::with_capacity(ny + 1),
        keys: Vec::new(),
        positions: Vec::new(),
    };
    let row_of = |j: usize, k: usize| {
        let s = field.index(0, j, k);
        &field.values[s..s + nx]
    };
    for j in 0..ny {
        layer.row_start.push(to_u32(layer.keys.len()));
        let row = row_of(j, z);
        // A missing neighbour row is replaced by the row itself, which never differs in sign, so
        // the scan below stays free of per-node bounds logic.
        let ahead = if j + 1 < ny { row_of(j + 1, z) } else { row };
        let above = if z + 1 < nz { row_of(j, z + 1) } else { row };
        for i in 0..nx {
            let v = row[i];
            let ins = field.inside(v);
            let next = [row[(i + 1).min(nx - 1)], ahead[i], above[i]];
            let differs = next.map(|w| field.inside(w) != ins);
            if !(differs[0] | differs[1] | differs[2]) {
                continue;
            }
            for axis in (0..3).filter(|&a| differs[a]) {
                let a = [i, j, z];
                let mut b = a;
                b[axis] += 1;
                let (pa, pb) = (field.node(a), field.node(b));
                let p = onto_edge(pa, pb, axis, refine(pa, v, pb, next[axis]));
                layer.keys.push(to_u32(3 * i + axis));
                layer.positions.push(p);
            }
        }
    }
    layer.row_start.push(to_u32(layer.keys.len()));
    layer
}

fn to_u32(n: usize) -> u32 {
    u32::try_from(n).expect("grid too large for 32-bit indices")
}

/// Every crossing of the grid: per-layer lists, each layer's first global index, and the
/// positions in global order (layer by layer, scan order within a layer).
pub(crate) struct Crossings {
    pub layers: Vec<Layer>,
    pub base: Vec<u32>,
    pub positions: Vec<Vec3>,
}

/// Finds and places all crossings, in parallel over layers; the order does not depend on the
/// number of threads.
pub(crate) fn all_crossings(field: &Samples, refine: &Refine, limit: u32) -> Crossings {
    let layers: Vec<Layer> = (0..field.dims[2])
        .into_par_iter()
        .map(|z| layer_crossings(field, z, refine))
        .collect();
    let mut base = Vec::with_capacity(layers.len());
    let mut n = 0usize;
    for layer in &layers {
        base.push(n as u32);
        n += layer.len();
        assert!(n < limit as usize, "too many vertices");
    }
    let mut positions = Vec::with_capacity(n);
    for layer in &layers {
        positions.extend_from_slice(&layer.positions);
    }
    Crossings {
        layers,
        base,
        positions,
    }
}
