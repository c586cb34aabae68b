//! The check every operation makes of its result before returning it: a field with no inside
//! (nothing to contour) or no outside (no surface within its box) is refused with the
//! operation's own reason, instead of being written as a file that only a later decode refuses.

use pgvol_core::Mesh;
use pgvol_field::CoefficientVolume;
use rayon::prelude::*;

use crate::error::{Error, ErrorKind, Result};

/// The sides of the surface a field's grid nodes lie on: negative values inside, positive
/// outside, as contouring reads them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Sides {
    pub inside: bool,
    pub outside: bool,
}

impl Sides {
    const BOTH: Sides = Sides {
        inside: true,
        outside: true,
    };

    fn of(v: f32) -> Sides {
        Sides {
            inside: v < 0.0,
            outside: v > 0.0,
        }
    }

    fn join(self, other: Sides) -> Sides {
        Sides {
            inside: self.inside || other.inside,
            outside: self.outside || other.outside,
        }
    }

    /// The sides of node values.
    pub fn of_values(values: &[f32]) -> Sides {
        Sides {
            inside: values.par_iter().any(|&v| v < 0.0),
            outside: values.par_iter().any(|&v| v > 0.0),
        }
    }

    /// The sides of `volume`'s field at the nodes of its grid, stopping once both are found.
    pub fn of_volume(volume: &CoefficientVolume) -> Sides {
        let coeffs = &volume.coeffs;
        // The nodes of an absent brick away from its faces see only its background. Absent
        // bricks on both sides (a closed part's inside and outside) settle it from the grid's
        // tables, before any pass over the coefficients.
        let (inside, outside) = coeffs.absent_sides();
        let background = coeffs.background();
        let mut sides = [(inside, true), (outside, false)]
            .into_iter()
            .filter(|&(absent, _)| absent)
            .map(|(_, side)| Sides::of(background.value(side)))
            .fold(Sides::default(), Sides::join);
        if sides == Sides::BOTH {
            return sides;
        }
        // Every basis function is non-negative, so coefficients of one sign give a field of
        // that sign: the common empty results need no evaluation.
        let [lo, hi] = coeffs.value_range();
        if lo >= 0.0 || hi <= 0.0 {
            return Sides {
                inside: lo < 0.0,
                outside: hi > 0.0,
            };
        }
        let stored: Vec<[usize; 3]> = coeffs.stored().map(|(b, _)| b).collect();
        let found = stored
            .par_iter()
            .map(|&b| Ok(brick_sides(volume, b)))
            .try_reduce(Sides::default, |a, b| match a.join(b) {
                Sides::BOTH => Err(()),
                s => Ok(s),
            });
        sides = match found {
            Ok(s) => sides.join(s),
            Err(()) => Sides::BOTH,
        };
        sides
    }
}

/// The sides of the field at the nodes of coefficient brick `b`.
fn brick_sides(volume: &CoefficientVolume, b: [usize; 3]) -> Sides {
    let (lo, n) = volume.coeffs.brick_extent(b);
    let mut sides = Sides::default();
    for k in lo[2]..lo[2] + n[2] {
        for j in lo[1]..lo[1] + n[1] {
            for i in lo[0]..lo[0] + n[0] {
                sides = sides.join(Sides::of(volume.value(volume.grid.point(i, j, k))));
                if sides == Sides::BOTH {
                    return sides;
                }
            }
        }
    }
    sides
}

/// What an operation says of an empty result: the result, and for each way of being empty
/// why it happened and what would work, in the operation's own terms.
pub(crate) struct IfEmpty<'a> {
    /// The result as the subject of a sentence ("the intersection").
    pub result: &'a str,
    /// Why no node is inside, and what would give an inside.
    pub no_inside: &'a str,
    /// Why every node is inside, and what would give a surface.
    pub no_outside: &'a str,
}

/// Refuses a result whose nodes lie on one side only, with `why`'s reason.
pub(crate) fn require_surface(sides: Sides, why: &IfEmpty<'_>) -> Result<()> {
    let message = match (sides.inside, sides.outside) {
        (true, true) => return Ok(()),
        (false, _) => format!(
            "{} is empty (no point of its grid is inside): {}",
            why.result, why.no_inside
        ),
        (true, false) => format!(
            "{} has no surface (every point of its grid is inside): {}",
            why.result, why.no_outside
        ),
    };
    Err(Error::new(ErrorKind::EmptyResult, message))
}

/// Vertices this close to one plane, relative to the mesh's extent, make it flat: f32
/// positions round a tilted plane by about 1e-7 of the extent.
const FLAT: f32 = 1e-6;

/// Whether every vertex of `mesh` lies in one plane (any orientation), so it encloses no volume
/// at any resolution. Cheap enough to ask before any distance is sampled: a mesh with depth
/// answers at its first vertex off the plane.
pub(crate) fn is_flat(mesh: &Mesh) -> bool {
    let Some((lo, hi)) = mesh.bounds() else {
        return false;
    };
    let extent = (hi - lo).max_element();
    let p = &mesh.positions;
    // The normal of the largest triangle among the first ones is the plane's, if there is one.
    let normal = mesh
        .triangles
        .iter()
        .take(64)
        .map(|t| {
            let [a, b, c] = t.map(|i| p[i as usize]);
            (b - a).cross(c - a)
        })
        .max_by(|x, y| x.length_squared().total_cmp(&y.length_squared()))
        .and_then(|n| n.try_normalize());
    let Some(n) = normal else {
        return false;
    };
    let origin = p[mesh.triangles[0][0] as usize];
    mesh.triangles
        .iter()
        .flatten()
        .all(|&i| (p[i as usize] - origin).dot(n).abs() <= FLAT * extent)
}

