//! Stray pieces on a contouring grid: the connected regions of grid nodes whose side of the
//! field's zero set matches no region of the mesh's own side, and the bumps that remove them.
//!
//! Marching cubes puts a surface only across grid edges whose two nodes differ in sign, so two
//! 6-adjacent nodes of one sign are never separated by it: the pieces of the contoured surface
//! are fixed by the 6-connected regions of inside and of outside nodes. A field region is kept
//! when it is, for some region of the mesh's own node signs, the field region of that sign
//! overlapping it most; every other region is a stray piece (a blob outside, a pocket inside),
//! and turning its nodes over makes it part of the region around it. The grid is padded by a
//! layer of outside nodes, as the contouring is, so the outside touching the border is one.

use std::collections::HashMap;

use glam::{DVec3, Vec3};

use crate::field::{Perturbation, PerturbationError, PerturbationField};
use crate::quadric::Quadric;

/// What [`clear_strays`] did on one grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Strays {
    /// Stray pieces (node regions) found before the pass.
    pub pieces: usize,
    /// Their nodes, each given a bump.
    pub nodes: usize,
    /// Of those, nodes on the mesh's side of the surface that a stray piece held all the
    /// same (parts thinner than the grid): their bump crosses the surface and dents it.
    pub against_mesh: usize,
    /// Passes that found stray pieces (each resamples the field's node signs and relabels).
    pub rounds: usize,
    /// Stray pieces left after the last pass (zero unless the pass limit was reached).
    pub pieces_left: usize,
}

/// Smallest radius of a node's bump, in grid spacings: a node on the surface itself still
/// gets a ball (of a radius that dents the surface by at most this much).
pub const STRAY_MIN_RADIUS: f64 = 0.05;

/// Smallest margin by which a turned node ends on its new side, in grid spacings, so that the
/// resampled value keeps its sign through the coefficient fit's rounding.
pub const STRAY_MIN_MARGIN: f64 = 0.05;

/// Radius of the bump turning a node that lies on the mesh's side (a part thinner than the
/// grid), in grid spacings: under one spacing, so it reaches no other node of the grid.
pub const STRAY_AGAINST_RADIUS: f64 = 0.5;

/// Labels the 6-connected regions of equal `inside` over `dims` (x fastest), padded by one
/// layer of outside nodes; returns the labels of the padded grid and the padded dims.
fn label(dims: [usize; 3], inside: &dyn Fn(usize) -> bool) -> (Vec<u32>, [usize; 3]) {
    let p = dims.map(|n| n + 2);
    let total = p[0] * p[1] * p[2];
    let padded_inside = |i: usize| {
        let (x, y, z) = (i % p[0], (i / p[0]) % p[1], i / (p[0] * p[1]));
        if x == 0 || y == 0 || z == 0 || x == p[0] - 1 || y == p[1] - 1 || z == p[2] - 1 {
            return false;
        }
        inside((x - 1) + dims[0] * ((y - 1) + dims[1] * (z - 1)))
    };
    let side: Vec<bool> = (0..total).map(padded_inside).collect();
    let mut labels = vec![u32::MAX; total];
    let mut next = 0u32;
    let mut stack = Vec::new();
    let steps = [1isize, -1, p[0] as isize, -(p[0] as isize)]
        .into_iter()
        .chain([(p[0] * p[1]) as isize, -((p[0] * p[1]) as isize)])
        .collect::<Vec<_>>();
    for start in 0..total {
        if labels[start] != u32::MAX {
            continue;
        }
        labels[start] = next;
        stack.push(start);
        while let Some(i) = stack.pop() {
            let (x, y, z) = (i % p[0], (i / p[0]) % p[1], i / (p[0] * p[1]));
            let open = [
                x + 1 < p[0],
                x > 0,
                y + 1 < p[1],
                y > 0,
                z + 1 < p[2],
                z > 0,
            ];
            for (k, &step) in steps.iter().enumerate() {
                if !open[k] {
                    continue;
                }
                let j = (i as isize + step) as usize;
                if labels[j] == u32::MAX && side[j] == side[i] {
                    labels[j] = next;
                    stack.push(j);
                }
            }
        }
        next += 1;
    }
    (labels, p)
}

