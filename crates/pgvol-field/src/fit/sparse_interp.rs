//! B-spline interpolation of band-limited samples held sparsely, computed brick by brick.
//!
//! The exact prefilter is global, but its influence falls as `|z|^k` with the distance `k` in
//! nodes (`|z|` ≈ 0.268 cubic, 0.172 quadratic), and a constant input gives that same constant
//! as coefficients. So the coefficients of a brick follow, to within `HALO_TOLERANCE` of the
//! sample range, from the samples of the brick plus a halo of `H` nodes per side, and far from
//! the stored bricks they are the background. Only the bricks near stored samples are computed,
//! each from a local window, and the work grows with the band, not with the grid.

use rayon::prelude::*;

use pgvol_core::progress::{self, Span};
use pgvol_core::sparse::{brick_offset, BrickValues};
use pgvol_core::{SparseGrid, BRICK_EDGE, BRICK_NODES};

use super::node_values::taps;
use crate::basis::Basis;
use crate::prefilter::prefilter_lanes;
use crate::stencil::mirror;

/// Bricks per edge of a group: the groups of `GROUP`³ bricks share one halo, whose cost per
/// brick falls as the group grows, while a group only partly in the band filters nodes no brick
/// needs (its window is trimmed to its bricks' bounding box). On banded spheres at 128³–256³
/// (`tests::window_nodes_per_coefficient`), 8 gathers and x-filters 4.5–4.9 window nodes per
/// coefficient, against 8.0–8.4 at 4 and 19 at 2; 16 gathers 2.7–4.0, but its windows of up to
/// 216³ nodes take ~175 MB per thread with the filter's f64 passes (8: up to 88³, ~10 MB), and a
/// 256³ grid has only 8 such groups to share among the threads.
const GROUP: usize = 8;

/// Weight below which samples past the halo are ignored, relative to the largest: the halo is
/// the smallest `H` with `|z|^H` under it, 12 nodes for the cubic B-spline and 9 for the
/// quadratic. The coefficients then move by at most one f32 ulp (tests below), less than the
/// global filter's own rounding.
const HALO_TOLERANCE: f64 = 2e-7;

/// Nodes per side of the window a group is filtered in, for the filter pole `z`.
pub(crate) fn halo(z: f64) -> usize {
    (HALO_TOLERANCE.ln() / z.abs().ln()).ceil() as usize
}

/// The coefficients interpolating `samples` for the recursive filter of pole `z`, stored for
/// the stored sample bricks and every brick touching one (26-neighbourhood): the field at a
/// node reads the coefficients one node around it, and between nodes two, so the field over
/// the stored bricks comes only from computed coefficients. The bricks left to the background
/// start 9 nodes from any stored sample, where for smooth samples the true coefficients differ
/// from the background by about 1.4 · |z|⁹ (1e-5 cubic) of the samples' departure from it.
///
/// Each group of bricks is filtered in a window of its bricks' bounding box plus `halo(z)`
/// nodes per side, clipped to the grid: absent bricks read as their side's background, the
/// grid's own borders keep the global filter's mirror boundary, and interior window edges
/// mirror too, which only moves coefficients by `|z|^H` once inside the kept bricks. Groups run
/// in parallel, each alone, and are inserted in a fixed order, so the result does not depend
/// on the thread count. Unstored bricks keep the samples' sides: the samples are cloned and
/// emptied first, at a cost in their stored bricks and tiles and none per absent brick, and
/// before the new bricks exist, so the peak memory is that of the samples and the result.
/// Groups are counted through `span`; after a stop request the groups not yet begun are left
/// out, and the incomplete result is for the caller to discard.
pub(crate) fn prefilter_sparse(samples: &SparseGrid, z: f64, span: Option<Span>) -> SparseGrid {
    prefilter_sparse_with(samples, z, halo(z), GROUP, DROP_TOLERANCE, span)
}

/// A computed neighbour brick whose coefficients all lie within this fraction of the clamp of
/// its side's background is left to the background: as close as the halo's truncation and far
/// below the file's quantisation step (h/512 at a clamp of 4 h is 5·10⁻⁴ of the clamp).
const DROP_TOLERANCE: f32 = 1e-5;

/// Bricks per edge of the groups [`prefilter_sparse`] filters together; a group's coefficients
/// follow from the samples within its bricks' box plus the halo.
pub const SPARSE_GROUP: usize = GROUP;

