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
use super::sparse_node_values::blurred_brick_into;
use crate::basis::Basis;
use crate::prefilter::prefilter_lanes;

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

/// The samples a layered prefilter reads: borrowed and kept whole, or owned and released a
/// layer at a time once no later group or check reads them.
pub(crate) enum SampleStore<'a> {
    Borrowed(&'a SparseGrid),
    Owned(SparseGrid),
}

impl SampleStore<'_> {
    pub(crate) fn grid(&self) -> &SparseGrid {
        match self {
            SampleStore::Borrowed(g) => g,
            SampleStore::Owned(g) => g,
        }
    }

    /// The samples as a grid of their own (a copy of borrowed ones).
    pub(crate) fn into_grid(self) -> SparseGrid {
        match self {
            SampleStore::Borrowed(g) => g.clone(),
            SampleStore::Owned(g) => g,
        }
    }

    /// Drops the owned bricks below brick layer `z`.
    fn release_below(&mut self, z: usize) {
        if let SampleStore::Owned(g) = self {
            g.retain(|b, _| b[2] >= z);
        }
    }
}

/// What the sign check of [`prefilter_and_check`] found, and the time it took.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Checked {
    /// Nodes of the coefficient bricks farther than a spacing from the surface where the
    /// field's sign differs from the samples' (see [`sign_changes_in`]).
    pub changes: usize,
    pub seconds: f64,
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
/// on the thread count. Unstored bricks keep the samples' sides ([`SparseGrid::sides_only`]).
///
/// The groups go a layer along z at a time. Once a layer is filtered its coefficients are
/// final, the bricks a brick below it are checked for sign changes ([`sign_changes_in`]; the
/// count is a sum, so the same in any order), and owned samples below the next layer's halo
/// are dropped: memory then holds the coefficients and a few brick layers of samples, not both
/// whole. Groups are counted through `span`; after a stop request the groups not yet begun are
/// left out, and the incomplete result is for the caller to discard.
pub(crate) fn prefilter_and_check(
    samples: SampleStore,
    basis: Basis,
    z: f64,
    spacing: f32,
    span: Option<Span>,
) -> (SparseGrid, Checked) {
    let check = Some((basis, spacing));
    prefilter_layers(samples, z, halo(z), GROUP, DROP_TOLERANCE, check, span)
}

/// A computed neighbour brick whose coefficients all lie within this fraction of the clamp of
/// its side's background is left to the background: as close as the halo's truncation and far
/// below the file's quantisation step (h/512 at a clamp of 4 h is 5·10⁻⁴ of the clamp).
const DROP_TOLERANCE: f32 = 1e-5;

/// Bricks per edge of the groups [`prefilter_and_check`] filters together; a group's coefficients
/// follow from the samples within its bricks' box plus the halo.
pub const SPARSE_GROUP: usize = GROUP;

/// The coefficient bricks [`prefilter_and_check`] computes for the groups whose y and z indices
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

/// The coefficients of [`prefilter_and_check`] alone, with a given halo, group edge and drop
/// tolerance.
#[cfg(test)]
fn prefilter_sparse_with(
    samples: &SparseGrid,
    z: f64,
    h: usize,
    group: usize,
    drop: f32,
    span: Option<Span>,
) -> SparseGrid {
    let samples = SampleStore::Borrowed(samples);
    prefilter_layers(samples, z, h, group, drop, None, span).0
}

