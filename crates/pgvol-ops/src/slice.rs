//! Planar slices of a field: marching squares on a fine 2D grid per layer, vertices on the
//! continuous field, loops traced with the inside on their left.

use glam::Vec3;
use pgvol_field::kernel::{axis_window, AxisWindow, Profile};
use pgvol_field::{mirror, Basis, CoefficientVolume};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::OpsError;
use crate::polygon::signed_area;
use crate::simplify::simplify_loops;

/// Most layers one call produces: far beyond any printer, small enough to refuse typos.
pub const MAX_LAYERS: usize = 1_000_000;

/// Most nodes in one layer's 2D grid (a 16384² grid would need 1 GiB per layer in flight).
pub const MAX_LAYER_NODES: usize = 1 << 26;

/// Vertices keep this fraction of their grid edge from its ends, so no segment touches a node
/// and segments of different cells meet only at shared vertices.
const EDGE_MARGIN: f32 = 1e-3;

/// The build direction. Layer coordinates `(u, v)` are the next two axes in cyclic order
/// (X: `(y, z)`, Y: `(z, x)`, Z: `(x, y)`), so `u × v` points along the axis and
/// counter-clockwise means counter-clockwise seen from the positive side of the axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    X,
    Y,
    #[default]
    Z,
}

impl Axis {
    /// Indices of (axis, u, v) in a `Vec3`.
    pub fn indices(self) -> [usize; 3] {
        match self {
            Axis::X => [0, 1, 2],
            Axis::Y => [1, 2, 0],
            Axis::Z => [2, 0, 1],
        }
    }

    /// The 3D point at height `h` and layer coordinates `(u, v)`.
    fn point(self, h: f32, u: f32, v: f32) -> Vec3 {
        let [a, b, c] = self.indices();
        let mut p = [0.0f32; 3];
        p[a] = h;
        p[b] = u;
        p[c] = v;
        Vec3::from_array(p)
    }
}

/// How to slice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceOptions {
    pub axis: Axis,
    /// Distance between layer planes, > 0.
    pub layer_height: f32,
    /// Height of the first plane; `None` for half a layer above the bottom of the bounds, so
    /// each plane sits in the middle of the slab it stands for.
    pub first: Option<f32>,
    /// Spacing of the 2D grid the contours are extracted on, > 0. Features thinner than about
    /// one spacing may be missed; the field's own grid spacing is a sensible start.
    pub resolution: f32,
    /// Largest distance a simplified loop may move away from any vertex of the extracted one;
    /// 0 keeps every vertex.
    pub tolerance: f32,
}

impl SliceOptions {
    /// Slicing along `axis` with the first plane half a layer above the bottom and a
    /// simplification tolerance of a tenth of `resolution`.
    pub fn new(axis: Axis, layer_height: f32, resolution: f32) -> Self {
        SliceOptions {
            axis,
            layer_height,
            first: None,
            resolution,
            tolerance: resolution / 10.0,
        }
    }
}

/// One closed contour. The last point is not repeated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Loop {
    /// Layer coordinates `(u, v)` (see [`Axis`]).
    pub points: Vec<[f32; 2]>,
    /// A hole: clockwise, with the solid on its outside. Outer boundaries (including islands
    /// inside holes) are counter-clockwise.
    pub hole: bool,
}

/// The contours of one plane.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Layer {
    /// Position of the plane along the axis.
    pub height: f32,
    pub loops: Vec<Loop>,
}

/// The box of a volume's grid, the natural bounds for [`slice_volume`].
pub fn volume_bounds(volume: &CoefficientVolume) -> (Vec3, Vec3) {
    (volume.grid.origin, volume.grid.max_corner())
}

