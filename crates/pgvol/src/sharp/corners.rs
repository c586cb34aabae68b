//! Slicing a file with sharp-feature vertices: where a crease crosses a layer's plane, the
//! smooth field's contour is rounded over a cell or two, and the stored vertex of the crease's
//! cell there is the corner. The contour's points around it give way to it.

use glam::Vec3;
use pgvol_core::Grid;
use pgvol_format::sharp::SharpCells;
use pgvol_slice::{Axis, Layer};

use super::cells::cell_at;

/// A stored vertex is a corner of a layer's contour when it lies off the contour by more than
/// this many spacings: the vertices of cells on a face lie on it within the fit's error.
const CORNER_OFF: f32 = 0.05;

/// ... and by less than this many: farther off, it is not this contour's corner.
const CORNER_REACH: f32 = 1.5;

/// The contour's points within this many spacings of a corner give way to it: the smooth
/// field rounds a crease over about two cells.
const CORNER_RUN: f32 = 2.0;

/// ... when the contour turns by more than this (degrees) from before those points to after
/// them: a straight stretch near a stored vertex is a face, such as a side under a horizontal
/// crease whose rounding shrinks the layers near it.
const CORNER_TURN: f32 = 30.0;

/// Puts the corners that the stored vertices `cells` of a file on `grid` mark into `layers`,
/// sliced along `axis` from that file's field. A layer at height `h` takes the vertices of the
/// cells whose span along the axis holds `h`, projected onto its plane (exact for creases
/// across the plane at a right angle, such as a prism's edges), farthest from the contour first.
pub(crate) fn sharpen_layers(layers: &mut [Layer], grid: &Grid, cells: &SharpCells, axis: Axis) {
    let [a, ua, va] = axis.indices();
    let spacing = grid.spacing;
    let along = grid.dims[a].saturating_sub(1);
    let projected = |i: usize| {
        let cell = cell_at(grid, cells.keys[i]).map(|c| c as f32);
        let vertex = grid.origin + spacing * (Vec3::from(cell) + Vec3::from(cells.position(i)));
        [vertex[ua], vertex[va]]
    };
    // A crease crossing the layers has stored vertices in the cells above or below along the
    // axis that project within half a spacing; a face lying in a layer's cell has none.
    let cells_per = [0, 1, 2].map(|d| grid.dims[d].saturating_sub(1) as u64);
    let step = [1, cells_per[0], cells_per[0] * cells_per[1]][a];
    let mut by_cell: Vec<Vec<[f32; 2]>> = vec![Vec::new(); along];
    for (i, &key) in cells.keys.iter().enumerate() {
        let cell = cell_at(grid, key);
        let p = projected(i);
        let across = [cell[a].checked_sub(1).map(|_| key - step), Some(key + step)]
            .into_iter()
            .flatten()
            .filter_map(|k| cells.keys.binary_search(&k).ok())
            .any(|j| {
                let q = projected(j);
                (p[0] - q[0]).hypot(p[1] - q[1]) < 0.5 * spacing
            });
        if let (true, Some(list)) = (across, by_cell.get_mut(cell[a] as usize)) {
            list.push(p);
        }
    }
    for layer in layers.iter_mut() {
        let t = (layer.height - grid.origin[a]) / spacing;
        if !(t >= 0.0 && t < along as f32) {
            continue;
        }
        let mut corners: Vec<(f32, [f32; 2])> = by_cell[t as usize]
            .iter()
            .map(|&c| (off_loops(&layer.loops, c), c))
            .filter(|&(off, _)| off > CORNER_OFF * spacing && off < CORNER_REACH * spacing)
            .collect();
        corners.sort_by(|x, y| y.0.total_cmp(&x.0));
        let mut placed: Vec<[f32; 2]> = Vec::new();
        for (_, c) in corners {
            // The vertices of the cells beside a corner lie on its faces: the corner wins.
            let beside = |p: &[f32; 2]| (p[0] - c[0]).hypot(p[1] - c[1]) < CORNER_RUN * spacing;
            if placed.iter().any(beside) {
                continue;
            }
            let Some((l, off)) = nearest_loop(&layer.loops, c) else {
                continue;
            };
            if off > CORNER_OFF * spacing
                && off < CORNER_REACH * spacing
                && place_corner(&mut layer.loops[l].points, c, CORNER_RUN * spacing)
            {
                placed.push(c);
            }
        }
    }
}

