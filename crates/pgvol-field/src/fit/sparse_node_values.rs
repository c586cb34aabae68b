//! The field at the nodes of its own grid, brick by brick, for sparse volumes. A separable
//! B-spline at the nodes is a 3-tap blur of the coefficients; a brick of constant coefficients
//! with constant neighbours blurs to the same constant, so only the stored bricks and the bricks
//! touching them need work, and every other brick keeps its background.

use pgvol_core::sparse::BrickValues;
use pgvol_core::{SparseGrid, BRICK_EDGE, BRICK_NODES};
use rayon::prelude::*;

use super::node_values::taps;
use crate::stencil::mirror;
use crate::volume::CoefficientVolume;

/// Window edge: one brick and one node either side.
const WIN: usize = BRICK_EDGE + 2;

/// The field at every node, as a sparse grid with the coefficients' background and sides:
/// stored where a stored coefficient brick is within one brick. Pseudo-Gaussians do not sum to
/// one, so constant coefficients do not give that constant: every brick is computed for them.
pub fn node_values_sparse(volume: &CoefficientVolume) -> SparseGrid {
    let coeffs = &volume.coeffs;
    let mut out = coeffs.clone();
    let bricks = match taps(volume.basis) {
        Some(_) => touched_bricks(coeffs),
        None => coeffs.all_bricks().collect(),
    };
    let computed: Vec<([usize; 3], Box<BrickValues>)> = bricks
        .par_iter()
        .map(|&b| (b, Box::new(brick_node_values(volume, b))))
        .collect();
    for (b, v) in computed {
        out.insert(b, v);
    }
    out
}

/// Stored bricks and their 26 neighbours, in brick order.
pub(crate) fn touched_bricks(grid: &SparseGrid) -> Vec<[usize; 3]> {
    let counts = grid.brick_counts();
    let mut touched: Vec<[usize; 3]> = Vec::with_capacity(grid.stored_count() * 3);
    for (b, _) in grid.stored() {
        for dz in -1i64..=1 {
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let n = [b[0] as i64 + dx, b[1] as i64 + dy, b[2] as i64 + dz];
                    if (0..3).all(|a| n[a] >= 0 && (n[a] as usize) < counts[a]) {
                        touched.push(n.map(|c| c as usize));
                    }
                }
            }
        }
    }
    touched.sort_unstable_by_key(|b| (b[2], b[1], b[0]));
    touched.dedup();
    touched
}

/// The field at the nodes of brick `b` of the volume's own grid (nodes past the grid's end hold
/// the brick's background).
pub fn brick_node_values(volume: &CoefficientVolume, b: [usize; 3]) -> BrickValues {
    let mut out = [0.0; BRICK_NODES];
    brick_node_values_into(volume, b, &mut out);
    out
}

/// [`brick_node_values`] into `out`, which a caller can keep on the heap without moving it.
pub fn brick_node_values_into(volume: &CoefficientVolume, b: [usize; 3], out: &mut BrickValues) {
    let coeffs = &volume.coeffs;
    let Some(taps) = taps(volume.basis) else {
        let (lo, n) = coeffs.brick_extent(b);
        out.fill(coeffs.background_of(b));
        return direct_node_values(volume, lo, n, out);
    };
    blurred_brick_into(coeffs, taps, b, out);
}

/// [`brick_node_values_into`] for a separable basis of node weights `(side, centre)`, from the
/// coefficients alone.
pub(crate) fn blurred_brick_into(
    coeffs: &SparseGrid,
    taps: (f32, f32),
    b: [usize; 3],
    out: &mut BrickValues,
) {
    pgvol_core::cpu::run(BlurredBrick {
        coeffs,
        taps,
        b,
        out,
    })
}

/// [`blurred_brick_into`] as a kernel: the decode and the fit's sign check take every stored
/// brick's node values through it.
struct BlurredBrick<'a> {
    coeffs: &'a SparseGrid,
    taps: (f32, f32),
    b: [usize; 3],
    out: &'a mut BrickValues,
}

impl pgvol_core::cpu::Kernel for BlurredBrick<'_> {
    type Output = ();
    #[inline(always)]
    fn run(self) {
        blurred_brick_here(self.coeffs, self.taps, self.b, self.out)
    }
}

/// [`blurred_brick_into`], inlined into both builds of its kernel with the window and blur
/// loops it calls.
#[inline(always)]
fn blurred_brick_here(coeffs: &SparseGrid, taps: (f32, f32), b: [usize; 3], out: &mut BrickValues) {
    let (lo, n) = coeffs.brick_extent(b);
    out.fill(coeffs.background_of(b));
    let mut win = [0.0f32; WIN * WIN * WIN];
    window(coeffs, b, lo, n, &mut win);
    if n == [BRICK_EDGE; 3] {
        return blur_whole(&win, taps.0, taps.1, out);
    }
    blur_box(&win, n, taps, out);
}