/// The coefficient bricks [`prefilter_sparse`] computes for the groups whose y and z indices
/// (in groups) lie in `gy` and `gz`, in the order it stores them. `samples` must hold every
/// brick within [`layer_reach`] grid bricks of those groups as the whole grid's samples do;
/// then the bricks are bit for bit the ones of the whole grid, since each group is filtered
/// alone from its own window. Groups not begun by a stop request of `report` are left out.
pub(crate) fn prefilter_groups(
    samples: &SparseGrid,
    z: f64,
    gy: std::ops::Range<usize>,
    gz: std::ops::Range<usize>,
    report: progress::Report,
) -> Vec<([usize; 3], Box<BrickValues>)> {
    let bricks = output_bricks(samples, GROUP);
    let group_of = |b: &[usize; 3]| b.map(|c| c / GROUP);
    let groups: Vec<&[[usize; 3]]> = bricks
        .chunk_by(|a, b| group_of(a) == group_of(b))
        .filter(|g| gy.contains(&(g[0][1] / GROUP)) && gz.contains(&(g[0][2] / GROUP)))
        .collect();
    let counter = Span::whole(report).counter(groups.len());
    let computed: Vec<Vec<([usize; 3], Box<BrickValues>)>> = groups
        .par_iter()
        .map_init(Scratch::default, |scratch, group| {
            if counter.stopped() {
                return Vec::new();
            }
            let bricks = filter_group(samples, z, halo(z), group, DROP_TOLERANCE, scratch);
            counter.tick();
            bricks
        })
        .collect();
    computed.into_iter().flatten().collect()
}

/// Grid bricks around a layer of groups whose samples its coefficients read: the halo (12
/// nodes for the cubic) rounded up to bricks, plus the one brick of neighbours that decides
/// which bricks get coefficients.
pub fn layer_reach(z: f64) -> usize {
    halo(z).div_ceil(BRICK_EDGE).max(1)
}

/// [`prefilter_sparse`] with a given halo, group edge and drop tolerance.
fn prefilter_sparse_with(
    samples: &SparseGrid,
    z: f64,
    h: usize,
    group: usize,
    drop: f32,
    span: Option<Span>,
) -> SparseGrid {
    let bricks = output_bricks(samples, group);
    let group_of = |b: &[usize; 3]| b.map(|c| c / group);
    let groups: Vec<&[[usize; 3]]> = bricks.chunk_by(|a, b| group_of(a) == group_of(b)).collect();
    let counter = span.map(|s| s.counter(groups.len()));
    let mut out = samples.clone();
    out.retain(|_, _| false);
    let computed: Vec<Vec<([usize; 3], Box<BrickValues>)>> = groups
        .par_iter()
        .map_init(Scratch::default, |scratch, group| {
            if progress::stopped(counter.as_ref()) {
                return Vec::new();
            }
            let bricks = filter_group(samples, z, h, group, drop, scratch);
            progress::tick(counter.as_ref());
            bricks
        })
        .collect();
    for (b, values) in computed.into_iter().flatten() {
        out.insert(b, values);
    }
    out
}

/// The stored bricks and their neighbours, sorted by group of `group`³ bricks (z, y, x) and
/// then by brick, once each.
fn output_bricks(samples: &SparseGrid, group: usize) -> Vec<[usize; 3]> {
    let counts = samples.brick_counts();
    let mut out = Vec::with_capacity(samples.stored_count() * 4);
    for (b, _) in samples.stored() {
        let range = |a: usize| b[a].saturating_sub(1)..=(b[a] + 1).min(counts[a] - 1);
        for k in range(2) {
            for j in range(1) {
                for i in range(0) {
                    out.push([i, j, k]);
                }
            }
        }
    }
    let key = |b: &[usize; 3]| {
        let g = b.map(|c| c / group);
        (g[2], g[1], g[0], b[2], b[1], b[0])
    };
    out.sort_unstable_by_key(key);
    out.dedup();
    out
}

/// Buffers reused from group to group on one thread.
#[derive(Default)]
struct Scratch {
    window: Vec<f32>,
    lanes: Vec<f64>,
    /// The window after the x pass, narrowed to the kept x range.
    xs: Vec<f64>,
    /// After the y pass, narrowed to the kept x and y ranges.
    ys: Vec<f64>,
}

/// Where a group is filtered, in nodes: the kept box `lo..hi` (its bricks' bounding box) and
/// the window `w_lo..w_hi` (the kept box and the halo, clipped to the grid).
struct GroupWindow {
    lo: [usize; 3],
    hi: [usize; 3],
    w_lo: [usize; 3],
    w_hi: [usize; 3],
}

