//! Cross-sections of the field through the points in axis-aligned planes, cut from the field
//! itself (the RBF interpolant for the RBF methods, [`crate::reconstruct_with`]) rather than
//! from its B-spline resampling on the grid: the output of the RBF method of Turk and O'Brien
//! and Morse et al., where the surface is wanted as contours in given planes.
//!
//! Each plane is contoured by the slicer's marching squares ([`pgvol_slice::slice`]): the field
//! at the nodes of a 2D grid over the grid box's cross-section, one vertex per crossed grid
//! edge at the field's zero along the edge (regula falsi), so every vertex lies on the field's
//! zero set, then a simplification that keeps a subset of the vertices.

use pgvol_core::Grid;
use pgvol_slice::{
    Axis, Layer, SliceError, SliceOptions, MAX_LAYERS, MAX_LAYER_COORDINATE, MAX_LAYER_NODES,
};
use rayon::prelude::*;

use crate::PointField;

/// Where and how finely to cut.
#[derive(Clone, Debug, PartialEq)]
pub struct SectionPlanes {
    /// The axis the planes are normal to.
    pub axis: Axis,
    /// Plane positions along the axis, in the cloud's units.
    pub heights: Vec<f32>,
    /// Spacing of each plane's 2D sampling grid (> 0).
    pub resolution: f32,
    /// Simplification tolerance (≥ 0; 0 keeps every vertex).
    pub tolerance: f32,
}

impl SectionPlanes {
    /// Planes at `heights` along `axis`, sampled at `resolution` and simplified to a tenth of
    /// it (as `pgvol_slice::SliceOptions::new`).
    pub fn new(axis: Axis, heights: Vec<f32>, resolution: f32) -> Self {
        SectionPlanes {
            axis,
            heights,
            resolution,
            tolerance: resolution / 10.0,
        }
    }
}

/// The name of an axis, for messages.
pub fn axis_name(axis: Axis) -> &'static str {
    match axis {
        Axis::X => "x",
        Axis::Y => "y",
        Axis::Z => "z",
    }
}

/// Refuses section planes that cannot be cut in `grid`'s box: heights missing, not finite, not
/// below [`MAX_LAYER_COORDINATE`] in magnitude, more than [`MAX_LAYERS`] or outside the box
/// along the axis (where the field through the points is not defined), named with the box; a
/// resolution or tolerance that is not a positive (non-negative) number, or a resolution so
/// fine that a plane's grid would exceed [`MAX_LAYER_NODES`]. Cheap: callers check before
/// fitting.
pub fn check(grid: &Grid, planes: &SectionPlanes) -> Result<(), SliceError> {
    let heights = &planes.heights;
    if heights.is_empty() {
        return Err(SliceError::BadParameter("no section heights given".into()));
    }
    if heights.len() > MAX_LAYERS {
        return Err(SliceError::BadParameter(format!(
            "{} section heights, more than the limit of {MAX_LAYERS}",
            heights.len()
        )));
    }
    let [a, u, v] = planes.axis.indices();
    let name = axis_name(planes.axis);
    let (lo, hi) = (grid.origin, grid.max_corner());
    for &h in heights {
        if !(h.is_finite() && h.abs() < MAX_LAYER_COORDINATE) {
            return Err(SliceError::BadParameter(format!(
                "the section height {h} is not a finite number below {MAX_LAYER_COORDINATE:e} \
                 in magnitude"
            )));
        }
        if !(lo[a]..=hi[a]).contains(&h) {
            return Err(SliceError::BadParameter(format!(
                "the section height {name} = {h} is outside the grid box around the points, \
                 which spans {name} from {} to {}",
                lo[a], hi[a]
            )));
        }
    }
    let res = planes.resolution;
    if !(res.is_finite() && res > 0.0) {
        return Err(SliceError::BadParameter(format!(
            "the sections' resolution must be a positive length, got {res}"
        )));
    }
    if !(planes.tolerance.is_finite() && planes.tolerance >= 0.0) {
        return Err(SliceError::BadParameter(format!(
            "the sections' simplification tolerance must be >= 0, got {}",
            planes.tolerance
        )));
    }
    // As the slicer lays out a plane: the box's cells and a ring of nodes around them.
    let nodes = |k: usize| ((hi[k] - lo[k]) / res).ceil().max(1.0) as f64 + 3.0;
    let (nu, nv) = (nodes(u), nodes(v));
    if nu * nv > MAX_LAYER_NODES as f64 {
        return Err(SliceError::BadParameter(format!(
            "sections at a resolution of {res} sample {nu} x {nv} nodes per plane, more than \
             the limit of {MAX_LAYER_NODES}; use a coarser resolution"
        )));
    }
    Ok(())
}

