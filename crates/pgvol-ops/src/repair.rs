//! Restoring a field inside axis-aligned masks: removing a protrusion by a least-squares
//! Laplace fill, or smoothing noise by coarse resampling, then re-fitting only the
//! coefficients whose support meets the mask.
//!
//! Protrusion removal (after Interactive restoration of implicit surfaces): the node values
//! inside the mask are the least-squares solution of "the discrete Laplacian is zero at every
//! node of the mask", with the field's own values on the layer of nodes around the mask as
//! Dirichlet conditions, and on the mask's layer next to the face the protrusion's base crosses
//! the values fixed to the outer neighbour's plus `alpha·h` (a normal derivative: larger alpha
//! lowers the cap toward a flat one). With every Dirichlet value known the system's square part
//! is the Dirichlet Laplacian, which is non-singular, so the overdetermined system has full
//! column rank and one solution; CGLS finds it. A mask reaching the grid's border has no
//! outer layer there: its border layer becomes the Dirichlet layer, with values interpolated
//! linearly across it from its rim (the mean of the interpolations along its two axes).
//!
//! Denoising samples the field on a coarse lattice over the mask, interpolates the samples
//! with the quadratic B-spline and takes that interpolant's values at the mask's nodes.

use glam::Vec3;
use pgvol_field::fit::solve::cgls;
use pgvol_field::{Basis, CoefficientVolume, Grid};

use crate::error::OpsError;
use crate::local_fit::{node_value, refit_box, LocalFit, NodeBox};

/// Masks larger than this many nodes are refused: the solve holds a few arrays of f64 per node
/// and its iterations grow with the mask's side.
pub const MAX_MASK_NODES: usize = 1 << 22;

/// An axis-aligned box in world coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mask {
    pub lo: Vec3,
    pub hi: Vec3,
}

/// A face of a mask: the axis (0 = x, 1 = y, 2 = z) and whether it is the upper one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Face {
    pub axis: usize,
    pub upper: bool,
}

/// What to do inside the masks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Restore {
    /// Replace a protrusion whose base crosses `face` with a smooth cap.
    Protrusion { face: Face, alpha: f32 },
    /// Resample with `coarse` samples along the mask's longest side.
    Denoise { coarse: usize },
}

/// What the repair did in one mask.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaskReport {
    /// Nodes whose values were restored.
    pub nodes: usize,
    /// CGLS iterations of the Laplace fill (0 when denoising).
    pub iterations: usize,
    pub refit: LocalFit,
}

/// The nodes strictly inside `mask` on `grid`, or an error naming the mask.
pub fn mask_nodes(grid: &Grid, mask: &Mask) -> Result<NodeBox, OpsError> {
    let bad = |why: &str| {
        OpsError::BadParameter(format!(
            "mask {},{},{},{},{},{}: {why}",
            mask.lo.x, mask.lo.y, mask.lo.z, mask.hi.x, mask.hi.y, mask.hi.z
        ))
    };
    if !(mask.lo.is_finite() && mask.hi.is_finite()) || mask.hi.cmplt(mask.lo).any() {
        return Err(bad(
            "the box needs finite corners with x1 ≥ x0, y1 ≥ y0, z1 ≥ z0",
        ));
    }
    let u0 = (mask.lo - grid.origin) / grid.spacing;
    let u1 = (mask.hi - grid.origin) / grid.spacing;
    let mut lo = [0; 3];
    let mut hi = [0; 3];
    for a in 0..3 {
        let n = grid.dims[a] as f32;
        let l = u0[a].ceil().max(0.0);
        let h = u1[a].floor().min(n - 1.0);
        if h < l {
            return Err(bad(
                "it holds no grid node (it lies outside the grid or is thinner than \
                 one spacing)",
            ));
        }
        lo[a] = l as usize;
        hi[a] = h as usize;
    }
    let nodes = NodeBox { lo, hi };
    if nodes.count() > MAX_MASK_NODES {
        return Err(bad(&format!(
            "it holds {} nodes, more than the {MAX_MASK_NODES} a mask may; use a smaller box",
            nodes.count()
        )));
    }
    Ok(nodes)
}