/// The field at the `n` nodes (at most a brick's per axis) of the volume's own grid from node
/// `lo`, anywhere in the grid, laid out as a brick's (x fastest, [`BRICK_EDGE`] per row): the
/// values [`brick_node_values`] gives at those nodes, to the bit. Entries past `n` are left as
/// they are.
pub fn box_node_values_into(
    volume: &CoefficientVolume,
    lo: [usize; 3],
    n: [usize; 3],
    out: &mut BrickValues,
) {
    debug_assert!(n.iter().all(|&k| k <= BRICK_EDGE));
    let Some(taps) = taps(volume.basis) else {
        return direct_node_values(volume, lo, n, out);
    };
    let mut win = [0.0f32; WIN * WIN * WIN];
    gathered_window(&volume.coeffs, lo, n, &mut win);
    blur_box(&win, n, taps, out);
}

/// Radial bases: the field evaluated at each node.
fn direct_node_values(
    volume: &CoefficientVolume,
    lo: [usize; 3],
    n: [usize; 3],
    out: &mut BrickValues,
) {
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let p = volume.grid.point(lo[0] + i, lo[1] + j, lo[2] + k);
                out[i + BRICK_EDGE * (j + BRICK_EDGE * k)] = volume.value(p);
            }
        }
    }
}

/// The 3-tap blur along x, y and z of the window of `n` nodes, into `out`'s first `n` nodes.
#[inline(always)]
fn blur_box(win: &Window, n: [usize; 3], (side, centre): (f32, f32), out: &mut BrickValues) {
    let blur = |a: f32, c: f32, d: f32| side * (a + d) + centre * c;
    let mut xs = [0.0f32; WIN * WIN * WIN];
    for z in 0..n[2] + 2 {
        for y in 0..n[1] + 2 {
            for x in 1..=n[0] {
                let at = x + WIN * (y + WIN * z);
                xs[at] = blur(win[at - 1], win[at], win[at + 1]);
            }
        }
    }
    let mut ys = [0.0f32; WIN * WIN * WIN];
    for z in 0..n[2] + 2 {
        for y in 1..=n[1] {
            for x in 1..=n[0] {
                let at = x + WIN * (y + WIN * z);
                ys[at] = blur(xs[at - WIN], xs[at], xs[at + WIN]);
            }
        }
    }
    let plane = WIN * WIN;
    for z in 1..=n[2] {
        for y in 1..=n[1] {
            for x in 1..=n[0] {
                let at = x + WIN * (y + WIN * z);
                out[(x - 1) + BRICK_EDGE * ((y - 1) + BRICK_EDGE * (z - 1))] =
                    blur(ys[at - plane], ys[at], ys[at + plane]);
            }
        }
    }
}

/// The 3-tap blur of a whole brick's window along each axis: [`brick_node_values`]' loops,
/// in the same arithmetic, over fixed-length rows the compiler turns into vector operations.
#[inline(always)]
fn blur_whole(win: &Window, side: f32, centre: f32, out: &mut BrickValues) {
    const E: usize = BRICK_EDGE;
    let blur = |a: f32, c: f32, d: f32| side * (a + d) + centre * c;
    let row = |at: usize| -> &[f32; WIN] { win[at..at + WIN].try_into().expect("a window row") };
    // Along x: every window row, to its brick's E nodes.
    let mut xs = [[0.0f32; E]; WIN * WIN];
    for (r, out) in xs.iter_mut().enumerate() {
        let w = row(WIN * r);
        for x in 0..E {
            out[x] = blur(w[x], w[x + 1], w[x + 2]);
        }
    }
    // Along y: rows y - 1, y, y + 1 of each window plane.
    let mut ys = [[0.0f32; E]; E * WIN];
    for z in 0..WIN {
        for y in 0..E {
            let [a, c, d] = [y, y + 1, y + 2].map(|t| &xs[t + WIN * z]);
            let out = &mut ys[y + E * z];
            for x in 0..E {
                out[x] = blur(a[x], c[x], d[x]);
            }
        }
    }
    // Along z: planes z - 1, z, z + 1.
    for z in 0..E {
        for y in 0..E {
            let [a, c, d] = [z, z + 1, z + 2].map(|t| &ys[y + E * t]);
            let at = E * (y + E * z);
            for x in 0..E {
                out[at + x] = blur(a[x], c[x], d[x]);
            }
        }
    }
}

