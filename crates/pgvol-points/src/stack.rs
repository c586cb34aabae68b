//! Contour stacks by distance interpolation: on every plane the exact 2D signed distance of its
//! loops at the grid's node columns, corrected so the plane's cubic spline passes through the
//! loops ([`plane_fit`](crate::plane_fit)), joined across the planes by a cubic B-spline along
//! the stacking axis fitted to the planes' values and the natural cubic spline (C2) through
//! them, clamped to the band and sampled brick by brick. At the planes the field is the plane's
//! values, so slicing the result there gives the input loops back; between them the cubic
//! follows a smoothly varying cross-section better than a linear blend. Matched regions of
//! neighbouring planes that barely overlap are also interpolated in a frame moving with them
//! ([`bridge`](crate::bridge)), so leaning parts stay joined.
//!
//! Tops and bottoms close half a layer beyond the outermost planes (at least a grid spacing):
//! three virtual planes continue the stack (at ½, 1 and 2 layers out) with the distance to the
//! outermost region extruded to the cap, zero over the region at the cap itself.

use pgvol_core::sparse::{brick_offset, Background, BRICK_EDGE, BRICK_NODES};
use pgvol_core::{Grid, SparseGrid};
use rayon::prelude::*;

use crate::bridge::{find_bridges, Bridge};
use crate::contours::ContourPlane;
use crate::plane_distance::{plane_distance, Lattice};
use crate::plane_fit::pass_through_loops;

/// The 2D distances are exact within this many layer distances of the loops (at least the
/// band) and clamped beyond: the cubic across the planes sees true distances wherever its
/// value can come near zero, so clamping does not bend it into spurious crossings.
pub const DISTANCE_LAYERS: f32 = 2.0;

