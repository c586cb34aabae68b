//! Signed distance of a mesh at points and on grids.

use glam::Vec3;
use pgvol_mesh::Mesh;

use crate::{
    bvh::Bvh, bvh::Closest, pseudonormal::Pseudonormals, rims::Rims, winding::WindingTree,
};

/// How inside and outside are told apart.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SignMode {
    /// The winding number, on faces the caller has oriented outward (the facade does). On a
    /// closed mesh it is a whole number, carried along the grid's rows without evaluating it,
    /// so it costs no more than the pseudonormal, and it stays right where a closed mesh
    /// folds over or crosses itself.
    #[default]
    Auto,
    /// Generalized winding number > 1/2: robust to holes, flips and self-intersections.
    Winding,
    /// Angle-weighted pseudonormal at the closest point: exact and fast on closed, manifold,
    /// consistently oriented meshes; wrong near holes and overlaps.
    Pseudonormal,
    /// Ray parity: an odd number of crossings along a ray means inside, by majority of three
    /// rays (a ray through an edge or a vertex abstains and another direction is tried). For
    /// closed meshes; orientation-blind.
    Parity,
}

impl SignMode {
    pub fn name(self) -> &'static str {
        match self {
            SignMode::Auto => "auto",
            SignMode::Winding => "winding",
            SignMode::Pseudonormal => "pseudonormal",
            SignMode::Parity => "parity",
        }
    }
}

/// Why a distance field could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SdfError {
    #[error("the mesh has no triangles")]
    Empty,
    #[error("the mesh has a non-finite vertex coordinate")]
    NonFinite,
    /// Outside the sizes whose distances stay exact in f32 (see [`pgvol_mesh::MAX_COORDINATE`]
    /// and [`pgvol_mesh::MIN_EXTENT`]).
    #[error("the mesh is out of range: coordinates must be below 1e8 and its largest extent at least 1e-6")]
    OutOfRange,
}

/// A mesh prepared for signed-distance queries.
pub struct MeshSdf {
    bvh: Bvh,
    winding: WindingTree,
    pseudonormals: Option<Pseudonormals>,
    /// The mode in force (never `Auto`: that is resolved on construction).
    mode: SignMode,
    /// Edges where the triangles' orientations do not cancel (open boundaries, edges used twice
    /// the same way, ...): the winding number varies fast near them.
    rims: Rims,
    /// Whether grid scans run their AVX2 build (detected on construction).
    avx2: bool,
    /// Whether grid scans skip leaves by their oriented boxes.
    oriented: bool,
    /// Winding numbers the grid sampler computed rather than carried, to check how rarely.
    #[cfg(test)]
    pub(crate) sampler_windings: std::sync::atomic::AtomicUsize,
}

/// Winding numbers within this margin of 1/2 are recomputed with a finer expansion before the
/// sign is decided (the coarse expansion's error is below 0.04, see `winding.rs`).
const SIGN_MARGIN: f32 = 0.1;

/// Error bounds assumed for the coarse and the refined winding number.
const COARSE_ERROR: f32 = 0.06;
const REFINED_ERROR: f32 = 0.01;

impl MeshSdf {
    pub fn new(mesh: &Mesh, mode: SignMode) -> Result<MeshSdf, SdfError> {
        if mesh.triangles.is_empty() {
            return Err(SdfError::Empty);
        }
        if mesh.positions.iter().any(|p| !p.is_finite()) {
            return Err(SdfError::NonFinite);
        }
        // The same limits as the mesh readers and writers apply.
        if pgvol_mesh::coordinate_out_of_range(mesh).is_some()
            || pgvol_mesh::too_small(mesh).is_some()
        {
            return Err(SdfError::OutOfRange);
        }
        let bvh = Bvh::build(mesh);
        let winding = WindingTree::new(&bvh);
        let mode = match mode {
            SignMode::Auto => SignMode::Winding,
            m => m,
        };
        let pseudonormals =
            (mode == SignMode::Pseudonormal).then(|| Pseudonormals::new(mesh, &bvh));
        let rims = if mode == SignMode::Winding {
            Rims::new(mesh)
        } else {
            Rims::default()
        };
        Ok(MeshSdf {
            bvh,
            winding,
            pseudonormals,
            mode,
            rims,
            avx2: crate::wide::avx2_available(),
            oriented: true,
            #[cfg(test)]
            sampler_windings: Default::default(),
        })
    }

