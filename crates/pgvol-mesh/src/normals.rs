//! Unit normals for writers, every one of length 1 (glTF validators reject others): a mesh's
//! own (`Mesh::normals`, a contour's field gradients) where it has one per vertex, else weighted
//! from the faces. Each face's contribution is computed in f64, so that tiny or huge triangles
//! neither underflow nor overflow, then scaled by one factor for the whole mesh and added in f32
//! in the normals' own array, which is normalised in place: beyond the output only a batch of
//! faces is held, since the normals of a large mesh are made while it is held whole.

use std::borrow::Cow;
use std::collections::HashMap;

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
    let scale = weight_scale(mesh);
    let mut sums = vec![Vec3::ZERO; mesh.positions.len()];
    // Each face's three weighted normals (the angles' arc cosines are most of the work) are
    // computed in parallel a batch of faces at a time, then added in face order, so the sums
    // are the same floats whatever the thread count.
    let mut batch: Vec<Option<Corners>> = Vec::with_capacity(FACE_BATCH);
    for faces in mesh.triangles.chunks(FACE_BATCH) {
        faces
            .par_iter()
            .map(|tri| weighted_corners(mesh, tri, scale))
            .collect_into_vec(&mut batch);
        for (idx, weighted) in batch.iter().flatten() {
            for (&i, w) in idx.iter().zip(weighted) {
                sums[i] += *w;
            }
        }
    }
    // Normalised in place; a sum without a direction is marked by zero, which no unit
    // normal is.
    sums.par_iter_mut().for_each(|s| {
        *s = unit(s.as_dvec3()).map_or(Vec3::ZERO, |u| renormalise(u.as_vec3()));
    });
    fill_vanished(mesh, &mut sums);
    sums
}

/// The normals a writer stores: the mesh's own where it has one per position (the exact
/// normals a contour gives), each zero one replaced as in [`vertex_normals`]; else
/// [`vertex_normals`].
pub fn output_normals(mesh: &Mesh) -> Cow<'_, [Vec3]> {
    if mesh.normals.len() != mesh.positions.len() {
        return Cow::Owned(vertex_normals(mesh));
    }
    // Borrowed as they are when every one is a unit vector already: no second copy of a large
    // mesh's normals while it is written.
    let unit_length = |n: &Vec3| (n.length_squared() - 1.0).abs() <= UNIT_SLACK;
    if mesh.normals.par_iter().all(unit_length) {
        return Cow::Borrowed(&mesh.normals);
    }
    let mut normals: Vec<Vec3> = mesh
        .normals
        .par_iter()
        .map(|&n| unit(n.as_dvec3()).map_or(Vec3::ZERO, |u| renormalise(u.as_vec3())))
        .collect();
    fill_vanished(mesh, &mut normals);
    Cow::Owned(normals)
}

/// How far a stored normal's squared length may be from 1 (a few f32 rounding steps) for it to
/// be written as it is.
const UNIT_SLACK: f32 = 1e-6;

/// Gives each zero entry of `normals` the direction of the first face with area at its vertex,
/// or +Z where there is none.
fn fill_vanished(mesh: &Mesh, normals: &mut [Vec3]) {
    let vanished: Vec<u32> = (0..normals.len() as u32)
        .into_par_iter()
        .filter(|&i| normals[i as usize] == Vec3::ZERO)
        .collect();
    if vanished.is_empty() {
        return;
    }
    let first = first_faces_with_area(mesh, &vanished);
    for i in vanished {
        let dir = first.get(&i).copied().flatten().unwrap_or(DVec3::Z);
        normals[i as usize] = renormalise(dir.as_vec3());
    }
}

