//! The solid pieces of a field: the sets of grid nodes inside it joined across node faces
//! (6-connected). Counted on the nodes, so a result is checked before it is contoured or
//! written. Brick by brick: each stored brick's inside nodes are labelled locally, an absent
//! inside brick is one label, and labels touching across brick faces are merged.

use pgvol_core::sparse::{brick_offset, BRICK_EDGE, BRICK_NODES};
use pgvol_field::CoefficientVolume;
use rayon::prelude::*;
use std::ops::Range;

/// No label: the node is outside.
const OUT: u16 = u16::MAX;

/// The inside nodes of one brick, labelled by piece within the brick.
enum Labels {
    /// Every node outside.
    Outside,
    /// Every node inside, one piece.
    Inside,
    /// Labels per node ([`OUT`] outside) and their count.
    Nodes(Box<[u16; BRICK_NODES]>, u16),
}

impl Labels {
    fn count(&self) -> usize {
        match self {
            Labels::Outside => 0,
            Labels::Inside => 1,
            Labels::Nodes(_, n) => usize::from(*n),
        }
    }

    /// The local label of brick node `n`, if inside.
    fn at(&self, n: [usize; 3]) -> Option<u16> {
        match self {
            Labels::Outside => None,
            Labels::Inside => Some(0),
            Labels::Nodes(labels, _) => Some(labels[brick_offset(n)]).filter(|&l| l != OUT),
        }
    }
}

/// The pieces of `volume`'s inside at its grid nodes. The field at the nodes is a blur of
/// the coefficients one node wide: bricks away from every stored brick take their
/// background's side throughout, so a row of such bricks with one side is one run.
///
/// Layers of bricks along z are labelled one at a time and joined to the layer below, so memory
/// is two layers' labels and one union-find entry per label: it follows the stored bricks, not
/// the grid (a 4096³ grid has 134 million bricks).
pub(crate) fn count_pieces(volume: &CoefficientVolume) -> usize {
    let coeffs = &volume.coeffs;
    let [bx, by, bz] = coeffs.brick_counts();
    let mut stored_by_layer: Vec<Vec<[u32; 2]>> = vec![Vec::new(); bz];
    for (b, _) in coeffs.stored() {
        stored_by_layer[b[2]].push([b[1] as u32, b[0] as u32]);
    }
    let mut parent: Vec<usize> = Vec::new();
    let mut below: Option<Vec<Vec<Segment>>> = None;
    for k in 0..bz {
        let touched = touched_in_layer(&stored_by_layer, k, [bx, by]);
        let rows = layer_rows(volume, k, &touched, &mut parent);
        for (j, row) in rows.iter().enumerate() {
            for pair in row.windows(2) {
                join(volume, &mut parent, &pair[0], &pair[1], [j, k], 0);
            }
            if j > 0 {
                join_rows(volume, &mut parent, &rows[j - 1], row, [j - 1, k], 1);
            }
            if let Some(below) = &below {
                join_rows(volume, &mut parent, &below[j], row, [j, k - 1], 2);
            }
        }
        below = Some(rows);
    }
    (0..parent.len())
        .filter(|&l| find(&mut parent, l) == l)
        .count()
}

/// A stretch of one row of bricks along x: a stored brick or a neighbour of one, labelled
/// node by node, or a run of other bricks on one side.
struct Segment {
    /// First brick along x, and one past the last.
    x: [usize; 2],
    /// The nodes' labels; a run's are [`Labels::Inside`] or [`Labels::Outside`] throughout.
    labels: Labels,
    /// The global label of local label 0.
    first: usize,
}

impl Segment {
    /// The global label of node `n` of brick `x` of the segment, if inside.
    fn at(&self, n: [usize; 3]) -> Option<usize> {
        self.labels.at(n).map(|l| self.first + usize::from(l))
    }
}

/// The bricks of layer `k` within one brick of a stored brick, as `[j, i]`, sorted.
fn touched_in_layer(stored: &[Vec<[u32; 2]>], k: usize, counts: [usize; 2]) -> Vec<[u32; 2]> {
    let [bx, by] = counts.map(|c| c as u32);
    let mut touched = Vec::new();
    for layer in &stored[k.saturating_sub(1)..(k + 2).min(stored.len())] {
        for &[j, i] in layer {
            for tj in j.saturating_sub(1)..(j + 2).min(by) {
                for ti in i.saturating_sub(1)..(i + 2).min(bx) {
                    touched.push([tj, ti]);
                }
            }
        }
    }
    touched.sort_unstable();
    touched.dedup();
    touched
}

