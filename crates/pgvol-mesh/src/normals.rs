//! Unit normals for writers. Computed in f64 so that tiny or huge triangles neither underflow
//! nor overflow, and every vertex gets a normal of length 1 (glTF validators reject others).

use glam::{DVec3, Vec3};

use crate::Mesh;

/// Unit normal of a triangle (counter-clockwise corners give the outward side), or
/// `Vec3::ZERO` when the triangle has no area and therefore no direction.
pub fn face_normal(tri: [Vec3; 3]) -> Vec3 {
    let [a, b, c] = tri.map(|p| p.as_dvec3());
    unit((b - a).cross(c - a)).map_or(Vec3::ZERO, |u| renormalise(u.as_vec3()))
}

/// One unit normal per position: the sum over adjacent faces of the face normal weighted by
/// face area and by the corner angle at the vertex. Area weighting keeps slivers from
/// dominating; angle weighting makes the result independent of how a flat region is split.
/// Vertices whose sum vanishes (unreferenced, or only degenerate/cancelling faces) take the
/// normal of an adjacent face with area, or +Z if there is none.
pub fn vertex_normals(mesh: &Mesh) -> Vec<Vec3> {
    let n = mesh.positions.len();
    let mut sums = vec![DVec3::ZERO; n];
    // The first face with area at each vertex, by index: a normal per vertex would take eight
    // times the room, for the rare vertex whose sum vanishes.
    let mut fallback = vec![NO_FACE; n];
    let corners = |tri: &[u32; 3]| {
        let idx = tri.map(|i| i as usize);
        (idx.iter().all(|&i| i < n)).then(|| (idx, idx.map(|i| mesh.positions[i].as_dvec3())))
    };
    for (f, tri) in mesh.triangles.iter().enumerate() {
        let Some((idx, p)) = corners(tri) else {
            continue;
        };
        // Length is twice the area, so this is the area-weighted direction.
        let area_normal = (p[1] - p[0]).cross(p[2] - p[0]);
        if unit(area_normal).is_none() {
            continue;
        }
        for k in 0..3 {
            let e1 = p[(k + 1) % 3] - p[k];
            let e2 = p[(k + 2) % 3] - p[k];
            let angle = e1.angle_between(e2);
            let angle = if angle.is_finite() { angle } else { 0.0 };
            sums[idx[k]] += area_normal * angle;
            if fallback[idx[k]] == NO_FACE {
                fallback[idx[k]] = f as u32;
            }
        }
    }
    let face_dir = |f: u32| {
        let (_, p) = corners(&mesh.triangles[f as usize])?;
        unit((p[1] - p[0]).cross(p[2] - p[0]))
    };
    sums.iter()
        .zip(&fallback)
        .map(|(&s, &f)| {
            let dir = unit(s)
                .or_else(|| (f != NO_FACE).then(|| face_dir(f)).flatten())
                .unwrap_or(DVec3::Z);
            renormalise(dir.as_vec3())
        })
        .collect()
}

/// No face yet, in [`vertex_normals`]' table of first faces.
const NO_FACE: u32 = u32::MAX;

/// Direction of `v` in f64, `None` if it has none (zero, denormal-small or non-finite).
fn unit(v: DVec3) -> Option<DVec3> {
    // Rescale first so that very small or very large vectors normalise accurately.
    let m = v.abs().max_element();
    if !(m.is_finite() && m > 0.0) {
        return None;
    }
    let u = (v / m).normalize();
    u.is_finite().then_some(u)
}

/// Rounding to f32 can leave the length a few ulps off 1; one more f32 pass brings it within
/// 1e-6, and it never changes the direction meaningfully.
fn renormalise(v: Vec3) -> Vec3 {
    let u = v.normalize();
    if u.is_finite() {
        u
    } else {
        Vec3::Z
    }
}
