//! Checks every mesh must pass before it leaves a reader or enters a writer, so downstream code
//! (distance fields, grids) never meets NaN, absurd magnitudes or dangling indices.

use crate::Mesh;

/// Coordinates at or beyond this magnitude are rejected. The point–triangle distance multiplies
/// pairs of dot products, fourth powers of the mesh's size, which overflow f32 from about 1e9
/// (a tetrahedron of size 1e10 got distances 38 % off); 1e8 leaves a margin for grid points
/// beyond the mesh.
pub const MAX_COORDINATE: f32 = 1e8;

/// Meshes whose largest bounding-box extent is below this are rejected: the same fourth powers
/// underflow (a tetrahedron of size 1e-10 lost every distance). Giving the mesh in smaller units
/// (millimetres instead of metres, say) brings it into range.
pub const MIN_EXTENT: f32 = 1e-6;

/// The first problem found in `mesh`, phrased for a person; `None` when the mesh is usable.
/// `owner` is "file" or "mesh", to say whose vertices the message counts.
pub(crate) fn problem(mesh: &Mesh, owner: &str) -> Option<String> {
    if mesh.triangles.is_empty() {
        return Some("no triangles".into());
    }
    for (i, p) in mesh.positions.iter().enumerate() {
        if let Some(c) = p.to_array().into_iter().find(|c| !c.is_finite()) {
            let what = if c.is_nan() { "NaN" } else { "infinity" };
            // The position too: a reader may have reordered the file's vertices.
            return Some(format!(
                "vertex {i} (counted from 0; at {}, {}, {}) has a non-finite coordinate ({what})",
                p.x, p.y, p.z
            ));
        }
    }
    if !mesh.offset.is_finite() {
        return Some(format!("the frame offset {} is not finite", mesh.offset));
    }
    if let Some((i, c)) = coordinate_out_of_range(mesh) {
        return Some(format!(
            "coordinate {:e} at vertex {i} is out of range (|x| must be < 1e8); give the mesh \
             relative to a nearer origin or in larger units",
            c as f32
        ));
    }
    let n = mesh.positions.len();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if let Some(&bad) = tri.iter().find(|&&i| i as usize >= n) {
            return Some(format!(
                "face {t} refers to vertex {bad} but the {owner} has {n} vertices"
            ));
        }
    }
    // After the index check: the bounds read the vertices the faces name.
    too_small(mesh).map(|extent| {
        format!(
            "the mesh is too small to process: its largest extent is {extent:e} (must be at \
             least 1e-6; give it in smaller units)"
        )
    })
}

/// The first problem found in a mesh given in memory (not read from a file), phrased for a
/// person; `None` when it is usable. The same checks as every reader and writer makes.
pub fn mesh_problem(mesh: &Mesh) -> Option<String> {
    problem(mesh, "mesh")
}

/// The first vertex with a world coordinate (offset added, in f64) at or beyond
/// [`MAX_COORDINATE`], and that coordinate.
pub fn coordinate_out_of_range(mesh: &Mesh) -> Option<(usize, f64)> {
    let limit = f64::from(MAX_COORDINATE);
    (0..mesh.positions.len()).find_map(|i| {
        mesh.world(i)
            .to_array()
            .into_iter()
            .find(|c| c.abs() >= limit)
            .map(|c| (i, c))
    })
}

/// The largest rounding, relative to the mesh's longest extent, that a format storing f32
/// world coordinates (STL) may add; beyond it such a write is refused.
pub const MAX_F32_ROUNDING: f64 = 1e-5;

/// For a format holding f32 world coordinates: the rounding error at the mesh's farthest
/// coordinate (half an f32 step there) and that error over the mesh's longest extent, when the
/// latter exceeds [`MAX_F32_ROUNDING`]. Meshes near the origin (offset zero) are stored as
/// they are and never refused.
pub fn f32_rounding_loss(mesh: &Mesh) -> Option<(f64, f64)> {
    if mesh.offset == glam::DVec3::ZERO {
        return None;
    }
    let (lo, hi) = mesh.bounds()?;
    let size = f64::from((hi - lo).max_element());
    let far = (mesh.offset.abs() + lo.abs().max(hi.abs()).as_dvec3()).max_element();
    // Half the spacing of f32 values at `far`.
    let step = f64::from((far as f32).next_up() - far as f32) * 0.5;
    let relative = step / size;
    (relative > MAX_F32_ROUNDING).then_some((step, relative))
}

/// The largest bounding-box extent of the faces' vertices when it is below [`MIN_EXTENT`]
/// (`None` also for a mesh without faces). The faces must name existing vertices.
pub fn too_small(mesh: &Mesh) -> Option<f32> {
    let (lo, hi) = mesh.bounds()?;
    let extent = (hi - lo).max_element();
    (extent < MIN_EXTENT).then_some(extent)
}
