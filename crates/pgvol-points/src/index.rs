//! A uniform hash grid over points: radius and k-nearest queries in time proportional to the
//! points near the query. Points on a surface fill few cells of a box, so cells are kept in a
//! hash map rather than a dense array (1M surface points would otherwise need ~10⁷ cells).

use std::borrow::Cow;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::Vec3;

/// Points bucketed by cell of side `cell`.
pub struct PointIndex<'a> {
    points: Cow<'a, [Vec3]>,
    cell: f32,
    /// Point indices sorted by cell.
    order: Vec<u32>,
    /// Per occupied cell, its range in `order`.
    cells: HashMap<[i32; 3], (u32, u32), BuildHasherDefault<CellHasher>>,
}

/// A multiplicative hash for cell coordinates: the default SipHash, built to resist crafted
/// keys, made lookups the bulk of a query's time.
#[derive(Default)]
pub struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_i32(&mut self, v: i32) {
        self.write_u64(v as u32 as u64);
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(21) ^ v).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

impl<'a> PointIndex<'a> {
    /// Buckets `points` (borrowed or owned) into cells of side `cell` (> 0).
    pub fn new(points: impl Into<Cow<'a, [Vec3]>>, cell: f32) -> Self {
        let points = points.into();
        let cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            1.0
        };
        let key = |p: Vec3| (p / cell).floor().as_ivec3().to_array();
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        order.sort_unstable_by_key(|&i| key(points[i as usize]));
        let mut cells = HashMap::default();
        let mut start = 0;
        while start < order.len() {
            let k = key(points[order[start] as usize]);
            let mut end = start + 1;
            while end < order.len() && key(points[order[end] as usize]) == k {
                end += 1;
            }
            cells.insert(k, (start as u32, end as u32));
            start = end;
        }
        Self {
            points,
            cell,
            order,
            cells,
        }
    }

    /// The indexed points.
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// Calls `f(index, squared distance)` for every point within `r` of `p`, cell by cell in
    /// raster order (x fastest).
    pub fn for_each_within(&self, p: Vec3, r: f32, mut f: impl FnMut(usize, f32)) {
        let lo = ((p - r) / self.cell).floor().as_ivec3();
        let hi = ((p + r) / self.cell).floor().as_ivec3();
        let r2 = r * r;
        let mut scan = |(a, b): (u32, u32)| {
            for &i in &self.order[a as usize..b as usize] {
                let d2 = self.points[i as usize].distance_squared(p);
                if d2 <= r2 {
                    f(i as usize, d2);
                }
            }
        };
        let span = |a: i32, b: i32| (i64::from(b) - i64::from(a) + 1).max(0) as u64;
        let in_reach = span(lo.x, hi.x)
            .saturating_mul(span(lo.y, hi.y))
            .saturating_mul(span(lo.z, hi.z));
        if in_reach > self.cells.len() as u64 {
            // A reach of many cells (a query far from the other points, an outlier's
            // neighbours): the occupied cells are fewer, so they are the ones visited, in the
            // same order.
            let mut near: Vec<([i32; 3], (u32, u32))> = self
                .cells
                .iter()
                .filter(|(c, _)| (0..3).all(|a| c[a] >= lo[a] && c[a] <= hi[a]))
                .map(|(&c, &range)| (c, range))
                .collect();
            near.sort_unstable_by_key(|&([x, y, z], _)| (z, y, x));
            near.into_iter().for_each(|(_, range)| scan(range));
            return;
        }
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    if let Some(&range) = self.cells.get(&[x, y, z]) {
                        scan(range);
                    }
                }
            }
        }
    }

    /// The `k` nearest points to `p` within `max_r` as (squared distance, index), nearest
    /// first; fewer when fewer lie within `max_r`. The search radius doubles from one cell, so
    /// a query costs about the cells within the k-th distance.
    pub fn nearest(&self, p: Vec3, k: usize, max_r: f32, out: &mut Vec<(f32, u32)>) {
        let mut r = self.cell;
        loop {
            out.clear();
            let reach = r.min(max_r);
            self.for_each_within(p, reach, |i, d2| out.push((d2, i as u32)));
            if out.len() >= k || reach >= max_r {
                break;
            }
            r *= 2.0;
        }
        if out.len() > k {
            out.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
            out.truncate(k);
        }
        out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    }
}

/// Mean distance from a point to its nearest neighbour, over up to 2000 evenly spread points;
/// the scale every radius of the reconstruction is given in.
pub fn mean_spacing(points: &[Vec3]) -> f32 {
    mean_neighbour_distance(points, 1)
}

