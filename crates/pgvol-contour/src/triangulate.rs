//! Triangulation of a closed contour loop without forbidden diagonals.

use glam::Vec3;

/// Triangulates the polygon `points` (in loop order) into `points.len() - 2` triangles that keep
/// the loop's winding, using only diagonals `allowed(i, j)` accepts (`i < j`), and minimising the
/// total diagonal length so the triangles stay well shaped. Returns `None` when every
/// triangulation needs a forbidden diagonal. Ties go to the lowest split index, so the result is
/// deterministic.
pub(crate) fn triangulate_loop(
    points: &[Vec3],
    allowed: impl Fn(usize, usize) -> bool,
) -> Option<Vec<[usize; 3]>> {
    let n = points.len();
    assert!(n >= 3, "a loop needs at least three points");
    // Cost of using chord (i, j) as a triangle side: free for loop sides, length for diagonals.
    let chord = |i: usize, j: usize| -> f32 {
        if j == i + 1 || (i == 0 && j == n - 1) {
            0.0
        } else if allowed(i, j) {
            points[i].distance(points[j])
        } else {
            f32::INFINITY
        }
    };
    // best[i][j]: cheapest triangulation of the sub-polygon i..=j closed by chord (i, j).
    let mut best = vec![vec![0.0f32; n]; n];
    let mut split = vec![vec![0usize; n]; n];
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            best[i][j] = f32::INFINITY;
            for k in i + 1..j {
                let cost = best[i][k] + best[k][j] + chord(i, k) + chord(k, j);
                if cost < best[i][j] {
                    best[i][j] = cost;
                    split[i][j] = k;
                }
            }
        }
    }
    if !best[0][n - 1].is_finite() {
        return None;
    }
    let mut tris = Vec::with_capacity(n - 2);
    let mut stack = vec![(0, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j - i < 2 {
            continue;
        }
        let k = split[i][j];
        tris.push([i, k, j]);
        stack.push((i, k));
        stack.push((k, j));
    }
    tris.sort_unstable();
    Some(tris)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hexagon() -> Vec<Vec3> {
        (0..6)
            .map(|i| {
                let a = i as f32 * std::f32::consts::TAU / 6.0;
                Vec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect()
    }

    #[test]
    fn keeps_the_winding_and_covers_the_area() {
        let p = hexagon();
        let tris = triangulate_loop(&p, |_, _| true).unwrap();
        assert_eq!(tris.len(), 4);
        let area: f32 = tris
            .iter()
            .map(|t| {
                let n = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
                assert!(n.z > 0.0, "flipped triangle {t:?}");
                n.z / 2.0
            })
            .sum();
        assert!((area - 3.0 * 3f32.sqrt() / 2.0).abs() < 1e-5);
    }

    #[test]
    fn avoids_forbidden_diagonals() {
        let p = hexagon();
        let tris = triangulate_loop(&p, |i, j| !(i == 0 || j == 3)).unwrap();
        for t in &tris {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])] {
                let side = b == a + 1 || (a == 0 && b == 5);
                assert!(side || !(a == 0 || b == 3), "used {a}-{b}");
            }
        }
    }

    #[test]
    fn reports_impossible_loops() {
        let quad = [Vec3::ZERO, Vec3::X, Vec3::ONE, Vec3::Y];
        assert!(triangulate_loop(&quad, |_, _| false).is_none());
    }
}