fn group_window(samples: &SparseGrid, group: &[[usize; 3]], h: usize) -> GroupWindow {
    let dims = samples.dims();
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    for &b in group {
        let (blo, n) = samples.brick_extent(b);
        for a in 0..3 {
            lo[a] = lo[a].min(blo[a]);
            hi[a] = hi[a].max(blo[a] + n[a]);
        }
    }
    let w_lo = lo.map(|c| c.saturating_sub(h));
    let w_hi = [0, 1, 2].map(|a| (hi[a] + h).min(dims[a]));
    GroupWindow { lo, hi, w_lo, w_hi }
}

/// The coefficient bricks of one group (bricks sorted and all in one group).
fn filter_group(
    samples: &SparseGrid,
    z: f64,
    h: usize,
    group: &[[usize; 3]],
    drop: f32,
    s: &mut Scratch,
) -> Vec<([usize; 3], Box<BrickValues>)> {
    let GroupWindow { lo, hi, w_lo, w_hi } = group_window(samples, group, h);
    let wn = [0, 1, 2].map(|a| w_hi[a] - w_lo[a]);
    let off = [0, 1, 2].map(|a| lo[a] - w_lo[a]);
    let kn = [0, 1, 2].map(|a| hi[a] - lo[a]);
    let [wx, wy, wz] = wn;
    let [kx, ky, _] = kn;

    s.window.resize(wx * wy * wz, 0.0);
    samples.gather(w_lo, wn, &mut s.window);

    // x: each z-plane transposed so its x lines are interleaved lanes, all filtered at once.
    s.lanes.resize(wx * wy, 0.0);
    s.xs.resize(kx * wy * wz, 0.0);
    for k in 0..wz {
        let plane = &s.window[wx * wy * k..][..wx * wy];
        for (j, row) in plane.chunks_exact(wx).enumerate() {
            for (i, &v) in row.iter().enumerate() {
                s.lanes[j + wy * i] = v as f64;
            }
        }
        prefilter_lanes(&mut s.lanes, wy, wx, z);
        let out = &mut s.xs[kx * wy * k..][..kx * wy];
        for j in 0..wy {
            for i in 0..kx {
                out[i + kx * j] = s.lanes[j + wy * (off[0] + i)];
            }
        }
    }
    // y: per z-plane, the kept x columns are the lanes.
    s.ys.resize(kx * ky * wz, 0.0);
    for k in 0..wz {
        let plane = &mut s.xs[kx * wy * k..][..kx * wy];
        prefilter_lanes(plane, kx, wy, z);
        s.ys[kx * ky * k..][..kx * ky].copy_from_slice(&plane[kx * off[1]..][..kx * ky]);
    }
    // z: every kept (x, y) column at once.
    prefilter_lanes(&mut s.ys, kx * ky, wz, z);

    let fill = samples.background().outside;
    let bg = samples.background();
    let tolerance = drop * bg.outside.abs().max(bg.inside.abs());
    group
        .iter()
        .filter_map(|&b| {
            let (blo, n) = samples.brick_extent(b);
            let mut values = Box::new([fill; BRICK_NODES]);
            for k in 0..n[2] {
                for j in 0..n[1] {
                    let src = (blo[0] - lo[0])
                        + kx * ((blo[1] - lo[1] + j) + ky * (blo[2] - lo[2] + k + off[2]));
                    let dst = BRICK_EDGE * (j + BRICK_EDGE * k);
                    for (d, &c) in values[dst..dst + n[0]]
                        .iter_mut()
                        .zip(&s.ys[src..src + n[0]])
                    {
                        *d = c as f32;
                    }
                }
            }
            // A neighbour whose coefficients all sit at its side's background adds nothing.
            let side = samples.background_of(b);
            let flat = drop > 0.0 && !samples.is_stored(b) && {
                let mut flat = true;
                for k in 0..n[2] {
                    for j in 0..n[1] {
                        let at = BRICK_EDGE * (j + BRICK_EDGE * k);
                        flat &= values[at..at + n[0]]
                            .iter()
                            .all(|c| (c - side).abs() <= tolerance);
                    }
                }
                flat
            };
            (!flat).then_some((b, values))
        })
        .collect()
}