    /// Rim edges (see [`MeshSdf`]), which bound the winding number's gradient.
    pub fn rims(&self) -> &Rims {
        &self.rims
    }

    /// Number of rim edges (0 for closed, consistently oriented meshes).
    pub fn rim_count(&self) -> usize {
        self.rims.len()
    }

    /// The sign mode in force (`Auto` resolved).
    pub fn sign_mode(&self) -> SignMode {
        self.mode
    }

    /// Whether grid scans run their AVX2 build.
    pub(crate) fn avx2(&self) -> bool {
        self.avx2
    }

    /// Makes grid scans run their baseline build, to compare it with the AVX2 one.
    #[cfg(test)]
    pub(crate) fn use_baseline_scans(&mut self) {
        self.avx2 = false;
    }

    /// Whether grid scans skip leaves by their oriented boxes.
    pub(crate) fn skips_by_oriented_boxes(&self) -> bool {
        self.oriented
    }

    /// Makes grid scans open leaves by their axis-aligned boxes only, to compare with.
    #[cfg(test)]
    pub(crate) fn use_axis_aligned_boxes_only(&mut self) {
        self.oriented = false;
    }

    /// Whether the sign is the winding number and that takes whole values off the surface: a
    /// closed mesh (no rims), however folded or overlapping. Then it is constant between
    /// crossings and 0 outside the mesh's box.
    pub fn winding_is_whole(&self) -> bool {
        self.sign_mode() == SignMode::Winding && self.rims.is_empty()
    }

    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// Generalized winding number at `p`, accurate to about 0.002 near 1/2.
    pub fn winding_number(&self, p: Vec3) -> f32 {
        self.winding_with_error(p).0
    }

    /// Generalized winding number at `p` and a bound on its error, with a safety factor over
    /// the errors measured in `winding.rs` (0.030 coarse, 0.002 refined).
    pub fn winding_with_error(&self, p: Vec3) -> (f32, f32) {
        let w = self.winding.winding(&self.bvh, p);
        if (w - 0.5).abs() < SIGN_MARGIN {
            (self.winding.winding_refined(&self.bvh, p), REFINED_ERROR)
        } else {
            (w, COARSE_ERROR)
        }
    }

    /// Whether `p` is inside, given its closest point on the mesh.
    pub fn is_inside_near(&self, p: Vec3, closest: &Closest) -> bool {
        match self
            .pseudonormals
            .as_ref()
            .filter(|_| self.sign_mode() == SignMode::Pseudonormal)
        {
            Some(pn) => {
                let n = pn.normal(closest.slot, closest.feature);
                (glam::Vec3A::from(p) - glam::Vec3A::from(closest.point)).dot(n) < 0.0
            }
            None => self.is_inside(p),
        }
    }

    /// Whether `p` is inside.
    pub fn is_inside(&self, p: Vec3) -> bool {
        match self.sign_mode() {
            SignMode::Pseudonormal => match self.bvh.closest(p, f32::INFINITY) {
                Some(c) => self.is_inside_near(p, &c),
                None => false,
            },
            SignMode::Parity => self.parity_inside(p),
            _ => self.winding_number(p) > 0.5,
        }
    }

    /// Majority of three ray-parity votes; rays that graze an edge or a vertex abstain.
    fn parity_inside(&self, p: Vec3) -> bool {
        // Directions with no simple rational slope, so they rarely run along mesh features.
        const DIRECTIONS: [[f32; 3]; 7] = [
            [0.5773, 0.6118, 0.5407],
            [-0.7072, 0.3162, 0.6325],
            [0.2673, -0.8018, 0.5345],
            [0.9045, 0.1812, -0.3861],
            [-0.3015, -0.6030, -0.7385],
            [0.1104, 0.9608, -0.2543],
            [-0.8729, -0.2182, 0.4364],
        ];
        let (mut inside, mut votes) = (0, 0);
        for d in DIRECTIONS {
            if let Some(n) = self.bvh.ray_crossings(p, Vec3::from(d).normalize()) {
                votes += 1;
                inside += (n % 2) as i32;
                if votes == 3 {
                    break;
                }
            }
        }
        if votes == 0 {
            // Every ray grazed an edge: rare enough that the slower robust answer is fine.
            return self.winding_number(p) > 0.5;
        }
        2 * inside > votes
    }