/// The plane heights for `bounds` and `options`: `first + i · layer_height` (computed in f64,
/// rounded once) for `i = 0, 1, …` while not above the top of the bounds.
pub fn layer_heights(bounds: (Vec3, Vec3), options: &SliceOptions) -> Result<Vec<f32>, OpsError> {
    let a = options.axis.indices()[0];
    let (lo, hi) = (bounds.0[a] as f64, bounds.1[a] as f64);
    let step = options.layer_height as f64;
    if !(step.is_finite() && step > 0.0) {
        return Err(OpsError::BadParameter(format!(
            "layer height must be positive, got {}",
            options.layer_height
        )));
    }
    let first = options.first.map_or(lo + step / 2.0, |f| f as f64);
    if !first.is_finite() {
        return Err(OpsError::BadParameter(
            "first layer height is not finite".into(),
        ));
    }
    let mut count = if first > hi {
        0.0
    } else {
        ((hi - first) / step).floor() + 1.0
    };
    if count > MAX_LAYERS as f64 {
        return Err(OpsError::BadParameter(format!(
            "{count} layers, more than the limit of {MAX_LAYERS}"
        )));
    }
    // The division may round either way; settle the count on the products themselves.
    while count > 0.0 && first + (count - 1.0) * step > hi {
        count -= 1.0;
    }
    while first + count * step <= hi {
        count += 1.0;
    }
    let heights: Vec<f32> = (0..count as usize)
        .map(|i| (first + i as f64 * step) as f32)
        .collect();
    Ok(heights)
}

/// Slices a coefficient volume; see [`slice`]. For the separable bases each layer first
/// collapses the coefficients along the axis into a 2D spline (4 nodes per column for the cubic
/// B-spline), so a layer node costs 16 terms instead of 64; values are those of
/// [`CoefficientVolume::value`] up to float rounding, outside the grid box included.
pub fn slice_volume(
    volume: &CoefficientVolume,
    bounds: (Vec3, Vec3),
    options: &SliceOptions,
) -> Result<Vec<Layer>, OpsError> {
    slice_volume_range(volume, bounds, options, 0..usize::MAX)
}

/// The layers of [`slice_volume`] numbered `range` (from 0 at the first plane), each the same
/// as in the whole slicing: every layer is computed alone from its own plane, so layers can be
/// sliced in parts and concatenated. A layer needs only the coefficients within the basis
/// support of its plane.
pub fn slice_volume_range(
    volume: &CoefficientVolume,
    bounds: (Vec3, Vec3),
    options: &SliceOptions,
    range: std::ops::Range<usize>,
) -> Result<Vec<Layer>, OpsError> {
    let profile = match volume.basis {
        Basis::Trilinear => Profile::Linear,
        Basis::Bspline2 => Profile::Quadratic,
        Basis::Bspline3 => Profile::Cubic,
        Basis::Pg { .. } => {
            let field = &|p| volume.value(p);
            let axis = options.axis;
            return slice_layers(bounds, options, range, &|h| PointField { field, axis, h });
        }
    };
    slice_layers(bounds, options, range, &|h| {
        CollapsedPlane::new(volume, profile, options.axis, h)
    })
}

/// A separable coefficient volume restricted to one axis-aligned plane: the coefficients summed
/// along the axis with the plane's weights, evaluated as a 2D spline plus the distance to the
/// grid box, as [`CoefficientVolume::value`] does.
struct CollapsedPlane {
    coeffs: Vec<f32>,
    dims: [usize; 2],
    origin: [f32; 2],
    spacing: f32,
    profile: Profile,
    /// Distance of the plane from the grid box along the axis.
    off_axis: f32,
}

impl CollapsedPlane {
    fn new(volume: &CoefficientVolume, profile: Profile, axis: Axis, h: f32) -> Self {
        let g = &volume.grid;
        let [a, b, c] = axis.indices();
        let (lo, hi) = (g.origin[a], g.max_corner()[a]);
        let q = h.clamp(lo, hi);
        let window = axis_window(profile, (q - lo) / g.spacing, g.dims[a]);
        let dims = [g.dims[b], g.dims[c]];
        let mut coeffs = vec![0.0f32; dims[0] * dims[1]];
        for t in 0..window.len {
            let w = window.w[t][0];
            let layer = mirror(window.first + t as i64, g.dims[a]);
            for iv in 0..dims[1] {
                for (iu, out) in coeffs[iv * dims[0]..(iv + 1) * dims[0]]
                    .iter_mut()
                    .enumerate()
                {
                    let mut n = [0; 3];
                    (n[a], n[b], n[c]) = (layer, iu, iv);
                    *out += w * volume.coeffs.get(n);
                }
            }
        }
        CollapsedPlane {
            coeffs,
            dims,
            origin: [g.origin[b], g.origin[c]],
            spacing: g.spacing,
            profile,
            off_axis: h - q,
        }
    }