/// Nodes of the stored coefficient bricks farther than `spacing` from the surface where the
/// field's sign differs from the samples'. Elsewhere every coefficient a node reads is within
/// ≈ 1e-5 of the background of its side, so the field there has the samples' sign. Bricks are
/// counted through `span`, and those not begun by a stop request are not checked.
pub(crate) fn sparse_sign_changes(
    basis: Basis,
    coeffs: &SparseGrid,
    samples: &SparseGrid,
    spacing: f32,
    span: Option<Span>,
) -> usize {
    let Some((side, centre)) = taps(basis) else {
        return 0;
    };
    let dims = coeffs.dims();
    let stored: Vec<[usize; 3]> = coeffs.stored().map(|(b, _)| b).collect();
    let counter = span.map(|s| s.counter(stored.len()));
    stored
        .par_iter()
        .map(|&b| {
            if progress::stopped(counter.as_ref()) {
                return 0;
            }
            progress::tick(counter.as_ref());
            let (lo, n) = coeffs.brick_extent(b);
            // The brick and one node around it, mirrored at the grid's borders.
            let w_lo = lo.map(|c| c.saturating_sub(1));
            let wn = [0, 1, 2].map(|a| (lo[a] + n[a] + 1).min(dims[a]) - w_lo[a]);
            let mut window = [0.0f32; PADDED];
            coeffs.gather(w_lo, wn, &mut window);
            // Window index of node `lo + t − 1` along each axis.
            let mut index = [[0usize; BRICK_EDGE + 2]; 3];
            for (a, index) in index.iter_mut().enumerate() {
                for (t, at) in index[..n[a] + 2].iter_mut().enumerate() {
                    *at = mirror((lo[a] + t) as i64 - 1, dims[a]) - w_lo[a];
                }
            }
            let [ix, iy, iz] = index;
            let blur = |p: f32, h: f32, q: f32| side * (p + q) + centre * h;
            // One axis at a time: x over the padded y, z; then y; then z.
            let (e, f) = (BRICK_EDGE, BRICK_EDGE + 2);
            let mut xs = [0.0f32; PADDED];
            for tk in 0..n[2] + 2 {
                for tj in 0..n[1] + 2 {
                    let row = wn[0] * (iy[tj] + wn[1] * iz[tk]);
                    for i in 0..n[0] {
                        let r = |t: usize| window[row + ix[t]];
                        xs[i + e * (tj + f * tk)] = blur(r(i), r(i + 1), r(i + 2));
                    }
                }
            }
            let mut ys = [0.0f32; PADDED];
            for tk in 0..n[2] + 2 {
                for j in 0..n[1] {
                    for i in 0..n[0] {
                        let r = |t: usize| xs[i + e * (t + f * tk)];
                        ys[i + e * (j + e * tk)] = blur(r(j), r(j + 1), r(j + 2));
                    }
                }
            }
            let sampled = samples.brick_values(b);
            let mut count = 0;
            for k in 0..n[2] {
                for j in 0..n[1] {
                    for i in 0..n[0] {
                        let r = |t: usize| ys[i + e * (j + e * t)];
                        let v = blur(r(k), r(k + 1), r(k + 2));
                        let d = sampled[brick_offset([i, j, k])];
                        if d.abs() > spacing && (v < 0.0) != (d < 0.0) {
                            count += 1;
                        }
                    }
                }
            }
            count
        })
        .sum()
}

