//! A contour plane's node lattice, and the exact 2D signed distance of the plane's loops at
//! its nodes.

use crate::contours::ContourPlane;

/// A plane's node lattice: `dims[0] × dims[1]` nodes at `origin + spacing · (i, j)`, u fastest.
#[derive(Clone, Copy, Debug)]
pub struct Lattice {
    pub origin: [f32; 2],
    pub spacing: f32,
    pub dims: [usize; 2],
}

/// The 2D signed distance of a plane's loops at the nodes of `lattice` (u fastest), exact
/// within `reach` of a loop and ±`reach` beyond; negative inside by the even-odd rule.
pub(crate) fn plane_distance(plane: &ContourPlane, lattice: &Lattice, reach: f32) -> Vec<f32> {
    let [nu, nv] = lattice.dims;
    let ([ou, ov], h) = (lattice.origin, lattice.spacing);
    let mut sq = vec![reach * reach; nu * nv];
    let to_index = |x: f32, o: f32, n: usize| ((x - o) / h).clamp(0.0, (n - 1) as f32);
    for lp in &plane.loops {
        for k in 0..lp.len() {
            let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
            let i0 = to_index(a[0].min(b[0]) - reach, ou, nu).floor() as usize;
            let i1 = to_index(a[0].max(b[0]) + reach, ou, nu).ceil() as usize;
            let j0 = to_index(a[1].min(b[1]) - reach, ov, nv).floor() as usize;
            let j1 = to_index(a[1].max(b[1]) + reach, ov, nv).ceil() as usize;
            let d = [b[0] - a[0], b[1] - a[1]];
            let len2 = (d[0] * d[0] + d[1] * d[1]).max(f32::MIN_POSITIVE);
            for j in j0..=j1 {
                let y = ov + h * j as f32;
                for i in i0..=i1 {
                    let x = ou + h * i as f32;
                    let t = (((x - a[0]) * d[0] + (y - a[1]) * d[1]) / len2).clamp(0.0, 1.0);
                    let (ex, ey) = (x - a[0] - t * d[0], y - a[1] - t * d[1]);
                    let s = &mut sq[i + nu * j];
                    *s = s.min(ex * ex + ey * ey);
                }
            }
        }
    }
    // Even-odd sides row by row, from the crossings of every loop edge with the row.
    let mut crossings = Vec::new();
    for j in 0..nv {
        let y = ov + h * j as f32;
        crossings.clear();
        for lp in &plane.loops {
            for k in 0..lp.len() {
                let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
                if (a[1] > y) != (b[1] > y) {
                    crossings.push(a[0] + (y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]));
                }
            }
        }
        crossings.sort_by(f32::total_cmp);
        let mut next = 0;
        for i in 0..nu {
            let x = ou + h * i as f32;
            while next < crossings.len() && crossings[next] < x {
                next += 1;
            }
            let s = &mut sq[i + nu * j];
            let d = s.sqrt().min(reach);
            *s = if next % 2 == 1 { -d } else { d };
        }
    }
    sq
}

#[cfg(test)]
mod tests {
    use super::*;
    use pgvol_core::Grid;

    #[test]
    fn a_disc_has_its_2d_distance_at_the_plane() {
        let circle: Vec<[f32; 2]> = (0..200)
            .map(|i| {
                let t = i as f32 / 200.0 * std::f32::consts::TAU;
                [t.cos(), t.sin()]
            })
            .collect();
        let grid = Grid::cube_res(glam::Vec3::splat(-2.0), glam::Vec3::splat(2.0), 41).unwrap();
        let plane = ContourPlane {
            height: 0.0,
            loops: vec![circle],
        };
        let lattice = Lattice {
            origin: [grid.origin.x, grid.origin.y],
            spacing: grid.spacing,
            dims: [grid.dims[0], grid.dims[1]],
        };
        let d = plane_distance(&plane, &lattice, 1.0);
        for (c, v) in d.iter().enumerate() {
            let n = grid.dims[0];
            let p = [
                grid.origin.x + grid.spacing * (c % n) as f32,
                grid.origin.y + grid.spacing * (c / n) as f32,
            ];
            let truth = ((p[0] * p[0] + p[1] * p[1]).sqrt() - 1.0).clamp(-1.0, 1.0);
            assert!((v - truth).abs() < 2e-3, "{p:?}: {v} vs {truth}");
        }
    }
}