    /// The clamped grid coordinate along layer axis `k`, with the distance beyond the box.
    fn window(&self, k: usize, x: f32) -> (AxisWindow, f32) {
        let top = self.origin[k] + self.spacing * (self.dims[k] - 1) as f32;
        let q = x.clamp(self.origin[k], top);
        let w = axis_window(
            self.profile,
            (q - self.origin[k]) / self.spacing,
            self.dims[k],
        );
        (w, x - q)
    }
}

impl LayerField for CollapsedPlane {
    /// Rows of nodes share their v weights and columns their u weights: each row is first
    /// collapsed to a line of coefficients along u, then each node takes 4 terms.
    fn sample(&self, us: &[f32], vs: &[f32], out: &mut [f32]) {
        let wus: Vec<(AxisWindow, f32)> = us.iter().map(|&u| self.window(0, u)).collect();
        let mut line = vec![0.0f32; self.dims[0]];
        for (j, &v) in vs.iter().enumerate() {
            let (wv, dv) = self.window(1, v);
            line.fill(0.0);
            for t in 0..wv.len {
                let row = mirror(wv.first + t as i64, self.dims[1]) * self.dims[0];
                let w = wv.w[t][0];
                for (l, c) in line.iter_mut().zip(&self.coeffs[row..row + self.dims[0]]) {
                    *l += w * c;
                }
            }
            for (i, (wu, du)) in wus.iter().enumerate() {
                let mut value = 0.0f32;
                for r in 0..wu.len {
                    value += wu.w[r][0] * line[mirror(wu.first + r as i64, self.dims[0])];
                }
                let outside = Vec3::new(*du, dv, self.off_axis).length();
                out[i + us.len() * j] = value + outside;
            }
        }
    }

    fn value(&self, u: f32, v: f32) -> f32 {
        let h = self.spacing;
        let top = |k: usize| self.origin[k] + h * (self.dims[k] - 1) as f32;
        let (qu, qv) = (
            u.clamp(self.origin[0], top(0)),
            v.clamp(self.origin[1], top(1)),
        );
        let wu = axis_window(self.profile, (qu - self.origin[0]) / h, self.dims[0]);
        let wv = axis_window(self.profile, (qv - self.origin[1]) / h, self.dims[1]);
        let mut value = 0.0f32;
        for t in 0..wv.len {
            let row = mirror(wv.first + t as i64, self.dims[1]) * self.dims[0];
            let mut s = 0.0f32;
            for r in 0..wu.len {
                s += wu.w[r][0] * self.coeffs[row + mirror(wu.first + r as i64, self.dims[0])];
            }
            value += wv.w[t][0] * s;
        }
        let outside = Vec3::new(u - qu, v - qv, self.off_axis).length();
        value + outside
    }
}

/// Cuts the solid `field < 0` by the planes of [`layer_heights`] within `bounds`.
///
/// Per layer the field is sampled on a 2D grid of spacing `options.resolution` covering the
/// bounds (centred on them), surrounded by one ring of nodes counted as outside so every loop
/// closes (a solid cut by the bounds is closed less than one spacing outside them). Each crossed grid edge gets one vertex, placed at the zero of the field along the edge
/// (regula falsi, Illinois) and kept a little away from the nodes; ambiguous cells are split by
/// the asymptotic decider (the sign of the bilinear interpolant at its saddle). Hence, before
/// simplification, the loops of a layer are closed, simple and pairwise disjoint. They are
/// traced with the inside on their left: outer boundaries counter-clockwise, holes clockwise.
/// [`simplify_loops`] then reduces them to `options.tolerance` keeping these properties.
///
/// Non-finite field values count as outside. Layers run in parallel; the output does not depend
/// on the number of threads.
pub fn slice(
    field: &(dyn Fn(Vec3) -> f32 + Sync),
    bounds: (Vec3, Vec3),
    options: &SliceOptions,
) -> Result<Vec<Layer>, OpsError> {
    let axis = options.axis;
    slice_layers(bounds, options, 0..usize::MAX, &|h| PointField {
        field,
        axis,
        h,
    })
}