    /// Signed distance at `p`: exact magnitude, negative inside.
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        self.signed_distance_with_hint(p, None).0
    }

    /// Signed distance and the leaf slot of the closest triangle, to seed the next nearby query.
    pub fn signed_distance_with_hint(&self, p: Vec3, hint: Option<u32>) -> (f32, Option<u32>) {
        match self.bvh.closest_with_hint(p, f32::INFINITY, hint) {
            Some(c) => {
                let d = c.distance_squared.sqrt();
                (
                    if self.is_inside_near(p, &c) { -d } else { d },
                    Some(c.slot),
                )
            }
            None => (f32::INFINITY, None),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;
    use pgvol_mesh::shapes::octasphere as sphere;

    fn unit_cube() -> Mesh {
        pgvol_mesh::shapes::cuboid(Vec3::ZERO, Vec3::ONE)
    }

    /// Exact SDF of the axis-aligned unit cube.
    fn cube_sdf(p: Vec3) -> f32 {
        let q = (p - Vec3::splat(0.5)).abs() - Vec3::splat(0.5);
        q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
    }

    #[test]
    fn cube_matches_the_analytic_sdf() {
        let sdf = MeshSdf::new(&unit_cube(), SignMode::Winding).unwrap();
        let grid = Grid::cube_res(Vec3::ZERO, Vec3::ONE, 17).unwrap();
        let values = sdf.sample_grid(&grid, &|_: f64| {});
        for k in 0..17 {
            for j in 0..17 {
                for i in 0..17 {
                    let p = grid.point(i, j, k);
                    let want = cube_sdf(p);
                    let got = values[grid.index(i, j, k)];
                    if want.abs() > 1e-4 {
                        assert!((got - want).abs() < 1e-5, "{p}: {got} vs {want}");
                    }
                }
            }
        }
    }

    #[test]
    fn sphere_mesh_is_close_to_the_analytic_sdf() {
        let mesh = sphere(5);
        let sdf = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
        // The polyhedron lies inside the unit sphere by at most the chord sag.
        for p in [
            Vec3::ZERO,
            Vec3::new(0.3, 0.2, 0.1),
            Vec3::new(1.5, 0.0, 0.2),
            Vec3::new(-2.0, 1.0, 0.5),
        ] {
            let want = p.length() - 1.0;
            let got = sdf.signed_distance(p);
            assert!((got - want).abs() < 0.01, "{p}: {got} vs {want}");
        }
    }

    #[test]
    fn flipped_mesh_keeps_the_distance_and_turns_inside_out() {
        let mut mesh = unit_cube();
        let sdf = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
        let flipped = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
        // A fully flipped closed mesh has winding number -1 inside: the sign says outside, but
        // the distance value is untouched by the sign method.
        for p in [
            Vec3::splat(0.5),
            Vec3::new(0.9, 0.2, 0.4),
            Vec3::new(2.0, 0.5, 0.5),
        ] {
            assert_eq!(sdf.signed_distance(p).abs(), flipped.signed_distance(p));
        }
        assert!(sdf.signed_distance(Vec3::splat(0.5)) < 0.0);
    }

    #[test]
    fn empty_and_nan_meshes_are_refused() {
        assert_eq!(
            MeshSdf::new(&Mesh::default(), SignMode::Winding).err(),
            Some(SdfError::Empty)
        );
        let mut mesh = unit_cube();
        mesh.positions[3].x = f32::NAN;
        assert_eq!(
            MeshSdf::new(&mesh, SignMode::Winding).err(),
            Some(SdfError::NonFinite)
        );
    }
}