/// Node samples on `grid` of the distance interpolation of `planes` (sorted by height) stacked
/// along `axis`, clamped to ±`band` (mesh units). Bricks whose nodes are all a band from the
/// surface are not stored; those inside are marked so.
pub fn stack_samples(planes: &[ContourPlane], axis: usize, grid: &Grid, band: f32) -> SparseGrid {
    let (ua, va) = ((axis + 1) % 3, (axis + 2) % 3);
    let (nu, nv) = (grid.dims[ua], grid.dims[va]);
    let gaps: Vec<f32> = planes
        .windows(2)
        .map(|w| w[1].height - w[0].height)
        .collect();
    let max_gap = gaps.iter().copied().fold(0.0f32, f32::max);
    let reach = (DISTANCE_LAYERS * max_gap)
        .max(band)
        .max(2.0 * grid.spacing);
    let lattice = Lattice {
        origin: [grid.origin[ua], grid.origin[va]],
        spacing: grid.spacing,
        dims: [nu, nv],
    };
    // Knot heights: the planes plus three virtual planes beyond either end.
    // The caps lie half a layer out, and at least a grid spacing: the cubic cannot turn from
    // the outermost plane's values to the cap's within less than a node.
    let end_gap = |g: Option<&f32>| g.copied().unwrap_or(0.0).max(2.0 * grid.spacing);
    let (g_lo, g_hi) = (end_gap(gaps.first()), end_gap(gaps.last()));
    let (h_lo, h_hi) = (planes[0].height, planes[planes.len() - 1].height);
    let (cap_lo, cap_hi) = (h_lo - 0.5 * g_lo, h_hi + 0.5 * g_hi);
    let fields: Vec<Vec<f32>> = planes
        .par_iter()
        .map(|p| {
            let mut values = plane_distance(p, &lattice, reach);
            // No plane is deeper than its distance to the nearer cap: a plane close to an end
            // would otherwise keep its full 2D depth next to the shallow end plane, and the
            // cubic through that jump over a short gap swings across zero between the planes.
            // Limited before the fit through the loops, which the limit would otherwise undo.
            let floor = -(p.height - cap_lo).min(cap_hi - p.height);
            values.iter_mut().for_each(|v| *v = v.max(floor));
            pass_through_loops(&mut values, p, &lattice);
            values
        })
        .collect();
    let mut knots: Vec<f32> = [2.0, 1.0, 0.5].iter().map(|s| h_lo - s * g_lo).collect();
    knots.extend(planes.iter().map(|p| p.height));
    knots.extend([0.5, 1.0, 2.0].iter().map(|s| h_hi + s * g_hi));
    let nodes = Nodes {
        origin: grid.origin[axis],
        spacing: grid.spacing,
        count: grid.dims[axis],
    };
    let bridges = find_bridges(planes, &lattice, reach);
    let columns: Vec<Column> = (0..nu * nv)
        .into_par_iter()
        .map(|c| {
            let end = |d: f32, g: f32, s: f32| {
                let out = d.max(0.0);
                if s == 0.0 {
                    out
                } else {
                    (out * out + (s * g) * (s * g)).sqrt()
                }
            };
            let (d_lo, d_hi) = (fields[0][c], fields[planes.len() - 1][c]);
            let mut values: Vec<f32> = [1.5, 0.5, 0.0]
                .iter()
                .map(|&s| end(d_lo, g_lo, s))
                .collect();
            values.extend(fields.iter().map(|f| f[c]));
            values.extend([0.0, 0.5, 1.5].iter().map(|&s| end(d_hi, g_hi, s)));
            let extra = bridged_knots(&bridges, c % nu, c / nu, &knots, &values, nodes);
            if extra.is_empty() {
                return Column::new(&knots, values, band, nodes);
            }
            let mut merged: Vec<(f32, f32)> = knots.iter().copied().zip(values).collect();
            merged.extend(extra);
            merged.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (knots, values): (Vec<f32>, Vec<f32>) = merged.into_iter().unzip();
            Column::new(&knots, values, band, nodes)
        })
        .collect();
    let mut samples = SparseGrid::new(grid.dims, Background::clamp(band));
    let bricks: Vec<[usize; 3]> = samples.all_bricks().collect();
    let column_of = |n: [usize; 3]| n[ua] + nu * n[va];
    let filled: Vec<([usize; 3], Fill)> = bricks
        .par_iter()
        .map(|&b| {
            let lo = b.map(|c| c * BRICK_EDGE);
            let in_grid = |n: [usize; 3]| n.iter().zip(&grid.dims).all(|(a, d)| a < d);
            // A brick whose columns all keep one side is background.
            let mut sides = [false; 2];
            let mut varies = false;
            for j in 0..BRICK_EDGE {
                for i in 0..BRICK_EDGE {
                    let mut n = lo;
                    n[ua] += i;
                    n[va] += j;
                    if !in_grid(n) {
                        continue;
                    }
                    match columns[column_of(n)].constant {
                        Some(v) => sides[usize::from(v < 0.0)] = true,
                        None => varies = true,
                    }
                }
            }
            if !(varies || sides[0] && sides[1]) {
                return (b, Fill::Side(sides[1]));
            }
            let mut brick = Box::new([band; BRICK_NODES]);
            let mut near = false;
            let mut inside = 0;
            for k in 0..BRICK_EDGE {
                for j in 0..BRICK_EDGE {
                    for i in 0..BRICK_EDGE {
                        let n = [lo[0] + i, lo[1] + j, lo[2] + k];
                        if !in_grid(n) {
                            continue;
                        }
                        let v = columns[column_of(n)].value(n[axis], band);
                        near |= v.abs() < band;
                        inside += usize::from(v < 0.0);
                        brick[brick_offset([i, j, k])] = v;
                    }
                }
            }
            if near || (inside > 0 && inside < BRICK_NODES) {
                (b, Fill::Stored(brick))
            } else {
                (b, Fill::Side(inside > 0))
            }
        })
        .collect();
    for (b, fill) in filled {
        match fill {
            Fill::Stored(values) => samples.insert(b, values),
            Fill::Side(true) => samples.set_inside(b, true),
            Fill::Side(false) => {}
        }
    }
    samples
}

/// A brick of samples: stored, or wholly on one side (true: inside) a band from the surface.
enum Fill {
    Stored(Box<[f32; BRICK_NODES]>),
    Side(bool),
}