/// The field on one layer plane.
trait LayerField {
    fn value(&self, u: f32, v: f32) -> f32;

    /// Values at the nodes `(us[i], vs[j])` into `out[i + us.len() · j]`.
    fn sample(&self, us: &[f32], vs: &[f32], out: &mut [f32]) {
        for (j, &v) in vs.iter().enumerate() {
            for (i, &u) in us.iter().enumerate() {
                out[i + us.len() * j] = self.value(u, v);
            }
        }
    }
}

struct PointField<'a> {
    field: &'a (dyn Fn(Vec3) -> f32 + Sync),
    axis: Axis,
    h: f32,
}

impl LayerField for PointField<'_> {
    fn value(&self, u: f32, v: f32) -> f32 {
        (self.field)(self.axis.point(self.h, u, v))
    }
}

/// [`slice`] with the field of each layer made by `layer_field(height)`.
fn slice_layers<G: LayerField>(
    bounds: (Vec3, Vec3),
    options: &SliceOptions,
    range: std::ops::Range<usize>,
    layer_field: &(dyn Fn(f32) -> G + Sync),
) -> Result<Vec<Layer>, OpsError> {
    if !(bounds.0.is_finite() && bounds.1.is_finite() && bounds.0.cmple(bounds.1).all()) {
        return Err(OpsError::BadParameter(
            "slice bounds must be finite with min <= max".into(),
        ));
    }
    let res = options.resolution;
    if !(res.is_finite() && res > 0.0) {
        return Err(OpsError::BadParameter(format!(
            "slice resolution must be positive, got {res}"
        )));
    }
    if !(options.tolerance.is_finite() && options.tolerance >= 0.0) {
        return Err(OpsError::BadParameter(format!(
            "simplification tolerance must be >= 0, got {}",
            options.tolerance
        )));
    }
    let [_, iu, iv] = options.axis.indices();
    let plane = Plane::new(
        (bounds.0[iu], bounds.1[iu]),
        (bounds.0[iv], bounds.1[iv]),
        res,
    )?;
    let mut heights = layer_heights(bounds, options)?;
    heights.truncate(range.end);
    heights.drain(..range.start.min(heights.len()));
    Ok(heights
        .into_par_iter()
        .map(|h| {
            let raw = plane.contours(&layer_field(h));
            let loops = simplify_loops(&raw, options.tolerance)
                .into_iter()
                .map(|points| {
                    let hole = signed_area(&points) < 0.0;
                    Loop { points, hole }
                })
                .collect();
            Layer { height: h, loops }
        })
        .collect())
}

/// A layer's 2D grid: `n[0] × n[1]` nodes at `origin + spacing · (i − 1, j − 1)`, the outer ring
/// artificial.
struct Plane {
    origin: [f32; 2],
    spacing: f32,
    n: [usize; 2],
}

impl Plane {
    fn new(u: (f32, f32), v: (f32, f32), spacing: f32) -> Result<Plane, OpsError> {
        let axis = |(lo, hi): (f32, f32)| {
            let cells = ((hi - lo) / spacing).ceil().max(1.0);
            let origin = (lo + hi) * 0.5 - cells * spacing * 0.5;
            (origin, cells as f64 + 3.0)
        };
        let (ou, nu) = axis(u);
        let (ov, nv) = axis(v);
        if nu * nv > MAX_LAYER_NODES as f64 {
            return Err(OpsError::BadParameter(format!(
                "a layer grid of {nu} x {nv} nodes exceeds the limit of {MAX_LAYER_NODES}; \
                 use a coarser resolution"
            )));
        }
        Ok(Plane {
            origin: [ou, ov],
            spacing,
            n: [nu as usize, nv as usize],
        })
    }

