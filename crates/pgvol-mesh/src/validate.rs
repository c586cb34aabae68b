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
        for c in p.to_array() {
            if !c.is_finite() {
                let what = if c.is_nan() { "NaN" } else { "infinity" };
                return Some(format!("vertex {i} has a non-finite coordinate ({what})"));
            }
            if c.abs() >= MAX_COORDINATE {
                return Some(format!(
                    "coordinate {c:e} at vertex {i} is out of range (|x| must be < 1e8)"
                ));
            }
        }
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
    let (lo, hi) = mesh.bounds()?;
    let extent = (hi - lo).max_element();
    if extent < MIN_EXTENT {
        return Some(format!(
            "the mesh is too small to process: its largest extent is {extent:e} (must be at \
             least 1e-6; give it in smaller units)"
        ));
    }
    None
}