/// The layered prefilter of [`prefilter_and_check`], with a given halo, group edge and drop
/// tolerance; the sign changes counted when `check` gives the basis and the grid spacing.
fn prefilter_layers(
    mut samples: SampleStore,
    z: f64,
    h: usize,
    group: usize,
    drop: f32,
    check: Option<(Basis, f32)>,
    span: Option<Span>,
) -> (SparseGrid, Checked) {
    let bricks = output_bricks(samples.grid(), group);
    let group_of = |b: &[usize; 3]| b.map(|c| c / group);
    let groups: Vec<&[[usize; 3]]> = bricks.chunk_by(|a, b| group_of(a) == group_of(b)).collect();
    let counter = span.map(|s| s.counter(groups.len()));
    let mut out = samples.grid().sides_only();
    // Sample brick layers below a group layer that its windows read.
    let reach = h.div_ceil(BRICK_EDGE).max(1);
    // Coefficient bricks filtered and not yet checked.
    let mut unchecked: Vec<[usize; 3]> = Vec::new();
    let mut checked = Checked::default();
    let mut first = 0;
    while first < groups.len() {
        let layer = groups[first][0][2] / group;
        let len = groups[first..]
            .iter()
            .take_while(|g| g[0][2] / group == layer)
            .count();
        let grid = samples.grid();
        let computed: Vec<Vec<([usize; 3], Box<BrickValues>)>> = groups[first..first + len]
            .par_iter()
            .map_init(Scratch::default, |scratch, g| {
                if progress::stopped(counter.as_ref()) {
                    return Vec::new();
                }
                let bricks = filter_group(grid, z, h, g, drop, scratch);
                progress::tick(counter.as_ref());
                bricks
            })
            .collect();
        for (b, values) in computed.into_iter().flatten() {
            if check.is_some() {
                unchecked.push(b);
            }
            out.insert(b, values);
        }
        first += len;
        // Every coefficient brick below the next layer's first brick layer is final.
        let done = groups
            .get(first)
            .map_or(usize::MAX, |g| g[0][2] / group * group);
        if let Some((basis, spacing)) = check {
            // A check reads the coefficients one node around its brick.
            let ready: Vec<[usize; 3]>;
            (ready, unchecked) = unchecked.into_iter().partition(|b| b[2] + 1 < done);
            let t = std::time::Instant::now();
            checked.changes += sign_changes_in(basis, &out, samples.grid(), spacing, &ready);
            checked.seconds += t.elapsed().as_secs_f64();
        }
        // Later windows start `reach` brick layers below `done`; later checks read their own
        // sample brick, at least a layer below it.
        samples.release_below(done.saturating_sub(reach));
    }
    (out, checked)
}

/// The stored bricks and their neighbours, sorted by group of `group`³ bricks (z, y, x) and
/// then by brick, once each. Marked in a bitmap of the brick grid (one bit per brick) and read
/// back in that order: a list of every stored brick's 27 neighbours, sorted and deduplicated,
/// gives the same bricks but holds 27 entries per stored brick (1.3 GB at 2048³).
fn output_bricks(samples: &SparseGrid, group: usize) -> Vec<[usize; 3]> {
    let counts = samples.brick_counts();
    let groups = counts.map(|c| c.div_ceil(group));
    let bit = |b: [usize; 3]| b[0] + counts[0] * (b[1] + counts[1] * b[2]);
    let group_of = |b: [usize; 3]| {
        let g = b.map(|c| c / group);
        g[0] + groups[0] * (g[1] + groups[1] * g[2])
    };
    let mut marked = vec![0u64; (counts.iter().product::<usize>()).div_ceil(64)];
    let mut group_marked = vec![false; groups.iter().product()];
    for (b, _) in samples.stored() {
        let range = |a: usize| b[a].saturating_sub(1)..=(b[a] + 1).min(counts[a] - 1);
        for k in range(2) {
            for j in range(1) {
                for i in range(0) {
                    let n = bit([i, j, k]);
                    marked[n / 64] |= 1 << (n % 64);
                    group_marked[group_of([i, j, k])] = true;
                }
            }
        }
    }
    let mut out = Vec::new();
    for gz in 0..groups[2] {
        for gy in 0..groups[1] {
            for gx in 0..groups[0] {
                if !group_marked[gx + groups[0] * (gy + groups[1] * gz)] {
                    continue;
                }
                let span = |g: usize, a: usize| g * group..((g + 1) * group).min(counts[a]);
                for k in span(gz, 2) {
                    for j in span(gy, 1) {
                        for i in span(gx, 0) {
                            let n = bit([i, j, k]);
                            if marked[n / 64] >> (n % 64) & 1 == 1 {
                                out.push([i, j, k]);
                            }
                        }
                    }
                }
            }
        }
    }
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
    pgvol_core::cpu::run(FilterGroup {
        samples,
        z,
        h,
        group,
        drop,
        s,
    })
}

/// [`filter_group`] as a kernel, for its transposes and copies (the filter is a kernel of its
/// own).
struct FilterGroup<'a> {
    samples: &'a SparseGrid,
    z: f64,
    h: usize,
    group: &'a [[usize; 3]],
    drop: f32,
    s: &'a mut Scratch,
}

impl pgvol_core::cpu::Kernel for FilterGroup<'_> {
    type Output = Vec<([usize; 3], Box<BrickValues>)>;
    #[inline(always)]
    fn run(self) -> Self::Output {
        let FilterGroup {
            samples,
            z,
            h,
            group,
            drop,
            s,
        } = self;
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
}

