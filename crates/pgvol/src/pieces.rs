//! The solid pieces of a field: the sets of grid nodes inside it joined across node faces
//! (6-connected). Counted on the nodes, so a result is checked before it is contoured or
//! written. Brick by brick: each stored brick's inside nodes are labelled locally, an absent
//! inside brick is one label, and labels touching across brick faces are merged.

use pgvol_core::sparse::{brick_offset, BRICK_EDGE, BRICK_NODES};
use pgvol_field::CoefficientVolume;
use rayon::prelude::*;

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
/// background's side throughout.
pub(crate) fn count_pieces(volume: &CoefficientVolume) -> usize {
    let coeffs = &volume.coeffs;
    let bricks: Vec<[usize; 3]> = coeffs.all_bricks().collect();
    let [bx, by, bz] = coeffs.brick_counts();
    let index = |b: [usize; 3]| b[0] + bx * (b[1] + by * b[2]);
    // Stored bricks and their neighbours see stored coefficients.
    let mut touched = vec![false; bricks.len()];
    for (b, _) in coeffs.stored() {
        for k in b[2].saturating_sub(1)..(b[2] + 2).min(bz) {
            for j in b[1].saturating_sub(1)..(b[1] + 2).min(by) {
                for i in b[0].saturating_sub(1)..(b[0] + 2).min(bx) {
                    touched[index([i, j, k])] = true;
                }
            }
        }
    }
    let labels: Vec<Labels> = bricks
        .par_iter()
        .zip(&touched)
        .map(|(&b, &touched)| {
            if touched {
                label_brick(volume, b)
            } else if coeffs.background_of(b) < 0.0 {
                Labels::Inside
            } else {
                Labels::Outside
            }
        })
        .collect();
    let mut first = Vec::with_capacity(labels.len());
    let mut total = 0usize;
    for l in &labels {
        first.push(total);
        total += l.count();
    }
    let mut parent: Vec<usize> = (0..total).collect();
    for (i, &b) in bricks.iter().enumerate() {
        let (_, n) = coeffs.brick_extent(b);
        for axis in 0..3 {
            let mut nb = b;
            nb[axis] += 1;
            if nb[axis] >= coeffs.brick_counts()[axis] {
                continue;
            }
            let j = index(nb);
            let (here, there) = (&labels[i], &labels[j]);
            if here.count() == 0 || there.count() == 0 {
                continue;
            }
            // The last layer of nodes of this brick faces the first of the next.
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for p in 0..n[u] {
                for q in 0..n[v] {
                    let mut a = [0; 3];
                    a[axis] = n[axis] - 1;
                    a[u] = p;
                    a[v] = q;
                    let mut c = a;
                    c[axis] = 0;
                    if let (Some(x), Some(y)) = (here.at(a), there.at(c)) {
                        union(
                            &mut parent,
                            first[i] + usize::from(x),
                            first[j] + usize::from(y),
                        );
                    }
                }
            }
        }
    }
    (0..total).filter(|&k| find(&mut parent, k) == k).count()
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
        pgvol_field::fit::interp_sparse(grid, Basis::Bspline3, &samples)
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
}