/// Values in a brick with one node of padding per side.
const PADDED: usize = (BRICK_EDGE + 2) * (BRICK_EDGE + 2) * (BRICK_EDGE + 2);

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use pgvol_core::Grid;

    use super::*;
    use crate::analytic::Sphere;

    use crate::prefilter::{CUBIC_POLE, QUADRATIC_POLE};

    /// A sphere's distance on an `n`³ grid over [−1, 1]³, banded as the encoder samples it.
    fn banded_sphere(n: usize, band: f32) -> (Grid, SparseGrid) {
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), n).unwrap();
        let ball = Sphere {
            centre: Vec3::new(0.03, -0.05, 0.07),
            radius: 0.6,
        };
        let samples = crate::analytic::banded_samples(&ball, &grid, band);
        (grid, samples)
    }

    /// Largest difference over the stored bricks of `a`, which `b` must store too.
    fn max_diff(a: &SparseGrid, b: &SparseGrid) -> f32 {
        a.stored()
            .map(|(at, x)| {
                let y = b.brick(at).expect("same bricks");
                let (_, n) = a.brick_extent(at);
                let mut worst = 0.0f32;
                for k in 0..n[2] {
                    for j in 0..n[1] {
                        for i in 0..n[0] {
                            let o = brick_offset([i, j, k]);
                            worst = worst.max((x[o] - y[o]).abs());
                        }
                    }
                }
                worst
            })
            .fold(0.0, f32::max)
    }

    /// What the halo alone costs in accuracy: against windows covering the whole grid (the
    /// global filter in f64, rounded once), the default halo moves coefficients by at most
    /// 8.4e-8 · clamp (one f32 ulp of values near the clamp) with both poles, with groups of 2
    /// (many interior window edges) as of 8, where 6 nodes would give 1.1e-4 (cubic) and 4.8e-6
    /// (quadratic).
    #[test]
    fn the_halo_truncation_is_below_float_rounding() {
        let (_, samples) = banded_sphere(100, 4.0);
        let clamp = samples.background().outside;
        for z in [CUBIC_POLE, QUADRATIC_POLE] {
            let whole = prefilter_sparse_with(&samples, z, 100, GROUP, 0.0, None);
            for group in [2, GROUP] {
                let local = prefilter_sparse_with(&samples, z, halo(z), group, 0.0, None);
                let short = prefilter_sparse_with(&samples, z, 6, group, 0.0, None);
                let err = max_diff(&local, &whole) / clamp;
                let short_err = max_diff(&short, &whole) / clamp;
                eprintln!(
                    "pole {z}, group {group}: halo {} {err:e}, halo 6 {short_err:e}",
                    halo(z)
                );
                assert!(err < 1.5e-7, "pole {z}, group {group}: {err:e}");
                assert!(short_err > 10.0 * err, "pole {z}, group {group}");
            }
        }
        assert_eq!((halo(CUBIC_POLE), halo(QUADRATIC_POLE)), (12, 9));
    }

    /// Every group size gives the same coefficients to float rounding.
    /// Neighbours left to the background move no coefficient by more than the drop tolerance,
    /// and some are left.
    #[test]
    fn dropped_neighbours_stay_within_the_tolerance() {
        let (_, samples) = banded_sphere(100, 4.0);
        let clamp = samples.background().outside;
        let kept = prefilter_sparse_with(&samples, CUBIC_POLE, 12, GROUP, 0.0, None);
        let dropped = prefilter_sparse_with(&samples, CUBIC_POLE, 12, GROUP, DROP_TOLERANCE, None);
        assert!(dropped.stored_count() < kept.stored_count());
        for (b, v) in kept.stored() {
            let (_, n) = kept.brick_extent(b);
            let w = dropped.brick_values(b);
            for k in 0..n[2] {
                for j in 0..n[1] {
                    for i in 0..n[0] {
                        let o = brick_offset([i, j, k]);
                        assert!((v[o] - w[o]).abs() <= DROP_TOLERANCE * clamp, "{b:?}");
                    }
                }
            }
        }
        eprintln!(
            "{} of {} bricks kept",
            dropped.stored_count(),
            kept.stored_count()
        );
    }

    /// Window nodes gathered and x-filtered per coefficient computed, for the bricks of the
    /// default encode's band (4 spacings) around a sphere.
    fn window_nodes_per_coefficient_of(n: usize, group: usize) -> f64 {
        let (_, samples) = banded_sphere(n, 4.0);
        let h = halo(CUBIC_POLE);
        let bricks = output_bricks(&samples, group);
        let group_of = |b: &[usize; 3]| b.map(|c| c / group);
        let (mut window, mut kept) = (0usize, 0usize);
        for g in bricks.chunk_by(|a, b| group_of(a) == group_of(b)) {
            let w = group_window(&samples, g, h);
            window += (0..3).map(|a| w.w_hi[a] - w.w_lo[a]).product::<usize>();
            kept += g
                .iter()
                .map(|&b| samples.brick_extent(b).1.iter().product::<usize>())
                .sum::<usize>();
        }
        window as f64 / kept as f64
    }

    /// The measurement behind `GROUP`: `cargo test --release -p pgvol-field --lib
    /// window_nodes_per_coefficient -- --nocapture` prints the table.
    #[test]
    fn window_nodes_per_coefficient() {
        for n in [128, 256] {
            let per = [2, 4, 8, 16].map(|g| window_nodes_per_coefficient_of(n, g));
            eprintln!(
                "{n}³: groups of 2³ {:.1}, 4³ {:.1}, 8³ {:.1}, 16³ {:.1} window nodes per coefficient",
                per[0], per[1], per[2], per[3]
            );
            // Larger groups share their halo among more bricks.
            assert!(per[2] < per[1] && per[1] < per[0], "{n}³: {per:?}");
            assert!(per[2] < 6.0, "{n}³: {per:?}");
        }
    }

    #[test]
    fn group_sizes_agree() {
        let (_, samples) = banded_sphere(45, 3.0);
        let clamp = samples.background().outside;
        let base = prefilter_sparse_with(&samples, CUBIC_POLE, halo(CUBIC_POLE), GROUP, 0.0, None);
        for group in [1, 2, 3, 4] {
            let other =
                prefilter_sparse_with(&samples, CUBIC_POLE, halo(CUBIC_POLE), group, 0.0, None);
            let diff = max_diff(&base, &other) / clamp;
            eprintln!("group {group}: {diff:e}");
            assert!(diff < 3e-7, "group {group}: {diff:e}");
        }
    }
}