/// Nodes of the coefficient bricks `bricks` (stored in `coeffs`, with every brick beside them
/// final) farther than `spacing` from the surface where the field's sign differs from the
/// samples'. Elsewhere every coefficient a node reads is within ≈ 1e-5 of the background of its
/// side, so the field there has the samples' sign.
fn sign_changes_in(
    basis: Basis,
    coeffs: &SparseGrid,
    samples: &SparseGrid,
    spacing: f32,
    bricks: &[[usize; 3]],
) -> usize {
    let Some(taps) = taps(basis) else {
        return 0;
    };
    bricks
        .par_iter()
        .map(|&b| {
            let (_, n) = coeffs.brick_extent(b);
            let mut values = [0.0f32; BRICK_NODES];
            blurred_brick_into(coeffs, taps, b, &mut values);
            let sampled = samples.brick_values(b);
            let mut count = 0;
            for k in 0..n[2] {
                for j in 0..n[1] {
                    let at = brick_offset([0, j, k]);
                    let row = values[at..at + n[0]].iter().zip(&sampled[at..at + n[0]]);
                    for (&v, &d) in row {
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

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use pgvol_core::Grid;

    use super::*;
    use crate::analytic::Sphere;
    use crate::volume::CoefficientVolume;

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

    /// The layered filter gives the same coefficients and sign count whether it drops the
    /// samples behind it or not, and the count is the check of every brick at the end. The
    /// samples are a sphere's distances with noise, filtered without a halo, so signs do change
    /// (61 to 1,510 nodes here).
    #[test]
    fn layers_that_drop_their_samples_give_the_whole_grid_result() {
        let (grid, mut samples) = banded_sphere(72, 4.0);
        let h = grid.spacing;
        for (b, values) in samples.stored_mut() {
            for (i, v) in values.iter_mut().enumerate() {
                let t = (b[0] * 7 + b[1] * 13 + b[2] * 29 + i) as f32;
                *v += 3.0 * h * (t * 12.9898).sin();
            }
        }
        for group in [2, 3, 8] {
            let check = Some((Basis::Bspline3, h));
            let borrowed = SampleStore::Borrowed(&samples);
            let (want, counted) =
                prefilter_layers(borrowed, CUBIC_POLE, 0, group, 0.0, check, None);
            let all: Vec<[usize; 3]> = want.stored().map(|(b, _)| b).collect();
            let whole = sign_changes_in(Basis::Bspline3, &want, &samples, h, &all);
            assert!(whole > 0, "the noise changes no sign");
            if group == 2 {
                // The count by the dense check, from the field at every node of the grid.
                let volume = CoefficientVolume::from_sparse(grid, Basis::Bspline3, want.clone())
                    .expect("a volume of the grid");
                let dense = crate::fit::spurious_sign_changes(&volume, &samples.to_dense());
                assert_eq!(whole, dense);
            }
            assert_eq!(counted.changes, whole, "group {group}");
            let owned = SampleStore::Owned(samples.clone());
            let (got, dropping) = prefilter_layers(owned, CUBIC_POLE, 0, group, 0.0, check, None);
            assert_eq!(dropping.changes, whole, "group {group}");
            assert_eq!(got.stored_count(), want.stored_count());
            for ((a, x), (b, y)) in got.stored().zip(want.stored()) {
                assert_eq!(a, b);
                assert!(x
                    .iter()
                    .zip(y.iter())
                    .all(|(p, q)| p.to_bits() == q.to_bits()));
            }
        }
    }

    /// The bricks of [`output_bricks`] the plain way: every stored brick's neighbours listed,
    /// sorted by group and brick, deduplicated.
    fn output_bricks_by_sorting(samples: &SparseGrid, group: usize) -> Vec<[usize; 3]> {
        let counts = samples.brick_counts();
        let mut out = Vec::new();
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
        out.sort_unstable_by_key(|b| {
            let g = b.map(|c| c / group);
            (g[2], g[1], g[0], b[2], b[1], b[0])
        });
        out.dedup();
        out
    }

    #[test]
    fn output_bricks_are_the_sorted_neighbours_of_the_stored_ones() {
        // Brick counts that groups divide and do not, bands that fill the grid's corners and not.
        for (n, band) in [(40, 4.0), (57, 2.0), (100, 4.0), (64, 30.0)] {
            let (_, samples) = banded_sphere(n, band);
            assert!(samples.stored_count() > 0);
            for group in [1, 2, 3, 4, 8] {
                let want = output_bricks_by_sorting(&samples, group);
                assert_eq!(
                    output_bricks(&samples, group),
                    want,
                    "{n}, band {band}, {group}"
                );
            }
        }
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