/// The field restored inside every mask; coefficients whose support misses all masks are
/// unchanged bit for bit.
pub fn repair(
    volume: &CoefficientVolume,
    masks: &[Mask],
    restore: Restore,
) -> Result<(CoefficientVolume, Vec<MaskReport>), OpsError> {
    if masks.is_empty() {
        return Err(OpsError::BadParameter("give at least one mask".into()));
    }
    let mut out = volume.clone();
    let mut reports = Vec::with_capacity(masks.len());
    for mask in masks {
        let nodes = mask_nodes(&volume.grid, mask)?;
        let (region, values, iterations) = match restore {
            Restore::Protrusion { face, alpha } => {
                let (region, values, iterations) = laplace_fill(&out, &nodes, face, alpha)?;
                (region, values, iterations)
            }
            Restore::Denoise { coarse } => (nodes, coarse_resample(&out, mask, &nodes, coarse)?, 0),
        };
        let refit = refit_box(&mut out, &region, &values)?;
        reports.push(MaskReport {
            nodes: region.count(),
            iterations,
            refit,
        });
    }
    Ok((out, reports))
}

/// The local problem of a protrusion fill: the box of nodes with its Dirichlet shell, which of
/// them are known, and their values.
pub struct LaplaceSystem {
    /// The mask's nodes and the layer around them.
    pub outer: NodeBox,
    /// Per node of `outer`: its value (known nodes) or 0.
    pub known: Vec<f32>,
    /// Per node of `outer`: the unknown's number, or `None` when known.
    pub unknown: Vec<Option<usize>>,
    /// Nodes of `outer` whose Laplacian is a row: every node strictly inside it.
    pub rows: Vec<usize>,
    pub unknowns: usize,
}

impl LaplaceSystem {
    /// The system for the mask's `nodes`, reading the field's node values around them.
    pub fn new(
        volume: &CoefficientVolume,
        nodes: &NodeBox,
        face: Face,
        alpha: f32,
    ) -> Result<LaplaceSystem, OpsError> {
        if face.axis > 2 || !alpha.is_finite() {
            return Err(OpsError::BadParameter(format!(
                "the face axis must be 0, 1 or 2 and alpha finite, got {} and {alpha}",
                face.axis
            )));
        }
        let dims = volume.grid.dims;
        // The layer around the mask; at the grid's border the mask's own border layer.
        let outer = nodes.grown(1, dims);
        let od = outer.dims();
        if od.iter().any(|&d| d < 3) {
            return Err(OpsError::BadParameter(
                "the mask needs at least one node inside its Dirichlet layer along every axis; \
                 make it wider than one grid spacing"
                    .into(),
            ));
        }
        let mut known = vec![0.0f32; outer.count()];
        let mut is_known = vec![false; outer.count()];
        let on_shell = |n: [usize; 3]| (0..3).any(|a| n[a] == outer.lo[a] || n[a] == outer.hi[a]);
        for i in 0..outer.count() {
            let n = outer.node(i);
            if on_shell(n) {
                known[i] = node_value(volume, n)?;
                is_known[i] = true;
            }
        }
        // Shell faces on the grid's border were part of the mask: interpolate across them.
        for (a, &n) in dims.iter().enumerate() {
            for (side, border) in [
                (outer.lo[a], nodes.lo[a] == 0),
                (outer.hi[a], nodes.hi[a] == n - 1),
            ] {
                if border {
                    interpolate_face(&outer, &mut known, a, side);
                }
            }
        }
        // The layer next to the face the protrusion's base crosses.
        let a = face.axis;
        let (layer, beyond) = if face.upper {
            (outer.hi[a] - 1, outer.hi[a])
        } else {
            (outer.lo[a] + 1, outer.lo[a])
        };
        let h = volume.grid.spacing;
        for i in 0..outer.count() {
            let n = outer.node(i);
            if n[a] == layer && !on_shell(n) {
                let mut m = n;
                m[a] = beyond;
                known[i] = known[outer.index(m)] + alpha * h;
                is_known[i] = true;
            }
        }
        let mut unknown = vec![None; outer.count()];
        let mut unknowns = 0;
        let mut rows = Vec::new();
        for i in 0..outer.count() {
            if !on_shell(outer.node(i)) {
                rows.push(i);
            }
            if !is_known[i] {
                unknown[i] = Some(unknowns);
                unknowns += 1;
            }
        }
        Ok(LaplaceSystem {
            outer,
            known,
            unknown,
            rows,
            unknowns,
        })
    }

