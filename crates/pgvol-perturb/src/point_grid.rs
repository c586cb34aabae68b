//! Points bucketed in a uniform grid of cubic cells, for the points within a ball or a box.

use std::collections::HashMap;

use glam::{IVec3, Vec3};

pub struct PointGrid {
    cell: f32,
    buckets: HashMap<IVec3, Vec<u32>>,
    /// The occupied cells in a fixed order, so a scan visits points in the same order on
    /// every run (sums and ties come out alike).
    keys: Vec<IVec3>,
}

impl PointGrid {
    pub fn new(points: &[Vec3], cell: f32) -> Self {
        let mut buckets: HashMap<IVec3, Vec<u32>> = HashMap::new();
        for (i, &p) in points.iter().enumerate() {
            buckets
                .entry(Self::key(p, cell))
                .or_default()
                .push(i as u32);
        }
        let mut keys: Vec<IVec3> = buckets.keys().copied().collect();
        keys.sort_unstable_by_key(|k| (k.z, k.y, k.x));
        Self {
            cell,
            buckets,
            keys,
        }
    }

    fn key(p: Vec3, cell: f32) -> IVec3 {
        (p / cell).floor().as_ivec3()
    }

    /// Calls `visit` with every point index in the cells overlapping `[lo, hi]` (a superset of
    /// the points in the box; callers test the exact condition).
    pub fn for_each_in_box(&self, lo: Vec3, hi: Vec3, mut visit: impl FnMut(u32)) {
        let (a, b) = (Self::key(lo, self.cell), Self::key(hi, self.cell));
        let cells = (b - a + IVec3::ONE).max(IVec3::ZERO).as_i64vec3();
        if cells.x * cells.y * cells.z > self.buckets.len() as i64 {
            // A box larger than the occupied cells: scanning the buckets is cheaper.
            for k in &self.keys {
                if k.cmpge(a).all() && k.cmple(b).all() {
                    self.buckets[k].iter().for_each(|&i| visit(i));
                }
            }
            return;
        }
        for z in a.z..=b.z {
            for y in a.y..=b.y {
                for x in a.x..=b.x {
                    if let Some(items) = self.buckets.get(&IVec3::new(x, y, z)) {
                        items.iter().for_each(|&i| visit(i));
                    }
                }
            }
        }
    }
}