/// The segments of every row of layer `k`, with global labels taken from `parent`'s end.
fn layer_rows(
    volume: &CoefficientVolume,
    k: usize,
    touched: &[[u32; 2]],
    parent: &mut Vec<usize>,
) -> Vec<Vec<Segment>> {
    let coeffs = &volume.coeffs;
    let [bx, by, _] = coeffs.brick_counts();
    let mut rows: Vec<Vec<Segment>> = (0..by)
        .into_par_iter()
        .map(|j| {
            let from = touched.partition_point(|t| (t[0] as usize) < j);
            let to = touched.partition_point(|t| (t[0] as usize) <= j);
            let mut row = Vec::new();
            let mut x = 0;
            for t in &touched[from..to] {
                let i = t[1] as usize;
                runs(volume, [j, k], x..i, &mut row);
                let labels = label_brick(volume, [i, j, k]);
                row.push(Segment {
                    x: [i, i + 1],
                    labels,
                    first: 0,
                });
                x = i + 1;
            }
            runs(volume, [j, k], x..bx, &mut row);
            row
        })
        .collect();
    for segment in rows.iter_mut().flatten() {
        segment.first = parent.len();
        let count = segment.labels.count();
        parent.extend(segment.first..segment.first + count);
    }
    rows
}

/// Pushes the runs of bricks `xs` of row `[j, k]`, none near a stored brick, split where their
/// side changes.
fn runs(volume: &CoefficientVolume, [j, k]: [usize; 2], xs: Range<usize>, row: &mut Vec<Segment>) {
    let coeffs = &volume.coeffs;
    let mut start = xs.start;
    while start < xs.end {
        let inside = coeffs.is_inside([start, j, k]);
        let end = coeffs.same_side_end([start, j, k], xs.end);
        row.push(Segment {
            x: [start, end],
            labels: if inside {
                Labels::Inside
            } else {
                Labels::Outside
            },
            first: 0,
        });
        start = end;
    }
}

/// Joins the pieces of two rows that touch across `axis` (1 or 2): `lower` is the row at
/// `[j, k]`, `upper` the next one along the axis.
fn join_rows(
    volume: &CoefficientVolume,
    parent: &mut [usize],
    lower: &[Segment],
    upper: &[Segment],
    row: [usize; 2],
    axis: usize,
) {
    let (mut a, mut b) = (0, 0);
    while a < lower.len() && b < upper.len() {
        let (s, t) = (&lower[a], &upper[b]);
        if s.x[0].max(t.x[0]) < s.x[1].min(t.x[1]) {
            join(volume, parent, s, t, row, axis);
        }
        if s.x[1] <= t.x[1] {
            a += 1;
        } else {
            b += 1;
        }
    }
}

/// Joins the labels of segments `s` and `t` that meet across `axis`: along x, `t` follows `s`
/// in row `[j, k]`; along y or z, `s` lies in row `[j, k]` and `t` one brick further on the axis,
/// their stretches overlapping.
fn join(
    volume: &CoefficientVolume,
    parent: &mut [usize],
    s: &Segment,
    t: &Segment,
    [j, k]: [usize; 2],
    axis: usize,
) {
    if s.labels.count() == 0 || t.labels.count() == 0 {
        return;
    }
    let uniform = |g: &Segment| matches!(g.labels, Labels::Inside);
    if uniform(s) && uniform(t) {
        union(parent, s.first, t.first);
        return;
    }
    // One of them is a single brick, so they meet at one brick face.
    let x = if axis == 0 {
        s.x[1] - 1
    } else {
        s.x[0].max(t.x[0])
    };
    let (_, n) = volume.coeffs.brick_extent([x, j, k]);
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    for p in 0..n[u] {
        for q in 0..n[v] {
            let mut a = [0; 3];
            a[axis] = n[axis] - 1;
            a[u] = p;
            a[v] = q;
            let mut c = a;
            c[axis] = 0;
            if let (Some(x), Some(y)) = (s.at(a), t.at(c)) {
                union(parent, x, y);
            }
        }
    }
}

