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

/// The straight sides on either side of a corner: the loop's points from the end of the run
/// that gives way to it to the first one this many spacings beyond the run.
const SIDE_LENGTH: f32 = 3.0;

/// A side is straight when every one of its points lies within this many spacings of its line.
const SIDE_STRAIGHT: f32 = 0.1;

/// Stored vertices within this many spacings of a side's line lie on its face.
const ON_SIDE: f32 = 0.25;

/// ... farther than this many spacings from the stored vertex: nearer ones are in cells whose
/// planes meet outside them, kept in the cell off either face, as the stored vertex is.
const CORNER_CLEAR: f32 = 1.0;

/// The sides' lines meeting within this many spacings of the stored vertex give the corner.
const CORNER_SNAP: f32 = 0.5;

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
                && place_corner(&mut layer.loops[l].points, c, &by_cell[t as usize], spacing)
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

/// Replaces the points of closed loop `points` within [`CORNER_RUN`] spacings of `c`, around its
/// segment nearest `c`, by the corner, when the loop turns by more than [`CORNER_TURN`] across
/// them; returns whether it did. A loop all within reach is left as it is. The corner is where
/// the loop's sides next to the run meet, moved onto the `stored` vertices of the layer that lie
/// on them (see [`sides_meet`]), or `c` itself.
fn place_corner(
    points: &mut Vec<[f32; 2]>,
    c: [f32; 2],
    stored: &[[f32; 2]],
    spacing: f32,
) -> bool {
    let run = CORNER_RUN * spacing;
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
    let corner = sides_meet(points, (first, next), c, stored, spacing).unwrap_or(c);
    // Rotated so the run starts the loop, the run gives way to the corner.
    points.rotate_left(first % n);
    points.splice(0..count, [corner]);
    true
}

/// The corner near the stored vertex `c` where the two sides of closed loop `points` meet that
/// end the run from index `first` to `next` (cyclic, `next` excluded).
///
/// `c` is dual contouring's vertex of its cell, kept in the cell: where the crease passes
/// through a cell that the decoded field does not cross (its rounding cuts inside), `c` is the
/// nearest crossed cell's vertex, on that cell's face, a fraction of a spacing from the corner.
/// The loop's sides away from the rounding give each face's direction (each side runs from the
/// run's end to the first point [`SIDE_LENGTH`] spacings beyond it; a simplified loop's side is
/// one long segment), and the stored vertices of the layer within [`ON_SIDE`] of a side and
/// [`CORNER_CLEAR`] or more from `c`, which lie on the face exactly, its offset. `None` when a side is not straight within
/// [`SIDE_STRAIGHT`] or the lines meet farther than [`CORNER_SNAP`] from `c`.
fn sides_meet(
    points: &[[f32; 2]],
    (first, next): (usize, usize),
    c: [f32; 2],
    stored: &[[f32; 2]],
    spacing: f32,
) -> Option<[f32; 2]> {
    let n = points.len();
    let distance = |p: [f32; 2]| (p[0] - c[0]).hypot(p[1] - c[1]);
    let reach = (CORNER_RUN + SIDE_LENGTH) * spacing;
    let side = |start: usize, backwards: bool| -> Vec<[f32; 2]> {
        let mut out = Vec::new();
        for k in 0..n / 2 {
            let p = points[if backwards { start + n - k } else { start + k } % n];
            out.push(p);
            if distance(p) >= reach {
                break;
            }
        }
        out
    };
    let on_faces = |line: Line| -> Line {
        let (m, d) = line;
        let normal = [-d[1], d[0]];
        let offsets: Vec<f32> = stored
            .iter()
            .filter(|&&q| (CORNER_CLEAR * spacing..reach).contains(&distance(q)))
            .map(|q| (q[0] - m[0]) * normal[0] + (q[1] - m[1]) * normal[1])
            .filter(|off| off.abs() < ON_SIDE * spacing)
            .collect();
        if offsets.is_empty() {
            return line;
        }
        let shift = offsets.iter().sum::<f32>() / offsets.len() as f32;
        ([m[0] + shift * normal[0], m[1] + shift * normal[1]], d)
    };
    let straight = SIDE_STRAIGHT * spacing;
    let before = on_faces(line_through(&side(first, true), straight)?);
    let after = on_faces(line_through(&side(next + n - 1, false), straight)?);
    let x = meet(before, after)?;
    (distance(x) < CORNER_SNAP * spacing).then_some(x)
}

/// A line as a point and a unit direction.
type Line = ([f32; 2], [f32; 2]);

/// The least-squares line through `points`, when there are two or more and all lie within
/// `tolerance` of it.
fn line_through(points: &[[f32; 2]], tolerance: f32) -> Option<Line> {
    if points.len() < 2 {
        return None;
    }
    let count = points.len() as f32;
    let m = points.iter().fold([0.0, 0.0], |s, p| {
        [s[0] + p[0] / count, s[1] + p[1] / count]
    });
    let (mut xx, mut xy, mut yy) = (0.0f32, 0.0f32, 0.0f32);
    for p in points {
        let (x, y) = (p[0] - m[0], p[1] - m[1]);
        xx += x * x;
        xy += x * y;
        yy += y * y;
    }
    // The principal direction of the points' spread.
    let angle = 0.5 * (2.0 * xy).atan2(xx - yy);
    let d = [angle.cos(), angle.sin()];
    let off = |p: &[f32; 2]| ((p[0] - m[0]) * d[1] - (p[1] - m[1]) * d[0]).abs();
    points.iter().all(|p| off(p) <= tolerance).then_some((m, d))
}

/// Where two lines meet; `None` when they are within a degree of parallel.
fn meet((p, d): Line, (q, e): Line) -> Option<[f32; 2]> {
    let cross = d[0] * e[1] - d[1] * e[0];
    if cross.abs() < 1f32.to_radians().sin() {
        return None;
    }
    let t = ((q[0] - p[0]) * e[1] - (q[1] - p[1]) * e[0]) / cross;
    Some([p[0] + t * d[0], p[1] + t * d[1]])
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
        assert!(place_corner(&mut points, [1.0, 1.0], &[], 0.15));
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
        assert!(!place_corner(&mut side, [1.05, 0.5], &[], 0.1));
        assert_eq!(side, before);
    }
}