    fn neighbours(&self, i: usize) -> [usize; 6] {
        let n = self.outer.node(i);
        let at = |a: usize, d: i64| {
            let mut m = n;
            m[a] = (m[a] as i64 + d) as usize;
            self.outer.index(m)
        };
        [
            at(0, -1),
            at(0, 1),
            at(1, -1),
            at(1, 1),
            at(2, -1),
            at(2, 1),
        ]
    }

    /// The Laplacians at the rows of the field with `x` at the unknowns and `fixed` (0 or 1)
    /// times the known values elsewhere.
    fn apply(&self, x: &[f64], fixed: f64) -> Vec<f64> {
        let value = |i: usize| match self.unknown[i] {
            Some(u) => x[u],
            None => fixed * self.known[i] as f64,
        };
        self.rows
            .iter()
            .map(|&i| {
                let s: f64 = self.neighbours(i).iter().map(|&m| value(m)).sum();
                (s - 6.0 * value(i)) / 6.0
            })
            .collect()
    }

    /// The Laplacian rows applied to the unknowns alone.
    pub fn forward(&self, x: &[f64]) -> Vec<f64> {
        self.apply(x, 0.0)
    }

    /// The transpose of [`LaplaceSystem::forward`].
    pub fn adjoint(&self, r: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.unknowns];
        for (&i, &ri) in self.rows.iter().zip(r) {
            if let Some(u) = self.unknown[i] {
                y[u] -= ri;
            }
            for m in self.neighbours(i) {
                if let Some(u) = self.unknown[m] {
                    y[u] += ri / 6.0;
                }
            }
        }
        y
    }

    /// The right-hand side: minus the known values' Laplacians.
    pub fn rhs(&self) -> Vec<f64> {
        self.apply(&vec![0.0; self.unknowns], 1.0)
            .into_iter()
            .map(|v| -v)
            .collect()
    }
}

/// Replaces the values of the face `axis = side` of `outer` inside its rim by the mean of the
/// linear interpolations between the rim values along the face's two axes.
fn interpolate_face(outer: &NodeBox, known: &mut [f32], axis: usize, side: usize) {
    let (u, v) = match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let at = |pu: usize, pv: usize| {
        let mut n = [0; 3];
        n[axis] = side;
        n[u] = pu;
        n[v] = pv;
        outer.index(n)
    };
    let (u0, u1, v0, v1) = (outer.lo[u], outer.hi[u], outer.lo[v], outer.hi[v]);
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let mut fresh = Vec::new();
    for pv in v0 + 1..v1 {
        for pu in u0 + 1..u1 {
            let tu = (pu - u0) as f32 / (u1 - u0) as f32;
            let tv = (pv - v0) as f32 / (v1 - v0) as f32;
            let along_u = lerp(known[at(u0, pv)], known[at(u1, pv)], tu);
            let along_v = lerp(known[at(pu, v0)], known[at(pu, v1)], tv);
            fresh.push((at(pu, pv), 0.5 * (along_u + along_v)));
        }
    }
    for (i, x) in fresh {
        known[i] = x;
    }
}

/// The least-squares Laplace fill of a mask: the region to re-fit (the mask's nodes, with the
/// Dirichlet layer) with its new values, and the CGLS iterations.
fn laplace_fill(
    volume: &CoefficientVolume,
    nodes: &NodeBox,
    face: Face,
    alpha: f32,
) -> Result<(NodeBox, Vec<f32>, usize), OpsError> {
    let system = LaplaceSystem::new(volume, nodes, face, alpha)?;
    let b = system.rhs();
    let (x, outcome) = cgls(
        |x| system.forward(x),
        |r| system.adjoint(r),
        &b,
        system.unknowns,
        0.0,
        1e-6,
        20_000,
    );
    let values: Vec<f32> = (0..system.outer.count())
        .map(|i| match system.unknown[i] {
            Some(u) => x[u] as f32,
            None => system.known[i],
        })
        .collect();
    Ok((system.outer, values, outcome.iterations))
}

