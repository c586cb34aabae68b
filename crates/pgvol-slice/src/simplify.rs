//! Simplification of a layer's closed loops with a bounded error and without changing the
//! layer's topology.

use crate::polygon::signed_area;

type P = [f32; 2];

/// Simplifies closed loops (last point not repeated) to within `tolerance`.
///
/// Each loop is reduced by Douglas–Peucker from two anchors, its first vertex and the vertex
/// farthest from it. The layer is then checked as a whole and repaired until valid: a simplified
/// segment that touches or crosses any other (of any loop) is split at its span's farthest
/// vertex and the two halves simplified again; a loop whose orientation changed, or whose
/// containment of another loop's first vertex changed, is restored with its partner.
///
/// Guarantees, for input loops that are simple and pairwise disjoint (as the slicer makes):
/// * every output loop is a subsequence of its input loop, starting at the same vertex, with at
///   least 3 points (all of them if the input has fewer than 4);
/// * every input vertex lies within `tolerance` of its output loop (every dropped vertex is
///   within `tolerance` of the output segment spanning it);
/// * the output loops are simple and pairwise disjoint, each keeps its orientation, and nesting
///   (which loop lies inside which) is unchanged.
///
/// The repair is iterative; in the worst case it restores the input. The nesting check is
/// quadratic in the number of loops of the layer (pruned by bounding boxes).
pub fn simplify_loops(loops: &[Vec<P>], tolerance: f32) -> Vec<Vec<P>> {
    // Zero, negative or NaN: nothing to simplify.
    if tolerance.is_nan() || tolerance <= 0.0 {
        return loops.to_vec();
    }
    let tol2 = tolerance as f64 * tolerance as f64;
    let mut kept: Vec<Vec<usize>> = loops.iter().map(|l| simplify_one(l, tol2)).collect();
    let areas: Vec<f64> = loops.iter().map(|l| signed_area(l)).collect();
    let boxes: Vec<[f32; 4]> = loops.iter().map(|l| bbox(l)).collect();
    loop {
        repair_crossings(loops, &mut kept, tol2);
        let mut restore = vec![false; loops.len()];
        for (l, pts) in loops.iter().enumerate() {
            let simple: Vec<P> = kept[l].iter().map(|&i| pts[i]).collect();
            let a = signed_area(&simple);
            if a == 0.0 || (a < 0.0) != (areas[l] < 0.0) {
                restore[l] = true;
            }
        }
        for (a, la) in loops.iter().enumerate() {
            let Some(&p) = la.first() else { continue };
            for (b, lb) in loops.iter().enumerate() {
                let bx = boxes[b];
                if a == b
                    || kept[b].len() == lb.len()
                    || p[0] < bx[0]
                    || p[0] > bx[2]
                    || p[1] < bx[1]
                    || p[1] > bx[3]
                {
                    continue;
                }
                let before = contains(lb.iter().copied(), p);
                let after = contains(kept[b].iter().map(|&i| lb[i]), p);
                if before != after {
                    restore[a] = true;
                    restore[b] = true;
                }
            }
        }
        let mut changed = false;
        for (l, r) in restore.into_iter().enumerate() {
            if r && kept[l].len() != loops[l].len() {
                kept[l] = (0..loops[l].len()).collect();
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    kept.iter()
        .zip(loops)
        .map(|(k, pts)| k.iter().map(|&i| pts[i]).collect())
        .collect()
}

fn bbox(pts: &[P]) -> [f32; 4] {
    let mut b = [
        f32::INFINITY,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NEG_INFINITY,
    ];
    for p in pts {
        b = [
            b[0].min(p[0]),
            b[1].min(p[1]),
            b[2].max(p[0]),
            b[3].max(p[1]),
        ];
    }
    b
}

/// Even-odd point-in-polygon test.
fn contains(poly: impl Iterator<Item = P> + Clone, p: P) -> bool {
    let mut inside = false;
    let mut prev = poly.clone().last();
    for q in poly {
        let r = prev.unwrap_or(q);
        if (q[1] > p[1]) != (r[1] > p[1]) {
            let x = q[0] as f64
                + (p[1] as f64 - q[1] as f64) * (r[0] as f64 - q[0] as f64)
                    / (r[1] as f64 - q[1] as f64);
            if (p[0] as f64) < x {
                inside = !inside;
            }
        }
        prev = Some(q);
    }
    inside
}

/// Squared distance from `p` to the segment `a`–`b`.
fn seg_dist2(p: P, a: P, b: P) -> f64 {
    let (px, py) = (p[0] as f64, p[1] as f64);
    let (ax, ay) = (a[0] as f64, a[1] as f64);
    let (dx, dy) = (b[0] as f64 - ax, b[1] as f64 - ay);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((px - ax) * dx + (py - ay) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (ex, ey) = (px - ax - t * dx, py - ay - t * dy);
    ex * ex + ey * ey
}

/// The vertex strictly between `a` and `b` (indices modulo the loop length, `a < b`) farthest
/// from the chord, with its squared distance.
fn farthest(pts: &[P], a: usize, b: usize) -> Option<(usize, f64)> {
    let n = pts.len();
    let (pa, pb) = (pts[a % n], pts[b % n]);
    (a + 1..b).map(|i| (i, seg_dist2(pts[i % n], pa, pb))).fold(
        None,
        |best: Option<(usize, f64)>, c| match best {
            Some(b) if b.1 >= c.1 => Some(b),
            _ => Some(c),
        },
    )
}

/// Douglas–Peucker on the span `a..b`: pushes the kept interior indices (unsorted).
fn dp(pts: &[P], a: usize, b: usize, tol2: f64, out: &mut Vec<usize>) {
    let mut stack = vec![(a, b)];
    while let Some((a, b)) = stack.pop() {
        if let Some((m, d2)) = farthest(pts, a, b) {
            if d2 > tol2 {
                out.push(m);
                stack.push((a, m));
                stack.push((m, b));
            }
        }
    }
}

/// Kept indices (sorted, starting at 0) of one loop.
fn simplify_one(pts: &[P], tol2: f64) -> Vec<usize> {
    let n = pts.len();
    if n <= 3 {
        return (0..n).collect();
    }
    let p0 = pts[0];
    let far = (1..n)
        .map(|i| {
            let (dx, dy) = (pts[i][0] - p0[0], pts[i][1] - p0[1]);
            (i, dx as f64 * dx as f64 + dy as f64 * dy as f64)
        })
        .fold((1, -1.0), |b, c| if c.1 > b.1 { c } else { b })
        .0;
    let mut kept = vec![0, far];
    dp(pts, 0, far, tol2, &mut kept);
    dp(pts, far, n, tol2, &mut kept);
    if kept.len() < 3 {
        // Both halves lie within the tolerance of the chord: keep the farthest vertex of
        // either so the loop keeps an area.
        let a = farthest(pts, 0, far);
        let b = farthest(pts, far, n);
        let m = match (a, b) {
            (Some(a), Some(b)) => {
                if a.1 >= b.1 {
                    a.0
                } else {
                    b.0
                }
            }
            (Some(a), None) => a.0,
            (None, Some(b)) => b.0,
            (None, None) => unreachable!("n > 3 leaves a vertex besides 0 and far"),
        };
        kept.push(m % n);
    }
    kept.sort_unstable();
    kept
}

/// Orientation of `c` relative to `a`→`b`: the sign of the cross product. Exact for f32 inputs
/// up to the final subtraction.
fn orient(a: P, b: P, c: P) -> f64 {
    let (abx, aby) = (b[0] as f64 - a[0] as f64, b[1] as f64 - a[1] as f64);
    let (acx, acy) = (c[0] as f64 - a[0] as f64, c[1] as f64 - a[1] as f64);
    (abx * acy - aby * acx).signum() * (abx * acy - aby * acx != 0.0) as i32 as f64
}

/// Whether closed segments `p`–`q` and `r`–`s` share any point.
fn segments_touch(p: P, q: P, r: P, s: P) -> bool {
    let (o1, o2) = (orient(p, q, r), orient(p, q, s));
    let (o3, o4) = (orient(r, s, p), orient(r, s, q));
    if o1 * o2 > 0.0 || o3 * o4 > 0.0 {
        return false;
    }
    if o1 == 0.0 && o2 == 0.0 {
        // Collinear: overlapping projections.
        let overlap =
            |k: usize| p[k].min(q[k]) <= r[k].max(s[k]) && r[k].min(s[k]) <= p[k].max(q[k]);
        return overlap(0) && overlap(1);
    }
    true
}

/// Splits simplified segments that touch others until none does.
fn repair_crossings(loops: &[Vec<P>], kept: &mut [Vec<usize>], tol2: f64) {
    loop {
        let bad = touching_segments(loops, kept);
        if bad.is_empty() {
            return;
        }
        let mut progress = false;
        let mut extra: Vec<Vec<usize>> = vec![Vec::new(); loops.len()];
        for &(l, k) in &bad {
            let (pts, kl) = (&loops[l], &kept[l]);
            let a = kl[k];
            let b = if k + 1 < kl.len() {
                kl[k + 1]
            } else {
                pts.len()
            };
            if let Some((m, _)) = farthest(pts, a, b) {
                extra[l].push(m);
                dp(pts, a, m, tol2, &mut extra[l]);
                dp(pts, m, b, tol2, &mut extra[l]);
                progress = true;
            }
        }
        for (kl, e) in kept.iter_mut().zip(extra) {
            if !e.is_empty() {
                kl.extend(e);
                kl.sort_unstable();
                kl.dedup();
            }
        }
        if !progress {
            return;
        }
    }
}

/// Simplified segments `(loop, index)` that touch a segment other than their two neighbours,
/// or fold back onto a neighbour; found through a uniform grid of buckets.
fn touching_segments(loops: &[Vec<P>], kept: &[Vec<usize>]) -> Vec<(usize, usize)> {
    struct Seg {
        l: usize,
        k: usize,
        m: usize,
        p: P,
        q: P,
    }
    let mut segs = Vec::new();
    for (l, (pts, kl)) in loops.iter().zip(kept).enumerate() {
        let m = kl.len();
        for k in 0..m {
            segs.push(Seg {
                l,
                k,
                m,
                p: pts[kl[k]],
                q: pts[kl[(k + 1) % m]],
            });
        }
    }
    if segs.is_empty() {
        return Vec::new();
    }
    let mut bad = vec![false; segs.len()];
    // Fold-backs between neighbours: the next segment turns back along this one.
    for (i, s) in segs.iter().enumerate() {
        if s.m >= 3 {
            let next = &segs[i + 1 - if s.k + 1 == s.m { s.m } else { 0 }];
            let (a, b, c) = (s.p, s.q, next.q);
            let back = (a[0] as f64 - b[0] as f64) * (c[0] as f64 - b[0] as f64)
                + (a[1] as f64 - b[1] as f64) * (c[1] as f64 - b[1] as f64);
            if orient(a, b, c) == 0.0 && back > 0.0 {
                bad[i] = true;
            }
        }
    }
    let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    let mut total = 0.0f64;
    for s in &segs {
        for k in 0..2 {
            lo[k] = lo[k].min(s.p[k]).min(s.q[k]);
            hi[k] = hi[k].max(s.p[k]).max(s.q[k]);
        }
        total += ((s.q[0] - s.p[0]) as f64).hypot((s.q[1] - s.p[1]) as f64);
    }
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(f32::MIN_POSITIVE) as f64;
    // Buckets about one mean segment wide, but at most 256 per side so a long segment's
    // bounding box covers a bounded number of them.
    let cell = (total / segs.len() as f64).max(extent / 256.0);
    let key = |x: f32, k: usize| ((x as f64 - lo[k] as f64) / cell) as u64;
    let mut entries: Vec<(u64, u32)> = Vec::new();
    for (i, s) in segs.iter().enumerate() {
        let (x0, x1) = (key(s.p[0].min(s.q[0]), 0), key(s.p[0].max(s.q[0]), 0));
        let (y0, y1) = (key(s.p[1].min(s.q[1]), 1), key(s.p[1].max(s.q[1]), 1));
        for y in y0..=y1 {
            for x in x0..=x1 {
                entries.push(((y << 32) | x, i as u32));
            }
        }
    }
    entries.sort_unstable();
    for run in entries.chunk_by(|a, b| a.0 == b.0) {
        for (ai, &(_, a)) in run.iter().enumerate() {
            for &(_, b) in &run[ai + 1..] {
                let (s, t) = (&segs[a as usize], &segs[b as usize]);
                if s.l == t.l && (t.k == (s.k + 1) % s.m || s.k == (t.k + 1) % s.m) {
                    continue;
                }
                if segments_touch(s.p, s.q, t.p, t.q) {
                    bad[a as usize] = true;
                    bad[b as usize] = true;
                }
            }
        }
    }
    segs.iter()
        .zip(bad)
        .filter(|(_, b)| *b)
        .map(|(s, _)| (s.l, s.k))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn touching_and_separate_segments() {
        assert!(segments_touch([0., 0.], [2., 2.], [0., 2.], [2., 0.]));
        assert!(segments_touch([0., 0.], [2., 0.], [1., 0.], [3., 0.]));
        assert!(segments_touch([0., 0.], [2., 0.], [2., 0.], [3., 1.]));
        assert!(!segments_touch([0., 0.], [2., 0.], [2.5, 0.], [3., 0.]));
        assert!(!segments_touch([0., 0.], [2., 0.], [0., 1.], [2., 1.]));
    }

    #[test]
    fn a_square_with_collinear_points_loses_exactly_those() {
        let pts: Vec<P> = vec![
            [0., 0.],
            [1., 0.],
            [2., 0.],
            [2., 1.],
            [2., 2.],
            [1., 2.],
            [0., 2.],
            [0., 1.],
        ];
        let out = simplify_loops(&[pts], 1e-3);
        assert_eq!(out[0], vec![[0., 0.], [2., 0.], [2., 2.], [0., 2.]]);
    }

    #[test]
    fn a_dent_holding_an_island_is_kept() {
        // A square whose top edge has a shallow dent, and a tiny island inside the dent:
        // dropping the dent would swallow the island.
        let outer: Vec<P> = vec![
            [0., 0.],
            [10., 0.],
            [10., 10.],
            [6., 10.],
            [5., 9.],
            [4., 10.],
            [0., 10.],
        ];
        let island: Vec<P> = vec![[4.9, 9.5], [5.0, 9.4], [5.1, 9.5], [5.0, 9.6]];
        let out = simplify_loops(&[outer.clone(), island], 2.0);
        assert!(out[0].contains(&[5., 9.]), "{:?}", out[0]);
        assert_eq!(out[1].len(), 4);
        // Without the hole the dent goes.
        let alone = simplify_loops(&[outer], 2.0);
        assert!(!alone[0].contains(&[5., 9.]));
    }

    #[test]
    fn a_chord_crossing_another_loop_is_split() {
        // The same dented square, with an island standing in the dent and reaching above the
        // top edge: the straight top edge would cut through it.
        let outer: Vec<P> = vec![
            [0., 0.],
            [10., 0.],
            [10., 10.],
            [6., 10.],
            [5., 9.],
            [4., 10.],
            [0., 10.],
        ];
        let island: Vec<P> = vec![[4.9, 9.5], [5.1, 9.5], [5.1, 10.5], [4.9, 10.5]];
        let out = simplify_loops(&[outer, island], 2.0);
        assert!(out[0].contains(&[5., 9.]), "{:?}", out[0]);
        assert!(touching_segments(
            &out,
            &out.iter()
                .map(|l| (0..l.len()).collect())
                .collect::<Vec<_>>()
        )
        .is_empty());
    }
}