/// Knots that the bridges between matched regions add to node column (i, j): at the node
/// heights between the pair's planes (none when they are a node apart or less: a knot between
/// nodes there would keep the column from taking the planes' values exactly), the smaller of the sheared
/// interpolation and the linear one between the planes. A reach beyond the pair both are
/// the clamped distance, as is the column's natural spline, so the columns a bridge covers
/// join the others without a step (unless another region lies that close).
fn bridged_knots(
    bridges: &[Bridge],
    i: usize,
    j: usize,
    knots: &[f32],
    values: &[f32],
    nodes: Nodes,
) -> Vec<(f32, f32)> {
    let mut extra = Vec::new();
    for b in bridges.iter().filter(|b| b.covers(i, j)) {
        // The planes sit after the three virtual planes below the stack.
        let (h0, h1) = (knots[b.lower + 3], knots[b.lower + 4]);
        let to_node = |h: f32| (h - nodes.origin) / nodes.spacing;
        let fractions = (to_node(h0).ceil() as i64..=to_node(h1).floor() as i64)
            .map(|k| (nodes.origin + nodes.spacing * k as f32 - h0) / (h1 - h0))
            .filter(|t| (0.15..=0.85).contains(t));
        for t in fractions {
            let h = h0 + t * (h1 - h0);
            // The pair by the sheared interpolation, anything else near it linearly: the
            // natural spline would round the pair's ends into stubs beyond the moved regions.
            let (v0, v1) = (values[b.lower + 3], values[b.lower + 4]);
            let sheared = b.value(i, j, t).min((1.0 - t) * v0 + t * v1);
            // Two pairs bridging the same gap here: the union of both.
            match extra.iter_mut().find(|(at, _)| *at == h) {
                Some((_, v)) => *v = f32::min(*v, sheared),
                None => extra.push((h, sheared)),
            }
        }
    }
    extra
}

/// The node heights along the stacking axis.
#[derive(Clone, Copy)]
struct Nodes {
    origin: f32,
    spacing: f32,
    count: usize,
}

/// Weight of the smoothness term (squared second differences of the coefficients) against the
/// squared misfit at the knots: small, so the knots are interpolated to a fraction of a percent
/// of a layer's change, and the smoothness only decides between them.
const SMOOTHNESS: f64 = 1e-4;

/// Weight of the natural spline's value at each node against a knot's.
const NODE_WEIGHT: f64 = 0.05;

/// One node column: the node samples along the axis whose cubic B-spline interpolant passes
/// through the knot values at the knot heights (exactly where the knots are at least a node
/// apart), so that the fitted volume has the planes' 2D distances at the planes' heights.
struct Column {
    /// The value everywhere when every knot is clamped to one side.
    constant: Option<f32>,
    /// First node of `samples`; nodes outside hold +band (beyond the caps).
    first: usize,
    samples: Vec<f32>,
}

impl Column {
    fn new(knots: &[f32], values: Vec<f32>, band: f32, nodes: Nodes) -> Self {
        if values.iter().all(|&v| v >= band) || values.iter().all(|&v| v <= -band) {
            return Self {
                constant: Some(values[0].clamp(-band, band)),
                first: 0,
                samples: Vec::new(),
            };
        }
        let to_node = |h: f32| (h - nodes.origin) / nodes.spacing;
        let last = nodes.count as isize - 1;
        let lo = (to_node(knots[0]).floor() as isize - 1).clamp(0, last) as usize;
        let hi = (to_node(knots[knots.len() - 1]).ceil() as isize + 1).clamp(0, last) as usize;
        // Data: the knots, and the natural cubic spline through them at every node between
        // (weight NODE_WEIGHT), which decides the shape where the knots leave it open and keeps
        // the fit from ringing where the planes are closer than the nodes.
        let slopes = akima_slopes(knots, &values);
        let mut data: Vec<(f64, f64, f64)> = knots
            .iter()
            .zip(&values)
            .map(|(&h, &v)| (f64::from(to_node(h)), f64::from(v), 1.0))
            .collect();
        for k in lo..=hi {
            let h = nodes.origin + nodes.spacing * k as f32;
            if let Some(v) = interpolant_value(knots, &values, &slopes, h) {
                data.push((k as f64, f64::from(v), NODE_WEIGHT));
            }
        }
        let coefficients = fit_coefficients(&data, lo, hi);
        let samples = (lo..=hi)
            .map(|k| {
                let c = |i: usize| coefficients[i.clamp(lo, hi) - lo];
                let v = (c(k.saturating_sub(1)) + 4.0 * c(k) + c(k + 1)) / 6.0;
                (v as f32).clamp(-band, band)
            })
            .collect();
        Self {
            constant: None,
            first: lo,
            samples,
        }
    }