    fn node(&self, i: usize, j: usize) -> [f32; 2] {
        [
            self.origin[0] + self.spacing * (i as f32 - 1.0),
            self.origin[1] + self.spacing * (j as f32 - 1.0),
        ]
    }

    /// The closed loops of `f(u, v) < 0`, inside on the left, in a deterministic order.
    fn contours(&self, field: &impl LayerField) -> Vec<Vec<[f32; 2]>> {
        let f = |u, v| field.value(u, v);
        let [nu, nv] = self.n;
        let h = self.spacing;
        // Node values; `real` is false on the ring and where the field is not finite, whose
        // values are stand-ins (±h) and whose edges are cut by linear interpolation.
        let us: Vec<f32> = (1..nu - 1).map(|i| self.node(i, 0)[0]).collect();
        let vs: Vec<f32> = (1..nv - 1).map(|j| self.node(0, j)[1]).collect();
        let mut inner = vec![0.0f32; us.len() * vs.len()];
        field.sample(&us, &vs, &mut inner);
        let mut values = vec![h; nu * nv];
        let mut real = vec![false; nu * nv];
        for j in 1..nv - 1 {
            for i in 1..nu - 1 {
                let x = inner[i - 1 + us.len() * (j - 1)];
                let k = i + nu * j;
                if x.is_finite() {
                    values[k] = x;
                    real[k] = true;
                } else if x == f32::NEG_INFINITY {
                    values[k] = -h;
                }
            }
        }
        let inside = |k: usize| values[k] < 0.0;

        // One vertex per crossed edge: edge id 2·node for +u, 2·node + 1 for +v.
        let mut vertex_of = vec![u32::MAX; 2 * nu * nv];
        let mut vertices: Vec<[f32; 2]> = Vec::new();
        for j in 0..nv {
            for i in 0..nu {
                let a = i + nu * j;
                for (dir, ok, b) in [(0, i + 1 < nu, a + 1), (1, j + 1 < nv, a + nu)] {
                    if !ok || inside(a) == inside(b) {
                        continue;
                    }
                    let (va, vb) = (values[a], values[b]);
                    let t = if real[a] && real[b] {
                        let pa = self.node(i, j);
                        let step = [h * (1 - dir) as f32, h * dir as f32];
                        let g = |t: f32| f(pa[0] + step[0] * t, pa[1] + step[1] * t);
                        edge_root(&g, va, vb)
                    } else {
                        va / (va - vb)
                    };
                    let t = t.clamp(EDGE_MARGIN, 1.0 - EDGE_MARGIN);
                    let [u, v] = self.node(i, j);
                    vertex_of[2 * a + dir] = vertices.len() as u32;
                    vertices.push(if dir == 0 {
                        [u + h * t, v]
                    } else {
                        [u, v + h * t]
                    });
                }
            }
        }

        // Each vertex has exactly one outgoing segment: along a shared edge the counter-clockwise
        // orders of the two cells are opposite, so a crossing starts a segment in one cell and
        // ends one in the other.
        let mut next = vec![u32::MAX; vertices.len()];
        for j in 0..nv - 1 {
            for i in 0..nu - 1 {
                let c = [
                    i + nu * j,
                    i + 1 + nu * j,
                    i + 1 + nu * (j + 1),
                    i + nu * (j + 1),
                ];
                let ins = c.map(inside);
                if ins.iter().all(|&x| x) || ins.iter().all(|&x| !x) {
                    continue;
                }
                // Cell edges counter-clockwise: corner k to corner k + 1.
                let edges = [2 * c[0], 2 * c[1] + 1, 2 * c[3], 2 * c[0] + 1];
                let vert = |e: usize| vertex_of[edges[e]];
                let starts = (0..4).filter(|&k| ins[k] && !ins[(k + 1) % 4]);
                let ambiguous = ins[0] == ins[2] && ins[1] == ins[3];
                if ambiguous {
                    let v = c.map(|k| values[k] as f64);
                    // The bilinear interpolant's saddle; the denominator is non-zero here since
                    // the diagonals have opposite signs.
                    let saddle = (v[0] * v[2] - v[1] * v[3]) / (v[0] + v[2] - v[1] - v[3]);
                    // Inside joined through the centre: each start meets the next edge;
                    // otherwise the previous one, cutting off the inside corner.
                    let turn = if saddle < 0.0 { 1 } else { 3 };
                    for k in starts {
                        next[vert(k) as usize] = vert((k + turn) % 4);
                    }
                } else {
                    let end = (0..4).find(|&k| !ins[k] && ins[(k + 1) % 4]);
                    if let (Some(k), Some(e)) = (starts.into_iter().next(), end) {
                        next[vert(k) as usize] = vert(e);
                    }
                }
            }
        }

        let mut seen = vec![false; vertices.len()];
        let mut loops = Vec::new();
        for s in 0..vertices.len() {
            if seen[s] {
                continue;
            }
            let mut points = Vec::new();
            let mut k = s;
            while !seen[k] {
                seen[k] = true;
                points.push(vertices[k]);
                k = next[k] as usize;
            }
            loops.push(points);
        }
        loops
    }
}