/// The inside nodes of brick `b` labelled by 6-connected piece within the brick.
fn label_brick(volume: &CoefficientVolume, b: [usize; 3]) -> Labels {
    let (_, n) = volume.coeffs.brick_extent(b);
    let values = pgvol_field::fit::brick_node_values(volume, b);
    let mut inside = [false; BRICK_NODES];
    let mut count_in = 0;
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let o = brick_offset([i, j, k]);
                inside[o] = values[o] < 0.0;
                count_in += usize::from(inside[o]);
            }
        }
    }
    if count_in == 0 {
        return Labels::Outside;
    }
    if count_in == n[0] * n[1] * n[2] {
        return Labels::Inside;
    }
    let mut labels = Box::new([OUT; BRICK_NODES]);
    let mut count = 0u16;
    let mut stack = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let start = [i, j, k];
                if !inside[brick_offset(start)] || labels[brick_offset(start)] != OUT {
                    continue;
                }
                labels[brick_offset(start)] = count;
                stack.push(start);
                while let Some(c) = stack.pop() {
                    for axis in 0..3 {
                        for step in [-1isize, 1] {
                            let to = c[axis] as isize + step;
                            if to < 0 || to >= n[axis] as isize {
                                continue;
                            }
                            let mut d = c;
                            d[axis] = to as usize;
                            let o = brick_offset(d);
                            if inside[o] && labels[o] == OUT {
                                labels[o] = count;
                                stack.push(d);
                            }
                        }
                    }
                }
                count += 1;
            }
        }
    }
    Labels::Nodes(labels, count)
}

fn find(parent: &mut [usize], mut k: usize) -> usize {
    while parent[k] != k {
        parent[k] = parent[parent[k]];
        k = parent[k];
    }
    k
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb)] = ra.min(rb);
    }
}

/// Bricks are 8 nodes on a side: local labels fit in 16 bits with room for [`OUT`].
const _: () = assert!(BRICK_EDGE * BRICK_EDGE * BRICK_EDGE < OUT as usize);

#[cfg(test)]
mod tests {
    use super::*;
    use pgvol_core::{Background, Grid, SparseGrid};
    use pgvol_field::Basis;