/// Neighbours counted by [`sampling_radius`]: on a surface, 6 surround a point.
pub const RADIUS_NEIGHBOURS: usize = 6;

/// Mean distance from a point to its 6th nearest neighbour: the radius of the disc a point's
/// neighbourhood covers, which grows with the holes of unevenly spread points (3 000 random
/// points on a unit sphere: 2.7 × the mean spacing; evenly spread ones: 1.4 ×), where the mean
/// spacing alone does not see them.
pub fn sampling_radius(points: &[Vec3]) -> f32 {
    mean_neighbour_distance(points, RADIUS_NEIGHBOURS)
}

/// Mean distance from a point to its `k`-th nearest other point, over up to 2000 evenly spread
/// points (0 for fewer than `k + 1` points).
fn mean_neighbour_distance(points: &[Vec3], k: usize) -> f32 {
    if points.len() <= k {
        return 0.0;
    }
    let (lo, hi) = bounds(points);
    let diag = (hi - lo).length().max(f32::MIN_POSITIVE);
    // Surface samples of a shape of diagonal D lie about D/√N apart.
    let index = PointIndex::new(points, diag / (points.len() as f32).sqrt());
    let step = (points.len() / 2000).max(1);
    let mut near = Vec::new();
    let (mut sum, mut count) = (0.0f64, 0usize);
    for i in (0..points.len()).step_by(step) {
        index.nearest(points[i], k + 1, diag, &mut near);
        // The point itself (or a duplicate at distance 0) is not a neighbour.
        if let Some(&(d2, _)) = near
            .iter()
            .filter(|(d2, j)| *j as usize != i && *d2 > 0.0)
            .nth(k - 1)
        {
            sum += f64::from(d2.sqrt());
            count += 1;
        }
    }
    if count == 0 {
        0.0
    } else {
        (sum / count as f64) as f32
    }
}

/// The bounding box of `points`.
pub fn bounds(points: &[Vec3]) -> (Vec3, Vec3) {
    points.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` points along a closed curve through the box [−1, 1]² × [−0.5, 0.5].
    fn curve(n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let t = i as f32 * 0.618;
                Vec3::new(t.sin(), (t * 1.7).cos(), (t * 0.3).sin() * 0.5)
            })
            .collect()
    }

    /// Every point with its squared distance to `q`, nearest first.
    fn by_distance(points: &[Vec3], q: Vec3) -> Vec<(f32, u32)> {
        let mut all: Vec<(f32, u32)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| (p.distance_squared(q), i as u32))
            .collect();
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        all
    }

    #[test]
    fn nearest_matches_brute_force() {
        let points = curve(500);
        let index = PointIndex::new(&points, 0.05);
        let q = Vec3::new(0.1, -0.2, 0.05);
        let mut got = Vec::new();
        index.nearest(q, 7, 10.0, &mut got);
        let want = by_distance(&points, q);
        assert_eq!(
            got.iter().map(|x| x.1).collect::<Vec<_>>(),
            want[..7].iter().map(|x| x.1).collect::<Vec<_>>()
        );
    }

    /// A point far from the rest reaches across ~10¹⁴ cells of the others' size: the query
    /// visits the occupied cells instead, so it ends, with the same neighbours and order.
    #[test]
    fn an_outlier_finds_its_neighbours_without_visiting_empty_cells() {
        let mut points = curve(2000);
        points.push(Vec3::splat(1.0e5));
        let index = PointIndex::new(&points, 0.02);
        let q = points[2000];
        let mut got = Vec::new();
        index.nearest(q, 4, 1.0e6, &mut got);
        assert_eq!(got, by_distance(&points, q)[..4].to_vec());
        // Raster order of cells (x fastest) either way: the points within a reach of 3 cells
        // (which visits every cell in reach) and of 15 (which visits the occupied ones).
        let index = PointIndex::new(&points, 0.05);
        let rank: Vec<usize> = {
            let mut rank = vec![0; points.len()];
            for (at, &i) in index.order.iter().enumerate() {
                rank[i as usize] = at;
            }
            rank
        };
        for r in [0.15f32, 0.75] {
            let q = points[7];
            let mut got = Vec::new();
            index.for_each_within(q, r, |i, _| got.push(i));
            let mut want: Vec<usize> = (0..points.len())
                .filter(|&i| points[i].distance_squared(q) <= r * r)
                .collect();
            want.sort_by_key(|&i| {
                let [x, y, z] = (points[i] / 0.05).floor().as_ivec3().to_array();
                (z, y, x, rank[i])
            });
            assert!(want.len() > 5, "{r}: {}", want.len());
            assert_eq!(got, want, "reach {r}");
        }
    }
}