/// The zero of `g` on [0, 1] given `g(0) = va`, `g(1) = vb` of opposite signs: regula falsi with
/// the Illinois modification, which keeps the bracket and converges superlinearly.
fn edge_root(g: &dyn Fn(f32) -> f32, va: f32, vb: f32) -> f32 {
    let (mut t0, mut f0, mut t1, mut f1) = (0.0f32, va, 1.0f32, vb);
    let mut side = 0i8;
    let mut t = f0 / (f0 - f1);
    for _ in 0..12 {
        t = t0 - f0 * (t1 - t0) / (f1 - f0);
        if !t.is_finite() {
            return 0.5 * (t0 + t1);
        }
        let ft = g(t);
        if ft == 0.0 || (t1 - t0) < 1e-6 || !ft.is_finite() {
            break;
        }
        if (ft < 0.0) == (f1 < 0.0) {
            t1 = t;
            f1 = ft;
            if side == -1 {
                f0 *= 0.5;
            }
            side = -1;
        } else {
            t0 = t;
            f0 = ft;
            if side == 1 {
                f1 *= 0.5;
            }
            side = 1;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use pgvol_field::Grid;

    #[test]
    fn collapsed_planes_match_the_volume() {
        let grid = Grid {
            origin: Vec3::new(-1.0, -0.8, -0.6),
            spacing: 0.1,
            dims: [21, 15, 13],
            offset: Default::default(),
        };
        let mut samples = Vec::with_capacity(grid.len());
        for k in 0..grid.dims[2] {
            for j in 0..grid.dims[1] {
                for i in 0..grid.dims[0] {
                    let p = grid.point(i, j, k);
                    samples.push((2.0 * p.x).sin() * p.y + p.z * p.z - 0.1);
                }
            }
        }
        for (basis, profile) in [
            (Basis::Trilinear, Profile::Linear),
            (Basis::Bspline2, Profile::Quadratic),
            (Basis::Bspline3, Profile::Cubic),
        ] {
            let vol = CoefficientVolume::interpolate(grid, basis, samples.clone()).unwrap();
            for axis in [Axis::X, Axis::Y, Axis::Z] {
                for h in [-1.3f32, -0.6, -0.137, 0.0, 0.42, 0.6, 1.7] {
                    let plane = CollapsedPlane::new(&vol, profile, axis, h);
                    let us = [-2.0, -0.33, 0.0, 0.5, 1.9];
                    let vs = [-0.2, 0.0, 0.5, 0.71, 2.0];
                    let mut batch = [0.0f32; 25];
                    plane.sample(&us, &vs, &mut batch);
                    for (j, &v) in vs.iter().enumerate() {
                        for (i, &u) in us.iter().enumerate() {
                            let want = vol.value(axis.point(h, u, v));
                            for got in [plane.value(u, v), batch[i + 5 * j]] {
                                assert!(
                                    (want - got).abs() < 1e-5,
                                    "{basis:?} {axis:?} h={h} ({u}, {v}): {got} vs {want}"
                                );
                            }
                        }
                    }
                }
            }
        }
    }
}