/// The sections of `field` by the planes of `planes` within `grid`'s box: one layer per
/// distinct height, bottom first, its loops closed with the inside on their left (outer
/// boundaries counter-clockwise, holes clockwise) in the plane's coordinates `(u, v)` of
/// [`Axis`]. A plane that misses the surface gives a layer without loops. The planes are cut in
/// parallel.
pub fn sections(
    field: &PointField,
    grid: &Grid,
    planes: &SectionPlanes,
) -> Result<Vec<Layer>, SliceError> {
    check(grid, planes)?;
    let mut heights = planes.heights.clone();
    heights.sort_by(f32::total_cmp);
    heights.dedup();
    let a = planes.axis.indices()[0];
    let layers: Vec<Result<Layer, SliceError>> = heights
        .par_iter()
        .map(|&h| {
            // The grid box's cross-section at h: the slicer cuts exactly one plane there.
            let (mut lo, mut hi) = (grid.origin, grid.max_corner());
            lo[a] = h;
            hi[a] = h;
            let options = SliceOptions {
                axis: planes.axis,
                layer_height: grid.spacing,
                first: Some(h),
                resolution: planes.resolution,
                tolerance: planes.tolerance,
            };
            let mut layers = pgvol_slice::slice(field, (lo, hi), &options)?;
            debug_assert_eq!(layers.len(), 1);
            Ok(layers.pop().unwrap_or(Layer {
                height: h,
                loops: Vec::new(),
            }))
        })
        .collect();
    layers.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use pgvol_field::CoefficientVolume;

    use super::*;
    use crate::test_points::sphere_points;
    use crate::{reconstruct_with, Method, PointCloud, PointsOptions};

    /// What a section of a unit sphere's reconstruction looked like.
    struct Cut {
        layer: Layer,
        /// The largest |field| at the section's vertices: the field's own, and the resampled
        /// B-spline volume's.
        field_at_vertices: f32,
        volume_at_vertices: f32,
    }

    /// Sections at `heights` of the field `method` fits through `n` points of the unit sphere
    /// (normals given) on a 48³ grid, with the resampled volume's sections at the same planes.
    fn cut_sphere(method: Method, n: usize, heights: &[f32]) -> (Vec<Cut>, Vec<Layer>, f32) {
        let points = sphere_points(n, 1.0);
        let cloud = PointCloud {
            normals: Some(points.clone()),
            points,
        };
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), 48).unwrap();
        let options = PointsOptions {
            method,
            band: 4.0 * grid.spacing,
            support: None,
        };
        let planes = SectionPlanes::new(Axis::Z, heights.to_vec(), grid.spacing);
        let mut cut = None;
        let (volume, _) = reconstruct_with(&cloud, grid, &options, &mut |field| {
            let layers = sections(field, &grid, &planes).unwrap();
            let worst = |layer: &Layer| {
                vertices(layer)
                    .map(|p| field(p).abs())
                    .fold(0.0f32, f32::max)
            };
            let found: Vec<(Layer, f32)> = layers
                .into_iter()
                .map(|l| {
                    let w = worst(&l);
                    (l, w)
                })
                .collect();
            cut = Some(found);
        })
        .unwrap();
        let cuts = cut
            .expect("the field was visited")
            .into_iter()
            .map(|(layer, field_at_vertices)| Cut {
                volume_at_vertices: volume_at(&volume, &layer),
                layer,
                field_at_vertices,
            })
            .collect();
        let bounds = (grid.origin, grid.max_corner());
        let mut sorted = heights.to_vec();
        sorted.sort_by(f32::total_cmp);
        let resampled = sorted
            .iter()
            .map(|&h| {
                let mut options = SliceOptions::new(Axis::Z, 1.0, grid.spacing);
                options.first = Some(h);
                let (mut lo, mut hi) = bounds;
                lo.z = h;
                hi.z = h;
                pgvol_slice::slice_volume(&volume, (lo, hi), &options, pgvol_core::progress::QUIET)
                    .unwrap()
                    .remove(0)
            })
            .collect();
        (cuts, resampled, grid.spacing)
    }

    fn vertices(layer: &Layer) -> impl Iterator<Item = Vec3> + '_ {
        let h = layer.height;
        layer
            .loops
            .iter()
            .flat_map(move |l| l.points.iter().map(move |&[u, v]| Vec3::new(u, v, h)))
    }

    fn volume_at(volume: &CoefficientVolume, layer: &Layer) -> f32 {
        vertices(layer)
            .map(|p| volume.value(p).abs())
            .fold(0.0, f32::max)
    }

    /// Largest distance from a vertex of `a` to the polygon of `b` (one loop each).
    fn distance_to(a: &Layer, b: &Layer) -> f32 {
        let q = &b.loops[0].points;
        let segment = |p: [f32; 2], s: [f32; 2], e: [f32; 2]| {
            let (d, w) = ([e[0] - s[0], e[1] - s[1]], [p[0] - s[0], p[1] - s[1]]);
            let t = ((w[0] * d[0] + w[1] * d[1]) / (d[0] * d[0] + d[1] * d[1])).clamp(0.0, 1.0);
            (w[0] - t * d[0]).hypot(w[1] - t * d[1])
        };
        a.loops[0]
            .points
            .iter()
            .map(|&p| {
                (0..q.len())
                    .map(|i| segment(p, q[i], q[(i + 1) % q.len()]))
                    .fold(f32::INFINITY, f32::min)
            })
            .fold(0.0, f32::max)
    }

    /// Checks a section of the unit sphere at height `h` is one counter-clockwise loop of radius
    /// √(1 − h²); returns the area's and the mean radius's relative errors.
    fn check_circle(cut: &Cut, h: f32, what: &str) -> (f64, f64) {
        let layer = &cut.layer;
        assert_eq!(layer.height, h, "{what}");
        assert_eq!(layer.loops.len(), 1, "{what} at z = {h}: {layer:?}");
        assert!(!layer.loops[0].hole, "{what} at z = {h}");
        let r = (1.0 - h * h).sqrt();
        let radii: Vec<f32> = layer.loops[0]
            .points
            .iter()
            .map(|p| p[0].hypot(p[1]))
            .collect();
        let mean = radii.iter().sum::<f32>() / radii.len() as f32;
        let worst = radii.iter().map(|x| (x - r).abs()).fold(0.0, f32::max);
        let area = layer.area();
        let circle = std::f64::consts::PI * (r * r) as f64;
        let area_error = (area - circle) / circle;
        let radius_error = ((mean - r) / r) as f64;
        eprintln!(
            "{what} z = {h}: {} vertices, area {area:.5} ({:+.3} %), mean radius {mean:.5} \
             ({:+.4} %), worst {worst:.5}, |field| {:.1e}, |volume| {:.1e}",
            radii.len(),
            100.0 * area_error,
            100.0 * radius_error,
            cut.field_at_vertices,
            cut.volume_at_vertices
        );
        assert!(area_error.abs() < 0.01, "{what} at z = {h}: area {area}");
        assert!(
            radius_error.abs() < 0.002,
            "{what} at z = {h}: radius {mean}"
        );
        assert!(
            worst < 0.005,
            "{what} at z = {h}: a vertex {worst} off the circle"
        );
        (area_error, radius_error)
    }

    #[test]
    fn sections_of_the_wendland_field_are_circles_on_its_zero_set() {
        let heights = [0.0, 0.5, -0.5];
        let (cuts, resampled, h) = cut_sphere(Method::RbfWendland, 4000, &heights);
        // Bottom first.
        let order: Vec<f32> = cuts.iter().map(|c| c.layer.height).collect();
        assert_eq!(order, [-0.5, 0.0, 0.5]);
        for (cut, b) in cuts.iter().zip(&resampled) {
            let z = cut.layer.height;
            check_circle(cut, z, "rbf-wendland");
            // The vertices are on the RBF's own zero set, not on the resampled volume's: the
            // volume is off there by more than the root finding's precision.
            assert!(
                cut.field_at_vertices < 2e-5,
                "{z}: {}",
                cut.field_at_vertices
            );
            assert!(
                cut.volume_at_vertices > 5.0 * cut.field_at_vertices,
                "{z}: volume {} field {}",
                cut.volume_at_vertices,
                cut.field_at_vertices
            );
            // Close to the resampled volume's section, computed independently.
            let apart = distance_to(&cut.layer, b).max(distance_to(b, &cut.layer));
            eprintln!(
                "z = {z}: {apart:.2e} from the volume's section ({} h)",
                apart / h
            );
            assert!(apart < 0.15 * h, "{z}: {apart}");
            assert_ne!(cut.layer, *b);
        }
    }

    #[test]
    fn sections_of_the_cubic_rbf_are_circles_on_its_zero_set() {
        let (cuts, _, _) = cut_sphere(Method::RbfCubic, 1000, &[0.0, 0.5]);
        for cut in &cuts {
            check_circle(cut, cut.layer.height, "rbf-cubic");
            assert!(cut.field_at_vertices < 2e-5, "{}", cut.field_at_vertices);
        }
    }

    #[test]
    fn a_plane_missing_the_surface_gives_an_empty_layer() {
        // The grid box reaches 1.1 from the centre; the sphere 1.
        let (cuts, _, _) = cut_sphere(Method::Spline, 2000, &[1.05]);
        assert!(cuts[0].layer.loops.is_empty(), "{:?}", cuts[0].layer);
    }

    #[test]
    fn heights_outside_the_box_or_not_finite_are_refused_by_value() {
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), 16).unwrap();
        let planes = |axis: Axis, heights: Vec<f32>, res: f32| {
            check(&grid, &SectionPlanes::new(axis, heights, res)).map_err(|e| e.to_string())
        };
        let at = |h: f32| planes(Axis::Y, vec![0.0, h], 0.1);
        let (lo, hi) = (grid.origin.y, grid.max_corner().y);
        assert!(at(lo).is_ok() && at(hi).is_ok());
        let e = at(1.2).unwrap_err();
        assert!(
            e.contains("y = 1.2") && e.contains(&format!("from {lo} to {hi}")),
            "{e}"
        );
        assert!(at(hi + 1e-3).is_err() && at(lo - 1e-3).is_err());
        for bad in [f32::NAN, f32::INFINITY, -2e8] {
            let e = at(bad).unwrap_err();
            assert!(e.contains("not a finite number below 1e8"), "{e}");
        }
        let e = planes(Axis::Z, vec![], 0.1).unwrap_err();
        assert!(e.contains("no section heights"), "{e}");
        for res in [0.0, -1.0, f32::NAN] {
            let e = planes(Axis::Z, vec![0.0], res).unwrap_err();
            assert!(e.contains("resolution must be a positive length"), "{e}");
        }
        let e = planes(Axis::Z, vec![0.0], 1e-4).unwrap_err();
        assert!(
            e.contains("nodes per plane") && e.contains("coarser"),
            "{e}"
        );
    }
}