/// Why a flat mesh's field is empty.
pub(crate) const FLAT_MESH: &str = "the mesh is flat (all its vertices lie in one plane), so it \
     encloses no volume and a finer grid would not help; give it a thickness";

/// Why the field of `mesh` on a grid of `spacing` has no inside, and what would give one: a
/// mesh without thickness encloses nothing at any resolution; a thin closed one needs a finer
/// grid.
pub(crate) fn mesh_without_inside(mesh: &Mesh, spacing: f32) -> String {
    let stats = mesh.stats();
    let extent = mesh.bounds().map_or(Default::default(), |(lo, hi)| hi - lo);
    if extent.min_element() <= FLAT * extent.max_element() || is_flat(mesh) {
        FLAT_MESH.into()
    } else if !stats.watertight {
        format!(
            "the mesh is an open surface ({} boundary edges) with no thickness, so it encloses \
             no volume and a finer grid would not help; close it, or give it a thickness",
            stats.boundary_edges
        )
    } else {
        format!(
            "the mesh's solid parts are thinner than the grid spacing {spacing}; a grid finer \
             than their thickness would resolve them"
        )
    }
}

/// Refuses `result`, a field of `mesh` on a grid of `spacing` whose nodes lie on `sides`, when
/// it has no inside or no outside, saying why in the mesh's terms.
pub(crate) fn require_mesh_surface(
    sides: Sides,
    result: &str,
    mesh: &Mesh,
    spacing: f32,
) -> Result<()> {
    let no_inside = if sides.inside {
        String::new()
    } else {
        mesh_without_inside(mesh, spacing)
    };
    let why = IfEmpty {
        result,
        no_inside: &no_inside,
        no_outside: MESH_WITHOUT_OUTSIDE,
    };
    require_surface(sides, &why)
}

/// Why every node of a mesh's grid is inside it.
pub(crate) const MESH_WITHOUT_OUTSIDE: &str =
    "the mesh's faces may point inward; reversed, they would enclose the mesh's volume";

#[cfg(test)]
mod tests {
    use super::*;
    use pgvol_core::{Background, Grid, SparseGrid, BRICK_EDGE};
    use pgvol_field::Basis;

    fn volume(values: impl Fn([usize; 3]) -> f32) -> CoefficientVolume {
        let grid = Grid::cube_res(glam::Vec3::ZERO, glam::Vec3::ONE, 20).unwrap();
        let [nx, ny, nz] = grid.dims;
        let mut dense = Vec::new();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    dense.push(values([i, j, k]));
                }
            }
        }
        let coeffs = SparseGrid::from_dense(grid.dims, &dense, Background::clamp(1.0));
        CoefficientVolume::from_sparse(grid, Basis::Bspline3, coeffs).unwrap()
    }

    #[test]
    fn sides_are_those_of_the_nodes_not_of_the_coefficients() {
        let both = volume(|n| if n == [10, 10, 10] { -10.0 } else { 1.0 });
        assert_eq!(Sides::of_volume(&both), Sides::BOTH);
        // One slightly negative coefficient among positive ones: every node stays outside.
        let dip = volume(|n| if n == [10, 10, 10] { -0.1 } else { 1.0 });
        let sides = Sides::of_volume(&dip);
        assert_eq!((sides.inside, sides.outside), (false, true));
        let inside = volume(|_| -1.0);
        assert!(!Sides::of_volume(&inside).outside);
        let why = IfEmpty {
            result: "the result",
            no_inside: "A",
            no_outside: "B",
        };
        let e = require_surface(sides, &why).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::EmptyResult);
        assert!(e.message().ends_with(": A"), "{e}");
        let e = require_surface(Sides::of_volume(&inside), &why).unwrap_err();
        assert!(e.message().contains("no surface") && e.message().ends_with(": B"));
        require_surface(Sides::BOTH, &why).unwrap();
    }

    #[test]
    fn absent_bricks_count_with_their_background() {
        // 3³ bricks, the middle one stored with `stored`'s values, the others absent on the
        // side `inside` says.
        let sparse = |stored: &dyn Fn(usize) -> f32, inside: &dyn Fn([usize; 3]) -> bool| {
            let grid = Grid::cube_res(glam::Vec3::ZERO, glam::Vec3::ONE, 3 * BRICK_EDGE).unwrap();
            let mut coeffs = SparseGrid::new(grid.dims, Background::clamp(1.0));
            for b in coeffs.all_bricks().collect::<Vec<_>>() {
                if b == [1, 1, 1] {
                    coeffs.insert(b, Box::new(std::array::from_fn(stored)));
                } else {
                    coeffs.set_inside(b, inside(b));
                }
            }
            CoefficientVolume::from_sparse(grid, Basis::Bspline3, coeffs).unwrap()
        };
        let sides = |v: &CoefficientVolume| {
            let s = Sides::of_volume(v);
            (s.inside, s.outside)
        };
        // Absent bricks on both sides, whatever is stored.
        let halves = sparse(&|_| 0.5, &|b| b[2] == 0);
        assert_eq!(sides(&halves), (true, true));
        // Outside everywhere but a stored brick, which holds a node inside or none.
        let apart = sparse(&|_| 0.5, &|_| false);
        assert_eq!(sides(&apart), (false, true));
        let dip = sparse(&|i| if i == 300 { -10.0 } else { 0.5 }, &|_| false);
        assert_eq!(sides(&dip), (true, true));
        // Inside everywhere, the stored brick too.
        let within = sparse(&|_| -0.5, &|_| true);
        assert_eq!(sides(&within), (true, false));
    }
}