/// The nodes (indices into `dims`, x fastest) of the stray regions of `field_inside` against
/// the mesh's `mesh_inside`, and how many regions they make.
pub fn stray_nodes(
    dims: [usize; 3],
    field_inside: &dyn Fn(usize) -> bool,
    mesh_inside: &dyn Fn(usize) -> bool,
) -> (Vec<usize>, usize) {
    let (field, p) = label(dims, field_inside);
    let (mesh, _) = label(dims, mesh_inside);
    let inner = |i: usize| {
        (i % dims[0] + 1)
            + p[0] * ((i / dims[0]) % dims[1] + 1)
            + p[0] * p[1] * (i / (dims[0] * dims[1]) + 1)
    };
    // Overlap of every mesh region with the field regions of its sign (the padding included:
    // it is outside in both).
    let mut overlap: HashMap<(u32, u32), usize> = HashMap::new();
    let same = |i: usize| {
        let (x, y, z) = (i % p[0], (i / p[0]) % p[1], i / (p[0] * p[1]));
        let border = x == 0 || y == 0 || z == 0 || x == p[0] - 1 || y == p[1] - 1 || z == p[2] - 1;
        border || {
            let n = (x - 1) + dims[0] * ((y - 1) + dims[1] * (z - 1));
            field_inside(n) == mesh_inside(n)
        }
    };
    for i in 0..field.len() {
        if same(i) {
            *overlap.entry((mesh[i], field[i])).or_default() += 1;
        }
    }
    let mut best: HashMap<u32, (usize, u32)> = HashMap::new();
    for (&(m, f), &count) in &overlap {
        let e = best.entry(m).or_insert((0, f));
        if count > e.0 || (count == e.0 && f < e.1) {
            *e = (count, f);
        }
    }
    let kept: std::collections::HashSet<u32> = best.values().map(|&(_, f)| f).collect();
    let mut regions = std::collections::HashSet::new();
    let nodes: Vec<usize> = (0..dims[0] * dims[1] * dims[2])
        .filter(|&n| {
            let l = field[inner(n)];
            let stray = !kept.contains(&l);
            if stray {
                regions.insert(l);
            }
            stray
        })
        .collect();
    (nodes, regions.len())
}