    /// The sample at node `k` along the axis.
    fn value(&self, k: usize, band: f32) -> f32 {
        if let Some(v) = self.constant {
            return v;
        }
        match k.checked_sub(self.first).and_then(|i| self.samples.get(i)) {
            Some(&v) => v,
            None => band,
        }
    }
}

/// Cubic B-spline coefficients at nodes `lo..=hi` minimising the weighted squared misfit to
/// `data` (position in node units, value, weight) plus [`SMOOTHNESS`] times the squared second
/// differences: a symmetric banded system (half-bandwidth 3) solved by banded Cholesky in f64.
fn fit_coefficients(data: &[(f64, f64, f64)], lo: usize, hi: usize) -> Vec<f64> {
    const W: usize = 4;
    let m = hi - lo + 1;
    // band[i][d] holds A[i][i + d].
    let mut band = vec![[0.0f64; W]; m];
    let mut rhs = vec![0.0f64; m];
    for i in 0..m.saturating_sub(2) {
        let row = [(i, 1.0), (i + 1, -2.0), (i + 2, 1.0)];
        for &(a, wa) in &row {
            for &(b, wb) in &row {
                if b >= a {
                    band[a][b - a] += SMOOTHNESS * wa * wb;
                }
            }
        }
    }
    for &(at, v, weight) in data {
        let x = at - lo as f64;
        let base = x.floor();
        let t = x - base;
        // Uniform cubic B-spline weights of nodes base-1 ..= base+2.
        let w = [
            (1.0 - t).powi(3) / 6.0,
            (3.0 * t.powi(3) - 6.0 * t * t + 4.0) / 6.0,
            (-3.0 * t.powi(3) + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
            t.powi(3) / 6.0,
        ];
        let entries: Vec<(usize, f64)> = (0..4)
            .filter_map(|d| {
                let i = base as isize - 1 + d as isize;
                (0..m as isize).contains(&i).then_some((i as usize, w[d]))
            })
            .collect();
        for &(a, wa) in &entries {
            rhs[a] += weight * wa * v;
            for &(b, wb) in &entries {
                if b >= a {
                    band[a][b - a] += weight * wa * wb;
                }
            }
        }
    }
    // Banded Cholesky: A = L Lᵀ, L stored as band[i][d] = L[i + d][i].
    for j in 0..m {
        let mut diag = band[j][0];
        for k in j.saturating_sub(W - 1)..j {
            diag -= band[k][j - k] * band[k][j - k];
        }
        let diag = diag.max(1e-300).sqrt();
        band[j][0] = diag;
        for i in j + 1..(j + W).min(m) {
            let mut s = band[j][i - j];
            for k in i.saturating_sub(W - 1)..j {
                s -= band[k][i - k] * band[k][j - k];
            }
            band[j][i - j] = s / diag;
        }
    }
    for i in 0..m {
        let mut s = rhs[i];
        for k in i.saturating_sub(W - 1)..i {
            s -= band[k][i - k] * rhs[k];
        }
        rhs[i] = s / band[i][0];
    }
    for i in (0..m).rev() {
        let mut s = rhs[i];
        for k in i + 1..(i + W).min(m) {
            s -= band[i][k - i] * rhs[k];
        }
        rhs[i] = s / band[i][0];
    }
    rhs
}

/// The piecewise cubic through (`x`, `y`) with slopes `slope` at `h`; `None` outside the knots.
fn interpolant_value(x: &[f32], y: &[f32], slope: &[f32], h: f32) -> Option<f32> {
    let n = x.len();
    if !(h > x[0] && h < x[n - 1]) {
        return None;
    }
    let k = x.partition_point(|&v| v <= h).clamp(1, n - 1) - 1;
    let w = x[k + 1] - x[k];
    let t = (h - x[k]) / w;
    // Cubic Hermite basis on the interval.
    let (t2, t3) = (t * t, t * t * t);
    Some(
        (2.0 * t3 - 3.0 * t2 + 1.0) * y[k]
            + (t3 - 2.0 * t2 + t) * w * slope[k]
            + (-2.0 * t3 + 3.0 * t2) * y[k + 1]
            + (t3 - t2) * w * slope[k + 1],
    )
}

/// Slopes at the knots (`x`, `y`) of the modified Akima interpolant: each a weighted mean of
/// the secants on either side, weighted towards the side whose neighbourhood bends less. It
/// follows smooth data like a cubic spline, but stays flat between equal values and does not
/// ring where the knots are unevenly spaced (planes 0.01 apart next to gaps of 0.5, a steep
/// cap next to a flat side), which a natural spline turns into crossings between the planes.
fn akima_slopes(x: &[f32], y: &[f32]) -> Vec<f32> {
    let n = x.len();
    if n < 2 {
        return vec![0.0; n];
    }
    // Secants, continued linearly by two on either side.
    let mut m = Vec::with_capacity(n + 3);
    m.extend([0.0, 0.0]);
    m.extend((0..n - 1).map(|i| (y[i + 1] - y[i]) / (x[i + 1] - x[i])));
    if n == 2 {
        return vec![m[2]; 2];
    }
    m[1] = 2.0 * m[2] - m[3];
    m[0] = 2.0 * m[1] - m[2];
    let last = m.len() - 1;
    m.push(2.0 * m[last] - m[last - 1]);
    m.push(2.0 * m[last + 1] - m[last]);
    // Knot i lies between secants m[i + 1] (left) and m[i + 2] (right).
    (0..n)
        .map(|i| {
            let (a, b, c, d) = (m[i], m[i + 1], m[i + 2], m[i + 3]);
            let w_left = (d - c).abs() + 0.5 * (d + c).abs();
            let w_right = (b - a).abs() + 0.5 * (b + a).abs();
            let sum = w_left + w_right;
            if sum > 0.0 {
                (w_left * b + w_right * c) / sum
            } else {
                0.5 * (b + c)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_reproduce_a_line_and_interpolate_their_knots() {
        let nodes = Nodes {
            origin: -1.0,
            spacing: 0.1,
            count: 80,
        };
        let to_node = |h: f32| (h - nodes.origin) / nodes.spacing;
        let knots = [0.0f32, 1.0, 2.5, 3.0, 5.0];
        let line: Vec<f32> = knots.iter().map(|v| 2.0 * v - 1.0).collect();
        let col = Column::new(&knots, line, 100.0, nodes);
        for k in col.first + 1..col.first + col.samples.len() - 1 {
            let h = nodes.origin + nodes.spacing * k as f32;
            assert!((col.value(k, 100.0) - (2.0 * h - 1.0)).abs() < 1e-3, "{k}");
        }
        let y = [1.0f32, -2.0, 0.5, 3.0, -1.0];
        let (lo, hi) = (9, 61);
        let data: Vec<(f64, f64, f64)> = knots
            .iter()
            .zip(&y)
            .map(|(&h, &v)| (f64::from(to_node(h)), f64::from(v), 1.0))
            .collect();
        let c = fit_coefficients(&data, lo, hi);
        for (h, v) in knots.iter().zip(y) {
            let x = f64::from(to_node(*h)) - lo as f64;
            let (base, t) = (x.floor() as usize, x - x.floor());
            let c = |i: usize| c.get(i).copied().unwrap_or(0.0);
            let value = c(base - 1) * (1.0 - t).powi(3) / 6.0
                + c(base) * (3.0 * t.powi(3) - 6.0 * t * t + 4.0) / 6.0
                + c(base + 1) * (-3.0 * t.powi(3) + 3.0 * t * t + 3.0 * t + 1.0) / 6.0
                + c(base + 2) * t.powi(3) / 6.0;
            assert!((value - f64::from(v)).abs() < 1e-3, "{h}: {value} vs {v}");
        }
    }

    fn disc(c: [f32; 2], r: f32) -> Vec<[f32; 2]> {
        (0..96)
            .map(|i| {
                let t = i as f32 / 96.0 * std::f32::consts::TAU;
                [c[0] + r * t.cos(), c[1] + r * t.sin()]
            })
            .collect()
    }

    /// The fitted field of `planes` stacked along z on a 64³ grid around `lo`..`hi`, as
    /// `reconstruct_stack` fits it.
    fn fit(planes: &[ContourPlane], lo: f32, hi: f32) -> pgvol_field::CoefficientVolume {
        let grid = Grid::cube_res(glam::Vec3::splat(lo), glam::Vec3::splat(hi), 64).unwrap();
        let samples = stack_samples(planes, 2, &grid, 4.0 * grid.spacing);
        let basis = pgvol_field::Basis::Bspline3;
        pgvol_field::fit::interp_sparse(grid, basis, &samples, pgvol_core::progress::QUIET)
            .unwrap()
            .0
    }

    fn at(v: &pgvol_field::CoefficientVolume, x: f32, y: f32, z: f32) -> f32 {
        v.value(glam::Vec3::new(x, y, z))
    }

    #[test]
    fn branches_join_and_tops_close_half_a_layer_out() {
        // Two discs below, one covering both above.
        let planes = [
            ContourPlane {
                height: 0.0,
                loops: vec![disc([-1.0, 0.0], 0.6), disc([1.0, 0.0], 0.6)],
            },
            ContourPlane {
                height: 1.0,
                loops: vec![disc([0.0, 0.0], 1.8)],
            },
        ];
        let v = fit(&planes, -2.5, 2.5);
        assert!(at(&v, -1.0, 0.0, 0.0) < 0.0 && at(&v, 1.0, 0.0, 0.0) < 0.0);
        assert!(at(&v, 0.0, 0.0, 0.0) > 0.0, "the gap between the branches");
        assert!(at(&v, 0.0, 0.0, 1.0) < 0.0 && at(&v, 0.0, 0.0, 0.5) < 0.0);
        // Caps half a layer beyond the outermost planes.
        assert!(at(&v, 0.0, 0.0, 1.35) < 0.0 && at(&v, 0.0, 0.0, 1.65) > 0.0);
        assert!(at(&v, -1.0, 0.0, -0.35) < 0.0 && at(&v, -1.0, 0.0, -0.65) > 0.0);
    }

    #[test]
    fn holes_stay_open_through_the_stack() {
        let ring = vec![disc([0.0, 0.0], 1.5), disc([0.0, 0.0], 0.7)];
        let planes: Vec<ContourPlane> = (0..3)
            .map(|k| ContourPlane {
                height: k as f32 * 0.5,
                loops: ring.clone(),
            })
            .collect();
        let v = fit(&planes, -2.0, 2.0);
        for z in [0.0, 0.25, 0.5, 0.75, 1.0] {
            assert!(at(&v, 0.0, 0.0, z) > 0.0, "hole at {z}");
            assert!(at(&v, 1.1, 0.0, z) < 0.0, "ring at {z}");
            assert!(at(&v, 1.9, 0.0, z) > 0.0, "outside at {z}");
        }
    }

    #[test]
    fn a_leaning_part_whose_layers_do_not_overlap_stays_one_piece() {
        // Discs of radius 0.5 whose centres move 1.5 per layer: neighbouring layers share no
        // point, so distance interpolation alone closes each halfway to the next.
        let planes: Vec<ContourPlane> = (0..3)
            .map(|k| ContourPlane {
                height: k as f32,
                loops: vec![disc([1.5 * k as f32, 0.0], 0.5)],
            })
            .collect();
        let v = fit(&planes, -1.5, 3.5);
        // Between the layers the cross-section is the disc moved along: inside within 0.3 of
        // its centre line, outside beyond 0.7.
        for step in 0..=16 {
            let z = step as f32 / 8.0;
            let c = 1.5 * z;
            assert!(at(&v, c, 0.0, z) < 0.0, "centre at {z}");
            assert!(
                at(&v, c, 0.3, z) < 0.0 && at(&v, c, -0.3, z) < 0.0,
                "inside at {z}"
            );
            assert!(
                at(&v, c, 0.7, z) > 0.0 && at(&v, c, -0.7, z) > 0.0,
                "outside at {z}"
            );
        }
        // Overlapping neighbours are left to the distance interpolation: a straight cylinder
        // keeps its radius between the layers.
        let straight: Vec<ContourPlane> = (0..3)
            .map(|k| ContourPlane {
                height: k as f32,
                loops: vec![disc([0.0, 0.0], 0.5)],
            })
            .collect();
        assert!(find_bridges(&straight, &lattice(-1.5, 3.5), 2.0).is_empty());
    }

    fn lattice(lo: f32, hi: f32) -> Lattice {
        let grid = Grid::cube_res(glam::Vec3::splat(lo), glam::Vec3::splat(hi), 64).unwrap();
        Lattice {
            origin: [grid.origin.x, grid.origin.y],
            spacing: grid.spacing,
            dims: [grid.dims[0], grid.dims[1]],
        }
    }
}