/// The direction of the first face with area at each vertex of `vertices` (`None` where there
/// is none), by face index: the rare vertices whose sum vanished.
fn first_faces_with_area(mesh: &Mesh, vertices: &[u32]) -> HashMap<u32, Option<DVec3>> {
    let mut first: HashMap<u32, Option<DVec3>> = vertices.iter().map(|&i| (i, None)).collect();
    let mut left = first.len();
    for tri in &mesh.triangles {
        if left == 0 {
            break;
        }
        let Some((idx, p)) = corners(mesh, tri) else {
            continue;
        };
        let Some(dir) = unit((p[1] - p[0]).cross(p[2] - p[0])) else {
            continue;
        };
        for i in idx {
            if let Some(slot @ None) = first.get_mut(&(i as u32)) {
                *slot = Some(dir);
                left -= 1;
            }
        }
    }
    first
}

/// The factor that brings every face's weight (twice its area times an angle, at most
/// `3π·L²` for a mesh whose bounding box's longest side is `L`) to at most 1, so that f32 sums
/// of them neither overflow nor, for any triangle f32 positions can resolve, underflow.
fn weight_scale(mesh: &Mesh) -> f64 {
    let finite = mesh.positions.par_iter().filter(|p| p.is_finite());
    let (lo, hi) = finite
        .fold(
            || (Vec3::INFINITY, Vec3::NEG_INFINITY),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
        .reduce(
            || (Vec3::INFINITY, Vec3::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    let side = (hi - lo).max_element() as f64;
    if side.is_finite() && side > 0.0 {
        1.0 / (3.0 * std::f64::consts::PI * side * side)
    } else {
        1.0
    }
}

/// Faces whose weighted normals are computed together before they are added up.
const FACE_BATCH: usize = 1 << 16;

/// A face's vertex indices and, per corner, its area normal times the corner's angle, scaled.
type Corners = ([usize; 3], [Vec3; 3]);

/// A face's corners and their positions, `None` when an index is out of range.
fn corners(mesh: &Mesh, tri: &[u32; 3]) -> Option<([usize; 3], [DVec3; 3])> {
    let n = mesh.positions.len();
    let idx = tri.map(|i| i as usize);
    (idx.iter().all(|&i| i < n)).then(|| (idx, idx.map(|i| mesh.positions[i].as_dvec3())))
}

/// What face `tri` adds to its corners' sums, times `scale`; `None` for a face without area.
fn weighted_corners(mesh: &Mesh, tri: &[u32; 3], scale: f64) -> Option<Corners> {
    let (idx, p) = corners(mesh, tri)?;
    // Length is twice the area, so this is the area-weighted direction.
    let area_normal = (p[1] - p[0]).cross(p[2] - p[0]);
    unit(area_normal)?;
    let weighted = [0, 1, 2].map(|k| {
        let e1 = p[(k + 1) % 3] - p[k];
        let e2 = p[(k + 2) % 3] - p[k];
        let angle = e1.angle_between(e2);
        let angle = if angle.is_finite() { angle } else { 0.0 };
        (area_normal * (angle * scale)).as_vec3()
    });
    Some((idx, weighted))
}

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
        let scale = weight_scale(mesh);
        let mut sums = vec![Vec3::ZERO; mesh.positions.len()];
        for tri in &mesh.triangles {
            if let Some((idx, weighted)) = weighted_corners(mesh, tri, scale) {
                for (&i, w) in idx.iter().zip(weighted) {
                    sums[i] += w;
                }
            }
        }
        sums.iter()
            .map(|&s| renormalise(unit(s.as_dvec3()).unwrap_or(DVec3::Z).as_vec3()))
            .collect()
    }

    /// The same weights added in f64 without a scale: what the f32 sums approximate.
    fn in_f64(mesh: &Mesh) -> Vec<Vec3> {
        let mut sums = vec![DVec3::ZERO; mesh.positions.len()];
        for tri in &mesh.triangles {
            let (idx, p) = corners(mesh, tri).unwrap();
            let area_normal = (p[1] - p[0]).cross(p[2] - p[0]);
            for k in 0..3 {
                let angle = (p[(k + 1) % 3] - p[k]).angle_between(p[(k + 2) % 3] - p[k]);
                sums[idx[k]] += area_normal * angle;
            }
        }
        sums.iter().map(|&s| unit(s).unwrap().as_vec3()).collect()
    }

    /// A sphere of more faces than one batch (so batches meet at vertices), wobbled so that
    /// the sums depend on the order they are added in.
    fn wobbly_sphere() -> Mesh {
        let mut mesh = crate::shapes::octasphere(7);
        assert!(mesh.triangles.len() > FACE_BATCH);
        for (i, p) in mesh.positions.iter_mut().enumerate() {
            *p *= 1.0 + 0.01 * ((i as f32) * 0.7).sin();
        }
        mesh
    }

    #[test]
    fn normals_are_the_same_floats_whatever_the_threads() {
        let mesh = wobbly_sphere();
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

    /// The f32 sums give the f64 sums' directions to f32 precision, at the mesh's size and
    /// scaled by 1e-20 and 1e18, where unscaled f32 sums would underflow and overflow.
    #[test]
    fn f32_sums_keep_the_f64_directions_at_any_size() {
        let sphere = wobbly_sphere();
        for size in [1.0f32, 1e-20, 1e18] {
            let mut mesh = sphere.clone();
            for p in &mut mesh.positions {
                *p *= size;
            }
            let (got, want) = (vertex_normals(&mesh), in_f64(&mesh));
            let worst = got
                .iter()
                .zip(&want)
                .map(|(a, b)| (*a - *b).length())
                .fold(0.0f32, f32::max);
            // The chord between unit vectors: the angle, for small angles.
            assert!(worst < 1e-6, "size {size}: {worst} rad");
        }
    }

    #[test]
    fn a_meshs_own_normals_are_written_with_zero_ones_from_a_face() {
        let mut mesh = wobbly_sphere();
        let n = mesh.positions.len();
        // Not one per position: weighted from the faces.
        mesh.normals = vec![Vec3::X; n - 1];
        assert_eq!(
            output_normals(&mesh).as_ref(),
            vertex_normals(&mesh).as_slice()
        );
        mesh.normals = vec![Vec3::X; n];
        assert!(matches!(output_normals(&mesh), Cow::Borrowed(_)));
        // A zero normal takes its first face's direction; one slightly long is made unit.
        mesh.normals[0] = Vec3::ZERO;
        mesh.normals[1] = Vec3::new(0.0, 2.0, 0.0);
        let out = output_normals(&mesh);
        let tri = *mesh.triangles.iter().find(|t| t.contains(&0)).unwrap();
        let face = face_normal(tri.map(|i| mesh.positions[i as usize]));
        assert!((out[0] - face).length() < 1e-6, "{} vs {face}", out[0]);
        assert_eq!(out[1], Vec3::Y);
        assert!(out[2..].iter().all(|&v| v == Vec3::X));
    }

    /// A vertex whose faces cancel takes its first face's normal, a vertex of only arealess
    /// faces and an unreferenced one take +Z.
    #[test]
    fn vanished_sums_fall_back_to_a_face_or_z() {
        let positions = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::new(5.0, 0.0, 0.0),
            Vec3::new(6.0, 0.0, 0.0),
            Vec3::new(7.0, 0.0, 0.0),
            Vec3::new(9.0, 9.0, 9.0),
        ];
        // The same triangle both ways round, then a flat one, and an unused vertex.
        let triangles = vec![[0, 1, 2], [0, 2, 1], [3, 4, 5]];
        let mesh = Mesh::new(positions, triangles);
        let normals = vertex_normals(&mesh);
        for (i, n) in normals[..3].iter().enumerate() {
            assert_eq!(*n, Vec3::Z, "vertex {i}: the first face points up");
        }
        let flipped = Mesh::new(mesh.positions.clone(), vec![[0, 2, 1], [0, 1, 2]]);
        assert_eq!(vertex_normals(&flipped)[0], -Vec3::Z);
        for (i, n) in normals.iter().enumerate().skip(3) {
            assert_eq!(*n, Vec3::Z, "vertex {i}");
        }
    }
}