/// Coefficients around one brick, one node either side, x fastest.
type Window = [f32; WIN * WIN * WIN];

/// The coefficients of brick `b` (lowest node `lo`, `n` nodes per axis) and one node either
/// side.
#[inline(always)]
fn window(coeffs: &SparseGrid, b: [usize; 3], lo: [usize; 3], n: [usize; 3], win: &mut Window) {
    let dims = coeffs.dims();
    let inner = (0..3).all(|a| n[a] == BRICK_EDGE && lo[a] >= 1 && lo[a] + WIN - 1 <= dims[a]);
    if inner {
        inner_window(coeffs, b, win)
    } else {
        gathered_window(coeffs, lo, n, win)
    }
}

/// [`window`] of a whole brick away from the grid's ends: parts of the brick and its 26
/// neighbours, each looked up once (a gather looks a brick up per row segment).
#[inline(always)]
fn inner_window(coeffs: &SparseGrid, b: [usize; 3], win: &mut Window) {
    // Per axis: neighbour offset, first node in it, nodes taken (all or one), first window node.
    const PARTS: [(i64, usize, usize, usize); 3] = [
        (-1, BRICK_EDGE - 1, 1, 0),
        (0, 0, BRICK_EDGE, 1),
        (1, 0, 1, WIN - 1),
    ];
    for (dz, z0, nz, tz) in PARTS {
        for (dy, y0, ny, ty) in PARTS {
            for (dx, x0, nx, tx) in PARTS {
                let nb = [b[0] as i64 + dx, b[1] as i64 + dy, b[2] as i64 + dz].map(|c| c as usize);
                let source = coeffs.brick(nb);
                let fill = coeffs.background_of(nb);
                for z in 0..nz {
                    for y in 0..ny {
                        let to = tx + WIN * (ty + y + WIN * (tz + z));
                        let dst = &mut win[to..to + nx];
                        match (source, nx) {
                            (Some(v), BRICK_EDGE) => {
                                // A whole row at a fixed length: moved inline, not by a call.
                                let from = BRICK_EDGE * (y0 + y + BRICK_EDGE * (z0 + z));
                                let row: &[f32; BRICK_EDGE] =
                                    v[from..from + BRICK_EDGE].try_into().expect("a brick row");
                                let dst: &mut [f32; BRICK_EDGE] =
                                    dst.try_into().expect("a window row");
                                *dst = *row;
                            }
                            (Some(v), _) => {
                                // One node of a neighbour's face: a load, not a copy call.
                                dst[0] = v[x0 + BRICK_EDGE * (y0 + y + BRICK_EDGE * (z0 + z))];
                            }
                            (None, _) => dst.fill(fill),
                        }
                    }
                }
            }
        }
    }
}