/// The lattice a denoising mask is resampled on: `coarse` samples along the mask's longest
/// side, refused when finer than `grid` itself (that would smooth nothing and only cost time
/// and memory) or larger than [`MAX_MASK_NODES`].
pub fn coarse_lattice(grid: &Grid, mask: &Mask, coarse: usize) -> Result<Grid, OpsError> {
    let side = (mask.hi - mask.lo).max_element().max(grid.spacing);
    // The grid's own nodes along the side: the finest lattice that still resamples coarsely.
    let finest = ((side / grid.spacing) as f64).floor().min(1e9) as usize + 1;
    let finest = finest.max(4);
    if !(4..=finest).contains(&coarse) {
        return Err(OpsError::BadParameter(format!(
            "the coarse resolution must be 4 to {finest} samples along the mask's longest side \
             (the field's own grid has {finest} nodes there; fewer samples smooth more), got \
             {coarse}"
        )));
    }
    let step = side / (coarse - 1) as f32;
    let dims = [0, 1, 2].map(|a| (((mask.hi[a] - mask.lo[a]) / step).ceil() as usize + 1).max(4));
    let nodes = dims.iter().fold(1usize, |n, &d| n.saturating_mul(d));
    if nodes > MAX_MASK_NODES {
        return Err(OpsError::BadParameter(format!(
            "the coarse lattice of {} x {} x {} samples is larger than the {MAX_MASK_NODES} \
             nodes a mask may hold; use fewer samples or a smaller mask",
            dims[0], dims[1], dims[2]
        )));
    }
    Ok(Grid {
        origin: mask.lo,
        spacing: step,
        dims,
        offset: Default::default(),
    })
}

