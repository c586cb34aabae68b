//! The settings of dual contouring, with their measured defaults.

/// Settings of [`dual_contour`](crate::dual_contour).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualContourOptions {
    /// Keep each vertex inside its cell (a 1e-3 fraction of the cell clear of its faces). This is
    /// what makes the geometry as safe as the topology: no two vertices coincide and no triangle
    /// is degenerate or faces the wrong way along its grid edge. Default `true`.
    pub clamp_to_cell: bool,
    /// Singular values of the tangent-plane system below this fraction of the largest are
    /// treated as zero, leaving the vertex at the crossings' mass point along those directions.
    /// Default 0.1; see `DEFAULT_SINGULAR_THRESHOLD` in the source for the measurements.
    pub singular_threshold: f32,
    /// At cells where the tangent planes meet at a feature (more than one direction passes the
    /// singular value cut), replace each crossing's plane by the tangent plane at a point this
    /// many cells further along the surface, away from the cell's mass point. Smoothed fields
    /// (a decoded B-spline) round an edge over about two cells, which tilts the normals at the
    /// crossings next to it; further away they are the faces' own. 0 keeps the crossings'
    /// planes. See `docs/algorithms.md` for the measurements behind the default.
    pub feature_offset: f32,
    /// Move the vertex of every cell without a feature onto the zero set of the field (one
    /// Newton step, kept in the cell), where marching cubes puts its vertices; the plain QEF
    /// leaves it on the least-squares plane of the crossings, which blended normals tilt.
    /// Default `true`.
    pub project_smooth: bool,
    /// How far, in cells, a vertex may leave its cell through a face the surface does not
    /// cross (all four corners on one side), capped just below half a cell. Where planes meet
    /// at a thin wedge (a 45° notch whose tip no node lies in), the crease lies in a cell the
    /// surface does not cross, and a vertex kept in its own cell cuts the tip off. The
    /// guarantees of `clamp_to_cell` still hold (see `reach_bounds` in the source). Default 0.
    pub reach: f32,
}

/// Relative singular value cut of the QEF, measured on a cube rotated 30° about x and y (side
/// 19.5 cells; mean normal deviation from the true faces) and a sphere of radius 17 cells (mean
/// vertex distance from it), with the exact field and with its cubic B-spline interpolant, as
/// the pipeline decodes it:
///
/// | threshold | 0.01 | 0.02 | 0.05 | 0.1 | 0.2 | 0.3 |
/// |---|---|---|---|---|---|---|
/// | cube, exact (°) | 0.60 | 0.60 | 0.60 | 0.60 | 0.60 | 0.60 |
/// | cube, B-spline (°) | 6.93 | 5.46 | 4.34 | 3.55 | 3.40 | 3.80 |
/// | sphere, either (cells) | 0.0110 | 0.0110 | 0.0108 | 0.0108 | 0.0108 | 0.0108 |
///
/// Exact normals do not care; the smoothed normals of a decoded field near an edge do: small
/// cuts let their spurious second and third directions pull vertices off the surface, large
/// ones drop genuine edge planes. 0.1 is within 5% of the best everywhere and keeps planes
/// meeting at smaller angles than the cube's than 0.2 would. The test
/// `default_threshold_is_near_the_best_on_cube_and_sphere` repeats the measurement.
pub const DEFAULT_SINGULAR_THRESHOLD: f32 = 0.1;

/// Vertices given from outside for some cells: called with a cell's lowest corner (the
/// contour's local coordinates) for every cell the surface crosses once (one loop), it returns
/// that cell's vertex in cell units, or `None` to place it as usual. The vertex is kept inside
/// the cell as every dual contouring vertex is, but for up to [`MAX_OUTSIDE_REACH`] beyond faces the
/// surface does not cross (as [`DualContourOptions::reach`] allows), so the guarantees hold
/// whatever it returns.
pub type StoredVertices<'a> = dyn Fn(glam::Vec3) -> Option<glam::Vec3> + Sync + 'a;

/// The farthest, in cells, that [`DualContourOptions::reach`] and a stored vertex may take a
/// vertex outside its cell: below half a cell by the margin kept clear of faces, so vertices
/// entering one cell from opposite faces stay apart.
pub const MAX_OUTSIDE_REACH: f32 = 0.499;

/// Default of [`DualContourOptions::feature_offset`], in cells.
pub const DEFAULT_FEATURE_OFFSET: f32 = 0.5;

impl Default for DualContourOptions {
    fn default() -> Self {
        Self {
            clamp_to_cell: true,
            singular_threshold: DEFAULT_SINGULAR_THRESHOLD,
            feature_offset: DEFAULT_FEATURE_OFFSET,
            project_smooth: true,
            reach: 0.0,
        }
    }
}
