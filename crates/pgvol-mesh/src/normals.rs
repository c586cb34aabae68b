//! Unit normals for writers. Computed in f64 so that tiny or huge triangles neither underflow
//! nor overflow, and every vertex gets a normal of length 1 (glTF validators reject others).

use glam::{DVec3, Vec3};
use rayon::prelude::*;

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
    // Each face's three weighted normals (the angles' arc cosines are most of the work) are
    // computed in parallel a batch of faces at a time, then added in face order, so the sums
    // are the same floats whatever the thread count.
    let mut batch: Vec<Option<Corners>> = Vec::with_capacity(FACE_BATCH);
    for (b, faces) in mesh.triangles.chunks(FACE_BATCH).enumerate() {
        faces
            .par_iter()
            .map(|tri| weighted_corners(mesh, tri))
            .collect_into_vec(&mut batch);
        for (k, corners) in batch.iter().enumerate() {
            let Some((idx, weighted)) = corners else {
                continue;
            };
            let f = (b * FACE_BATCH + k) as u32;
            for (&i, w) in idx.iter().zip(weighted) {
                sums[i] += *w;
                if fallback[i] == NO_FACE {
                    fallback[i] = f;
                }
            }
        }
    }
    let face_dir = |f: u32| {
        let (_, p) = corners(mesh, &mesh.triangles[f as usize])?;
        unit((p[1] - p[0]).cross(p[2] - p[0]))
    };
    sums.par_iter()
        .zip(&fallback)
        .map(|(&s, &f)| {
            let dir = unit(s)
                .or_else(|| (f != NO_FACE).then(|| face_dir(f)).flatten())
                .unwrap_or(DVec3::Z);
            renormalise(dir.as_vec3())
        })
        .collect()
}

/// Faces whose weighted normals are computed together before they are added up.
const FACE_BATCH: usize = 1 << 16;

/// A face's vertex indices and, per corner, its area normal times the corner's angle.
type Corners = ([usize; 3], [DVec3; 3]);

/// A face's corners and their positions, `None` when an index is out of range.
fn corners(mesh: &Mesh, tri: &[u32; 3]) -> Option<([usize; 3], [DVec3; 3])> {
    let n = mesh.positions.len();
    let idx = tri.map(|i| i as usize);
    (idx.iter().all(|&i| i < n)).then(|| (idx, idx.map(|i| mesh.positions[i].as_dvec3())))
}

/// What face `tri` adds to its corners' sums, `None` for a face without area.
fn weighted_corners(mesh: &Mesh, tri: &[u32; 3]) -> Option<Corners> {
    let (idx, p) = corners(mesh, tri)?;
    // Length is twice the area, so this is the area-weighted direction.
    let area_normal = (p[1] - p[0]).cross(p[2] - p[0]);
    unit(area_normal)?;
    let weighted = [0, 1, 2].map(|k| {
        let e1 = p[(k + 1) % 3] - p[k];
        let e2 = p[(k + 2) % 3] - p[k];
        let angle = e1.angle_between(e2);
        let angle = if angle.is_finite() { angle } else { 0.0 };
        area_normal * angle
    });
    Some((idx, weighted))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The sums of [`vertex_normals`] in one loop over the faces, as a single thread adds them.
    fn sequential(mesh: &Mesh) -> Vec<Vec3> {
        let mut sums = vec![DVec3::ZERO; mesh.positions.len()];
        for tri in &mesh.triangles {
            if let Some((idx, weighted)) = weighted_corners(mesh, tri) {
                for (&i, w) in idx.iter().zip(weighted) {
                    sums[i] += w;
                }
            }
        }
        sums.iter()
            .map(|&s| renormalise(unit(s).unwrap_or(DVec3::Z).as_vec3()))
            .collect()
    }

    #[test]
    fn normals_are_the_same_floats_whatever_the_threads() {
        // More faces than one batch, so batches meet at vertices.
        let mut mesh = crate::shapes::octasphere(7);
        assert!(mesh.triangles.len() > FACE_BATCH);
        // A wobble, so the sums depend on the order they are added in.
        for (i, p) in mesh.positions.iter_mut().enumerate() {
            *p *= 1.0 + 0.01 * ((i as f32) * 0.7).sin();
        }
        let want = sequential(&mesh);
        for threads in [1, 2, 5] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let got = pool.install(|| vertex_normals(&mesh));
            assert!(got == want, "{threads} threads");
        }
    }
}