/// [`window`] anywhere, its nodes mirrored at the grid's ends as the basis is.
#[inline(always)]
fn gathered_window(coeffs: &SparseGrid, lo: [usize; 3], n: [usize; 3], win: &mut Window) {
    let dims = coeffs.dims();
    let index = |a: usize, t: usize| mirror(lo[a] as i64 - 1 + t as i64, dims[a]);
    let first = [0, 1, 2].map(|a| lo[a].saturating_sub(1));
    let last = [0, 1, 2].map(|a| (lo[a] + n[a] + 1).min(dims[a]));
    let size = [0, 1, 2].map(|a| last[a] - first[a]);
    let mut gathered = vec![0.0f32; size[0] * size[1] * size[2]];
    coeffs.gather(first, size, &mut gathered);
    for z in 0..n[2] + 2 {
        let gz = index(2, z) - first[2];
        for y in 0..n[1] + 2 {
            let gy = index(1, y) - first[1];
            for x in 0..n[0] + 2 {
                let gx = index(0, x) - first[0];
                win[x + WIN * (y + WIN * z)] = gathered[gx + size[0] * (gy + size[1] * gz)];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::basis::Basis;
    use crate::fit::node_values;
    use glam::Vec3;
    use pgvol_core::{Background, Grid};

    #[test]
    fn windows_of_inner_bricks_are_those_gathered() {
        let dims = [40, 33, 40];
        let mut g = SparseGrid::new(dims, Background::clamp(0.5));
        let mut x = 1u32;
        for b in g.all_bricks().collect::<Vec<_>>() {
            x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            match x >> 30 {
                0 | 1 => {
                    let mut v = Box::new([0.0f32; BRICK_NODES]);
                    for (i, c) in v.iter_mut().enumerate() {
                        *c = (i as f32 * 0.37 + (x >> 8) as f32).sin();
                    }
                    g.insert(b, v);
                }
                2 => g.set_inside(b, true),
                _ => {}
            }
        }
        let mut inner = 0;
        for b in g.all_bricks().collect::<Vec<_>>() {
            let (lo, n) = g.brick_extent(b);
            let mut gathered = [0.0; WIN * WIN * WIN];
            gathered_window(&g, lo, n, &mut gathered);
            if (0..3).all(|a| b[a] > 0 && lo[a] + WIN - 1 <= dims[a]) {
                let mut win = [f32::NAN; WIN * WIN * WIN];
                inner_window(&g, b, &mut win);
                assert_eq!(win, gathered, "{b:?}");
                inner += 1;
            }
        }
        assert!(inner >= 8, "{inner}");
    }

    /// Coefficients varying node to node on a grid of `dims`, one brick in three left to the
    /// background of its side.
    fn patchy_volume(dims: [usize; 3], basis: Basis) -> CoefficientVolume {
        let grid = Grid {
            origin: Vec3::new(-0.3, 0.1, 0.2),
            spacing: 0.07,
            dims,
            offset: Default::default(),
        };
        let dense: Vec<f32> = (0..grid.len())
            .map(|i| ((i * 37) % 11) as f32 * 0.1 - 0.5)
            .collect();
        let mut coeffs = SparseGrid::from_dense(dims, &dense, Background::clamp(0.6));
        let mut turn = 0;
        coeffs.retain(|_, _| {
            turn += 1;
            turn % 3 != 0
        });
        CoefficientVolume::from_sparse(grid, basis, coeffs).unwrap()
    }

    #[test]
    fn boxes_anywhere_give_the_bricks_node_values_to_the_bit() {
        for basis in [Basis::Bspline2, Basis::Bspline3, Basis::Pg { n: 3, r: 1.5 }] {
            let vol = patchy_volume([21, 17, 30], basis);
            let whole = node_values_sparse(&vol);
            // Boxes off the bricks' lattice, across brick faces, at both ends of the grid.
            for (lo, n) in [
                ([3, 5, 9], [8, 8, 8]),
                ([0, 0, 0], [5, 8, 3]),
                ([15, 9, 22], [6, 8, 8]),
                ([7, 1, 13], [1, 7, 2]),
            ] {
                let mut out = [f32::NAN; BRICK_NODES];
                box_node_values_into(&vol, lo, n, &mut out);
                for k in 0..n[2] {
                    for j in 0..n[1] {
                        for i in 0..n[0] {
                            let got = out[i + BRICK_EDGE * (j + BRICK_EDGE * k)];
                            let want = whole.get([lo[0] + i, lo[1] + j, lo[2] + k]);
                            assert_eq!(
                                got.to_bits(),
                                want.to_bits(),
                                "{basis:?} {lo:?} {i} {j} {k}"
                            );
                        }
                    }
                }
                // Entries past the box are left alone.
                assert!(out[BRICK_NODES - 1].is_nan() || n == [BRICK_EDGE; 3]);
            }
        }
    }

    #[test]
    fn match_the_dense_node_values_for_every_basis_and_leave_far_bricks_alone() {
        for dims in [[21, 17, 30], [9, 9, 9], [2, 12, 5]] {
            for basis in [
                Basis::Trilinear,
                Basis::Bspline2,
                Basis::Bspline3,
                Basis::Pg { n: 3, r: 1.5 },
            ] {
                let vol = patchy_volume(dims, basis);
                let want = node_values(&vol);
                let got = node_values_sparse(&vol).to_dense();
                for (i, (a, b)) in want.iter().zip(&got).enumerate() {
                    assert!(
                        (a - b).abs() <= 1e-6,
                        "{basis:?} {dims:?} node {i}: {a} vs {b}"
                    );
                }
            }
        }
        // A single stored brick in a large grid: only it and its neighbours are computed.
        let dims = [200, 200, 200];
        let grid = Grid {
            origin: Vec3::ZERO,
            spacing: 1.0,
            dims,
            offset: Default::default(),
        };
        let mut coeffs = SparseGrid::new(dims, Background::clamp(3.0));
        coeffs.insert([10, 10, 10], Box::new([0.5; BRICK_NODES]));
        let vol = CoefficientVolume::from_sparse(grid, Basis::Bspline3, coeffs).unwrap();
        let values = node_values_sparse(&vol);
        assert_eq!(values.stored_count(), 27);
        assert_eq!(values.get([0, 0, 0]), 3.0);
        assert_eq!(values.get([84, 84, 84]), 0.5);
        assert!((values.get([79, 84, 84]) - (3.0 * 5.0 / 6.0 + 0.5 / 6.0)).abs() < 1e-6);
    }
}