/// The field inside `mask` seen through a coarse lattice of `coarse` samples along the
/// mask's longest side: the quadratic B-spline interpolant of the samples, at the mask's nodes.
fn coarse_resample(
    volume: &CoefficientVolume,
    mask: &Mask,
    nodes: &NodeBox,
    coarse: usize,
) -> Result<Vec<f32>, OpsError> {
    let coarse_grid = coarse_lattice(&volume.grid, mask, coarse)?;
    let dims = coarse_grid.dims;
    let mut samples = Vec::with_capacity(dims.iter().product());
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                samples.push(volume.value(coarse_grid.point(i, j, k)));
            }
        }
    }
    let smooth = CoefficientVolume::interpolate(coarse_grid, Basis::Bspline2, samples)?;
    Ok((0..nodes.count())
        .map(|i| {
            let n = nodes.node(i);
            smooth.value(volume.grid.point(n[0], n[1], n[2]))
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::booleans::sample_bricks;

    const BUMP: Vec3 = Vec3::new(0.0, 0.0, 1.0);

    /// A unit sphere with a ball of radius 0.3 stuck on its top, distances clamped to ±0.6.
    fn bumpy_sphere(res: usize) -> CoefficientVolume {
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.3), res).unwrap();
        sample_bricks(grid, Basis::Bspline3, 0.6, 1.0, |p| {
            (p.length() - 1.0).min((p - BUMP).length() - 0.3)
        })
        .unwrap()
    }

    fn top_mask() -> Mask {
        Mask {
            lo: Vec3::new(-0.45, -0.45, 0.75),
            hi: Vec3::new(0.45, 0.45, 1.45),
        }
    }

    /// Distance from the origin to the surface along `dir`, by bisection.
    fn radius_along(v: &CoefficientVolume, dir: Vec3) -> f32 {
        let (mut a, mut b) = (0.5f32, 1.6f32);
        for _ in 0..40 {
            let m = 0.5 * (a + b);
            if v.value(dir * m) < 0.0 {
                a = m;
            } else {
                b = m;
            }
        }
        0.5 * (a + b)
    }

    const BASE: Face = Face {
        axis: 2,
        upper: false,
    };

    #[test]
    fn laplace_system_has_full_column_rank() {
        let v = bumpy_sphere(24);
        let nodes = mask_nodes(&v.grid, &top_mask()).unwrap();
        let s = LaplaceSystem::new(&v, &nodes, BASE, 0.0).unwrap();
        assert!(s.rows.len() > s.unknowns, "overdetermined");
        // AᵀA, column by column, then Cholesky: every pivot positive means rank n.
        let n = s.unknowns;
        let mut ata = vec![0.0f64; n * n];
        for j in 0..n {
            let mut e = vec![0.0; n];
            e[j] = 1.0;
            let col = s.adjoint(&s.forward(&e));
            ata[j * n..(j + 1) * n].copy_from_slice(&col);
        }
        let mut smallest = f64::INFINITY;
        for k in 0..n {
            for i in 0..k {
                let f = ata[k * n + i] / ata[i * n + i];
                for j in i..n {
                    ata[k * n + j] -= f * ata[i * n + j];
                }
            }
            smallest = smallest.min(ata[k * n + k]);
        }
        assert!(smallest > 1e-6, "a pivot of {smallest}: rank deficient");
        // The adjoint is the forward operator's transpose.
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let r: Vec<f64> = (0..s.rows.len()).map(|i| (i as f64 * 0.11).cos()).collect();
        let lhs: f64 = s.forward(&x).iter().zip(&r).map(|(a, b)| a * b).sum();
        let rhs: f64 = s.adjoint(&r).iter().zip(&x).map(|(a, b)| a * b).sum();
        assert!((lhs - rhs).abs() < 1e-9 * lhs.abs().max(1.0));
    }

    #[test]
    fn bump_is_removed_and_nothing_else_changes() {
        let v = bumpy_sphere(64);
        assert!(radius_along(&v, Vec3::Z) > 1.25, "the bump is there");
        let mask = top_mask();
        // Alpha a little under 1 (the gradient of a distance) suits this mask: measured errors
        // are 1.8 %, 0.65 %, 0.95 % and 1.3 % of the radius for 0.8, 0.9, 0.95 and 1.
        let restore = Restore::Protrusion {
            face: BASE,
            alpha: 0.9,
        };
        let (r, reports) = repair(&v, &[mask], restore).unwrap();
        assert_eq!(reports.len(), 1);
        // Within the mask, the surface is back on the unit sphere.
        let mut worst: f32 = 0.0;
        for i in 0..=10 {
            for j in 0..=10 {
                let d = Vec3::new(-0.4 + 0.08 * i as f32, -0.4 + 0.08 * j as f32, 1.0).normalize();
                worst = worst.max((radius_along(&r, d) - 1.0).abs());
            }
        }
        assert!(worst <= 0.01, "surface {worst} from the sphere");
        // Coefficients whose support misses the mask are bit-identical.
        let nodes = mask_nodes(&v.grid, &mask).unwrap().grown(3, v.grid.dims);
        let [nx, ny, nz] = v.grid.dims;
        let mut changed = 0;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let (a, b) = (v.coeffs.get([i, j, k]), r.coeffs.get([i, j, k]));
                    if a.to_bits() != b.to_bits() {
                        assert!(nodes.contains([i, j, k]), "changed outside at {i},{j},{k}");
                        changed += 1;
                    }
                }
            }
        }
        assert!(changed > 0);
    }

    #[test]
    fn larger_alpha_gives_a_flatter_cap() {
        let v = bumpy_sphere(48);
        let curvature = |alpha: f32| {
            let restore = Restore::Protrusion { face: BASE, alpha };
            let (r, _) = repair(&v, &[top_mask()], restore).unwrap();
            // Height of the cap on the axis and 0.2 off it: curvature 2·sag / 0.2².
            let top = radius_along(&r, Vec3::Z);
            let d = Vec3::new(0.2, 0.0, 1.0).normalize();
            let side = radius_along(&r, d) * d.z;
            2.0 * (top - side) / (0.2 * 0.2)
        };
        let (low, high) = (curvature(0.0), curvature(2.0));
        assert!(high < low, "alpha 2 gives {high}, alpha 0 gives {low}");
    }

    /// Mean angle (degrees) between the field's normal and the sphere's at surface points in
    /// directions of a cone around `axis`.
    fn normal_error(v: &CoefficientVolume, axis: Vec3, cone: f32) -> f32 {
        let (mut sum, mut count) = (0.0, 0);
        let (u, w) = axis.any_orthonormal_pair();
        for i in 0..=12 {
            for j in 0..=12 {
                let d = (axis
                    + u * (cone * (i as f32 / 6.0 - 1.0))
                    + w * (cone * (j as f32 / 6.0 - 1.0)))
                    .normalize();
                let p = d * radius_along(v, d);
                let (_, g) = v.eval(p);
                sum += g.normalize().dot(d).clamp(-1.0, 1.0).acos().to_degrees();
                count += 1;
            }
        }
        sum / count as f32
    }

    #[test]
    fn denoising_smooths_inside_the_mask_only() {
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), 64).unwrap();
        let noisy = sample_bricks(grid, Basis::Bspline3, 0.3, 1.5, |p| {
            p.length() - 1.0 + 0.006 * (37.0 * p.x).sin() * (41.0 * p.y).sin() * (43.0 * p.z).sin()
        })
        .unwrap();
        let mask = Mask {
            lo: Vec3::new(-0.5, -0.5, 0.6),
            hi: Vec3::new(0.5, 0.5, 1.2),
        };
        let (r, _) = repair(&noisy, &[mask], Restore::Denoise { coarse: 12 }).unwrap();
        let (inside_before, inside_after) = (
            normal_error(&noisy, Vec3::Z, 0.2),
            normal_error(&r, Vec3::Z, 0.2),
        );
        let (outside_before, outside_after) = (
            normal_error(&noisy, -Vec3::Z, 0.2),
            normal_error(&r, -Vec3::Z, 0.2),
        );
        assert!(
            inside_after < 0.5 * inside_before,
            "{inside_before} → {inside_after}"
        );
        assert_eq!(outside_before, outside_after);
    }

    #[test]
    fn coarse_lattices_finer_than_the_grid_are_refused() {
        let v = bumpy_sphere(48);
        let mask = Mask {
            lo: Vec3::new(-0.5, -0.5, 0.6),
            hi: Vec3::new(0.5, 0.5, 1.2),
        };
        let along = (1.0 / v.grid.spacing) as usize + 1;
        assert!(coarse_lattice(&v.grid, &mask, along).is_ok());
        for coarse in [3, along + 1, 3000, 100_000_000, usize::MAX] {
            let e = repair(&v, &[mask], Restore::Denoise { coarse })
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(&format!("4 to {along} samples")) && e.contains(&format!("{coarse}")),
                "{e}"
            );
        }
        // A mask far longer than the grid allows many samples along it, but not a lattice
        // beyond the node limit.
        let long = Mask {
            lo: Vec3::new(-1e6, -1e6, -1e6),
            hi: Vec3::new(1e6, 1e6, 1e6),
        };
        let e = coarse_lattice(&v.grid, &long, 1000)
            .unwrap_err()
            .to_string();
        assert!(e.contains("larger than the"), "{e}");
    }

    #[test]
    fn a_mask_over_the_grid_border_takes_interpolated_border_values() {
        let v = bumpy_sphere(48);
        // The grid ends near z = 1.45; the mask runs past it.
        let mask = Mask {
            lo: Vec3::new(-0.45, -0.45, 0.75),
            hi: Vec3::new(0.45, 0.45, 3.0),
        };
        let nodes = mask_nodes(&v.grid, &mask).unwrap();
        assert_eq!(nodes.hi[2], v.grid.dims[2] - 1);
        let restore = Restore::Protrusion {
            face: BASE,
            alpha: 0.9,
        };
        let (r, _) = repair(&v, &[mask], restore).unwrap();
        let top = radius_along(&r, Vec3::Z);
        assert!((top - 1.0).abs() < 0.05, "cap at {top}");
    }
}
