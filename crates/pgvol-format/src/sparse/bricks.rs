//! How the grid is cut into bricks: their count, coordinates and nodes.

/// Geometry of the brick decomposition.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bricks {
    pub(crate) dims: [usize; 3],
    pub(crate) edge: usize,
    pub(crate) count: [usize; 3],
}

impl Bricks {
    pub(crate) fn new(dims: [usize; 3], edge: usize) -> Bricks {
        Bricks {
            dims,
            edge,
            count: dims.map(|n| n.div_ceil(edge)),
        }
    }

    pub(crate) fn total(&self) -> usize {
        self.count.iter().product()
    }

    pub(crate) fn coords(&self, b: usize) -> [usize; 3] {
        [
            b % self.count[0],
            (b / self.count[0]) % self.count[1],
            b / (self.count[0] * self.count[1]),
        ]
    }

    /// First node and node counts of brick `b`.
    pub(crate) fn extent(&self, b: usize) -> ([usize; 3], [usize; 3]) {
        let c = self.coords(b);
        let lo = [0, 1, 2].map(|a| c[a] * self.edge);
        let n = [0, 1, 2].map(|a| (lo[a] + self.edge).min(self.dims[a]) - lo[a]);
        (lo, n)
    }

    /// Node indices of flat grid index `i`.
    #[inline]
    pub(crate) fn unflat(&self, i: usize) -> [usize; 3] {
        let [nx, ny, _] = self.dims;
        [i % nx, (i / nx) % ny, i / (nx * ny)]
    }

    /// Flat grid indices of brick `b`'s nodes, x fastest.
    pub(crate) fn nodes(&self, b: usize) -> impl Iterator<Item = usize> {
        let (lo, n) = self.extent(b);
        let [nx, ny, _] = self.dims;
        (0..n[2]).flat_map(move |k| {
            (0..n[1]).flat_map(move |j| {
                (0..n[0]).map(move |i| lo[0] + i + nx * (lo[1] + j + ny * (lo[2] + k)))
            })
        })
    }
}