/// The distance from `c` to the nearest loop.
fn off_loops(loops: &[pgvol_slice::Loop], c: [f32; 2]) -> f32 {
    nearest_loop(loops, c).map_or(f32::INFINITY, |(_, d)| d)
}

/// The loop nearest `c` and its distance.
fn nearest_loop(loops: &[pgvol_slice::Loop], c: [f32; 2]) -> Option<(usize, f32)> {
    loops
        .iter()
        .enumerate()
        .map(|(i, l)| (i, nearest_segment(&l.points, c).1))
        .min_by(|x, y| x.1.total_cmp(&y.1))
}

/// The segment of closed loop `points` nearest `c` (from point `i` to the next) and its
/// distance.
fn nearest_segment(points: &[[f32; 2]], c: [f32; 2]) -> (usize, f32) {
    let n = points.len();
    (0..n)
        .map(|i| (i, segment_distance(c, points[i], points[(i + 1) % n])))
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .unwrap_or((0, f32::INFINITY))
}

fn segment_distance(c: [f32; 2], p: [f32; 2], q: [f32; 2]) -> f32 {
    let d = [q[0] - p[0], q[1] - p[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    let t = if len2 > 0.0 {
        (((c[0] - p[0]) * d[0] + (c[1] - p[1]) * d[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let e = [p[0] + t * d[0] - c[0], p[1] + t * d[1] - c[1]];
    (e[0] * e[0] + e[1] * e[1]).sqrt()
}

/// Replaces the points of closed loop `points` within `run` of `c`, around its segment nearest
/// `c`, by `c`, when the loop turns by more than [`CORNER_TURN`] across them; returns whether it
/// did. A loop all within reach is left as it is.
fn place_corner(points: &mut Vec<[f32; 2]>, c: [f32; 2], run: f32) -> bool {
    let n = points.len();
    if n < 3 {
        return false;
    }
    let near = |p: [f32; 2]| (p[0] - c[0]).hypot(p[1] - c[1]) < run;
    let (m, _) = nearest_segment(points, c);
    // The run is points first..first + count (cyclic): back from m and on from m + 1.
    let mut first = m + n;
    let mut count = 0;
    while count < n && near(points[first % n]) {
        first -= 1;
        count += 1;
    }
    first += 1;
    let mut next = m + 1;
    while count < n && near(points[next % n]) {
        next += 1;
        count += 1;
    }
    if count + 2 >= n {
        return false;
    }
    let at = |i: usize| points[i % n];
    let (before, after) = (
        [
            at(first)[0] - at(first + n - 1)[0],
            at(first)[1] - at(first + n - 1)[1],
        ],
        [
            at(next)[0] - at(next + n - 1)[0],
            at(next)[1] - at(next + n - 1)[1],
        ],
    );
    let turn = (before[0] * after[1] - before[1] * after[0])
        .atan2(before[0] * after[0] + before[1] * after[1])
        .abs()
        .to_degrees();
    if turn <= CORNER_TURN {
        return false;
    }
    // Rotated so the run starts the loop, the run gives way to the corner.
    points.rotate_left(first % n);
    points.splice(0..count, [c]);
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rounded_corner_gives_way_to_the_corner() {
        // A unit square whose corner at (1, 1) is cut by a short arc.
        let mut points = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 0.8],
            [0.95, 0.95],
            [0.8, 1.0],
            [0.0, 1.0],
        ];
        assert!(place_corner(&mut points, [1.0, 1.0], 0.3));
        assert_eq!(points.len(), 4);
        assert!(points.contains(&[1.0, 1.0]));
        for p in [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]] {
            assert!(points.contains(&p), "{points:?}");
        }
        // The loop keeps its orientation: counter-clockwise area 1.
        let area: f32 = (0..4)
            .map(|i| {
                let (p, q) = (points[i], points[(i + 1) % 4]);
                p[0] * q[1] - q[0] * p[1]
            })
            .sum::<f32>()
            / 2.0;
        assert!((area - 1.0).abs() < 1e-6, "{area}");
        // A straight side near a vertex off it is a face: left as it is.
        let mut side = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 0.4],
            [1.0, 0.5],
            [1.0, 0.6],
            [1.0, 1.0],
            [0.0, 1.0],
        ];
        let before = side.clone();
        assert!(!place_corner(&mut side, [1.05, 0.5], 0.2));
        assert_eq!(side, before);
    }
}
