//! Checks every mesh must pass before it leaves a reader or enters a writer, so downstream code
//! (distance fields, grids) never meets NaN, absurd magnitudes or dangling indices.

use crate::Mesh;

/// Coordinates at or beyond this magnitude are rejected: squared distances would overflow f32.
pub const MAX_COORDINATE: f32 = 1e15;

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
                    "coordinate {c:e} at vertex {i} is out of range (|x| must be < 1e15)"
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
    None
}
