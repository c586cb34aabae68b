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
}