/// `field` with a bump turning over each of `nodes`: points with their signed distance to the
/// mesh `d` (negative inside), on a grid of spacing `h`. A node on the wrong side of the
/// field gets the clearing ball of radius `0.9 |d|` (at least [`STRAY_MIN_RADIUS`] spacings),
/// which holds no surface; one the field has on the mesh's side (a part thinner than the grid,
/// cut off) a ball of [`STRAY_AGAINST_RADIUS`] spacings. Either ends the node on its new side
/// by at least [`STRAY_MIN_MARGIN`] spacings.
pub fn clear_strays(
    field: &PerturbationField,
    nodes: &[(Vec3, f32)],
    h: f64,
    pieces: usize,
) -> Result<(PerturbationField, Strays), PerturbationError> {
    let mut terms = field.terms().to_vec();
    let mut against_mesh = 0;
    for &(p, d) in nodes {
        let p: DVec3 = p.as_dvec3();
        let d = d as f64;
        let v = field.value_f64(p);
        let wrong = (v > 0.0) != (d > 0.0);
        against_mesh += !wrong as usize;
        let rho = if wrong {
            (0.9 * d.abs()).max(STRAY_MIN_RADIUS * h)
        } else {
            STRAY_AGAINST_RADIUS * h
        };
        let margin = if wrong { d.abs() } else { 0.0 }.max(STRAY_MIN_MARGIN * h);
        let a = (v.abs() + margin).cbrt();
        terms.push(Perturbation {
            quadric: Quadric {
                centre: p,
                scale: rho,
                q: [-a, -a, -a, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, a],
            },
            // Toward the outside when the field holds the node inside.
            factor: if v <= 0.0 { 1.0 } else { -1.0 },
        });
    }
    let field = PerturbationField::new(*field.base(), terms)?;
    Ok((
        field,
        Strays {
            pieces,
            nodes: nodes.len(),
            against_mesh,
            rounds: 1,
            pieces_left: 0,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid_of(dims: [usize; 3], inside: &[[usize; 3]]) -> Vec<bool> {
        let mut v = vec![false; dims[0] * dims[1] * dims[2]];
        for n in inside {
            v[n[0] + dims[0] * (n[1] + dims[1] * n[2])] = true;
        }
        v
    }

    #[test]
    fn a_detached_node_and_a_pocket_are_stray_and_the_body_is_not() {
        let dims = [8, 8, 8];
        let mut body = Vec::new();
        for x in 1..5 {
            for y in 1..5 {
                for z in 1..5 {
                    body.push([x, y, z]);
                }
            }
        }
        let mesh = grid_of(dims, &body);
        // The field: the body with a pocket at (2,2,2), a dent at (1,1,1) (on the border of
        // the body, so not a pocket) and a blob at (6,6,6).
        let mut field = mesh.clone();
        let at = |n: [usize; 3]| n[0] + 8 * (n[1] + 8 * n[2]);
        field[at([2, 2, 2])] = false;
        field[at([1, 1, 1])] = false;
        field[at([6, 6, 6])] = true;
        let (nodes, pieces) = stray_nodes(dims, &|i| field[i], &|i| mesh[i]);
        assert_eq!(pieces, 2);
        let mut nodes = nodes;
        nodes.sort();
        assert_eq!(nodes, vec![at([2, 2, 2]), at([6, 6, 6])]);
        // The mesh against itself has none.
        assert!(stray_nodes(dims, &|i| mesh[i], &|i| mesh[i]).0.is_empty());
    }

    #[test]
    fn a_part_cut_off_by_the_field_is_stray_but_two_parts_of_the_mesh_are_not() {
        let dims = [10, 4, 4];
        let mesh = grid_of(dims, &[[1, 1, 1], [2, 1, 1], [6, 1, 1], [7, 1, 1]]);
        assert!(stray_nodes(dims, &|i| mesh[i], &|i| mesh[i]).0.is_empty());
        // The field cuts the first part in two: the smaller half is stray.
        let field = grid_of(
            dims,
            &[[1, 1, 1], [3, 1, 1], [4, 1, 1], [6, 1, 1], [7, 1, 1]],
        );
        let mesh = grid_of(
            dims,
            &[
                [1, 1, 1],
                [2, 1, 1],
                [3, 1, 1],
                [4, 1, 1],
                [6, 1, 1],
                [7, 1, 1],
            ],
        );
        let (nodes, pieces) = stray_nodes(dims, &|i| field[i], &|i| mesh[i]);
        assert_eq!((nodes, pieces), (vec![1 + 10 * (1 + 4)], 1));
    }

    #[test]
    fn a_turned_node_changes_side_and_the_surface_far_from_it_keeps_its_value() {
        let sphere = Quadric {
            centre: DVec3::ZERO,
            scale: 1.0,
            q: [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        };
        let field = PerturbationField::new(sphere, vec![]).unwrap();
        // A node just outside the unit sphere that the mesh says is inside (a wrong node), and
        // one inside the sphere that the mesh also says is inside (turned against the mesh).
        let wrong = (Vec3::new(1.02, 0.0, 0.0), -0.01f32);
        let against = (Vec3::new(0.0, 0.97, 0.0), -0.03f32);
        let h = 0.1;
        let (turned, report) = clear_strays(&field, &[wrong, against], h, 2).unwrap();
        assert_eq!(
            (report.nodes, report.against_mesh, report.pieces),
            (2, 1, 2)
        );
        assert!(turned.value(wrong.0) < 0.0);
        assert!(turned.value(against.0) > 0.0);
        for p in [-DVec3::X, DVec3::Z, -DVec3::Y] {
            assert_eq!(turned.value_f64(p), field.value_f64(p));
        }
    }
}