    /// Node samples interpolated, so the field takes them at the nodes.
    fn field(n: usize, inside: impl Fn([usize; 3]) -> bool) -> CoefficientVolume {
        let grid = Grid::cube_res(glam::Vec3::ZERO, glam::Vec3::ONE, n).unwrap();
        let mut samples = Vec::new();
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    samples.push(if inside([i, j, k]) { -1.0 } else { 1.0 });
                }
            }
        }
        let samples = SparseGrid::from_dense(grid.dims, &samples, Background::clamp(1.0));
        pgvol_field::fit::interp_sparse(
            grid,
            Basis::Bspline3,
            &samples,
            pgvol_core::progress::QUIET,
        )
        .unwrap()
        .0
    }

    #[test]
    fn pieces_are_counted_across_bricks() {
        // A bar across three bricks, and three separate cubes.
        let bar = field(30, |[i, j, k]| {
            (4..26).contains(&i) && (10..14).contains(&j) && (10..14).contains(&k)
        });
        assert_eq!(count_pieces(&bar), 1);
        let cubes = field(30, |[i, j, k]| {
            (10..14).contains(&j)
                && (10..14).contains(&k)
                && [3, 13, 23].iter().any(|&c| (c..c + 4).contains(&i))
        });
        assert_eq!(count_pieces(&cubes), 3);
        let empty = field(20, |_| false);
        assert_eq!(count_pieces(&empty), 0);
    }

    /// The pieces of the inside nodes by a flood fill over the whole grid, each node's side
    /// from the general evaluation of the field at its position; `None` when a node's value is
    /// within rounding of zero, where the general evaluation and the separable taps may take
    /// different sides.
    fn pieces_by_flood(volume: &CoefficientVolume) -> Option<usize> {
        let [nx, ny, nz] = volume.grid.dims;
        let index = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
        let mut inside = vec![false; nx * ny * nz];
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let value = volume.value(volume.grid.point(i, j, k));
                    if value.abs() < 1e-6 {
                        return None;
                    }
                    inside[index(i, j, k)] = value < 0.0;
                }
            }
        }
        let mut pieces = 0;
        let mut stack = Vec::new();
        for start in 0..inside.len() {
            if !inside[start] {
                continue;
            }
            pieces += 1;
            inside[start] = false;
            stack.push(start);
            while let Some(at) = stack.pop() {
                let (i, j, k) = (at % nx, at / nx % ny, at / (nx * ny));
                let near = [
                    (i > 0).then(|| at - 1),
                    (i + 1 < nx).then(|| at + 1),
                    (j > 0).then(|| at - nx),
                    (j + 1 < ny).then(|| at + nx),
                    (k > 0).then(|| at - nx * ny),
                    (k + 1 < nz).then(|| at + nx * ny),
                ];
                for n in near.into_iter().flatten() {
                    if inside[n] {
                        inside[n] = false;
                        stack.push(n);
                    }
                }
            }
        }
        Some(pieces)
    }

    /// Coefficients −1 inside `balls` (centre and radius in nodes) and +1 outside; of the
    /// bricks, those `keep` rejects are left to the background of their side where their nodes
    /// and those one node around them are all on one side (as a file leaves bricks absent only
    /// where the field is far from zero), and stored otherwise.
    fn balls_volume(n: usize, balls: &[([f32; 3], f32)], keep: &[bool]) -> CoefficientVolume {
        let grid = Grid::cube_res(glam::Vec3::ZERO, glam::Vec3::ONE, n).unwrap();
        let inside = |p: [usize; 3]| {
            balls
                .iter()
                .any(|(c, r)| (0..3).map(|a| (p[a] as f32 - c[a]).powi(2)).sum::<f32>() < r * r)
        };
        let mut values = Vec::new();
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    values.push(if inside([i, j, k]) { -1.0 } else { 1.0 });
                }
            }
        }
        let mut which = keep.iter().cycle();
        let coeffs =
            SparseGrid::from_dense_where(grid.dims, &values, Background::clamp(1.0), |b| {
                if *which.next().unwrap() {
                    return Some(true);
                }
                let lo = b.map(|c| (c * BRICK_EDGE).saturating_sub(1));
                let hi = b.map(|c| ((c + 1) * BRICK_EDGE + 1).min(n));
                let mut sides = (lo[2]..hi[2]).flat_map(|k| {
                    (lo[1]..hi[1]).flat_map(move |j| (lo[0]..hi[0]).map(move |i| [i, j, k]))
                });
                let first = inside([lo[0], lo[1], lo[2]]);
                if sides.all(|p| inside(p) == first) {
                    (!first).then_some(false)
                } else {
                    Some(true)
                }
            });
        CoefficientVolume::from_sparse(grid, Basis::Bspline3, coeffs).unwrap()
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
        #[test]
        fn pieces_match_a_flood_fill_of_the_nodes(
            n in 9usize..40,
            balls in proptest::collection::vec(
                ([0.0f32..40.0, 0.0f32..40.0, 0.0f32..40.0], 0.5f32..9.0), 1..7),
            keep in proptest::collection::vec(proptest::bool::weighted(0.6), 1..13),
        ) {
            let volume = balls_volume(n, &balls, &keep);
            let flood = pieces_by_flood(&volume);
            proptest::prop_assume!(flood.is_some());
            proptest::prop_assert_eq!(Some(count_pieces(&volume)), flood);
        }
    }

    #[test]
    fn absent_inside_bricks_join_their_neighbours_through_runs() {
        // A large ball whose middle bricks are all absent and inside, beside a small one.
        let keep = [true, false, false, false, false];
        let volume = balls_volume(
            48,
            &[([24.0, 24.0, 24.0], 18.0), ([3.0, 3.0, 3.0], 1.5)],
            &keep,
        );
        let absent_inside = volume
            .coeffs
            .all_bricks()
            .filter(|&b| !volume.coeffs.is_stored(b) && volume.coeffs.is_inside(b))
            .count();
        assert!(absent_inside > 4, "{absent_inside}");
        assert_eq!(Some(count_pieces(&volume)), pieces_by_flood(&volume));
        assert_eq!(count_pieces(&volume), 2);
    }
}
